"""Running a sweep on dask.distributed: chunks of (sample, controller) rows on workers, metrics
back to the client, one Parquet part per finished chunk, written atomically.

Resuming is reading the parts: a row whose (sample, controller) is in a part is never run again.
A worker killed mid-chunk costs that chunk only: dask runs it again on another worker, and the
client writes a chunk's rows once, when its result arrives. A chunk that kills two workers
(user code calling ``os._exit``, a segfault) is split into its rows, each then run alone on the
cluster, and a row that still kills its worker is a row with status ``crashed``: never a hole.
On a cluster of the user's (``--scheduler``), the files the rows read travel with the tasks
(:func:`shipped_files`, :mod:`nnrobust.core.shipped_files`): its workers need none of the client's.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

from ...core.exceptions import NNRobustError
from ...core.signals import check_interrupt, signals_as_interrupt
from ...run.verdicts import FLAGS
from ..base.cluster import (
    CRASHED,
    as_they_finish,
    check_local_workers,
    cluster_client,
    outcome,
    require_engine,
    run_alone,
    shared,
    shipped_files,
    ships_files,
    submit,
)
from ..base.plan import SweepSpec, base_config, base_values, check_controllers, draw, experiment, study_inputs

RESULTS = "results"
MARKER = "sweep.toml"
CHUNK_SECONDS = 2.0
"""Target compute per task: dask's scheduling costs a few ms per task, under 5 % of this."""
TASKS_PER_WORKER = 8
"""The fewest tasks per worker a sweep is cut into when it has the rows (chunk_size)."""


# ---- on the workers ------------------------------------------------------------------------------

SKIP_METRICS = ("rms_torque_per_joint", "singular_episodes", "message", "joint_limit_joint")


def _row_head(sample, controller: str) -> dict:
    """What names a row: its sample, controller, varied values and seed."""
    return {"sample": sample.id, "controller": controller, **sample.values, "seed": sample.seed}


def run_rows(spec: SweepSpec, base: dict, jobs: list[tuple[int, str]]) -> list[dict]:
    """Run (sample id, controller) jobs; one metrics row each.

    The worker rebuilds each experiment from the sweep and the base experiment's own values
    (:func:`~..base.plan.base_values`, so a remote worker needs no experiment file of the client's; the
    files the runs read come with the task on a cluster of the user's: :func:`shipped_files`). A
    run that cannot be built (the sample's trajectory leaves the workspace, say) is a row with
    status ``refused`` and its message; a diverged run is a row with status ``diverged``; an
    unexpected exception (a defect) a row with status ``error``, its type and message, so that
    one sample never aborts a sweep.
    """
    from ...core.exceptions import NNRobustError as LibraryError
    from ...run.experiment import run_experiment

    rows = []
    for sample_id, controller in jobs:
        start = time.perf_counter()
        sample = draw(spec, sample_id)
        row = _row_head(sample, controller)
        try:
            metrics = run_experiment(experiment(spec, base, sample, controller)).metrics()
        except LibraryError as err:
            row.update(status="refused", message=str(err)[:500], warnings=[])
        except BaseException as err:  # a defect (or user code raising SystemExit, BaseException): a row
            row.update(status="error", message=f"{type(err).__name__}: {err}"[:500], warnings=[])
        else:
            row.update({k: v for k, v in metrics.items() if k not in SKIP_METRICS})
            row["message"] = metrics.get("message", "")
        row["task_seconds"] = time.perf_counter() - start
        rows.append(row)
    return rows


# ---- on the client -------------------------------------------------------------------------------


def _done_rows(folder: Path, key: str) -> set[tuple[int, str]]:
    """The (sample, controller) rows the folder holds, each part checked against ``key`` (the
    sweep's inputs) and no row twice (:func:`nnrobust.studies.base.folder.read_parts`).
    """
    from ..base.folder import read_parts

    done: set[tuple[int, str]] = set()
    for table in read_parts(folder / RESULTS, ["sample", "controller"], key, IDS):
        done.update(zip(table.column("sample").to_pylist(), table.column("controller").to_pylist()))
    return done


IDS = ("sample", "controller")
"""The columns that name a row."""
TEXTS = ("status", "backend", "message")


def schema(spec: SweepSpec):
    """The columns of every part, the same in each: sample, controller, the varied keys (dotted
    names), seed, status, warnings, every scalar metric of metrics.json, task_seconds.
    """
    import pyarrow as pa

    from ...run.results import METRIC_UNITS

    def varied_type(values):
        numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
        if all(isinstance(v, bool) for v in values):
            return pa.bool_()
        if numbers and all(isinstance(v, int) for v in values):
            return pa.int64()  # seeds: exact beyond 2^53, where a float64 column would round them
        if numbers:
            return pa.float64()
        if all(
            isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)
            for v in values
        ):
            return pa.list_(pa.float64())
        return pa.string()  # strings, or a mix of types: each value as its TOML text

    fields = [("sample", pa.int64()), ("controller", pa.string())]
    for key, value in spec.vary.items():
        values = (
            value if isinstance(value, list) else (list(value.values())[0] if "choice" in value else [0.0])
        )
        fields.append((key, varied_type(values)))
    fields += [("seed", pa.int64()), ("warnings", pa.list_(pa.string()))]
    fields += [(name, pa.string()) for name in TEXTS] + [(name, pa.bool_()) for name in FLAGS]
    fields += [(name, pa.float64()) for name in METRIC_UNITS if name != "singular_episodes"]
    fields.append(("task_seconds", pa.float64()))
    return pa.schema(fields)


def _toml_text(value) -> str:
    from ...config import dump_toml

    return dump_toml({"v": value}).split(" = ", 1)[1].strip()


def _write_part(folder: Path, rows: list[dict], table_schema, key: str) -> Path:
    """One Parquet part, tied to the sweep's inputs (``key``) and written whole
    (:func:`nnrobust.studies.base.folder.write_part`).
    """
    import pyarrow as pa

    from ..base.folder import write_part

    columns = {name: [row.get(name) for row in rows] for name in table_schema.names}
    for field in table_schema:  # a varied value of another type than its column's: its TOML text
        if field.type == pa.string():
            columns[field.name] = [
                v if v is None or isinstance(v, str) else _toml_text(v) for v in columns[field.name]
            ]
    return write_part(folder / RESULTS, pa.Table.from_pydict(columns, schema=table_schema), key)


OUTPUTS = (RESULTS, MARKER, "summary.json", "plots", "worst")
"""What a sweep writes in its folder: all --overwrite ever removes."""


def prepare_folder(spec: SweepSpec, folder: Path, overwrite: bool, inputs) -> None:
    """Create DIR or accept it for resuming the same sweep on the same ``inputs``
    (:func:`~..base.plan.study_inputs`); refuse one of other inputs, naming what changed, unless
    ``overwrite``, which replaces only what a sweep wrote (:mod:`nnrobust.studies.base.folder`).
    DIR/sweep.toml is the resolved sweep with its inputs' digests, for the reader.
    """
    from ..base.folder import prepare

    prepare(folder, "sweep", spec.to_toml(), OUTPUTS, overwrite, "sweep", RESULTS, MARKER, inputs)


CHECK_REPORT_ROWS = 1000
"""Rows checked between two calls of :func:`plan`'s ``checking`` (a row takes about a
millisecond: 10^6 rows are minutes of checking, which the command line shows)."""


def plan(spec: SweepSpec, checking=None) -> tuple[dict, list[tuple[int, str]]]:
    """The base experiment's own values (:func:`~..base.plan.base_values`) and every (sample,
    controller) job, each row's experiment validated first (once per distinct set of varied
    values: rows that differ only by their seeds are one check): a value the schema refuses is a
    one-line error naming the key and the sample, before anything runs. Jobs are (id, controller) pairs,
    so the client's memory does not grow with the experiments, which the workers rebuild.
    ``checking(done, total)``, if given, is called every :data:`CHECK_REPORT_ROWS` rows checked
    and once at the end.
    """
    base_config(spec)  # the base file and [set], refused as the file's or as [set]'s
    base = base_values(spec)
    for sample_id in _first_checked(spec):  # each distinct grid value's first sample, at once
        for controller in spec.controllers:
            experiment(spec, base, draw(spec, sample_id), controller)
    jobs: list[tuple[int, str]] = []
    total = spec.size * len(spec.controllers)
    # Rows of the same varied values differ only by their seeds (nominal.seed, sensing.seed: any
    # draw is valid), so a grid point's or a choice's values are checked once, not once a sample
    # (a grid point's samples need no draw at all without a random key).
    repeats = all("choice" in spec.vary[key] for key in spec.random_keys)
    checked: set[tuple[str, str]] = set()
    reported = 0
    for sample_id in range(spec.size):
        if spec.random_keys or sample_id % spec.samples == 0:
            sample = draw(spec, sample_id)
            values = repr(sorted(sample.values.items())) if repeats else ""
            for controller in spec.controllers:
                if not repeats or (controller, values) not in checked:
                    experiment(spec, base, sample, controller)  # validates; not kept
                    if repeats:
                        checked.add((controller, values))
        jobs.extend((sample_id, controller) for controller in spec.controllers)
        if checking is not None and len(jobs) - reported >= CHECK_REPORT_ROWS:
            reported = len(jobs)
            checking(reported, total)
    if checking is not None:
        checking(len(jobs), total)
    return base, jobs


def _first_checked(spec: SweepSpec) -> list[int]:
    """One sample per distinct value of each grid key (the others at their first value, the first
    draw): checked before the rest, so a bad value late in a long grid is refused at once.
    """
    ids: list[int] = []
    stride = spec.samples
    for key in reversed(spec.grid_keys):
        seen: list = []
        for position, value in enumerate(spec.vary[key]):
            if value not in seen:
                seen.append(value)
                ids.append(position * stride)
        stride *= len(spec.vary[key])
    return sorted(set(ids))


def chunk_size(jobs: int, workers: int, seconds_per_job: float) -> int:
    """Jobs per task: about CHUNK_SECONDS of compute, and at least TASKS_PER_WORKER tasks per
    worker when there is enough work (so a killed worker loses little, and the workers finish
    about together: the last task of a stage leaves the others idle).
    """
    by_time = max(1, int(CHUNK_SECONDS / max(seconds_per_job, 1e-3)))
    by_balance = max(1, math.ceil(jobs / (TASKS_PER_WORKER * max(workers, 1))))
    return max(1, min(by_time, by_balance))


def crashed_rows(spec: SweepSpec, jobs: list[tuple[int, str]], reason: str) -> list[dict]:
    """The rows of ``jobs``, each with status ``crashed`` and ``reason``, naming the user's class
    the row ran (a law in C++ that ends its process or crashes says so on the worker's stderr).
    """
    return [
        {
            **_row_head(draw(spec, sample_id), controller),
            "status": CRASHED,
            "message": reason + _ran(spec, controller),
            "warnings": [],
            "task_seconds": 0.0,
        }
        for sample_id, controller in jobs
    ]


def run_sweep(
    spec: SweepSpec,
    folder: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress=None,
    seconds_per_job: float = 0.5,
    stop=None,
    checking=None,
    ship_files: bool | None = None,
) -> dict:
    """Run (or resume) a sweep into ``folder``; returns {"computed": rows, "skipped": rows,
    "parts": n, "stopped": rows not run}.

    ``ship_files``: send the files the rows read with the tasks (:func:`ships_files`; default:
    on a ``scheduler`` of the user's).

    ``checking(done, total)`` is called as the rows' experiments are validated, before anything
    runs (:func:`plan`); ``progress(done, total)`` as chunks finish. ``stop(records)``, given every row
    written so far (dicts), returns the (controller, grid cell) groups whose remaining rows need
    not run (sequential stopping, :func:`nnrobust.run.properties.refuted_groups`): their chunks are
    then cancelled, and a resumed sweep skips them.
    """
    require_engine()
    check_local_workers(workers, scheduler)  # before the rows are planned and the folder made
    folder = Path(folder)
    base, jobs = plan(spec, checking)  # every experiment validated before anything is written or run
    check_controllers(spec, base)  # and every controller built, its first step run
    inputs = study_inputs(spec)  # what every row is computed from, by content
    from ...core.folders import held

    with held(folder):  # one sweep at a time into a folder: never a row twice
        return _run_sweep(
            spec,
            folder,
            base,
            jobs,
            workers,
            scheduler,
            overwrite,
            progress,
            seconds_per_job,
            stop,
            inputs,
            ships_files(ship_files, scheduler),
        )


def _run_sweep(
    spec: SweepSpec,
    folder: Path,
    base: dict,
    jobs: list,
    workers,
    scheduler,
    overwrite: bool,
    progress,
    seconds_per_job: float,
    stop=None,
    inputs=None,
    ship: bool = False,
) -> dict:
    inputs = inputs if inputs is not None else study_inputs(spec)
    prepare_folder(spec, folder, overwrite, inputs)
    done = _done_rows(folder, inputs.key)
    jobs = [job for job in jobs if job not in done]
    total = spec.size * len(spec.controllers)
    skipped = total - len(jobs)

    def group(job) -> tuple[str, int]:
        return job[1], job[0] // spec.samples

    records = read_results(folder, inputs.key).to_dict("records") if stop and done else []
    stopped = stop(records) if stop else set()
    dropped = [job for job in jobs if group(job) in stopped]
    jobs = [job for job in jobs if group(job) not in stopped]
    if not jobs:
        return {"computed": 0, "skipped": skipped, "parts": 0, "stopped": len(dropped)}
    written = parts = 0
    table_schema = schema(spec)
    with signals_as_interrupt(), cluster_client(workers, scheduler) as client:
        n_workers = max(len(client.scheduler_info().get("workers", {})), 1)
        size = chunk_size(len(jobs), n_workers, seconds_per_job)
        if stop:  # chunks of one group each, so that a stopped group's chunks can be cancelled
            groups: dict[tuple[str, int], list] = {}
            for job in jobs:
                groups.setdefault(group(job), []).append(job)
            by_group = [(g, js[i : i + size]) for g, js in groups.items() for i in range(0, len(js), size)]
            by_group.sort(key=lambda item: item[1][0][0])  # samples in order, across groups
            chunks = [chunk for _, chunk in by_group]
        else:
            chunks = [jobs[i : i + size] for i in range(0, len(jobs), size)]
        spec_future, base_future = shared(client, spec), shared(client, base)
        files = shipped_files(client, inputs, ship)
        futures = [submit(client, files, run_rows, spec_future, base_future, chunk) for chunk in chunks]
        chunk_of = {f.key: chunk for f, chunk in zip(futures, chunks)}
        if progress:
            progress(skipped, total)
        pending = as_they_finish(futures)
        unfinished = {f.key: f for f in futures}
        del futures  # pending holds them until they finish; each is released once written
        suspects: list[tuple[int, str]] = []  # rows of chunks whose workers died
        for future in pending:
            check_interrupt()
            unfinished.pop(future.key, None)
            chunk = chunk_of.pop(future.key)
            if future.cancelled() and stop and group(chunk[0]) in stopped:
                continue
            rows, reason = outcome(future)
            if reason is not None:  # one of its rows, or a neighbour on its worker, ended the worker
                suspects += chunk
                continue
            future.release()  # the worker may drop the chunk's rows
            written, parts = written + len(rows), parts + 1
            _write_part(folder, rows, table_schema, inputs.key)
            if stop:
                records += rows
                newly = stop(records) - stopped
                if newly:
                    stopped |= newly
                    cancel = [f for key, f in unfinished.items() if group(chunk_of[key][0]) in newly]
                    client.cancel(cancel)
                    dropped += [job for f in cancel for job in chunk_of[f.key]]
            if progress:
                progress(skipped + written + len(dropped), total)
        # Each suspect row alone on the cluster, twice before it is called crashed: a
        # worker's death then has one cause. (A task queued on a worker that dies counts that death
        # too, so a row beside a crashing one is innocent until it runs alone.) Deterministic: the
        # crashing rows are the same whatever the timing and the load.
        for job in suspects:
            if stop and group(job) in stopped:
                dropped.append(job)
                continue
            rows, reason = run_alone(client, files, run_rows, spec_future, base_future, [job])
            rows = crashed_rows(spec, [job], reason) if reason is not None else rows
            written, parts = written + len(rows), parts + 1
            _write_part(folder, rows, table_schema, inputs.key)
            if stop:
                records += rows
                stopped |= stop(records)
            if progress:
                progress(skipped + written + len(dropped), total)
    return {"computed": written, "skipped": skipped, "parts": parts, "stopped": len(dropped)}


def _ran(spec: SweepSpec, controller: str) -> str:
    """What a crashed row adds for a controller entry of a user's class ("; it ran the law X (FILE)")."""
    from ...plugins.native_law import is_source
    from ...plugins.user_code import class_file

    cls = spec.entries.get(controller, {}).get("class")
    where = class_file(cls) if isinstance(cls, str) else None
    if where is None:
        return ""
    language = " in C++" if is_source(where) else ""
    return f"; it ran the law {cls.rpartition(':')[2]}{language} ({where})"


def read_results(folder: str | Path, key: str | None = None):
    """The sweep's rows as a pandas DataFrame (every part), each part checked against ``key``
    (default: the inputs its folder's marker records) and no row twice; sorted by sample, then
    controller.
    """
    import pandas as pd

    from ..base.folder import marker_name, read_parts, recorded_inputs

    folder = Path(folder)
    if not folder.is_dir():
        said = "is not a folder" if folder.exists() else "does not exist"
        raise NNRobustError(f"{folder} {said}: read_results reads the folder a sweep wrote (its --out)")
    if not (folder / marker_name("sweep")).is_file() and not (folder / RESULTS).is_dir():
        raise NNRobustError(
            f"{folder} is not a sweep's folder (no {marker_name('sweep')}, no {RESULTS}/): read_results "
            "reads the folder a sweep wrote (its --out)"
        )
    if key is None:
        recorded = recorded_inputs(Path(folder), "sweep")
        key = recorded.key if recorded is not None else None
    tables = read_parts(Path(folder) / RESULTS, key=key, ids=IDS if key is not None else ())
    if not tables:
        return pd.DataFrame()
    frame = pd.concat([t.to_pandas() for t in tables], ignore_index=True)
    # in sample order whatever order the parts were written in (an interrupted and resumed sweep
    # writes other parts): a sum over the rows is then the same to the last bit
    return frame.sort_values(list(IDS), kind="stable", ignore_index=True)


def log(message: str) -> None:
    """One line to stderr."""
    print(message, file=sys.stderr, flush=True)
