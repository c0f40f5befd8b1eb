"""Robustness sweeps on a real dask LocalCluster of 2 workers: every row exactly once, resume,
a killed worker, bad sweep files, diverged samples as rows."""

import os
import signal
import threading
import time

import numpy as np
import pytest

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from nnrobust.cli import main  # noqa: E402
from nnrobust.core.exceptions import ConfigError, NNRobustError  # noqa: E402
from nnrobust.studies.base.cluster import local_cluster
from nnrobust.studies.sweep import load_sweep, parse_sweep, read_results, run_sweep  # noqa: E402
from nnrobust.studies.sweep.engine import plan  # noqa: E402

SWEEP = """
name = "tiny"
base = "paper-ellipse"
controllers = ["nn", "no-u0"]
samples = 3
seed = 1
[set]
"simulation.duration" = {duration}
[vary]
"plant.disturbance_scale" = [0.5, 2.0]
"nn.sigma" = {{uniform = [0.02, 0.2]}}
"""


def _sweep_file(tmp_path, duration=2.5, text=None):
    path = tmp_path / "sweep.toml"
    path.write_text(text if text is not None else SWEEP.format(duration=duration))
    return path


def _assert_complete(frame, samples, controllers):
    pairs = list(zip(frame["sample"], frame["controller"]))
    assert len(pairs) == len(set(pairs)) == samples * len(controllers)  # every row exactly once
    assert set(pairs) == {(s, c) for s in range(samples) for c in controllers}


def test_every_row_once_then_resume_computes_nothing(scheduler, tmp_path):
    spec = load_sweep(_sweep_file(tmp_path))
    out = tmp_path / "out"
    first = run_sweep(spec, out, scheduler=scheduler)
    frame = read_results(out)
    _assert_complete(frame, 6, ["nn", "no-u0"])
    assert first["computed"] == 12 and set(frame["status"]) == {"completed"}
    # the varied values are columns, the same for both controllers of a sample (common random numbers)
    by_sample = frame.groupby("sample")["nn.sigma"].nunique()
    assert (by_sample == 1).all()
    assert set(frame["plant.disturbance_scale"]) == {0.5, 2.0}
    again = run_sweep(spec, out, scheduler=scheduler)
    assert again == {"computed": 0, "skipped": 12, "parts": 0, "stopped": 0}
    _assert_complete(read_results(out), 6, ["nn", "no-u0"])


def test_a_sample_reruns_as_a_normal_run(scheduler, tmp_path, capsys):
    """The rerun command of the summary reproduces the sample's row."""
    from nnrobust.config import apply_overrides, parse_override
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.sweep import draw, rerun_command

    spec = load_sweep(_sweep_file(tmp_path))
    run_sweep(spec, tmp_path / "out", scheduler=scheduler)
    frame = read_results(tmp_path / "out")
    row = frame[(frame["sample"] == 4) & (frame["controller"] == "nn")].iloc[0]
    import shlex

    words = shlex.split(rerun_command(spec, draw(spec, 4), "nn"))
    assert words[:5] == ["nnrobust", "run", "paper-ellipse", "--controller", "nn"]
    sets = [words[i + 1] for i, word in enumerate(words) if word == "--set"]
    config = apply_overrides(
        load_preset("paper-ellipse").replace(controller={"kind": "nn"}), dict(parse_override(s) for s in sets)
    )
    metrics = run_experiment(config).metrics()
    assert metrics["rms_error_after_2s"] == pytest.approx(row["rms_error_after_2s"], rel=1e-12)


def test_a_killed_worker_costs_only_its_chunk(tmp_path):
    """kill -9 of a worker in mid-sweep: dask runs its chunk again, and the table is complete with
    every row exactly once."""
    spec = load_sweep(_sweep_file(tmp_path, duration=6.0))
    out = tmp_path / "out"
    cluster = local_cluster(2)
    try:
        result = {}
        thread = threading.Thread(
            target=lambda: result.update(run_sweep(spec, out, scheduler=cluster.scheduler_address))
        )
        thread.start()
        deadline = time.monotonic() + 60
        while not list((out / "results").glob("part-*.parquet")) and time.monotonic() < deadline:
            time.sleep(0.05)
        victim = next(iter(cluster.workers.values()))
        os.kill(victim.process.pid, signal.SIGKILL)
        thread.join(timeout=240)
        assert not thread.is_alive()
    finally:
        cluster.close()
    assert result["computed"] == 12
    _assert_complete(read_results(out), 6, ["nn", "no-u0"])


def test_a_diverged_sample_is_a_row(scheduler, tmp_path):
    text = """
name = "unstable"
base = "paper-ellipse"
controllers = ["nn"]
[set]
"simulation.duration" = 1.0
"plant.torque_limits" = "none"
[vary]
"controller.Kv" = [[4.0], [2000.0]]
"""
    spec = load_sweep(_sweep_file(tmp_path, text=text))
    run_sweep(spec, tmp_path / "out", scheduler=scheduler)
    frame = read_results(tmp_path / "out").sort_values("sample")
    assert list(frame["status"]) == ["completed", "diverged"]
    assert "rad/s" in frame["message"].iloc[1]


def test_a_changed_sweep_is_refused_unless_overwrite(scheduler, tmp_path):
    spec = load_sweep(_sweep_file(tmp_path, duration=1.0))
    out = tmp_path / "out"
    run_sweep(spec, out, scheduler=scheduler)
    changed = load_sweep(_sweep_file(tmp_path, duration=1.5))
    with pytest.raises(NNRobustError, match="holds a different sweep"):
        run_sweep(changed, out, scheduler=scheduler)
    assert run_sweep(changed, out, scheduler=scheduler, overwrite=True)["computed"] == 12
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep me")
    with pytest.raises(NNRobustError, match="is not a sweep folder"):
        run_sweep(changed, tmp_path / "mine", scheduler=scheduler)
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep me"


def test_overwrite_replaces_only_what_the_sweep_wrote(scheduler, tmp_path, monkeypatch, capsys):
    """Issue 22 item 10: a folder holding the user's own sweep.toml is not a sweep folder, and
    --overwrite never removes it nor a file the sweep did not write; the working folder and its
    ancestors are refused as --out."""
    project = tmp_path / "project"
    project.mkdir()
    (project / "thesis.tex").write_text("years of work")
    path = project / "sweep.toml"
    path.write_text(SWEEP.format(duration=1.0))
    monkeypatch.chdir(project)
    for out in (".", str(project), str(tmp_path)):
        assert main(["sweep", "sweep.toml", "--out", out, "--overwrite", "--workers", "1"]) == 2
        assert "is the working folder or one of its ancestors" in capsys.readouterr().err
    study = project / "study"
    study.mkdir()
    (study / "sweep.toml").write_text(path.read_text())
    (study / "notes.md").write_text("mine")
    assert main(["sweep", "sweep.toml", "--out", "study", "--overwrite", "--workers", "1"]) == 2
    assert "is not a sweep folder (no .nnrobust-sweep)" in capsys.readouterr().err
    assert (study / "notes.md").read_text() == "mine" and (project / "thesis.tex").is_file()
    out = project / "out"
    assert main(["sweep", "sweep.toml", "--out", "out", "--scheduler", scheduler, "--quiet"]) == 0
    (out / "notes.md").write_text("my notes on this sweep")
    path.write_text(SWEEP.format(duration=1.5))
    assert (
        main(["sweep", "sweep.toml", "--out", "out", "--scheduler", scheduler, "--quiet", "--overwrite"]) == 0
    )
    assert (out / "notes.md").read_text() == "my notes on this sweep"
    assert "1.5" in (out / "sweep.toml").read_text() and (project / "thesis.tex").is_file()


def test_two_sweeps_into_one_folder_never_write_a_row_twice(tmp_path):
    """Issue 22 item 12: the sweep folder is locked; a second sweep into it is refused at once."""
    from nnrobust.outputs.run_folder import locked

    spec = load_sweep(_sweep_file(tmp_path, duration=1.0))
    out = tmp_path / "out"
    with locked(out):  # as a running sweep holds it
        with pytest.raises(NNRobustError, match="is writing"):
            run_sweep(spec, out, workers=1)


BAD = [
    ("unknown key", {"nmae": "x"}, "unknown key"),
    ("missing base", {"name": "x", "controllers": ["nn"]}, "base: missing"),
    ("unknown controller", {"controllers": ["nn", "lqr"]}, "controllers\\[1\\]: .lqr. is not one of nn"),
    ("unknown distribution", {"vary": {"nn.sigma": {"gamma": [1, 2]}}}, "unknown distribution"),
    ("reversed uniform", {"vary": {"nn.sigma": {"uniform": [0.3, 0.1]}}}, "needs a < b"),
    ("loguniform from zero", {"vary": {"nn.sigma": {"loguniform": [0.0, 1.0]}}}, "needs 0 < a"),
    ("unknown dotted key", {"vary": {"nn.sigmaa": [0.1]}}, "did you mean 'nn.sigma'"),
    ("empty grid", {"vary": {"nn.sigma": []}}, "expected a non-empty list"),
    ("negative samples", {"samples": 0}, "samples: expected an integer >= 1"),
    (
        "custom entry without class",
        {"controllers": [{"name": "mine"}]},
        "controllers\\[0\\]: a table entry is",
    ),
    (
        "entry with a class and a kind",
        {"controllers": [{"name": "mine", "class": "a.py:B", "kind": "nn"}]},
        "controllers\\[0\\]: a table entry is",
    ),
    (
        "entry of an unknown kind",
        {"controllers": [{"name": "mine", "kind": "lqr"}]},
        "controllers\\[0\\].kind: 'lqr' is not one of nn",
    ),
    (
        "entry setting the plant",
        {"controllers": [{"name": "mine", "kind": "nn", "set": {"plant.payload": 1.0}}]},
        "controllers\\[0\\].set.plant.payload: an entry's settings are the law's own",
    ),
    (
        "entry setting an unknown key",
        {"controllers": [{"name": "mine", "kind": "nn", "set": {"nn.FF": 1.0}}]},
        "controllers\\[0\\].set.nn.FF: .*did you mean 'nn.F'",
    ),
    (
        "custom entry named like a kind",
        {"controllers": [{"name": "nn", "class": "a.py:B"}]},
        "controllers\\[0\\].name: 'nn' must be .* not a built-in kind",
    ),
    (
        "custom entry twice",
        {"controllers": [{"name": "a", "class": "a.py:B"}, {"name": "a", "class": "a.py:C"}]},
        "lists a controller twice",
    ),
    (
        "controller kind in set",
        {"set": {"controller.kind": "pd"}},
        "set.controller.kind: the controllers list",
    ),
    (
        "controller params in vary",
        {"vary": {"controller.params.Kp": [1.0]}},
        "vary.controller.params.Kp: the controllers list",
    ),
]


def test_grid_points_follow_the_product_and_a_huge_grid_is_refused_at_once():
    """Sample ids walk the grid in itertools.product order; a grid of 10^12 points is refused by
    its size alone, without building it."""
    import itertools

    vary = {"nn.sigma": [0.1, 0.2, 0.3], "nn.F": [1.0, 2.0], "controller.k": [1.0, 2.0, 5.0, 7.0]}
    spec = parse_sweep(
        {"name": "g", "base": "paper-ellipse", "controllers": ["nn"], "samples": 2, "vary": vary}
    )
    points = list(itertools.product(*vary.values()))
    assert [spec.grid_point(i) for i in range(len(points))] == points and spec.size == 2 * len(points)
    huge = {f"nn.{k}": list(range(1, 1001)) for k in ("F", "gamma", "eps0", "centers")}
    start = time.perf_counter()
    with pytest.raises(ConfigError, match="1000000000000 samples x 1 controllers exceed 1000000 rows"):
        parse_sweep({"name": "g", "base": "paper-ellipse", "controllers": ["nn"], "vary": huge})
    assert time.perf_counter() - start < 1.0


@pytest.mark.parametrize("label, change, message", BAD, ids=[b[0] for b in BAD])
def test_bad_sweep_files_get_one_line_errors(label, change, message):
    data = {"name": "x", "base": "paper-ellipse", "controllers": ["nn"], **change}
    if label == "missing base":
        data = change
    with pytest.raises(ConfigError, match=message):
        parse_sweep(data)


def test_values_the_schema_refuses_are_caught_before_anything_runs(tmp_path, capsys):
    """A grid value the experiment schema refuses: one line naming the key and the sample, exit 2,
    and no folder is written."""
    text = """
name = "refused"
base = "paper-ellipse"
controllers = ["nn"]
[vary]
"nn.eps_min" = [0.5, -1.0]
"""
    path = _sweep_file(tmp_path, text=text)
    spec = load_sweep(path)
    with pytest.raises(ConfigError, match=r"vary: nn.eps_min: -1 is outside \[0, inf\].*sample 1"):
        plan(spec)
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("nnrobust: error:")
    assert not (tmp_path / "out").exists()


def test_cli_sweep_writes_results_summary_and_rerun_commands(scheduler, tmp_path, capsys):
    path = _sweep_file(tmp_path, duration=2.5)
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--out", str(out), "--scheduler", scheduler, "--keep-worst", "1"]) == 0
    printed = capsys.readouterr()
    assert "worst nn: sample" in printed.out and "nnrobust run paper-ellipse --controller nn" in printed.out
    import json

    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["controllers"]) == {"nn", "no-u0"}
    nn = summary["controllers"]["nn"]
    assert nn["rows"] == 6 and nn["success_rate"] == 1.0
    error = nn["rms_error_after_2s"]
    assert error["median"] <= error["p95"] <= error["max"]
    frame = read_results(out)
    assert np.isclose(
        frame[frame["controller"] == "nn"]["rms_error_after_2s"].max(), nn["rms_error_after_2s"]["max"]
    )
    by_scale = nn["by_grid"]["plant.disturbance_scale"]
    assert set(by_scale) == {"0.5", "2.0"}
    rows = frame[(frame["controller"] == "nn") & (frame["plant.disturbance_scale"] == 2.0)]
    assert np.isclose(by_scale["2.0"]["median"], rows["rms_error_after_2s"].median())
    written = (out / "sweep.toml").read_text()  # the resolved sweep, under the digests of its files
    assert (
        written.endswith(load_sweep(path).to_toml()) and "\n# the robot's URDF: three_link_planar " in written
    )
    plots = sorted(p.name for p in (out / "plots").glob("*.png"))
    assert plots == [
        "error_cdf.png",
        "error_vs_nn_sigma.png",
        "error_vs_plant_disturbance_scale.png",
        "pareto.png",
    ]
    # --keep-worst 1: the worst nn sample as a full run folder, the same run as its row
    worst = nn["worst"]
    folder = out / "worst" / f"nn-sample-{worst['sample']}"
    kept = json.loads((folder / "metrics.json").read_text())
    assert kept["rms_error_after_2s"] == pytest.approx(worst["rms_error_after_2s"], rel=1e-12)
    assert (folder / "animation.html").is_file() and (folder / "result.npz").is_file()


def test_a_custom_controller_joins_a_sweep_as_a_table_entry(scheduler, tmp_path, monkeypatch):
    """A controllers entry {name, class, params}: its class file is read from the sweep file's
    folder, the Dask workers import it, its rows are named by the entry, and the printed command
    reruns a row exactly. The entry is eq. (9) written again, so its rows equal no-u0's."""
    import json
    import shlex
    import shutil
    from pathlib import Path

    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", tmp_path / "laws.py")
    path = _sweep_file(
        tmp_path,
        text="""
name = "mine"
base = "paper-ellipse"
controllers = ["no-u0", {name = "eq9", class = "laws.py:Eq9", params = {Kp = 10.0, Kv = 4.0}}]
samples = 2
[set]
"simulation.duration" = 2.2
[vary]
"plant.disturbance_scale" = {uniform = [0.5, 2.0]}
""",
    )
    out = tmp_path / "out"
    monkeypatch.chdir(tmp_path / "..")
    assert main(["sweep", str(path), "--out", str(out), "--scheduler", scheduler]) == 0
    frame = read_results(out).sort_values(["controller", "sample"])
    mine, builtin = frame[frame["controller"] == "eq9"], frame[frame["controller"] == "no-u0"]
    assert list(mine["status"]) == ["completed"] * 2
    np.testing.assert_allclose(
        mine["rms_error_after_2s"].to_numpy(), builtin["rms_error_after_2s"].to_numpy(), rtol=1e-6
    )
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["controllers"]) == {"no-u0", "eq9"}
    command = summary["controllers"]["eq9"]["worst"]["command"]
    words = shlex.split(command)
    assert words[3:5] == ["--controller", f"{(tmp_path / 'laws.py').resolve()}:Eq9"]
    assert "controller.params.Kp=10.0" in words
    quiet = ["--quiet", "--no-plots", "--no-animation"]
    assert main([*words[1:], "--out", str(tmp_path / "again"), *quiet]) == 0
    again = json.loads((tmp_path / "again" / "metrics.json").read_text())
    worst = summary["controllers"]["eq9"]["worst"]
    assert again["rms_error_after_2s"] == pytest.approx(worst["rms_error_after_2s"], rel=1e-12)
    assert "params = {Kp = 10.0, Kv = 4.0}" in (out / "sweep.toml").read_text()


@pytest.mark.parametrize("name", ["paper-robustness", "panda-robustness"])
def test_shipped_studies_validate_every_sample(name):
    """The shipped studies load by name and every (sample, controller) experiment passes the schema."""
    from nnrobust.studies.base.plan import shipped_sweeps

    assert name in shipped_sweeps()
    spec = load_sweep(name)
    _, jobs = plan(spec)
    assert len(jobs) == spec.size * len(spec.controllers)
    assert {"nominal.relative_error", "plant.friction_scale", "plant.disturbance_scale"} <= set(spec.vary)


def test_client_memory_does_not_grow_with_samples(scheduler, tmp_path):
    """The client keeps (id, controller) pairs and writes each chunk's rows as they arrive: from
    40 to 400 rows its peak Python memory (tracemalloc, which also counts the in-process
    scheduler) grows by less per row than one row of the metrics table takes as Python objects.
    Both sweeps run in 8 chunks (seconds_per_job tiny), so dask's own bookkeeping per task,
    about 10 kB, is the same in both."""
    import sys
    import tracemalloc

    def peak(samples: int) -> int:
        spec = parse_sweep(
            {
                "name": f"memory-{samples}",
                "base": "paper-ellipse",
                "controllers": ["no-u0"],
                "samples": samples,
                "seed": 2,
                "set": {"simulation.duration": 0.01},
                "vary": {"plant.friction_scale": {"uniform": [0.5, 2.0]}},
            }
        )
        tracemalloc.start()
        try:
            run_sweep(spec, tmp_path / f"out-{samples}", scheduler=scheduler, seconds_per_job=1e-3)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    peak(20)  # warm up: imports, connections
    small, large = peak(40), peak(400)
    row = read_results(tmp_path / "out-400").iloc[0].to_dict()
    row_bytes = sys.getsizeof(row) + sum(sys.getsizeof(k) + sys.getsizeof(v) for k, v in row.items())
    assert (large - small) / 360 < row_bytes, (small, large, row_bytes)


def test_a_local_cluster_listens_on_loopback_only():
    """Every socket the local cluster's scheduler listens on (its RPC and the HTTP server dask
    starts even without a dashboard) is on 127.0.0.1, and none takes the dashboard's port 8787."""
    from nnrobust.studies.base.cluster import cluster_client as _client

    with _client(1, None) as client:
        scheduler = client.cluster.scheduler
        sockets = [s.getsockname() for s in scheduler.http_server._sockets.values()]
        sockets += [(host, port) for host, port in [scheduler.address.removeprefix("tcp://").rsplit(":", 1)]]
    assert sockets and all(host == "127.0.0.1" for host, _ in sockets), sockets
    assert all(int(port) != 8787 for _, port in sockets)


def test_local_workers_keep_the_environments_malloc_thresholds(monkeypatch):
    """Dask's nanny would set MALLOC_TRIM_THRESHOLD_ in its workers, which switches off glibc's
    dynamic mmap threshold and costs a sweep's rows 10 % (benchmarks/sweep_throughput.py): the
    local cluster's workers have the client's environment's value, absent or the user's."""
    from nnrobust.studies.base.cluster import cluster_client as _client

    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)
    with _client(1, None) as client:
        seen = client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_"))
    assert list(seen.values()) == [None], seen
    monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", "1048576")
    with _client(1, None) as client:
        seen = client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_"))
    assert list(seen.values()) == ["1048576"], seen


def test_a_sample_that_raises_is_a_row_and_the_sweep_goes_on(monkeypatch):
    """A defect that raises inside one run (not a refusal) is that row's status ``error`` with
    its type and message; the other rows run."""
    import nnrobust.run.experiment
    from nnrobust.studies.base.plan import base_values
    from nnrobust.studies.sweep.engine import run_rows

    spec = parse_sweep(
        {
            "name": "e",
            "base": "paper-ellipse",
            "controllers": ["nn"],
            "samples": 2,
            "set": {"simulation.duration": 0.2},
        }
    )
    real, calls = nnrobust.run.experiment.run_experiment, []

    def flaky(config, *args, **kwargs):
        calls.append(1)
        if len(calls) == 1:
            raise ZeroDivisionError("a defect")
        return real(config, *args, **kwargs)

    monkeypatch.setattr(nnrobust.run.experiment, "run_experiment", flaky)
    rows = run_rows(spec, base_values(spec), [(0, "nn"), (1, "nn")])
    assert [r["status"] for r in rows] == ["error", "completed"]
    assert rows[0]["message"] == "ZeroDivisionError: a defect"


def test_a_scheduler_address_that_is_not_a_scheduler_is_one_error_within_seconds(monkeypatch):
    """Issue 22 item 17: a silent port and a server of another protocol (an immediate reply whose
    first 8 bytes dask would read as an exabyte length) are refused before dask connects; a real
    scheduler passes."""
    import socket
    import threading

    from nnrobust.studies.base import cluster as engine

    monkeypatch.setattr(engine, "PROBE_SECONDS", 0.5)

    def server(reply: bytes) -> int:
        sock = socket.socket()
        sock.bind(("127.0.0.1", 0))
        sock.listen()

        def serve():
            conn, _ = sock.accept()
            if reply:
                conn.sendall(reply)
            time.sleep(2)
            conn.close()
            sock.close()

        threading.Thread(target=serve, daemon=True).start()
        return sock.getsockname()[1]

    start = time.perf_counter()
    with pytest.raises(NNRobustError, match="no dask handshake within 0.5 s"):
        engine.check_scheduler(f"127.0.0.1:{server(b'')}")
    with pytest.raises(NNRobustError, match="does not speak dask's protocol"):
        engine.check_scheduler(f"tcp://127.0.0.1:{server(b'HTTP/1.1 400 Bad Request')}")
    assert time.perf_counter() - start < 3
    with engine.cluster_client(1, None) as client:
        address = client.cluster.scheduler_address
        assert engine.check_scheduler(address) == address


def test_grids_of_mixed_types_and_seeds_beyond_2_53_are_stored_exactly(scheduler, tmp_path):
    """Issue 22 item 13: a grid mixing a name and a list, and seeds beyond 2^53, used to crash
    pyarrow on the first part; runs shorter than 2 s used to crash the plots."""
    path = _sweep_file(
        tmp_path,
        text="""
name = "mix"
base = "paper-ellipse"
controllers = ["pd"]
[set]
"simulation.duration" = 0.3
[vary]
"plant.torque_limits" = ["urdf", [60.0, 40.0, 20.0]]
"sensing.seed" = [9007199254740993, 3]
""",
    )
    assert (
        main(["sweep", str(path), "--out", str(tmp_path / "out"), "--scheduler", scheduler, "--quiet"]) == 0
    )
    frame = read_results(tmp_path / "out")
    assert set(frame["sensing.seed"]) == {9007199254740993, 3}  # exact: a float64 column would round it
    assert set(frame["plant.torque_limits"]) == {"urdf", "[60.0, 40.0, 20.0]"}
    assert set(frame["status"]) == {"completed"}
    assert (tmp_path / "out" / "plots" / "error_vs_plant_torque_limits.png").is_file()


def test_a_bad_value_late_in_a_long_grid_is_refused_before_the_rest_is_checked(monkeypatch):
    """The first sample of every distinct grid value is checked first: a bad 10,000th grid value
    is refused after a handful of checks, not after the 9,999 good samples (44 s before)."""
    from nnrobust.studies.base.plan import draw
    from nnrobust.studies.sweep import engine

    spec = parse_sweep(
        {
            "name": "late",
            "base": "paper-ellipse",
            "controllers": ["nn", "no-u0"],
            "samples": 2,
            "vary": {"simulation.duration": [3.0] * 9_999 + [-1.0], "plant.friction_scale": [1.0, 2.0]},
        }
    )
    first = engine._first_checked(spec)
    for key in spec.grid_keys:  # every distinct value of every grid key is among them
        assert {draw(spec, i).values[key] for i in first} == set(spec.vary[key])
    checked = []
    experiment = engine.experiment
    monkeypatch.setattr(engine, "experiment", lambda *a: checked.append(a[2].id) or experiment(*a))
    with pytest.raises(ConfigError, match=r"simulation.duration: must be positive, got -1.0 \(sample 39996"):
        plan(spec)
    assert len(checked) < 10


def test_a_damaged_results_folder_is_refused_on_resume_and_names_what_to_do(scheduler, tmp_path, capsys):
    """A part changed after it was written, or a file where results/ was: the resume stops with
    one line naming it (it was a pyarrow or FileExistsError traceback); removing it resumes."""
    sweep = tmp_path / "s.toml"
    sweep.write_text(
        'name = "s"\nbase = "paper-ellipse"\ncontrollers = ["nn"]\nsamples = 2\n'
        '[set]\n"simulation.duration" = 0.5\n'
    )
    out = tmp_path / "out"
    command = ["sweep", str(sweep), "--out", str(out), "--scheduler", scheduler, "--quiet"]
    assert main(command) == 0
    part = sorted((out / "results").glob("part-*.parquet"))[0]
    part.write_bytes(b"garbage")
    assert main(command) == 2
    assert f"{part} is not a readable Parquet part" in capsys.readouterr().err
    part.unlink()
    assert main(command) == 0 and len(read_results(out)) == 2  # its rows computed again
    import shutil

    shutil.rmtree(out / "results")
    (out / "results").write_text("mine")
    assert main(command) == 2 and "results is not a folder" in capsys.readouterr().err


def test_a_registered_law_joins_a_sweep_by_name_and_as_an_entry_with_its_params(
    scheduler, tmp_path, monkeypatch
):
    """controllers = ["slotine-li", {name, kind = "slotine-li", params}]: both run on every sample,
    the entry at its own parameters, and the printed command reruns its worst row exactly."""
    import json
    import shlex

    path = _sweep_file(
        tmp_path,
        text="""
name = "classics"
base = "paper-ellipse"
controllers = ["slotine-li", {name = "sl-slow", kind = "slotine-li", params = {Lambda = 30.0, gamma = 0.5}}]
samples = 2
[set]
"simulation.duration" = 2.2
[vary]
"plant.disturbance_scale" = {uniform = [0.5, 2.0]}
""",
    )
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--out", str(out), "--scheduler", scheduler]) == 0
    frame = read_results(out).sort_values(["controller", "sample"])
    fast, slow = frame[frame["controller"] == "slotine-li"], frame[frame["controller"] == "sl-slow"]
    assert list(fast["status"]) == list(slow["status"]) == ["completed"] * 2
    assert (slow["rms_error_after_2s"].to_numpy() > 2 * fast["rms_error_after_2s"].to_numpy()).all()
    words = shlex.split(
        json.loads((out / "summary.json").read_text())["controllers"]["sl-slow"]["worst"]["command"]
    )
    assert words[3:5] == ["--controller", "slotine-li"] and "controller.params.Lambda=30.0" in words
    monkeypatch.chdir(tmp_path)
    assert (
        main([*words[1:], "--out", str(tmp_path / "again"), "--quiet", "--no-plots", "--no-animation"]) == 0
    )
    again = json.loads((tmp_path / "again" / "metrics.json").read_text())
    assert again["rms_error_after_2s"] == pytest.approx(slow["rms_error_after_2s"].max(), rel=1e-12)


def test_a_registered_law_entry_is_checked_against_its_declaration(tmp_path, capsys):
    path = _sweep_file(
        tmp_path,
        text="""
name = "classics"
base = "paper-ellipse"
controllers = [{name = "sl", kind = "slotine-li", params = {Lamda = 30.0}}]
samples = 1
""",
    )
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "controller.params.Lamda: slotine-li has no parameter 'Lamda'" in capsys.readouterr().err
    nn_params = _sweep_file(
        tmp_path,
        text="""
name = "x"
base = "paper-ellipse"
controllers = [{name = "fast", kind = "nn", params = {F = 3.0}}]
samples = 1
""",
    )
    with pytest.raises(ConfigError, match="a table entry is"):
        load_sweep(nn_params)


@pytest.mark.parametrize("table", ["set", "vary"])
def test_a_set_or_varied_key_gives_the_configuration_of_the_edited_file(table, tmp_path):
    """Issue 34, item 9: [set] and [vary] keys are set in the base file's own values, as an edit of
    the file would set them. The README's panda (Kp = [25.0], a position task) with robot.task =
    "pose" gives six gains of 25; it said `controller.Kp: has 3 entries` (the keys were set in the
    resolved base, whose one-value gains were already written out three times)."""
    from nnrobust.config import load_config
    from nnrobust.studies.base.plan import base_config, base_values, draw, experiment
    from tests.run.test_experiment import _readme_panda

    base = tmp_path / "my-panda.toml"
    base.write_text(_readme_panda())
    edited = tmp_path / "edited.toml"
    edited.write_text(
        base.read_text().replace('task = "position"', 'task = "pose"') + "[sensing]\nseed = 3\n"
    )
    task = '"robot.task" = "pose"' if table == "set" else '[vary]\n"robot.task" = ["pose"]'
    seeds = '"nominal.seed" = 7\n"sensing.seed" = 3\n'  # the seeds a sample would otherwise draw
    path = _sweep_file(
        tmp_path,
        text=f'name = "p"\nbase = "my-panda.toml"\ncontrollers = ["nn"]\n[set]\n{seeds}{task}\n',
    )
    spec = load_sweep(path)
    plan(spec)  # every row validated
    config = experiment(spec, base_values(spec), draw(spec, 0), "nn")
    assert config == load_config(edited) and config.controller.Kp == [25.0] * 6
    if table == "set":
        assert base_config(spec) == load_config(edited)


UNBUILDABLE = {  # a controllers entry that can never run, and what the refusal says
    "a class file that is not there": ('class = "nope.py:Eq9"', "nope.py' is not a file"),
    "a constructor that raises": (
        'class = "laws.py:NeedsGain", params = {gain = -1.0}',
        "ValueError: gain must be >= 0, got -1.0",
    ),
    "a torque of the wrong shape": (
        'class = "laws.py:WrongShape"',
        "WrongShape.compute returned a torque of shape (4,) at t = 0 s; the arm has 3 joints",
    ),
}


@pytest.mark.parametrize("case", UNBUILDABLE)
def test_a_controller_that_cannot_run_is_refused_before_any_sample(case, tmp_path, capsys):
    """Issue 35, item 4: each controller is built on the base experiment and its first control
    step run before any sample: one that never can is one line naming it, and no folder is
    written (every one of its rows was "refused", rc 0)."""
    import shutil
    from pathlib import Path

    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", tmp_path / "laws.py")
    entry, message = UNBUILDABLE[case]
    path = _sweep_file(
        tmp_path,
        text=f'name = "b"\nbase = "paper-ellipse"\ncontrollers = ["no-u0", {{name = "mine", {entry}}}]\n'
        'samples = 2\n[set]\n"simulation.duration" = 0.2\n',
    )
    with pytest.raises(ConfigError, match="controllers: mine: cannot run: ") as info:
        run_sweep(load_sweep(path), tmp_path / "out", workers=1)
    assert message in str(info.value) and not (tmp_path / "out").exists()
    assert main(["sweep", str(path), "--out", str(tmp_path / "out"), "--workers", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and not (tmp_path / "out").exists()


def test_a_controller_runs_where_the_experiment_itself_cannot_be_built(scheduler, tmp_path):
    """The check blames a controller only when the shipped no-u0 runs where it does not: a base
    that only the samples make valid (its duration over the memory limit, each sample's within it)
    is left to the rows, which run."""
    (tmp_path / "long.toml").write_text('base = "paper-ellipse"\n[simulation]\nduration = 1e5\n')
    path = _sweep_file(
        tmp_path,
        text='name = "b"\nbase = "long.toml"\ncontrollers = ["nn"]\n[vary]\n"simulation.duration" = [0.2]\n',
    )
    assert run_sweep(load_sweep(path), tmp_path / "out", scheduler=scheduler)["computed"] == 1


def test_a_changed_input_is_named_and_a_copied_or_changed_part_is_refused(scheduler, tmp_path, capsys):
    """Issue 35, item 1: every row is tied to the SHA-256 of what it was computed from. An edited
    URDF, base experiment or sweep value is refused on resume in one line naming it (the old rows
    were reported as results of the new inputs, rc 0); the same content resumes, from a moved
    folder too. A part copied from a sweep of other inputs, a second copy of a row, and a part
    changed after it was written are refused by name (a copied part was counted: 30 rows for 12
    samples)."""
    import shutil
    from pathlib import Path

    import pandas as pd

    study = tmp_path / "study"
    study.mkdir()
    shutil.copy(Path(__file__).parents[3] / "urdf" / "three_link_planar.urdf", study / "arm.urdf")
    (study / "exp.toml").write_text(
        'base = "paper-ellipse"\n[robot]\nsource = "arm.urdf"\n[simulation]\nduration = 0.2\n'
    )
    (study / "s.toml").write_text('name = "s"\nbase = "exp.toml"\ncontrollers = ["nn"]\nsamples = 2\n')

    def sweep_into(folder: Path, sweep: Path) -> tuple[int, list[str]]:
        capsys.readouterr()
        code = main(["sweep", str(sweep), "--out", str(folder), "--scheduler", scheduler, "--quiet"])
        return code, capsys.readouterr().err.strip().splitlines()

    out = study / "out"
    assert sweep_into(out, study / "s.toml")[0] == 0
    for name, old, new, words in (
        ("arm.urdf", "</robot>", "</robot>\n<!-- edited -->", "the robot's URDF, {}, has changed"),
        ("exp.toml", "duration = 0.2", "duration = 0.25", "the base experiment, {}, has changed"),
        ("s.toml", "samples = 2", "samples = 2\nseed = 5", "seed was 0, now 5"),
    ):
        text = (study / name).read_text()
        (study / name).write_text(text.replace(old, new))
        code, err = sweep_into(out, study / "s.toml")
        expected = f"{out} holds a different sweep: {words.format((study / name).resolve())}"
        assert code == 2 and len(err) == 1 and expected in err[0] and "; pass --overwrite" in err[0], err
        (study / name).write_text(text)
    shutil.move(study, tmp_path / "moved")  # the same content elsewhere: resumes
    study, out = tmp_path / "moved", tmp_path / "moved" / "out"
    assert run_sweep(load_sweep(study / "s.toml"), out, scheduler=scheduler)["computed"] == 0
    (study / "o.toml").write_text((study / "s.toml").read_text() + "seed = 5\n")
    assert sweep_into(study / "other", study / "o.toml")[0] == 0
    part = sorted((out / "results").glob("part-*.parquet"))[0]
    for copy, words in (
        (sorted((study / "other" / "results").glob("part-*.parquet"))[0], "was computed from other inputs"),
        (part, "holds the row of sample"),  # a second copy of this sweep's own part
    ):
        copied = out / "results" / f"part-000000000000-{copy.name.rpartition('-')[2]}"
        shutil.copy(copy, copied)
        code, err = sweep_into(out, study / "s.toml")
        assert code == 2 and len(err) == 1 and words in err[0], err
        copied.unlink()
    frame = pd.read_parquet(part)
    frame["rms_error_after_2s"] = 0.0  # a better result, written in place
    frame.to_parquet(part)
    code, err = sweep_into(out, study / "s.toml")
    assert code == 2 and f"{part} was changed after it was written" in err[0], err


def test_local_workers_are_bounded_by_the_machines_cpus_and_memory(monkeypatch):
    """--workers beyond 4 per CPU, or beyond what the available memory holds at 0.5 GB each, is
    refused before any process starts, naming the bound and why (1024 were accepted on 2 cores:
    6 GB of processes in 38 s)."""
    from nnrobust.core import forked
    from nnrobust.studies.base import cluster as engine

    monkeypatch.setattr(forked, "available_cpus", lambda: 2)
    monkeypatch.setattr(engine, "_available_memory", lambda: 24e9)
    assert engine.max_local_workers() == (8, "2 CPUs, at most 4 workers each")
    monkeypatch.setattr(engine, "_available_memory", lambda: 2.2e9)
    assert engine.max_local_workers() == (4, "2.2 GB of memory available, 0.5 GB per worker")
    started = []
    monkeypatch.setattr(engine, "local_cluster", lambda *a, **k: started.append(a))
    with pytest.raises(
        NNRobustError,
        match=r"--workers 1024: give 1 to 4 local worker processes on this "
        r"machine \(2.2 GB of memory available, 0.5 GB per worker\); for more, start a cluster",
    ):
        with engine.cluster_client(1024, None):
            pass
    assert started == []


@pytest.mark.parametrize("command", ["sweep", "tune", "falsify", "study"])
def test_too_many_local_workers_are_refused_before_the_folder_is_made(command, tmp_path, capsys, monkeypatch):
    """--workers beyond the machine's bound is one line, and no folder is left behind: tune,
    falsify and study had made theirs (its marker, tune.toml, an empty history) and a sweep its
    marker before the cluster refused the number."""
    from pathlib import Path

    from nnrobust.studies.base import cluster as engine

    monkeypatch.setattr(engine, "max_local_workers", lambda: (8, "2 CPUs, at most 4 workers each"))
    box = tmp_path / "box.toml"
    box.write_text(
        'name = "box"\nbase = "paper-ellipse"\ncontrollers = ["pd"]\nsamples = 2\n'
        '[set]\n"simulation.duration" = 2.2\n[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
    )
    study = Path(__file__).resolve().parents[3] / "examples" / "study.toml"
    out = tmp_path / "out"
    argv = {
        "sweep": ["sweep", str(box)],
        "tune": ["tune", "paper-ellipse", "--controllers", "pd", "--budget", "4"],
        "falsify": ["falsify", str(box), "--controllers", "pd", "--require", "rms_error<=1", "--budget", "4"],
        "study": ["study", str(study)],
    }[command]
    capsys.readouterr()
    assert main([*argv, "--out", str(out), "--workers", "1024", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("nnrobust: error: --workers 1024: give 1 to 8 local"), err
    assert not out.exists()


def test_tuned_settings_of_every_kind_of_law_flow_into_a_sweep(scheduler, tmp_path, capsys):
    """sweep --tuned DIR: a custom class entry, a registered law and a shipped kind each run at
    their best setting of a tuning, as NAME-tuned; the rows' rerun commands carry exactly those
    settings and rerun to the row. A key that is not the law's own is refused naming --tuned."""
    import json
    import shlex
    import shutil
    from pathlib import Path

    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", tmp_path / "laws.py")
    path = _sweep_file(
        tmp_path,
        text="""
name = "tuned"
base = "paper-ellipse"
controllers = ["no-u0", "slotine-li", {name = "eq9", class = "laws.py:Eq9", params = {Kp = 10.0, Kv = 4.0}}]
samples = 2
[set]
"simulation.duration" = 2.2
[vary]
"plant.disturbance_scale" = {uniform = [0.5, 2.0]}
""",
    )
    best = {
        "no-u0": {"controller.Kp": [400.0], "controller.Kv": [40.0]},
        "slotine-li": {"controller.params.K_D": 5.0},
        "eq9": {"controller.params.Kp": 400.0, "controller.params.Kv": 40.0},
    }
    tuning = tmp_path / "tuning"
    tuning.mkdir()
    (tuning / "summary.json").write_text(
        json.dumps({"controllers": {k: {"best": {"params": v}} for k, v in best.items()}})
    )
    out = tmp_path / "out"
    assert (
        main(
            [
                "sweep",
                str(path),
                "--out",
                str(out),
                "--scheduler",
                scheduler,
                "--tuned",
                str(tuning),
                "--quiet",
            ]
        )
        == 0
    )
    frame = read_results(out)
    assert set(frame["controller"]) == {"no-u0-tuned", "slotine-li-tuned", "eq9-tuned"}
    summary = json.loads((out / "summary.json").read_text())
    mine = shlex.split(summary["controllers"]["eq9-tuned"]["worst"]["command"])
    assert "controller.params.Kp=400.0" in mine and "controller.params.Kv=40.0" in mine
    shipped = shlex.split(summary["controllers"]["no-u0-tuned"]["worst"]["command"])
    assert "controller.Kp=[400.0]" in shipped
    quiet = ["--quiet", "--no-plots", "--no-animation"]
    assert main([*mine[1:], "--out", str(tmp_path / "again"), *quiet]) == 0
    again = json.loads((tmp_path / "again" / "metrics.json").read_text())
    worst = summary["controllers"]["eq9-tuned"]["worst"]
    assert again["rms_error_after_2s"] == pytest.approx(worst["rms_error_after_2s"], rel=1e-12)
    # the tuned custom law equals eq. (9) at the same gains: the same rows as the shipped law's
    rows = frame.sort_values("sample")
    np.testing.assert_allclose(
        rows[rows["controller"] == "eq9-tuned"]["rms_error_after_2s"].to_numpy(),
        rows[rows["controller"] == "no-u0-tuned"]["rms_error_after_2s"].to_numpy(),
        rtol=1e-6,
    )
    capsys.readouterr()
    best["eq9"]["plant.disturbance_scale"] = 0.0
    (tuning / "summary.json").write_text(
        json.dumps({"controllers": {k: {"best": {"params": v}} for k, v in best.items()}})
    )
    assert main(["sweep", str(path), "--out", str(tmp_path / "x"), "--tuned", str(tuning), "--quiet"]) == 2
    assert (
        "sets 'plant.disturbance_scale' for eq9, which is not a key eq9 reads itself"
        in capsys.readouterr().err
    )


def test_a_million_row_grid_is_planned_in_seconds_and_a_long_check_shows_progress(monkeypatch):
    """Round 3: 10^6 valid rows printed nothing for 100 s while each row's experiment was checked.
    Rows that differ only by their seeds are one check (a grid point's samples need no draw), and
    ``checking(done, total)`` reports a long check as it goes."""
    from nnrobust.studies.sweep import engine

    grid = parse_sweep(
        {
            "name": "million",
            "base": "paper-ellipse",
            "controllers": ["nn", "pd"],
            "samples": 100_000,
            "vary": {"plant.disturbance_scale": [0.5, 1.0, 2.0, 3.0, 4.0]},
        }
    )
    checked = []
    experiment = engine.experiment
    monkeypatch.setattr(engine, "experiment", lambda *a: checked.append(a[2].id) or experiment(*a))
    start = time.perf_counter()
    _, jobs = plan(grid)
    assert len(jobs) == 1_000_000 and jobs[-1] == (499_999, "pd")
    assert len(checked) <= 2 * 2 * 5 and time.perf_counter() - start < 30
    drawn = parse_sweep(
        {
            "name": "drawn",
            "base": "paper-ellipse",
            "controllers": ["nn"],
            "samples": 25,
            "vary": {"plant.disturbance_scale": {"uniform": [0.5, 2.0]}},
        }
    )
    monkeypatch.setattr(engine, "CHECK_REPORT_ROWS", 10)
    calls: list = []
    plan(drawn, lambda done, total: calls.append((done, total)))
    assert calls == [(10, 25), (20, 25), (25, 25)]


def test_the_command_line_shows_a_long_check_and_an_interrupt_during_it(tmp_path, monkeypatch, capsys):
    import nnrobust.studies.sweep

    def slow_check(spec, out, *args, checking=None, **kwargs):
        time.sleep(1.05)  # the line is shown once the check has taken a second
        checking(1000, 1_000_000)
        raise KeyboardInterrupt

    monkeypatch.setattr(nnrobust.studies.sweep, "run_sweep", slow_check)
    assert main(["sweep", str(_sweep_file(tmp_path)), "--out", str(tmp_path / "out")]) == 130
    err = capsys.readouterr().err
    assert "sweep tiny: checking the experiments of 1000000 rows before any of them runs" in err
    assert "1000/1000000 rows checked, ETA" in err
    assert "sweep interrupted before any row was written; run the same command again" in err


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGHUP])
def test_a_stop_signal_to_the_process_group_prints_no_worker_traceback(sig, tmp_path):
    """Ctrl-C (SIGINT to the terminal's foreground group) or a hang-up reached every dask worker,
    each of which printed a KeyboardInterrupt traceback (a killed resource tracker a dozen more).
    The workers never receive them now: the client stops, closes the cluster and says what was
    kept, in one line; no process of the group is left."""
    import subprocess
    import sys

    # 600 rows, about a minute of work on 2 workers: the signal always finds rows running (12 rows
    # once finished before it on a fast machine, and the sweep exited 0)
    path = _sweep_file(tmp_path, text=SWEEP.format(duration=20.0).replace("samples = 3", "samples = 300"))
    command = [sys.executable, "-m", "nnrobust.cli", "sweep", str(path), "--out", str(tmp_path / "out")]
    child = subprocess.Popen(
        [*command, "--workers", "2"], stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    try:
        deadline = time.monotonic() + 120
        header = ""
        while "rows already done" not in header and time.monotonic() < deadline:
            header += child.stderr.readline()  # the cluster is up and the rows are running
        time.sleep(1.0)
        os.killpg(child.pid, sig)
        err = header + child.stderr.read()
        assert child.wait(60) == 130
    finally:
        if child.poll() is None:
            os.killpg(child.pid, signal.SIGKILL)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.rstrip().endswith("run the same command again to resume"), err
    deadline = time.monotonic() + 20  # no worker or tracker of the group is left
    while time.monotonic() < deadline:
        try:
            os.killpg(child.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.2)
    else:
        raise AssertionError(
            subprocess.run(
                ["ps", "-o", "pid,cmd", "-g", str(child.pid)], capture_output=True, text=True
            ).stdout
        )


BLOCK_NNROBUST = """
import sys
class _NoNnrobust:
    def find_spec(self, name, path=None, target=None):
        if name == "nnrobust" or name.startswith("nnrobust."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, _NoNnrobust())
"""
"""A worker's preload: nnrobust cannot be imported there (a worker of another environment)."""


def test_a_worker_without_nnrobust_is_one_line_naming_it(tmp_path, monkeypatch, capsys):
    """Round 3: a worker of the user's cluster without nnrobust died on its first task (a
    traceback in its log) and the sweep waited for a worker that never came."""
    from distributed import LocalCluster

    from nnrobust.studies.base import cluster as engine

    path = _sweep_file(tmp_path, duration=0.2)
    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None,
        preload=[BLOCK_NNROBUST],
    ) as cluster:  # fmt: skip
        address = cluster.scheduler_address
        start = time.monotonic()
        assert main(["sweep", str(path), "--out", str(tmp_path / "out"), "--scheduler", address]) == 2
        assert time.monotonic() - start < 60
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"nnrobust: error: --scheduler {address}: worker tcp://")
        assert (
            "cannot import nnrobust: ModuleNotFoundError: No module named 'nnrobust'; install nnrobust"
            in err[0]
        )
    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, protocol="tcp://", host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:  # fmt: skip
        monkeypatch.setattr(engine, "WORKER_PROBE", "'0.0.1'")  # a worker of another version
        assert (
            main(["sweep", str(path), "--out", str(tmp_path / "v"), "--scheduler", cluster.scheduler_address])
            == 2
        )
        assert "has nnrobust 0.0.1, this command" in capsys.readouterr().err
