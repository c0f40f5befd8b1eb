"""Running a study: for each case, the stages in order, each the existing command's own engine
writing its own folder (docs/study.md).

1. **tune**, once per optimiser seed (``nnrobust tune``'s engine, ``cases/C/tune-seedS/``);
2. **validate**: every (controller, seed) setting on fresh draws of the uncertainty set
   (``nnrobust sweep``'s engine, ``cases/C/validate/``); each controller keeps the seed with the
   least median error there;
3. **certify**: the kept settings on other fresh draws, as many as the claim needs (a sweep,
   ``cases/C/certify/``): certificates, statistics and paired comparisons on draws the
   selection never saw;
4. **falsify**: the kept settings searched for their worst plant (``nnrobust falsify``'s
   engine, ``cases/C/falsify/``);
5. **realtime** (with ``realtime = true``): each kept law exported (``nnrobust export``'s
   engine, ``cases/C/realtime/LABEL/law/``) at its setting on the first certification draw, and
   its step timed out of Python on that run's measured states (the export's ``bin/time_step``);
6. **engine** (with ``second_engine = true``): the certification draws again with MuJoCo as
   the plant (a sweep, ``cases/C/certify-mujoco/``), its statistics and certificates beside.

The step cost of each controller is read off the certification rows (their ``wall_seconds``
over the steps of a run, the loop alone, on the backend each ran on).

Every stage resumes (its engine does) and refuses inputs that changed since its rows were
computed; a finished study reruns to "nothing to do". One local cluster serves every stage.
Stages that do not need each other's results run side by side on it (:func:`side_by_side`): the
tunings of the optimiser seeds, then certify, falsify and the second engine's draws, so that
one's last tasks and the next one's first share the workers instead of leaving one idle. Each
stage's results do not depend on that timing (its draws and its searches are seeded).
"""

from __future__ import annotations

import math
import threading
from pathlib import Path

from ...core.exceptions import ChangedInputs, ConfigError, NNRobustError
from ...core.folders import own_folder
from .evidence import failures, realtime, step_cost
from .selection import convergence, half_name, select_kept
from .spec import StudyCase, StudySpec, kept_name

MARKER = "study.toml"
STAGE_FOLDERS = ("validate", "certify", "falsify", "certify-mujoco", "realtime", "responses")
"""A case's stage folders (besides tune-seedS), each written by its command's engine."""
VALIDATION_SEED = 1_000_003
"""Added to the study's seed for the validation draws (the tunings draw from seed + s, s < 20)."""
CERTIFY_SEED = 2_000_003
"""Added to the study's seed for the certification draws: independent of training and validation."""


def _write_if_changed(path: Path, text: str) -> None:
    """Write ``text`` atomically unless the file already holds it (a stage's input file: an
    unchanged rewrite keeps its resume).
    """
    from ...run.results import write_text_atomic

    if path.is_file() and path.read_text() == text:
        return
    write_text_atomic(path, text)


def seed_name(controller: str, seed: int) -> str:
    """The validation entry of one (controller, optimiser seed) setting."""
    return f"{controller}-seed{seed}"


def prepare(spec: StudySpec, folder: Path, overwrite: bool) -> None:
    """The study folder: new, or one of this study (its marker holds the same study file), or
    replaced with ``overwrite``; its stages then refuse their own changed inputs.
    """
    from ...core.folders import check_place

    check_place(folder)
    marker = folder / MARKER
    text = spec.path.read_text()
    if marker.is_file() and marker.read_text() != text and not overwrite:
        changed = _changed(marker.read_text(), text)
        if changed:  # (a comment or the layout alone changes nothing)
            raise NNRobustError(
                f"{folder} holds another study (changed since its rows were computed: {changed}); give "
                f"another --out, or --overwrite to run {spec.path} there"
            )
    folder.mkdir(parents=True, exist_ok=True)
    _write_if_changed(marker, text)
    stages = [*(f"tune-seed{s}" for s in range(spec.budgets["seeds"])), *STAGE_FOLDERS]
    for case in spec.cases:  # before any stage: no link planted in the folder is written through
        here = own_folder(own_folder(folder / "cases") / spec.case_name(case))
        for name in stages:
            if (here / name).is_symlink() or (here / name).exists():
                own_folder(here / name)


def _changed(old: str, new: str) -> str:
    """The keys whose values differ between two study files, in words ('' when none does)."""
    from ...config import parse_toml

    def flat(text: str) -> dict:
        try:
            data = parse_toml(text, "study")
        except ConfigError:
            return {"(the file)": text}
        out = {}
        for key, value in data.items():
            if isinstance(value, dict):
                out.update({f"{key}.{k}": v for k, v in value.items()})
            else:
                out[key] = value
        return out

    a, b = flat(old), flat(new)
    keys = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
    return ", ".join(f"{k} {a.get(k, 'unset')!r} -> {b.get(k, 'unset')!r}" for k in keys[:5])


def _check_controllers(spec: StudySpec) -> None:
    """Every controller built and its first step run on every case, and every tuned one with a
    search space, before any stage runs (a refusal names the controller and the case).
    """
    from ...config import parse_toml
    from ..base.plan import base_config, base_values, check_controllers, parse_sweep
    from ..base.tuned import law_of, own_keys, tunable
    from ..tune.engine import SETTLED_AFTER
    from ..tune.space import custom_space

    for case in spec.cases:
        view = spec.for_case(case)  # the controllers that run on this case, with its entries
        sweep = spec.case_sweep(case)
        where = f"{spec.path}: case {spec.case_name(case)}"
        try:
            # as its stages' sweep files will read it: the entries' own settings against [set]
            parse_sweep(parse_toml(sweep.to_toml(), where), where)
            config = base_config(sweep)  # the case's experiment with the study's and its own [set]
            check_controllers(_at_centres(view, sweep), base_values(sweep))
            if spec.vary and spec.budgets["falsify"]:
                from ..falsify.spec import box_of

                box_of(sweep)  # the box the falsify stage will search: ranges only
        except ConfigError as err:
            key = err.key.removeprefix(f"{where}: ")
            raise ConfigError(f"{where}: {key}", err.message) from err
        if config.simulation.duration <= SETTLED_AFTER:
            raise ConfigError(
                f"{where}: simulation.duration",
                f"{config.simulation.duration:g} s: a study selects, certifies and reports by the RMS "
                f"error after {SETTLED_AFTER:g} s, so runs must last longer",
            )
        for name in view.controllers:  # a tuned law's own keys are its tuning's, not the case's
            if name in view.fixed:
                continue
            keys, prefixes = own_keys(law_of(name, view.entries))
            fixed = [k for k in spec.case_set(case) if k in keys or k.startswith(prefixes)]
            if fixed:
                raise ConfigError(
                    f"{where}: set.{fixed[0]}",
                    f"is a key of {name}, which the study tunes: set it in {name}'s entry with "
                    "tune = false, or leave it to the tuning",
                )
    for name in spec.controllers:
        if name in spec.fixed:
            continue
        entry = spec.entries.get(name)
        if entry is None and name not in tunable():
            raise ConfigError(
                f"{spec.path}: controllers",
                f"{name!r} has no search space to tune; set tune = false in its entry",
            )
        if entry is not None and "class" in entry:
            from ...controllers.base import Controller
            from ...plugins.user_code import load_class

            try:
                custom_space(name, load_class(entry["class"], Controller, "controller.class"))
            except ConfigError as err:
                said = str(err).split(": ", 1)[1]
                raise ConfigError(
                    f"{spec.path}: controllers.{name}",
                    f"{said}; or run it untuned: tune = false in its entry",
                ) from err


def _at_centres(spec: StudySpec, sweep):
    """The case's sweep with each tuned class entry at the centre of the space it declares (the
    tuner builds it there first; it never runs at its entry's own params, which a law in C++ need
    not give), so that the up-front check builds what the stages will run.
    """
    import dataclasses

    from ...controllers.base import Controller
    from ...plugins.user_code import load_class
    from ..tune.space import custom_space

    entries = {k: dict(v) for k, v in sweep.entries.items()}
    for name, entry in entries.items():
        if name in spec.fixed or "class" not in entry:
            continue
        try:
            space = custom_space(name, load_class(entry["class"], Controller, "controller.class"))
        except ConfigError:
            continue  # refused with its reason below (_check_controllers)
        centre = space.overrides({p.name: math.sqrt(p.low * p.high) for p in space.params})
        own = {k.removeprefix("controller.params."): v for k, v in centre.items()}
        entry["params"] = {**own, **(entry.get("params") or {})}
    return dataclasses.replace(sweep, entries=entries)


def run_study(
    spec: StudySpec,
    folder: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    say=None,
    progress=None,
) -> dict:
    """Run (or resume) every stage of every case into ``folder``; returns the report (also
    DIR/report.json, report.html and tables/). ``say(line)`` is told each stage as it starts and
    ends; ``progress(done, total)`` each stage engine's progress.
    """
    say = say or (lambda line: None)
    folder = Path(folder).resolve()  # the report's commands name absolute paths
    if len(spec.cases) * len(spec.controllers) > 8:
        say(
            f"checking {len(spec.controllers)} controllers on {len(spec.cases)} cases (each built and "
            "stepped once) before any stage runs"
        )
    _check_controllers(spec)
    from ..base.cluster import check_local_workers, ships_files

    check_local_workers(workers, scheduler)  # before the folder is made
    prepare(spec, folder, overwrite)
    kept = set(_result_parts(folder))
    ship = ships_files(None, scheduler)  # the stages run on the study's own cluster: decided here
    from ...core.signals import signals_as_interrupt

    with signals_as_interrupt(), _SharedCluster(workers, scheduler) as address:
        cases = {}
        for case in spec.cases:
            before: dict[Path, str | None] = {}  # the stages' input files as they were
            try:
                cases[spec.case_name(case)] = _run_case(
                    spec, case, folder, address, overwrite, say, progress, ship, before
                )
            except ChangedInputs:  # a stage refused its folder: its input files name its rows again
                for path, text in before.items():
                    if text is None:
                        path.unlink(missing_ok=True)
                    else:
                        _write_if_changed(path, text)
                raise
    new = len(set(_result_parts(folder)) - kept)
    say(
        f"{new} new part{'s' if new != 1 else ''} of results beside the {len(kept)} kept"
        if new
        else f"nothing computed: every stage's {len(kept)} parts of results were there; the report again"
    )
    from .report import write_report

    return write_report(spec, folder, cases)


def _result_parts(folder: Path) -> list[Path]:
    """Every file of rows the stages wrote (sweep results, tuning trials, searches' histories)."""
    from ..base.folder import PART_GLOB

    return list((folder / "cases").rglob(PART_GLOB))


class _SharedCluster:
    """One local cluster for every stage (or the given scheduler): its address."""

    def __init__(self, workers, scheduler):
        self.workers, self.scheduler, self.cluster = workers, scheduler, None

    def __enter__(self) -> str:
        if self.scheduler:
            return self.scheduler
        from ..base.cluster import checked_local_cluster

        self.cluster = checked_local_cluster(self.workers)  # as sweep, tune and falsify start theirs
        return self.cluster.scheduler_address

    def __exit__(self, *exc):
        if self.cluster is not None:
            from ...core.signals import signals_held

            with signals_held():  # a close cut short leaves its cluster closing for 10 s at exit
                self.cluster.close()
        return False


def _stage_file(path: Path, text: str, before: dict) -> None:
    """Write a stage's input file, keeping in ``before`` what it held first (None: nothing)."""
    if path not in before:
        before[path] = path.read_text() if path.is_file() else None
    _write_if_changed(path, text)


def _run_case(
    spec: StudySpec,
    case: StudyCase,
    folder: Path,
    address: str,
    overwrite: bool,
    say,
    progress,
    ship: bool,
    before: dict,
) -> dict:
    """Every stage of one case on the cluster at ``address``; ``ship``: the files the runs read
    travel with the tasks (:func:`nnrobust.studies.base.cluster.ships_files`). Each stage's input file is
    written through :func:`_stage_file`, which keeps in ``before`` what it held first: a stage
    that refuses its folder (computed from other inputs,
    :class:`~nnrobust.core.exceptions.ChangedInputs`) then has them put back (:func:`run_study`).
    """
    from ..base.plan import base_config, load_sweep
    from ..falsify import FalsifySpec, run_falsify
    from ..sweep.engine import read_results, run_sweep
    from ..tune.engine import TuneSpec, run_tune

    spec = spec.for_case(case)  # the controllers that run on this case, with its entries
    name = spec.case_name(case)
    here = own_folder(own_folder(folder / "cases") / name)  # never through a link planted there
    sweep = spec.case_sweep(case)
    case_file = here / "case.toml"
    _stage_file(case_file, sweep.to_toml(), before)
    b = spec.budgets
    tuned = [c for c in spec.controllers if c not in spec.fixed]
    out: dict = {"case": case.base, "stages": {}}
    if case.set:
        out["set"] = dict(case.set)

    # 1. tune, once per optimiser seed; on one draw where every draw is the same plant
    tunings = {}
    train_samples = b["train_samples"] if draws_differ(sweep) else 1
    if tuned and train_samples < b["train_samples"]:
        say(f"{name}: every draw is the same plant (no box, no noise, no drawn model error): tuned on one")
    together = _Together(progress)

    def tune(s: int, told):
        tune_spec = TuneSpec(
            str(case_file),
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
            here / f"tune-seed{s}",
            scheduler=address,
            overwrite=overwrite,
            progress=told,
            ship_files=ship,
        )

    if tuned:
        seeds = range(b["seeds"])
        say(
            f"{name}: tune {b['seeds']} optimiser seed{'s side by side' if b['seeds'] > 1 else ''}: "
            f"{', '.join(tuned)}, {b['tune']} simulations each"
        )
        tunings = dict(zip(seeds, side_by_side([lambda s=s, t=together.stage(): tune(s, t) for s in seeds])))
    out["stages"]["tune"] = (
        "finished"
        if tuned
        else "skipped: every law runs at "
        + (f"the kept settings of {spec.tuned}" if spec.tuned else "its own settings (tune = false)")
    )
    out["tunings"] = {s: str(here / f"tune-seed{s}") for s in tunings}
    out["train_samples"] = train_samples  # what the tunings ran on (one draw where all are the same)
    from .evidence import tuning_curves

    out["curves"] = tuning_curves(tunings)
    out["search"] = {  # per law and seed: the space searched, as widened, and what moved
        c: {s: {"space": summary["controllers"][c]["space"], "widened": summary["controllers"][c]["widened"]}
            for s, summary in tunings.items() if c in summary["controllers"]}
        for c in tuned
    }  # fmt: skip
    duration = base_config(sweep).simulation.duration
    out["training"] = {
        c: sum(
            summary["controllers"][c]["simulations"]
            for summary in tunings.values()
            if c in summary["controllers"]
        )
        * duration
        for c in tuned
    }
    # the keys each tuned law does not search, with why (the same for every seed)
    out["fixed"] = {
        c: entry.get("fixed", {})
        for summary in tunings.values()
        for c, entry in summary["controllers"].items()
    }

    # 2. validate every (controller, seed) on fresh draws; keep each controller's best seed
    from ..base.tuned import tuned_entry

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
        for s, summary in tunings.items():
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
    out["not_kept"] = {
        c: "; ".join(
            f"seed {s}: {summary['controllers'].get(c, {}).get('note', 'no best setting')}"
            for s, summary in tunings.items()
        )
        for c in tuned
        if not any(setting_of.get(seed_name(c, s)) for s in tunings)
    }
    for c, reason in out["not_kept"].items():
        say(f"{name}: {c} has no setting to validate: {reason}")
    if not names:
        raise NNRobustError(
            f"{name}: no controller has a setting to validate ({'; '.join(out['not_kept'].values())})"
        )
    validate = sweep_of(spec, case, names, entries, b["validation"], spec.seed + VALIDATION_SEED)
    validate_file = here / "validate.toml"
    _stage_file(validate_file, validate.to_toml(), before)
    say(f"{name}: validate {len(names)} settings on {b['validation']} fresh draws")
    validate_spec = load_sweep(validate_file)
    run_sweep(
        validate_spec,
        here / "validate",
        scheduler=address,
        overwrite=overwrite,
        progress=progress,
        ship_files=ship,
    )
    frame = read_results(here / "validate")
    from ..sweep.summary import summarize, write_summary

    write_summary(here / "validate", summarize(validate_spec, frame))
    kept, per_seed, infeasible = select_kept(spec, frame, setting_of)
    for c, reason in infeasible.items():
        out["not_kept"][c] = reason
        say(f"{name}: {c} is not kept: {reason}")
    out["convergence"] = {
        c: convergence(spec, frame, [label for label, s in setting_of.items() if s[0] == c], halves)
        for c in kept
        if c not in spec.fixed
    }
    out["stages"]["validate"] = "finished"
    out["kept"], out["per_seed"] = kept, per_seed
    if not kept:
        raise NNRobustError(
            f"{name}: no controller is feasible on the validation draws ({'; '.join(infeasible.values())})"
        )

    # 3. certify the kept settings on draws the selection never saw
    from ...run.properties import samples_needed

    certify_names, certify_entries, settings = [], {}, {}
    for c, entry in kept.items():
        label = c if c in spec.fixed else kept_name(c)
        certify_names.append(label)
        if c in spec.fixed:
            if c in spec.entries:
                certify_entries[c] = spec.entries[c]
        else:
            certify_entries[label] = tuned_entry(c, entry["settings"], spec.entries)
            settings[c] = entry["settings"]
    out["entries"] = {label: certify_entries.get(label) or {"kind": label} for label in certify_names}
    n = b["certify"] or samples_needed(b["epsilon"], b["beta"])
    certify = sweep_of(spec, case, certify_names, certify_entries, n, spec.seed + CERTIFY_SEED)
    certify_file = here / "certify.toml"
    _stage_file(certify_file, certify.to_toml(), before)
    say(
        f"{name}: certify {len(certify_names)} controllers on {n} fresh draws "
        f"(epsilon {b['epsilon']:g}, beta {b['beta']:g})"
    )
    certify_spec = load_sweep(certify_file)
    together = _Together(progress)
    status: dict[str, str] = {}  # stage -> how it ended, put in the report in the stages' order
    told = together.stage()
    stages = {
        "certify": lambda: _certified(spec, certify_spec, here / "certify", address, overwrite, told, ship)
    }

    # 4. falsify the kept settings
    if spec.vary and b["falsify"]:
        say(f"{name}: falsify {len(kept)} controllers, {b['falsify']} simulations each (and as many random)")
        falsify_spec = FalsifySpec(
            str(case_file),
            list(kept),
            list(spec.require),
            b["falsify"],
            seed=spec.seed,
            margin=b["margin"],
            tuned=settings or None,
        )
        falsify_told = together.stage()
        stages["falsify"] = lambda: run_falsify(
            falsify_spec, here / "falsify", scheduler=address, overwrite=overwrite, progress=falsify_told,
            claim=(b["epsilon"], b["beta"]), ship_files=ship,
        )  # fmt: skip
    elif b["falsify"]:
        status["falsify"] = "skipped: the study has no [vary] box to search"
    else:
        status["falsify"] = "skipped: falsify = 0"

    # 6. the certification draws again on the second engine
    if not b["second_engine"]:
        status["engine"] = "skipped: second_engine = false"
    elif not _has_mujoco():
        status["engine"] = "skipped: MuJoCo is not installed (pip install 'nnrobust[mujoco]')"
    else:
        again = load_sweep(certify_file)
        again.set["plant.engine"] = "mujoco"
        engine_file = here / "certify-mujoco.toml"
        _stage_file(engine_file, again.to_toml(), before)
        say(f"{name}: the certification draws again with MuJoCo as the plant")
        engine_spec = load_sweep(engine_file)
        engine_told = together.stage()
        stages["engine"] = lambda: _certified(
            spec, engine_spec, here / "certify-mujoco", address, overwrite, engine_told, ship
        )[0]
    if len(stages) > 1:
        say(f"{name}: {', '.join(stages)} side by side")
    done = dict(zip(stages, side_by_side(list(stages.values()))))
    summary, rows = done.pop("certify")
    out["certify"] = summary
    out["held_out"] = _varies(rows)
    out["step_cost"] = step_cost(certify_spec, rows)
    out["failures"] = failures(rows)
    from ...run.properties import run_properties
    from .evidence import failing_draws

    out["failing"] = failing_draws(certify_spec, rows, run_properties(spec.certified_properties()))
    status.update({stage: "finished" for stage in ("certify", *done)})
    out.update(done)

    # 5. the kept laws exported and timed out of Python: alone on the machine, after the stages
    # above (a step timed beside the workers' simulations would be timed on a busy core)
    if b["realtime"]:
        say(f"{name}: export the kept laws and time their steps out of Python")
        out["realtime"] = realtime(certify_spec, certify_names, here / "realtime")
        status["realtime"] = "finished"
    else:
        status["realtime"] = "skipped: realtime = false"
    out["stages"].update({stage: status[stage] for stage in ("certify", "falsify", "realtime", "engine")})
    from .evidence import responses

    say(f"{name}: the kept laws' time responses on their median and worst certification draws")
    out["responses"] = responses(certify_spec, rows, certify_names, here / "responses")
    return out


def _has_mujoco() -> bool:
    try:
        import mujoco  # noqa: F401
    except ImportError:
        return False
    return True


STOP_SECONDS = 30.0
"""How long stages asked to stop are waited for (each notices within a second,
:data:`nnrobust.studies.base.cluster.POLL_SECONDS`) before the cluster is closed under them."""


def side_by_side(stages: list) -> list:
    """Each stage's result (callables, each a stage engine run with its own client of the study's
    cluster), the stages run on threads side by side: one's last tasks and the next one's first
    share the workers. The first error (or interrupt) asks the others to stop at their next check
    (:func:`nnrobust.core.signals.stop_stages`); once every stage has ended, each keeping what it
    computed, it is raised.
    """
    if len(stages) == 1:
        return [stages[0]()]
    from concurrent.futures import FIRST_EXCEPTION, ThreadPoolExecutor, wait

    from ...core.signals import signals_held, stop_stages

    pool = ThreadPoolExecutor(len(stages), thread_name_prefix="nnrobust-stage")
    futures = [pool.submit(stage) for stage in stages]
    try:
        finished, _ = wait(futures, return_when=FIRST_EXCEPTION)
        first = next((f.exception() for f in futures if f in finished and f.exception()), None)
        if first is not None:
            raise first
    except BaseException:
        stop_stages()
        try:
            with signals_held():  # a second Ctrl-C would close the cluster under the stages
                wait(futures, timeout=STOP_SECONDS)
        finally:
            stop_stages(False)
            pool.shutdown(wait=False)
        raise
    pool.shutdown()
    return [f.result() for f in futures]


class _Together:
    """One progress display for the stages running side by side: the sum of their done and total
    runs, told to ``progress(done, total)``.
    """

    def __init__(self, progress):
        self.progress, self.counts, self.lock = progress, {}, threading.Lock()

    def stage(self):
        """The ``progress`` callback of one more stage."""
        if self.progress is None:
            return None
        key = len(self.counts)
        self.counts[key] = (0, 0)

        def told(done: int, total: int) -> None:
            with self.lock:
                self.counts[key] = (done, total)
                counts = self.counts.values()
                self.progress(sum(d for d, _ in counts), sum(t for _, t in counts))

        return told


def _certified(
    spec: StudySpec, sweep, folder: Path, address: str, overwrite: bool, progress, ship: bool = False
):
    """(summary, rows) of a certification sweep run into ``folder``: its statistics, paired
    comparisons and a certificate per property (the study's epsilon and beta), summary.json written.
    """
    from ...run.properties import certify, run_properties
    from ..sweep.engine import read_results, run_sweep
    from ..sweep.summary import summarize, write_summary

    run_sweep(sweep, folder, scheduler=address, overwrite=overwrite, progress=progress, ship_files=ship)
    rows = read_results(folder)
    summary = summarize(sweep, rows)
    b = spec.budgets
    properties = run_properties(spec.certified_properties())
    for label, entry in certify(sweep, rows, properties, b["epsilon"], b["beta"]).items():
        summary["controllers"][label].update(entry)
    write_summary(folder, summary)
    return summary, rows


def sweep_of(spec: StudySpec, case: StudyCase, names: list[str], entries: dict, samples: int, seed: int):
    """A sweep of ``names`` (with their ``entries``) on ``samples`` draws of the case's box."""
    from ..base.plan import SweepSpec

    return SweepSpec(
        name=f"{spec.name}-{spec.case_name(case)}",
        base=case.base,
        controllers=list(names),
        samples=samples,
        seed=seed,
        set=spec.case_set(case),
        vary=dict(spec.vary),
        entries={k: v for k, v in entries.items() if k in names},
    )


def draws_differ(sweep) -> bool:
    """Whether a case's draws are different plants before any runs: a ``[vary]`` box, sensor
    noise, or a nominal model whose error is drawn from each draw's seed. Where none is, every
    draw is the same plant and a tuning setting needs one run (the budget buys settings).
    """
    from ...config import nominal_kind
    from ..base.plan import base_config

    config = base_config(sweep)
    sensing, nominal = config.sensing, config.nominal
    noisy = any(sensing.position_noise) or any(sensing.velocity_noise)
    return bool(sweep.vary or noisy or (nominal_kind(config) == "urdf" and nominal.perturbed))


def _varies(frame) -> bool:
    """Whether the rows of a sweep differ from draw to draw: a case with no randomness (no box,
    no noise) gives every draw the same plant, so "held-out" draws are the training plant.
    """
    import numpy as np

    for _, rows in frame.groupby("controller"):
        values = rows["rms_error_after_2s"].to_numpy(dtype=float)
        values = values[np.isfinite(values)]
        if values.size > 1 and np.ptp(values) > 0:
            return True
    return False


def read_report(folder: str | Path) -> dict:
    """DIR/report.json (shown as HTML in Jupyter)."""
    from ...run.results import read_json
    from .tables import StudyReport

    report = read_json(Path(folder) / "report.json", "study's report")
    if not isinstance(report, dict):
        raise NNRobustError(f"{Path(folder) / 'report.json'}: not a study's report (not a table)")
    return StudyReport(report)
