"""Every script in examples/ runs as a user runs it (a fresh interpreter, from the repository
root), on short settings, and prints what it promises."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def _run(script: str, *args: str) -> str:
    done = subprocess.run([sys.executable, str(EXAMPLES / script), *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def test_every_example_is_tested():
    tested = {"custom_controller.py", "custom_robot.py", "sweep.py", "read_results.py", "tuning.py"}
    assert {p.name for p in EXAMPLES.glob("*.py")} == tested


def test_custom_controller_runs_beside_the_nn(tmp_path):
    out = _run("custom_controller.py", "--duration", "2.5", "--out", str(tmp_path))
    assert "TaskPD" in out and "nn" in out
    assert (tmp_path / "paper-ellipse-TaskPD" / "result.npz").is_file()
    assert 'class = "' + str(EXAMPLES / "custom_controller.py") + ':TaskPD"' in (
        tmp_path / "paper-ellipse-TaskPD" / "config.toml").read_text()


def test_custom_robot_then_sweep_then_pandas(tmp_path):
    out = _run("custom_robot.py", "--duration", "2.5", "--out", str(tmp_path))
    assert "n = 4, task frame 'tool'" in out and "status completed" in out
    out = _run("sweep.py", "--samples", "2", "--duration", "2.2", "--out", str(tmp_path / "sweep"))
    assert "taskpd" in out and "rerun the worst taskpd sample: nnrobust run paper-ellipse --controller" in out
    out = _run("read_results.py", "--sweep", str(tmp_path / "sweep"), "--run", str(tmp_path / "four-link-nn"))
    assert "6 rows" in out and "the NN compensator is best on" in out and "status completed" in out


@pytest.mark.filterwarnings("ignore")
def test_tuning_reports_each_best_setting(tmp_path):
    out = _run("tuning.py", "--budget", "4", "--out", str(tmp_path / "tune"))
    assert "pd: train" in out and "no-u0: train" in out
    assert (tmp_path / "tune" / "summary.json").is_file()
