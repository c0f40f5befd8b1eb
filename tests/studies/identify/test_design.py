"""``nnrobust identify design``: the designed excitation is at rest where it says, keeps the limits
on a grid finer than its search's (the torque by Pinocchio's RNEA and the URDF's friction, not by
the regressor the design uses), its condition number is the one an SVD of the stacked regressor
gives, it beats random trajectories at the same limits, and its experiment file follows it.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

from nnrobust.cli import main
from nnrobust.core.exceptions import ConfigError
from nnrobust.model.loading import load_robot
from nnrobust.model.regressor import ParameterLayout, base_parameters, position_ranges
from nnrobust.studies.identify.design import DesignOptions, ExcitationProblem, design_excitation
from nnrobust.studies.identify.synthetic import FourierTrajectory

ROBOT = "three_link_planar"
OPTIONS = DesignOptions(evaluations=600, seed=3, torque_share=0.3)


@pytest.fixture(scope="module")
def arm():
    return load_robot(ROBOT, task="position")


@pytest.fixture(scope="module")
def design(arm):
    return design_excitation(arm.model, tuple(arm.model.names[1:]), OPTIONS)


def test_every_search_point_is_at_rest_at_the_start_and_each_period_end(arm):
    problem = ExcitationProblem(arm.model, OPTIONS, tuple(arm.model.names[1:]))
    rng = np.random.default_rng(0)
    period = 1 / OPTIONS.frequency
    for _ in range(5):
        trajectory = problem.trajectory(rng.normal(0, 1, problem.dimension))
        _, dq, ddq = trajectory.states(np.array([0.0, period, 3 * period]))
        scale = np.abs(trajectory.a).max()
        np.testing.assert_allclose(dq, 0.0, atol=1e-12 * scale)
        np.testing.assert_allclose(ddq, 0.0, atol=1e-11 * scale)


def test_the_design_keeps_every_limit_on_a_2_khz_grid(arm, design):
    model = arm.model
    t = np.arange(int(2000 / OPTIONS.frequency)) / 2000.0
    q, dq, ddq = design.trajectory.states(t)
    low, high = position_ranges(model)
    room = (high - low) * (0.5 - OPTIONS.position_margin)
    mid = (low + high) / 2
    assert np.all(np.abs(q - mid) <= room * (1 + 1e-9))
    assert np.all(np.abs(dq) <= OPTIONS.velocity_share * model.velocityLimit * (1 + 1e-9))
    data = model.createData()
    tau = np.array([pin.rnea(model, data, *s) for s in zip(q, dq, ddq)])
    tau += model.damping * dq + model.friction * np.sign(dq)  # the URDF's <dynamics>
    assert np.all(np.abs(tau) <= OPTIONS.torque_share * model.effortLimit * (1 + 1e-9))
    # and it uses its room: some limit is nearly reached (a design that moves little is no design)
    assert max(max(v) for v in design.peaks.values()) > 0.75


def test_the_condition_number_is_the_svd_of_the_stacked_base_regressor(arm, design):
    model = arm.model
    n = model.nv
    t = np.arange(OPTIONS.samples) / (OPTIONS.samples * OPTIONS.frequency)
    q, dq, ddq = design.trajectory.states(t)
    layout = ParameterLayout(tuple(model.names[1:]))
    base = base_parameters(model, layout.names[: 10 * n])
    data = model.createData()
    reach = round(OPTIONS.reversal_guard * OPTIONS.samples * OPTIONS.frequency)  # rows either side
    guarded = set()
    for j in range(n):  # identify's reversal guard: rows about a velocity sign change are no equations
        for f in np.flatnonzero(np.sign(dq[1:, j]) != np.sign(dq[:-1, j])) + 1:
            guarded |= {(k, j) for k in range(f - reach, f + reach)}
    rows = []
    for k in range(len(t)):
        Y = pin.computeJointTorqueRegressor(model, data, q[k], dq[k], ddq[k])[:, base.base]
        for j in range(n):
            if abs(dq[k, j]) < OPTIONS.stick_band or (k, j) in guarded:  # rows in stick neither
                continue
            friction = np.zeros(2 * n)
            friction[j], friction[n + j] = dq[k, j], np.sign(dq[k, j])
            rows.append(np.concatenate([Y[j], friction]))
    W = np.array(rows)
    W /= np.linalg.norm(W, axis=0)
    assert design.condition == pytest.approx(np.linalg.cond(W), rel=1e-8)


def test_the_design_beats_random_trajectories_at_the_same_limits(arm, design):
    problem = ExcitationProblem(arm.model, OPTIONS, tuple(arm.model.names[1:]))
    rng = np.random.default_rng(11)
    conditions = []
    for _ in range(10):
        trajectory = problem.random_at_limits(rng)
        peak = max(float(np.nanmax(v)) for v in problem.check(trajectory).values())
        assert 0.99 <= peak <= 1.0
        q, dq, ddq = trajectory.states(problem.sample_times)
        conditions.append(problem.condition(problem.regressor(q, dq, ddq), dq))
    assert design.condition < min(conditions) and design.condition < 0.6 * np.median(conditions)
    assert design.condition < design.start_condition


def test_the_command_writes_an_experiment_that_follows_the_joint_trajectory(tmp_path, capsys):
    from nnrobust.config import load_config
    from nnrobust.run.experiment import build

    out = tmp_path / "traj.toml"
    argv = [
        "identify",
        "design",
        "--robot",
        ROBOT,
        "--out",
        str(out),
        "--evaluations",
        "200",
        "--periods",
        "1",
    ]
    assert main(argv) == 0
    assert "condition number" in capsys.readouterr().out
    record = json.loads(out.with_suffix(".json").read_text())
    trajectory = FourierTrajectory(
        np.array(record["q0"]), np.array(record["a"]), np.array(record["b"]), record["frequency"]
    )
    config = load_config(out)
    assert config.robot.task == "planar" and config.plant.disturbance == "none"  # every torque logged
    assert config.simulation.duration == pytest.approx(record["period"])
    experiment = build(config)
    robot = experiment.robot
    t = np.linspace(0.0, record["period"], 37)
    q, dq, ddq = trajectory.states(t)
    x_d = np.array([experiment.trajectory(tk)[0] for tk in t])
    np.testing.assert_allclose(x_d, [robot.task_position(qk) for qk in q], atol=1e-9)
    # between waypoints too: the spline's velocity is J q' to the spacing's fourth order
    tk = 1.2345
    qk, dqk, _ = trajectory.states(np.array([tk]))
    v = experiment.trajectory(tk)[1]
    np.testing.assert_allclose(v, robot.task_jacobian(qk[0]) @ dqk[0], atol=1e-5)
    np.testing.assert_allclose(experiment.q0, q[0], atol=1e-9)  # starts at rest where the design does
    assert main(argv) == 2  # an existing design is kept unless --overwrite
    assert "--overwrite" in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra, named",
    [
        (["--harmonics", "1"], "--harmonics"),
        (["--velocity-share", "0"], "--velocity-share"),
        (["--friction", "viscous,stribeck"], "--friction"),
        (["--periods", "0"], "--periods"),
    ],
)
def test_bad_options_get_one_line_naming_the_option(tmp_path, capsys, extra, named):
    argv = ["identify", "design", "--robot", ROBOT, "--out", str(tmp_path / "t.toml"), *extra]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert named in err and len(err.strip().splitlines()) == 1


def test_an_out_file_that_is_not_toml_is_refused(tmp_path, capsys):
    assert main(["identify", "design", "--robot", ROBOT, "--out", str(tmp_path / "t.json")]) == 2
    assert ".toml" in capsys.readouterr().err


def test_a_joint_without_a_velocity_limit_needs_max_velocity(arm):
    model = pin.Model(arm.model)
    model.velocityLimit[1] = 0.0
    with pytest.raises(ConfigError, match="max-velocity.*joint2"):
        ExcitationProblem(model, OPTIONS, tuple(model.names[1:]))
    problem = ExcitationProblem(model, DesignOptions(max_velocity=2.0), tuple(model.names[1:]))
    assert problem.velocity_limit[1] == pytest.approx(0.8 * 2.0)
