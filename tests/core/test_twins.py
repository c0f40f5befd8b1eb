"""Each compiled component against its Python twin, alone, on random states: the law's torque and
next state, the weighted criterion's gradient (on the nominal model) and value (on the true robot),
and the plant's q''. A whole-run comparison (tests/run/test_compiled.py) can hide a component that
differs only where a run rarely goes; these states are drawn across the joints' ranges.
"""

import copy

import numpy as np
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.run import compiled
from nnrobust.run.experiment import build

pytestmark = pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())

CASES = {
    "paper arm, NN, paper criterion": ("paper-ellipse", {}),
    "paper arm, sliding mode": ("paper-ellipse", {"controller": {"kind": "sliding-mode"}}),
    "paper arm, PD": ("paper-ellipse", {"controller": {"kind": "pd"}}),
    "paper arm, error basis, printed law": (
        "paper-ellipse",
        {"nn": {"basis_input": "error", "law": "printed", "sigma": 0.0}},
    ),
    "paper line": ("paper-line", {}),
    "Panda, point to point": (
        "panda-ellipse",
        {"trajectory": {"kind": "point_to_point", "goal": [0.5, 0.15, 0.35], "move_time": 1.5}},
    ),
    "Panda pose, waypoints, PD": (
        "panda-pose",
        {
            "controller": {"kind": "pd"},
            "trajectory": {
                "kind": "waypoints",
                "waypoints": [[0.45, 0.0, 0.45], [0.5, 0.12, 0.5], [0.4, 0.15, 0.4], [0.45, 0.0, 0.45]],
                "waypoint_times": [0.0, 0.8, 1.6, 2.4],
            },
        },
    ),
    "Panda, manipulability and joint limits": ("panda-ellipse", {}),
    "Panda pose, computed torque": ("panda-pose", {"controller": {"kind": "computed-torque"}}),
    "UR5, no u0": ("ur5-ellipse", {"controller": {"kind": "no-u0"}}),
    "planar7, half det and joint limits": (
        "planar7-ellipse",
        {"subtasks": {"criteria": ["half_det_manipulability", "joint_limits"], "weights": [0.7, 0.3]}},
    ),
    "planar7, obstacles and smoothness": (
        "planar7-ellipse",
        {
            "subtasks": {
                "criteria": ["obstacles", "joint_smoothness", "joint_centering"],
                "weights": [0.5, 0.3, 0.2],
                "obstacles": [[0.3, 0.2, 0.0, 0.05]],
                "obstacle_influence": 0.3,
                "smoothness_coefficients": [0.5, -1.0, 1.0, 0.2, -0.3, 0.1, 0.4],
            }
        },
    ),
}


def _config(name):
    preset, changes = CASES[name]
    return load_preset(preset).replace(simulation={"duration": 0.01}, **changes)


def _twin(name):
    setup = build(_config(name))
    assert compiled.twin_refusal(setup) == ""
    robot, nominal, spec = compiled._prepared(setup, 0.01)
    return setup, spec, robot, nominal


def _states(setup, count, seed):
    """Random (t, q, v, z): q across the joints' ranges, v up to 2 rad/s, z a positive NN state."""
    rng = np.random.default_rng(seed)
    lower, upper = setup.robot.lower_limits, setup.robot.upper_limits
    lower, upper = np.where(np.isfinite(lower), lower, -np.pi), np.where(np.isfinite(upper), upper, np.pi)
    z0 = setup.controller.initial_state()
    for _ in range(count):
        q = rng.uniform(lower + 0.02 * (upper - lower), upper - 0.02 * (upper - lower))
        v = rng.uniform(-2.0, 2.0, q.size)
        z = z0 + rng.uniform(0.0, 5.0, z0.size)
        yield rng.uniform(0.0, 20.0), q, v, z


def _close(a, b, what, rel=1e-9):
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(1.0, float(np.abs(b).max(initial=0.0)))
    np.testing.assert_allclose(a, b, rtol=0, atol=rel * scale, err_msg=what)


@pytest.mark.parametrize("name", list(CASES))
def test_each_law_step_is_its_python_twin(name):
    """Torque, next state and every signal (the robust term's, the pseudo-inverse's damping) of
    one control step."""
    setup, spec, _, nominal = _twin(name)
    period = setup.config.simulation.control_period
    module = compiled._module()
    for t, q, v, z in _states(setup, 25, seed=1):
        ours = module.twin_control(nominal, spec, t, q, v, z)
        theirs = setup.controller.compute(t, q, v, z, period)
        _close(ours.tau, theirs.tau, f"{name}: tau at t = {t:.3f}")
        if z.size:
            _close(ours.z, theirs.state if theirs.state is not None else z, f"{name}: z_next")
        names = setup.controller.signal_names
        assert len(ours.signals) == len(names) == len(theirs.signals), name
        for i, signal in enumerate(names):
            _close(ours.signals[i], theirs.signals[signal], f"{name}: {signal}")


def test_every_shipped_twin_is_tested_here_and_reads_its_fields_by_name():
    """Every law, robust term and path class with a compiled twin is among the cases above (the
    registered laws have their own files); the C++ side builds each from its fields by name: an
    unknown name, or a field left out, is an error naming it."""
    from nnrobust.controllers import NNCompensator, SlidingModeCompensator, TaskSpaceController, TaskSpacePD
    from nnrobust.trajectories import EllipseTrajectory, PiecewisePolynomialPath

    specs = [_twin(n)[1] for n in CASES]
    shipped = {"law": {TaskSpaceController.twin, TaskSpacePD.twin}, "path": set(), "robust": set()}
    shipped["robust"] = {NNCompensator.twin, SlidingModeCompensator.twin}
    shipped["path"] = {EllipseTrajectory.twin, PiecewisePolynomialPath.twin}
    for part, names in shipped.items():
        assert names <= {getattr(s, part) for s in specs}, part
    assert any(s.pose for s in specs)
    setup, spec, _, nominal = _twin("Panda pose, computed torque")
    module, q, v = compiled._module(), setup.q0, setup.v0
    z = setup.controller.initial_state()
    for part, field in (("law", "Kv"), ("path", "omega"), ("pose", "axis")):
        params = dict(getattr(spec, f"{part}_params"))
        del params[field]
        setattr(spec, f"{part}_params", params)
        with pytest.raises(ValueError, match=f"needs the field {field}"):
            module.twin_control(nominal, spec, 0.0, q, v, z)
        setup, spec, _, nominal = _twin("Panda pose, computed torque")
    for part, wrong in (("law", "task-space"), ("path", "elipse")):
        setattr(spec, part, wrong)
        with pytest.raises(ValueError, match=f"unknown {part} {wrong}"):
            module.twin_control(nominal, spec, 0.0, q, v, z)
    setup, spec, _, nominal = _twin("paper arm, sliding mode")
    spec.robust = "sliding"
    with pytest.raises(ValueError, match="unknown robust term sliding"):
        module.twin_control(nominal, spec, 0.0, setup.q0, setup.v0, setup.controller.initial_state())


@pytest.mark.parametrize("name", [n for n in CASES if _config(n).subtasks.criteria != []])
def test_each_criterion_is_its_python_twin(name):
    """Gradient on the nominal model (what the law uses) and value on the true robot (what is
    recorded), across the joints' ranges."""
    setup, spec, robot, nominal = _twin(name)
    module = compiled._module()
    for _, q, _, _ in _states(setup, 25, seed=2):
        _close(
            module.twin_criterion_gradient(nominal, spec, q),
            setup.criterion.gradient(setup.nominal, q),
            f"{name}: gradient",
        )
        _close(
            module.twin_criterion_value(robot, spec, q), setup.criterion.value(setup.robot, q), f"{name}: h"
        )


def test_every_declared_criterion_has_a_twin_tested_here_and_reads_its_fields_by_name():
    """Every shipped criterion declares a twin and is among the cases above; the C++ side builds
    each from its fields by name: an unknown name, or a field left out, is an error naming it."""
    from nnrobust.subtasks import CRITERION_KINDS

    tested = {c for n in CASES for c in _twin(n)[0].config.subtasks.criteria or []}
    tested |= {c for n in CASES if (s := _twin(n)[1]) is not None for c in s.criteria}  # defaults
    assert {k for k, kind in CRITERION_KINDS.items() if kind.twin_fields is not None} == set(CRITERION_KINDS)
    assert set(CRITERION_KINDS) <= tested, set(CRITERION_KINDS) - tested
    setup, spec, robot, nominal = _twin("planar7, obstacles and smoothness")
    module, q = compiled._module(), setup.q0
    params = [dict(p) for p in spec.criterion_params]
    del params[0]["influence"]
    spec.criterion_params = params
    with pytest.raises(ValueError, match="the criterion obstacles needs the field influence"):
        module.twin_criterion_value(robot, spec, q)
    spec.criteria = ["obstacle", *spec.criteria[1:]]
    with pytest.raises(ValueError, match="unknown criterion obstacle"):
        module.twin_criterion_value(robot, spec, q)


@pytest.mark.parametrize(
    "plant",
    [
        {},
        {"stiction": 1.5},
        {"torque_limits": "none", "joint_stop_stiffness": 300.0},
        {"loads": [{"kind": "wrench", "time": 0.0, "force": [3.0, -2.0, 1.0], "moment": [0.1, 0.0, 0.2]}]},
        {
            "loads": [
                {"kind": "step", "time": 4.0, "torque": "JOINTS"},
                {"kind": "impulse", "time": 8.0, "duration": 6.0, "impulse": "JOINTS"},
                {"kind": "payload", "time": 5.0, "mass": 1.5},
                {"kind": "payload", "time": 12.0, "mass": 0.2},
            ]
        },
    ],
    ids=["as shipped", "stiction", "stiff stops", "tool wrench", "steps, impulse and payloads"],
)
@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-ellipse"])
def test_the_plant_derivative_is_its_python_twin(preset, plant):
    """Q'' of the slipping law with friction, disturbance, stops (states beyond the limits
    included) and a held load, at random times and torques."""
    config = load_preset(preset)
    n = {"paper-ellipse": 3, "panda-ellipse": 7}[preset]
    plant = copy.deepcopy(plant)  # the cases are shared by both presets
    for load in plant.get("loads", []):  # a joint vector of the arm's size
        for key in ("torque", "impulse"):
            if load.get(key) == "JOINTS":
                load[key] = list(np.linspace(-2.0, 3.0, n))
    setup = build(config.replace(simulation={"duration": 0.01}, plant=plant))
    spec = compiled.loop_spec(setup, 0.01)
    model = compiled.load_model(setup.plant.model.pinocchio_model, setup.robot.task_frame)
    module = compiled._module()
    rng = np.random.default_rng(3)
    lower, upper = setup.robot.lower_limits, setup.robot.upper_limits
    stopped = 0
    for t, q, v, _ in _states(setup, 25, seed=4):
        past = rng.uniform(size=q.size) < 0.4  # these joints pressed into a stop, up to 0.02 rad
        depth = rng.uniform(0.0, 0.02, q.size)
        q = np.where(past, np.where(rng.uniform(size=q.size) < 0.5, upper + depth, lower - depth), q)
        stopped += int(past.sum())
        tau = rng.uniform(-5.0, 5.0, q.size)
        setup.plant.begin_period(t)
        _close(
            module.twin_plant_acceleration(model, spec, t, q, v, tau),
            setup.plant.acceleration(t, q, v, tau),
            f"{preset}: q'' (limits {lower.round(2)}..{upper.round(2)})",
        )
    assert stopped > 10


def test_the_plant_twin_reads_every_part_by_name():
    """Each part the Python plant lists (Plant.twin_parts) reaches the C++ side under its name with
    the fields its class declares; a part or a field left out is an error naming it, not a
    default."""
    setup = build(load_preset("panda-ellipse").replace(simulation={"duration": 0.01}))
    spec = compiled.loop_spec(setup, 0.01)
    plant = setup.plant
    assert set(spec.plant_params) == set(plant.twin_fields)
    for name in ("friction", "disturbance", "loads", "sensor", "stops"):
        assert set(type(getattr(plant, name)).twin_fields) <= set(spec.plant_parts[name]), name
    model = compiled.load_model(plant.model.pinocchio_model, setup.robot.task_frame)
    module, q, v, tau = compiled._module(), setup.q0, setup.v0, np.ones(plant.nq)
    for part, field in (("friction", "static"), ("disturbance", "omega"), ("stops", "ring_frequencies")):
        parts = {k: dict(p) for k, p in spec.plant_parts.items()}
        del parts[part][field]
        spec.plant_parts = parts
        with pytest.raises(ValueError, match=f"the plant's {part}( sinusoid)? needs the field {field}"):
            module.twin_plant_acceleration(model, spec, 0.0, q, v, tau)
        spec = compiled.loop_spec(setup, 0.01)
    spec.disturbance = "sinusoidal"  # a disturbance is the one registered under its twin's name
    with pytest.raises(ValueError, match="unknown disturbance sinusoidal"):
        module.twin_plant_acceleration(model, spec, 0.0, q, v, tau)
    spec = compiled.loop_spec(setup, 0.01)
    parts = dict(spec.plant_parts)
    del parts["sensor"]
    spec.plant_parts = parts
    with pytest.raises(ValueError, match="needs the part sensor"):
        module.twin_plant_acceleration(model, spec, 0.0, q, v, tau)


DISTURBANCE_CASES = {
    "sinusoid": {
        "disturbance_amplitude": [[1.0, 0.5], [0.0, 2.0], [3.0, -1.0]],
        "disturbance_omega": [2.0, 7.0],
    },
    "scaled": {"disturbance_level": 0.3},
}


@pytest.mark.parametrize("kind", ["paper", "none", "sinusoid", "scaled"])
def test_each_disturbance_kind_is_its_python_twin(kind):
    """Every shipped plant.disturbance builds a class with a compiled twin (registered in
    csrc/plant/disturbance.cpp under the class's twin name), whose torque enters q'' as the
    Python one does, scaled and shifted by the plant's disturbance keys, at random times."""
    from nnrobust.plant.disturbance import DISTURBANCE_KINDS

    assert set(DISTURBANCE_KINDS) == {"paper", "none", "sinusoid", "scaled"}  # a new kind: add its case
    plant = {"disturbance": kind, "disturbance_scale": 1.7, "disturbance_phase_shift": 0.4}
    plant |= DISTURBANCE_CASES.get(kind, {})
    setup = build(load_preset("paper-ellipse").replace(simulation={"duration": 0.01}, plant=plant))
    assert compiled.own_twin(setup.plant.disturbance) is not None
    spec = compiled.loop_spec(setup, 0.01)
    assert spec.disturbance == compiled.own_twin(setup.plant.disturbance)
    model = compiled.load_model(setup.plant.model.pinocchio_model, setup.robot.task_frame)
    module, rng = compiled._module(), np.random.default_rng(5)
    for t, q, v, _ in _states(setup, 8, seed=6):
        t = float(t + rng.uniform(0.0, 20.0))
        tau = rng.uniform(-5.0, 5.0, q.size)
        setup.plant.begin_period(t)
        _close(
            module.twin_plant_acceleration(model, spec, t, q, v, tau),
            setup.plant.acceleration(t, q, v, tau),
            f"{kind}: q'' at t = {t:.3f}",
        )
