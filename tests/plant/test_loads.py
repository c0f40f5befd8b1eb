"""External loads of ``[[plant.loads]]``: torque steps and impulses, a tool wrench, payload changes,
checked against independent references (the same torque given by the controller, the impulse-
momentum law, finite-difference kinematics, a static payload) and the same on both loops.
"""

import numpy as np
import pinocchio as pin
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.controllers.base import Controller, ControlOutput
from nnrobust.core.exceptions import ConfigError
from nnrobust.run import compiled
from nnrobust.run.experiment import build, run_experiment
from nnrobust.run.simulation import simulate

needs_extension = pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())


def _config(preset="paper-ellipse", duration=1.0, loads=None, **plant):
    config = load_preset(preset)
    return config.replace(
        simulation={"duration": duration, "backend": "python"},
        plant={"loads": loads, **plant},
    )


def _run(setup, controller=None, duration=None, v0=None):
    config = setup.config
    return simulate(
        setup.plant,
        controller or setup.controller,
        setup.q0,
        setup.v0 if v0 is None else v0,
        duration or config.simulation.duration,
        config.simulation.control_period,
        setup.substeps,
    )


class Still(Controller):
    """Commands no torque."""

    def __init__(self, n):
        self.n = n

    def compute(self, t, q, v, z, period=0.0):
        return ControlOutput(np.zeros(self.n))


class Plus(Controller):
    """Another controller's command plus u from t0 on: a step load given by the actuators."""

    def __init__(self, inner, u, t0):
        self.inner, self.u, self.t0 = inner, np.asarray(u, float), t0
        self.state_size, self.signal_names = inner.state_size, inner.signal_names

    def initial_state(self):
        return self.inner.initial_state()

    def compute(self, t, q, v, z, period=0.0):
        out = self.inner.compute(t, q, v, z, period)
        tau = out.tau + self.u if t >= self.t0 - 1e-12 else out.tau
        return ControlOutput(tau, out.signals, out.state)


def test_a_torque_step_is_the_same_torque_added_by_the_actuators():
    """With ideal actuators, a step load u from t0 moves the arm exactly as the controller's
    command plus u from t0 (and not at all before t0)."""
    u, t0 = [0.5, -1.0, 2.0], 0.3
    loaded = build(_config(loads=[{"kind": "step", "time": t0, "torque": u}], torque_limits="none"))
    plain = build(_config(torque_limits="none"))
    a = _run(loaded)
    b = _run(plain, Plus(plain.controller, u, t0))
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.dq, b.dq, rtol=0, atol=1e-10)
    reference = _run(build(_config(torque_limits="none")))
    k0 = int(round(t0 / 1e-3))
    np.testing.assert_array_equal(a.q[: k0 + 1], reference.q[: k0 + 1])  # switched at t0, not before
    assert np.abs(a.q[k0 + 2] - reference.q[k0 + 2]).max() > 0


@pytest.mark.parametrize("duration", [2e-3, 1e-3])
def test_an_impulse_changes_the_momentum_by_the_impulse(duration):
    """From rest, with no gravity in the plane, friction or disturbance: after a joint impulse p
    the velocity is M(q0)^-1 p, to within the pulse's length (the arm moves a little during it)."""
    p = np.array([0.02, -0.01, 0.015])
    config = _config(
        duration=0.01,
        loads=[{"kind": "impulse", "time": 0.002, "impulse": p.tolist(), "duration": duration}],
        disturbance="none",
        viscous_friction=[0.0] * 3,
        coulomb_friction=[0.0] * 3,
        torque_limits="none",
    )
    setup = build(config)
    trace = _run(setup, Still(3), duration=0.01, v0=np.zeros(3))
    expected = np.linalg.solve(setup.plant.model.mass(setup.q0), p)
    after = trace.dq[int(round((0.002 + duration) / 1e-3)) + 1]
    assert np.abs(trace.dq[:3]).max() == 0.0  # nothing before the pulse
    assert np.linalg.norm(after - expected) < 0.01 * np.linalg.norm(expected)
    # the momentum law holds exactly for the pulse's integral: the mean torque over it is p / d
    np.testing.assert_allclose(setup.plant.loads.pulses[0].torque * duration, p, rtol=1e-15)


def test_a_tool_wrench_acts_as_the_finite_difference_jacobian_transposed():
    """tau = J^T w: the force by the virtual work of the task frame's position, the moment by that
    of its rotation, both by central differences of the forward kinematics (7 joints)."""
    f, m = np.array([3.0, -2.0, 5.0]), np.array([0.4, 0.1, -0.3])
    loads = [{"kind": "wrench", "time": 0.0, "force": f.tolist(), "moment": m.tolist()}]
    setup = build(_config("panda-ellipse", loads=loads))
    plant = setup.plant
    plant.begin_period(0.0)
    model, data, fid = plant.model.model, plant.model.model.createData(), plant.model.frame_id

    def pose(q):
        pin.framesForwardKinematics(model, data, q)
        return data.oMf[fid].translation.copy(), data.oMf[fid].rotation.copy()

    rng = np.random.default_rng(4)
    for _ in range(3):
        q = setup.q0 + rng.uniform(-0.4, 0.4, setup.q0.size)
        x0, R0 = pose(q)
        expected = np.zeros(q.size)
        h = 1e-6
        for i in range(q.size):
            dq = np.zeros(q.size)
            dq[i] = h
            (xp, Rp), (xm, Rm) = pose(q + dq), pose(q - dq)
            expected[i] = f @ (xp - xm) / (2 * h) + m @ pin.log3(Rp @ Rm.T) / (2 * h)
        np.testing.assert_allclose(plant.load_torque(q), expected, rtol=0, atol=1e-7 * np.abs(expected).max())
    plant.begin_period(-1.0)  # before the wrench: nothing
    assert np.all(plant.load_torque(setup.q0) == 0)


def test_a_payload_picked_up_is_the_static_payload_from_then_on():
    """A payload change at t0: before t0 the run is the unloaded one bit for bit; a change at 0 is
    plant.payload exactly; the true M(q) after it is that of the loaded arm; the nominal model
    never knows."""
    mass = 1.5
    picked = _run(
        build(_config("panda-ellipse", 0.6, loads=[{"kind": "payload", "time": 0.0, "mass": mass}]))
    )
    static = _run(build(_config("panda-ellipse", 0.6, payload=mass)))
    np.testing.assert_allclose(picked.q, static.q, rtol=0, atol=1e-12)

    t0 = 0.2
    later = build(_config("panda-ellipse", 0.6, loads=[{"kind": "payload", "time": t0, "mass": mass}]))
    unloaded = _run(build(_config("panda-ellipse", 0.6)))
    trace = _run(later)
    k0 = int(round(t0 / 1e-3))
    np.testing.assert_array_equal(trace.q[: k0 + 1], unloaded.q[: k0 + 1])
    assert np.abs(trace.q[-1] - unloaded.q[-1]).max() > 1e-6
    q = later.q0
    loaded = build(_config("panda-ellipse", payload=mass))
    later.plant.begin_period(t0)
    np.testing.assert_allclose(later.plant.model.mass(q), loaded.plant.model.mass(q), rtol=0, atol=1e-14)
    later.plant.begin_period(0.0)  # the arm put back as built: a rerun repeats the run
    np.testing.assert_allclose(later.plant.model.mass(q), unloaded_mass(q), rtol=0, atol=1e-14)
    assert later.nominal.mass(q)[0, 0] != pytest.approx(loaded.plant.model.mass(q)[0, 0])
    np.testing.assert_array_equal(_run(later).q, trace.q)


def unloaded_mass(q):
    return build(_config("panda-ellipse")).plant.model.mass(q)


def test_payload_changes_replace_one_another_in_time_order():
    """Drop-off before pick-up in the file: sorted by time, each change replaces the one before."""
    loads = [{"kind": "payload", "time": 0.4, "mass": 0.0}, {"kind": "payload", "time": 0.1, "mass": 2.0}]
    setup = build(_config("panda-ellipse", loads=loads))
    plant, q = setup.plant, setup.q0
    masses = []
    for t in (0.0, 0.1, 0.39, 0.4):
        plant.begin_period(t)
        masses.append(plant.model.mass(q)[0, 0])
    assert masses[0] == masses[3] < masses[1] == masses[2]


LOADS = {
    "step and impulse": lambda n: [
        {"kind": "step", "time": 0.1, "torque": [1.0] * n, "duration": 0.2},
        {"kind": "impulse", "time": 0.15, "impulse": [0.02] * n, "duration": 0.005},
    ],
    "wrench": lambda n: [
        {"kind": "wrench", "time": 0.1, "force": [5.0, -3.0, 2.0], "moment": [0.1, 0.2, 0.3]}
    ],
    "payload": lambda n: [
        {"kind": "payload", "time": 0.1, "mass": 1.0},
        {"kind": "payload", "time": 0.2, "mass": 0.0},
    ],
}


@needs_extension
@pytest.mark.parametrize("kind", list(LOADS))
@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-ellipse"])
def test_loads_are_the_same_on_both_loops(preset, kind):
    config = _config(preset, 0.3)
    config = config.replace(plant={"loads": LOADS[kind](build(config).plant.nq)})
    py = run_experiment(config)
    cc = run_experiment(config.replace(simulation={"backend": "compiled"}))
    assert cc.metrics()["backend"] == "compiled"
    for name in ("q", "dq", "tau"):
        np.testing.assert_allclose(getattr(cc, name), getattr(py, name), rtol=0, atol=1e-9, err_msg=name)
    assert np.abs(py.q - run_experiment(_config(preset, 0.3)).q).max() > 1e-6  # the loads acted


@pytest.mark.parametrize(
    ("entry", "key", "message"),
    [
        ({"kind": "push", "time": 0.0}, "plant.loads[0].kind", "not one of step, impulse, wrench, payload"),
        ({"kind": "step", "torque": [1, 0, 0]}, "plant.loads[0].time", "needs the time"),
        (
            {"kind": "step", "time": 0.0105, "torque": [1, 0, 0]},
            "plant.loads[0].time",
            "give e.g. 0.01 or 0.011",
        ),
        ({"kind": "step", "time": 0.0, "torque": [1, 0]}, "plant.loads[0].torque", "has 2 entries; give 3"),
        (
            {"kind": "impulse", "time": 0.0, "impulse": [1, 0, 0], "duration": 0},
            "plant.loads[0].duration",
            "> 0",
        ),
        ({"kind": "wrench", "time": 0.0}, "plant.loads[0].force", "force [N] and/or moment"),
        ({"kind": "wrench", "time": 0.0, "force": [1, 2]}, "plant.loads[0].force", "has 2 entries; give 3"),
        ({"kind": "payload", "time": 0.0, "mass": -1}, "plant.loads[0].mass", "in [0, 1000] kg"),
        (
            {"kind": "payload", "time": 0.0, "mass": 1, "duration": 1},
            "plant.loads[0].duration",
            "keys: kind, time, mass",
        ),
        (
            {"kind": "step", "time": 0.0, "torque": [1, "a", 0]},
            "plant.loads[0].torque",
            "list of finite numbers",
        ),
    ],
)
def test_bad_loads_are_refused_by_key(entry, key, message):
    with pytest.raises(ConfigError) as err:
        build(_config(loads=[entry]))
    assert err.value.key == key and message in str(err.value)


def test_only_a_load_starting_after_the_run_is_said_never_to_act():
    """Each load's start is compared with the run's end, not with the load before it's duration:
    an impulse (one period long) made a later step inside the run 'never act', and a step to the
    end of the run hid a later load that starts after it."""
    import warnings

    impulse = {"kind": "impulse", "time": 0.01, "impulse": [0.0, 0.01, 0.0]}
    step = {"kind": "step", "time": 0.01, "torque": [0.0, 0.1, 0.0]}
    inside = {"kind": "step", "time": 0.05, "torque": [0.0, 1.0, 0.0]}
    after = {"kind": "step", "time": 5.0, "torque": [0.0, 1.0, 0.0]}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        setup = build(_config(duration=0.1, loads=[impulse, inside]))
    assert [p.start for p in setup.plant.loads.pulses] == [0.01, 0.05]
    with pytest.warns(UserWarning, match=r"plant\.loads\[1\]\.time: 5 s is not before the run ends") as seen:
        build(_config(duration=0.1, loads=[step, after]))
    assert len([w for w in seen if "never acts" in str(w.message)]) == 1


def test_wrench_and_payload_have_no_mujoco_twin_yet():
    pytest.importorskip("mujoco")
    loads = [{"kind": "wrench", "time": 0.0, "force": [1.0, 0.0, 0.0]}]
    with pytest.raises(ConfigError, match="'wrench' load has no MuJoCo twin yet"):
        build(_config(loads=loads, engine="mujoco"))


@needs_extension
def test_step_and_impulse_loads_act_on_mujoco_alike_on_both_loops():
    """On MuJoCo the joint loads enter as applied forces: both loops agree in closed loop, and open
    loop on the frictionless arm the loads move it as they move the Pinocchio plant."""
    pytest.importorskip("mujoco")
    loads = LOADS["step and impulse"](3)
    config = _config(duration=0.3, loads=loads, engine="mujoco")
    py, cc = (run_experiment(config.replace(simulation={"backend": b})) for b in ("python", "compiled"))
    assert cc.metrics()["backend"] == "compiled"
    np.testing.assert_allclose(cc.q, py.q, rtol=0, atol=1e-9)
    effect = {}
    for engine in ("mujoco", "pinocchio"):
        end = []
        for given in (None, loads):
            frictionless = dict(disturbance="none", viscous_friction=[0.0] * 3, coulomb_friction=[0.0] * 3)
            setup = build(_config(duration=0.3, loads=given, engine=engine, **frictionless))
            end.append(_run(setup, Still(3), v0=np.zeros(3)).q[-1])
        effect[engine] = end[1] - end[0]
    assert np.abs(effect["pinocchio"]).max() > 0.1
    np.testing.assert_allclose(effect["mujoco"], effect["pinocchio"], rtol=1e-5)
