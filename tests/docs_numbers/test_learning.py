"""The numbers docs/learning.md quotes: each against its data file, and the reruns behind them."""

from tests.docs_numbers.common import (
    _example_convergence,
    _example_median,
    _example_passed,
    _learning,
    quoted_figures_test,
)

QUOTES: list[tuple] = [
    (
        "docs/learning.md",
        r"the residual on the no-u₀ law reaches ([\d.]+) mm",
        "example_study",
        _example_median("learned-residual"),
        1e3,
    ),
    (
        "docs/learning.md",
        r"and the torque policy ([\d.]+) mm: both",
        "example_study",
        _example_median("learned-torque"),
        1e3,
    ),
    (
        "docs/learning.md",
        r"the PD meets the whole requirement on (\d+) of 29",
        "example_study",
        _example_passed("pd"),
        1.0,
    ),
    ("docs/learning.md", r"draws\n\(([\d.]+) mm\), the NN", "example_study", _example_median("pd"), 1e3),
    ("docs/learning.md", r"the NN on (\d+) of 29", "example_study", _example_passed("nn"), 1.0),
    ("docs/learning.md", r"of 29 \(([\d.]+) mm; the error", "example_study", _example_median("nn"), 1e3),
    (
        "docs/learning.md",
        r"task-space PD on none \(([\d.]+) mm\)",
        "example_study",
        _example_median("taskpd"),
        1e3,
    ),
    (
        "docs/learning.md",
        r"\(to ([\d.]+) and [\d.]+ of their values",
        "example_study",
        _example_convergence("nn"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"\(to [\d.]+ and ([\d.]+) of their values",
        "example_study",
        _example_convergence("pd"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"at ([\d.]+) of the batch's steps per\nsecond on the paper's arm",
        "learning_env",
        _learning("paper-ellipse", "vector_over_batch"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"second on the paper's arm and ([\d.]+) on the Panda",
        "learning_env",
        _learning("panda-ellipse", "vector_over_batch"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"costs ([\d.]+) µs \(paper arm\)",
        "learning_env",
        _learning("paper-ellipse", "single_env_overhead_us"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"and ([\d.]+) µs\n\(Panda\) more",
        "learning_env",
        _learning("panda-ellipse", "single_env_overhead_us"),
        1.0,
    ),
]

CASE = "paper-ellipse-noisy"


def _pair(a: str, b: str, key: str, index: int | None = None):
    """A paired comparison's figure in the example study's report (d = a - b)."""

    def value(d):
        (pair,) = [p for p in d["cases"][CASE]["paired"] if (p["a"], p["b"]) == (a, b)]
        return pair[key] if index is None else pair[key][index]

    return value


def _curves(name: str, which: str, at: float | None = None):
    """The least or largest validation median error [m] over a trained policy's seeds, at the curve
    point ``at`` simulated seconds (the last point where None), kept or not."""

    def value(d):
        case = d["cases"][CASE]
        trained = case["controllers"][name]["trained"] if name in case["controllers"] else None
        trained = trained or case["not_kept_trained"][name]
        values = []
        for curve in trained["curves"].values():
            point = curve[-1] if at is None else next(p for p in curve if p["simulated_seconds"] == at)
            values.append(point["median_rms_error_after_2s"])
        return {"min": min, "max": max}[which](values)

    return value


def _best_by(name: str, seconds: float, which: str):
    """The least or largest over a policy's seeds of each seed's best validation median error
    [m] up to ``seconds`` of training."""

    def value(d):
        curves = d["cases"][CASE]["controllers"][name]["trained"]["curves"].values()
        best = [
            min(p["median_rms_error_after_2s"] for p in c if p["simulated_seconds"] <= seconds)
            for c in curves
        ]
        return {"min": min, "max": max}[which](best)

    return value


def _later_gain(name: str, seconds: float):
    """The most any seed's best validation error improved after ``seconds``, as a share of its
    best up to then."""

    def value(d):
        gains = []
        for curve in d["cases"][CASE]["controllers"][name]["trained"]["curves"].values():
            before = min(p["median_rms_error_after_2s"] for p in curve if p["simulated_seconds"] <= seconds)
            after = min(p["median_rms_error_after_2s"] for p in curve if p["simulated_seconds"] > seconds)
            gains.append(max(0.0, (before - after) / before))
        return max(gains)

    return value


def _statistic(name: str, key: str, engine: str | None = None):
    def value(d):
        entry = d["cases"][CASE]["controllers"][name]
        return (entry["engines"][engine] if engine else entry["statistics"])[key]["median"]

    return value


def _worst(name: str):
    return lambda d: d["cases"][CASE]["controllers"][name]["worst"]["metrics"]["rms_error_after_2s"]


def _convergence_change(name: str):
    return lambda d: d["cases"][CASE]["controllers"][name]["tuned"]["convergence"]["change"]


E, L = "example_study", "docs/learning.md"
QUOTES += [
    (
        L,
        r"the residual on the PD's kept\nsetting reaches ([\d.]+) mm",
        E,
        _example_median("ppo-residual"),
        1e3,
    ),
    (L, r"mm against the PD's ([\d.]+) mm, better", E, _example_median("pd"), 1e3),
    (L, r"better on (\d+) of 29 paired", E, lambda d: 29 - _pair("pd", "ppo-residual", "a_better")(d), 1.0),
    (L, r"PD's error is ([\d.]+) times the residual's", E, _pair("pd", "ppo-residual", "ratio"), 1.0),
    (L, r"95 % interval ([\d.]+)\nto [\d.]+;", E, _pair("pd", "ppo-residual", "ratio_interval", 0), 1.0),
    (L, r"95 % interval [\d.]+\nto ([\d.]+);", E, _pair("pd", "ppo-residual", "ratio_interval", 1), 1.0),
    (L, r"sign test p = ([\d.]+)·10⁻⁸", E, _pair("pd", "ppo-residual", "holm_p"), 1e8),
    (L, r"median RMS torque of ([\d.]+) against", E, _statistic("ppo-residual", "rms_torque"), 1.0),
    (L, r"RMS torque of [\d.]+ against ([\d.]+) N m", E, _statistic("pd", "rms_torque"), 1.0),
    (L, r"requirement on (\d+) of 29 draws \(P\(fail\)", E, _example_passed("ppo-residual"), 1.0),
    (
        L,
        r"\(P\(fail\) ≤ ([\d.]+) at 95 %\)",
        E,
        lambda d: d["cases"][CASE]["controllers"]["ppo-residual"]["certificates"][0]["p_upper"],
        1.0,
    ),  # fmt: skip
    (L, r"worst plant is ([\d.]+) mm against", E, _worst("ppo-residual"), 1e3),
    (L, r"worst plant is [\d.]+ mm against ([\d.]+) mm", E, _worst("pd"), 1e3),
    (
        L,
        r"MuJoCo agrees \(([\d.]+) against",
        E,
        _statistic("ppo-residual", "rms_error_after_2s", "mujoco"),
        1e3,
    ),
    (
        L,
        r"MuJoCo agrees \([\d.]+ against ([\d.]+) mm\)",
        E,
        _statistic("pd", "rms_error_after_2s", "mujoco"),
        1e3,
    ),
    (L, r"early: from ([\d.]+) to [\d.]+ mm at 0 s", E, _curves("ppo-residual", "min", 0.0), 1e3),
    (L, r"early: from [\d.]+ to ([\d.]+) mm at 0 s", E, _curves("ppo-residual", "max", 0.0), 1e3),
    (L, r"within 480 simulated seconds \(to ([\d.]+) to", E, _best_by("ppo-residual", 480.0, "min"), 1e3),
    (
        L,
        r"within 480 simulated seconds \(to [\d.]+ to ([\d.]+) mm,",
        E,
        _best_by("ppo-residual", 480.0, "max"),
        1e3,
    ),
    (L, r"no seed got more than (\d+) % better", E, _later_gain("ppo-residual", 480.0), 100.0),
    (L, r"2400 s they end at ([\d.]+) to", E, _curves("ppo-residual", "min"), 1e3),
    (L, r"2400 s they end at [\d.]+ to\s+([\d.]+) mm", E, _curves("ppo-residual", "max"), 1e3),
    (L, r"error changed by (-?[\d.]+) % between", E, _convergence_change("ppo-residual"), 100.0),
    (L, r"validation median falls from ([\d.]+) to", E, _curves("ppo-torque", "min", 0.0), 1e3),
    (L, r"falls from [\d.]+ to ([\d.]+) mm at 0 s", E, _curves("ppo-torque", "max", 0.0), 1e3),
    (L, r"arm falls\) to ([\d.]+) to", E, _curves("ppo-torque", "min"), 1e3),
    (L, r"arm falls\) to [\d.]+ to ([\d.]+) mm at 2400 s", E, _curves("ppo-torque", "max"), 1e3),
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)
