"""The numbers docs/falsification.md quotes: each against its data file, and the reruns behind them."""

import re

import pytest

from tests.docs_numbers.common import (
    FALSIFIED,
    FT,
    PAPER,
    PF,
    PT,
    ROOT,
    _certified,
    _docs_data_commands,
    _falsified,
    _margin,
    _panda_noisy_kept,
    _paper_noisy_kept,
    _pick_certificate,
    _random_failures,
    _read,
    _reproduces_or_is_chaotic,
    _worst_config,
    _worst_draw,
    quoted_figures_test,
)

FALSIFY_PAPER, FALSIFY_PANDA = "falsify_paper", "falsify_panda"
FALSIFY_PAPER_TUNED, FALSIFY_PANDA_TUNED = "falsify_paper_tuned", "falsify_panda_tuned"
"""The falsification studies' whole reports (their certification entries), beside their
falsification views (FALSIFIED, PF, FT, PT)."""

PT_HOLDS = ("nn-tuned", "sliding-mode-tuned", "slotine-li-tuned")
"""The tuned Panda laws the falsification did not falsify (docs/falsification.md)."""

PT_FALSIFIED = ("no-u0-tuned", "pd-tuned", "rbf-nn-tuned")
"""The tuned Panda laws it falsified."""


def _laws(d) -> dict:
    """The controllers' entries of a one-case study's report."""
    (case,) = d["cases"].values()
    return case["controllers"]


def _certificate(d, controller: str, metric: str | None = None) -> dict:
    """A controller's certificate in a one-case study's report (:func:`_pick_certificate`)."""
    return _pick_certificate(_laws(d)[controller]["certificates"], metric)


def _fails(controller: str, metric: str | None = None, key: str = "k"):
    """How many of a study's certification draws fail (``key`` "p_upper": the bound on P(fail))
    the whole requirement, or with ``metric`` the property on it."""
    return lambda d: _certificate(d, controller, metric)[key]


def _fails_over(stat, controllers, metric: str | None = None):
    """``stat`` over ``controllers`` (None: every law) of their failing certification draws."""
    return lambda d: stat(_certificate(d, c, metric)["k"] for c in (controllers or _laws(d)))


def _limit(metric: str):
    """The bound of the study's certified property on ``metric`` (rms_torque<=10: 10)."""

    def get(d):
        (text,) = [p for p in d["certified_properties"] if p.startswith(f"{metric}<=")]
        return float(text.split("<=")[1])

    return get


def _torque_median(stat):
    """``stat`` over the laws of their median RMS torque on the certification draws [N m]."""
    return lambda d: stat(e["statistics"]["rms_torque"]["median"] for e in _laws(d).values())


def _stop_bound(stat, controllers):
    """``stat`` over ``controllers`` of their largest stop violation on the 59 certification draws
    (Wilks' 95 % / 95 % bound at N = 59: the largest draw) [rad]."""

    def get(d):
        bounds = []
        for c in controllers:
            (b,) = [q for q in _laws(d)[c]["quantile_bounds"] if q["metric"] == "max_joint_limit_violation"]
            assert b["N"] == 59 and b["quantile"] == 0.95
            bounds.append(b["bound"])
        return stat(bounds)

    return get


def _plant(controller: str, key: str, search: str | None = None):
    """A coordinate of a falsification's worst plant (or its random baseline's)."""

    def get(d):
        entry = d["controllers"][controller]
        entry = entry[search] if search else entry
        return entry["worst"]["values"][key]

    return get


def _first(controller: str):
    return lambda d: d["controllers"][controller]["first_violation"]


def _kept_range(case: str, stat, laws):
    """``stat`` over ``laws`` of their kept validation medians in a tuned study's case [m]."""

    def get(d):
        entries = d["cases"][case]["controllers"]
        return stat(
            next(s["median_error"] for s in e["tuned"]["seeds"] if s["seed"] == e["tuned"]["kept_seed"])
            for c, e in entries.items()
            if c in laws
        )

    return get


SIX = ("nn", "no-u0", "pd", "sliding-mode", "slotine-li", "rbf-nn")
"""The laws of the tuned falsify studies, by their names in the tuned studies."""

MODEL_BASED = ("nn-tuned", "no-u0-tuned", "sliding-mode-tuned", "slotine-li-tuned", "rbf-nn-tuned")
"""falsify-paper-tuned's laws with a model (every law but the PD)."""

PAPER_FACTORS = ("β̂₁", "β̂₂", "β̂₃", "p̂₁", "p̂₂", "p̂₃")
"""The paper arm's nominal.factors[0..5], in order (nnrobust/model/nominal.py)."""

MD = "docs/falsification.md"

QUOTES: list[tuple] = [
    # -- falsify-paper-tuned: the tuned paper laws on the paper's box
    *[
        (MD, pattern, FT, where, scale)
        for pattern, where, scale in (
            (r"only up to\s+([\d.]+) of its size for no-u0", _margin("no-u0-tuned"), 1.0),
            (
                r"only up to\s+([\d.]+) of its size for no-u0 and for the sliding mode",
                _margin("sliding-mode-tuned"),
                1.0,
            ),
            (
                r"still tracks to\s+[\d.]+ mm\. (\d+) of its 200 random plants fail",
                _random_failures("rbf-nn-tuned"),
                1.0,
            ),
            (r"Slotine–Li holds ([\d.]+) of\s+the box, the widest", _margin("slotine-li-tuned"), 1.0),
            (r"The NN compensator holds ([\d.]+), [\d.]+ times", _margin("nn-tuned"), 1.0),
            (
                r"The NN compensator holds [\d.]+, ([\d.]+) times no-u0's",
                lambda d: _margin("nn-tuned")(d) / _margin("no-u0-tuned")(d),
                1.0,
            ),
            (r"safe: (\d+) of its 200 random plants fail the NN", _random_failures("nn-tuned"), 1.0),
            (r"fail the NN and (\d+)\s+Slotine–Li", _random_failures("slotine-li-tuned"), 1.0),
            (r"\(P\(fail\) ≤ ([\d.]+) % and [\d.]+ %\)", _certified("nn-tuned"), 100.0),
            (r"\(P\(fail\) ≤ [\d.]+ % and ([\d.]+) %\)", _certified("slotine-li-tuned"), 100.0),
            (r"This one's worst plant gives (\d+) mm", _falsified("pd-tuned"), 1e3),
            (
                r"This one's worst plant gives \d+ mm \(friction × ([\d.]+)",
                _plant("pd-tuned", "plant.friction_scale"),
                1.0,
            ),
            (
                r"\(friction × [\d.]+, the\s+disturbance × ([\d.]+)\): it saturates",
                _plant("pd-tuned", "plant.disturbance_scale"),
                1.0,
            ),
            (r"(\d+) of the 200 random\s+plants fail it", _random_failures("pd-tuned"), 1.0),
            (r"plants fail it\s+\(P\(fail\) ≤ ([\d.]+) %\), the worst", _certified("pd-tuned"), 100.0),
            (
                r"the worst again at low friction \(× ([\d.]+)\)",
                _plant("pd-tuned", "plant.friction_scale", "random_baseline"),
                1.0,
            ),
            (r"low friction \(× [\d.]+\) with ([\d.]+) mm\.", _falsified("pd-tuned", "random_baseline"), 1e3),
            (r"Its margin, ([\d.]+) of the box, is second", _margin("pd-tuned"), 1.0),
            (r"For no-u0 CMA-ES found (\d+) mm", _falsified("no-u0-tuned"), 1e3),
            (r"nearly as bad \((\d+) mm\)", _falsified("no-u0-tuned", "random_baseline"), 1e3),
            (r"with a margin of ([\d.]+), \d+ of the 200", _margin("no-u0-tuned"), 1.0),
            (
                r"with a margin of [\d.]+, (\d+) of the 200 random plants fail",
                _random_failures("no-u0-tuned"),
                1.0,
            ),
            (
                r"the search found (\d+) mm and random search \d+ mm\. For Slotine",
                _falsified("nn-tuned"),
                1e3,
            ),
            (r"and random search (\d+) mm\. For Slotine", _falsified("nn-tuned", "random_baseline"), 1e3),
            (r"For Slotine–Li it found (\d+) mm at its", _falsified("slotine-li-tuned"), 1e3),
            (r"at its (\d+)th\s+simulation, random search", _first("slotine-li-tuned"), 1.0),
            (
                r"th\s+simulation, random search (\d+) mm",
                _falsified("slotine-li-tuned", "random_baseline"),
                1e3,
            ),
        )
    ],
    *[
        (MD, pattern, FALSIFY_PAPER_TUNED, where, scale)
        for pattern, where, scale in (
            (r"None is certified: (\d+) to \d+ of each model-based", _fails_over(min, MODEL_BASED), 1.0),
            (r"None is certified: \d+ to (\d+) of each model-based", _fails_over(max, MODEL_BASED), 1.0),
            (r"\(the PD's: (\d+)\)", _fails("pd-tuned"), 1.0),
            (r"needs more than the (\d+) N m RMS the tuning allowed", _limit("rms_torque"), 1.0),
            (
                r"On the error alone (\d+) to \d+ of them fail",
                _fails_over(min, MODEL_BASED, "rms_error_after_2s"),
                1.0,
            ),
            (
                r"On the error alone \d+ to (\d+) of them fail",
                _fails_over(max, MODEL_BASED, "rms_error_after_2s"),
                1.0,
            ),
            (
                r"\(Slotine–Li (\d+), the RBF network \d+; the PD",
                _fails("slotine-li-tuned", "rms_error_after_2s"),
                1.0,
            ),
            (
                r"\(Slotine–Li \d+, the RBF network (\d+); the PD",
                _fails("rbf-nn-tuned", "rms_error_after_2s"),
                1.0,
            ),
            (r"the RBF network \d+; the PD (\d+)\)", _fails("pd-tuned", "rms_error_after_2s"), 1.0),
        )
    ],
    (
        MD,
        r"to validation errors of ([\d.]+)–",
        "tuned_paper",
        _kept_range("paper-ellipse-noisy", min, SIX),
        1e3,
    ),
    (
        MD,
        r"to validation errors of [\d.]+–([\d.]+) mm",
        "tuned_paper",
        _kept_range("paper-ellipse-noisy", max, SIX),
        1e3,
    ),
    (MD, r"Its validation error, ([\d.]+) mm, is next to", "tuned_paper", _paper_noisy_kept("rbf-nn"), 1e3),
    (MD, r"is next to\s+the NN's ([\d.]+) mm", "tuned_paper", _paper_noisy_kept("nn"), 1e3),
    # -- falsify-panda-tuned: the tuned Panda laws on the Panda's box
    *[
        (MD, pattern, PT, where, scale)
        for pattern, where, scale in (
            (r"falsified at simulation (\d+) by a plant", _first("no-u0-tuned"), 1.0),
            (
                r"falsified at simulation \d+ by a plant\s+\(disturbance × ([\d.]+)",
                _plant("no-u0-tuned", "plant.disturbance_scale"),
                1.0,
            ),
            (
                r"by a plant\s+\(disturbance × [\d.]+, friction × ([\d.]+), a",
                _plant("no-u0-tuned", "plant.friction_scale"),
                1.0,
            ),
            (
                r"by a plant\s+\(disturbance × [\d.]+, friction × [\d.]+, a ([\d.]+) kg",
                _plant("no-u0-tuned", "plant.payload"),
                1.0,
            ),
            (r"leaves the ellipse \((\d+) mm; MuJoCo as the plant", _falsified("no-u0-tuned"), 1e3),
            (r"Its margin is ([\d.]+) of the box; \d+ of its 200", _margin("no-u0-tuned"), 1.0),
            (r"of the box; (\d+) of its 200 random plants and", _random_failures("no-u0-tuned"), 1.0),
            (r"At simulation (\d+) the search found a plant\n", _first("rbf-nn-tuned"), 1.0),
            (
                r"\(disturbance × ([\d.]+), friction × [\d.]+, a [\d.]+ kg payload\)"
                r" on which it saturates in",
                _plant("rbf-nn-tuned", "plant.disturbance_scale"),
                1.0,
            ),
            (
                r"\(disturbance × [\d.]+, friction × ([\d.]+), a [\d.]+ kg payload\)"
                r" on which it saturates in",
                _plant("rbf-nn-tuned", "plant.friction_scale"),
                1.0,
            ),
            (
                r"\(disturbance × [\d.]+, friction × [\d.]+, a ([\d.]+) kg payload\)"
                r" on which it saturates in",
                _plant("rbf-nn-tuned", "plant.payload"),
                1.0,
            ),
            (r"steps and gives (\d+) mm; MuJoCo as the plant loses", _falsified("rbf-nn-tuned"), 1e3),
            (r"Its margin is\s+([\d.]+) of the box, the narrowest", _margin("rbf-nn-tuned"), 1.0),
            (
                r"the narrowest here; (\d+) of its 200 random plants fail",
                _random_failures("rbf-nn-tuned"),
                1.0,
            ),
            (r"random plants fail \(P\(fail\) ≤ ([\d.]+) %\) and", _certified("rbf-nn-tuned"), 100.0),
            (r"At its (\d+)th simulation of 200 the search", _first("pd-tuned"), 1.0),
            (
                r"found a plant \(disturbance × ([\d.]+), friction × [\d.]+, a [\d.]+ kg payload\)"
                r" on which it gives",
                _plant("pd-tuned", "plant.disturbance_scale"),
                1.0,
            ),
            (
                r"found a plant \(disturbance × [\d.]+, friction × ([\d.]+), a [\d.]+ kg payload\)"
                r" on which it gives",
                _plant("pd-tuned", "plant.friction_scale"),
                1.0,
            ),
            (
                r"found a plant \(disturbance × [\d.]+, friction × [\d.]+, a ([\d.]+) kg payload\)"
                r" on which it gives",
                _plant("pd-tuned", "plant.payload"),
                1.0,
            ),
            (r"kg payload\) on which it gives ([\d.]+) mm\s+against", _falsified("pd-tuned"), 1e3),
            (r"Its margin is ([\d.]+), and none of its 200", _margin("pd-tuned"), 1.0),
            (
                r"falsified even at ([\d.]+) times the box",
                lambda d: d["margin"]["nn-tuned"]["largest_scale"],
                1.0,
            ),
            (r"worst plants give\s+([\d.]+)–", lambda d: min(_falsified(c)(d) for c in PT_HOLDS), 1e3),
            (
                r"worst plants give\s+[\d.]+–([\d.]+) mm",
                lambda d: max(_falsified(c)(d) for c in PT_HOLDS),
                1e3,
            ),
        )
    ],
    *[
        (MD, pattern, FALSIFY_PANDA_TUNED, where, scale)
        for pattern, where, scale in (
            (r"Each setting met\s+(\d+) N m RMS", _limit("rms_torque"), 1.0),
            (r"whole requirement \(the\s+0.5 mm, at most (\d+) N m", _limit("rms_torque"), 1.0),
            (
                r"N m RMS torque and (\d+) % of the steps saturated, no stop hit, no runaway,"
                r" the\npath kept\) on 59",
                _limit("saturated_fraction"),
                100.0,
            ),
            (
                r"with up to (\d+) kg at the tool and the disturbance",
                lambda d: d["box"]["plant.payload"]["uniform"][1],
                1.0,
            ),
            (
                r"kg at the tool and the disturbance\s+up to × (\d+),",
                lambda d: d["box"]["plant.disturbance_scale"]["uniform"][1],
                1.0,
            ),
            (r"median RMS torque is (\d+)–", _torque_median(min), 1.0),
            (r"median RMS torque is \d+–(\d+) N m", _torque_median(max), 1.0),
            (r"and (\d+) to \d+ of the 59 draws fail the\s+whole", _fails_over(min, None), 1.0),
            (r"and \d+ to (\d+) of the 59 draws fail the\s+whole", _fails_over(max, None), 1.0),
            (
                r"whole requirement, (\d+) to \d+ of them by the torque",
                _fails_over(min, None, "rms_torque"),
                1.0,
            ),
            (
                r"whole requirement, \d+ to (\d+) of them by the torque",
                _fails_over(max, None, "rms_torque"),
                1.0,
            ),
            (
                r"random plants and (\d+) of the 59 certification draws\s+fail the",
                _fails("no-u0-tuned", "rms_error_after_2s"),
                1.0,
            ),
            (
                r"\(P\(fail\) ≤ [\d.]+ %\) and (\d+)\s+of the 59 certification draws",
                _fails("rbf-nn-tuned", "rms_error_after_2s"),
                1.0,
            ),
        )
    ],
    (
        MD,
        r"at most 0.5 mm, (\d+) to \d+ times their",
        "tuned_panda",
        lambda d: 5e-4 / _panda_noisy_kept(max)(d),
        1.0,
    ),
    (
        MD,
        r"at most 0.5 mm, \d+ to (\d+) times their",
        "tuned_panda",
        lambda d: 5e-4 / _panda_noisy_kept(min)(d),
        1.0,
    ),
    (
        MD,
        r"validation errors of ([\d.]+)–[\d.]+ mm\. The study certifies",
        "tuned_panda",
        _panda_noisy_kept(min),
        1e3,
    ),
    (
        MD,
        r"validation errors of [\d.]+–([\d.]+) mm\. The study certifies",
        "tuned_panda",
        _panda_noisy_kept(max),
        1e3,
    ),
    # -- falsify-panda: the Panda at its preset's gains
    (MD, r"At simulation (\d+) the\s+search found", PF, _first("nn"), 1.0),
    (MD, r"on which it gives\s+([\d.]+) mm: the actuators", PF, _falsified("nn"), 1e3),
    (MD, r"violation \(at\s+worst ([\d.]+) mm\)", PF, _falsified("nn", "random_baseline"), 1e3),
    (MD, r"up to ([\d.]+) of its size for the NN,", PF, _margin("nn"), 1.0),
    (MD, r"for the NN, ([\d.]+) for the RBF network", PF, _margin("rbf-nn"), 1.0),
    (MD, r"and\s+([\d.]+) for Slotine–Li \(worst", PF, _margin("slotine-li"), 1.0),
    (MD, r"\(worst plants ([\d.]+) and", PF, _falsified("rbf-nn"), 1e3),
    (MD, r"\(worst plants [\d.]+ and ([\d.]+) mm\)", PF, _falsified("slotine-li"), 1e3),
    (MD, r"against ([\d.]+) for the sliding-mode term\.", PF, _margin("sliding-mode"), 1.0),
    (MD, r"none fails the NN, (\d+)\s+the RBF", PF, _random_failures("rbf-nn"), 1.0),
    (MD, r"network\s+and (\d+) Slotine–Li", PF, _random_failures("slotine-li"), 1.0),
    (MD, r"P\(fail\) ≤ ([\d.]+) %, [\d.]+ % and", PF, _certified("nn"), 100.0),
    (MD, r"P\(fail\) ≤ [\d.]+ %, ([\d.]+) % and", PF, _certified("rbf-nn"), 100.0),
    (MD, r"% and ([\d.]+) %, each\s+within", PF, _certified("slotine-li"), 100.0),
    (MD, r"while (\d+) of 200 \(P", PF, _random_failures("sliding-mode"), 1.0),
    (MD, r"of 200 \(P\(fail\) ≤ ([\d.]+) %\) fail the", PF, _certified("sliding-mode"), 100.0),
    (MD, r"term ends at\s+(\d+) mm", PF, _falsified("sliding-mode"), 1e3),
    (MD, r"the PD at (\d+) mm and", PF, _falsified("pd"), 1e3),
    (MD, r"and no-u0 at (\d+) mm, each", PF, _falsified("no-u0"), 1e3),
    *[
        (MD, pattern, FALSIFY_PANDA, where, scale)
        for pattern, where, scale in (
            (
                r"the sliding-mode term fails on (\d+) of\s+them",
                _fails("sliding-mode", "rms_error_after_2s"),
                1.0,
            ),
            (
                r"at most (\d+) N m RMS torque and \d+ % of the steps saturated, no\s+stop",
                _limit("rms_torque"),
                1.0,
            ),
            (
                r"at most \d+ N m RMS torque and (\d+) % of the steps saturated, no\s+stop",
                _limit("saturated_fraction"),
                100.0,
            ),
            (r"median RMS torque over\s+the 59 draws is (\d+)–", _torque_median(min), 1.0),
            (r"the 59 draws is \d+–(\d+) N m, against", _torque_median(max), 1.0),
            (r"N m, against the (\d+) allowed", _limit("rms_torque"), 1.0),
            (r"Slotine–Li fails on\s+(\d+) of 59 draws", _fails("slotine-li"), 1.0),
            (r"The NN fails on (\d+) \(torque", _fails("nn"), 1.0),
            (r"The NN fails on \d+ \(torque (\d+), stops", _fails("nn", "rms_torque"), 1.0),
            (r"\(torque \d+, stops (\d+)\), the", _fails("nn", "max_joint_limit_violation"), 1.0),
            (r"the RBF network on (\d+) each", _fails("sliding-mode"), 1.0),
            (r"the RBF network on (\d+) each", _fails("rbf-nn"), 1.0),
            (r"no-u0 and the PD on all (\d+)\.", _fails("no-u0"), 1.0),
            (r"no-u0 and the PD on all (\d+)\.", _fails("pd"), 1.0),
            (r"into a stop on (\d+) of the\s+draws", _fails("nn", "max_joint_limit_violation"), 1.0),
            (
                r"the first three by at most ([\d.]+) mrad",
                _stop_bound(max, ("nn", "sliding-mode", "rbf-nn")),
                1e3,
            ),
            (r"None\s+does it within (\d+) N m RMS torque", _limit("rms_torque"), 1.0),
            (r"the NN hits a stop on (\d+) of 59 draws", _fails("nn", "max_joint_limit_violation"), 1.0),
        )
    ],
    # -- falsify-paper: the paper's arm at the paper's gains
    ("docs/falsification.md", r"Its 150 draws saw at most (\d+) mm", PAPER, _worst_draw("nn"), 1e3),
    (MD, r"robustness study's 150 draws saw at most (\d+) mm", PAPER, _worst_draw("nn"), 1e3),
    *[
        (MD, pattern, FALSIFY_PAPER, where, scale)
        for pattern, where, scale in (
            (
                r"at most (\d+) N m RMS torque and \d+ % of the steps saturated, and",
                _limit("rms_torque"),
                1.0,
            ),
            (
                r"at most \d+ N m RMS torque and (\d+) % of the steps saturated, and",
                _limit("saturated_fraction"),
                100.0,
            ),
            (r"the (\d+) mm on the error and the study's", _limit("rms_error_after_2s"), 1e3),
            (
                r"None of its (\d+) draws fails any property",
                lambda d: _certificate(d, "slotine-li")["N"],
                1.0,
            ),
            (r"NN compensator fails on (\d+) of 59", _fails("nn"), 1.0),
            (
                r"fails on \d+ of 59 \(P\(fail\) ≤ ([\d.]+) %\), and rarely",
                _fails("nn", key="p_upper"),
                100.0,
            ),
            (r"rarely on the error: (\d+) draws exceed", _fails("nn", "rms_error_after_2s"), 1.0),
            (r"draws exceed\s+(\d+) mm, but", _limit("rms_error_after_2s"), 1e3),
            (r"mm, but (\d+) need more than", _fails("nn", "rms_torque"), 1.0),
            (r"need more than (\d+) N m RMS, \d+ saturate", _limit("rms_torque"), 1.0),
            (r"N m RMS, (\d+) saturate more than", _fails("nn", "saturated_fraction"), 1.0),
            (r"saturate more than (\d+) % of the steps and", _limit("saturated_fraction"), 100.0),
            (r"of the steps and (\d+) drive a\s+joint", _fails("nn", "max_joint_limit_violation"), 1.0),
            (r"The RBF network fails on (\d+) draws", _fails("rbf-nn"), 1.0),
            (r"the sliding-mode term on (\d+); on", _fails("sliding-mode"), 1.0),
            (r"No-u0 and computed torque fail on all (\d+)", _fails("no-u0"), 1.0),
            (r"No-u0 and computed torque fail on all (\d+)", _fails("computed-torque"), 1.0),
            (r"its margin is [\d.]+ against [\d.]+, and\s+(\d+) of its 59 draws fail", _fails("nn"), 1.0),
        )
    ],
    *[
        (MD, pattern, FALSIFIED, where, scale)
        for pattern, where, scale in (
            (r"no violation up to ([\d.]+) of it, and", _margin("rbf-nn"), 1.0),
            (r"of it, and (\d+) of its 200\s+random", _random_failures("rbf-nn"), 1.0),
            (r"plants fail against the\s+NN's (\d+)\.", _random_failures("nn"), 1.0),
            (r"term tolerates ([\d.]+)\s+of the box", _margin("sliding-mode"), 1.0),
            (r"of the box and Slotine–Li ([\d.]+);", _margin("slotine-li"), 1.0),
            (r"the sliding-mode term gives\s+(\d+) mm", _falsified("sliding-mode"), 1e3),
            (r"no-u0 (\d+) mm, computed torque", _falsified("no-u0"), 1e3),
            (r"computed torque (\d+) mm, the RBF", _falsified("computed-torque"), 1e3),
            (r"runs away and gives (\d+) mm\.\n", _falsified("slotine-li"), 1e3),
            (
                r"near a corner of the box \(β̂ and p̂ off by up to (\d+) %",
                lambda d: (
                    100
                    * max(
                        abs(v - 1)
                        for k, v in d["controllers"]["slotine-li"]["worst"]["values"].items()
                        if k.startswith("nominal.factors")
                    )
                ),
                1.0,
            ),
            (r"off by up to \d+ %, friction × ([\d.]+),", _plant("slotine-li", "plant.friction_scale"), 1.0),
            (
                r"friction × [\d.]+,\s+disturbance × ([\d.]+)\) on which it saturates",
                _plant("slotine-li", "plant.disturbance_scale"),
                1.0,
            ),
            (r"its margin is ([\d.]+) against [\d.]+, and", _margin("nn"), 1.0),
            (r"its margin is [\d.]+ against ([\d.]+), and", _margin("slotine-li"), 1.0),
            (r"the RBF network (\d+) mm and Slotine–Li", _falsified("rbf-nn"), 1e3),
            (r"and Slotine–Li (\d+) mm,\s+each on its own", _falsified("slotine-li"), 1e3),
            (r"at its (\d+)th simulation the search\s+found a plant", _first("slotine-li"), 1.0),
            (
                r"\((\d+) simulations, and \d+ more for the margins",
                lambda d: sum(
                    e["simulations"] + e["random_baseline"]["simulations"] for e in d["controllers"].values()
                ),
                1.0,
            ),
            (
                r"simulations, and (\d+) more for the margins",
                lambda d: sum(m["simulations"] for m in d["margin"].values()),
                1.0,
            ),
            (r"Scaled to ([\d.]+) of the box \(each", _margin("nn"), 1.0),
            (r"inertial parameter within ±(\d+) %", lambda d: 30 * d["margin"]["nn"]["holds_up_to"], 1.0),
            (
                r"parameter within ±\d+ %, friction × ([\d.]+)–",
                lambda d: 2 ** -d["margin"]["nn"]["holds_up_to"],
                1.0,
            ),
            (
                r"parameter within ±\d+ %, friction × [\d.]+–([\d.]+),",
                lambda d: 2 ** d["margin"]["nn"]["holds_up_to"],
                1.0,
            ),
            (
                r"1.\d+, disturbance × ([\d.]+)–",
                lambda d: 1.25 - 0.75 * d["margin"]["nn"]["holds_up_to"],
                1.0,
            ),
            (
                r"1.\d+, disturbance × [\d.]+–([\d.]+)\)",
                lambda d: 1.25 + 0.75 * d["margin"]["nn"]["holds_up_to"],
                1.0,
            ),
            (r"found a violation \(at its (\d+)th simulation\)", _first("rbf-nn"), 1.0),
            (r"for sliding mode, (\d+) mm for the RBF network", _falsified("rbf-nn", "random_baseline"), 1e3),
            (
                r"NN controller at the paper's gains fails.\*\* Its worst plant[^:]*?: (\d+) mm RMS",
                _falsified("nn"),
                1e3,
            ),
            (r"The (\d+) mm is one trajectory", _falsified("nn"), 1e3),
            (r"worse than the (\d+) mm this search found", _falsified("nn"), 1e3),
            (
                r"friction × ([\d.]+),\n  disturbance × [\d.]+\) leaves the ellipse",
                _plant("nn", "plant.friction_scale"),
                1.0,
            ),
            (r"disturbance × ([\d.]+)\) leaves the ellipse", _plant("nn", "plant.disturbance_scale"), 1.0),
            *[
                (rf"{name} × ([\d.]+)", _plant("nn", f"nominal.factors[{i}]"), 1.0)
                for i, name in enumerate(PAPER_FACTORS)
            ],
        )
    ],
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)


@pytest.mark.parametrize("name", [FALSIFIED, PF, FT, PT])
def test_the_published_worst_plants_rerun_to_their_metrics(name):
    """docs/falsification.md's worst plants (docs/data/falsify_*.json, written by nnrobust
    falsify): each printed command reproduces the error the search recorded, or is a chaotic run
    (a millionth of the disturbance moves it by more than 1 %) that fails the property as well."""
    from nnrobust.run.properties import run_properties

    data = _read(name)
    (limit,) = [p.value for p in run_properties(data["properties"]) if p.metric == "rms_error_after_2s"]
    for name, entry in data["controllers"].items():
        if not entry["falsified"]:
            limit_here = None  # a worst plant that holds: its digits must reproduce or be chaotic
        else:
            limit_here = float(limit)
        config = _worst_config(entry["worst"]["command"])
        _reproduces_or_is_chaotic(config, entry["worst"]["metrics"]["rms_error_after_2s"], name, limit_here)


def test_the_nn_worst_plant_fails_on_the_python_loop_too():
    """The NN's worst plant is a chaotic run once saturated: the Python loop, whose rounding differs,
    ends elsewhere (docs/falsification.md quotes both, the Python loop's from
    benchmarks/worst_plant_loops.py: a minute of the Python loop, measured there and not here), but
    past the 50 mm required as well: the verdict does not depend on the loop."""
    from nnrobust.run.experiment import run_experiment

    data = _read(FALSIFIED)
    command = data["controllers"]["nn"]["worst"]["command"]
    config = _worst_config(command)
    text = (ROOT / "docs" / "falsification.md").read_text()
    loops = _read("worst_plant_loops")
    assert loops["command"] == command  # measured on the plant the page names
    python = loops["loops"]["python"]
    quoted = float(re.search(r"The Python loop, whose rounding differs,\s+gave (\d+) mm", text).group(1))
    assert quoted == round(1e3 * python["rms_error_after_2s"]) and python["rms_error_after_2s"] > 0.05
    compiled = run_experiment(config).metrics()  # the saturation and the stop the text quotes
    said = re.search(
        r"compiled loop, (\d+) % of the steps\s+saturated, and the self-motion drives a joint ([\d.]+) rad",
        text,
    )
    assert 100 * compiled["saturated_fraction"] == pytest.approx(float(said.group(1)), abs=0.5)
    assert compiled["max_joint_limit_violation"] == pytest.approx(float(said.group(2)), abs=0.0005)
    assert compiled["rms_error_after_2s"] == pytest.approx(loops["loops"]["compiled"]["rms_error_after_2s"])


def test_the_margins_violating_plants_rerun_to_their_margins():
    """docs/falsification.md's margins: the plant that violated each robust law's property at the
    top of its bracket reruns from its printed command to the margins the search recorded."""
    from nnrobust.run.experiment import run_experiment
    from nnrobust.run.properties import run_properties

    data = _read(FALSIFIED)
    properties = run_properties(data["properties"])
    for name in ("nn", "sliding-mode"):
        plant = data["margin"][name]["violating_plant"]
        metrics = run_experiment(_worst_config(plant["command"])).metrics()
        for p in properties:
            assert p.margin(metrics) == pytest.approx(plant["margins"][p.text], rel=1e-9), name
            assert p.margin(metrics) < 0, name


def test_the_first_commands_worst_plant_is_worse_than_the_studys_worst_sample():
    """docs/falsification.md's first command (issue 21's acceptance: falsify paper-robustness, the
    NN, 200 simulations): the worst plant it printed reruns to the figure quoted, and that is worse
    than the worst of the paper-robustness study's certification draws, quoted beside it."""
    from nnrobust.run.experiment import run_experiment

    text = (ROOT / "docs" / "falsification.md").read_text()
    said = re.search(
        r"gives (\d+) mm, against ([\d.]+) mm for the worst of the robustness study's 150\s+draws", text
    )
    block = re.search(r"the command it printed reruns it:\s+(nnrobust run .*?)\n\n", text, re.S)
    command = " ".join(block.group(1).replace("\\\n", " ").split())
    metrics = run_experiment(_worst_config(command)).metrics()
    study = _read(PAPER)
    worst_sample = max(
        case["controllers"]["nn"]["statistics"]["rms_error_after_2s"]["max"]
        for case in study["cases"].values()
    )
    assert sum(case["controllers"]["nn"]["statistics"]["rows"] for case in study["cases"].values()) == 150
    assert 1e3 * metrics["rms_error_after_2s"] == pytest.approx(float(said.group(1)), abs=0.5)
    assert 1e3 * worst_sample == pytest.approx(float(said.group(2)), abs=0.05)
    assert metrics["rms_error_after_2s"] > worst_sample


def test_the_plant_the_search_no_longer_finds_still_fails():
    """docs/falsification.md: the NN's worst plants of earlier searches (one on an earlier plant
    step, one of the previous regeneration), rerun from their printed commands, give the figures
    quoted today, past 50 mm."""
    from nnrobust.run.experiment import run_experiment

    text = (ROOT / "docs" / "falsification.md").read_text()
    block = re.search(r"today's step, it gives (\d+) mm:\s+(nnrobust run .*?)\n\n", text, re.S)
    earlier = re.search(
        r"for the NN the plant\s+(nnrobust run .*?)\n\n\s+on which it gives (\d+) mm", text, re.S
    )
    for command, quoted in ((block.group(2), block.group(1)), (earlier.group(1), earlier.group(2))):
        metrics = run_experiment(_worst_config(" ".join(command.replace("\\\n", " ").split()))).metrics()
        assert metrics["refined_periods"] > 0  # the step was cut (for speed, and at the stops)
        assert metrics["rms_error_after_2s"] > 0.05
        assert metrics["rms_error_after_2s"] * 1e3 == pytest.approx(float(quoted), abs=0.5)


def test_the_pandas_nn_worst_plant_is_what_the_text_says():
    """docs/falsification.md: the NN's worst Panda plant saturates and reaches a stop as quoted,
    and MuJoCo as the plant gives the error quoted, past the 5 mm required as well."""
    pytest.importorskip("mujoco")
    from nnrobust.run.experiment import run_experiment

    data = _read(PF)
    config = _worst_config(data["controllers"]["nn"]["worst"]["command"])
    metrics = run_experiment(config).metrics()
    text = (ROOT / "docs" / "falsification.md").read_text()
    said = re.search(r"saturate in (\d+) % of the steps and joint (\d) goes ([\d.]+) rad", text)
    assert 100 * metrics["saturated_fraction"] == pytest.approx(float(said.group(1)), abs=0.5)
    assert metrics["joint_limit_joint"] + 1 == int(said.group(2))  # panda_joint6 is index 5
    assert metrics["max_joint_limit_violation"] == pytest.approx(float(said.group(3)), abs=0.0005)
    mujoco = run_experiment(config.replace(plant={"engine": "mujoco"})).metrics()["rms_error_after_2s"]
    quoted = float(re.search(r"MuJoCo as the plant gives ([\d.]+) mm", text).group(1))
    assert mujoco > 0.005 and 1e3 * mujoco == pytest.approx(quoted, abs=0.05)


def test_the_tuned_pandas_falsified_plants_are_what_the_text_says():
    """docs/falsification.md, the Panda at the tuned study's kept settings: no-u0's and the RBF
    network's worst plants saturate as quoted and lose the path on MuJoCo too, past the figure
    quoted; the PD's, found at the search's last simulations, saturates as quoted and holds on
    MuJoCo to the figure quoted (the edge the text names)."""
    pytest.importorskip("mujoco")
    from nnrobust.run.experiment import run_experiment

    data = _read(PT)
    text = (ROOT / "docs" / "falsification.md").read_text()
    cases = (
        (
            "no-u0-tuned",
            r"saturate in (\d+) %\s+of the steps and it leaves",
            r"MuJoCo as the plant loses it too, beyond (\d+) mm",
            True,
        ),
        (
            "rbf-nn-tuned",
            r"it saturates in (\d+) % of the\s+steps and gives \d+ mm; MuJoCo",
            r"MuJoCo as the plant loses the path too, beyond (\d+) mm",
            True,
        ),
        (
            "pd-tuned",
            r"mm allowed, saturated in (\d+) % of the steps",
            r"MuJoCo as the plant tracks it to\s+([\d.]+) mm",
            False,
        ),
    )
    for name, saturates, on_mujoco, fails in cases:
        config = _worst_config(data["controllers"][name]["worst"]["command"])
        metrics = run_experiment(config).metrics()
        assert 100 * metrics["saturated_fraction"] == pytest.approx(
            float(re.search(saturates, text).group(1)), abs=0.5
        ), name
        assert metrics["rms_error_after_2s"] > 0.0005, name
        mujoco = run_experiment(config.replace(plant={"engine": "mujoco"})).metrics()["rms_error_after_2s"]
        assert (mujoco > 0.0005) == fails, name
        said = float(re.search(on_mujoco, text).group(1))
        if fails:  # a lost path: where it ends moves with MuJoCo's floating-point code, by CPU
            assert 1e3 * mujoco > said, name
        else:
            assert 1e3 * mujoco == pytest.approx(said, abs=0.005), name


def test_every_worst_plant_fails_on_mujoco_too():
    """docs/falsification.md: each falsified law's worst plant (today every law's, Slotine-Li's
    included), rerun with MuJoCo as the plant, violates the 50 mm property too (the NN's on both
    loops), and the worst plant of a law the search did not falsify satisfies it there as well;
    the figures quoted are the compiled loop's. On MuJoCo the NN's saturates in the share of the
    steps quoted and Slotine-Li's runs away, as on this package's plant."""
    pytest.importorskip("mujoco")
    from nnrobust.run.experiment import run_experiment

    data = _read(FALSIFIED)
    text = (ROOT / "docs" / "falsification.md").read_text()
    quoted = {"nn": float(re.search(r"the NN's worst plant gives (\d+) mm", text).group(1))}
    others = re.search(r"computed torque's give (\d+), (\d+) and (\d+) mm", text).groups()
    quoted.update(zip(("sliding-mode", "no-u0", "computed-torque"), map(float, others)))
    quoted["rbf-nn"] = float(re.search(r"the RBF network's (\d+) mm \(chaotic", text).group(1))
    quoted["slotine-li"] = float(
        re.search(r"Slotine–Li's worst plant ([\d.]+) mm, (?:inside|past)", text).group(1)
    )
    for name, entry in data["controllers"].items():
        config = _worst_config(entry["worst"]["command"]).replace(plant={"engine": "mujoco"})
        on_mujoco = run_experiment(config).metrics()
        compiled = on_mujoco["rms_error_after_2s"]
        assert (compiled > 0.05) == entry["falsified"], name
        if name == "nn":
            said = float(
                re.search(r"the NN's worst plant gives \d+ mm, (\d+) % of the\s+steps saturated", text).group(
                    1
                )
            )
            assert 100 * on_mujoco["saturated_fraction"] == pytest.approx(said, rel=0.02)
        if name == "slotine-li":
            assert on_mujoco["runaway"] and "past the property and\n  running away" in text
        if name == "nn":  # the Python loop too (13 s a run), for the paper's controller
            on_python = config.replace(simulation={"backend": "python"})
            assert run_experiment(on_python).metrics()["rms_error_after_2s"] > 0.05
        if not entry["falsified"]:  # a run that holds is not chaotic: its figure is stable
            assert 1e3 * compiled == pytest.approx(quoted[name], abs=0.005), name
        # the quoted figures of the falsified (the compiled loop's on the machine that wrote them;
        # a chaotic run's digits move with the rounding, test_the_published_worst_plants_rerun_...)
        assert (quoted[name] > 50) == entry["falsified"], name


@pytest.mark.parametrize(
    "study, case",
    [
        ("falsify-paper", "paper-ellipse"),
        ("falsify-panda", "panda-ellipse"),
        ("falsify-paper-tuned", "paper-ellipse-noisy"),
        ("falsify-panda-tuned", "panda-ellipse-noisy"),
    ],
)
def test_the_published_falsifications_are_their_studys_falsification_stage(study, case):
    """make docs-data runs each falsification study and copies its report, whose falsification
    and margin entries the tables read: that report searched the study's box, with the study's
    controllers, property, budget and margins, each law at the study's settings (its own, or the
    tuned study's kept ones as NAME-tuned, untuned here); every worst plant lies in the box."""
    from nnrobust.studies.study import load_study

    spec = load_study(ROOT / "benchmarks" / "studies" / f"{study}.toml")
    name = study.replace("-", "_")
    assert any(study in " ".join(c) for c in _docs_data_commands() if c[:3] == ["for", "study", "in"])
    report = _read(name)
    assert report["study"] == study and list(report["cases"]) == [case]
    assert report["require"] == spec.require
    assert {k: report["budgets"][k] for k in ("falsify", "margin")} == {
        k: spec.budgets[k] for k in ("falsify", "margin")
    }
    laws = report["cases"][case]["controllers"]
    assert spec.fixed == spec.controllers == list(laws)  # nothing tuned again here
    bounds = {k: v.get("uniform", v.get("loguniform")) for k, v in spec.vary.items()}
    for controller, entry in laws.items():
        found = entry["falsification"]
        assert found["simulations"] == found["random_baseline"]["simulations"] == spec.budgets["falsify"]
        assert bool(entry.get("margin")) == spec.budgets["margin"], controller
        for plant in (found["worst"], found["random_baseline"]["worst"]):
            for key, value in plant["values"].items():
                low, high = bounds[key]
                assert low <= value <= high, (controller, key, value)
    assert f"<!-- table: {study}-factors -->" in (ROOT / "docs" / "falsification.md").read_text()


def test_the_panda_certification_prose_matches_its_report():
    """docs/falsification.md: on the Panda's box at the preset's gains no law meets the whole
    requirement; on the error property alone the NN, Slotine-Li and the RBF network pass every
    draw and the PD and no-u0 fail every one; Slotine-Li fails by the torque alone, and of the
    NN, the sliding-mode term and the RBF network none but the NN exceeds the saturation share,
    while Slotine-Li hits no stop."""
    report = _read(FALSIFY_PANDA)
    laws = _laws(report)
    assert not any(e["certificates"][0]["holds"] for e in laws.values())
    error = {c: _certificate(report, c, "rms_error_after_2s")["k"] for c in laws}
    assert {c for c, k in error.items() if k == 0} == {"nn", "slotine-li", "rbf-nn"}
    assert error["pd"] == error["no-u0"] == 59
    # Slotine-Li: every failing draw fails the torque, and no other property fails
    assert _certificate(report, "slotine-li")["k"] == _certificate(report, "slotine-li", "rms_torque")["k"]
    assert all(c["k"] == 0 for c in laws["slotine-li"]["certificates"] if "rms_torque" not in c["property"])
    text = (ROOT / "docs" / "falsification.md").read_text()
    assert "No law meets it at the preset's gains." in text
    assert "On the error alone\nthe NN, Slotine–Li and the RBF network pass every draw" in text
    assert re.search(r"the PD and no-u0 on every one\. The torque is what fails", text)
    assert re.search(r"fails on\s+\d+ of 59 draws, each by the torque alone", text)
    assert re.search(r"where Slotine–Li\s+hits none", text)
    for c in ("nn", "sliding-mode", "rbf-nn", "no-u0"):  # "each drive a joint into a stop on 36"
        assert _certificate(report, c, "max_joint_limit_violation")["k"] == 36, c
    assert _certificate(report, "slotine-li", "max_joint_limit_violation")["k"] == 0


def test_the_paper_certification_prose_matches_its_report():
    """docs/falsification.md, falsify-paper's certification of the whole requirement: Slotine-Li
    alone passes every draw; every failing draw of the RBF network and of the sliding-mode term
    hits a stop; no-u0 and computed torque lose the path on every draw."""
    report = _read(FALSIFY_PAPER)
    laws = _laws(report)
    assert [c for c, e in laws.items() if e["certificates"][0]["k"] == 0] == ["slotine-li"]
    assert [c for c, e in laws.items() if e["certificates"][0]["holds"]] == ["slotine-li"]
    for c in ("rbf-nn", "sliding-mode"):
        assert _certificate(report, c)["k"] == _certificate(report, c, "max_joint_limit_violation")["k"], c
    for c in ("no-u0", "computed-torque"):
        assert _certificate(report, c, "tracking_error_ratio")["k"] == 59, c
    text = (ROOT / "docs" / "falsification.md").read_text()
    assert "**Only Slotine–Li meets the whole requirement.**" in text
    assert re.search(r"on\s+each failing draw a joint hits its stop", text)
    assert re.search(r"fail on all 59: they lose\s+the path", text)


def test_the_paper_worst_plants_saturate_and_run_away_as_the_text_says():
    """docs/falsification.md: Slotine-Li's worst plant on the paper's box saturates in the share
    of the steps quoted and runs away, and so does the RBF network's; on MuJoCo Slotine-Li's runs
    away too."""
    from nnrobust.run.experiment import run_experiment

    data = _read(FALSIFIED)
    text = (ROOT / "docs" / "falsification.md").read_text()
    slotine = _worst_config(data["controllers"]["slotine-li"]["worst"]["command"])
    metrics = run_experiment(slotine).metrics()
    said = float(
        re.search(r"on which it saturates in (\d+) % of the steps, runs away and gives", text).group(1)
    )
    assert 100 * metrics["saturated_fraction"] == pytest.approx(said, abs=0.5)
    assert metrics["runaway"] and metrics["rms_error_after_2s"] > 0.05
    rbf = _worst_config(data["controllers"]["rbf-nn"]["worst"]["command"])
    assert run_experiment(rbf).metrics()["runaway"]
    assert re.search(r"a plant on which it runs away and\s+loses the path entirely", text)


def test_on_the_pandas_box_tuned_no_u0_the_pd_and_the_rbf_are_falsified():
    """docs/falsification.md and README.md: at the tuned-panda study's kept settings the
    falsification finds a violation for no-u0, the PD (by the search alone) and the RBF network;
    the NN, the sliding mode and Slotine-Li hold the largest box the margin search reaches and
    none of their random plants or certification draws fails the error property. The RBF
    network, the most accurate on the validation draws, has the narrowest margin and the most
    random plants failing. No law meets the whole requirement: most draws fail the torque."""
    data = _read(PT)
    falsified = {c: e["falsified_by"] for c, e in data["controllers"].items() if e["falsified"]}
    assert falsified == {
        "no-u0-tuned": ["search", "random"],
        "pd-tuned": ["search"],
        "rbf-nn-tuned": ["search", "random"],
    }
    assert set(data["controllers"]) - set(falsified) == set(PT_HOLDS)
    for c in PT_HOLDS:
        margin = data["margin"][c]
        assert margin["violated_at"] is None and margin["holds_up_to"] == margin["largest_scale"], c
        assert _random_failures(c)(data) == 0, c
    assert data["controllers"]["pd-tuned"]["first_violation"] > 190  # "at its 194th of 200"
    assert _random_failures("pd-tuned")(data) == 0  # "none of its 200 random plants fails"
    margins = {c: _margin(c)(data) for c in data["margin"]}
    assert min(margins, key=margins.get) == "rbf-nn-tuned"
    failures = {c: _random_failures(c)(data) for c in data["controllers"]}
    assert max(failures, key=failures.get) == "rbf-nn-tuned"
    kept = _read("tuned_panda")["cases"]["panda-ellipse-noisy"]["controllers"]
    validation = {
        c: next(s["median_error"] for s in e["tuned"]["seeds"] if s["seed"] == e["tuned"]["kept_seed"])
        for c, e in kept.items()
        if c in SIX
    }
    assert min(validation, key=validation.get) == "rbf-nn"
    report = _read(FALSIFY_PANDA_TUNED)
    laws = _laws(report)
    assert not any(e["certificates"][0]["holds"] for e in laws.values())
    for c in laws:
        assert 2 * _certificate(report, c, "rms_torque")["k"] > 59, c  # most draws fail the torque
    error = {c: _certificate(report, c, "rms_error_after_2s")["k"] for c in laws}
    assert {c for c, k in error.items() if k} == {"no-u0-tuned", "rbf-nn-tuned"}
    text = (ROOT / "docs" / "falsification.md").read_text()
    assert "On the error alone every law but no-u0 and\n  the RBF network passes all 59." in text
    assert "**The NN compensator, the sliding-mode term and Slotine–Li hold the whole box:**" in text
    assert "The most accurate law on the validation draws is the most\n  fragile on the box." in text


def test_the_tuned_paper_certification_and_margins_are_what_the_text_says():
    """docs/falsification.md, falsify-paper-tuned: every law is falsified; every draw that fails a
    law's whole requirement fails its torque; no-u0 and the sliding mode hold the same scale;
    Slotine-Li has the widest margin and the PD the second; the PD's worst plants lie at low
    friction."""
    data = _read(FT)
    assert all(e["falsified"] for e in data["controllers"].values())
    report = _read(FALSIFY_PAPER_TUNED)
    for c in _laws(report):
        assert _certificate(report, c)["k"] == _certificate(report, c, "rms_torque")["k"], c
        assert not _certificate(report, c)["holds"], c
    assert _margin("no-u0-tuned")(data) == _margin("sliding-mode-tuned")(data)
    ranked = sorted(data["margin"], key=lambda c: -_margin(c)(data))
    assert ranked[:2] == ["slotine-li-tuned", "pd-tuned"]
    pd = data["controllers"]["pd-tuned"]  # its worst plants, the search's and random's: low friction
    assert pd["worst"]["values"]["plant.friction_scale"] < 0.65
    assert pd["random_baseline"]["worst"]["values"]["plant.friction_scale"] < 0.65
    text = (ROOT / "docs" / "falsification.md").read_text()
    assert "every failing draw\n  needs more than the 10 N m RMS" in text
    assert "the widest of the six" in text and re.search(r"is second\s+to Slotine–Li's", text)


def test_the_tuned_rbf_setting_fails_at_the_centre_of_the_papers_box():
    """docs/falsification.md: the RBF network's kept setting (noisy case b) fails at the box's
    centre (the disturbance x 1.25: margin 0), saturating and hitting a stop, with the error
    quoted, and still tracks at x 1.1 to the quoted error; the tuned PD's worst plant saturates as
    quoted and runs away."""
    from nnrobust.run.experiment import run_experiment

    data = _read(FT)
    assert data["margin"]["rbf-nn-tuned"]["holds_up_to"] == 0.0
    centre = _worst_config(data["margin"]["rbf-nn-tuned"]["violating_plant"]["command"])
    assert centre.plant.disturbance_scale == 1.25 and centre.plant.friction_scale == 1.0
    text = (ROOT / "docs" / "falsification.md").read_text()
    said = re.search(
        r"there its kept setting saturates in (\d+) %\s+of the steps, drives a joint into its stop"
        r" and gives ([\d.]+) mm",
        text,
    )
    metrics = run_experiment(centre).metrics()
    assert 100 * metrics["saturated_fraction"] == pytest.approx(float(said.group(1)), abs=0.5)
    assert metrics["max_joint_limit_violation"] > 0
    assert 1e3 * metrics["rms_error_after_2s"] == pytest.approx(float(said.group(2)), abs=0.05)
    quoted = float(re.search(r"at × 1\.1 it still tracks to\s+([\d.]+) mm", text).group(1))
    lower = run_experiment(centre.replace(plant={"disturbance_scale": 1.1})).metrics()["rms_error_after_2s"]
    assert 1e3 * lower == pytest.approx(quoted, abs=0.005) and lower < 0.0005
    pd = run_experiment(_worst_config(data["controllers"]["pd-tuned"]["worst"]["command"])).metrics()
    said = float(
        re.search(r"it saturates in (\d+) % of the steps and runs away\. \d+ of the 200", text).group(1)
    )
    assert 100 * pd["saturated_fraction"] == pytest.approx(said, abs=0.5) and pd["runaway"]


def test_the_previous_regenerations_figures_are_commit_a3a2eb5s():
    """docs/falsification.md quotes the previous regeneration (commit a3a2eb5, before the
    optimiser seeds derived from each law's name): its tuned paper margins and PD, and on the
    Panda its NN falsified by one random plant while the RBF network and the PD held. Read from
    git, so skipped where the history is not there."""
    import json
    import subprocess

    def old(name):
        try:
            out = subprocess.run(
                ["git", "show", f"a3a2eb5:docs/data/{name}.json"], cwd=ROOT, capture_output=True, check=True
            ).stdout
        except (OSError, subprocess.CalledProcessError):
            pytest.skip("commit a3a2eb5 is not in this checkout's history")
        laws = _laws(json.loads(out))
        return {
            "controllers": {c: e["falsification"] for c, e in laws.items()},
            "margin": {c: e["margin"] for c, e in laws.items() if e.get("margin")},
        }

    text = (ROOT / "docs" / "falsification.md").read_text()
    paper = old("falsify_paper_tuned")
    said = re.search(r"whose PD held ([\d.]+) of the box\s+and gave ([\d.]+) mm at worst", text)
    assert float(said.group(1)) == pytest.approx(_margin("pd-tuned")(paper), abs=0.005)
    assert float(said.group(2)) == pytest.approx(1e3 * _falsified("pd-tuned")(paper), abs=0.05)
    said = re.search(
        r"other margins: no-u0 ([\d.]+), the\s+sliding mode ([\d.]+), Slotine–Li ([\d.]+)\.", text
    )
    for quoted, law in zip(said.groups(), ("no-u0-tuned", "sliding-mode-tuned", "slotine-li-tuned")):
        half = 0.5 * 10 ** -len(quoted.split(".")[1])  # half the last printed digit
        assert float(quoted) == pytest.approx(_margin(law)(paper), abs=half), law
    assert all(e["falsified"] for e in paper["controllers"].values())  # "falsified every law as here"
    panda = old("falsify_panda_tuned")
    said = re.search(r"one random plant\s+falsified the NN \((\d+) mm, margin ([\d.]+)\)", text)
    nn = panda["controllers"]["nn-tuned"]
    assert nn["falsified_by"] == ["random"]
    assert float(said.group(1)) == pytest.approx(
        1e3 * _falsified("nn-tuned", "random_baseline")(panda), abs=0.5
    )
    assert float(said.group(2)) == pytest.approx(_margin("nn-tuned")(panda), abs=0.005)
    assert (
        not panda["controllers"]["rbf-nn-tuned"]["falsified"]
        and not panda["controllers"]["pd-tuned"]["falsified"]
    )
    assert re.search(r"the RBF network and the PD held the whole box", text)
