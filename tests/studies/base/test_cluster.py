"""User code that ends its dask worker (``os._exit``, a segfault) or raises what is not an
Exception: every row is still there with its status, the built-in law's rows included, and the
command says so with a non-zero exit; tune and falsify name the crash instead of a traceback.
A task queued on a dying worker counts that death too, so each suspect runs again alone: the
crashing rows are the same whatever the timing."""

import json
from pathlib import Path

import pytest

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from nnrobust.cli import main  # noqa: E402
from nnrobust.studies.sweep import read_results  # noqa: E402

LAWS = Path(__file__).parents[2] / "controllers" / "eq9_again.py"

SWEEP = """
name = "dead"
base = "paper-ellipse"
controllers = ["no-u0", {{name = "mine", class = "{laws}:{cls}"}}]
samples = 2
[set]
"simulation.duration" = 2.2
[vary]
"plant.disturbance_scale" = {{uniform = [0.5, 2.0]}}
"""


@pytest.mark.parametrize(
    "cls, status, message",
    [
        ("EndsItsProcess", "crashed", "the worker process died twice running it"),
        ("RaisesBaseException", "error", "BaseException: not an Exception"),
    ],
)
def test_a_law_that_ends_its_worker_is_a_row_never_a_hole(cls, status, message, tmp_path, capsys):
    path = tmp_path / "sweep.toml"
    path.write_text(SWEEP.format(laws=LAWS, cls=cls))
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--out", str(out), "--workers", "2", "--quiet"]) == 1

    frame = read_results(out)
    assert sorted(zip(frame["controller"], frame["sample"])) == sorted(
        (c, s) for c in ("mine", "no-u0") for s in range(2)
    )
    by = dict(zip(zip(frame["controller"], frame["sample"]), zip(frame["status"], frame["message"])))
    for s in range(2):
        assert by[("no-u0", s)][0] == "completed"  # its neighbours on the dying workers are innocent
        assert by[("mine", s)][0] == status and message in by[("mine", s)][1]
    err = capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["controllers"]["mine"]["statuses"] == {status: 2}
    # resuming computes nothing: the crashed rows are rows
    assert main(["sweep", str(path), "--out", str(out), "--workers", "2", "--quiet"]) == 1
    assert "2 rows ended without a result" in capsys.readouterr().err + err


def test_tune_and_falsify_name_a_crash_and_go_on(tmp_path, capsys, monkeypatch):
    from nnrobust.studies.base import cluster

    # both workers dead at once and their nannies given up: replaced after 5 s, not 20 (the suite's
    # time; test_a_local_cluster_whose_nannies_gave_up_gets_new_workers covers the revival itself)
    monkeypatch.setattr(cluster, "REVIVE_SECONDS", 5.0)
    box = tmp_path / "box.toml"
    box.write_text(SWEEP.format(laws=LAWS, cls="EndsItsProcess").replace('"no-u0", ', ""))
    law = f"{LAWS}:EndsItsProcess"
    # every setting of the space crashes before 2.2 s, or lasts: the crashed ones fail
    code = main(
        ["tune", str(box), "--controllers", law, "--budget", "6", "--validation", "0"]
        + ["--workers", "2", "--out", str(tmp_path / "tune"), "--quiet"]
    )
    assert code == 0
    rows = read_results_of_trials(tmp_path / "tune")
    crashed = [run for row in rows for run in row["runs"] if run["status"] == "crashed"]
    lasted = [row for row in rows if row["params"]["controller.params.after"] > 2.2]
    assert crashed and len(crashed) == len(rows) - len(lasted)
    assert (
        main(
            ["falsify", str(box), "--controllers", law, "--require", "rms_error_after_2s<=1"]
            + ["--budget", "4", "--workers", "2", "--out", str(tmp_path / "f")]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "EndsItsProcess: FALSIFIED" in out and "the run ended crashed: the worker process died" in out


def read_results_of_trials(folder):
    from nnrobust.studies.base.folder import recorded_inputs
    from nnrobust.studies.tune.engine import _read_trials

    return _read_trials(folder, recorded_inputs(folder, "tune").key)


def test_a_cluster_left_without_workers_is_one_error_not_a_hang(monkeypatch):
    """Every worker dead and none restarted: waiting for a result raises, naming why, after
    NO_WORKER_SECONDS (1 s here) instead of waiting forever."""
    import time

    from distributed import Client

    from nnrobust.core.exceptions import NNRobustError
    from nnrobust.studies.base import cluster as engine

    monkeypatch.setattr(engine, "NO_WORKER_SECONDS", 1.0)
    cluster = engine.local_cluster(1)
    client = Client(cluster)
    try:
        future = client.submit(time.sleep, 60, pure=False)
        cluster.scale(0)
        start = time.monotonic()
        with pytest.raises(NNRobustError, match="the cluster has had no worker for 1 s"):
            engine.outcome(future)
        assert time.monotonic() - start < 60
    finally:
        client.close()
        cluster.close()


def test_a_local_cluster_whose_nannies_gave_up_gets_new_workers(monkeypatch):
    """A nanny that stopped restarting its worker (closed here by hand, as dask's nanny does when
    its worker dies while it is starting) is replaced after REVIVE_SECONDS: the task runs."""
    from distributed import Client

    from nnrobust.studies.base import cluster as engine

    monkeypatch.setattr(engine, "REVIVE_SECONDS", 1.0)
    cluster = engine.local_cluster(1)
    client = Client(cluster)
    try:
        (nanny,) = cluster.workers.values()
        cluster.sync(nanny.close)
        assert client.scheduler_info()["workers"] == {} and len(cluster.worker_spec) == 1
        future = client.submit(sum, [1, 2], pure=False)
        assert engine.outcome(future) == (3, None)
        assert len(client.scheduler_info()["workers"]) == 1
    finally:
        client.close()
        cluster.close()


def _ends_its_worker(value):
    import os

    os._exit(3)


def test_a_shared_input_killed_with_crashing_neighbours_is_sent_again(monkeypatch):
    """CI, round 5: a tuning on two workers whose law ends its process on half its settings kept
    none. Each crash loses the inputs the dead worker held (the sweep, the base experiment); one
    computed again twice on workers that crashing neighbours ended is itself KilledWorker, and every
    task reading it inherited that death, the settings that last included. A task lost so is not
    counted against it, and its input is submitted afresh: the task runs."""
    from distributed import Client

    from nnrobust.studies.base import cluster as engine

    cluster = engine.local_cluster(1)
    client = Client(cluster)
    try:
        value = engine.shared(client, [1, 2])
        first = value.future()
        value._future = client.submit(_ends_its_worker, 0, pure=False)  # the input, killed twice
        reader = engine.submit(client, None, sum, value)
        assert engine.outcome(reader) == (None, engine.LOST_INPUT)  # not the reader's own death
        assert engine.run_alone(client, None, sum, value) == (3, None)
        assert value.future() is not first and value.future().status == "finished"
        # a task that ends its worker itself is still named so, on each of two runs alone
        result, reason = engine.run_alone(client, None, _ends_its_worker, value)
        assert result is None and reason.startswith("the worker process died twice running it")
    finally:
        client.close()
        cluster.close()


def test_a_wait_for_tasks_notices_a_stop_while_a_task_hangs():
    """A study's stages run on threads, which receive no signal: a stop asked of them
    (signals.stop_stages) is noticed by a sweep waiting on a task that never ends (a law that
    hangs), within a poll, not when the task ends."""
    import threading
    import time

    from distributed import Client

    from nnrobust.core.signals import stop_stages
    from nnrobust.studies.base import cluster as engine

    cluster = engine.local_cluster(1)
    client = Client(cluster)
    ended = []

    def stage():
        with client.as_current():
            future = client.submit(time.sleep, 300, pure=False)
            try:
                for _ in engine.as_they_finish([future]):
                    ended.append("finished")
            except KeyboardInterrupt:
                ended.append("stopped")

    try:
        thread = threading.Thread(target=stage)
        thread.start()
        time.sleep(0.5)
        stop_stages()
        thread.join(120)  # the task sleeps 300 s
        assert ended == ["stopped"]
    finally:
        stop_stages(False)
        client.close()
        cluster.close()


def test_a_stop_signal_while_a_cluster_closes_is_raised_once_it_has_closed():
    """signals_held (around closing a cluster, around stopping side-by-side stages): a stop
    signal is only noted in the block and raised as it ends; with an exception already leaving
    the block, that exception leaves, not a second interrupt. (The handler is called directly:
    which thread the system would deliver a signal to does not matter to it.)"""
    import signal

    from nnrobust.core import signals

    done = []
    with signals.signals_as_interrupt():
        with pytest.raises(KeyboardInterrupt):
            with signals.signals_held():
                signals._stop(signal.SIGINT, None)  # not raised here: the close goes on
                done.append("closed")
        assert done == ["closed"]
        with pytest.raises(ValueError):
            with signals.signals_held():
                signals._stop(signal.SIGINT, None)
                raise ValueError("the close failed")
    signals.check_interrupt()  # the block handled it
