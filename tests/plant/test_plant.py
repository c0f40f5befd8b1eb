import numpy as np
import pytest

from nnrobust.config import ExperimentConfig
from nnrobust.plant import Friction, Plant, SinusoidalDisturbance
from nnrobust.run.experiment import build
from nnrobust.run.simulation import simulate
from tests.problems import VERTICAL_GRAVITY, ConstantTorque, paper_robot

Q0 = np.array([0.3, 1.0, -0.8])
V0 = np.array([1.5, -2.0, 3.0])


def energies(plant, trace):
    return np.array([plant.energy(q, v) for q, v in zip(trace.q, trace.dq)])


def _energy_drift(robot, plant, trace) -> float:
    """Largest energy change over the run, relative to the motion's largest kinetic energy (the
    potential energy has an arbitrary zero)."""
    E = energies(plant, trace)
    scale = max(robot.kinetic_energy(q, v) for q, v in zip(trace.q, trace.dq))
    return float(np.abs(E - E[0]).max() / scale)


@pytest.mark.parametrize("gravity", [None, VERTICAL_GRAVITY], ids=["horizontal", "vertical"])
def test_frictionless_unforced_arm_conserves_energy(gravity):
    """Relative energy drift < 1e-6 over 5 s with RK4 at the default 1 ms period. Falling in a
    vertical plane the light outer link whips to 150 rad/s: the speed-adaptive step cuts those
    periods (simulation.max_step_rotation)."""
    robot = paper_robot(gravity)
    plant = Plant(robot, Friction.none(3), SinusoidalDisturbance.none(3))
    trace = simulate(plant, ConstantTorque(np.zeros(3)), Q0, V0, 5.0)
    assert trace.status == "completed" and trace.t[-1] == pytest.approx(5.0 - 1e-3)
    assert _energy_drift(robot, plant, trace) < 1e-6
    assert (trace.refined_periods > 1000) == (gravity is not None)


def test_the_speed_adaptive_step_converges_at_third_order_or_better():
    """The whipping arm of the test above: at a fixed 1 ms step energy drifts by over 1 %; with
    the step cut for speed the drift falls by at least 64x when max_step_rotation is quartered
    (third order; RK4's fourth gives 256x, the chaotic arm's paths differing between settings;
    benchmarks/adaptive_step.py)."""
    robot = paper_robot(VERTICAL_GRAVITY)
    plant = Plant(robot, Friction.none(3), SinusoidalDisturbance.none(3))

    def drift(rotation):
        trace = simulate(plant, ConstantTorque(np.zeros(3)), Q0, V0, 5.0, max_step_rotation=rotation)
        return _energy_drift(robot, plant, trace)

    assert drift(np.inf) > 1e-2
    assert drift(0.04) / drift(0.01) > 64


def test_friction_only_dissipates_energy():
    """With viscous and Coulomb friction and no input, energy never increases, not even in the
    steps where a joint stops or reverses (the stick-slip events are located inside the step)."""
    robot = paper_robot()
    plant = Plant(
        robot, Friction(robot.viscous_friction, robot.coulomb_friction), SinusoidalDisturbance.none(3)
    )
    trace = simulate(plant, ConstantTorque(np.zeros(3)), Q0, V0, 3.0)
    E = energies(plant, trace)
    assert trace.friction_events > 0
    assert np.all(np.diff(E) <= 1e-12 * E[0])
    assert E[-1] < 0.01 * E[0]  # and it does dissipate


@pytest.mark.parametrize("coulomb", [0.0, 1.0], ids=["viscous", "viscous and coulomb"])
def test_energy_balance_with_torque_and_disturbance(coulomb):
    """E(T) - E(0) equals the integral of q'^T (tau - F(q') - tau_d) (power balance); with Coulomb
    friction the joints slide and stick (a held joint does no work)."""
    robot = paper_robot()
    plant = Plant(robot, Friction(robot.viscous_friction, np.full(3, coulomb)), SinusoidalDisturbance.paper())
    tau = np.array([2.0, -1.0, 0.5])
    trace = simulate(plant, ConstantTorque(tau), Q0, V0, 1.0, control_period=1e-4)
    E = energies(plant, trace)
    power = np.array(
        [v @ (tau - plant.friction.torque(v) - plant.disturbance(t)) for t, v in zip(trace.t, trace.dq)]
    )
    work = np.sum(0.5 * (power[1:] + power[:-1])) * 1e-4  # trapezoid
    assert E[-1] - E[0] == pytest.approx(work, rel=1e-4, abs=1e-6)
    assert (trace.friction_events > 0) == (coulomb > 0)


def test_while_every_joint_slides_the_plant_is_the_sgn_law():
    """With no joint held, the stick-slip right-hand side is eq. (7) with F = F_d q' + F_c sgn(q'),
    computed independently here from M and N."""
    robot = paper_robot()
    coulomb = np.array([1.0, 0.7, 0.4])
    plant = Plant(robot, Friction(robot.viscous_friction, coulomb), SinusoidalDisturbance.paper())
    rng = np.random.default_rng(1)
    for _ in range(10):
        q, v, tau = rng.uniform(-2, 2, 3), rng.uniform(-2, 2, 3), rng.uniform(-5, 5, 3)
        friction = robot.viscous_friction * v + coulomb * np.sign(v)
        expected = np.linalg.solve(robot.mass(q), tau - friction - plant.disturbance(0.7) - robot.bias(q, v))
        np.testing.assert_allclose(plant.acceleration(0.7, q, v, tau), expected, rtol=1e-9, atol=1e-9)
        a, hold = plant.constrained_acceleration(0.7, q, v, tau, np.sign(v).astype(int))
        np.testing.assert_allclose(a, expected, rtol=1e-9, atol=1e-9)
        assert hold.size == 0


def test_paper_disturbance_is_the_errata_reading():
    """tau_d = [4 cos 2t, sin t + cos 2t, 2 sin t]."""
    d = SinusoidalDisturbance.paper()
    for t in (0.0, 0.7, 3.1):
        expected = [4 * np.cos(2 * t), np.sin(t) + np.cos(2 * t), 2 * np.sin(t)]
        np.testing.assert_allclose(d(t), expected, atol=1e-12)
    np.testing.assert_allclose(d.bound(), [4, 2, 2])


@pytest.mark.parametrize("controller", ["nn", "no-u0"])
def test_rk4_and_solve_ivp_agree_on_the_paper_closed_loop(controller):
    """The closed loop of case (b) for 2 s: fixed-step RK4 vs DOP853 at tight tolerances.

    Coulomb friction is left out: its sgn(q') makes an adaptive integrator crawl at every sign
    change, and an accuracy check needs a smooth right-hand side.
    """
    base = ExperimentConfig().replace(
        nominal={"p": [0.4, 0.1, 0.1], "viscous_friction": [4.0, 1.0, 0.2]},
        plant={"coulomb_friction": [0.0, 0.0, 0.0]},
        controller={"kind": controller},
        simulation={"q_seed": [0.2, 1.0, 1.0], "duration": 2.0},
    )
    runs = {}
    for integrator in ("rk4", "solve_ivp"):
        setup = build(base.replace(simulation={"integrator": integrator}))
        runs[integrator] = simulate(
            setup.plant,
            setup.controller,
            setup.q0,
            setup.v0,
            2.0,
            integrator=integrator,
            rtol=1e-8,
            atol=1e-8,
        )
    diff = np.abs(runs["rk4"].q - runs["solve_ivp"].q).max()
    assert diff < 1e-4, diff


def test_solve_ivp_and_rk4_agree_through_stick_slip():
    """With Coulomb friction on, DOP853 and RK4 integrate the same stick-slip events: the paper's
    closed loop agrees to 1e-6 rad (before, sgn made the adaptive integrator crawl)."""
    base = ExperimentConfig().replace(
        nominal={"p": [0.4, 0.1, 0.1], "viscous_friction": [4.0, 1.0, 0.2]},
        controller={"kind": "no-u0"},
        simulation={"q_seed": [0.2, 1.0, 1.0], "duration": 0.5},
    )
    runs = {}
    for integrator in ("rk4", "solve_ivp"):
        setup = build(base.replace(simulation={"integrator": integrator}))
        runs[integrator] = simulate(
            setup.plant,
            setup.controller,
            setup.q0,
            setup.v0,
            0.5,
            integrator=integrator,
            rtol=1e-10,
            atol=1e-10,
        )
    assert runs["rk4"].friction_events > 0
    assert np.abs(runs["rk4"].q - runs["solve_ivp"].q).max() < 1e-6


def test_per_joint_friction_and_disturbance_scales_and_the_disturbance_frequency_and_phase():
    """plant.joint_friction_scales and joint_disturbance_scales multiply each joint's friction and
    disturbance row after the global scales, missing entries being 1; disturbance_omega_scale and
    disturbance_phase_shift move every harmonic; one entry is set alone as an indexed key."""
    from nnrobust.config import apply_overrides
    from nnrobust.config.presets import load_preset

    base = load_preset("paper-ellipse").replace(plant={"friction_scale": 2.0, "disturbance_scale": 0.5})
    ref = build(base).plant
    changed = build(
        apply_overrides(
            base,
            {
                "plant.joint_friction_scales[2]": 3.0,
                "plant.joint_disturbance_scales": [0.0, 4.0],
                "plant.disturbance_omega_scale": 1.5,
                "plant.disturbance_phase_shift": 0.25,
            },
        )
    ).plant
    np.testing.assert_array_equal(changed.friction.viscous, ref.friction.viscous * [1.0, 1.0, 3.0])
    np.testing.assert_array_equal(changed.friction.coulomb, ref.friction.coulomb * [1.0, 1.0, 3.0])
    np.testing.assert_array_equal(changed.friction.static, ref.friction.static * [1.0, 1.0, 3.0])
    np.testing.assert_array_equal(
        changed.disturbance.amplitude, ref.disturbance.amplitude * [[0.0], [4.0], [1.0]]
    )
    np.testing.assert_array_equal(changed.disturbance.omega, 1.5 * ref.disturbance.omega)
    np.testing.assert_array_equal(changed.disturbance.phase, ref.disturbance.phase + 0.25)
    t = 0.37  # the torque itself, joint by joint
    d_ref, d = ref.disturbance(t), changed.disturbance(t)
    A, w, ph = ref.disturbance.amplitude, ref.disturbance.omega, ref.disturbance.phase
    np.testing.assert_allclose(d[1], 4.0 * np.sum(A[1] * np.sin(1.5 * w * t + ph[1] + 0.25)), rtol=1e-12)
    assert d[0] == 0.0 and d_ref[0] != 0.0


@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-ellipse"])
def test_a_payload_is_a_sphere_at_the_task_frame_in_the_true_plant_only(preset):
    """plant.payload = m: the true plant's M(q) gains exactly the kinetic energy of a solid sphere
    at the task frame, m Jv^T Jv + (2/5) m r^2 Jw^T Jw (frame Jacobians in world axes), and its
    gravity exactly m g through Jv; the controller's nominal model is unchanged."""
    import pinocchio as pin

    from nnrobust.config.presets import load_preset
    from nnrobust.plant.build import PAYLOAD_RADIUS

    base = load_preset(preset)
    m = 2.5
    plain, loaded = build(base), build(base.replace(plant={"payload": m}))
    robot, true = plain.plant.model, loaded.plant.model
    frame = robot.model.getFrameId(robot.task_frame)
    g = robot.model.gravity.linear
    rng = np.random.default_rng(3)
    low, high = robot.working_range
    for _ in range(5):
        q = rng.uniform(low, high)
        J = pin.computeFrameJacobian(robot.model, robot.model.createData(), q, frame, pin.LOCAL_WORLD_ALIGNED)
        Jv, Jw = J[:3], J[3:]
        sphere = m * Jv.T @ Jv + 0.4 * m * PAYLOAD_RADIUS**2 * Jw.T @ Jw
        np.testing.assert_allclose(true.mass(q) - robot.mass(q), sphere, atol=1e-10)
        np.testing.assert_allclose(true.gravity(q) - robot.gravity(q), -m * Jv.T @ g, atol=1e-10)
    q = plain.q0
    np.testing.assert_array_equal(loaded.nominal.mass(q), plain.nominal.mass(q))


def test_every_declared_disturbance_is_a_choice_and_builds_what_it_says():
    """plant.disturbance takes the declared kinds (and auto, custom); each builds on the paper's
    arm: none is zero, paper the paper's tau_d, scaled peaks at disturbance_level x the torque
    scale on every joint, sinusoid is the amplitudes given."""
    from nnrobust.config.presets import load_preset
    from nnrobust.core.exceptions import ConfigError
    from nnrobust.plant.disturbance import DISTURBANCE_KINDS, SinusoidalDisturbance
    from nnrobust.plant.scaling import torque_scale
    from nnrobust.run.experiment import build

    assert set(DISTURBANCE_KINDS) == {"none", "paper", "scaled", "sinusoid"}
    base = load_preset("paper-ellipse").replace(simulation={"duration": 0.01})
    with pytest.raises(ConfigError, match="auto, none, paper, scaled, sinusoid, custom"):
        base.replace(plant={"disturbance": "gusts"})
    times = np.linspace(0.0, 7.0, 701)
    built = {k: build(base.replace(plant={"disturbance": k})).plant.disturbance for k in ("none", "paper")}
    assert all(not built["none"](t).any() for t in times)
    paper = SinusoidalDisturbance.paper()
    assert all(np.array_equal(built["paper"](t), paper(t)) for t in times)
    setup = build(base.replace(plant={"disturbance": "scaled", "disturbance_level": 0.2}))
    peak = np.max([np.abs(setup.plant.disturbance(t)) for t in np.linspace(0, 2 * np.pi, 4001)], axis=0)
    assert np.all(peak <= 0.2 * torque_scale(setup.robot) + 1e-12)
    assert np.all(peak >= 0.85 * 0.2 * torque_scale(setup.robot))  # (sin x + sin 2x) / 2 peaks at 0.88
    amplitude = [[1.0], [2.0], [3.0]]
    given = base.replace(
        plant={"disturbance": "sinusoid", "disturbance_amplitude": amplitude, "disturbance_omega": [2.0]}
    )
    assert np.allclose(build(given).plant.disturbance(np.pi / 4), [1.0, 2.0, 3.0])
