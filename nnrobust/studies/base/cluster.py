"""The cluster every study command runs on: a local Dask cluster on 127.0.0.1 (or the user's
scheduler, probed before use), its workers checked for nnrobust's version, the files a run reads
shipped with the tasks where the workers do not share them, and the tasks collected as they finish
with a death of a worker charged to the task that ran on it (each suspect run again alone). Sweep,
tune, falsify, learning and the study share it (docs/robustness.md, "Clusters").
"""

from __future__ import annotations

import logging
import os
import signal
import threading
import time
from contextlib import contextmanager
from typing import Any

from ...core.exceptions import NNRobustError
from ...core.package_version import package_version
from ...core.signals import STOP_SIGNALS, check_interrupt, signals_held


def require_engine():
    """Refuse, in one line naming the extra to install, a study command without dask and pyarrow."""
    try:
        import distributed  # noqa: F401
        import pyarrow  # noqa: F401
    except ImportError as err:
        raise NNRobustError(
            f"sweeps need dask.distributed and pyarrow ({err}); pip install 'nnrobust[sweep]'"
        ) from err


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
    from ...core.forked import available_cpus

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
def cluster_client(workers: int | None, scheduler: str | None):
    """A client of an existing scheduler, or of a LocalCluster on 127.0.0.1 (its HTTP server on a
    free loopback port) with one single-threaded worker process per core; closed on the way out,
    whatever happens. It is this thread's current client: ``distributed.wait`` waits with it,
    not with another thread's (a study's stages side by side). A stop signal while the cluster
    closes is held until it has closed (:func:`~nnrobust.core.signals.signals_held`).
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


CRASHED = "crashed"
"""The status of a row (or simulation) whose worker process died running it twice."""


def _same(value):
    return value


class SharedInput:
    """A value many tasks read (a sweep, a base experiment, the shipped files), held on the
    cluster as a task of its own (:func:`_same`), not as scattered data: when the worker holding
    it dies, the scheduler computes it again, where scattered data would be lost and every task
    needing it cancelled. The client keeps the value: a task of its own can itself be killed
    (a worker that user code ends while the input is computed there again, twice:
    ``KilledWorker`` of the input, which every task reading it would then inherit), and
    :meth:`future` then submits it afresh, so that one input lost to crashing neighbours never
    fails the tasks that come after.
    """

    def __init__(self, client, value):
        self.client, self.value = client, value
        self._future = client.submit(_same, value, pure=False)

    def future(self):
        """The input's future on the cluster; submitted again when the last one was lost."""
        if self._future.status in ("error", "cancelled", "lost"):
            self._future = self.client.submit(_same, self.value, pure=False)
        return self._future


def shared(client, value) -> SharedInput:
    """``value`` as a :class:`SharedInput` for many tasks (sent to the cluster once)."""
    return SharedInput(client, value)


def shipped_files(client, inputs, ship: bool):
    """The files the rows are computed from (``inputs``: :func:`~..base.plan.study_inputs`), read once
    and checked against their SHA-256 (:func:`nnrobust.core.shipped_files.bundle_of`), as a
    :func:`shared` future for the tasks of a cluster that may not see them (``ship``); None for
    a cluster of this command's, whose workers read the client's files.
    """
    if not ship:
        return None
    from ...core.shipped_files import bundle_of

    return shared(client, bundle_of(inputs.files.values()))


def submit(client, files, function, *args):
    """The future of ``function(*args)`` on the cluster; with ``files`` (:func:`shipped_files`),
    run within them on the worker (:func:`nnrobust.core.shipped_files.run_within`). A
    :class:`SharedInput` among the arguments is passed as its current future.
    """
    args = tuple(a.future() if isinstance(a, SharedInput) else a for a in args)
    if files is None:
        return client.submit(function, *args, pure=False)
    from ...core.shipped_files import run_within

    return client.submit(run_within, files.future(), function, *args, pure=False)


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
    process: ``os._exit``, a segfault), an input it reads was lost with crashing neighbours
    (:data:`LOST_INPUT`), or the cluster cancelled it. The result is fetched once: dask keeps it
    on the worker, and a second fetch after that worker died (a crashing neighbour) would run the
    task again and could count that death against it.
    """
    wait_alive([future])
    try:
        return future.result(), None
    except NNRobustError:  # raised on purpose around the task code: its files refused (shipped_files)
        raise
    except Exception as err:  # KilledWorker, CancelledError: the task code itself catches its errors
        name = type(err).__name__
        if name == "KilledWorker":
            if getattr(err, "task", future.key) != future.key:
                return None, LOST_INPUT
            return None, (
                "the worker process died twice running it (os._exit, a segfault or the OS killing it; "
                "nnrobust's own errors are rows, never a dead worker)"
            )
        return None, f"the cluster lost it ({name}: {str(err)[:200]})"


LOST_INPUT = "an input it reads was lost with the workers its neighbours ended"
"""The reason of a task that failed because a :class:`SharedInput` it reads was killed (twice
computed again on a worker that crashing user code ended): never held against the task."""

MAX_LOST_INPUTS = 3
"""Runs alone a task may lose to its inputs (each submitted afresh) before it counts as lost."""


def run_alone(client, files, *task) -> tuple[Any, str | None]:
    """:func:`outcome` of a task run alone: its reason is set only when it ended its worker on each
    of two such runs (under load a death a crashing neighbour caused a moment before, a worker
    dead and not yet noticed, can still be counted against a task once, not twice). A run lost to
    an input killed with its neighbours (:data:`LOST_INPUT`; the input is submitted afresh) is
    not counted, up to :data:`MAX_LOST_INPUTS` of them.
    """
    reason = None
    counted = lost = 0
    while counted < 2:
        result, reason = outcome(submit(client, files, *task))
        if reason is None:
            return result, None
        if reason == LOST_INPUT and lost < MAX_LOST_INPUTS:
            lost += 1
        else:
            counted += 1
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
