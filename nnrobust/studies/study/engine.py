"""Running a study: for each case, the stages of the stage table (:data:`.stages.STAGES`), each
the existing command's own engine writing its own folder (docs/study.md).

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
from pathlib import Path

from ...controllers.laws.policy import policy_params
from ...core.exceptions import ChangedInputs, ConfigError, NNRobustError
from ...core.folders import own_folder
from .spec import StudyCase, StudySpec
from .stages import STAGE_FOLDERS, CaseRun, run_case

MARKER = "study.toml"


def _write_if_changed(path: Path, text: str) -> None:
    """Write ``text`` atomically unless the file already holds it (a stage's input file: an
    unchanged rewrite keeps its resume).
    """
    from ...run.results import write_text_atomic

    if path.is_file() and path.read_text() == text:
        return
    write_text_atomic(path, text)


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
        out: dict = {}

        def put(key: str, value) -> None:
            if isinstance(value, dict):
                for k, v in value.items():
                    put(f"{key}.{k}", v)
            else:
                out[key] = value

        for key, value in data.items():
            if key == "controllers" and isinstance(value, list):  # an entry by its name: what changed in it
                for i, entry in enumerate(value):
                    name = entry.get("name", i) if isinstance(entry, dict) else entry
                    put(f"controllers.{name}", entry if isinstance(entry, dict) else "listed")
                out["controllers (their order)"] = [
                    e.get("name") if isinstance(e, dict) else e for e in value
                ]
            elif isinstance(value, dict):
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
    not give), and each policy the study trains as its base law (its file is the train stage's),
    so that the up-front check builds what the stages will run.
    """
    import dataclasses

    from ...controllers.base import Controller
    from ...plugins.user_code import load_class
    from ..tune.space import custom_space

    entries = {k: dict(v) for k, v in sweep.entries.items()}
    for name in spec.trained:  # no file before the train stage: its base law, which the episodes run
        entries[name] = {"kind": policy_params(entries[name].get("params"))["base"], "set": {}}
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
        f"{new} new part{'s' if new != 1 else ''} of results (or trained policies) beside the "
        f"{len(kept)} kept"
        if new
        else f"nothing computed: every stage's {len(kept)} parts of results (and trained policies) were "
        "there; the report again"
    )
    from .report import write_report

    return write_report(spec, folder, cases)


def _result_parts(folder: Path) -> list[tuple[Path, int]]:
    """Every file of rows the stages wrote (sweep results, tuning trials, searches' histories) and
    every trained policy file, each with its modification time (a policy trained again is new).
    """
    from ..base.folder import PART_GLOB

    files = [*(folder / "cases").rglob(PART_GLOB), *(folder / "cases").glob("*/train/*/policy.onnx")]
    return [(path, path.stat().st_mtime_ns) for path in files]


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
    """Every stage of one case (:data:`~.stages.STAGES`) on the cluster at ``address``; ``ship``:
    the files the runs read travel with the tasks (:func:`nnrobust.studies.base.cluster.ships_files`).
    Each stage's input file is written through :func:`_stage_file`, which keeps in ``before`` what
    it held first: a stage that refuses its folder (computed from other inputs,
    :class:`~nnrobust.core.exceptions.ChangedInputs`) then has them put back (:func:`run_study`).
    """
    spec = spec.for_case(case)  # the controllers that run on this case, with its entries
    here = own_folder(own_folder(folder / "cases") / spec.case_name(case))  # never through a planted link
    run = CaseRun(
        spec, case, spec.case_sweep(case), here, address, overwrite, say, progress, ship,
        stage_file=lambda path, text: _stage_file(path, text, before),
    )  # fmt: skip
    run.stage_file(run.case_file, run.sweep.to_toml())
    run.out = {"case": case.base, "stages": {}}
    if case.set:
        run.out["set"] = dict(case.set)
    return run_case(run)


def read_report(folder: str | Path) -> dict:
    """DIR/report.json (shown as HTML in Jupyter)."""
    from ...run.results import read_json
    from .tables import StudyReport

    report = read_json(Path(folder) / "report.json", "study's report")
    if not isinstance(report, dict):
        raise NNRobustError(f"{Path(folder) / 'report.json'}: not a study's report (not a table)")
    return StudyReport(report)
