"""Run independent pieces of work (figures, the animation) in forked processes at once.

Writing a run folder's figures and animation is pure Python and matplotlib, so threads do not
help; forked children do, sharing the finished result without copying or pickling it. Each
child ignores Ctrl-C and SIGHUP (the parent decides), dies with its parent, sends back its
warnings and its error, and leaves by ``os._exit``. Where ``fork`` is missing, one CPU is
available, or another Python thread runs (forking it could copy a held lock), the work runs
here, in order.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
import traceback
import warnings
from collections.abc import Callable, Sequence

MAX_WORKERS = 4


def available_cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


WORKERS_VARIABLE = "NNROBUST_DRAW_WORKERS"
"""Environment variable: how many processes draw a run folder's figures and animation."""


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


def share(weights: Sequence[float], workers: int) -> list[list[int]]:
    """Job indices per worker, heaviest job first onto the least loaded worker (worker 0 is
    this process).
    """
    loads, groups = [0.0] * workers, [[] for _ in range(workers)]
    for i in sorted(range(len(weights)), key=lambda i: -weights[i]):
        w = loads.index(min(loads))
        groups[w].append(i)
        loads[w] += weights[i]
    return [sorted(g) for g in groups if g]


def run_jobs(jobs: Sequence[Callable[[], None]], weights: Sequence[float] | None = None,
             workers: int | None = None) -> None:
    """Call every job, spread over ``workers`` processes (default :func:`default_workers`).

    Warnings a child raises are raised again here; the first error of a child is raised here
    once all have ended (an ``OSError`` as an ``OSError``, Ctrl-C as ``KeyboardInterrupt``,
    anything else as a ``RuntimeError`` holding the child's traceback). On Ctrl-C or SIGTERM
    here the children are killed and reaped before the interrupt goes on.
    """
    weights = [1.0] * len(jobs) if weights is None else list(weights)
    workers = min(default_workers() if workers is None else workers, len(jobs))
    # a fork copies only this thread: a lock another Python thread holds (a dask client's event
    # loop, a logging handler) would stay locked in the child forever, so then work here
    if workers <= 1 or not hasattr(os, "fork") or threading.active_count() > 1:
        for job in jobs:
            job()
        return
    groups = share(weights, workers)
    children: list[tuple[int, int]] = []  # (pid, read end of its pipe)
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        for group in groups[1:]:
            read, write = os.pipe()
            pid = os.fork()
            if pid == 0:  # pragma: no cover - the child; measured through its effects
                os.close(read)
                _child([jobs[i] for i in group], write)
            os.close(write)
            children.append((pid, read))
        for i in groups[0]:
            jobs[i]()
        reports = []
        while children:
            reports.append(_collect(*children[0]))
            children.pop(0)
    except BaseException:
        for pid, read in children:
            _kill(pid, read)
        raise
    for warned in (w for report in reports for w in report["warnings"]):
        warnings.warn(warned[0], warned[1], stacklevel=2)
    for report in reports:
        _raise(report)


def _child(jobs, write: int) -> None:  # pragma: no cover - runs in the forked child
    """Run ``jobs`` in the forked child, report through ``write`` and leave."""
    code = 0
    report = {"warnings": [], "error": None}
    try:
        _die_with_parent()
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGHUP, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        signal.pthread_sigmask(signal.SIG_SETMASK, ())
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                for job in jobs:
                    job()
            finally:
                report["warnings"] = [(str(w.message), _category(w.category)) for w in caught]
    except BaseException as err:  # everything goes back to the parent
        code = 1
        report["error"] = _error_record(err)
    try:
        with os.fdopen(write, "wb") as pipe:
            pickle.dump(report, pipe)
    finally:
        os._exit(code)


def _category(category):
    return category if category.__module__ == "builtins" else UserWarning


def _error_record(err: BaseException) -> dict:
    if isinstance(err, OSError):
        return {"kind": "OSError", "errno": err.errno, "strerror": err.strerror or str(err),
                "filename": None if err.filename is None else str(err.filename)}
    if isinstance(err, KeyboardInterrupt):
        return {"kind": "KeyboardInterrupt"}
    return {"kind": "error", "text": "".join(traceback.format_exception(err)).strip()}


def _die_with_parent() -> None:  # pragma: no cover - runs in the forked child
    """Linux: the kernel kills this child when the parent dies (even by SIGKILL)."""
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):
        return
    if os.getppid() == 1:  # the parent died before prctl took effect
        os._exit(1)


def _collect(pid: int, read: int) -> dict:
    with os.fdopen(read, "rb") as pipe:
        data = pipe.read()
    _, status = os.waitpid(pid, 0)
    try:
        return pickle.loads(data)
    except (pickle.UnpicklingError, EOFError, ValueError):  # the child died without reporting
        code = os.waitstatus_to_exitcode(status)
        what = f"killed by signal {-code}" if code < 0 else f"exit code {code}"
        return {"warnings": [], "error": {"kind": "error", "text": f"a drawing process ended ({what})"}}


def _kill(pid: int, read: int) -> None:
    try:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    except (ProcessLookupError, ChildProcessError):
        pass
    try:
        os.close(read)
    except OSError:  # closed by an interrupted read
        pass


def _raise(report: dict) -> None:
    error = report["error"]
    if error is None:
        return
    if error["kind"] == "OSError":
        raise OSError(error["errno"], error["strerror"], error["filename"])
    if error["kind"] == "KeyboardInterrupt":
        raise KeyboardInterrupt
    raise RuntimeError(error["text"])
