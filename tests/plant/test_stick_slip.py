"""Coulomb friction and stiction integrated as stick-slip: exact stops, holds and breakaways."""

import numpy as np
import pytest

from nnrobust import load_robot
from nnrobust.config.presets import load_preset
from nnrobust.model.planar_chain import planar_chain_urdf
from nnrobust.plant import Friction, Plant, SinusoidalDisturbance
from nnrobust.plant.stick_slip import settle
from nnrobust.run import compiled
from nnrobust.run.simulation import simulate
from tests.problems import ConstantTorque, paper_robot

FD, FC = 0.3, 0.8
"""Viscous [N m s/rad] and Coulomb [N m] friction of the one-link arm."""


def one_link(static=None):
    robot = load_robot(planar_chain_urdf(1, lengths=0.5, masses=2.0))
    plant = Plant(robot, Friction([FD], [FC], static=static), SinusoidalDisturbance.none(1))
    return plant, robot.mass(np.zeros(1))[0, 0]


@pytest.mark.parametrize("substeps", [1, 3])
@pytest.mark.parametrize("tau", [0.0, 0.5])
def test_a_sliding_joint_stops_when_the_analytic_solution_does_and_stays(tau, substeps):
    """I v' = tau - F_d v - F_c from v0 > 0: v = (v0 + c) e^(-F_d t / I) - c with c = (F_c - tau) / F_d,
    which reaches 0 at t* = (I / F_d) ln(1 + F_d v0 / (F_c - tau)); then tau < F_c holds the joint.
    The recorded velocity is exactly 0 after t* (a fixed step across sgn left it chattering at
    about F_c h / I) and q stops where the solution does (to 1e-12 rad)."""
    plant, inertia = one_link()
    v0 = 2.0
    trace = simulate(plant, ConstantTorque([tau]), np.zeros(1), np.array([v0]), 2.0, substeps=substeps)
    c = (FC - tau) / FD
    t_stop = inertia / FD * np.log(1 + v0 / c)
    q_stop = (v0 + c) * inertia / FD * (1 - np.exp(-FD * t_stop / inertia)) - c * t_stop
    moving = trace.t < t_stop
    v_exact = (v0 + c) * np.exp(-FD * trace.t[moving] / inertia) - c
    np.testing.assert_allclose(trace.dq[moving, 0], v_exact, atol=1e-11)
    assert np.all(trace.dq[~moving] == 0.0)
    np.testing.assert_allclose(trace.q[~moving, 0], q_stop, atol=1e-12)
    assert trace.friction_events == 1


@pytest.mark.parametrize("static", [None, [1.2]])
def test_a_joint_at_rest_is_held_up_to_the_static_level_and_then_slides_on_the_coulomb_level(static):
    """From rest, a torque below F_s never moves the joint; above it the joint accelerates at
    exactly (tau - F_c - F_d v) / I: the slide follows the analytic solution to 1e-11."""
    plant, inertia = one_link(static)
    level = FC if static is None else static[0]
    held = simulate(plant, ConstantTorque([0.999 * level]), np.zeros(1), np.zeros(1), 0.5)
    assert np.all(held.q == 0.0) and np.all(held.dq == 0.0)
    tau = 1.01 * level
    slide = simulate(plant, ConstantTorque([tau]), np.zeros(1), np.zeros(1), 0.5)
    c = (tau - FC) / FD
    np.testing.assert_allclose(slide.dq[:, 0], c * (1 - np.exp(-FD * slide.t / inertia)), atol=1e-11)


def test_without_coulomb_friction_a_joint_at_rest_moves():
    """The hold comes from the dry friction alone: with F_c = 0 the same small torque moves it."""
    robot = load_robot(planar_chain_urdf(1, lengths=0.5, masses=2.0))
    plant = Plant(robot, Friction([FD], [0.0]), SinusoidalDisturbance.none(1))
    trace = simulate(plant, ConstantTorque([0.5]), np.zeros(1), np.zeros(1), 0.2)
    assert trace.dq[-1, 0] > 0.1 and trace.friction_events == 0


def test_settled_modes_hold_within_the_static_level_on_the_coupled_arm():
    """On the paper's arm at rest under random torques, every held joint needs at most F_s, every
    released joint needed more, and a released joint accelerates the way it slides."""
    robot = paper_robot()
    plant = Plant(
        robot,
        Friction(robot.viscous_friction, [1.0, 1.0, 1.0], static=[1.5, 1.5, 1.5]),
        SinusoidalDisturbance.none(3),
    )
    rng = np.random.default_rng(3)
    seen = set()
    for _ in range(200):
        q, v = rng.uniform(-2, 2, 3), np.zeros(3)
        tau = rng.uniform(-2.5, 2.5, 3)
        mode = settle(plant, 0.0, q, v, tau, np.zeros(3, int))
        a, hold = plant.constrained_acceleration(0.0, q, v, tau, mode)
        held = mode == 0
        assert np.all(np.abs(hold) <= 1.5 + 1e-12)
        assert np.all(a[held] == 0.0)
        assert np.all(a[~held] * mode[~held] > 0)
        seen.add(int(held.sum()))
    assert seen == {0, 1, 2, 3}  # the draws cover every number of held joints


def test_the_held_friction_is_what_balances_the_arm():
    """With joints held, M q'' + N + F = tau: the returned holding torque closes the balance."""
    robot = paper_robot()
    plant = Plant(robot, Friction(robot.viscous_friction, [1.0, 1.0, 1.0]), SinusoidalDisturbance.none(3))
    q, v, tau = np.array([0.3, 1.0, -0.8]), np.array([0.4, 0.0, 0.0]), np.array([0.2, 0.3, -0.1])
    mode = np.array([1, 0, 0])
    a, hold = plant.constrained_acceleration(0.0, q, v, tau, mode)
    friction = np.array([robot.viscous_friction[0] * v[0] + 1.0, *hold])
    np.testing.assert_allclose(robot.mass(q) @ a + robot.bias(q, v) + friction, tau, atol=1e-12)
    assert a[1] == a[2] == 0.0


def test_static_friction_below_coulomb_is_refused():
    with pytest.raises(ValueError, match="static level"):
        Friction([0.1], [1.0], static=[0.5])


@pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())
def test_the_plant_step_is_converged_for_a_chattering_controller():
    """A stiff sliding mode on paper-ellipse (the case where a fixed step across sgn made 10 x the
    chatter): 1 and 16 plant steps per period agree within 2 % in RMS torque, 10 % in chatter.
    On the compiled loop; the Python loop takes the same steps (tests/run/test_compiled.py compares
    the two step by step, speed-adaptive cuts included)."""
    config = load_preset("paper-ellipse").replace(
        controller={
            "kind": "sliding-mode",
            "Kp": [1e4],
            "Kv": [200.0],
            "sliding_gain": 40.0,
            "sliding_boundary": 5.0,
        },
        simulation={"duration": 3.0, "backend": "compiled"},
    )
    from nnrobust.run.experiment import run_experiment

    coarse, fine = (run_experiment(config.replace(simulation={"substeps": s})).metrics() for s in (1, 16))
    assert coarse["rms_torque"] == pytest.approx(fine["rms_torque"], rel=0.02)
    assert coarse["torque_chatter"] == pytest.approx(fine["torque_chatter"], rel=0.10)
    assert coarse["rms_error_after_2s"] == pytest.approx(fine["rms_error_after_2s"], rel=0.02)
