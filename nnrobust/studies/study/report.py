"""A study's report: ``report.json`` (the numbers, under the schema of docs/study.md),
``report.html`` (one self-contained file: tables, figures inside, the reproducibility appendix:
nnrobust.studies.study.html), ``tables/`` (CSV and LaTeX booktabs: nnrobust.studies.study.tables) and
``figures/`` (PNG, SVG, PDF: nnrobust.studies.study.figures), all from the stages' own folders.
"""

from __future__ import annotations

import json
import math
import platform
from pathlib import Path

import numpy as np

from ...run.results import write_json_atomic
from ..base.tuned import STUDY_REPORT
from .spec import DESIGN, StudySpec, kept_name

SCHEMA = f"{STUDY_REPORT}1"
STATISTICS = (
    "rows",
    "success_rate",
    "statuses",
    "rms_error_after_2s",
    "rms_torque",
    "torque_chatter",
    "saturated_fraction_mean",
    "rows_with_warnings",
)
"""The keys of a certification sweep's summary each controller's statistics hold (either engine)."""


def _versions() -> dict:
    import numpy
    import pinocchio
    import scipy

    from ...core.package_version import package_version

    return {
        "nnrobust": package_version(),
        "python": platform.python_version(),
        "pinocchio": pinocchio.__version__,
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "platform": platform.platform(),
    }


def _inputs(spec: StudySpec) -> dict:
    """SHA-256 of every input file: the study file, and per case what its rows are computed from
    (the experiment files, the URDF, the custom classes: :func:`nnrobust.studies.base.plan.study_inputs`).
    """
    from ..base.folder import file_sha256
    from ..base.plan import study_inputs

    out = {_shown(spec.path): file_sha256(spec.path)}
    if spec.tuned:  # the tuning the settings come from
        from ..base.tuned import tuned_file

        source, _ = tuned_file(spec.tuned)
        out[_shown(source)] = file_sha256(source)
    for case in spec.cases:
        for path, digest in study_inputs(spec.case_sweep(case)).files.values():
            out[_shown(path)] = digest
    return out


def _shown(path) -> str:
    """A path as the report shows it: relative to the folder the study was run from when it lies
    beneath it (a report read on another machine names the project's files, not this one's
    folders), else as given; a robot's name (a built-in URDF) unchanged.
    """
    p = Path(path)
    if not p.is_absolute():
        return str(path)
    try:
        return str(p.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def _commands(spec: StudySpec, folder: Path, name: str, case: dict) -> dict:
    """The command that recomputes each stage's numbers from its own folder's input file."""
    here = folder / "cases" / name
    b = spec.budgets
    tuned = spec.searched
    out = {}
    for s, path in case.get("tunings", {}).items():
        out[f"tune seed {s}"] = (
            f"nnrobust tune {here / 'case.toml'} --controllers {','.join(tuned)} --budget {b['tune']} "
            f"--train-samples {case.get('train_samples', b['train_samples'])} --validation 0 "
            f"--seed {spec.seed + int(s)}"
            + (f" --max-rms-torque {b['max_rms_torque']:g}" if math.isfinite(b["max_rms_torque"]) else "")
            + (f" --max-saturated {b['max_saturated']:g}" if b["max_saturated"] < 1 else "")
            + f" --out {path}"
        )
    out["validate"] = f"nnrobust sweep {here / 'validate.toml'} --out {here / 'validate'}"
    if case["stages"].get("train") == "finished":  # each seed's training: its record holds every option
        out["validate trained"] = (
            f"nnrobust sweep {here / 'validate-train.toml'} --out {here / 'validate-train'}"
        )
    require = " ".join(f"--require '{r}'" for r in spec.certified_properties())
    searched = " ".join(f"--require '{r}'" for r in spec.require)
    out["certify"] = (
        f"nnrobust sweep {here / 'certify.toml'} {require} --epsilon {b['epsilon']:g} --beta {b['beta']:g} "
        f"--out {here / 'certify'}"
    )
    if case["stages"].get("engine") == "finished":
        out["engine"] = (
            f"nnrobust sweep {here / 'certify-mujoco.toml'} {require} --epsilon {b['epsilon']:g} "
            f"--beta {b['beta']:g} --out {here / 'certify-mujoco'}"
        )
    if case["stages"].get("falsify") == "finished":
        kept = ",".join(case["kept"])
        out["falsify"] = (
            f"nnrobust falsify {here / 'case.toml'} --controllers {kept} {searched} --budget {b['falsify']} "
            f"--seed {spec.seed} --tuned {here / 'kept.json'} --epsilon {b['epsilon']:g} --beta {b['beta']:g}"
            + (" --margin" if b["margin"] else "")
            + f" --out {here / 'falsify'}"
        )
    return out


def _controller_entry(spec: StudySpec, case: dict, c: str) -> dict:
    label = c if c in spec.fixed else kept_name(c)
    certify = case["certify"]["controllers"].get(label, {})
    kept = case["kept"].get(c)
    per_seed = case["per_seed"].get(c, [])
    # the seeds' spread and median over the seeds feasible on validation: a seed that broke the
    # study's constraints is not a result under them (selection.select_kept), so it ranks nowhere
    medians = [
        e["median_error"] for e in per_seed if math.isfinite(e["median_error"]) and e.get("feasible", True)
    ]
    certified_entry = dict(case.get("entries", {}).get(label) or {"kind": c})
    if "class" in certified_entry:  # the file as the report's inputs name it
        file, _, cls = certified_entry["class"].rpartition(":")
        certified_entry["class"] = f"{_shown(file)}:{cls}"
    entry: dict = {
        "label": label,
        "entry": certified_entry,  # what the certification ran: kind or class, params, set
        "tuned": None
        if c in spec.fixed
        else {
            "seeds": per_seed,
            "kept_seed": kept["seed"] if kept else None,
            "settings": kept["settings"] if kept else None,
            "seed_spread": [min(medians), max(medians)] if medians else None,
            "seed_median": float(np.median(medians)) if medians else None,
            "infeasible_seeds": [e["seed"] for e in per_seed if not e.get("feasible", True)],
            "at_bound": kept["at_bound"] if kept else None,
            "fixed": case.get("fixed", {}).get(c, {}),
            "convergence": case.get("convergence", {}).get(c),
            # the kept seed's space as searched (bounds, why physical) and what every seed widened
            "space": (case.get("search", {}).get(c, {}).get(kept["seed"] if kept else None) or {}).get(
                "space"
            ),
            "widened": {
                s: r["widened"] for s, r in case.get("search", {}).get(c, {}).items() if r["widened"]
            },
        },
        "training": _training(spec, case, c),
        "trained": case.get("trained", {}).get(c),  # a policy the study trained: its seeds' records
        "fixed": c in spec.fixed,
        "validation": {
            "median_error": kept["median_error"],
            "rows": kept["rows"],
            "completed": kept["completed"],
            "feasible": kept.get("feasible"),
            **(kept.get("validation") or {}),
        }
        if kept
        else None,
        "statistics": {k: certify.get(k) for k in STATISTICS},
        "certificates": certify.get("certificates", []),
        "quantile_bounds": certify.get("quantile_bounds", []),
        "warnings": certify.get("warnings_by_kind", {}),
        "failures": case.get("failures", {}).get(label, {}),
        "failing": case.get("failing", {}).get(label),
    }
    cost = case.get("step_cost", {}).get(label, {})
    entry["step_cost_us"], entry["backend"] = cost.get("step_cost_us"), cost.get("backend")
    entry["realtime"] = (case.get("realtime") or {}).get(label)
    engines = {"pinocchio": entry["statistics"]}
    second = (case.get("engine") or {}).get("controllers", {}).get(label)
    if second:
        engines["mujoco"] = {
            **{k: second.get(k) for k in STATISTICS},
            "certificates": second.get("certificates", []),
        }
    entry["engines"] = engines
    falsified = (case.get("falsify") or {}).get("controllers", {})
    found = falsified.get(label) or falsified.get(c)
    if found:
        from ..falsify.summary import replayed_worst

        worst, found_by = replayed_worst(found)  # the plant whose command replays the verdict
        entry["worst"] = {
            "falsified": found["falsified"],
            "found_by": found_by,
            "simulations": found["simulations"],
            "margin": worst["margin"],
            "metrics": worst["metrics"],
            "command": worst["command"],
        }
        entry["falsification"] = found  # the stage's record: both searches, the baseline's certificate
    margins = (case.get("falsify") or {}).get("margin", {})
    if label in margins or c in margins:
        entry["margin"] = margins.get(label) or margins.get(c)
    return entry


def _training(spec: StudySpec, case: dict, c: str) -> dict | None:
    """What a law's setting was trained on, in simulated seconds: its tunings' simulations (every
    seed) for a tuned law, its training record's for a learned policy; None for a law at its own
    settings.
    """
    if c in spec.trained:
        table = spec.trained[c]
        seconds = case.get("training", {}).get(c)
        by = f"the train stage: {table['algorithm'].upper()}, {table['seeds']} seeds of {table['budget']:g} s"
        return None if seconds is None else {"simulated_seconds": seconds, "by": by}
    if c not in spec.fixed:
        seconds = case.get("training", {}).get(c)
        return (
            None
            if seconds is None
            else {"simulated_seconds": seconds, "by": "the study's tunings, every seed"}
        )
    params = spec.entries.get(c, {}).get("params") or {}
    if spec.entries.get(c, {}).get("kind") == "policy" and isinstance(params.get("file"), str):
        try:
            record = json.loads(Path(f"{params['file']}.json").read_text())
        except (OSError, ValueError):
            return None
        if isinstance(record, dict) and isinstance(record.get("simulated_seconds"), (int, float)):
            return {"simulated_seconds": float(record["simulated_seconds"]), "by": "its training record"}
    return None


def property_names(spec: StudySpec) -> dict[str, str]:
    """Each certified property's short name in the tables: the design part it stands for, or the
    metric a ``require`` property reads.
    """
    names = {r: r.split("<")[0].split(">")[0].split("=")[0].split("!")[0] for r in spec.require}
    return {**names, **{text: name for name, text in spec.design_requirement().items()}}


def study_warnings(spec: StudySpec) -> list[str]:
    """What a reader of the report must know before its numbers: no torque or saturation
    constraint (kept settings may saturate), each part of the design's requirement the file
    waives, and each policy scored outside the horizon it was trained on.
    """
    from ...controllers.laws.policy import horizon_warning
    from ...run.results import SETTLED_AFTER
    from ..base.plan import base_config

    b = spec.budgets
    out = []
    if not math.isfinite(b["max_rms_torque"]) and b["max_saturated"] >= 1:
        out.append(
            "no torque or saturation constraint (budgets.max_rms_torque, budgets.max_saturated): kept "
            "settings may saturate the actuators"
        )
    out += [f"waived by the study file: {DESIGN[w]}" for w in spec.waive]
    for case in spec.cases:
        duration = base_config(spec.case_sweep(case)).simulation.duration
        view = spec.for_case(case)
        for c in view.controllers:
            params = view.entries.get(c, {}).get("params") or {}
            if view.entries.get(c, {}).get("kind") == "policy" and isinstance(params.get("file"), str):
                said = horizon_warning(c, params["file"], duration, SETTLED_AFTER)
                if said:
                    out.append(f"{spec.case_name(case)}: {said}")
    return out


def build_report(spec: StudySpec, folder: Path, cases: dict) -> dict:
    """report.json's content (docs/study.md's schema)."""
    report: dict = {
        "schema": SCHEMA,
        "study": spec.name,
        "description": spec.description,
        "versions": _versions(),
        "inputs": _inputs(spec),
        "require": spec.require,
        "tuned_from": spec.tuned or None,
        "budgets": {
            k: (None if isinstance(v, float) and math.isinf(v) else v) for k, v in spec.budgets.items()
        },
        "certified_properties": spec.certified_properties(),
        "property_names": property_names(spec),
        "waived": {w: DESIGN[w] for w in spec.waive},
        "box": dict(spec.vary),
        "identified_box": dict(spec.box),
        "warnings": study_warnings(spec),
        "cases": {},
    }
    by_name = {spec.case_name(c): c for c in spec.cases}
    study = spec
    for name, case in cases.items():
        spec = study.for_case(by_name[name])  # the controllers of this case, with its entries
        label_of = {(c if c in spec.fixed else kept_name(c)): c for c in spec.controllers}
        paired = [
            {**p, "a": label_of.get(p["a"], p["a"]), "b": label_of.get(p["b"], p["b"])}
            for p in case["certify"].get("paired", [])
        ]
        report["cases"][name] = {
            "case": case["case"],
            "set": case.get("set", {}),
            "stages": case["stages"],
            "held_out": case["held_out"],
            "validated_on": "fresh draws of the uncertainty set, independent of the training draws"
            if case["held_out"]
            else "the training plant: the case has no randomness (every draw is the same plant)",
            "controllers": {
                c: _controller_entry(spec, case, c) for c in spec.controllers if c in case["kept"]
            },
            "not_kept": case.get("not_kept", {}),
            # a policy the study trained and did not keep: its seeds' records and curves still
            "not_kept_trained": {c: t for c, t in case.get("trained", {}).items() if c not in case["kept"]},
            "paired": paired,
            "commands": _commands(spec, folder, name, case),
        }
    spec = study
    report["composed_claim"] = composed_claim(study, report)
    return report


CHANGES_THE_BOX = ("plant.joint_friction_scales", "plant.payload", "plant.loads", "plant.armature")
"""Keys that change the true plant beyond an identified box's point: set or drawn, the plant is
no longer the box's, so the identification's confidence says nothing of it."""


def composed_claim(spec: StudySpec, report: dict) -> dict | None:
    """The study's claim composed with its identified box's (docs/identification.md, "The box"):
    with confidence >= 1 - alpha the robot is in the box (the identification), and over the box
    P(fail) <= epsilon with confidence 1 - beta (the certificate); by the union bound both hold
    with confidence >= 1 - alpha - beta. None without a box file that states a level.
    """
    level = spec.box.get("claim", {}).get("level") if spec.box else None
    if not isinstance(level, (int, float)):
        return None
    alpha, beta = round(1 - float(level), 12), float(spec.budgets["beta"])
    changed = sorted(
        k for k in (*spec.set, *spec.vary) if any(k == c or k.startswith(c + "[") for c in CHANGES_THE_BOX)
    )
    out: dict = {
        "box": spec.box["file"],
        "box_sha256": spec.box["sha256"],
        "alpha": alpha,
        "beta": beta,
        "epsilon": float(spec.budgets["epsilon"]),
        "together": round(1 - alpha - beta, 12),
        "method": spec.box["claim"].get("method", ""),
    }
    if changed:
        why = (
            f"{', '.join(changed)} change{'s' if len(changed) == 1 else ''} the plant beyond the box's point"
        )
        return {**out, "stated": False, "why": why}
    from ...run.properties import overall_certificate

    laws: dict = {}
    for name, case in report["cases"].items():
        for c, entry in case["controllers"].items():
            found = overall_certificate(entry.get("certificates", []))
            laws.setdefault(name, {})[c] = (
                None if found is None else {k: found[k] for k in ("holds", "p_upper", "N")}
            )
    return {**out, "stated": True, "cases": laws}


def finite(value):
    """``value`` with every non-finite float as null, so that report.json is standard JSON (a
    margin of -inf, a run that did not complete, is null beside the status that says why).
    """
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    return value


def write_report(spec: StudySpec, folder: Path, cases: dict) -> dict:
    """report.json, tables/, figures/ and report.html; returns the report."""
    from . import figures as draw
    from .html import write_html
    from .tables import write_tables

    for name, case in cases.items():  # the kept settings, as --tuned reads them (the falsify command)
        kept = {  # a fixed controller runs at its own settings: --tuned leaves it untuned
            c: {"fixed": True} if c in spec.fixed else {"best": {"params": k["settings"]}}
            for c, k in case["kept"].items()
        }
        write_json_atomic(folder / "cases" / name / "kept.json", {"controllers": kept})
    report = build_report(spec, folder, cases)
    report = finite(report)
    write_json_atomic(folder / "report.json", report)
    write_tables(report, folder)
    figures = {}
    for name, case in cases.items():
        entries = report["cases"][name]["controllers"]
        figures[name] = {
            "cdf": draw.error_cdf(name, folder, spec.require)[0],
            "tuning": draw.tuning_curves(name, case.get("curves", {}), spec.budgets["tune"] // 2),
            "learning": draw.learning_curves(
                name,
                case.get("trained", {}),
                {
                    c: seconds
                    for c, seconds in case.get("training", {}).items()
                    if c not in case.get("trained", {})
                },
            ),
            "falsification": draw.falsification_curves(
                name, {c: e["falsification"] for c, e in entries.items() if e.get("falsification")}
            ),
            "responses": draw.time_responses(name, case.get("responses", {})),
        }
    write_html(report, folder, figures)
    from .tables import StudyReport

    return StudyReport(report)
