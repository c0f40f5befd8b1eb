"""``nnrobust identify`` end to end: a CSV log, a run folder, the folder it writes, and the
identified model as an experiment's nominal model."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

pytest.importorskip("cvxpy")
pytest.importorskip("pyarrow")

from nnrobust.cli import main  # noqa: E402
from nnrobust.model.identified import IdentifiedModel, read_identified  # noqa: E402
from nnrobust.model.loading import load_robot  # noqa: E402
from nnrobust.model.perturbation import perturb_inertias  # noqa: E402
from nnrobust.plant.friction import Friction  # noqa: E402
from nnrobust.studies.identify.synthetic import (  # noqa: E402
    FourierTrajectory,
    SensorFaults,
    synthetic_log,
    write_csv,
)


def _write_csv(path, log, joints, named=False):
    write_csv(log, path, joints, named)


@pytest.fixture(scope="module")
def paper_log(tmp_path_factory):
    """A 30 s log of a paper arm whose masses are 20 % off the URDF's, with friction, noise,
    quantisation, jittered stamps and 2 % stale samples."""
    folder = tmp_path_factory.mktemp("log")
    model = load_robot("three_link_planar").model
    true = perturb_inertias(model, relative_error=0.2, seed=3)
    friction = Friction(np.full(3, 0.1), np.full(3, 0.2))
    faults = SensorFaults(torque_noise=0.02, torque_quantum=0.001, jitter=5e-5, stale=0.02)
    log = synthetic_log(
        true, FourierTrajectory.random(model, seed=4, speed=1.5), 30.0, friction=friction, faults=faults
    )
    _write_csv(folder / "log.csv", log, model.names[1:], named=True)
    return folder / "log.csv", true, friction


def test_identify_writes_a_model_that_runs_as_the_nominal(paper_log, tmp_path, capsys):
    path, true, friction = paper_log
    out = tmp_path / "identified"
    assert main(["identify", str(path), "--robot", "three_link_planar", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "physical: yes" in printed and "joint3" in printed
    summary = json.loads((out / "identification.json").read_text())
    assert summary["log"]["stale_samples"] > 0 and summary["identifiability"]["unexcited"] == []
    assert summary["checks"]["physical"] and summary["log"]["files"][str(path)]
    page = (out / "report.html").read_text()  # self-contained: torque, residual shares, friction
    assert page.count('src="data:image/png;base64,') == 3 and "Held-out torque" in page
    assert f"{summary['identifiability']['condition_number']:.4g}" in page
    assert all(p["name"] in page for p in summary["parameters"][:5])
    held = np.array(summary["residuals"]["physical"]["held_out_rms"])
    assert np.all(held < 1.2 * 0.02 * 1.0)  # the noise floor (interpolation only lowers it)
    assert np.all(held < 0.2 * np.array(summary["residuals"]["urdf"]["held_out_rms"]))
    model = read_identified(out / "nominal.json")
    assert np.allclose(model.viscous, friction.viscous, atol=0.01)
    assert np.allclose(model.coulomb, friction.coulomb, atol=0.02)
    # the parameters' table has a row per base parameter and friction term, with its interval
    lines = (out / "parameters.csv").read_text().splitlines()
    assert len(lines) == 1 + 7 + 6 and lines[0] == "name,least_squares,standard_error,low,high,physical"
    region = summary["confidence"]
    assert region["level"] == 0.95 and np.array(region["covariance"]).shape == (13, 13)
    assert not all(region["white"]) and "sandwich" in region["method"]  # resampled stale samples
    for row in summary["parameters"]:
        assert row["low"] < row["least_squares"] < row["high"]
    # a second identification into the folder is refused; --overwrite replaces it
    assert main(["identify", str(path), "--robot", "three_link_planar", "--out", str(out), "--quiet"]) == 2
    assert "holds an identification already" in capsys.readouterr().err
    assert (
        main(
            [
                "identify",
                str(path),
                "--robot",
                "three_link_planar",
                "--out",
                str(out),
                "--quiet",
                "--overwrite",
            ]
        )
        == 0
    )
    # and the model is an experiment's nominal model, its file's digest in the run's record
    experiment = tmp_path / "experiment.toml"
    experiment.write_text(
        'base = "paper-ellipse"\n[simulation]\nduration = 1.0\n'
        '[nominal]\nkind = "identified"\nfile = "identified/nominal.json"\n'
    )
    run = tmp_path / "run"
    assert main(["run", str(experiment), "--out", str(run), "--no-plots", "--no-animation", "--quiet"]) == 0
    assert "# identified model sha256: " in (run / "config.toml").read_text()


def test_an_identified_model_of_the_urdfs_own_bodies_runs_as_the_urdf(tmp_path):
    """The same bodies and no friction: kind = 'identified' is kind = 'urdf' to the last bit."""
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import run_experiment

    robot = load_robot("panda", task="position")
    n = robot.nq
    own = IdentifiedModel(
        "panda",
        tuple(robot.model.names[1:]),
        tuple(robot.model.inertias[j] for j in range(1, n + 1)),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
        np.zeros(n),
    )
    path = tmp_path / "nominal.json"
    path.write_text(json.dumps(own.to_dict()))
    config = load_preset("panda-ellipse").replace(simulation={"duration": 0.5})
    urdf = run_experiment(config.replace(nominal={"kind": "urdf"}))
    identified = run_experiment(config.replace(nominal={"kind": "identified", "file": str(path)}))
    assert np.array_equal(urdf.tau, identified.tau) and np.array_equal(urdf.q, identified.q)


def test_a_run_folder_is_a_log(tmp_path):
    """A simulated run read back as a log: its torque held over each period (half a period late)."""
    from nnrobust.studies.identify.logs import read_log

    run = tmp_path / "run"
    assert (
        main(
            [
                "run",
                "paper-ellipse",
                "--out",
                str(run),
                "--set",
                "simulation.duration=2",
                "--no-plots",
                "--no-animation",
                "--quiet",
            ]
        )
        == 0
    )
    log = read_log([run], ("joint1", "joint2", "joint3"))
    assert log.samples > 1000 and log.dq is not None
    assert log.torque_lag == pytest.approx(0.5 * (log.t[1] - log.t[0]))


def test_armature_is_identified_where_a_log_can_separate_it(tmp_path):
    """--armature on the paper arm: joint1's rotor inertia is one with the links' about its fixed
    axis (held at the URDF's value, said), joint2's and joint3's are identified from the log."""
    model = load_robot("three_link_planar").model
    true = pin.Model(model)
    true.armature = np.array([0.0, 0.04, 0.02])
    log = synthetic_log(true, FourierTrajectory.random(model, seed=4, speed=1.5), 20.0,
                        faults=SensorFaults(torque_noise=0.005))  # fmt: skip
    path = tmp_path / "log.csv"
    _write_csv(path, log, model.names[1:], named=True)
    out = tmp_path / "identified"
    code = main(["identify", str(path), "--robot", "three_link_planar", "--out", str(out), "--armature",
                 "--friction", "viscous", "--quiet"])  # fmt: skip
    assert code == 0
    summary = json.loads((out / "identification.json").read_text())
    assert summary["identifiability"]["armature_held"] == ["joint1"]
    names = [p["name"] for p in summary["parameters"]]
    assert "armature@joint1" not in names and {"armature@joint2", "armature@joint3"} <= set(names)
    identified = read_identified(out / "nominal.json")
    np.testing.assert_allclose(identified.armature[1:], [0.04, 0.02], atol=4e-3)
    assert identified.armature[0] == 0.0  # the URDF's
