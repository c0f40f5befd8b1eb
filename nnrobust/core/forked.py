"""Jobs run by processes forked before their input exists.

Drawing a run folder's figures is pure Python and matplotlib, so threads do not help, and
importing matplotlib alone takes about half a second. :class:`ForkedJobs` therefore forks its
first worker at once: that process imports what the jobs need (``prepare``) while this one
computes their input. :meth:`ForkedJobs.run` then sends it a small message (a run folder's path);
the first worker loads the input from it, forks the other workers (which inherit its imports and
the input, with nothing copied or pickled), shares the jobs with them by weight, and reports
back, while this process does other work (``meanwhile``).

Every forked worker ignores Ctrl-C and SIGHUP (this process decides), dies with its parent
(``PR_SET_PDEATHSIG``), sends back its warnings and its first error, and leaves by
``os._exit``. On SIGTERM the first worker kills and reaps the others before it leaves, so that
stopping it leaves no process behind. Where ``fork`` is missing, one worker is asked for, or
another Python thread runs (forking it could copy a held lock), everything runs here, in order.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import sys
import threading
import time
import traceback
import warnings
from collections.abc import Callable, Sequence
from typing import Any

from .signals import STOP_SIGNALS

MAX_WORKERS = 4

STOP_TIMEOUT = 5.0
"""Seconds a first worker has to stop its siblings on SIGTERM before it is killed."""


def available_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


WORKERS_VARIABLE = "NNROBUST_DRAW_WORKERS"
"""Environment variable: how many processes draw a run folder's figures."""


def default_workers() -> int:
    """Processes to draw with: $NNROBUST_DRAW_WORKERS, else the CPUs this process may use, at
    most :data:`MAX_WORKERS`.
    """
    value = os.environ.get(WORKERS_VARIABLE)
    if value is None or not value.strip():
        return max(1, min(MAX_WORKERS, available_cpus()))
    if not value.strip().isdigit() or int(value) < 1:
        from .exceptions import NNRobustError

        raise NNRobustError(f"{WORKERS_VARIABLE}={value!r}: expected a whole number of processes, 1 or more")
    return int(value)


def can_fork() -> bool:
    """Whether forking is safe here: ``fork`` exists and no other Python thread runs (a fork copies
    only this thread, so a lock another one holds, a dask client's event loop or a logging
    handler, would stay locked in the child forever).
    """
    return hasattr(os, "fork") and threading.active_count() == 1


def share(weights: Sequence[float], workers: int) -> list[list[int]]:
    """Job indices per worker, heaviest job first onto the least loaded worker."""
    loads, groups = [0.0] * workers, [[] for _ in range(workers)]  # type: list[float], list[list[int]]
    for i in sorted(range(len(weights)), key=lambda i: -weights[i]):
        w = loads.index(min(loads))
        groups[w].append(i)
        loads[w] += weights[i]
    return [sorted(g) for g in groups if g]


class ForkedJobs:
    """``jobs`` (each called with one input) run by ``workers`` processes (default
    :func:`default_workers`), the first of them forked now to call ``prepare``.

    ``load`` turns the message given to :meth:`run` into the jobs' input, in the first worker
    (default: the message itself). Use as a context manager: leaving it without :meth:`run`
    (an error, Ctrl-C, nothing to draw) stops the first worker.
    """

    def __init__(
        self,
        jobs: Sequence[Callable[[Any], None]],
        weights: Sequence[float] | None = None,
        workers: int | None = None,
        prepare: Callable[[], None] | None = None,
        load: Callable[[Any], Any] | None = None,
    ):
        self._jobs = list(jobs)
        self._weights = [1.0] * len(self._jobs) if weights is None else list(weights)
        workers = default_workers() if workers is None else workers
        self._workers = max(1, min(workers, len(self._jobs)))
        self._prepare = prepare or (lambda: None)
        self._load = load or (lambda message: message)
        # (pid, the write end of its message pipe, the read end of its report pipe)
        self._first: tuple[int, int | None, int] | None = None
        self.killed = False
        """Whether :meth:`close` had to kill the first worker (it outlived STOP_TIMEOUT after SIGTERM)."""
        if self._workers > 1 and can_fork():
            self._fork_first()

    @property
    def forked(self) -> bool:
        """Whether the jobs run in forked processes (else :meth:`run` runs them here)."""
        return self._first is not None

    def _fork_first(self) -> None:
        message_read, message_write = os.pipe()
        report_read, report_write = os.pipe()

        def first_worker():  # pragma: no cover - forked; measured through its effects
            os.close(message_write)
            os.close(report_read)
            _worker(lambda: _first_worker(self, message_read, report_write), report_write, parent)

        parent = os.getpid()
        with _stop_signals_blocked():  # until the worker is on record here, and has its own handlers
            pid = _fork(first_worker)
            os.close(message_read)
            os.close(report_write)
            self._first = (pid, message_write, report_read)

    def run(self, message: Any, meanwhile: Callable[[], None] | None = None) -> None:
        """Run the jobs on ``load(message)`` (a small, picklable message), and ``meanwhile`` here.

        Warnings of the workers are raised again here; their first error is raised here once all
        have ended (an ``OSError`` as an ``OSError``, Ctrl-C as ``KeyboardInterrupt``, anything
        else as a ``RuntimeError`` holding the worker's traceback). Ctrl-C or SIGTERM here stops
        the workers (none is left behind) before the interrupt goes on.
        """
        if self._first is None:
            self._prepare()
            data = self._load(message)
            for job in self._jobs:
                job(data)
            if meanwhile is not None:
                meanwhile()
            return
        pid, message_write, report_read = self._first
        try:
            if message_write is not None:  # None: the message went before an interrupted run ended
                try:
                    _write_all(message_write, pickle.dumps(message))
                except BrokenPipeError:  # the worker has ended: its report says why
                    pass
                os.close(message_write)
            self._first = (pid, None, report_read)
            if meanwhile is not None:
                meanwhile()
            report = _collect(pid, report_read)
            self._first = None
        except BaseException:
            self.close()
            raise
        for warned in report["warnings"]:
            warnings.warn(warned[0], warned[1], stacklevel=2)
        _raise(report)

    def close(self) -> None:
        """Stop the workers if they still run (their jobs are not wanted); idempotent."""
        if self._first is None:
            return
        pid, message_write, report_read = self._first
        self._first = None
        for fd in (message_write, report_read):
            if fd is not None:
                _close(fd)
        self.killed = _stop(pid)

    def __enter__(self) -> ForkedJobs:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _first_worker(jobs: ForkedJobs, message_read: int, report_write: int) -> list[dict]:  # pragma: no cover
    """The first worker's work: prepare, wait for the message, fork the others, run its share and
    return the others' reports (``report_write``: its own report pipe, which the others close).
    """
    siblings: list[tuple[int, int]] = []  # (pid, read end of its report pipe)

    def stop(signum, frame):
        for pid, read in siblings:
            _kill(pid, read)
        os._exit(128 + signum)

    signal.signal(signal.SIGTERM, stop)
    jobs._prepare()
    blob = _read_all(message_read)
    _close(message_read)
    if not blob:  # closed without a message: the jobs are not wanted
        os._exit(0)
    data = jobs._load(pickle.loads(blob))
    groups = share(jobs._weights, jobs._workers)
    if not can_fork():
        groups = [sorted(i for g in groups for i in g)]
    me = os.getpid()
    for group in groups[1:]:
        read, write = os.pipe()

        def sibling(group=group, read=read, write=write):
            os.close(read)
            os.close(report_write)
            _worker(lambda: _run_group(jobs, group, data), write, me)

        with _stop_signals_blocked():
            siblings.append((_fork(sibling), read))
            os.close(write)
    _run_group(jobs, groups[0], data)
    reports = []
    while siblings:
        reports.append(_collect(*siblings[0]))
        siblings.pop(0)
    return reports


def _run_group(jobs: ForkedJobs, group: list[int], data) -> list[dict]:  # pragma: no cover - forked
    for i in group:
        jobs._jobs[i](data)
    return []


@contextlib.contextmanager
def _stop_signals_blocked():
    """Hold Ctrl-C, SIGTERM and SIGHUP back in the block. Forked in it, a worker starts with them
    held back (and none pending), so that none can reach the Python handlers it inherits, which
    would raise in the caller's code, before :func:`_worker` has set its own.
    """
    old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _fork(child: Callable[[], None]) -> int:
    """Fork; the child runs ``child`` and leaves by ``os._exit``, never returning to the caller's
    code (which would go on as a copy of this process). Returns the child's pid.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # pragma: no cover - the child
        try:
            child()
        finally:
            os._exit(1)
    return pid


def _worker(work: Callable[[], list[dict]], write: int, parent: int) -> None:  # pragma: no cover
    """Run ``work`` in a forked worker, report through ``write`` (its own warnings and error, merged
    with the reports ``work`` returns) and leave.
    """
    code = 0
    report: dict[str, Any] = {"warnings": [], "error": None}
    others: list[dict] = []
    try:
        _die_with_parent(parent)
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGHUP, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_SETMASK, ())
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                others = work()
            finally:
                report["warnings"] = [(str(w.message), _category(w.category)) for w in caught]
    except BaseException as err:  # everything goes back to the parent
        code = 1
        report["error"] = _error_record(err)
    for other in others:
        report["warnings"] += other["warnings"]
        if report["error"] is None:
            report["error"] = other["error"]
    try:
        with os.fdopen(write, "wb") as pipe:
            pickle.dump(report, pipe)
    finally:
        os._exit(code)


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


def _read_all(fd: int) -> bytes:
    chunks = []
    while chunk := os.read(fd, 1 << 16):
        chunks.append(chunk)
    return b"".join(chunks)


def _close(fd: int) -> None:
    try:
        os.close(fd)
    except OSError:  # closed by an interrupted read
        pass


def _category(category):
    return category if category.__module__ == "builtins" else UserWarning


def _error_record(err: BaseException) -> dict:
    if isinstance(err, OSError):
        return {
            "kind": "OSError",
            "errno": err.errno,
            "strerror": err.strerror or str(err),
            "filename": None if err.filename is None else str(err.filename),
        }
    if isinstance(err, KeyboardInterrupt):
        return {"kind": "KeyboardInterrupt"}
    return {"kind": "error", "text": "".join(traceback.format_exception(err)).strip()}


def _die_with_parent(parent: int) -> None:  # pragma: no cover - runs in a forked worker
    """Linux: the kernel kills this worker when its parent dies (even by SIGKILL)."""
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the parent died before prctl took effect
        os._exit(1)


def _collect(pid: int, read: int) -> dict:
    with os.fdopen(read, "rb") as pipe:
        data = pipe.read()
    _, status = os.waitpid(pid, 0)
    try:
        return pickle.loads(data)
    except (pickle.UnpicklingError, EOFError, ValueError):  # the worker died without reporting
        code = os.waitstatus_to_exitcode(status)
        what = f"killed by signal {-code}" if code < 0 else f"exit code {code}"
        return {"warnings": [], "error": {"kind": "error", "text": f"a drawing process ended ({what})"}}


def _kill(pid: int, read: int) -> None:
    try:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    except (ProcessLookupError, ChildProcessError):
        pass
    _close(read)


def _stop(pid: int) -> bool:
    """SIGTERM to a first worker (it kills and reaps its siblings), then SIGKILL if it lingers;
    reaped. Returns whether it had to be killed.
    """
    try:
        os.kill(pid, signal.SIGTERM)
        deadline = time.monotonic() + STOP_TIMEOUT
        while os.waitpid(pid, os.WNOHANG) == (0, 0):
            if time.monotonic() > deadline:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                return True
            time.sleep(0.005)
    except (ProcessLookupError, ChildProcessError):
        pass
    return False


def _raise(report: dict) -> None:
    error = report["error"]
    if error is None:
        return
    if error["kind"] == "OSError":
        raise OSError(error["errno"], error["strerror"], error["filename"])
    if error["kind"] == "KeyboardInterrupt":
        raise KeyboardInterrupt
    raise RuntimeError(error["text"])
