"""The honest plant: torque saturation, joint stops, sensing and delay."""

from pathlib import Path

import numpy as np
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.controllers import ControlOutput
from nnrobust.plant import Friction, JointStops, Plant, Sensor, SinusoidalDisturbance, saturate
from nnrobust.run.experiment import build, run_experiment
from nnrobust.run.simulation import simulate
from tests.problems import ConstantTorque, paper_robot


class Recorder:
    """A controller that commands tau = [t, 2t, 3t] and keeps every measurement it is given."""

    state_size = 0
    signal_names = ()

    def __init__(self):
        self.measured = []

    def initial_state(self):
        return np.zeros(0)

    def compute(self, t, q, v, z, period=0.0):
        self.measured.append((q.copy(), v.copy()))
        return ControlOutput(np.array([t, 2 * t, 3 * t]), {})


def _free_plant(**kwargs):
    robot = paper_robot()
    return Plant(robot, Friction.none(3), SinusoidalDisturbance.none(3), **kwargs)


def test_saturation_clips_each_joint_to_its_limit():
    limit = np.array([60.0, 40.0, 20.0])
    np.testing.assert_array_equal(saturate(np.array([100.0, -50.0, 5.0]), limit), [60.0, -40.0, 5.0])
    np.testing.assert_array_equal(saturate(np.array([1e9, 0, 0]), np.array([np.inf, 1, 1])), [1e9, 0, 0])
    assert saturate(np.array([1e9]), None)[0] == 1e9


def test_applied_torque_never_exceeds_the_limit_and_the_command_is_recorded():
    """A constant command above the limits: tau is the clipped command, tau_cmd the command."""
    limit = np.array([1.0, 0.5, 0.2])
    plant = _free_plant(torque_limit=limit)
    trace = simulate(plant, ConstantTorque([3.0, -2.0, 0.1]), np.zeros(3) + 0.5, np.zeros(3), 0.2)
    np.testing.assert_array_equal(trace.tau_cmd, np.tile([3.0, -2.0, 0.1], (trace.t.size, 1)))
    np.testing.assert_array_equal(trace.tau, np.tile([1.0, -0.5, 0.1], (trace.t.size, 1)))


@pytest.mark.parametrize("preset", ["paper-ellipse", "paper-line"])
def test_a_paper_run_stays_within_the_effort_limits(preset):
    """With saturation on (the default) the applied torque of the paper's runs never exceeds the
    URDF's effort limits, even where the command does (paper's law, no leakage)."""
    config = load_preset(preset).replace(simulation={"duration": 6.0}, nn={"sigma": 0.0, "eps_min": 0.0})
    result = run_experiment(config)
    limit = np.array([60.0, 40.0, 20.0])
    assert np.all(np.abs(result.tau) <= limit + 1e-12)
    over = np.any(np.abs(result.tau_cmd) > limit, axis=1)
    assert result.metrics()["saturated_fraction"] == pytest.approx(np.mean(over))


@pytest.mark.parametrize("engine", ["pinocchio", "mujoco"])
def test_an_effort_limit_of_zero_is_said_to_be_no_limit(tmp_path, engine):
    """<limit effort="0"> is read as no limit, as a joint without one (a limit of 0 would hold the
    joint still), on both engines; it was silent, and now a warning names the joint."""
    from nnrobust import paper_arm_urdf

    urdf = tmp_path / "arm.urdf"
    urdf.write_text(Path(paper_arm_urdf()).read_text().replace('effort="60"', 'effort="0"', 1))
    if engine == "mujoco":
        pytest.importorskip("mujoco")
    config = load_preset("paper-ellipse").replace(
        robot={"source": str(urdf)}, plant={"engine": engine}, simulation={"duration": 0.05}
    )
    with pytest.warns(
        UserWarning, match=r"joint 'joint1' of .*arm\.urdf gives <limit effort=\"0\">, read as"
    ):
        setup = build(config)
    np.testing.assert_array_equal(setup.plant.torque_limit, [np.inf, 40.0, 20.0])


def _stop_run(alpha, duration=0.4, period=5e-5, ring=False):
    """Joint 2 thrown at 4 rad/s into its stop at +2.8 rad; frictionless, no input. ``ring``: the
    stops know their ring frequencies, so the adaptive step resolves the contact (as built)."""
    from nnrobust.run.experiment import stop_rings

    robot = paper_robot()
    stops = JointStops(robot.lower_limits, robot.upper_limits, np.full(3, 2000.0), alpha)
    plant = _free_plant(stops=stops)
    q0, v0 = np.array([0.0, 2.6, 0.0]), np.array([0.0, 4.0, 0.0])
    if ring:
        stop_rings(plant, q0)
    trace = simulate(plant, ConstantTorque(np.zeros(3)), q0, v0, duration, control_period=period)
    return plant, trace


def test_an_elastic_stop_conserves_energy():
    """alpha = 0: the stop is a spring; kinetic + stop energy is conserved through the impact.

    Away from contact RK4 conserves it to round-off. The stop force is continuous but its slope
    jumps at contact, so the steps that cross it lose RK4's order: the impact's energy error is
    8.4e-4 of E at the default 1 ms step (a gain), 7.5e-6 at 0.2 ms and 3.7e-6 at 0.05 ms,
    shrinking with the step (docs/plant.md).
    """
    drift = {}
    for period in (1e-3, 2e-4, 5e-5):
        plant, trace = _stop_run(alpha=0.0, period=period)
        E = np.array([plant.energy(q, v) for q, v in zip(trace.q, trace.dq)])
        contact = np.flatnonzero(trace.q[:, 1] > 2.8)
        assert contact.size > 10  # it did hit the stop
        assert np.abs(E[: contact[0]] - E[0]).max() < 1e-9 * E[0]
        assert trace.q[-1, 1] < 2.8  # it bounced back
        drift[period] = abs(E[-1] - E[0]) / E[0]
    assert drift[5e-5] < 1e-5
    assert drift[1e-3] < 2e-3  # the documented bound at the default step
    assert drift[1e-3] > 10 * drift[2e-4] > 15 * drift[5e-5]  # converges as the step shrinks


def test_the_adaptive_step_resolves_a_contact_at_the_default_period():
    """With the stops' ring frequencies known (as every built experiment has them), a period in
    which a joint is at its stop, or would reach it, is cut so that one step turns the stop's
    oscillation by at most simulation.max_step_rotation: the elastic impact at 1 ms then keeps
    its energy to 2.6e-6 of E (8.2e-4 with the fixed step; 3.7e-6 at a fixed 0.05 ms), and only
    the periods near the contact are cut."""
    plant, fixed = _stop_run(alpha=0.0, period=1e-3)
    plant, cut = _stop_run(alpha=0.0, period=1e-3, ring=True)
    omega = plant.stops.ring[1]
    assert omega == pytest.approx(
        np.sqrt(2000.0 * np.linalg.inv(plant.model.mass(np.array([0, 2.6, 0])))[1, 1])
    )
    drift = {}
    for name, trace in (("fixed", fixed), ("cut", cut)):
        E = np.array([plant.energy(q, v) for q, v in zip(trace.q, trace.dq)])
        drift[name] = abs(E[-1] - E[0]) / E[0]
    assert drift["fixed"] > 5e-4 and drift["cut"] < 5e-6
    stops = plant.stops
    beyond = np.maximum(cut.q - stops.upper, stops.lower - cut.q)
    near = np.any(beyond + np.abs(cut.dq) * 1e-3 > 0, axis=1)
    fast = np.abs(cut.dq).max(axis=1) * 1e-3 > 0.02  # the speed rule's cuts
    assert near[1:].sum() > 10 and cut.refined_periods == np.sum((near | fast)[:-1])


def test_a_damped_stop_only_dissipates_and_holds_the_joint():
    """alpha > 0: energy never increases, the impact removes some, and the joint stays near the limit."""
    plant, trace = _stop_run(alpha=1.0)
    E = np.array([plant.energy(q, v) for q, v in zip(trace.q, trace.dq)])
    assert np.all(np.diff(E) <= 1e-9 * E[0])
    assert E[-1] < 0.9 * E[0]
    # energy bound on the penetration: K delta^2 / 2 <= E(0)
    assert trace.q[:, 1].max() - 2.8 <= np.sqrt(2 * E[0] / 2000.0)
    assert trace.q[-1, 1] < 2.8  # bounced back


def test_stop_torque_is_continuous_and_points_back():
    stops = JointStops(np.array([-1.0]), np.array([1.0]), np.array([100.0]), 0.5)
    assert stops.torque(np.array([1.0]), np.array([5.0]))[0] == 0.0  # zero at contact
    assert stops.torque(np.array([1.01]), np.array([0.0]))[0] == pytest.approx(-1.0)
    assert stops.torque(np.array([-1.01]), np.array([0.0]))[0] == pytest.approx(1.0)
    # leaving fast: the damping would pull, the clamp keeps it at zero
    assert stops.torque(np.array([1.01]), np.array([-10.0]))[0] == 0.0
    assert stops.torque(np.array([0.3]), np.array([10.0]))[0] == 0.0


def test_delay_applies_the_command_computed_d_periods_earlier():
    """tau_cmd[k] is the command of step k - d (the first command before that)."""
    for d in (0, 1, 3):
        plant = _free_plant(delay=d)
        trace = simulate(plant, Recorder(), np.full(3, 0.5), np.zeros(3), 0.01)
        computed_at = np.maximum(np.arange(trace.t.size) - d, 0) * 1e-3
        np.testing.assert_allclose(trace.tau_cmd[:, 0], computed_at, atol=1e-15)


def test_sensor_noise_has_the_asked_standard_deviation_and_is_seeded():
    plant = _free_plant(sensor=Sensor(np.full(3, 1e-3), np.full(3, 0.02), np.zeros(3), seed=4))
    rec = Recorder()
    trace = simulate(plant, rec, np.full(3, 0.5), np.zeros(3), 2.0)
    dq = np.array([m[0] for m in rec.measured]) - trace.q
    dv = np.array([m[1] for m in rec.measured]) - trace.dq
    np.testing.assert_allclose(dq.std(axis=0), 1e-3, rtol=0.1)
    np.testing.assert_allclose(dv.std(axis=0), 0.02, rtol=0.1)
    assert np.abs(dq.mean()) < 1e-4
    again = Recorder()
    simulate(
        _free_plant(sensor=Sensor(np.full(3, 1e-3), np.full(3, 0.02), np.zeros(3), seed=4)),
        again,
        np.full(3, 0.5),
        np.zeros(3),
        2.0,
    )
    np.testing.assert_array_equal(rec.measured[-1][0], again.measured[-1][0])


def test_encoder_quantisation_rounds_to_whole_counts():
    res = 2 * np.pi / 4096
    plant = _free_plant(sensor=Sensor(np.zeros(3), np.zeros(3), np.full(3, res)))
    rec = Recorder()
    trace = simulate(plant, rec, np.array([0.5, 0.3, -0.2]), np.array([0.3, -0.2, 0.1]), 0.5)
    q_m = np.array([m[0] for m in rec.measured])
    np.testing.assert_allclose(q_m / res, np.round(q_m / res), atol=1e-9)
    assert np.abs(q_m - trace.q).max() <= res / 2 + 1e-12


def test_noise_comes_before_the_encoder_so_measurements_stay_on_its_grid():
    """q_m = Q(q + n_q): with noise larger than a count, every measurement is still a whole number
    of counts, and the noise shows (rounding first and adding noise after leaves the grid)."""
    res = 2 * np.pi / 4096
    plant = _free_plant(sensor=Sensor(np.full(3, 5 * res), np.zeros(3), np.full(3, res), seed=2))
    rec = Recorder()
    trace = simulate(plant, rec, np.array([0.5, 0.3, -0.2]), np.zeros(3), 0.3)
    q_m = np.array([m[0] for m in rec.measured])
    np.testing.assert_allclose(q_m / res, np.round(q_m / res), atol=1e-9)
    assert np.abs(q_m - trace.q).max() > 3 * res


def test_stiff_stops_are_refused_with_the_substeps_needed():
    """A stop too stiff for an RK4 step set explicitly gets a clear error before the run; with the
    substeps unset, each such stop is sized to the step from its joint's effective inertia,
    h omega = 1, and said (the yield at the torque scale is tiny here: 1e6 / rad was asked)."""
    from nnrobust.core.exceptions import ConfigError

    config = load_preset("paper-ellipse").replace(plant={"joint_stop_stiffness": 1e6})
    with pytest.raises(ConfigError, match="joint_stop_stiffness.*substeps >="):
        build(config.replace(simulation={"substeps": 1}))
    with pytest.warns(UserWarning, match="stops of 'joint1' .* are softened to their effective inertia"):
        setup = build(config)
    M_inv = np.linalg.inv(setup.robot.mass(setup.q0))
    omega = np.sqrt(setup.plant.stops.stiffness * np.diag(M_inv))
    np.testing.assert_allclose(omega * config.simulation.control_period, 1.0, rtol=1e-12)
    assert setup.substeps == 1
