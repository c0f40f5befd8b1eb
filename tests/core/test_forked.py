"""Jobs run by processes forked before their input exists (nnrobust/core/forked.py): the first worker
prepares while this process works, the others inherit what it prepared, the jobs are shared,
warnings and errors come back, and no process is left behind however the work ends."""

import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path

import pytest

from nnrobust.core.forked import ForkedJobs, share


def _alive(pid: int) -> bool:
    """Whether process pid runs (a zombie, dead but not yet reaped by its parent, does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state not in ("Z", "X")


def _wait_for(path: Path, seconds: float = 20.0) -> str:
    end = time.monotonic() + seconds
    while not path.exists():
        assert time.monotonic() < end, f"{path} never appeared"
        time.sleep(0.01)
    time.sleep(0.01)  # written whole
    return path.read_text()


def test_share_balances_by_weight_and_keeps_every_job_once():
    groups = share([4.5, 1, 1, 1, 1, 1, 1, 1], 2)
    assert sorted(i for g in groups for i in g) == list(range(8))
    loads = [sum([4.5, 1, 1, 1, 1, 1, 1, 1][i] for i in g) for g in groups]
    assert max(loads) - min(loads) <= 1.0
    assert share([1.0], 4) == [[0]]


def test_the_first_worker_prepares_before_the_input_exists_and_the_others_inherit_it(tmp_path):
    """prepare runs in a forked process while this one still works (its file appears before run
    is called); every job runs once, in two processes other than this one, both of which see
    what prepare set up; the jobs get load(message); meanwhile runs here."""

    def prepare():
        os.environ["PREPARED_IN"] = str(os.getpid())
        (tmp_path / "prepared").write_text(str(os.getpid()))

    def job(i):
        def run(data):
            (tmp_path / f"job{i}").write_text(f"{os.getpid()} {os.environ.get('PREPARED_IN')} {data}")

        return run

    with ForkedJobs(
        [job(i) for i in range(5)], workers=2, prepare=prepare, load=lambda message: message.upper()
    ) as jobs:
        assert jobs.forked
        first = _wait_for(tmp_path / "prepared")  # before the input is given
        assert first != str(os.getpid()) and "PREPARED_IN" not in os.environ
        jobs.run("input", meanwhile=lambda: (tmp_path / "meanwhile").write_text(str(os.getpid())))
    records = [(tmp_path / f"job{i}").read_text().split() for i in range(5)]
    assert {r[1] for r in records} == {first} and {r[2] for r in records} == {"INPUT"}
    pids = {r[0] for r in records}
    assert len(pids) == 2 and first in pids and str(os.getpid()) not in pids
    assert (tmp_path / "meanwhile").read_text() == str(os.getpid())


def test_warnings_and_errors_come_back_from_every_worker():
    def warn(data):
        warnings.warn(f"from {data}")

    def full(data):
        raise OSError(28, "No space left on device", "plots/x.png")

    def bug(data):
        raise ValueError("a bug")

    with pytest.warns(UserWarning, match="from the input") as caught:
        ForkedJobs([warn, warn], workers=2).run("the input")
    assert len(caught) == 2  # one from the first worker, one from the other
    with pytest.raises(OSError, match="No space left") as error:
        ForkedJobs([lambda data: None, full], weights=[2, 1], workers=2).run(None)
    assert error.value.errno == 28 and error.value.filename == "plots/x.png"
    with pytest.raises(RuntimeError, match="ValueError: a bug"):
        ForkedJobs([bug, lambda data: None], weights=[2, 1], workers=2).run(None)


def test_an_interrupted_parent_stops_every_worker(tmp_path):
    """Ctrl-C here while both workers still work: neither runs when the interrupt arrives (the
    first worker stops the one it forked before it leaves)."""

    def job(i):
        def run(data):
            (tmp_path / f"pid{i}").write_text(str(os.getpid()))
            time.sleep(60)

        return run

    def meanwhile():
        for i in range(2):
            _wait_for(tmp_path / f"pid{i}")
        raise KeyboardInterrupt

    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        with ForkedJobs([job(0), job(1)], workers=2) as jobs:
            jobs.run(None, meanwhile=meanwhile)
    assert time.monotonic() - started < 10
    pids = [int((tmp_path / f"pid{i}").read_text()) for i in range(2)]
    assert len(set(pids)) == 2 and not any(_alive(pid) for pid in pids)


def test_leaving_without_running_stops_the_first_worker_even_while_it_prepares(tmp_path):
    def prepare():
        (tmp_path / "pid").write_text(str(os.getpid()))
        time.sleep(60)

    started = time.monotonic()
    with ForkedJobs([lambda data: None, lambda data: None], workers=2, prepare=prepare):
        pid = int(_wait_for(tmp_path / "pid"))
    assert time.monotonic() - started < 10 and not _alive(pid)


def test_workers_ignore_ctrl_c_the_parent_decides(tmp_path):
    def job(i):
        def run(data):
            os.kill(os.getpid(), signal.SIGINT)  # as a terminal's Ctrl-C reaches the whole group
            (tmp_path / f"done{i}").write_text("yes")

        return run

    ForkedJobs([job(0), job(1)], workers=2).run(None, meanwhile=lambda: time.sleep(0.2))
    assert [(tmp_path / f"done{i}").read_text() for i in range(2)] == ["yes", "yes"]


def test_the_workers_die_with_a_killed_parent(tmp_path):
    """kill -9 of the process that forked them: the first worker and the one it forked end too."""
    script = textwrap.dedent(f"""
        import os, time
        from pathlib import Path
        from nnrobust.core.forked import ForkedJobs

        def job(i):
            def run(data):
                Path({str(tmp_path)!r}, f"pid{{i}}").write_text(str(os.getpid()))
                time.sleep(60)
            return run

        ForkedJobs([job(0), job(1)], workers=2).run(None)
    """)
    parent = subprocess.Popen([sys.executable, "-c", script])
    try:
        pids = [int(_wait_for(tmp_path / f"pid{i}", 60)) for i in range(2)]
    finally:
        parent.kill()
        parent.wait()
    end = time.monotonic() + 10
    while any(_alive(pid) for pid in pids) and time.monotonic() < end:
        time.sleep(0.05)
    assert not any(_alive(pid) for pid in pids)


def test_one_worker_runs_everything_here_in_order(tmp_path):
    order = []
    jobs = ForkedJobs(
        [lambda data: order.append(("job", data, os.getpid()))],
        workers=1,
        prepare=lambda: order.append(("prepare", os.getpid())),
        load=lambda m: m * 2,
    )
    assert not jobs.forked
    jobs.run(21, meanwhile=lambda: order.append(("meanwhile", os.getpid())))
    me = os.getpid()
    assert order == [("prepare", me), ("job", 42, me), ("meanwhile", me)]


def test_with_another_thread_running_the_work_stays_in_this_process(tmp_path):
    """A fork copies only the calling thread; with a second Python thread alive (a dask client's
    event loop) the jobs run here instead."""
    import threading

    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        work = [lambda data, i=i: (tmp_path / f"{i}").write_text(str(os.getpid())) for i in range(3)]
        jobs = ForkedJobs(work, workers=2)
        assert not jobs.forked
        jobs.run(None)
    finally:
        stop.set()
        other.join()
    assert {(tmp_path / f"{i}").read_text() for i in range(3)} == {str(os.getpid())}


TRIALS = 20
"""Forks stopped at once by the signal test (the interrupt it guards against, swallowed in a fork
hook, made every one of them linger)."""


def test_a_signal_at_the_fork_is_neither_lost_nor_sends_a_worker_back_into_the_callers_code(tmp_path):
    """With a Python SIGTERM handler that raises (as the command line installs), the workers are
    stopped right after the fork. The worker must not take the handler it inherits: raised in a
    fork hook, its KeyboardInterrupt was swallowed and the worker lived on until killed after
    STOP_TIMEOUT; raised a moment later, it went on as a copy of this process (it once ran the
    rest of a test session)."""
    from nnrobust.core.forked import STOP_TIMEOUT

    me, escaped = os.getpid(), tmp_path / "escaped"

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGTERM, interrupt)
    killed = []
    try:
        for _ in range(TRIALS):
            jobs = None
            try:
                with ForkedJobs([lambda data: None] * 2, workers=2, prepare=lambda: time.sleep(30)) as jobs:
                    pass  # left at once: the first worker is stopped right after its fork
            except KeyboardInterrupt:
                pass
            if os.getpid() != me:  # a worker that came back here: say so and leave
                escaped.write_text(str(os.getpid()))
                os._exit(0)
            killed.append(jobs is not None and jobs.killed)
    finally:
        signal.signal(signal.SIGTERM, old)
    assert not escaped.exists()
    # each worker ends on SIGTERM, not by the SIGKILL after STOP_TIMEOUT (the swallowed interrupt
    # made every one of them linger); not timed: one worker a machine starves of CPU for
    # STOP_TIMEOUT s is allowed (it happened once with both cores busy), a pattern is not
    assert sum(killed) <= 1, f"{sum(killed)} of {TRIALS} first workers outlived SIGTERM by {STOP_TIMEOUT} s"
