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
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..config import CLASS_PATTERN
from ..drawing import drawn_alone
from ..exceptions import ConfigError, NNRobustError
from ..results import SETTLED_AFTER
from ..search_coordinates import controller_seed
from ..signals import signals_as_interrupt
from ..sweep.spec import NAME
from .space import SearchSpace, arm_scales, custom_space, search_space, tunable

if TYPE_CHECKING:
    import optuna

OBJECTIVES = ("rms_error_after_2s", "rms_torque", "torque_chatter")
"""What every setting is recorded with (the Pareto front's axes, all minimised): [m], [N m], [N m].
The search minimises the first under the constraints."""

CONSTRAINTS = (
    "rms_torque_over_limit",
    "saturated_over_limit",
    "runaway",
    "joint_limit_violation",
    "completed",
)
"""Each setting's constraints, met when <= 0 (the order of :func:`judge`'s list)."""

FAILED = (1.0, 1e4, 1e4)
"""Objective values of a setting whose run failed (diverged, refused): worse than any real one."""


MARKER = "tune.toml"
TRIALS = "trials"
WIDEN_FROM = 0.5
"""Fraction of a controller's settings after which a best setting on a bound widens its space."""
MAX_WIDENINGS = 4
"""Decades a bound may move out; past them it is reported in ``at_bound`` as searched to its end."""
GAIN_SHARE = 0.3
"""Share of a robust law's budget spent on its gains with u_0 = 0 (see _Controller)."""


@dataclass
class TuneSpec:
    """What a tuning is: target, controllers, budget, samples, constraints, seed.

    Attributes:
        target: a preset, an experiment file or a sweep file (its [vary] is the uncertainty set).
        controllers: controller kinds to tune.
        budget: simulations per controller (the training runs; validation is extra).
        train_samples: samples each setting is simulated on (common random numbers).
        validation: held-out samples the best setting is checked on.
        max_rms_torque: [N m] constraint (inf: none).
        max_saturated: constraint on the fraction of saturated steps (1: none).
        seed: seed of the optimiser and of the samples.
        set: fixed overrides of the target's experiment (``--set KEY=VALUE``, as a sweep file's
            [set]: every run takes them; a key the target's [vary] draws is refused).

    """

    target: str
    controllers: list[str]
    budget: int
    train_samples: int = 1
    validation: int = 4
    max_rms_torque: float = math.inf
    max_saturated: float = 1.0
    seed: int = 0
    set: dict = field(default_factory=dict)

    def __post_init__(self):
        checks = [
            ("--budget", self.budget >= 2 and self.budget <= 100_000, "an integer in [2, 100000]"),
            ("--train-samples", 1 <= self.train_samples <= 1000, "an integer in [1, 1000]"),
            ("--validation", 0 <= self.validation <= 1000, "an integer in [0, 1000]"),
            ("--max-rms-torque", self.max_rms_torque > 0, "> 0 [N m]"),
            ("--max-saturated", 0 <= self.max_saturated <= 1, "in [0, 1]"),
            ("--seed", 0 <= self.seed < 2**31, "an integer in [0, 2^31)"),
        ]
        for flag, ok, valid in checks:
            if not ok:
                raise ConfigError(flag, f"must be {valid}")
        if self.budget < self.train_samples:
            raise ConfigError(
                "--budget",
                f"{self.budget} simulations cannot run one setting on {self.train_samples} training samples",
            )
        if not self.controllers or len(set(self.controllers)) != len(self.controllers):
            raise ConfigError(
                "--controllers",
                f"needs distinct names among {', '.join(tunable())}, custom "
                "classes as file.py:Class, or the custom entries of a sweep file; got "
                f"{', '.join(self.controllers) or 'none'}",
            )

    @property
    def trials(self) -> int:
        """Settings per controller: the budget over the training samples."""
        return self.budget // self.train_samples

    def to_toml(self) -> str:
        """The resolved tuning (DIR/tune.toml)."""
        from ..config import dump_toml

        return dump_toml(
            {
                "target": self.target,
                "controllers": self.controllers,
                "budget": self.budget,
                "train_samples": self.train_samples,
                "validation": self.validation,
                "max_rms_torque": self.max_rms_torque if math.isfinite(self.max_rms_torque) else "inf",
                "max_saturated": self.max_saturated,
                "seed": self.seed,
                **({"set": dict(self.set)} if self.set else {}),
            }
        )


def sweep_of(spec: TuneSpec):
    """The uncertainty set as a sweep: the target's [vary] draws (or only seeds), no grid."""
    from ..sweep.spec import SweepSpec, load_sweep

    path = Path(spec.target)
    is_sweep = False
    if path.suffix == ".toml" and path.is_file():
        from ..config import parse_toml, read_text_file

        data = parse_toml(read_text_file(path, what="tuning target"), str(path))
        is_sweep = "base" in data and "controllers" in data
    else:
        from ..sweep.spec import shipped_sweeps

        is_sweep = spec.target in shipped_sweeps()
    size = spec.train_samples + spec.validation
    if is_sweep:
        sweep = load_sweep(spec.target)
        if sweep.grid_keys:
            raise ConfigError(
                "vary",
                f"tuning draws its samples from [vary] distributions; the grid keys "
                f"{', '.join(sweep.grid_keys)} are lists (make them a distribution or "
                "set them in [set])",
            )
        sweep.samples, sweep.seed = size, spec.seed
        varied = sorted(set(spec.set) & set(sweep.vary))
        if varied:
            raise ConfigError(
                f"--set {varied[0]}", "is drawn by the sweep file's [vary]: it cannot also be fixed"
            )
        sweep.set = {**sweep.set, **spec.set}
    else:
        base = str(path.resolve()) if path.suffix == ".toml" else spec.target
        sweep = SweepSpec(
            name=path.stem if path.suffix == ".toml" else spec.target,
            base=base,
            controllers=[],
            samples=size,
            seed=spec.seed,
            set=dict(spec.set),
        )
    return _with_controllers(sweep, spec.controllers)


TUNED_FILE_BYTES = 50_000_000
"""The largest tuning summary or study report --tuned reads (the shipped reports are under 0.3 MB)."""


def law_of(name: str, entries: dict | None = None) -> str:
    """The law a controller name runs, as :func:`.space.own_keys` knows it: a shipped kind or
    registered law by its name, a sweep file's entry by its kind (or ``custom``), a class given as
    file.py:Class as ``custom``.
    """
    entry = (entries or {}).get(name)
    if entry is not None:
        return entry.get("kind", "custom")
    return "custom" if CLASS_PATTERN.fullmatch(name) else name


def summary_name(name: str) -> str:
    """The name a controller has in a tuning's summary: a class given as NAME=file.py:Class by
    NAME, as file.py:Class by its class name, any other by the name given (:func:`_with_controllers`).
    """
    label, equals, spec = name.partition("=")
    if equals and CLASS_PATTERN.fullmatch(spec):
        return label
    return name.rpartition(":")[2] if CLASS_PATTERN.fullmatch(name) else name


def check_tuned(
    tuned: dict[str, dict], varied=(), where: str = "--tuned", entries: dict | None = None
) -> None:
    """Refuse a tuned setting (controller name -> dotted-key settings) that sets a key the law
    does not read itself (:func:`.space.own_keys`: a plant's, the controller's kind, another
    law's; a custom law's are its ``controller.params.*``), or a key the box varies (``varied``,
    dotted keys): it would run every point of the box at that value while the summary claims the
    box. ``where`` names the settings' file in the message; ``entries``: the sweep file's table
    entries, by name.
    """
    import re

    from .space import own_keys

    box = {re.sub(r"\[\d+\]$", "", str(k)) for k in varied}
    for name, settings in tuned.items():
        keys, prefixes = own_keys(law_of(name, entries))
        for key in settings:
            plain = re.sub(r"\[\d+\]$", "", str(key))
            if plain not in keys and not plain.startswith(prefixes):
                own = ", ".join([*sorted(keys), *(f"{p}*" for p in prefixes)])
                raise ConfigError(
                    "--tuned",
                    f"{where} sets {key!r} for {name}, which is not a key {name} reads itself; a tuned "
                    f"setting may set only the law's own keys ({own})",
                )
            if plain in box:
                raise ConfigError(
                    "--tuned",
                    f"{where} sets {key!r} for {name}, which the box varies: a tuned setting may not "
                    "fix a coordinate of the box (drop it from [vary], or tune without it)",
                )


STUDY_REPORT = "nnrobust-study-report/"
"""The schema of a study's report.json, whose kept settings ``--tuned FILE#CASE`` reads."""


def _study_kept(report: dict, file: Path, case: str) -> dict:
    """One case's kept settings of a study's report.json, as its ``cases/CASE/kept.json`` holds
    them: each tuned controller's kept setting as its best, an untuned one as fixed.
    """
    cases = report.get("cases")
    if not isinstance(cases, dict):
        cases = {}
    if case not in cases or not isinstance(cases[case], dict):
        raise ConfigError(
            "--tuned",
            f"{file} is a study's report: name one of its cases as {file}#CASE, one of "
            f"{', '.join(repr(k) for k in cases)}" + (f" (not {case!r})" if case else ""),
        )
    controllers = cases[case].get("controllers")
    if not isinstance(controllers, dict):
        raise ConfigError("--tuned", f"{file}: case {case!r} has no controllers table")
    kept: dict = {}
    for name, entry in controllers.items():
        tuned = entry.get("tuned") if isinstance(entry, dict) else None
        settings = tuned.get("settings") if isinstance(tuned, dict) else None
        kept[name] = {"fixed": True} if tuned is None else {"best": {"params": settings}}
    return {"controllers": kept}


def kept_entry(path: str | Path, name: str) -> dict | None:
    """The controllers entry a study certified as ``name`` (the name the study gave the law, its
    kept setting's ``NAME-tuned`` label, or the class name of a file.py:Class) in one case of its
    report (``REPORT.json#CASE``): its kind or class and the params and settings it ran with; None
    where the source is not a study's report or has no such law.
    """
    file, case = tuned_file(path)
    try:
        report = (
            json.loads(file.read_text()) if file.is_file() and file.stat().st_size < TUNED_FILE_BYTES else {}
        )
    except (OSError, ValueError, RecursionError):
        return None
    if not isinstance(report, dict) or not str(report.get("schema", "")).startswith(STUDY_REPORT):
        return None
    controllers = ((report.get("cases") or {}).get(case) or {}).get("controllers") or {}
    wanted = summary_name(name)
    for law, entry in controllers.items():
        if (
            isinstance(entry, dict)
            and wanted in (law, entry.get("label"))
            and isinstance(entry.get("entry"), dict)
        ):
            return entry["entry"]
    return None


def tuned_file(path: str | Path) -> tuple[Path, str]:
    """(the file ``--tuned`` reads, the case named after ``#``): a tuning's DIR is its
    summary.json; ``FILE#CASE`` names one case of a study's report.
    """
    text, _, case = str(path).partition("#")
    return (Path(text) / "summary.json" if Path(text).is_dir() else Path(text)), case


def tuned_settings(
    path: str | Path, names: list[str], varied=(), entries: dict | None = None
) -> dict[str, dict]:
    """Each named controller's best setting in a tuning's summary (``DIR`` or its summary.json), or
    a study's kept settings of one case (its ``cases/CASE/kept.json``, or its report.json named as
    ``FILE#CASE``): name -> its dotted-key overrides, each a key the law reads itself and none of
    ``varied``, the box's keys (:func:`check_tuned`). Every law takes them: a shipped kind, a
    registered law, a class as file.py:Class (found under its class name) and a sweep file's
    entry (``entries``, by name).
    """
    from ..config import read_text_file

    file, case = tuned_file(path)
    try:
        summary = json.loads(read_text_file(file, limit=TUNED_FILE_BYTES, what="tuning summary"))
    except ValueError as err:
        raise ConfigError("--tuned", f"{file} is not JSON ({err})") from err
    except RecursionError as err:
        raise ConfigError("--tuned", f"{file} nests too deeply to be a tuning's summary") from err
    if isinstance(summary, dict) and str(summary.get("schema", "")).startswith(STUDY_REPORT):
        summary = _study_kept(summary, file, case)
    elif case:
        raise ConfigError("--tuned", f"{file} is one tuning, not a study's report: drop #{case}")
    tuned = summary.get("controllers") if isinstance(summary, dict) else None
    if not isinstance(tuned, dict) or not all(isinstance(e, dict) for e in tuned.values()):
        raise ConfigError(
            "--tuned",
            f"{file} is not a tuning's summary.json (no controllers table; nnrobust tune writes one)",
        )
    out = {}
    for name in names:
        if (tuned.get(summary_name(name)) or {}).get("fixed") is True:  # a study's untuned controller
            continue
        best = (tuned.get(summary_name(name)) or {}).get("best")
        if not best:
            raise ConfigError(
                "--tuned",
                f"{file} has no best setting for {summary_name(name)!r} (it tuned "
                f"{', '.join(tuned) or 'nothing'})",
            )
        if not isinstance(best, dict) or not isinstance(best.get("params"), dict):
            raise ConfigError("--tuned", f"{file}: the best setting of {name!r} has no table of params")
        out[name] = dict(best["params"])
    check_tuned(out, varied, str(file), entries)
    return out


def tuned_target(path: str | Path) -> str:
    """The experiment a tuning tuned on (its summary's ``target``; a study report's case, by
    name), "" when the file does not say (read after :func:`tuned_settings` accepted it).
    """
    from ..config import read_text_file

    file, case = tuned_file(path)
    try:
        summary = json.loads(read_text_file(file, limit=TUNED_FILE_BYTES, what="tuning summary"))
    except (ValueError, RecursionError, ConfigError):
        return ""
    if isinstance(summary, dict) and str(summary.get("schema", "")).startswith(STUDY_REPORT):
        cases = summary.get("cases")  # a case's name: the preset, or the experiment file's stem
        return case if isinstance(cases, dict) and case in cases else ""
    target = summary.get("target") if isinstance(summary, dict) else None
    return target if isinstance(target, str) else ""


def tuned_entry(name: str, settings: dict, entries: dict) -> dict:
    """The sweep entry that runs controller ``name`` at its tuned dotted-key ``settings``, as a
    sweep file would write it: a shipped kind as ``{kind, set}``, a registered law's
    ``controller.params.*`` as its ``params``; a custom law (file.py:Class, or a sweep entry of a
    class) as ``{class, params}`` with the settings' ``controller.params.*`` over its own params; a
    sweep entry of a kind with the settings over its own.
    """
    from ..user_code import class_file

    entry = entries.get(name)
    if entry is None and CLASS_PATTERN.fullmatch(name):
        path = class_file(name)
        entry = {
            "class": f"{path.resolve()}:{summary_name(name)}" if path is not None else name,
            "params": {},
        }
    prefix = "controller.params."
    params = {k[len(prefix) :]: v for k, v in settings.items() if k.startswith(prefix)}
    rest = {k: v for k, v in settings.items() if not k.startswith(prefix)}
    if entry is None:
        entry = {"kind": name, "set": {}}
    if "class" in entry:
        return {"class": entry["class"], "params": {**(entry.get("params") or {}), **params}}
    own = {**(entry.get("params") or {}), **params}
    return {**entry, "set": {**(entry.get("set") or {}), **rest}, **({"params": own} if own else {})}


def check_tuned_values(sweep, tuned: dict, where: str = "--tuned") -> None:
    """Each tuned setting's values checked as the experiment reads them (on the sweep's first
    sample), a refusal naming --tuned, the law and the key, not a sample of the box.
    """
    from ..sweep.spec import base_values, draw, experiment

    base = base_values(sweep)
    for name in tuned:
        try:
            experiment(sweep, base, draw(sweep, 0), f"{summary_name(name)}-tuned")
        except ConfigError as err:
            said = str(err).removeprefix("vary: ").split(" (sample ")[0]
            raise ConfigError(where, f"the tuned setting of {name}: {said}") from err


def _with_controllers(sweep, names: list[str], tuned: dict | None = None):
    """The sweep with the tuning's controllers: built-in kinds, the sweep file's table entries by
    name, and classes given as file.py:Class (named by the class, the file read from the working
    folder). A built-in law in ``tuned`` (name -> dotted-key settings) runs at those settings as
    the entry ``NAME-tuned``.
    """
    from ..user_code import class_file

    entries, controllers = {}, []
    for name in names:
        if tuned and name in tuned:
            tuned_name = f"{summary_name(name)}-tuned"
            entries[tuned_name] = tuned_entry(name, tuned[name], sweep.entries)
            controllers.append(tuned_name)
        elif name in tunable():
            controllers.append(name)
        elif name in sweep.entries:
            entries[name] = sweep.entries[name]
            controllers.append(name)
        elif CLASS_PATTERN.fullmatch(name.partition("=")[2] if "=" in name else name):
            label, _, spec = name.rpartition("=")  # NAME=file.py:Class names the entry itself
            path, cls = class_file(spec), spec.rpartition(":")[2]
            label = label or cls
            if not NAME.fullmatch(label):
                raise ConfigError("--controllers", f"{label!r} must be 1-40 letters, digits, '_' or '-'")
            entries[label] = {"class": f"{path.resolve()}:{cls}" if path is not None else spec, "params": {}}
            controllers.append(label)
        else:
            raise ConfigError(
                "--controllers",
                f"{name!r} is not one of {', '.join(tunable())}, a class as "
                f"file.py:Class, nor a custom entry of the sweep file "
                f"({', '.join(sweep.entries) or 'it has none'})",
            )
    if len(set(controllers)) != len(controllers):
        raise ConfigError(
            "--controllers",
            f"names a controller twice: {', '.join(controllers)} (two files with one class name: name "
            "each, NAME=file.py:Class)",
        )
    sweep.controllers, sweep.entries = controllers, entries
    return sweep


ROUND_SIMULATIONS = 2
"""Simulations per controller per round of the optimiser (a batch of settings, each on every
training sample): fixed, so that the settings asked, and the results, are the same on any number
of workers (they were sized to the cluster, so one worker and two tuned differently). Every
controller's batch runs in the same round: 6 controllers on 2 samples are 12 tasks a round."""


# ---- on the workers ------------------------------------------------------------------------------


def evaluate(sweep, base: dict, controller: str, overrides: dict, sample_id: int) -> dict:
    """One simulation of a setting on one sample: its metrics (or the reason it failed). The
    setting's keys are set with the sample's in the base's own values
    (:func:`nnrobust.sweep.spec.experiment`), as an edit of the file would set them.
    """
    import time

    from ..experiment import run_experiment
    from ..sweep.spec import draw, experiment

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
    the tasks: :func:`nnrobust.sweep.engine.shipped_files`): its result, or status ``crashed``
    when it ends its worker (:func:`nnrobust.sweep.engine.run_tasks`).
    """
    from ..sweep.engine import CRASHED, run_tasks

    return run_tasks(client, tasks, lambda reason: {"status": CRASHED, "message": reason}, files)


def judge(spec: TuneSpec, runs: list[dict]) -> tuple[tuple[float, ...], list[float], dict]:
    """(objectives, constraints <= 0 when met, the mean metrics) of one setting's runs."""
    completed = all(r.get("status") == "completed" for r in runs)
    finite = all(r.get(k) is not None and math.isfinite(float(r[k])) for r in runs for k in OBJECTIVES)
    if not completed or not finite:
        return FAILED, [1.0] * len(CONSTRAINTS), {"status": "failed"}
    numbers = {k: float(np.mean([r[k] for r in runs])) for k in OBJECTIVES}
    saturated = float(max(r["saturated_fraction"] for r in runs))
    violation = float(max(r["max_joint_limit_violation"] for r in runs))
    runaway = bool(any(r["runaway"] for r in runs))
    mean = {
        **numbers,
        "saturated_fraction": saturated,
        "max_joint_limit_violation": violation,
        "runaway": runaway,
        "status": "completed",
    }
    torque = numbers["rms_torque"] - spec.max_rms_torque if math.isfinite(spec.max_rms_torque) else -1.0
    constraints = [torque, saturated - spec.max_saturated, 1.0 if runaway else -1.0, violation, -1.0]
    return tuple(numbers[k] for k in OBJECTIVES), constraints, mean


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
    no trial twice (:func:`nnrobust.study_folder.read_parts`).
    """
    from ..study_folder import read_parts

    tables = read_parts(folder / TRIALS, [*TRIAL_IDS, "row"], key, TRIAL_IDS)
    rows = [json.loads(r) for t in tables for r in t.column("row").to_pylist()]
    return sorted(rows, key=lambda r: (r["controller"], r["trial"]))


def _write_trials(folder: Path, rows: list[dict], key: str) -> None:
    """One Parquet part, tied to the tuning's inputs (``key``) and written whole: flat columns
    for pandas, and the whole row as JSON for resuming.
    """
    import pandas as pd
    import pyarrow as pa

    from ..study_folder import write_part

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
    """What the tuning's trials are computed from (:func:`nnrobust.sweep.spec.study_inputs`): the
    uncertainty set and its base, the controllers, and the options.
    """
    from ..sweep.spec import study_inputs

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
    ``overwrite``, which replaces only what a tuning wrote (:mod:`nnrobust.study_folder`).
    DIR/tune.toml is the resolved tuning with its inputs' digests, for the reader.
    """
    from ..study_folder import prepare

    outputs = (TRIALS, MARKER, "summary.json", "pareto.png", "pareto.svg")
    prepare(folder, "tune", spec.to_toml(), outputs, overwrite, "tuning", TRIALS, MARKER, inputs)


class _Controller:
    """One controller's search: its space, its history, what to ask next.

    A law with a robust term (NN, sliding mode) is eq. (9) with u_0 added, and with u_0 off it is
    the no-u0 law. Such a controller spends the first GAIN_SHARE of its own budget on its gains
    with u_0 = 0 (phase ``gains``), then searches every knob (phase ``all``) from its best gains
    with the robust term at its weakest: a random robust term at high gains chatters past the
    torque limit, and a search started there learns to avoid the only gains where the law can
    win. Its best setting is chosen among the phase ``all`` runs, which use the law itself. A
    registered law with an adaptive or robust term (its ``weak`` parameters) runs itself in the
    gain phase, with those parameters at their weakest.
    """

    def __init__(self, spec: TuneSpec, name: str, space: SearchSpace):
        self.spec, self.name, self.space = spec, name, space
        self.gain_trials = int(GAIN_SHARE * spec.trials) if space.robust else 0
        self.rows: list[dict] = []
        self.widenings: list[dict] = []  # {param, side, old, bound, trial, probe}, in order
        self.queue: list[dict] = []  # settings to try before the sampler's own: starts, probes
        # from the law's name, not its place in the list: a law tunes the same beside any others
        self.sampler_seed = (spec.seed + controller_seed(name)) % 2**31

    @property
    def phase(self) -> str:
        return "gains" if len(self.rows) < self.gain_trials else "all"

    def law(self, phase: str) -> str:
        """The controller kind the runs of a phase use."""
        return "no-u0" if phase == "gains" and not self.space.custom else self.name

    def overrides(self, values: dict, phase: str) -> dict:
        """The experiment overrides of a setting's runs in a phase."""
        if phase == "gains" and self.space.custom:  # the law itself, its robust term at its weakest
            values = {**values, **self.space.weakest()}
        return self.space.overrides(values)

    def _distributions(self, phase: str):
        import optuna

        params = self.space.gains if phase == "gains" else self.space.params
        return {p.name: optuna.distributions.FloatDistribution(p.low, p.high, log=True) for p in params}

    def _study(self):
        import warnings

        import optuna

        optuna.logging.set_verbosity(optuna.logging.WARNING)
        warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
        phase = self.phase
        sampler = optuna.samplers.TPESampler(
            seed=self.sampler_seed + 7919 * len(self.rows),
            multivariate=True,
            constant_liar=True,
            n_startup_trials=min(10, max(2, self.spec.trials // 5)),
        )
        study = optuna.create_study(direction="minimize", sampler=sampler)
        history = [r for r in self.rows if r["phase"] == phase]
        for row in history:
            study.add_trial(
                optuna.trial.create_trial(
                    params=row["search"],
                    distributions=self._distributions(phase),
                    value=row["objectives"][0],
                    constraints=dict(zip(CONSTRAINTS, row["constraints"])),
                )
            )
        return study

    @property
    def remaining(self) -> int:
        return self.spec.trials - len(self.rows)

    def best(self, phase: str = "all", trials: int | None = None) -> dict | None:
        """The feasible setting of a phase with the least training error (among the first
        ``trials`` settings tried, or all).
        """
        rows = self.rows if trials is None else self.rows[:trials]
        feasible = [r for r in rows if r["feasible"] and r["phase"] == phase]
        return min(feasible, key=lambda r: r["train"]["rms_error_after_2s"]) if feasible else None

    def curve(self) -> list[list[float | None]]:
        """The search's convergence: [simulations run, the least training error of a feasible
        setting of the law itself so far (phase ``all``; None before one)] after each setting.
        """
        out: list[list[float | None]] = []
        least = math.inf
        for i, row in enumerate(self.rows):
            if row["feasible"] and row["phase"] == "all":
                least = min(least, row["train"]["rms_error_after_2s"])
            out.append([(i + 1) * self.spec.train_samples, least if math.isfinite(least) else None])
        return out

    def starts(self) -> list[dict]:
        """The gain settings the full search starts from: the best of the gain phase, and the best
        with a tenth and a quarter of the torque limit to spare (a robust term adds torque, and
        the best gains often sit on the limit).
        """
        feasible = sorted(
            (r for r in self.rows if r["feasible"] and r["phase"] == "gains"),
            key=lambda r: r["train"]["rms_error_after_2s"],
        )
        limit = self.spec.max_rms_torque
        out: list[dict] = []
        for share in (1.0, 0.9, 0.75):
            pick = next(
                (
                    r
                    for r in feasible
                    if not math.isfinite(limit) or r["train"]["rms_torque"] <= share * limit
                ),
                None,
            )
            if pick is not None and pick not in out:
                out.append(pick)
        return out

    def tell(self, trial, values: dict, phase: str, results: list[dict]) -> dict:
        """Judge a setting's runs, tell the study, and return its trials-table row."""
        objectives, constraints, mean = judge(self.spec, results)
        for key, value in zip(CONSTRAINTS, constraints):
            trial.set_constraint(key, value)
        trial.study.tell(trial, objectives[0])
        return {
            "controller": self.name,
            "phase": phase,
            "law": self.law(phase),
            "search": values,
            "params": self.overrides(values, phase),
            "objectives": list(objectives),
            "constraints": constraints,
            "feasible": all(v <= 0 for v in constraints),
            "queued": values in self.queue,
            "train": mean,
            "runs": results,
        }

    def record(self, row: dict) -> None:
        """Add a finished trial; from WIDEN_FROM of the budget on, widen the space where the best
        sits on a bound that is not physical, and queue a probe past it (module docstring).
        Replaying the rows in order repeats every widening and probe, so a resumed tuning asks
        what an uninterrupted one would.
        """
        before = self.phase
        row["trial"] = len(self.rows)
        self.rows.append(row)
        if row.get("queued"):
            self.queue = [p for p in self.queue if p != row["search"]]
        if before == "gains" and self.phase == "all":
            self.queue += [{**g["search"], **self.space.weakest()} for g in self.starts()]
        if len(self.rows) < max(1, int(WIDEN_FROM * self.spec.trials)) or self.phase != "all":
            return
        best = self.best()
        if best is None:
            return
        moved = Counter((w["param"], w["side"]) for w in self.widenings)
        wider, widenings = self.space.widened(
            best["search"], skip=lambda p, side: moved[p, side] >= MAX_WIDENINGS
        )
        if not widenings:
            return
        self.space = wider
        probe = dict(best["search"])
        for w in widenings:
            old = w["old"]
            probe[w["param"]] = old / math.sqrt(10) if w["side"] == "low" else old * math.sqrt(10)
            self.widenings.append({**w, "trial": len(self.rows), "probe": probe[w["param"]]})
        self.queue.append(probe)

    def ask(self, count: int) -> list[tuple[optuna.trial.Trial, dict, str]]:
        """Up to ``count`` new settings of the current phase: (Optuna trial, values, phase),
        queued settings first. The study is rebuilt from the rows, seeded by their number, so
        what is asked depends on the rows alone: a resumed tuning asks what an uninterrupted one
        would.
        """
        study = self._study()
        phase = self.phase
        left = (self.gain_trials - len(self.rows)) if phase == "gains" else self.remaining
        out = []
        pending = list(self.queue)
        for _ in range(min(count, left)):
            if pending:
                study.enqueue_trial(pending.pop(0))
            trial = study.ask(self._distributions(phase))
            out.append((trial, dict(trial.params), phase))
        return out


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
    tasks (:func:`nnrobust.sweep.engine.ships_files`; default: on a ``scheduler`` of the user's).
    """
    from ..study_folder import held
    from ..sweep.engine import check_local_workers, ships_files

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
    from ..sweep.engine import _client, _require_engine, first_step, shared, shipped_files
    from ..sweep.spec import base_config, base_values, draw, experiment

    _require_engine()
    try:
        import optuna  # noqa: F401
    except ImportError as err:
        raise NNRobustError(f"tuning needs Optuna ({err}); pip install 'nnrobust[tune]'") from err
    folder = Path(folder)
    sweep = sweep_of(spec)
    base_config(sweep)  # the base file and [set], refused as the file's or as [set]'s
    base = base_values(sweep)
    from ..controllers.base import Controller
    from ..user_code import load_class

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
        controllers[name] = _Controller(spec, name, space)
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
        from ..sweep.engine import CRASHED, run_task_groups

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
    from ..display import TuneSummary

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
    from ..sweep.spec import draw

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
    from ..results import write_text_atomic

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
