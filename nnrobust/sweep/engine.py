"""Running a sweep on dask.distributed: chunks of (sample, controller) rows on workers, metrics
back to the client, one Parquet part per finished chunk, written atomically.

Resuming is reading the parts: a row whose (sample, controller) is in a part is never run again.
A worker killed mid-chunk costs that chunk only: dask runs it again on another worker, and the
client writes a chunk's rows once, when its result arrives. A chunk that kills two workers
(user code calling ``os._exit``, a segfault) is split into its rows, each then run alone on the
cluster, and a row that still kills its worker is a row with status ``crashed``: never a hole.
On a cluster of the user's (``--scheduler``), the files the rows read travel with the tasks
(:func:`shipped_files`, :mod:`nnrobust.shipped_files`): its workers need none of the client's.
"""

from __future__ import annotations

import logging
import math
import os
import signal
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ..config import ExperimentConfig
from ..exceptions import ConfigError, NNRobustError
from ..package_version import package_version
from ..signals import STOP_SIGNALS, check_interrupt, signals_as_interrupt, signals_held
from ..verdicts import FLAGS
from .spec import SweepSpec, base_config, base_values, draw, experiment, study_inputs

RESULTS = "results"
MARKER = "sweep.toml"
CHUNK_SECONDS = 2.0
"""Target compute per task: dask's scheduling costs a few ms per task, under 5 % of this."""
TASKS_PER_WORKER = 8
"""The fewest tasks per worker a sweep is cut into when it has the rows (chunk_size)."""


def _require_engine():
    try:
        import distributed  # noqa: F401
        import pyarrow  # noqa: F401
    except ImportError as err:
        raise NNRobustError(
            f"sweeps need dask.distributed and pyarrow ({err}); pip install 'nnrobust[sweep]'"
        ) from err


# ---- on the workers ------------------------------------------------------------------------------

SKIP_METRICS = ("rms_torque_per_joint", "singular_episodes", "message", "joint_limit_joint")


def _row_head(sample, controller: str) -> dict:
    """What names a row: its sample, controller, varied values and seed."""
    return {"sample": sample.id, "controller": controller, **sample.values, "seed": sample.seed}


def run_rows(spec: SweepSpec, base: dict, jobs: list[tuple[int, str]]) -> list[dict]:
    """Run (sample id, controller) jobs; one metrics row each.

    The worker rebuilds each experiment from the sweep and the base experiment's own values
    (:func:`~.spec.base_values`, so a remote worker needs no experiment file of the client's; the
    files the runs read come with the task on a cluster of the user's: :func:`shipped_files`). A
    run that cannot be built (the sample's trajectory leaves the workspace, say) is a row with
    status ``refused`` and its message; a diverged run is a row with status ``diverged``; an
    unexpected exception (a defect) a row with status ``error``, its type and message, so that
    one sample never aborts a sweep.
    """
    from ..exceptions import NNRobustError as LibraryError
    from ..experiment import run_experiment

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
    sweep's inputs) and no row twice (:func:`nnrobust.study_folder.read_parts`).
    """
    from ..study_folder import read_parts

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

    from ..results import METRIC_UNITS

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
    from ..config import dump_toml

    return dump_toml({"v": value}).split(" = ", 1)[1].strip()


def _write_part(folder: Path, rows: list[dict], table_schema, key: str) -> Path:
    """One Parquet part, tied to the sweep's inputs (``key``) and written whole
    (:func:`nnrobust.study_folder.write_part`).
    """
    import pyarrow as pa

    from ..study_folder import write_part

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
    (:func:`~.spec.study_inputs`); refuse one of other inputs, naming what changed, unless
    ``overwrite``, which replaces only what a sweep wrote (:mod:`nnrobust.study_folder`).
    DIR/sweep.toml is the resolved sweep with its inputs' digests, for the reader.
    """
    from ..study_folder import prepare

    prepare(folder, "sweep", spec.to_toml(), OUTPUTS, overwrite, "sweep", RESULTS, MARKER, inputs)


LOOPBACK_HTTP = "127.0.0.1:0"
"""Where a local cluster's scheduler serves HTTP: dask starts that server even when asked for no
dashboard (dask/distributed#7207, #8136), on port 8787 of the cluster's host; here on a free
loopback port, so that it neither takes 8787 nor listens beyond this machine."""


WORKERS_PER_CPU = 4
"""Most local worker processes per CPU this process may use: each is single-threaded, so more
only add memory and task switching."""

WORKER_MEMORY = 0.5e9
"""[bytes] What a local worker process may take (Pinocchio, numpy and a run's arrays: about
0.14 GB idle, more while it holds a long run): --workers is bounded by the memory available
divided by this."""


def max_local_workers() -> tuple[int, str]:
    """(the most local worker processes this machine takes for --workers, why): WORKERS_PER_CPU per
    CPU this process may use, and no more than the available memory holds at WORKER_MEMORY each.
    """
    from ..forked import available_cpus

    cpus = available_cpus()
    by_cpu = WORKERS_PER_CPU * cpus
    memory = _available_memory()
    if memory is None:
        return by_cpu, f"{cpus} CPUs, at most {WORKERS_PER_CPU} workers each"
    by_memory = max(1, int(memory // WORKER_MEMORY))
    if by_memory < by_cpu:
        return by_memory, f"{memory / 1e9:.1f} GB of memory available, {WORKER_MEMORY / 1e9:g} GB per worker"
    return by_cpu, f"{cpus} CPUs, at most {WORKERS_PER_CPU} workers each"


def _available_memory() -> float | None:
    """MemAvailable of /proc/meminfo [bytes], or None where there is none (not Linux)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        return None
    return None


PROBE_SECONDS = 5.0
"""How long a scheduler has to accept the connection and send its handshake."""

MAX_HANDSHAKE = 1 << 20
"""Most bytes a scheduler's first message may announce: a dask handshake is a few hundred; a
server of another protocol announces anything (its first 8 bytes read as a length)."""


def check_scheduler(address: str) -> str:
    """``tcp://HOST:PORT`` of a reachable dask scheduler, checked before dask connects: the address
    parsed, the port open within :data:`PROBE_SECONDS`, and the peer's first message framed as a
    dask handshake of at most :data:`MAX_HANDSHAKE` bytes. A web server, a silent or refusing port,
    or another protocol is one clear error, never a hang or a huge allocation.
    """
    import socket
    import struct
    from urllib.parse import urlsplit

    text = address if "://" in address else f"tcp://{address}"
    parts = urlsplit(text)
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme != "tcp" or not parts.hostname or port is None or not 0 < port < 65536 or parts.path:
        hint = "" if parts.scheme in ("tcp", "") else f"; {parts.scheme}:// is not supported"
        if parts.scheme == "tls":
            hint += " (a TLS cluster needs dask's security settings: connect from Python, distributed.Client)"
        raise NNRobustError(
            f"--scheduler {address!r}: not a dask scheduler's address; give tcp://HOST:PORT, "
            f"e.g. tcp://127.0.0.1:8786{hint}"
        )
    where = f"--scheduler {address}"
    try:
        with socket.create_connection((parts.hostname, port), timeout=PROBE_SECONDS) as sock:
            sock.settimeout(PROBE_SECONDS)
            head = b""
            while len(head) < 8:
                chunk = sock.recv(8 - len(head))
                if not chunk:
                    raise NNRobustError(
                        f"{where}: the peer closed the connection without a dask handshake; "
                        "is it a dask scheduler?"
                    )
                head += chunk
    except TimeoutError as err:
        raise NNRobustError(
            f"{where}: no dask handshake within {PROBE_SECONDS:g} s (a silent port, or a "
            "server of another protocol such as a web server); give a dask scheduler's "
            "address"
        ) from err
    except OSError as err:
        raise NNRobustError(
            f"{where}: cannot connect ({err.strerror or err}); is a dask scheduler running there?"
        ) from err
    (announced,) = struct.unpack("<Q", head)
    if not 0 < announced <= MAX_HANDSHAKE:
        raise NNRobustError(
            f"{where}: the peer does not speak dask's protocol (its first message announces "
            f"{announced} bytes); give a dask scheduler's address"
        )
    return f"tcp://{parts.hostname}:{port}"


QUIET_CLUSTER = {
    # Dask's nanny sets MALLOC_TRIM_THRESHOLD_ in its workers' environment so that they give freed
    # memory back to the OS; setting it also turns off glibc's dynamic mmap threshold, so that
    # every trace array of a run is mapped and page-faulted anew (about 6 % of a 20 s
    # paper-ellipse row). A run's memory is bounded and the next run reuses it. A value set in the
    # user's environment is still passed on.
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
    # The timers of an idle 2-worker cluster take 9-10 % of a core, which a sweep on as many workers
    # as cores takes from its runs: the event-loop health tick (every 20 ms in each process), the
    # statistical profiler (a stack sample every 10 ms per worker), the system monitor (500 ms)
    # and the memory monitor (100 ms). Slower, they take 1-1.5 %.
    "distributed.admin.tick.interval": "1s",
    "distributed.worker.profile.enabled": False,
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "500ms",
    # A task on 2 workers that died is failed (KilledWorker) rather than tried on 4: one kill -9
    # is survived, and user code that ends its process costs 2 worker restarts, not 4.
    "distributed.scheduler.allowed-failures": 1,
}
"""Dask settings of the local cluster that `nnrobust sweep`, tune and falsify start; set them in
the dask configuration of a cluster of your own (benchmarks/sweep_throughput.py measures them)."""


QUIET_WORKER = "import signal\nsignal.signal(signal.SIGINT, signal.SIG_IGN)\n"
"""The script each local worker process preloads: it ignores SIGINT. Text, not a module of
nnrobust: importing the package before the worker registers made each restart slower, enough
for dask to give up on a worker that user code keeps ending (its lost-worker-timeout)."""


def local_cluster(workers: int, **options):
    """A dask LocalCluster of ``workers`` single-threaded worker processes on 127.0.0.1 (its HTTP
    server on a free loopback port), with :data:`QUIET_CLUSTER`'s settings.

    A Ctrl-C or a hang-up sent to the terminal's process group is the client's alone (it stops
    and closes the cluster); received by the workers, each printed a traceback (and the resource
    tracker, killed by SIGHUP, a dozen more). The processes started here, and dask's threads that
    later restart workers, inherit both signals blocked and never receive them (multiprocessing's
    resource tracker unblocks SIGINT in the thread that starts it, so it is started first); each
    worker also preloads :data:`QUIET_WORKER`, which ignores SIGINT. A stop signal that arrives
    while the cluster starts is held (raised inside, it left a half-started cluster and a
    traceback at exit) and raised once the cluster is up.
    """
    from multiprocessing import resource_tracker

    import dask
    from distributed import LocalCluster

    main = threading.current_thread() is threading.main_thread()
    arrived: list[int] = []
    previous = (
        {sig: signal.signal(sig, lambda signum, frame: arrived.append(signum)) for sig in STOP_SIGNALS}
        if main
        else {}
    )
    group = {signal.SIGINT, signal.SIGHUP}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, group)

    def restore():
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        for sig in dict.fromkeys(arrived):
            signal.raise_signal(sig)

    try:
        resource_tracker.ensure_running()
        signal.pthread_sigmask(signal.SIG_BLOCK, group)
        with dask.config.set(QUIET_CLUSTER):
            cluster = LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                dashboard_address=LOOPBACK_HTTP,
                preload=[QUIET_WORKER],
                **options,
            )
    except BaseException:
        restore()
        raise
    try:
        restore()
        check_interrupt()
        return cluster
    except BaseException:
        cluster.close()
        raise


def check_local_workers(workers: int | None, scheduler: str | None = None) -> None:
    """``--workers`` refused in one line when it is not 1 to what this machine's cores and
    memory allow, for a local cluster (a ``scheduler`` of the user's has its own workers).
    Sweep, tune, falsify and study call it before they write anything into their folder.
    """
    if workers is None or scheduler:
        return
    if not (isinstance(workers, int) and workers >= 1):
        raise NNRobustError(f"--workers {workers}: give at least 1 local worker process")
    most, why = max_local_workers()
    if workers > most:
        raise NNRobustError(
            f"--workers {workers}: give 1 to {most} local worker processes on this machine ({why}); "
            "for more, start a cluster and pass --scheduler"
        )


def checked_local_cluster(workers: int | None):
    """The :func:`local_cluster` of ``--workers`` (None: one per core), checked by
    :func:`check_local_workers`.
    """
    check_local_workers(workers)
    return local_cluster(workers or os.cpu_count() or 1, silence_logs=logging.CRITICAL)


WORKER_PROBE = "__import__('nnrobust').__version__"
"""What each worker of a cluster of the user's evaluates first: nnrobust's version, which needs
the package (and what it imports) installed where the worker runs."""


def check_workers(client, address: str) -> None:
    """Every worker of the scheduler at ``address`` imports nnrobust, of this version: a worker
    without it died on the first task it was sent (the task's pickle names nnrobust's functions)
    and the command waited for a worker that never came; now one line names the worker and
    what it lacks. The probe is a builtin's call, which any Python worker can unpickle.
    """
    version = package_version()
    answers = client.run(eval, WORKER_PROBE, on_error="return")
    for worker, answer in sorted(answers.items()):
        if isinstance(answer, BaseException):
            hint = f"; install nnrobust {version} where the workers run"
            raise NNRobustError(
                f"--scheduler {address}: worker {worker} cannot import nnrobust: "
                f"{type(answer).__name__}: {str(answer)[:200]}{hint * isinstance(answer, ImportError)}"
            )
        if answer != version:
            raise NNRobustError(
                f"--scheduler {address}: worker {worker} has nnrobust {str(answer)[:40]}, this command "
                f"{version}; give the workers the same version (results depend on it)"
            )


@contextmanager
def _client(workers: int | None, scheduler: str | None):
    """A client of an existing scheduler, or of a LocalCluster on 127.0.0.1 (its HTTP server on a
    free loopback port) with one single-threaded worker process per core; closed on the way out,
    whatever happens. It is this thread's current client: ``distributed.wait`` waits with it,
    not with another thread's (a study's stages side by side). A stop signal while the cluster
    closes is held until it has closed (:func:`~nnrobust.signals.signals_held`).
    """
    from distributed import Client

    if scheduler:
        client = Client(check_scheduler(scheduler), timeout="20s")
        try:
            check_workers(client, scheduler)
            with client.as_current():
                yield client
        finally:
            client.close()
        return
    cluster = checked_local_cluster(workers)
    client = Client(cluster)
    try:
        with client.as_current():
            yield client
    finally:
        with signals_held():  # a close cut short leaves its cluster closing for 10 s at exit
            client.close()
            cluster.close()


CHECK_REPORT_ROWS = 1000
"""Rows checked between two calls of :func:`plan`'s ``checking`` (a row takes about a
millisecond: 10^6 rows are minutes of checking, which the command line shows)."""


def plan(spec: SweepSpec, checking=None) -> tuple[dict, list[tuple[int, str]]]:
    """The base experiment's own values (:func:`~.spec.base_values`) and every (sample,
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


def first_step(config: ExperimentConfig):
    """The experiment built (:func:`nnrobust.experiment.build`) and its controller's first control
    step run at q(0), v(0), its output checked as the loop checks it (a torque per joint, declared
    signals, a state of z's size); returns the Setup. What fails is the builder's or the loop's
    one-line error, as a run would raise it (a user's exception located in their file).
    """
    import numpy as np

    from ..controllers.custom import checked_output, failed
    from ..experiment import build

    setup = build(config)
    controller = setup.controller
    if getattr(type(controller), "native", None):  # a law in C++: its first step on the compiled loop
        from ..compiled import simulate_compiled

        try:
            simulate_compiled(setup, setup.config.simulation.control_period)
        except NNRobustError:
            raise
        except Exception as err:
            raise failed(controller, err, 0.0) from err
        return setup
    try:
        z = np.asarray(controller.initial_state(), dtype=float)
        out = controller.compute(
            0.0, setup.q0.copy(), setup.v0.copy(), z, setup.config.simulation.control_period
        )
    except NNRobustError:
        raise
    except Exception as err:
        raise failed(controller, err, 0.0) from err
    checked_output(controller, out, setup.robot.nq, z.size, 0.0)
    return setup


REFERENCE = "no-u0"
"""The shipped law a controller that cannot run is compared with: if it runs on the same
experiment, the controller is at fault (:func:`check_controllers`)."""


def check_controllers(spec: SweepSpec, base: dict, values: dict | None = None) -> None:
    """Refuse, before any sample runs, a controller that can never run: each is built on the base
    experiment (with ``values``, falsify's centre of the box) and its first control step run
    (:func:`first_step`). A missing class file, a constructor that raises or a torque of the wrong
    shape is one line naming the controller, with the builder's message. Where the shipped
    :data:`REFERENCE` law fails there too, the experiment is at fault, not the controller, and its
    rows say why (a base that only the samples make valid, say).
    """
    from .spec import Sample, sample_seed

    sample = Sample(-1, dict(values or {}), sample_seed(spec.seed, 0))
    for name in spec.controllers:
        try:
            first_step(experiment(spec, base, sample, name))
        except NNRobustError as err:
            try:
                first_step(experiment(spec, base, sample, REFERENCE))
            except NNRobustError:
                continue  # the experiment itself fails: every row will say so
            raise ConfigError(f"controllers: {name}", f"cannot run: {err}") from err


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


CRASHED = "crashed"
"""The status of a row (or simulation) whose worker process died running it twice."""


def _same(value):
    return value


def shared(client, value):
    """A future holding ``value`` for many tasks. It is a task of its own, not scattered data:
    when the worker holding it dies, the scheduler computes it again, where scattered data would
    be lost and every task needing it cancelled.
    """
    return client.submit(_same, value, pure=False)


def shipped_files(client, inputs, ship: bool):
    """The files the rows are computed from (``inputs``: :func:`~.spec.study_inputs`), read once
    and checked against their SHA-256 (:func:`nnrobust.shipped_files.bundle_of`), as a
    :func:`shared` future for the tasks of a cluster that may not see them (``ship``); None for
    a cluster of this command's, whose workers read the client's files.
    """
    if not ship:
        return None
    from ..shipped_files import bundle_of

    return shared(client, bundle_of(inputs.files.values()))


def submit(client, files, function, *args):
    """The future of ``function(*args)`` on the cluster; with ``files`` (:func:`shipped_files`),
    run within them on the worker (:func:`nnrobust.shipped_files.run_within`).
    """
    if files is None:
        return client.submit(function, *args, pure=False)
    from ..shipped_files import run_within

    return client.submit(run_within, files, function, *args, pure=False)


def ships_files(ship_files: bool | None, scheduler: str | None) -> bool:
    """Whether a command sends the files its rows read with its tasks: as ``ship_files`` says, by
    default when it runs on a cluster it did not start (``scheduler``), whose workers may not see
    the client's files (docs/robustness.md#a-cluster-without-shared-files).
    """
    return bool(scheduler) if ship_files is None else ship_files


POLL_SECONDS = 1.0
"""How often a wait for tasks checks for an interrupt and for a cluster left without workers."""
NO_WORKER_SECONDS = 120.0
"""How long a cluster may have no worker at all before the command stops waiting for it."""

REVIVE_SECONDS = 20.0
"""How long a local cluster may have no worker before its dead workers are replaced."""


def revive(cluster) -> None:
    """Give a local ``cluster`` with no live worker a new nanny and worker process per worker.

    When a worker's process ends (user code calling ``os._exit``, a segfault), its nanny starts
    another; when that takes longer than dask's ``lost-worker-timeout`` (15 s: a loaded 2-core
    machine, a worker that dies again while it starts), the cluster closes the nanny for good
    and the worker is never replaced. The cluster keeps the worker's spec: closing what is left of
    its nannies and scaling to that spec starts each again.
    """

    async def close_all():
        for name in list(cluster.workers):
            nanny = cluster.workers.pop(name)
            await nanny.close(timeout=10)

    cluster.sync(close_all)
    cluster.scale(len(cluster.worker_spec))


def as_they_finish(futures: list):
    """Each of ``futures`` as it finishes (or is cancelled), in the order they finish. Between two,
    an interrupt, or a stop asked of a study's stages run side by side on threads (which receive
    no signal), is noticed within :data:`POLL_SECONDS` even while every task runs on (a law that
    hangs): ``distributed.as_completed`` would wait for the next task to finish first.
    """
    remaining = dict.fromkeys(futures)  # an ordered set
    del futures
    while remaining:
        wait_alive(list(remaining), first=True)
        for future in [f for f in remaining if f.done()]:
            del remaining[future]
            yield future


def wait_alive(futures: list, first: bool = False) -> None:
    """``distributed.wait(futures)`` (with ``first``: until one of them is done), or one error
    instead of a hang when the cluster has had no worker for :data:`NO_WORKER_SECONDS` (every
    worker process dead and none restarted: user code that ends its process, under a load that
    makes the nanny give up restarting it). A local cluster of this command's with no worker for
    :data:`REVIVE_SECONDS` is given new workers (:func:`revive`) first.
    """
    from distributed import wait

    if not futures or (any if first else all)(f.done() for f in futures):
        return
    return_when = "FIRST_COMPLETED" if first else "ALL_COMPLETED"
    client = futures[0].client
    cluster = getattr(client, "cluster", None)
    since = None
    revived = False
    while True:
        check_interrupt()  # a stop asked of stages run side by side (signals.stop_stages)
        try:
            wait(futures, timeout=POLL_SECONDS, return_when=return_when)
            return
        except TimeoutError:
            pass
        alive = len(client.scheduler_info().get("workers", {}))
        now = time.monotonic()
        since = None if alive else since or now
        if since is None:
            revived = False
        elif cluster is not None and not revived and now - since > REVIVE_SECONDS:
            revive(cluster)
            revived = True
        elif now - since > NO_WORKER_SECONDS:
            raise NNRobustError(
                f"the cluster has had no worker for {NO_WORKER_SECONDS:g} s (every worker process died "
                "and none was restarted); what was computed is kept: run the command again to resume"
            )


def outcome(future) -> tuple[Any, str | None]:
    """``(result, None)`` when ``future`` finished and its result reached the client, else
    ``(None, reason)``: one line on why not, its worker died running it (user code that ends its
    process: ``os._exit``, a segfault) or the cluster cancelled it. The result is fetched once:
    dask keeps it on the worker, and a second fetch after that worker died (a crashing
    neighbour) would run the task again and could count that death against it.
    """
    wait_alive([future])
    try:
        return future.result(), None
    except NNRobustError:  # raised on purpose around the task code: its files refused (shipped_files)
        raise
    except Exception as err:  # KilledWorker, CancelledError: the task code itself catches its errors
        name = type(err).__name__
        if name == "KilledWorker":
            return None, (
                "the worker process died twice running it (os._exit, a segfault or the OS killing it; "
                "nnrobust's own errors are rows, never a dead worker)"
            )
        return None, f"the cluster lost it ({name}: {str(err)[:200]})"


def run_alone(client, files, *task) -> tuple[Any, str | None]:
    """:func:`outcome` of a task run alone: its reason is set only when it ended its worker on each
    of two such runs (under load a death a crashing neighbour caused a moment before, a worker
    dead and not yet noticed, can still be counted against a task once, not twice).
    """
    reason = None
    for _ in range(2):
        result, reason = outcome(submit(client, files, *task))
        if reason is None:
            return result, None
    return None, reason


def run_tasks(client, tasks: list[tuple], crashed, files=None) -> list:
    """Each (function, *arguments) task's result, run on the cluster (within ``files``:
    :func:`submit`) and waited for together. A task whose worker died (:func:`outcome`) is
    submitted again and waited for alone, once every other has finished (a task queued on a
    dying worker counts that death too: alone, its result does not depend on its neighbours);
    when it kills its worker on each run alone (:func:`run_alone`) its result is
    ``crashed(reason)``.
    """
    futures = [submit(client, files, *task) for task in tasks]
    wait_alive(futures)
    return _results(client, files, tasks, futures, crashed)


def _results(client, files, tasks: list[tuple], futures: list, crashed, in_flight=()) -> list:
    """The results of finished ``futures`` (of ``tasks``): a task whose worker died is run again
    alone (:func:`run_alone`), once ``in_flight``, the other tasks still running, have finished.
    """
    out = []
    for task, future in zip(tasks, futures):
        result, reason = outcome(future)
        if reason is not None:
            wait_alive(list(in_flight))
            result, reason = run_alone(client, files, *task)
        out.append(crashed(reason) if reason is not None else result)
    return out


def run_task_groups(client, groups: dict, crashed, then, files=None) -> None:
    """Run groups of (function, *arguments) tasks side by side: as soon as every task of a group
    has finished, ``then(key, results)`` gets its results (in its tasks' order) and returns that
    key's next group (empty or None: the key is done), which is submitted at once. Independent
    searches (one optimiser per controller) thus keep the cluster busy while one of them is told
    its results and asks again; each key's results are those :func:`run_tasks` gives its groups
    one after another. A task whose worker died is run again alone once every task in flight has
    finished, as :func:`run_tasks` does; ``crashed(reason)`` is its result when it ends its
    worker each time.
    """
    pending = {
        key: (tasks, [submit(client, files, *t) for t in tasks]) for key, tasks in groups.items() if tasks
    }
    while pending:
        # until one more task finishes (a group with a finished task may still be running: waiting
        # on every future would return at once and spin)
        wait_alive([f for _, futures in pending.values() for f in futures if not f.done()], first=True)
        for key in [k for k, (_, futures) in pending.items() if all(f.done() for f in futures)]:
            tasks, futures = pending.pop(key)
            others = [f for _, running in pending.values() for f in running]
            following = then(key, _results(client, files, tasks, futures, crashed, others))
            if following:
                pending[key] = (following, [submit(client, files, *t) for t in following])


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
    not run (sequential stopping, :func:`nnrobust.properties.refuted_groups`): their chunks are
    then cancelled, and a resumed sweep skips them.
    """
    _require_engine()
    check_local_workers(workers, scheduler)  # before the rows are planned and the folder made
    folder = Path(folder)
    base, jobs = plan(spec, checking)  # every experiment validated before anything is written or run
    check_controllers(spec, base)  # and every controller built, its first step run
    inputs = study_inputs(spec)  # what every row is computed from, by content
    from ..study_folder import held

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
    with signals_as_interrupt(), _client(workers, scheduler) as client:
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
    from ..native_law import is_source
    from ..user_code import class_file

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

    from ..study_folder import marker_name, read_parts, recorded_inputs

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
