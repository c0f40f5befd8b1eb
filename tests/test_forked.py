"""Forked drawing (nnrobust/forked.py): work split over processes, warnings and errors carried
back, and no process left behind when the parent is interrupted."""

import os
import signal
import time
import warnings

import pytest

from nnrobust.forked import run_jobs, share


def test_share_balances_by_weight_and_keeps_every_job_once():
    groups = share([4.5, 1, 1, 1, 1, 1, 1, 1], 2)
    assert sorted(i for g in groups for i in g) == list(range(8))
    loads = [sum([4.5, 1, 1, 1, 1, 1, 1, 1][i] for i in g) for g in groups]
    assert max(loads) - min(loads) <= 1.0
    assert share([1.0], 4) == [[0]]


def test_jobs_run_in_separate_processes_and_all_of_them_run(tmp_path):
    def job(i):
        return lambda: (tmp_path / f"{i}").write_text(str(os.getpid()))

    run_jobs([job(i) for i in range(5)], workers=2)
    pids = {(tmp_path / f"{i}").read_text() for i in range(5)}
    assert len(pids) == 2 and str(os.getpid()) in pids


def test_a_childs_warnings_and_errors_come_back():
    def warn():
        warnings.warn("from a child")

    def full():
        raise OSError(28, "No space left on device", "plots/x.png")

    with pytest.warns(UserWarning, match="from a child"):
        run_jobs([lambda: None, warn], weights=[2, 1], workers=2)
    with pytest.raises(OSError, match="No space left") as caught:
        run_jobs([lambda: None, full], weights=[2, 1], workers=2)
    assert caught.value.errno == 28 and caught.value.filename == "plots/x.png"

    def bug():
        raise ValueError("a bug")

    with pytest.raises(RuntimeError, match="ValueError: a bug"):
        run_jobs([lambda: None, bug], weights=[2, 1], workers=2)


def test_an_interrupted_parent_kills_and_reaps_its_children(tmp_path):
    """Ctrl-C in the parent while a child still draws: the child is gone when the interrupt
    arrives (no orphan, no zombie)."""
    def child():
        (tmp_path / "pid").write_text(str(os.getpid()))
        time.sleep(60)

    def parent():
        while not (tmp_path / "pid").exists():
            time.sleep(0.01)
        raise KeyboardInterrupt

    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        run_jobs([parent, child], weights=[2, 1], workers=2)
    assert time.monotonic() - started < 10
    pid = int((tmp_path / "pid").read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)


def test_children_ignore_ctrl_c_the_parent_decides(tmp_path):
    def child():
        os.kill(os.getpid(), signal.SIGINT)  # as a terminal's Ctrl-C reaches the whole group
        (tmp_path / "done").write_text("yes")

    run_jobs([lambda: time.sleep(0.2), child], weights=[2, 1], workers=2)
    assert (tmp_path / "done").read_text() == "yes"


def test_one_worker_runs_everything_here(tmp_path):
    run_jobs([lambda: (tmp_path / "a").write_text(str(os.getpid()))], workers=1)
    assert (tmp_path / "a").read_text() == str(os.getpid())


def test_with_another_thread_running_the_work_stays_in_this_process(tmp_path):
    """A fork copies only the calling thread; with a second Python thread alive (a dask client's
    event loop) the jobs run here instead."""
    import threading

    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        run_jobs([lambda i=i: (tmp_path / f"{i}").write_text(str(os.getpid())) for i in range(3)], workers=2)
    finally:
        stop.set()
        other.join()
    assert {(tmp_path / f"{i}").read_text() for i in range(3)} == {str(os.getpid())}
