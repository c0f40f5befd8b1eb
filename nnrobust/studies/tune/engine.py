"""``nnrobust tune``: every controller tuned by the same optimiser, at the same budget, on the same
samples, under the same constraints; validated on samples the search never saw (docs/tuning.md).

The optimiser is Optuna's TPE sampler, minimising the RMS error after 2 s under constraints (RMS
torque, saturated fraction, no runaway, no stop hit, a completed run): the best setting under the
constraints is what is compared. RMS torque and chatter are recorded for every setting, and each
controller's Pareto front (error, torque, chatter) is drawn from all the settings it tried (a
multi-objective search spread its budget along the low-gain end of that front and, at 120
simulations, left the NN at 22 mm where a hand search found 0.13 mm). Each round asks every
controller for a batch of settings (:data:`ROUND_SIMULATIONS`, whatever the cluster's size, so a
tuning's results do not depend on how many workers ran it); their simulations run on the sweep's
Dask cluster (one task per setting and training sample) and are told back. The controllers' rounds
run side by side, each optimiser asking from its own rows alone, so the cluster stays busy while
one controller is told and asks again. Every finished trial is appended
to DIR/trials as a Parquet part, so an interrupted tuning resumes from what it wrote: the studies
are rebuilt from the rows. From half the budget on, whenever the best setting sits on a bound of
its space that is not physical, that bound moves out a decade and the next setting tried is a
probe: the best with that coordinate half a decade past the old bound. A best that stays is then
interior with a worse setting tried beyond it; one that moves goes on being checked. The rows
already run stay in the widened space's history.
"""

from __future__ import annotations

import json
import math
import os
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...core.drawing import drawn_alone
from ...core.exceptions import ConfigError, NNRobustError
from ...core.signals import signals_as_interrupt
from ...run.results import SETTLED_AFTER
from .search import ControllerSearch, judge
from .space import arm_scales, custom_space, search_space
from .spec import (
    CONSTRAINTS,
    MARKER,
    OBJECTIVES,
    ROUND_SIMULATIONS,
    TRIALS,
    TuneSpec,
    sweep_of,
)

if TYPE_CHECKING:
    pass


# ---- on the workers ------------------------------------------------------------------------------


def evaluate(sweep, base: dict, controller: str, overrides: dict, sample_id: int) -> dict:
    """One simulation of a setting on one sample: its metrics (or the reason it failed). The
    setting's keys are set with the sample's in the base's own values
    (:func:`nnrobust.studies.base.plan.experiment`), as an edit of the file would set them.
    """
    import time

    from ...run.experiment import run_experiment
    from ..base.plan import draw, experiment

    start = time.perf_counter()  # task_seconds: build, run and metrics, as a sweep's rows carry
    try:
        config = experiment(sweep, base, draw(sweep, sample_id), controller, overrides)
        metrics = run_experiment(config).metrics()
    except NNRobustError as err:
        metrics = {"status": "refused", "message": str(err)[:300]}
        keep: tuple[str, ...] = ("status", "message")
    except BaseException as err:  # a defect, or user code raising SystemExit or BaseException
        metrics = {"status": "error", "message": f"{type(err).__name__}: {err}"[:300]}
        keep = ("status", "message")
    else:
        keep = (*OBJECTIVES, "status", "saturated_fraction", "runaway", "max_joint_limit_violation")
    return {**{k: metrics.get(k) for k in keep}, "task_seconds": time.perf_counter() - start}


# ---- on the client -------------------------------------------------------------------------------


def _simulate(client, tasks: list[tuple], files=None) -> list[dict]:
    """Run each (function, *arguments) task on the cluster (within ``files``, the files sent with
    the tasks: :func:`nnrobust.studies.base.cluster.shipped_files`): its result, or status ``crashed``
    when it ends its worker (:func:`nnrobust.studies.base.cluster.run_tasks`).
    """
    from ..base.cluster import CRASHED, run_tasks

    return run_tasks(client, tasks, lambda reason: {"status": CRASHED, "message": reason}, files)


WITHOUT_RESULT = ("refused", "error", "crashed")
"""The statuses of a run that produced no result (its law was refused, raised, or ended its
worker): a tuning in which every run of a law ended so exits 1 (``nnrobust tune``)."""


def why_none(rows: list[dict]) -> str:
    """Why no setting of ``rows`` (trials-table rows) was feasible: how many runs ended with each
    status other than completed, with its first message, and how many settings broke each
    constraint.
    """
    failed: Counter = Counter()
    first: dict[str, str] = {}
    for run in (run for row in rows for run in row["runs"]):
        status = str(run.get("status"))
        if status != "completed":
            failed[status] += 1
            first.setdefault(status, str(run.get("message", "")))
    broken: Counter = Counter(
        name
        for row in rows
        if row["train"].get("status") == "completed"
        for name, value in zip(CONSTRAINTS, row["constraints"])
        if value > 0
    )
    parts = [f"{n} runs {status} (first: {first[status][:200]})" for status, n in sorted(failed.items())]
    parts += [f"{n} settings {name.replace('_', ' ')}" for name, n in sorted(broken.items())]
    return "; ".join(parts) or "no setting was tried"


TRIAL_IDS = ("controller", "trial")
"""The columns of the trials that name a row."""


def _read_trials(folder: Path, key: str) -> list[dict]:
    """The trials the folder holds, each part checked against ``key`` (the tuning's inputs) and
    no trial twice (:func:`nnrobust.studies.base.folder.read_parts`).
    """
    from ..base.folder import read_parts

    tables = read_parts(folder / TRIALS, [*TRIAL_IDS, "row"], key, TRIAL_IDS)
    rows = [json.loads(r) for t in tables for r in t.column("row").to_pylist()]
    return sorted(rows, key=lambda r: (r["controller"], r["trial"]))


def _write_trials(folder: Path, rows: list[dict], key: str) -> None:
    """One Parquet part, tied to the tuning's inputs (``key``) and written whole: flat columns
    for pandas, and the whole row as JSON for resuming.
    """
    import pandas as pd
    import pyarrow as pa

    from ..base.folder import write_part

    flat = []
    for r in rows:
        item = {
            "controller": r["controller"],
            "trial": r["trial"],
            "feasible": r["feasible"],
            **{f"search.{k}": v for k, v in r["search"].items()},
            **{f"train.{k}": v for k, v in r["train"].items() if not isinstance(v, (list, dict))},
            "row": json.dumps(r),
        }
        flat.append(item)
    write_part(folder / TRIALS, pa.Table.from_pandas(pd.DataFrame(flat), preserve_index=False), key)


def tuning_inputs(spec: TuneSpec, sweep):
    """What the tuning's trials are computed from (:func:`nnrobust.studies.base.plan.study_inputs`): the
    uncertainty set and its base, the controllers, and the options.
    """
    from ..base.plan import study_inputs

    options = {
        "--budget": str(spec.budget),
        "--train-samples": str(spec.train_samples),
        "--validation": str(spec.validation),
        "--max-rms-torque": repr(spec.max_rms_torque),
        "--max-saturated": repr(spec.max_saturated),
        "--seed": str(spec.seed),
    }  # the --set values are the sweep's [set]: study_inputs records them
    return study_inputs(sweep, options)


def prepare_folder(spec: TuneSpec, folder: Path, overwrite: bool, inputs) -> None:
    """Create DIR or accept it for resuming the same tuning on the same ``inputs``
    (:func:`tuning_inputs`); one of other inputs is refused, naming what changed, unless
    ``overwrite``, which replaces only what a tuning wrote (:mod:`nnrobust.studies.base.folder`).
    DIR/tune.toml is the resolved tuning with its inputs' digests, for the reader.
    """
    from ..base.folder import prepare

    outputs = (TRIALS, MARKER, "summary.json", "pareto.png", "pareto.svg")
    prepare(folder, "tune", spec.to_toml(), outputs, overwrite, "tuning", TRIALS, MARKER, inputs)


def run_tune(
    spec: TuneSpec,
    folder: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress=None,
    ship_files: bool | None = None,
) -> dict:
    """Run (or resume) a tuning into ``folder``; returns the summary (also DIR/summary.json).

    ``progress(done, total)`` is called as settings finish (done and total count simulations).
    The folder is locked for the run. ``ship_files``: send the files the runs read with the
    tasks (:func:`nnrobust.studies.base.cluster.ships_files`; default: on a ``scheduler`` of the user's).
    """
    from ...core.folders import held
    from ..base.cluster import check_local_workers, ships_files

    check_local_workers(workers, scheduler)  # before the folder is made
    ship = ships_files(ship_files, scheduler)
    with held(Path(folder)):
        return _run_tune(spec, Path(folder), workers, scheduler, overwrite, progress, ship)


def _run_tune(
    spec: TuneSpec,
    folder: Path,
    workers: int | None,
    scheduler: str | None,
    overwrite: bool,
    progress,
    ship: bool = False,
) -> dict:
    from ..base.cluster import cluster_client as _client
    from ..base.cluster import require_engine as _require_engine
    from ..base.cluster import shared, shipped_files
    from ..base.plan import base_config, base_values, draw, experiment, first_step

    _require_engine()
    try:
        import optuna  # noqa: F401
    except ImportError as err:
        raise NNRobustError(f"tuning needs Optuna ({err}); pip install 'nnrobust[tune]'") from err
    folder = Path(folder)
    sweep = sweep_of(spec)
    base_config(sweep)  # the base file and [set], refused as the file's or as [set]'s
    base = base_values(sweep)
    from ...controllers.base import Controller
    from ...plugins.user_code import load_class

    controllers = {}
    for name in sweep.controllers:  # every experiment validated before anything runs
        for sample_id in range(sweep.samples):
            experiment(sweep, base, draw(sweep, sample_id), name)
        first = experiment(sweep, base, draw(sweep, 0), name)
        if first.simulation.duration <= SETTLED_AFTER:
            raise ConfigError(
                "simulation.duration",
                f"{first.simulation.duration:g} s: tuning minimises the RMS error after "
                f"{SETTLED_AFTER:g} s, so runs must last longer",
            )
        entry = sweep.entries.get(name, {"kind": name})
        if "class" in entry:  # its declared space; built, its first step run, at the space's centre
            space = custom_space(name, load_class(entry["class"], Controller, "controller.class"))
            centre = space.overrides({p.name: math.sqrt(p.low * p.high) for p in space.params})
            first_step(experiment(sweep, base, draw(sweep, 0), name, centre))
        else:
            space = search_space(entry["kind"], arm_scales(first_step(first)))
        controllers[name] = ControllerSearch(spec, name, space)
    inputs = tuning_inputs(spec, sweep)
    prepare_folder(spec, folder, overwrite, inputs)
    for row in _read_trials(folder, inputs.key):  # resume: replay the history, widening as it did
        if row["controller"] in controllers:
            controllers[row["controller"]].record(row)
    train = list(range(spec.train_samples))
    total = spec.trials * len(controllers) * spec.train_samples
    with signals_as_interrupt(), _client(workers, scheduler) as client:
        sweep_future, base_future = shared(client, sweep), shared(client, base)
        files = shipped_files(client, inputs, ship)
        batch = max(1, math.ceil(ROUND_SIMULATIONS / spec.train_samples))

        def done_count():
            return sum(len(c.rows) for c in controllers.values()) * spec.train_samples

        if progress:
            progress(done_count(), total)
        # Each controller's optimiser asks from its own rows alone, so the controllers' rounds
        # run side by side (run_task_groups): one is told and asks again while the others'
        # simulations run, and the settings asked are those of rounds run one after another.
        from ..base.cluster import CRASHED, run_task_groups

        asked: dict[str, list] = {}
        new: list[dict] = []  # rows not yet written

        def flush() -> None:
            if new:
                _write_trials(folder, new, inputs.key)
                new.clear()

        def round_of(c) -> list[tuple]:
            asked[c.name] = c.ask(batch) if c.remaining > 0 else []
            return [
                (evaluate, sweep_future, base_future, c.law(phase), c.overrides(values, phase), s)
                for _, values, phase in asked[c.name]
                for s in train
            ]

        def told(name: str, flat: list[dict]) -> list[tuple]:
            c = controllers[name]
            rows = [
                c.tell(trial, values, phase, flat[i * len(train) : (i + 1) * len(train)])
                for i, (trial, values, phase) in enumerate(asked[name])
            ]
            for row in rows:  # after every tell: recording may widen a space (a new study)
                c.record(row)
            new.extend(rows)
            if len(new) >= len(controllers) * batch:  # about one round of every controller a part
                flush()
            if progress:
                progress(done_count(), total)
            return round_of(c)

        try:
            run_task_groups(
                client,
                {name: round_of(c) for name, c in controllers.items()},
                lambda reason: {"status": CRASHED, "message": reason},
                told,
                files,
            )
        finally:
            flush()  # what finished is kept, also when interrupted
        summary = _summary(spec, sweep, controllers, client, sweep_future, base_future, files)
    _write_json(folder / "summary.json", summary)
    plot_pareto(summary, folder)
    from .summary import TuneSummary

    return TuneSummary(summary)


def error_torque_front(pareto: list[dict]) -> list[tuple[float, float]]:
    """(RMS torque [N m], RMS error [mm]) of the settings no other beats in both, by torque: the
    2-D front the figures draw (a subset of the 3-D front in the summary).
    """
    points = sorted((p["train"]["rms_torque"], 1e3 * p["train"]["rms_error_after_2s"]) for p in pareto)
    front: list[tuple[float, float]] = []
    for torque, error in points:
        if not front or error < front[-1][1]:
            front.append((torque, error))
    return front


def _pareto(rows: list[dict]) -> list[dict]:
    """The feasible settings no other feasible setting beats in every objective."""
    feasible = [r for r in rows if r["feasible"]]
    out = []
    for r in feasible:
        a = np.asarray(r["objectives"])
        dominated = any(
            np.all(np.asarray(o["objectives"]) <= a) and np.any(np.asarray(o["objectives"]) < a)
            for o in feasible
        )
        if not dominated:
            out.append(r)
    return sorted(out, key=lambda r: r["objectives"][0])


def _summary(spec, sweep, controllers, client, sweep_future, base_future, files=None) -> dict:
    from ..base.plan import draw

    held_out = list(range(spec.train_samples, spec.train_samples + spec.validation))
    out = {
        "target": spec.target,
        "budget": spec.budget,
        "trials": spec.trials,
        "seed": spec.seed,
        "objectives": list(OBJECTIVES),
        "constraints": {
            "max_rms_torque": spec.max_rms_torque if math.isfinite(spec.max_rms_torque) else None,
            "max_saturated": spec.max_saturated,
            "runaway": False,
            "max_joint_limit_violation": 0.0,
        },
        "train_samples": [
            {"sample": i, "seed": draw(sweep, i).seed, **draw(sweep, i).values}
            for i in range(spec.train_samples)
        ],
        "validation_samples": [
            {"sample": i, "seed": draw(sweep, i).seed, **draw(sweep, i).values} for i in held_out
        ],
        "controllers": {},
    }
    for name, c in controllers.items():
        best = c.best()
        entry: dict = {
            "simulations": len(c.rows) * spec.train_samples,
            "space": c.space.to_dict(),
            "fixed": dict(c.space.fixed),
            "pareto": [
                {"params": r["params"], "search": r["search"], "train": r["train"]}
                for r in _pareto([r for r in c.rows if r["phase"] == "all"])
            ],
            "gain_phase_simulations": c.gain_trials * spec.train_samples,
        }
        entry["runs_without_result"] = sum(
            run.get("status") in WITHOUT_RESULT for row in c.rows for run in row["runs"]
        )
        if best is None:
            entry["best"] = None
            entry["note"] = f"no setting met the constraints: {why_none(c.rows)}"
        else:
            runs = _simulate(
                client,
                [(evaluate, sweep_future, base_future, name, best["params"], s) for s in held_out],
                files,
            )
            entry["best"] = {
                "params": best["params"],
                "search": best["search"],
                "train": best["train"],
                **validated(spec, runs),
                "at_bound": c.space.at_bound(best["search"]),
            }
        half = c.best(trials=spec.trials // 2)
        entry["half_budget_best"] = None if half is None else {
            "simulations": (spec.trials // 2) * spec.train_samples,
            "params": half["params"],
            "search": half["search"],
            "train": half["train"],
        }  # fmt: skip
        entry["curve"] = c.curve()
        entry["widened"] = c.widenings
        out["controllers"][name] = entry
    return out


def validated(spec: TuneSpec, runs: list[dict]) -> dict:
    """A setting's held-out runs judged as its training runs were (:func:`judge`): ``validation``
    (their mean metrics), ``validation_constraints`` (each constraint's value, met when <= 0) and
    ``validation_feasible`` (every constraint met on the held-out draws too); empty without runs.
    """
    if not runs:
        return {"validation": {}}
    _, constraints, mean = judge(spec, runs)
    return {
        "validation": mean,
        "validation_constraints": dict(zip(CONSTRAINTS, constraints)),
        "validation_feasible": all(v <= 0 for v in constraints),
    }


def infeasible_text(spec_limits: dict, metrics: dict, constraints: dict) -> str:
    """Which constraints ``constraints`` (:data:`CONSTRAINTS` -> value) break, with the numbers:
    "RMS torque 13.1 N m > 10 N m, saturated 7.9 % > 1 %" ("" when every one is met).
    """
    parts = []
    if constraints.get("completed", -1) > 0:
        return f"a run did not complete ({metrics.get('status', 'failed')})"
    if constraints.get("rms_torque_over_limit", -1) > 0:
        parts.append(f"RMS torque {metrics['rms_torque']:.3g} N m > {spec_limits['max_rms_torque']:g} N m")
    if constraints.get("saturated_over_limit", -1) > 0:
        share, limit = 100 * metrics["saturated_fraction"], 100 * spec_limits["max_saturated"]
        parts.append(f"saturated {share:.3g} % > {limit:g} %")
    if constraints.get("runaway", -1) > 0:
        parts.append("the error ran away")
    if constraints.get("joint_limit_violation", -1) > 0:
        parts.append(f"a joint stop hit by {metrics['max_joint_limit_violation']:.3g}")
    return ", ".join(parts)


def _write_json(path: Path, data: dict) -> None:
    from ...run.results import write_text_atomic

    write_text_atomic(path, json.dumps(data, indent=1, default=float) + "\n")


@drawn_alone
def plot_pareto(summary: dict, folder: Path) -> None:
    """DIR/pareto.png and .svg: every controller's Pareto front, RMS error against RMS torque."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name, entry in summary["controllers"].items():
        points = error_torque_front(entry["pareto"])
        if points:
            ax.plot(*zip(*points), "o-", ms=4, label=name)
        if entry["best"]:
            ax.plot(
                entry["best"]["train"]["rms_torque"],
                1e3 * entry["best"]["train"]["rms_error_after_2s"],
                "k*",
                ms=10,
            )
    limit = summary["constraints"]["max_rms_torque"]
    if limit:
        ax.axvline(limit, color="0.5", ls=":", label=f"RMS torque limit {limit:g} N m")
    ax.set_yscale("log")
    ax.set_xlabel("RMS torque [N m]")
    ax.set_ylabel("RMS error, t ≥ 2 s [mm]")
    ax.set_title(f"Pareto fronts at {summary['budget']} simulations each (★ best under the constraints)")
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()  # once, where bbox_inches="tight" would lay out every format again
    for ext in ("png", "svg"):
        tmp = folder / f".pareto.partial.{ext}"
        fig.savefig(tmp, dpi=120)
        os.replace(tmp, folder / f"pareto.{ext}")
    plt.close(fig)
