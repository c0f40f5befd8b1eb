"""Every script in examples/ runs as a user runs it (a fresh interpreter, from the repository
root), on short settings, and prints what it promises."""

import subprocess
import sys
from pathlib import Path

import pytest

from nnrobust.run import compiled

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"


def _run(script: str, *args: str) -> str:
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / script), *args], cwd=ROOT, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def test_every_example_is_tested():
    tested = {
        "classics.py",
        "custom_controller.py",
        "custom_robot.py",
        "disturbances.py",
        "sweep.py",
        "read_results.py",
        "tuning.py",
        "slotine_li.toml",
        "controllers/slotine_li.py",
        "study.toml",  # tests/studies/study/test_engine.py, its budgets cut down
        "train_policy.py",
        "synthetic_log.py",  # tests/studies/identify/test_walkthrough.py, with the two below
        "identified.toml",
        "identified_study.toml",
    }
    assert {str(p.relative_to(EXAMPLES)) for p in EXAMPLES.rglob("*.py")} | {
        p.name for p in EXAMPLES.glob("*.toml")
    } == tested


def test_disturbances_compares_each_load_with_the_quiet_run():
    out = _run("disturbances.py", "--duration", "4", "--controller", "pd")
    for event in ("push", "tap", "hand", "parcel", "square wave"):
        assert event in out
    rows = [line.split() for line in out.splitlines() if line.startswith(("push", "hand"))]
    assert all(float(row[-1]) != float(row[-2]) for row in rows)  # the loads acted


def test_classics_run_beside_the_nn_on_the_compiled_loop():
    out = _run("classics.py", "--duration", "2.5")
    rows = [line.split() for line in out.splitlines()[1:]]
    assert [(r[0], r[1]) for r in rows] == [
        (preset, law)
        for preset in ("paper-ellipse", "panda-ellipse")
        for law in ("nn", "sliding-mode", "no-u0", "slotine-li", "rbf-nn")
    ]
    loops = {r[-2] for r in rows}
    assert loops == ({"compiled"} if compiled.available() else {"python"}) and all(
        r[-1] == "(completed)" for r in rows
    )


def test_custom_controller_runs_beside_the_nn(tmp_path):
    out = _run("custom_controller.py", "--duration", "2.5", "--out", str(tmp_path))
    assert "TaskPD" in out and "nn" in out
    assert (tmp_path / "paper-ellipse-TaskPD" / "result.npz").is_file()
    assert (
        'class = "' + str(EXAMPLES / "custom_controller.py") + ':TaskPD"'
        in (tmp_path / "paper-ellipse-TaskPD" / "config.toml").read_text()
    )


def test_custom_robot_then_sweep_then_pandas(tmp_path):
    out = _run("custom_robot.py", "--duration", "2.5", "--out", str(tmp_path))
    assert "n = 4, task frame 'tool'" in out and "status completed" in out
    out = _run("sweep.py", "--samples", "2", "--duration", "2.2", "--out", str(tmp_path / "sweep"))
    assert "taskpd" in out and "rerun the worst taskpd sample: nnrobust run paper-ellipse --controller" in out
    out = _run("read_results.py", "--sweep", str(tmp_path / "sweep"), "--run", str(tmp_path / "four-link-nn"))
    assert "6 rows" in out and "the NN compensator is best on" in out and "status completed" in out


@pytest.mark.filterwarnings("ignore")
def test_slotine_li_regressor_is_m_qddr_plus_christoffel_c_qdr_plus_g():
    """examples/controllers/slotine_li.py, written by someone else from docs/extending.md: its
    exact regressor Y(q, q', q'_r, q''_r) theta is M q''_r + C(q, q') q'_r + g with Pinocchio's
    own Coriolis matrix (the one with M' - 2C skew), on the Panda at random states."""
    import numpy as np
    import pinocchio as pin

    from nnrobust.config import load_config
    from nnrobust.run.experiment import build

    with pytest.warns(UserWarning, match="T\\*lambda_max"):  # its explicit wrist gain is near the limit
        setup = build(load_config(EXAMPLES / "slotine_li.toml").replace(simulation={"duration": 0.1}))
    law, model = setup.controller, setup.nominal.pinocchio_model
    data, rng = model.createData(), np.random.default_rng(0)
    theta = law.initial_state()
    for _ in range(5):
        q = pin.randomConfiguration(model)
        v, v_r, a_r = (rng.normal(size=model.nv) for _ in range(3))
        upper = pin.crba(model, data, q).copy()  # the upper triangle of M
        M = np.triu(upper) + np.triu(upper, 1).T
        C = pin.computeCoriolisMatrix(model, data, q, v)
        expected = M @ a_r + C @ v_r + pin.computeGeneralizedGravity(model, data, q)
        np.testing.assert_allclose(law.regressor_matrix(q, v, v_r, a_r) @ theta, expected, atol=1e-9)


def test_slotine_li_runs_from_its_experiment_file(tmp_path):
    import json

    from nnrobust.cli import main

    run = tmp_path / "run"
    assert (
        main(
            [
                "run",
                str(EXAMPLES / "slotine_li.toml"),
                "--duration",
                "2.5",
                "--out",
                str(run),
                "--quiet",
                "--no-plots",
                "--no-animation",
            ]
        )
        == 0
    )
    metrics = json.loads((run / "metrics.json").read_text())
    assert metrics["status"] == "completed" and metrics["rms_error_after_2s"] < 1e-3
    assert metrics["backend"] in ("hybrid", "python")


def test_tuning_reports_each_best_setting(tmp_path):
    short = tmp_path / "short.toml"  # the default target, paper-line, shortened to 3 s
    short.write_text('base = "paper-line"\nname = "short"\n[simulation]\nduration = 3.0\n')
    out = _run("tuning.py", "--budget", "4", "--target", str(short), "--out", str(tmp_path / "tune"))
    assert "pd: train" in out and "no-u0: train" in out and "TaskPD: train" in out
    assert (tmp_path / "tune" / "summary.json").is_file()


@pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())
def test_train_policy_writes_a_policy_and_its_record(tmp_path):
    pytest.importorskip("gymnasium")
    pytest.importorskip("onnx")
    out = _run(
        "train_policy.py", "--only", "residual", "--generations", "1", "--population", "2",
        "--episodes", "1", "--duration", "0.2", "--out", str(tmp_path),
    )  # fmt: skip
    assert "residual: 3 simulations of 0.2 s" in out
    assert (tmp_path / "residual.onnx").stat().st_size > 0 and (tmp_path / "residual.onnx.json").is_file()
