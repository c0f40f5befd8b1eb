"""Write the tables of README.md and docs/ from the benchmark results in docs/data/.

    python docs/render_tables.py            # rewrite the tables in place
    python docs/render_tables.py --check    # exit 1 if a table differs from its data

Each table sits between ``<!-- table: NAME -->`` and ``<!-- /table -->`` in a Markdown file and
is rendered from docs/data/*.json, which the benchmark scripts write (each table says which
command made its data). tests/docs_numbers/ runs the check and re-runs one row of every
data file, so the numbers in the docs are those the current code produces.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from statistics import median

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "docs" / "data"
DOCUMENTS = (
    "README.md",
    "docs/controller.md",
    "docs/plant.md",
    "docs/fair-comparison.md",
    "docs/robots.md",
    "docs/robustness.md",
    "docs/engines.md",
    "docs/falsification.md",
    "docs/learning.md",
    "docs/serve.md",
    "docs/compiled.md",
)
TABLE = re.compile(r"(<!-- table: (?P<name>[\w-]+) -->\n)(?P<body>.*?)(<!-- /table -->)", re.S)


def _data(name: str) -> dict:
    return json.loads((DATA / f"{name}.json").read_text())


def _mm(value: float) -> str:
    return f"{1e3 * value:.3g}" if value is not None else "–"


def _warn(row: dict) -> str:
    kinds = [w.split(":")[0] for w in row["warnings"]]
    return ", ".join(kinds) if kinds else "none"


def _markdown(
    columns: list[tuple[str, str, object]], rows: list[dict], made_by: str = "", chaos_note: bool = True
) -> str:
    """A Markdown table: ``columns`` are (header, "l" or "r", function of the row giving the cell)."""
    lines = [
        "| " + " | ".join(h for h, _, _ in columns) + " |",
        "|" + "|".join("---" if a == "l" else "---:" for _, a, _ in columns) + "|",
    ]
    lines += ["| " + " | ".join(cell(r) for _, _, cell in columns) + " |" for r in rows]
    note = f"\n\n{CHAOS_NOTE}" if chaos_note and any(r.get("chaotic") for r in rows) else ""
    return "\n".join(lines) + note + (f"\n\nMade by `{made_by}`.\n" if made_by else "\n")


def _g3(key: str, scale: float = 1.0):
    return lambda r: "–" if r.get(key) is None else f"{scale * r[key]:.3g}"


def _text(key: str):
    return lambda r: str(r[key])


def _probed(key: str, scale: float = 1.0):
    """A metric's cell: 3 significant digits, or for a chaotic row its range over the chaos probes
    (benchmarks/_common.py: the disturbance scaled by 1 +- 1e-6) marked †."""

    def cell(r):
        if r.get(key) is None:
            return "–"
        if r.get("chaotic") and f"{key}_min" in r:
            return f"{scale * r[f'{key}_min']:.3g}–{scale * r[f'{key}_max']:.3g} †"
        return f"{scale * r[key]:.3g}"

    return cell


CHAOS_NOTE = (
    "† chaotic: scaling the disturbance by 1 ± 1e-6 moves this run's metrics by more than 1 %; "
    "the range is over the three runs, and no digit beyond it means anything."
)

ERROR = ("RMS error, t ≥ 2 s [mm]", "r", _probed("rms_error_after_2s", 1e3))
TORQUE = ("RMS torque [N m]", "r", _probed("rms_torque"))
CHATTER = ("chatter [N m]", "r", _probed("torque_chatter"))
SATURATED = ("saturated steps [%]", "r", lambda r: f"{100 * r['saturated_fraction']:.1f}")
WARNINGS = ("warnings", "l", _warn)


def paper_reproduction() -> str:
    return _markdown(
        [
            ("case", "l", _text("case")),
            ("controller", "l", _text("variant")),
            ERROR,
            TORQUE,
            CHATTER,
            SATURATED,
            WARNINGS,
        ],
        _data("paper_reproduction")["rows"],
        "python benchmarks/paper_reproduction.py --json docs/data/paper_reproduction.json",
    )


def nn_options() -> str:
    return _markdown(
        [
            ("variant", "l", _text("variant")),
            ERROR,
            ("max e [mm]", "r", lambda r: _mm(r["max_error"])),
            TORQUE,
            CHATTER,
            SATURATED,
            ("ρ̂ at 20 s", "r", _g3("final_rho_hat")),
        ],
        _data("nn_options")["rows"],
        "python benchmarks/nn_options.py --json docs/data/nn_options.json",
    )


def subtask() -> str:
    return _markdown(
        [
            ("variant", "l", _text("variant")),
            ("h two laps before the end", "r", lambda r: f"{r['h_start']:.4f}"),
            ("h at 20 s", "r", lambda r: f"{r['h_end']:.4f}"),
            ERROR,
            TORQUE,
        ],
        _data("subtask")["rows"],
        "python benchmarks/subtask.py --json docs/data/subtask.json",
    )


def arm_presets() -> str:
    return _markdown(
        [
            ("preset", "l", _text("preset")),
            ("controller", "l", _text("controller")),
            ERROR,
            ("RMS rotation error [mrad]", "r", _g3("rms_orientation_error_after_2s", 1e3)),
            TORQUE,
            CHATTER,
            SATURATED,
            WARNINGS,
        ],
        _data("arm_presets")["rows"],
        "python benchmarks/arm_presets.py --json docs/data/arm_presets.json",
    )


def torque_speed() -> str:
    return _markdown(
        [
            ("preset", "l", _text("preset")),
            ("envelope", "l", _text("envelope")),
            ("RMS error, t ≥ 2 s [mm]", "r", lambda r: _mm(r["rms_error_after_2s"])),
            SATURATED,
            ("peak speed / limit", "r", _g3("max_speed_ratio")),
            WARNINGS,
        ],
        _data("torque_speed")["rows"],
        "python benchmarks/torque_speed.py --json docs/data/torque_speed.json",
        chaos_note=False,
    )


def plant_convergence() -> str:
    data = _data("plant_convergence")

    def value(key, scale=1.0):  # a chaotic row: the median over its runs at the default step
        def cell(r):
            v = r.get(f"{key}_median", r[key]) if r["chaotic"] else r[key]
            return f"{scale * v:.3g}"

        return cell

    def delta(key):
        def cell(r):
            if r["both_diverged"]:
                return "–"
            if r["chaotic"]:
                return f"{100 * r[f'{key}_median_difference']:.2f} (p = {r[f'{key}_p']:.2g})"
            return f"{100 * r[f'{key}_relative_difference']:.2f}"

        return cell

    def verdict(r):
        if r["both_diverged"]:
            return "diverges at both steps"
        label = "converged" if r["converged"] else "**not converged**"
        if r["chaotic"]:
            runs = len(data["probes"]) + 1
            label += (
                f" (chaotic: {runs} runs per step; diverged {r['diverged_runs']} and "
                f"{r['fine_diverged_runs']})"
            )
        return label

    table = _markdown(
        [
            ("preset", "l", _text("preset")),
            ("controller", "l", _text("controller")),
            ("RMS error [mm]", "r", value("rms_error_after_2s", 1e3)),
            ("Δ error [%]", "r", delta("rms_error_after_2s")),
            ("RMS torque [N m]", "r", value("rms_torque")),
            ("Δ torque [%]", "r", delta("rms_torque")),
            ("chatter [N m]", "r", value("torque_chatter")),
            ("Δ chatter [%]", "r", delta("torque_chatter")),
            ("stick-slip events", "r", _text("friction_events")),
            ("cut periods", "r", _text("refined_periods")),
            ("verdict", "l", verdict),
        ],
        data["rows"],
        chaos_note=False,
    )
    converged = sum(r["converged"] for r in data["rows"])
    return table + (
        f"\nΔ: the default step (one RK4 step per 1 ms period, cut where a joint turns more than "
        f"0.02 rad in one) against {data['fine']} steps per period; tolerances 2 % (error, "
        f"torque) and 10 % (chatter). A chaotic row gives the median over its runs at the "
        f"default step and, as Δ, the difference between the two steps' medians with the "
        f"two-sided Mann–Whitney p-value of their runs; a metric agrees when p ≥ "
        f"{data['alpha']:g} or Δ is within its tolerance, and the row converges when every "
        f"metric agrees and Fisher's exact p on the diverged runs is ≥ {data['alpha']:g}. Cut "
        f"periods: control periods whose step was cut for speed or for a stop's contact. "
        f"{converged} of {len(data['rows'])} runs converged. Made by `python "
        "benchmarks/plant_convergence.py --json docs/data/plant_convergence.json`.\n"
    )


def adaptive_step() -> str:
    def rotation(r):
        return "fixed 1 ms step" if r["max_step_rotation"] is None else f"{r['max_step_rotation']:g}"

    return _markdown(
        [
            ("max_step_rotation [rad]", "l", rotation),
            ("energy drift", "r", lambda r: f"{r['energy_drift']:.2g}"),
            ("fastest joint [rad/s]", "r", lambda r: f"{r['max_joint_speed']:.0f}"),
            ("cut periods", "r", lambda r: f"{r['refined_periods']} of {r['periods']}"),
            ("wall [s]", "r", lambda r: f"{r['wall_seconds']:.2f}"),
        ],
        _data("adaptive_step")["rows"],
        "python benchmarks/adaptive_step.py --json docs/data/adaptive_step.json",
    )


def friction_compensation() -> str:
    def spread(key, scale=1.0):
        def cell(r):
            low, mid, high = (scale * r[k] for k in (f"{key}_min", key, f"{key}_max"))
            same = f"{low:.3g}" == f"{high:.3g}"
            return f"{mid:.3g}" if same else f"{mid:.3g} ({low:.3g}–{high:.3g})"

        return cell

    return _markdown(
        [
            ("variant", "l", _text("variant")),
            ("RMS error, t ≥ 2 s [mm]", "r", spread("rms_error_after_2s", 1e3)),
            ("RMS torque [N m]", "r", spread("rms_torque")),
            ("chatter [N m]", "r", spread("torque_chatter")),
        ],
        _data("friction_compensation")["rows"],
        "python benchmarks/friction_compensation.py --json docs/data/friction_compensation.json",
    )


TUNED_STUDIES = ("tuned-paper", "tuned-panda")
"""The shipped studies of the fair comparison (benchmarks/studies/), their report.json copied to
docs/data/tuned_paper.json and tuned_panda.json by `make docs-data`."""


def _study_command(study: str) -> str:
    """The command that makes a shipped study's report (benchmarks/studies/STUDY.toml)."""
    return f"nnrobust study benchmarks/studies/{study}.toml --out out/{study} --workers 2"


TUNED_COMMAND = " and ".join(_study_command(s) for s in TUNED_STUDIES)

TUNED_LABELS = {
    "paper-line": "case (a) line",
    "paper-ellipse": "case (b) ellipse",
    "panda-ellipse": "Panda ellipse",
}
"""Each case's name in the tables (its sensing, ideal or noisy, follows)."""


def tuned_cases() -> list[dict]:
    """Every case of the tuned studies, in their order: its label, its report entry, the study's
    controllers (in the study file's order), its budgets."""
    from nnrobust.studies.study import load_study

    out = []
    for study in TUNED_STUDIES:
        report = _data(study.replace("-", "_"))
        controllers = load_study(ROOT / "benchmarks" / "studies" / f"{study}.toml").controllers
        for name, case in report["cases"].items():
            arm = name.removesuffix("-noisy")
            sensing = "noisy" if name.endswith("-noisy") else "ideal"
            names = set(case["controllers"]) | set(case["not_kept"])
            order = [c for c in controllers if c in names]
            out.append(
                {
                    "label": f"{TUNED_LABELS.get(arm, arm)}, {sensing}",
                    "name": name,
                    "case": case,
                    "controllers": order,
                    "budgets": report["budgets"],
                }
            )
    return out


def tuned_seed_errors(case: dict, name: str) -> list[float]:
    """The validation median RMS error [m] of a controller's best setting for each optimiser seed
    of a case whose setting met the constraints on the validation draws (``feasible``): a seed
    that broke them is not a result under the constraints, so no table ranks it."""
    entry = case["controllers"].get(name)
    tuned = entry["tuned"] if entry is not None else None
    if not tuned:
        return []
    return [
        s["median_error"] for s in tuned["seeds"] if s["median_error"] is not None and s.get("feasible", True)
    ]


def _paired(case: dict, a: str, b: str) -> dict | None:
    """The paired comparison of a and b on the certification draws, as "a - b"."""
    for pair in case["paired"]:
        if (pair["a"], pair["b"]) == (a, b):
            return pair
        if (pair["a"], pair["b"]) == (b, a):
            k, n, ties = pair["a_better"], pair["n"] - pair["undefined"], pair["ties"]
            low, high = pair["interval"]
            return {**pair, "a": a, "b": b, "a_better": n - k - ties, "interval": [-high, -low],
                    "median_difference": -pair["median_difference"]}  # fmt: skip
    return None


def tuned_verdict(case: dict, names: list[str]) -> dict:
    """A case's verdict: the controller with the least median validation error over the seeds,
    whether it is clear (its worst seed beats every other controller's best seed), the NN's
    median over the best other controller's, and the paired comparison of the two on the
    certification draws."""
    medians = {n: median(e) for n in names if (e := tuned_seed_errors(case, n))}
    best = min(medians, key=medians.__getitem__)
    others = [n for n in medians if n != best]
    clear = all(max(tuned_seed_errors(case, best)) < min(tuned_seed_errors(case, n)) for n in others)
    rival = min((n for n in medians if n != "nn"), key=medians.__getitem__)
    return {
        "best": best,
        "clear": clear,
        "medians": medians,
        "rival": rival,
        "nn_ratio": medians["nn"] / medians[rival] if "nn" in medians else None,
        "paired": _paired(case, rival, "nn") if "nn" in medians else None,
    }


def tuned_convergence(case: dict, name: str) -> dict | None:
    """A controller's convergence record in a tuned case (its report entry's
    ``tuned.convergence``: the kept seed's validation median at half the budget and at the whole,
    their relative change and the tolerance), None if the law was not tuned there."""
    entry = case["controllers"].get(name)
    return (entry.get("tuned") or {}).get("convergence") if entry is not None else None


def _not_converged(case: dict, names: list[str]) -> list[str]:
    return [n for n in names if (conv := tuned_convergence(case, n)) and not conv["converged"]]


def tuned_headline() -> str:
    cases = tuned_cases()
    seeds = {c["budgets"]["seeds"] for c in cases}.pop()

    def cell(c, name):
        errors = tuned_seed_errors(c["case"], name)
        if not errors:
            return "no setting met the constraints"
        text = f"{1e3 * median(errors):.3g} ({1e3 * min(errors):.2g}–{1e3 * max(errors):.2g})"
        text += f", {len(errors)} of {seeds} seeds" if len(errors) < seeds else ""
        text += " †" if _not_converged(c["case"], [name]) else ""
        return f"**{text}**" if tuned_verdict(c["case"], c["controllers"])["best"] == name else text

    columns = [("controller", "l", _text("controller"))] + [
        (c["label"], "r", lambda r, c=c: cell(c, r["controller"])) for c in cases
    ]
    names = list(dict.fromkeys(n for c in cases for n in c["controllers"]))
    limits = sorted({c["budgets"]["max_rms_torque"] for c in cases})
    budget = {c["budgets"]["tune"] for c in cases}.pop()
    validation = {c["budgets"]["validation"] for c in cases}.pop()
    same = [c["label"] for c in cases if not c["case"]["held_out"]]
    tolerance = {
        conv["tolerance"]
        for c in cases
        for n in c["controllers"]
        if (conv := tuned_convergence(c["case"], n))
    }.pop()
    unconverged = sum(len(_not_converged(c["case"], c["controllers"])) for c in cases)
    tuned = sum(1 for c in cases for n in c["controllers"] if tuned_convergence(c["case"], n))
    return _markdown(columns, [{"controller": n} for n in names]) + (
        f"\nRMS task error (t ≥ 2 s) in mm of each controller's best setting under the constraints, "
        f"on {validation} validation draws the tuning never ran: per optimiser seed the median over "
        f"the draws; the cell gives the median over the seeds (0 to {seeds - 1}) whose setting met the "
        f"constraints on those draws ({seeds} unless the cell says fewer: a seed that broke them is "
        f"no result under them) and in brackets the least and the greatest. Each seed gave every "
        f"controller {budget} simulations per case: "
        f"RMS torque ≤ {' or '.join(f'{v:g}' for v in limits)} N m (the paper's arm or the Panda), "
        f"at most {100 * cases[0]['budgets']['max_saturated']:g} % saturated steps, no runaway, no "
        "stop hit. The least median is in bold. Held out means other plants only where draws differ "
        "(sensor noise, the Panda's drawn model error); "
        + (
            f"in {' and '.join(same)} every draw is the same plant: validated on the training plant. "
            if same
            else ""
        )
        + f"† not converged at {budget} simulations ({unconverged} of {tuned} kept tunings, one per "
        f"law and case): the kept "
        f"seed's validation median moved by more than {100 * tolerance:g} % between {budget // 2} "
        f"and {budget} simulations, so a longer search may still lower it. "
        f"Made by `{TUNED_COMMAND}`.\n"
    )


def tuned_verdicts() -> str:
    rows = []
    for c in tuned_cases():
        v = tuned_verdict(c["case"], c["controllers"])
        pair = v["paired"]
        rows.append(
            {
                "case": c["label"],
                "best": v["best"],
                "clear": "yes" if v["clear"] else "no: within the seeds' spread",
                "nn": "–" if v["nn_ratio"] is None else f"{v['nn_ratio']:.2g}",
                "rival": v["rival"],
                "converged": ", ".join(
                    f"{n} not"
                    for n in _not_converged(c["case"], list(dict.fromkeys([v["best"], v["rival"], "nn"])))
                )
                or "yes",
                "paired": "–"
                if pair is None
                else f"one plant: {1e3 * pair['median_difference']:.2g} mm on every draw, no test"
                if pair.get("plants") == 1
                else (
                    f"{pair['a_better']} of {pair['n'] - pair['undefined']}, "
                    f"{1e3 * pair['median_difference']:.2g} mm "
                    f"({1e3 * pair['interval'][0]:.2g} to {1e3 * pair['interval'][1]:.2g}), "
                    f"sign test p = {pair['sign_p']:.2g} (Holm {pair['holm_p']:.2g})"
                ),
            }
        )
    return _markdown(
        [
            ("case", "l", _text("case")),
            ("least median error", "l", _text("best")),
            ("every seed better than every other controller's?", "l", _text("clear")),
            ("NN median / best other's", "r", _text("nn")),
            ("best other", "l", _text("rival")),
            ("converged at the budget?", "l", _text("converged")),
            ("best other better than NN, paired on the certification draws", "l", _text("paired")),
        ],
        rows,
        TUNED_COMMAND,
    ) + (
        "The paired column: on how many certification draws the best other law's kept setting "
        "has the lower error, the median of its error minus the NN's with its distribution-free "
        "order-statistic interval (nominal 95 %), and the two-sided sign test with its p after "
        "Holm's correction over the case's pairs ([robustness.md](robustness.md#paired-comparisons)); "
        "where every draw is the same plant the draws are one comparison, and no test is made. "
        "The converged column names the least-error law, the best other and the NN where their "
        "tuning had not converged at the budget (the headline table's †): such a verdict holds at "
        "that budget only.\n"
    )


def tuned_settings() -> str:
    rows = []
    for c in tuned_cases():
        for name in c["controllers"]:
            entry = c["case"]["controllers"].get(name)
            tuned = entry["tuned"] if entry is not None else None
            if not tuned:
                rows.append({"case": c["label"], "controller": name, "seed": "all", "setting": "–",
                             "error": "–", "bounds": c["case"]["not_kept"].get(name, "–")})  # fmt: skip
                continue
            for seed in tuned["seeds"]:
                setting = ", ".join(
                    f"{k.split('.')[-1]} {v[0] if isinstance(v, list) else v:.3g}"
                    for k, v in seed["settings"].items()
                    if k != "nn.eps0"
                )
                bounds = (
                    "; ".join(
                        f"{b['param']} {b['side']}" + (" (physical)" if b["physical"] else "")
                        for b in seed["at_bound"]
                    )
                    or "interior"
                )
                kept = " (kept)" if seed["seed"] == tuned["kept_seed"] else ""
                rows.append(
                    {
                        "case": c["label"],
                        "controller": name,
                        "seed": f"{seed['seed']}{kept}",
                        "setting": setting,
                        "error": _mm(seed["median_error"]),
                        "bounds": bounds,
                    }
                )
    return _markdown(
        [
            ("case", "l", _text("case")),
            ("controller", "l", _text("controller")),
            ("seed", "r", _text("seed")),
            ("best setting", "l", _text("setting")),
            ("validation error [mm]", "r", _text("error")),
            ("on a bound", "l", _text("bounds")),
        ],
        rows,
        TUNED_COMMAND,
    )


def _requirement(entry: dict, names: dict) -> tuple[dict, str]:
    """A law's certificates in a study report: the first is the whole requirement (every property
    at once), the others one property each. Returns the first and the failing draws of each
    property that failed on some draw, by the report's ``property_names`` ("torque 18, stops
    21"), "none" if none did."""
    whole, *parts = entry["certificates"]
    failing = [f"{names.get(c['property'], c['property'])} {c['k']}" for c in parts if c["k"]]
    return whole, ", ".join(failing) or ("none" if parts else "–")


def _certificate_cells(entry: dict, names: dict) -> dict:
    """A law's certificate cells (:func:`_certificate_columns`): k of N failing the requirement,
    the failing draws of each property, the bound, its verdict."""
    c, parts = _requirement(entry, names)
    return {
        "failing": f"{c['k']} of {c['N']}",
        "parts": parts,
        "bound": f"{100 * c['p_upper']:.1f} %",
        "certified": "yes" if c["holds"] else "no",
    }


def _certificate_columns(entry: dict, beta: float) -> list[tuple]:
    """The columns of a study report's certificates (``entry`` is one law's, naming the
    requirement and the claim): the draws failing the requirement and each of its properties, the
    Clopper-Pearson bound on P(fail) and whether the sampled claim over the box holds."""
    c, _ = _requirement(entry, {})
    return [
        (f"draws failing the requirement ({c['property']})", "r", _text("failing")),
        ("failing draws by property", "l", _text("parts")),
        (f"P(fail) ≤ ({100 * (1 - beta):g} % confidence)", "r", _text("bound")),
        (f"P(fail) ≤ {100 * c['epsilon']:g} % over the box, sampled", "l", _text("certified")),
    ]


def _robustness(name: str):
    """A robustness study's report (docs/data/<name>.json): per case (a disturbance scale) and
    controller, on the certification draws, the RMS error's median, 95th percentile and worst,
    the RMS torque, the saturated steps and the certificate; then the runs on which each warning
    fired, over every case."""

    def render() -> str:
        report = _data(name.replace("-", "_"))
        rows = []
        for case_name, case in report["cases"].items():
            scale = case["set"].get("plant.disturbance_scale")
            for controller, entry in case["controllers"].items():
                stats = entry["statistics"]
                error, torque = stats["rms_error_after_2s"], stats["rms_torque"]
                rows.append(
                    {
                        "case": f"{case_name} (× {scale:g})",
                        "controller": controller,
                        "completed": f"{100 * stats['success_rate']:.0f} %",
                        "median": _mm(error["median"]),
                        "p95": _mm(error["p95"]),
                        "max": _mm(error["max"]),
                        "torque": f"{torque['median']:.3g}",
                        "torque_p95": f"{torque['p95']:.3g}",
                        "saturated": f"{100 * stats['saturated_fraction_mean']:.2g}",
                        **_certificate_cells(entry, report.get("property_names", {})),
                    }
                )
        columns = [
            ("disturbance", "l", _text("case")),
            ("controller", "l", _text("controller")),
            ("completed", "r", _text("completed")),
            ("median error [mm]", "r", _text("median")),
            ("p95 [mm]", "r", _text("p95")),
            ("max [mm]", "r", _text("max")),
            ("median torque [N m]", "r", _text("torque")),
            ("p95 [N m]", "r", _text("torque_p95")),
            ("saturated steps [%]", "r", _text("saturated")),
            *_certificate_columns(entry, report["budgets"]["beta"]),
        ]
        table = _markdown(columns, rows)
        counts: dict[str, dict[str, int]] = {}
        runs: dict[str, int] = {}
        for case in report["cases"].values():
            for controller, entry in case["controllers"].items():
                runs[controller] = runs.get(controller, 0) + entry["statistics"]["rows"]
                for kind, n in entry["warnings"].items():
                    counts.setdefault(controller, {})
                    counts[controller][kind] = counts[controller].get(kind, 0) + n
        kinds = sorted({k for c in counts.values() for k in c})
        if kinds:
            table += "\nRuns on which each warning fired, over every case "
            table += "(docs/plant.md#verdicts-in-metricsjson):\n\n"
            table += _markdown(
                [("controller", "l", _text("controller")), ("runs", "r", _text("runs"))]
                + [(k, "r", lambda e, k=k: str(e["counts"].get(k, 0))) for k in kinds],
                [{"controller": c, "runs": runs[c], "counts": counts.get(c, {})} for c in runs],
            )
        errors = "errors are RMS over t ≥ 2 s"
        return table + (
            f"\n{rows[0]['failing'].split(' of ')[1]} draws per case; {errors}. "
            f"Made by `{_study_command(name)}` (report.json).\n"
        )

    return render


def example_study() -> str:
    """examples/study.toml's report (docs/data/example_study.json, report.json with the repository's
    path taken out): each controller's error and effort on the certification draws, the share that
    passed the whole requirement and its bound, the worst plant and MuJoCo's figures."""
    report = _data("example_study")
    ((case, entry),) = report["cases"].items()
    rows = [{"controller": name, **e} for name, e in entry["controllers"].items()]
    certified = ", ".join(f"`{r}`" for r in report.get("certified_properties", report["require"]))
    seeds = report["budgets"]["seeds"]

    def stat(e, key="rms_error_after_2s", which="median", engine=None, scale=1e3):
        block = e["engines"][engine] if engine else e["statistics"]
        value = block[key][which]
        return "–" if value is None else f"{scale * value:.3g}"

    def settings(e):
        trained = (e.get("training") or {}).get("simulated_seconds")
        budget = "" if trained is None else f", {trained:.0f} simulated s"
        if e.get("fixed"):
            return "fixed (trained offline" + budget + ")"
        if e.get("trained"):  # the study's train stage: its own seeds
            by = e["trained"]
            return f"trained ({by['algorithm'].upper()}), best of {len(by['curves'])} seeds{budget}"
        return f"tuned, best of {seeds} seeds{budget}"

    def passed(e):
        whole = e["certificates"][0]
        return f"{100 * (1 - whole['k'] / whole['N']):.0f}"

    table = _markdown(
        [
            ("controller", "l", _text("controller")),
            ("settings", "l", settings),
            ("median error [mm]", "r", lambda e: stat(e)),
            ("median RMS torque [N m]", "r", lambda e: stat(e, "rms_torque", scale=1.0)),
            ("saturated [%]", "r", lambda e: f"{100 * e['statistics']['saturated_fraction_mean']:.3g}"),
            ("passed [%]", "r", passed),
            ("P(fail) ≤", "r", lambda e: f"{e['certificates'][0]['p_upper']:.3g}"),
            ("worst plant [mm]", "r", lambda e: f"{1e3 * e['worst']['metrics']['rms_error_after_2s']:.3g}"),
            ("least margin", "r", lambda e: f"{e['worst']['margin']:.3g}"),
            ("MuJoCo median [mm]", "r", lambda e: stat(e, engine="mujoco")),
        ],
        rows,
    )
    n = rows[0]["certificates"][0]["N"]
    dropped = "".join(f"{c} was not kept: {why}. " for c, why in entry.get("not_kept", {}).items())
    return table + (
        f"\n{dropped}{case}, {n} certification draws of the box per controller; errors and torques are "
        "RMS over "
        f"t ≥ 2 s and the run; saturated is the mean share of saturated steps; passed is the share of "
        f"draws that met the whole requirement ({certified}) and P(fail) its sampled bound at 95 % "
        f"confidence; the worst plant and the margin are the falsifier's ({report['budgets']['falsify']} "
        "simulations). Made by `nnrobust study examples/study.toml --out out/study` (report.json).\n"
    )


def _gap_cell(variant: str):
    """A variant's RMS error t >= 2 s [mm] and, for MuJoCo, its change from Pinocchio's in %."""

    def cell(r):
        value, reference = r[variant].get("rms_error_after_2s"), r["pinocchio"].get("rms_error_after_2s")
        if value is None:
            return r[variant].get("status", "–")
        text = f"{1e3 * value:.3g}"
        if variant != "pinocchio" and reference:
            text += f" ({100 * (value - reference) / reference:+.1f} %)"
        return text + ("" if r[variant].get("status") == "completed" else f" {r[variant]['status']}")

    return cell


def _flips(variant: str):
    """The verdicts that differ between Pinocchio's run and the variant's."""

    def cell(r):
        pin, other = r["verdicts"]["pinocchio"], r["verdicts"][variant]
        keys = dict.fromkeys([*pin, *other])
        flips = [
            f"{k}: {pin.get(k, 'no')} → {other.get(k, 'no')}"
            for k in keys
            if pin.get(k, "no") != other.get(k, "no")
        ]
        return "; ".join(flips) or "none"

    return cell


GAP_COLUMNS = [
    ("Pinocchio [mm]", "r", _gap_cell("pinocchio")),
    ("MuJoCo RK4", "r", _gap_cell("mujoco")),
    ("RK4, 4× steps", "r", _gap_cell("mujoco_fine")),
    ("implicitfast", "r", _gap_cell("implicitfast")),
    ("implicitfast, 4× steps", "r", _gap_cell("implicitfast_fine")),
    ("verdicts that change (RK4)", "l", _flips("mujoco")),
    ("(implicitfast)", "l", _flips("implicitfast")),
]
GAP_COMMAND = "python benchmarks/engine_gap.py --json docs/data/engine_gap.json"


def engine_gap_presets() -> str:
    columns = [("preset", "l", _text("preset")), ("controller", "l", _text("controller")), *GAP_COLUMNS]
    return _markdown(columns, _data("engine_gap")["presets"], GAP_COMMAND)


def engine_gap_tuned() -> str:
    columns = [
        ("case", "l", lambda r: f"{TUNED_LABELS.get(r['case'], r['case'])}, {r['sensing']}"),
        ("controller", "l", _text("controller")),
        ("sample", "r", _text("sample")),
        *GAP_COLUMNS,
    ]
    return _markdown(columns, _data("engine_gap")["tuned"], GAP_COMMAND)


def _margin_cell(margin: dict | None) -> str:
    if not margin:
        return "–"
    holds, violated = margin["holds_up_to"], margin["violated_at"]
    if violated is None:
        return f"at least {margin['largest_scale']:.2g} (no violation found)"
    if violated == 0:
        return "0: the nominal plant fails"
    return f"{holds:.2g} (violated at {violated:.2g})"


def _certificate_cell(certified: dict | None) -> str:
    """The random baseline's certificate of the (first) property: k of N failing, the bound."""
    if not certified:
        return "–"
    c = certified["certificates"][0]
    bound = f"{100 * c['p_upper']:.1f}".removesuffix(".0")
    return f"{c['k']} of {c['N']}: {bound} %"


def _certified_box(name: str):
    """A falsification study's certification stage (its report.json): each law at its own
    settings on N fresh draws of the box, the RMS error's median, 95th percentile and worst, the
    draws failing the property and the Clopper-Pearson bound on P(fail)."""

    def render() -> str:
        report = _data(name)
        (case,) = report["cases"].values()
        rows = []
        for controller, entry in case["controllers"].items():
            error = entry["statistics"]["rms_error_after_2s"]
            rows.append(
                {
                    "controller": controller,
                    "median": _mm(error["median"]),
                    "p95": _mm(error["p95"]),
                    "max": _mm(error["max"]),
                    **_certificate_cells(entry, report.get("property_names", {})),
                }
            )
        columns = [
            ("controller", "l", _text("controller")),
            ("median RMS error after 2 s [mm]", "r", _text("median")),
            ("95th percentile [mm]", "r", _text("p95")),
            ("worst [mm]", "r", _text("max")),
            *_certificate_columns(entry, report["budgets"]["beta"]),
        ]
        return _markdown(columns, rows, _study_command(report["study"]))

    return render


def _falsified(name: str):
    """A falsification study's falsification stage (its report.json's ``falsification`` and
    ``margin`` entries): per controller, its worst plant and the random baseline's, the plant's
    friction, disturbance and payload, the margin and the baseline's certificate."""

    def render() -> str:
        report = _data(name)
        (case,) = report["cases"].values()
        rows = []
        for controller, law in case["controllers"].items():
            entry = law["falsification"]
            worst, baseline = entry["worst"], entry["random_baseline"]["worst"]
            values = worst["values"]
            margin = law.get("margin")
            if entry["first_violation"] is not None:
                falsified = f"yes, at simulation {entry['first_violation']}"
            elif entry["falsified"]:  # only the random baseline found a violating plant
                falsified = (
                    f"yes, by random search at its simulation {entry['random_baseline']['first_violation']} "
                    "(the search found none)"
                )
            else:
                falsified = "no"
            rows.append(
                {
                    "controller": controller,
                    "falsified": falsified,
                    "worst": _mm(worst["metrics"]["rms_error_after_2s"]),
                    "random": _mm(baseline["metrics"]["rms_error_after_2s"]),
                    "plant": ", ".join(
                        f"{k.split('.')[-1]} {values[k]:.2g}"
                        for k in ("plant.friction_scale", "plant.disturbance_scale", "plant.payload")
                        if k in values
                    ),
                    "margin": _margin_cell(margin),
                    "certificate": _certificate_cell(entry.get("certificate")),
                }
            )
        columns = [
            ("controller", "l", _text("controller")),
            ("falsified", "l", _text("falsified")),
            ("worst RMS error after 2 s [mm]", "r", _text("worst")),
            ("random search, same budget [mm]", "r", _text("random")),
            ("worst plant (friction, disturbance, payload [kg])", "l", _text("plant")),
        ]
        if any(r["margin"] != "–" for r in rows):
            columns.append(("margin (× the box)", "l", _text("margin")))
        falsifications = [law["falsification"] for law in case["controllers"].values()]
        certified = [e["certificate"] for e in falsifications if e.get("certificate")]
        if certified:
            confidence = 100 * (1 - certified[0]["certificates"][0]["beta"])
            header = f"random plants failing: P(fail) ≤ ({confidence:g} % confidence)"
            columns.append((header, "l", _text("certificate")))
        return _markdown(columns, rows, _study_command(report["study"]))

    return render


def registered_laws() -> str:
    """The registered laws and their [controller.params], from their declarations."""
    from nnrobust.controllers.registry import LAWS, law_names

    lines = [
        "| `controller.kind` | parameter | unit | default | range | searched by `tune` |",
        "|---|---|---|---|---|---|",
    ]
    for name in law_names():
        for p in LAWS[name].params:
            search = (
                f"no: {p.fixed_reason}"
                if p.search is None
                else ("from the arm" if callable(p.search) else f"{p.search[0]:g} to {p.search[1]:g}")
            )
            lines.append(f"| `{name}` | {_param_cells(p, 'sized by the law')} | {search} |")
    return "\n".join(lines) + "\n\nMade from the laws' declarations (`nnrobust/controllers/laws/`).\n"


def _valid(p) -> str:
    """A declared parameter's valid values: its choices, true or false, or its range and size."""
    size = {"1": "", "2": " (2 entries)", "n": " (per joint)", "m": " (per task row)"}[p.size]
    if p.choices:
        return " or ".join(f"`{c}`" for c in p.allowed)
    return "true or false" if isinstance(p.default, bool) else f"{p.range}{size}"


def _param_cells(p, unset: str) -> str:
    """A declared parameter's cells: `name`: doc | unit | default | valid values."""
    valid = _valid(p)
    if getattr(p, "path", False):  # a file's path: no default, no range
        return f"`{p.name}`: {p.doc} | {p.unit} | required | a file (relative: from the experiment file)"
    one = isinstance(p.default, tuple) and len(p.default) == 1  # one value for every row
    value = p.default[0] if one else p.default
    shown = f"{value:.4g}" if isinstance(value, float) else str(value)
    default = unset if p.default is None else f"`{shown}`"
    return f"`{p.name}`: {p.doc} | {p.unit} | {default} | {valid}"


def paper_kind_keys() -> str:
    """The keys the paper's kinds read, from their declarations (the shared ones, then each
    kind's own)."""
    from nnrobust.controllers.registry import PAPER_KINDS, SHARED_KEYS, paper_kinds

    lines = [
        "| read by | key | unit | default | valid values | not searched by `tune`, because |",
        "|---|---|---|---|---|---|",
    ]
    for shared in SHARED_KEYS:
        lines += [
            f"| {shared.owner} ({shared.reader_names()}) | {_param_cells(p, '-')} | {p.fixed_reason} |"
            for p in shared.params
        ]
    for name in paper_kinds():
        lines += [
            f"| `{name}` | {_param_cells(p, 'sized from the arm')} | {p.fixed_reason} |"
            for p in PAPER_KINDS[name].params
        ]
    return "\n".join(lines) + (
        "\n\nMade from the declarations (`SharedKeys` in task_space.py and pseudoinverse.py, "
        "`PaperKind.params`; nnrobust/controllers/). A key with no reason is searched, or set from "
        "a searched coordinate (docs/tuning.md).\n"
    )


def paper_kinds() -> str:
    """The paper's kinds of controller.kind, from their declarations."""
    from nnrobust.controllers.registry import PAPER_KINDS, paper_kinds

    lines = [
        "| `controller.kind` | u0 | nominal model and friction | its own keys |",
        "|---|---|---|---|",
    ]
    for name in paper_kinds():
        kind = PAPER_KINDS[name]
        keys = ", ".join(f"`{k}`" for k in kind.keys) or "-"
        lines.append(f"| `{name}` | {kind.u0} | {kind.nominal} | {keys} |")
    return "\n".join(lines) + "\n\nMade from the kinds' declarations (`PaperKind`, nnrobust/controllers/).\n"


def _declared(params) -> str:
    """The keys a kind declares beyond its section's fields, for a table's cell ("" if none)."""
    cells = []
    for p in params:
        unit = "" if p.unit == "-" else f" [{p.unit}]"
        default = "set by the kind" if p.default is None else f"default `{p.default}`"
        cells.append(f"`{p.name}`{unit}: {p.doc} ({default}, {_valid(p)})")
    return "; ".join(cells)


def disturbance_kinds() -> str:
    """The shipped disturbances of plant.disturbance, from their declarations."""
    from nnrobust.plant.disturbance import DISTURBANCE_KINDS

    lines = ["| `plant.disturbance` | τ_d(t) |", "|---|---|"]
    lines.append("| `auto` (default) | `paper` on the paper's arm, `scaled` on any other |")
    for name in sorted(DISTURBANCE_KINDS):
        kind = DISTURBANCE_KINDS[name]
        keys = _declared(kind.params)
        lines.append(f"| `{name}` | {kind.description}{'; its keys: ' + keys if keys else ''} |")
    lines.append(
        "| `custom` | a class of yours, `disturbance_class` and `disturbance_params` (docs/extending.md) |"
    )
    return (
        "\n".join(lines)
        + "\n\nMade from the disturbances' declarations (`DisturbanceKind`, nnrobust/plant/).\n"
    )


def path_kinds() -> str:
    """The shipped paths of trajectory.kind, from their declarations."""
    from nnrobust.trajectories import PATH_KINDS

    lines = ["| `kind` | x_d(t) | keys |", "|---|---|---|"]
    for name, kind in PATH_KINDS.items():
        default = " (default)" if name == "ellipse" else ""
        declared = _declared(kind.params)
        keys = kind.keys_doc + (f"; {declared}" if declared else "")
        lines.append(f"| `{name}`{default} | {kind.description} | {keys} |")
    lines.append(
        "| `custom` | a class of yours (planar and position tasks; docs/extending.md) | `class`, `params` |"
    )
    return "\n".join(lines) + "\n\nMade from the paths' declarations (`PathKind`, nnrobust/trajectories/).\n"


def criterion_kinds() -> str:
    """The shipped criteria of subtasks.criteria, from their declarations."""
    from nnrobust.subtasks import CRITERION_KINDS

    lines = ["| name | h(q), as declared | keys it declares |", "|---|---|---|"]
    for name, kind in CRITERION_KINDS.items():
        lines.append(f"| `{name}` | {kind.description} | {_declared(kind.params) or '-'} |")
    return (
        "\n".join(lines)
        + "\n\nMade from the criteria's declarations (`CriterionKind`, nnrobust/subtasks/): a criterion's "
        "own keys beyond `[subtasks]`'s fields are declared there (`params`).\n"
    )


def serve_misses() -> str:
    """docs/serve.md: the virtual robot at 1 kHz with an export's driver in another process."""
    data = _data("serve_misses")

    def latency(r):
        lat = r["latency_us"]
        return " / ".join(
            "–" if lat[k] is None else f"{lat[k]:,.0f}".replace(",", " ") for k in ("p50", "p99", "max")
        )

    return _markdown(
        [
            (
                "arm",
                "l",
                lambda r: {"paper-ellipse": "paper arm", "panda-ellipse": "Panda"}.get(r["arm"], r["arm"]),
            ),
            ("load", "l", _text("load")),
            ("scheduling", "l", lambda r: "SCHED_FIFO" if "FIFO" in r["scheduling"] else r["scheduling"]),
            ("periods", "r", _text("periods")),
            ("deadline misses", "r", _text("misses")),
            ("round trip p50 / p99 / max [µs]", "l", latency),
            ("robot lateness p99 [µs]", "r", lambda r: f"{r['lateness_us']['p99']:.0f}"),
            (
                "tracking, served / simulated",
                "r",
                lambda r: "–" if r["tracking"] is None else f"{r['tracking']:.4f}",
            ),
        ],
        data["rows"],
        f"python benchmarks/serve_misses.py --seconds {data['seconds']:g} --json docs/data/serve_misses.json",
    )


def loop_profile() -> str:
    """docs/compiled.md: the compiled step in parts, per arm and law (µs and system-allocator calls
    per step), from benchmarks/loop_profile.py."""
    data = _data("loop_profile")
    cases = list(dict.fromkeys((r["preset"], r["law"]) for r in data["rows"]))
    parts = list(dict.fromkeys(r["part"] for r in data["rows"]))
    by = {(r["preset"], r["law"], r["part"]): r for r in data["rows"]}

    def cell(case, part):
        r = by[(*case, part)]
        calls = r["allocations_per_step"]
        return f"{r['us_per_step']:.2f} ({'–' if calls is None else f'{calls:.1f}'})"

    def total(case):
        rows = [by[(*case, p)] for p in parts]
        calls = [r["allocations_per_step"] for r in rows]
        shown = "–" if None in calls else f"{sum(calls):.1f}"
        return f"{sum(r['us_per_step'] for r in rows):.2f} ({shown})"

    arms = {"paper-ellipse": "paper arm", "panda-ellipse": "Panda"}
    columns = [("arm", "l", lambda c: arms.get(c[0], c[0])), ("controller", "l", lambda c: c[1])]
    columns += [(part, "r", lambda c, p=part: cell(c, p)) for part in parts]
    columns.append(("step", "r", total))
    return _markdown(
        columns,
        cases,
        f"python benchmarks/loop_profile.py --duration {data['duration']:g} --repeats {data['repeats']} "
        "--json docs/data/loop_profile.json",
        chaos_note=False,
    )


def _closed_loop_made(data: dict) -> str:
    command = (
        f"python benchmarks/closed_loop.py --duration {data['duration']:g} --repeats {data['repeats']} "
        "--json docs/data/closed_loop.json"
    )
    return f"\nMade by `{command}` on {data['date']}, every contender interleaved in one process.\n"


def closed_loop() -> str:
    """docs/compiled.md: every contender of benchmarks/closed_loop.py, µs per 1 ms control step,
    interleaved in one process."""
    data = _data("closed_loop")
    columns = [
        ("preset", "l", lambda r: r["preset"]),
        ("contender", "l", lambda r: r["contender"]),
        ("µs per step", "r", lambda r: f"{1e6 * r['step_seconds']:.1f}"),
        ("× real time", "r", lambda r: f"{r['realtime_factor']:.1f}"),
        (
            "/ C++ floor",
            "r",
            lambda r: "–" if r["ratio_to_cpp_floor"] is None else f"{r['ratio_to_cpp_floor']:.1f}",
        ),
    ]
    return _markdown(columns, data["rows"], chaos_note=False) + _closed_loop_made(data)


def closed_loop_summary() -> str:
    """README: the Python and compiled loops against the C++ floor per arm, from
    docs/data/closed_loop.json."""
    data = _data("closed_loop")
    us = {(r["preset"], r["contender"]): 1e6 * r["step_seconds"] for r in data["rows"]}
    joints = {"paper-ellipse": 3, "panda-ellipse": 7}
    presets = list(dict.fromkeys(r["preset"] for r in data["rows"]))

    def ratio(p, contender):
        return f"{us[p, contender] / us[p, 'floor, C++']:.1f}"

    columns = [
        ("preset", "l", lambda p: f"{p} ({joints.get(p, '?')} joints)"),
        ("Python loop", "r", lambda p: f"{us[p, 'nnrobust, Python loop']:.0f}"),
        ("compiled loop", "r", lambda p: f"{us[p, 'nnrobust, compiled loop']:.1f}"),
        ("C++ floor", "r", lambda p: f"{us[p, 'floor, C++']:.1f}"),
        ("compiled × real time", "r", lambda p: f"{1e3 / us[p, 'nnrobust, compiled loop']:.0f}"),
        ("compiled / floor", "r", lambda p: ratio(p, "nnrobust, compiled loop")),
        ("Slotine–Li / floor", "r", lambda p: ratio(p, "slotine-li, compiled loop")),
    ]
    return _markdown(columns, presets, chaos_note=False) + _closed_loop_made(data)


def interval_coverage() -> str:
    """docs/robustness.md: the coverage of the paired median's interval, bootstrap against order
    statistics, by N and distribution."""
    data = _data("interval_coverage")
    names = list(dict.fromkeys(r["distribution"] for r in data["rows"]))
    by = {(r["n"], r["distribution"]): r for r in data["rows"]}
    columns = [("N", "r", lambda n: str(n)), ("order statistics, exact", "r",
               lambda n: f"{100 * by[n, names[0]]['exact']:.1f} %")]  # fmt: skip

    def both(n, k):
        return f"{100 * by[n, k]['order']:.1f} / {100 * by[n, k]['bootstrap']:.1f} %"

    for name in names:
        columns.append((f"{name}: order stat. / bootstrap", "r", lambda n, k=name: both(n, k)))
    lines = [
        "| " + " | ".join(h for h, _, _ in columns) + " |",
        "|" + "|".join("---:" for _ in columns) + "|",
        *("| " + " | ".join(cell(n) for _, _, cell in columns) + " |" for n in data["sizes"]),
    ]
    return (
        "\n".join(lines)
        + f"\n\nShare of {data['trials']} samples whose 95 % interval contains the true median (bootstrap: "
        f"{data['resamples']} resamples each). Made by `python benchmarks/interval_coverage.py --trials "
        f"{data['trials']} --json docs/data/interval_coverage.json --figure "
        "docs/img/interval_coverage.png`.\n"
    )


RENDERERS = {
    "interval-coverage": interval_coverage,
    "registered-laws": registered_laws,
    "paper-kinds": paper_kinds,
    "paper-kind-keys": paper_kind_keys,
    "path-kinds": path_kinds,
    "disturbance-kinds": disturbance_kinds,
    "criterion-kinds": criterion_kinds,
    "falsify-paper-factors": _falsified("falsify_paper"),
    "falsify-panda-factors": _falsified("falsify_panda"),
    "falsify-paper-certified": _certified_box("falsify_paper"),
    "falsify-panda-certified": _certified_box("falsify_panda"),
    "falsify-paper-tuned-factors": _falsified("falsify_paper_tuned"),
    "falsify-panda-tuned-factors": _falsified("falsify_panda_tuned"),
    "falsify-paper-tuned-certified": _certified_box("falsify_paper_tuned"),
    "falsify-panda-tuned-certified": _certified_box("falsify_panda_tuned"),
    "engine-gap-presets": engine_gap_presets,
    "engine-gap-tuned": engine_gap_tuned,
    "arm-presets": arm_presets,
    "torque-speed": torque_speed,
    "paper-robustness": _robustness("paper-robustness"),
    "panda-robustness": _robustness("panda-robustness"),
    "paper-reproduction": paper_reproduction,
    "nn-options": nn_options,
    "subtask": subtask,
    "plant-convergence": plant_convergence,
    "adaptive-step": adaptive_step,
    "friction-compensation": friction_compensation,
    "tuned-headline": tuned_headline,
    "tuned-settings": tuned_settings,
    "tuned-verdicts": tuned_verdicts,
    "example-study": example_study,
    "serve-misses": serve_misses,
    "loop-profile": loop_profile,
    "closed-loop": closed_loop,
    "closed-loop-summary": closed_loop_summary,
}


def render(text: str) -> str:
    """The document with every table re-rendered from its data."""

    def replace(match):
        name = match["name"]
        if name not in RENDERERS:
            raise SystemExit(f"unknown table {name!r}; known: {', '.join(RENDERERS)}")
        return match.group(1) + RENDERERS[name]() + match.group(4)

    return TABLE.sub(replace, text)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 when a table is out of date")
    args = parser.parse_args()
    stale = []
    for name in DOCUMENTS:
        path = ROOT / name
        text = path.read_text()
        new = render(text)
        if new != text:
            stale.append(name)
            if not args.check:
                path.write_text(new)
    if args.check and stale:
        print(f"out of date: {', '.join(stale)}; run python docs/render_tables.py", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
