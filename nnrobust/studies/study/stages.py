"""A study case's stages as one table (:data:`STAGES`): each stage's name, the budget keys it reads,
its folder under ``cases/C/``, what it runs, what it puts in the report and whether it runs side
by side with the others that do (docs/study.md). The engine (:func:`run_case`) reads the table:
the stages before the first side-by-side one run in order, the side-by-side ones together on the
study's cluster, then the rest in order (the realtime timing alone on the machine, after the
simulations). A new stage is one function here and one entry of the table.

Each stage's ``run(case)`` takes the :class:`CaseRun` (what every stage reads, what the earlier
ones found, and the report entry ``case.out`` it fills) and returns what runs: a function of no
argument for the engine to call (side by side, or in turn), with ``finish`` putting its result
into the report; or a string, the stage's status when it has nothing to run ("skipped: ...").
"""

from __future__ import annotations

from ...core.exceptions import NNRobustError
from .case_run import (  # what the stages share (re-exported: the stages' seeds and sweeps)
    CERTIFY_SEED,
    VALIDATION_SEED,
    CaseRun,
    Stage,
    Together,
    certified,
    draws_differ,
    has_mujoco,
    seed_name,
    side_by_side,
    sweep_of,
    varies,
)
from .evidence import failing_draws, failures, realtime, responses, step_cost, tuning_curves
from .selection import convergence, half_name, select_kept
from .spec import kept_name
from .stage_table import STAGE_ROWS
from .training import train, trained_report

# ---- 1. tune -------------------------------------------------------------------------------------


def tune(run: CaseRun):
    """Tune once per optimiser seed, side by side (``nnrobust tune``'s engine, ``tune-seedS/``); on
    one draw where every draw is the same plant.
    """
    from ..tune.engine import TuneSpec, run_tune

    spec, b, tuned = run.spec, run.spec.budgets, run.tuned
    train_samples = b["train_samples"] if draws_differ(run.sweep) else 1
    if tuned and train_samples < b["train_samples"]:
        run.say(
            f"{run.name}: every draw is the same plant (no box, no noise, no drawn model error): tuned on one"
        )
    run.out["train_samples"] = train_samples  # what the tunings ran on (one draw where all are the same)
    if not tuned:
        tuned_report(run, {})
        return "skipped: every law runs at " + (
            f"the kept settings of {spec.tuned}" if spec.tuned else "its own settings (tune = false)"
        )
    together = Together(run.progress)

    def one(s: int, told):
        tune_spec = TuneSpec(
            str(run.case_file),
            list(tuned),
            b["tune"],
            train_samples=train_samples,
            validation=0,
            max_rms_torque=b["max_rms_torque"],
            max_saturated=b["max_saturated"],
            seed=spec.seed + s,
        )
        return run_tune(
            tune_spec,
            run.here / f"tune-seed{s}",
            scheduler=run.address,
            overwrite=run.overwrite,
            progress=told,
            ship_files=run.ship,
        )

    seeds = range(b["seeds"])
    run.say(
        f"{run.name}: tune {b['seeds']} optimiser seed{'s side by side' if b['seeds'] > 1 else ''}: "
        f"{', '.join(tuned)}, {b['tune']} simulations each"
    )
    return lambda: dict(zip(seeds, side_by_side([lambda s=s, t=together.stage(): one(s, t) for s in seeds])))


def tuned_report(run: CaseRun, tunings) -> None:
    """The tunings' folders, curves, spaces as searched, training time and fixed keys."""
    from ..base.plan import base_config

    run.tunings = tunings = tunings or {}
    out, tuned = run.out, run.tuned
    out["tunings"] = {s: str(run.here / f"tune-seed{s}") for s in tunings}
    out["curves"] = tuning_curves(tunings)
    out["search"] = {  # per law and seed: the space searched, as widened, and what moved
        c: {s: {"space": summary["controllers"][c]["space"], "widened": summary["controllers"][c]["widened"]}
            for s, summary in tunings.items() if c in summary["controllers"]}
        for c in tuned
    }  # fmt: skip
    duration = base_config(run.sweep).simulation.duration
    out["training"] = {
        c: sum(s["controllers"][c]["simulations"] for s in tunings.values() if c in s["controllers"])
        * duration
        for c in tuned
    }
    # the keys each tuned law does not search, with why (the same for every seed)
    out["fixed"] = {
        c: entry.get("fixed", {})
        for summary in tunings.values()
        for c, entry in summary["controllers"].items()
    }


# ---- 2. validate ---------------------------------------------------------------------------------


def _candidates(run: CaseRun) -> tuple[list[str], dict, dict, dict]:
    """The validation entries: every fixed law, and every (controller, seed) best with its best at
    half the budget beside it. (names, entries, setting_of, halves).
    """
    from ..base.tuned import tuned_entry

    spec = run.spec
    entries: dict = {}
    names: list[str] = []
    # validation row -> (controller, seed, settings, the coordinates on a bound of its space)
    setting_of: dict[str, tuple[str, int | None, dict, list]] = {}
    halves: dict[str, str] = {}  # a seed's label -> the label of its half-budget best
    for c in spec.controllers:
        if c in spec.fixed:
            names.append(c)
            if c in spec.entries:
                entries[c] = spec.entries[c]
            setting_of[c] = (c, None, {}, [])
            continue
        for s, summary in run.tunings.items():
            best = summary["controllers"].get(c, {}).get("best")
            if not best:
                continue
            label = seed_name(c, s)
            entries[label] = tuned_entry(c, best["params"], spec.entries)
            names.append(label)
            setting_of[label] = (c, s, dict(best["params"]), best.get("at_bound") or [])
            # the same seed's best at half the budget, validated beside it: does doubling move it?
            half = summary["controllers"].get(c, {}).get("half_budget_best")
            if half and half["params"] != best["params"]:
                entries[half_name(label)] = tuned_entry(c, half["params"], spec.entries)
                names.append(half_name(label))
                halves[label] = half_name(label)
            elif half:
                halves[label] = label
    return names, entries, setting_of, halves


def validate(run: CaseRun):
    """Every (controller, seed) setting on fresh draws (``nnrobust sweep``'s engine, ``validate/``);
    each controller keeps its best seed feasible there (:func:`~.selection.select_kept`).
    """
    from ..base.plan import load_sweep
    from ..sweep.engine import read_results, run_sweep

    spec, b, name = run.spec, run.spec.budgets, run.name
    names, entries, setting_of, halves = _candidates(run)
    run.out["not_kept"] = {
        c: "; ".join(
            f"seed {s}: {summary['controllers'].get(c, {}).get('note', 'no best setting')}"
            for s, summary in run.tunings.items()
        )
        for c in run.tuned
        if not any(setting_of.get(seed_name(c, s)) for s in run.tunings)
    }
    for c, reason in run.out["not_kept"].items():
        run.say(f"{name}: {c} has no setting to validate: {reason}")
    if not names and spec.trained:
        run.out["kept"], run.out["per_seed"] = {}, {}
        return "skipped: no tuned or fixed law (the trained policies are validated after their training)"
    if not names:
        raise NNRobustError(
            f"{name}: no controller has a setting to validate ({'; '.join(run.out['not_kept'].values())})"
        )
    sweep = sweep_of(spec, run.case, names, entries, b["validation"], spec.seed + VALIDATION_SEED)
    validate_file = run.here / "validate.toml"
    run.stage_file(validate_file, sweep.to_toml())
    run.say(f"{name}: validate {len(names)} settings on {b['validation']} fresh draws")
    validate_spec = load_sweep(validate_file)
    run.validation = {"setting_of": setting_of, "halves": halves, "spec": validate_spec}

    def rows():
        run_sweep(
            validate_spec,
            run.here / "validate",
            scheduler=run.address,
            overwrite=run.overwrite,
            progress=run.progress,
            ship_files=run.ship,
        )
        return read_results(run.here / "validate")

    return rows


def kept_report(run: CaseRun, frame) -> None:
    """Each controller's kept setting, every seed's validation and the convergence of the budget."""
    from ..sweep.summary import summarize, write_summary

    spec, name, out = run.spec, run.name, run.out
    setting_of, halves = run.validation["setting_of"], run.validation["halves"]
    write_summary(run.here / "validate", summarize(run.validation["spec"], frame))
    kept, per_seed, infeasible = select_kept(spec, frame, setting_of)
    for c, reason in infeasible.items():
        out["not_kept"][c] = reason
        run.say(f"{name}: {c} is not kept: {reason}")
    out["convergence"] = {
        c: convergence(spec, frame, [label for label, s in setting_of.items() if s[0] == c], halves)
        for c in kept
        if c not in spec.fixed
    }
    out["kept"], out["per_seed"] = kept, per_seed
    if not kept:
        raise NNRobustError(
            f"{name}: no controller is feasible on the validation draws ({'; '.join(infeasible.values())})"
        )


# ---- 4. certify, 5. falsify, 7. engine: side by side -------------------------------------------


def certify(run: CaseRun):
    """The kept settings on draws the selection never saw, as many as the claim needs (a sweep,
    ``certify/``): certificates, statistics and paired comparisons.
    """
    from ...run.properties import samples_needed
    from ..base.plan import load_sweep
    from ..base.tuned import tuned_entry

    spec, b = run.spec, run.spec.budgets
    names, entries, settings = [], {}, {}
    for c, entry in run.out["kept"].items():
        label = c if c in spec.fixed else kept_name(c)
        names.append(label)
        if c in spec.fixed:
            if c in spec.entries:
                entries[c] = spec.entries[c]
        else:
            entries[label] = tuned_entry(c, entry["settings"], spec.entries)
            settings[c] = entry["settings"]
    run.out["entries"] = {label: entries.get(label) or {"kind": label} for label in names}
    n = b["certify"] or samples_needed(b["epsilon"], b["beta"])
    sweep = sweep_of(spec, run.case, names, entries, n, spec.seed + CERTIFY_SEED)
    certify_file = run.here / "certify.toml"
    run.stage_file(certify_file, sweep.to_toml())
    run.say(
        f"{run.name}: certify {len(names)} controllers on {n} fresh draws "
        f"(epsilon {b['epsilon']:g}, beta {b['beta']:g})"
    )
    certify_spec = load_sweep(certify_file)
    run.certification = {"names": names, "settings": settings, "spec": certify_spec, "file": certify_file}
    told = run.together.stage()
    return lambda: certified(
        spec, certify_spec, run.here / "certify", run.address, run.overwrite, told, run.ship
    )


def certified_report(run: CaseRun, result) -> None:
    """The certification's summary, whether its draws differ, step costs, failures, failing draws."""
    from ...run.properties import run_properties

    summary, rows = result
    certify_spec = run.certification["spec"]
    run.certification["rows"] = rows
    out = run.out
    out["certify"] = summary
    out["held_out"] = varies(rows)
    out["step_cost"] = step_cost(certify_spec, rows)
    out["failures"] = failures(rows)
    out["failing"] = failing_draws(certify_spec, rows, run_properties(run.spec.certified_properties()))


def falsify(run: CaseRun):
    """The kept settings searched for their worst plant (``nnrobust falsify``'s engine, ``falsify/``)."""
    from ..falsify import FalsifySpec, run_falsify

    spec, b, kept = run.spec, run.spec.budgets, run.out["kept"]
    if not (spec.vary and b["falsify"]):
        return "skipped: the study has no [vary] box to search" if b["falsify"] else "skipped: falsify = 0"
    run.say(
        f"{run.name}: falsify {len(kept)} controllers, {b['falsify']} simulations each (and as many random)"
    )
    falsify_spec = FalsifySpec(
        str(run.case_file),
        list(kept),
        list(spec.require),
        b["falsify"],
        seed=spec.seed,
        margin=b["margin"],
        tuned=run.certification["settings"] or None,
    )
    told = run.together.stage()
    return lambda: run_falsify(
        falsify_spec, run.here / "falsify", scheduler=run.address, overwrite=run.overwrite, progress=told,
        claim=(b["epsilon"], b["beta"]), ship_files=run.ship,
    )  # fmt: skip


def second_engine(run: CaseRun):
    """The certification draws again with MuJoCo as the plant (a sweep, ``certify-mujoco/``)."""
    from ..base.plan import load_sweep

    if not run.spec.budgets["second_engine"]:
        return "skipped: second_engine = false"
    if not has_mujoco():
        return "skipped: MuJoCo is not installed (pip install 'nnrobust[mujoco]')"
    again = load_sweep(run.certification["file"])
    again.set["plant.engine"] = "mujoco"
    engine_file = run.here / "certify-mujoco.toml"
    run.stage_file(engine_file, again.to_toml())
    run.say(f"{run.name}: the certification draws again with MuJoCo as the plant")
    engine_spec = load_sweep(engine_file)
    told = run.together.stage()
    return lambda: certified(
        run.spec, engine_spec, run.here / "certify-mujoco", run.address, run.overwrite, told, run.ship
    )[0]


# ---- 5. realtime, and the time responses: after the simulations ----------------------------------


def realtime_stage(run: CaseRun):
    """The kept laws exported and timed out of Python (``realtime/``): alone on the machine, after
    the side-by-side stages (a step timed beside the workers' simulations is timed on a busy core).
    """
    if not run.spec.budgets["realtime"]:
        return "skipped: realtime = false"
    run.say(f"{run.name}: export the kept laws and time their steps out of Python")
    certification = run.certification
    return lambda: realtime(certification["spec"], certification["names"], run.here / "realtime")


def responses_stage(run: CaseRun):
    """The kept laws' time responses on their median and worst certification draws (``responses/``)."""
    run.say(f"{run.name}: the kept laws' time responses on their median and worst certification draws")
    c = run.certification
    return lambda: responses(c["spec"], c["rows"], c["names"], run.here / "responses")


def _into(key: str):
    def put(run: CaseRun, result) -> None:
        run.out[key] = result

    return put


_RUNS = {
    "tune": (tune, tuned_report),
    "validate": (validate, kept_report),
    "train": (train, trained_report),
    "certify": (certify, certified_report),
    "falsify": (falsify, _into("falsify")),
    "realtime": (realtime_stage, _into("realtime")),
    "engine": (second_engine, _into("engine")),
    "responses": (responses_stage, _into("responses")),
}
STAGES: tuple[Stage, ...] = tuple(Stage(row, *_RUNS[row.name]) for row in STAGE_ROWS)
"""The stages of a case, in the report's order (docs/study.md)."""

STAGE_FOLDERS = tuple(folder for stage in STAGES for folder in stage.folders)
"""A case's stage folders (besides tune-seedS), each written by its command's engine."""


def run_case(run: CaseRun) -> dict:
    """Every stage of the table on one case: those before the first side-by-side stage in turn,
    the side-by-side ones together (:func:`side_by_side`), then the rest in turn. Returns the
    case's report entry (``run.out``).
    """
    status: dict[str, str] = {}

    def alone(stage: Stage) -> None:
        work = stage.run(run)
        if isinstance(work, str):
            status[stage.name] = work
        else:
            stage.finish(run, work())
            status[stage.name] = "finished"

    first = next(i for i, s in enumerate(STAGES) if s.side_by_side)
    for stage in STAGES[:first]:
        alone(stage)
    run.together = Together(run.progress)
    works = []
    for stage in (s for s in STAGES[first:] if s.side_by_side):
        work = stage.run(run)
        if isinstance(work, str):
            status[stage.name] = work
        else:
            works.append((stage, work))
    if len(works) > 1:
        run.say(f"{run.name}: {', '.join(stage.name for stage, _ in works)} side by side")
    for (stage, _), result in zip(works, side_by_side([work for _, work in works])):
        stage.finish(run, result)
        status[stage.name] = "finished"
    for stage in STAGES[first:]:
        if not stage.side_by_side:
            alone(stage)
    run.out["stages"] = {stage.name: status[stage.name] for stage in STAGES if stage.reported}
    return run.out
