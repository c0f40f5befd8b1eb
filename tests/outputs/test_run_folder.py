"""Run folders under hostile use: concurrent runs, --overwrite, interrupted and failed writes,
corrupt folders, output paths that cannot work, signals. A good result is never lost."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.cli.runs import run_labels
from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import ConfigError, NNRobustError, one_line
from nnrobust.outputs.run_folder import MARKER, ExtrasInterrupted, RunFolderError, locked, write_run
from nnrobust.run.experiment import run_experiment
from nnrobust.run.results import Result

QUICK = ["--duration", "0.3", "--no-plots", "--no-animation", "--quiet"]


def _run(out, *extra, target="paper-ellipse"):
    return main(["run", target, "--out", str(out), *QUICK, *extra])


def _one_error_line(capsys) -> str:
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and err[0].startswith("nnrobust: error:"), err
    return err[0]


def _marker(folder: Path) -> dict:
    return json.loads((folder / MARKER).read_text())


def test_a_second_run_into_a_locked_folder_is_refused(tmp_path, capsys):
    """Two runs with the same --out: the second is refused at once (the first holds the lock for
    its whole run), instead of both finishing and one result silently replacing the other."""
    out = tmp_path / "run"
    with locked(out):
        assert _run(out) == 2
        assert "another nnrobust run (pid " in _one_error_line(capsys)
        assert not out.exists()
    assert _run(out) == 0 and _marker(out)["status"] == "completed"
    assert [p.name for p in tmp_path.iterdir()] == ["run"]  # lock file gone


def test_two_concurrent_processes_one_result(tmp_path):
    """Two real processes started together: exactly one writes the folder, the other exits 2."""
    out = tmp_path / "run"
    cmd = [
        sys.executable,
        "-m",
        "nnrobust.cli",
        "run",
        "paper-ellipse",
        "--out",
        str(out),
        "--duration",
        "2",
        "--no-plots",
        "--no-animation",
        "--quiet",
        "--backend",
        "python",
    ]
    procs = [subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    codes = sorted(p.wait(timeout=300) for p in procs)
    assert codes == [0, 2]
    assert Result.load(out).t.size == 2000


def test_overwrite_replaces_only_run_folders(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    assert _run(mine, "--overwrite") == 2
    assert "is not a run folder" in _one_error_line(capsys)
    assert (mine / "notes.txt").read_text() == "keep me"
    # a run folder is replaced, and a folder with only a run's files (no marker) counts as one
    out = tmp_path / "run"
    assert _run(out) == 0
    (out / MARKER).unlink()
    assert _run(out, "--overwrite") == 0 and (out / MARKER).is_file()


def test_a_failed_run_never_replaces_a_completed_one(tmp_path, capsys):
    out = tmp_path / "run"
    assert _run(out) == 0
    before = (out / "result.npz").read_bytes()
    # torque limits off and a huge Kv: the run diverges
    assert (
        _run(
            out,
            "--overwrite",
            "--set",
            "plant.torque_limits='none'",
            "--set",
            "controller.Kv=[2000.0]",
            "--set",
            "plant.joint_stops=false",
        )
        == 1
    )
    assert (out / "result.npz").read_bytes() == before and _marker(out)["status"] == "completed"
    beside = tmp_path / "run.diverged"
    assert _marker(beside)["status"] == "diverged" and (beside / "result.npz").is_file()
    assert "is kept; this diverged run is written to" in capsys.readouterr().err


def test_ctrl_c_while_plotting_keeps_the_finished_simulation(tmp_path, monkeypatch):
    result = run_experiment(load_preset("paper-line").replace(simulation={"duration": 0.3}))

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("nnrobust.outputs.plots.plot_run", interrupted)
    with pytest.raises(ExtrasInterrupted, match="arrays and metrics are saved"):
        write_run(tmp_path / "run", result)
    folder = tmp_path / "run"
    assert _marker(folder) | {"nnrobust": None} == {
        "format": 1,
        "nnrobust": None,
        "status": "completed",
        "extras": "interrupted",
    }
    np.testing.assert_array_equal(Result.load(folder).q, result.q)
    assert sorted(p.name for p in folder.iterdir()) == [MARKER, "config.toml", "metrics.json", "result.npz"]


def test_ctrl_c_while_the_run_is_saved_names_what_was_kept_and_nnrobust_plot(tmp_path, monkeypatch, capsys):
    """A second Ctrl-C while a long run's arrays are written is held until they are in place; it
    then says the folder is complete and that `nnrobust plot` draws the rest (it said only
    `nnrobust: interrupted`, the marker saying extras pending). The signal is sent to this thread,
    which holds it back: sent to the process, it went to another thread when one ran (a dask
    client's, from an earlier test), and was raised here when that thread was next scheduled."""
    import signal
    import threading

    from nnrobust.outputs import run_folder

    place = run_folder._place

    def place_then_ctrl_c(tmp, folder):
        place(tmp, folder)
        signal.pthread_kill(threading.get_ident(), signal.SIGINT)  # held until the block ends

    monkeypatch.setattr(run_folder, "_place", place_then_ctrl_c)
    folder = tmp_path / "run"
    code = main(["run", "paper-line", "--out", str(folder), "--duration", "0.3", "--quiet"])
    err = capsys.readouterr().err
    assert code == 130 and f"'nnrobust plot {folder}' draws the plots" in err, err
    assert "as the run was saved" in err and _marker(folder)["extras"] == "pending"
    monkeypatch.undo()
    assert main(["plot", str(folder)]) == 0 and _marker(folder)["extras"] == "complete"


def test_plot_draws_again_the_figures_a_run_drew(tmp_path, capsys):
    """nnrobust plot on a run folder whose plots/ and animation.html are gone: the same PNG files,
    pixel for pixel, and the animation back; the arrays untouched."""
    folder = tmp_path / "run"
    assert main(["run", "paper-line", "--out", str(folder), "--duration", "0.5", "--quiet"]) == 0
    drawn = {p.name: p.read_bytes() for p in (folder / "plots").glob("*.png")}
    arrays = (folder / "result.npz").read_bytes()
    shutil.rmtree(folder / "plots")
    (folder / "animation.html").unlink()
    assert main(["plot", str(folder)]) == 0
    assert {p.name: p.read_bytes() for p in (folder / "plots").glob("*.png")} == drawn and len(drawn) == 7
    assert (folder / "animation.html").stat().st_size > 500_000
    assert (folder / "result.npz").read_bytes() == arrays and _marker(folder)["extras"] == "complete"


def test_figures_and_animation_read_the_runs_info_not_its_toml(tmp_path, capsys):
    """The analysis reads the typed run info stored with the arrays (criteria, weights, units,
    robot): with config.toml unreadable, nnrobust plot draws the same figures, the subtask
    figure's title and unit included, and the animation; the info round-trips exactly."""
    from nnrobust.outputs.run_folder import load_run
    from nnrobust.run.run_info import RunInfo

    folder = tmp_path / "run"
    words = ["run", "panda-ellipse", "--out", str(folder), "--duration", "0.3", "--quiet"]
    assert main([*words, "--set", "subtasks.criteria=['joint_limits', 'manipulability']"]) == 0
    drawn = {p.name: p.read_bytes() for p in (folder / "plots").glob("*.png")}
    info = load_run(folder).info
    assert info == RunInfo.from_config(load_run(folder).experiment(), 7)
    assert info.criterion_label[0].startswith("h(q) = ") and "joint_limits" in info.criterion_label[0]
    assert info.criterion_units == ("1", "m$^3$") and info.robot_source == "panda"
    (folder / "config.toml").write_text("this is [not TOML")
    shutil.rmtree(folder / "plots")
    (folder / "animation.html").unlink()
    assert main(["plot", str(folder)]) == 0
    assert {p.name: p.read_bytes() for p in (folder / "plots").glob("*.png")} == drawn
    assert (folder / "animation.html").stat().st_size > 5_000_000  # the Panda's meshes


def test_plot_finishes_a_run_whose_drawing_was_interrupted(tmp_path, monkeypatch, capsys):
    result = run_experiment(load_preset("paper-line").replace(simulation={"duration": 0.3}))

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    with monkeypatch.context() as patched:
        patched.setattr("nnrobust.outputs.plots.plot_run", interrupted)
        with pytest.raises(ExtrasInterrupted, match="'nnrobust plot .*' draws the plots"):
            write_run(tmp_path / "run", result)
    folder = tmp_path / "run"
    assert _marker(folder)["extras"] == "interrupted" and not (folder / "plots").exists()
    assert main(["plot", str(folder)]) == 0
    assert _marker(folder)["extras"] == "complete"
    assert len(list((folder / "plots").iterdir())) == 14 and (folder / "animation.html").is_file()


def test_plot_draws_only_into_run_folders(tmp_path, capsys):
    """A folder of the user's that holds a run's files among its own: refused, left as it was."""
    folder = tmp_path / "mine"
    write_run(
        folder,
        run_experiment(load_preset("paper-line").replace(simulation={"duration": 0.1})),
        plots=False,
        animation=False,
    )
    (folder / MARKER).unlink()
    (folder / "notes.txt").write_text("mine")
    before = sorted(p.name for p in folder.iterdir())
    assert main(["plot", str(folder)]) == 2
    assert "is not a run folder" in _one_error_line(capsys)
    assert sorted(p.name for p in folder.iterdir()) == before
    assert main(["plot", str(tmp_path / "missing")]) == 2
    assert "no such folder" in _one_error_line(capsys)


def test_a_write_failure_keeps_the_previous_run_and_rescues_the_arrays(tmp_path, monkeypatch):
    result = run_experiment(load_preset("paper-line").replace(simulation={"duration": 0.3}))
    folder = write_run(tmp_path / "run", result, plots=False, animation=False)
    before = (folder / "metrics.json").read_text()

    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("nnrobust.outputs.run_folder._write_marker", full)
    with pytest.raises(
        RunFolderError,
        match=r"No space left.*previous run there is unchanged.*arrays are in "
        r"(\S+\.npz)",
    ) as caught:
        write_run(folder, result, overwrite=True, plots=False, animation=False)
    rescued = Path(str(caught.value).rsplit("arrays are in ", 1)[1])
    with np.load(rescued) as data:
        np.testing.assert_array_equal(data["q"], result.q)
    rescued.unlink()
    assert (folder / "metrics.json").read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ["run"]


@pytest.mark.parametrize("kind", ["file", "symlink", "dot", "parent of cwd", "parent is a file", "read-only"])
def test_output_paths_that_cannot_work_are_refused_before_simulating(kind, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    if kind == "file":
        out = tmp_path / "taken"
        out.write_text("x")
        expected = "is not a folder"
    elif kind == "symlink":
        (tmp_path / "real").mkdir()
        out = tmp_path / "link"
        out.symlink_to(tmp_path / "real")
        expected = "symbolic link"
    elif kind == "dot":
        out, expected = Path("."), "not '.' or '..'"
    elif kind == "parent of cwd":
        (tmp_path / "deep").mkdir()
        monkeypatch.chdir(tmp_path / "deep")
        out, expected = tmp_path, "working folder or one of its ancestors"
    elif kind == "parent is a file":
        (tmp_path / "plain").write_text("x")
        out, expected = tmp_path / "plain" / "run", "plain is a file, not a folder"
    else:
        if os.geteuid() == 0:  # root writes anywhere: let the permission check see what a user would
            monkeypatch.setattr("nnrobust.outputs.run_folder.os.access", lambda path, mode: False)
        locked_dir = tmp_path / "ro"
        locked_dir.mkdir()
        locked_dir.chmod(0o555)
        out, expected = locked_dir / "run", "permission denied"

    def simulate(*args, **kwargs):
        raise AssertionError("simulated before the output path was refused")

    monkeypatch.setattr("nnrobust.run.experiment.run_experiment", simulate)
    assert main(["run", "paper-ellipse", "--out", str(out), "--overwrite", "--quiet"]) == 2
    assert expected in _one_error_line(capsys)


def test_corrupt_run_folders_get_one_line(tmp_path, capsys):
    good = tmp_path / "good"
    assert _run(good) == 0
    truncated = tmp_path / "truncated"
    assert _run(truncated) == 0
    data = (truncated / "result.npz").read_bytes()
    (truncated / "result.npz").write_bytes(data[: len(data) // 2])
    garbage = tmp_path / "garbage"
    assert _run(garbage) == 0
    (garbage / "metrics.json").write_text("{not json")
    listed = tmp_path / "listed"
    assert _run(listed) == 0
    (listed / "metrics.json").write_text("[1, 2]")
    pickled = tmp_path / "pickled"
    assert _run(pickled) == 0
    np.savez(pickled / "result.npz", t=np.array([object()], dtype=object))
    mistyped, stringy = tmp_path / "mistyped", tmp_path / "stringy"
    for folder, change in ((mistyped, {"criterion_weights": ["x"]}), (stringy, {"criteria": "abc"})):
        assert _run(folder) == 0
        with np.load(folder / "result.npz") as data:
            arrays = {k: data[k] for k in data.files}
        arrays["info"] = np.asarray(json.dumps({**json.loads(str(arrays["info"])), **change}))
        np.savez(folder / "result.npz", **arrays)
    capsys.readouterr()
    for bad in (truncated, garbage, listed, pickled, mistyped, stringy, tmp_path / "missing"):
        assert main(["compare", str(good), str(bad)]) == 2
        assert str(bad) in _one_error_line(capsys)
        assert main(["view", str(bad), "--seconds", "0"]) == 2
        _one_error_line(capsys)


def test_compare_keeps_runs_whose_folders_share_a_name(tmp_path, capsys):
    for parent, kind in (("x", "nn"), ("y", "no-u0")):
        assert _run(tmp_path / parent / "run", "--controller", kind) == 0
    assert run_labels([str(tmp_path / "x" / "run"), str(tmp_path / "y" / "run")]) == ["x/run", "y/run"]
    assert main(["compare", str(tmp_path / "x" / "run"), str(tmp_path / "y" / "run")]) == 0
    table = capsys.readouterr().out
    assert "x/run" in table and "y/run" in table
    with pytest.raises(NNRobustError, match="given twice"):
        run_labels([str(tmp_path / "x" / "run"), str(tmp_path / "x" / "run")])


@pytest.mark.parametrize("name", ["a\x1bb", "../../escape", "a" * 200, "", "a/b"])
def test_names_that_would_break_a_run_folder(name, tmp_path):
    with pytest.raises(ConfigError, match="not a valid name"):
        load_preset("paper-ellipse").replace(name=name)


def test_descriptions_with_control_characters_round_trip(tmp_path):
    from nnrobust.config import load_config

    config = load_preset("paper-ellipse").replace(description='tab\there "quoted" \x1b[31m\x00 back\\slash\n')
    path = tmp_path / "e.toml"
    path.write_text(config.to_toml())
    assert load_config(path).description == config.description


def test_messages_are_one_bounded_line():
    message = str(ConfigError("robot.source", "x" * 5_000_000 + "\nsecond line\x1b[2J"))
    assert len(message) <= 1000 and "\n" not in message and "\x1b" not in message
    assert "characters elided" in message and message.endswith("second line\\x1b[2J")
    assert one_line("short") == "short"


@pytest.mark.parametrize("kind", ["/dev/zero", "fifo", "huge", "deep", "bigint"])
def test_experiment_files_are_read_bounded(kind, tmp_path, capsys):
    if kind == "/dev/zero":
        target = "/dev/zero"
    elif kind == "fifo":
        target = str(tmp_path / "pipe.toml")
        os.mkfifo(target)
    elif kind == "huge":
        target = str(tmp_path / "huge.toml")
        Path(target).write_text("# padding\n" * 200_000)
    elif kind == "deep":
        target = str(tmp_path / "deep.toml")
        Path(target).write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    else:
        target = str(tmp_path / "bigint.toml")
        Path(target).write_text("[sensing]\nseed = " + "9" * 400 + "\n")
    assert main(["run", target, "--out", str(tmp_path / "out"), "--quiet"]) == 2
    line = _one_error_line(capsys)
    assert {
        "/dev/zero": "not a regular file",
        "fifo": "not a regular file",
        "huge": "larger than 1000 kB",
        "deep": "nested too deeply",
        "bigint": "integer in (-2^63, 2^63)",
    }[kind] in line


def test_runs_too_large_for_memory_are_refused_before_they_start(capsys, tmp_path):
    assert _run(tmp_path / "big", "--duration", "100000") == 2  # after QUICK's: the last one counts
    assert "simulation.memory_limit: this run needs about 211 GB" in _one_error_line(capsys)
    assert _run(tmp_path / "ok", "--set", "simulation.memory_limit=0.0001") == 2
    assert "raise memory_limit" in _one_error_line(capsys)
    for key, value, fragment in (
        ("simulation.substeps", "100000", "at most 10000"),
        ("nn.centers", "100000", "outside [1, 1000]"),
        ("simulation.control_period", "1e-12", "steps; at most"),
    ):
        assert _run(tmp_path / "x", "--set", f"{key}={value}") == 2
        assert fragment in _one_error_line(capsys)


def test_the_memory_estimate_counts_the_models_and_stops_at_what_the_machine_has(monkeypatch):
    """A long chain's Pinocchio models grow as n^3: a 150-joint chain's six copies need 0.63 GB
    (0.67 with the arrays), one copy measured by creating it; and a memory_limit above the
    machine's available memory does not let a run through."""
    from nnrobust.run import experiment

    probe = (
        "import gc, pinocchio as pin\n"
        "from nnrobust.model import load_robot\n"
        "def rss():\n"
        "    lines = open('/proc/self/status').read().splitlines()\n"
        "    return next(float(x.split()[1]) * 1e3 for x in lines if x.startswith('VmRSS'))\n"
        "robot = load_robot('planar150'); gc.collect(); before = rss()\n"
        "data = pin.Data(robot.model); print(rss() - before)\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    measured = float(done.stdout.split()[-1])  # in a fresh interpreter: no freed memory to reuse
    assert measured == pytest.approx(experiment.DATA_BYTES_PER_CUBED_JOINT * 150**3, rel=0.15)
    config = load_preset("planar7-ellipse").replace(
        robot={"source": "planar150"}, simulation={"memory_limit": 0.5, "duration": 1.0}
    )
    with pytest.raises(ConfigError, match=r"needs about 0.6\d+ GB \(1 s at 0.001 s per step, 150 joints\)"):
        experiment.build(config)
    monkeypatch.setattr(experiment, "available_memory", lambda: 1e7)  # 10 MB left
    with pytest.raises(ConfigError, match=r"this machine has 0.01 GB available"):
        experiment.build(load_preset("paper-ellipse").replace(simulation={"memory_limit": 1e6}))


UNDER_WAY = """
import sys
from pathlib import Path

from nnrobust import cli
from nnrobust.core import progress

flag, argv = Path(sys.argv[1]), sys.argv[2:]
report = progress.ProgressBar.__call__


def report_and_say(self, t, q=None):
    if t >= 0.5 and not getattr(self, "said", False):
        self.said = True
        flag.write_text(repr(t))
    return report(self, t, q)


progress.ProgressBar.__call__ = report_and_say
sys.argv = ["nnrobust", *argv]
cli.run()
"""
"""`nnrobust run` (the console entry point) that writes the file sys.argv[1] once the run has
simulated 0.5 s: the moment a test's signal is sure to find the simulation under way."""


def _wait_for(path: Path, proc, seconds: float = 120.0) -> None:
    """Until ``path`` exists; ``seconds`` is only a safety net (a child that died or hangs)."""
    deadline = time.monotonic() + seconds
    while not path.exists():
        assert proc.poll() is None, f"the run ended before {path.name}: {proc.stderr.read()}"
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.05)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_signal_mid_run_leaves_a_partial_run_marked_as_such(sig, tmp_path):
    """SIGINT, SIGTERM or SIGHUP during the simulation: exit 130 or 1 with the partial run in
    place, marked interrupted; no hidden partial folder, no lock file, no process left. The signal
    is sent once the run says it has simulated 0.5 s (it was sent 2 s after the lock file
    appeared, which on a busy machine could be before the simulation began)."""
    folder = tmp_path / "runs"
    folder.mkdir()
    out, under_way = folder / "run", tmp_path / "under-way"
    args = ["run", "paper-ellipse", "--out", str(out), "--duration", "60", "--backend", "python"]
    proc = subprocess.Popen(
        [sys.executable, "-c", UNDER_WAY, str(under_way), *args, "--no-animation"],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        _wait_for(under_way, proc)
        proc.send_signal(sig)
        code = proc.wait(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert code == 1, proc.stderr.read()
    assert _marker(out)["status"] == "interrupted"
    # the bar says t = 0.5 s at the top of step 500; a signal then keeps steps 0..499 (t = 0.499)
    assert 0.499 <= Result.load(out).t[-1] < 60
    assert sorted(p.name for p in folder.iterdir()) == ["run"]


def test_a_relative_urdf_path_is_read_from_the_experiment_files_folder(tmp_path, monkeypatch):
    from nnrobust.config import load_config
    from nnrobust.model import paper_arm_urdf

    folder = tmp_path / "experiments"
    (folder / "robots").mkdir(parents=True)
    (folder / "robots" / "arm.urdf").write_text(paper_arm_urdf().read_text())
    (folder / "e.toml").write_text('name = "rel"\n[robot]\nsource = "robots/arm.urdf"\n')
    monkeypatch.chdir(tmp_path)  # not the file's folder
    config = load_config(folder / "e.toml")
    assert config.robot.source == str((folder / "robots" / "arm.urdf").resolve())
    (folder / "f.toml").write_text('name = "rel"\n[robot]\nsource = "arm.urdf"\n')
    (tmp_path / "arm.urdf").write_text(paper_arm_urdf().read_text())  # next to the cwd: not read
    with pytest.raises(ConfigError, match=r"'arm.urdf' is not a file in .*experiments \(a relative path"):
        load_config(folder / "f.toml")


def test_config_toml_records_versions_and_the_urdf_hash_and_notices_a_change(tmp_path):
    import hashlib

    from nnrobust import __version__
    from nnrobust.config import load_config
    from nnrobust.model import paper_arm_urdf

    urdf = tmp_path / "arm.urdf"
    urdf.write_text(paper_arm_urdf().read_text())
    config = load_preset("paper-line").replace(robot={"source": str(urdf)}, simulation={"duration": 0.2})
    folder = write_run(tmp_path / "run", run_experiment(config), plots=False, animation=False)
    text = (folder / "config.toml").read_text()
    assert text.startswith(f"# written by nnrobust {__version__} (pin ")
    assert f"# urdf sha256: {hashlib.sha256(urdf.read_bytes()).hexdigest()}\n" in text
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        again = load_config(folder / "config.toml")  # unchanged: no warning
    assert again.robot.source == str(urdf)
    urdf.write_text(urdf.read_text().replace('effort="60"', 'effort="61"'))
    with pytest.warns(UserWarning, match="has changed since this run was written"):
        load_config(folder / "config.toml")


def test_planted_links_are_never_written_through(tmp_path):
    """Issue 22 item 11: symbolic links planted at the names a run writes before renaming (the
    marker's and the animation's partial files) or at its lock beside the folder are removed,
    never followed: their targets keep their content."""
    out = tmp_path / "run"
    assert _run(out, "--no-plots", "--no-animation") == 0
    victims = {
        name: tmp_path / f"victim-{i}"
        for i, name in enumerate((".nnrobust-run.partial", ".animation.html.partial"))
    }
    for name, victim in victims.items():
        victim.write_text("precious")
        (out / name).symlink_to(victim)
    lock_victim = tmp_path / "victim-lock"
    lock_victim.write_text("precious")
    (tmp_path / ".run.lock").symlink_to(lock_victim)
    assert main(["plot", str(out)]) == 0
    assert (out / "animation.html").is_file() and (out / "animation.html").stat().st_size > 10_000
    assert _run(out, "--overwrite", "--no-plots", "--no-animation") == 0
    for victim in [*victims.values(), lock_victim]:
        assert victim.read_text() == "precious", victim


def _processes_mentioning(marker: str) -> list[int]:
    """Live processes whose command line contains ``marker`` (Linux /proc)."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if marker in (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace"):
                    out.append(int(entry.name))
            except OSError:
                continue
    return out


@pytest.mark.skipif(not Path("/proc/self/cmdline").exists(), reason="reads /proc")
def test_sigterm_of_bench_leaves_no_worker_behind(tmp_path):
    """`nnrobust bench` stopped by SIGTERM while a benchmark's worker pool runs: the script and
    every worker it started are gone within seconds (they used to run on with parent pid 1)."""
    out = tmp_path / "bench-out"  # in every command line of the benchmark and of its workers
    proc = subprocess.Popen(
        [sys.executable, "-m", "nnrobust.cli", "bench", "plant_convergence", "--out", str(out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and len(_processes_mentioning(str(out))) < 3:  # script + 2 workers
        time.sleep(0.2)
    assert len(_processes_mentioning(str(out))) >= 3, "the benchmark's workers never started"
    time.sleep(1.0)
    proc.send_signal(signal.SIGTERM)
    proc.wait(timeout=60)
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline and _processes_mentioning(str(out)):
        time.sleep(0.2)
    left = _processes_mentioning(str(out))
    for pid in left:  # do not leave them to the rest of the suite
        os.kill(pid, signal.SIGKILL)
    assert not left, f"{len(left)} processes left behind"
