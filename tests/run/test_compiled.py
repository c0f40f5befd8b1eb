"""The compiled backend's foundation: the extension loads, and simulates exactly the model Python built.

`make test` sets NNROBUST_REQUIRE_COMPILED=1 when a C++ compiler is on the machine, so a build
that silently fell back to Python fails here instead of skipping.
"""

import os
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from nnrobust.core.exceptions import NNRobustError
from nnrobust.model.perturbation import perturb_inertias
from nnrobust.run import compiled
from tests.arms import arm, random_configurations

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from closed_loop import cpp_floor_loop, python_floor_loop  # noqa: E402  (the benchmark's floors)

from tests.problems import VERTICAL_GRAVITY, paper_robot

needs_extension = pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())


def test_the_extension_is_built_where_a_compiler_is():
    if os.environ.get("NNROBUST_REQUIRE_COMPILED") == "1":
        assert compiled.available(), compiled.unavailable_reason()


def _robots():
    panda = arm("panda", "pose")
    return {
        "paper arm": paper_robot(),
        "paper arm, vertical plane": paper_robot(VERTICAL_GRAVITY),
        "panda, fingers locked": panda,
        "panda, perturbed inertias": (
            perturb_inertias(panda.model, 1.1, 0.9, 0.2, 0.01, seed=3),
            panda.task_frame,
        ),
        "planar7": arm("planar7", "planar"),
    }


@needs_extension
@pytest.mark.parametrize("name", list(_robots()))
def test_the_same_model_on_both_sides(name):
    """The C++ side rebuilds exactly the model Python built (compiled.model_spec): M and V_m v + G
    are bit for bit the same on random states, and the task frame's Jacobian (computed there in
    two steps) agrees to 1e-12."""
    robot = _robots()[name]
    model, frame = robot if isinstance(robot, tuple) else (robot.model, robot.task_frame)
    loaded = compiled.load_model(model, frame)
    data, fid = model.createData(), model.getFrameId(frame)
    assert loaded.nq == model.nq
    rng = np.random.default_rng(5)
    low = np.maximum(model.lowerPositionLimit, -np.pi)
    high = np.minimum(model.upperPositionLimit, np.pi)
    for _ in range(20):
        q, v = rng.uniform(low, high), rng.uniform(-2, 2, model.nv)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        np.testing.assert_array_equal(loaded.mass(q), M)
        bias = pin.rnea(model, data, q, v, np.zeros(model.nv))
        np.testing.assert_array_equal(loaded.bias(q, v), bias)
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(loaded.frame_jacobian(q), J, rtol=0, atol=1e-12)


@needs_extension
@pytest.mark.parametrize("name, task", [("panda", "position"), ("planar7", "planar")])
def test_the_floor_loop_is_the_python_loop(name, task):
    """The bare C++ loop that benchmarks/closed_loop.py times computes what its Python twin does."""
    robot = arm(name, task)
    q0 = random_configurations(robot, 1, seed=2)[0]
    v0 = np.linspace(-0.5, 0.5, robot.nq)
    loaded = compiled.load_model(robot.model, robot.task_frame)
    ours = cpp_floor_loop(loaded, q0, v0, 200, 1e-3)
    theirs = python_floor_loop(robot.model, robot.task_frame, q0, v0, 200, 1e-3)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-10)


def test_without_the_extension_the_package_says_why(monkeypatch):
    """A machine without a compiler: available() is False, the reason says how to get the loop,
    and asking for it is one clear error, not an ImportError from deep inside."""
    import importlib

    real = importlib.import_module

    def missing(name, *args):
        if "_loop" in name:
            raise ImportError(f"No module named {name!r}")
        return real(name, *args)

    monkeypatch.setattr(compiled, "_MODULE", None)
    monkeypatch.setattr(compiled, "_REASON", "")
    monkeypatch.setattr(importlib, "import_module", missing)
    assert not compiled.available()
    assert "reinstall nnrobust with a C++ compiler" in compiled.unavailable_reason()
    with pytest.raises(NNRobustError, match="the compiled loop is not built"):
        robot = paper_robot()
        compiled.load_model(robot.model, robot.task_frame)
    # auto falls back to the Python loop with one clear warning; the run still works
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import build, choose_backend, run_experiment

    config = load_preset("paper-ellipse").replace(simulation={"duration": 0.2})
    with pytest.warns(UserWarning, match="running on the Python backend: the compiled loop is not built"):
        assert choose_backend(build(config)) == "python"
    with pytest.warns(UserWarning):
        assert run_experiment(config).metrics()["backend"] == "python"


# ---- the compiled closed loop against the Python reference -------------------------------------

PAPER_PRESETS = [
    "paper-ellipse",
    "paper-line",
    "paper-ellipse-noisy",
    "paper-ellipse-paper-law",
    "paper-ellipse-vertical",
]
ARM_PRESETS = ["panda-ellipse", "panda-pose", "ur5-ellipse", "planar7-ellipse"]
"""Presets on Pinocchio nominal models (perturbed URDFs), planar, position and pose tasks, the
manipulability and joint-range criteria, the error-space NN basis."""
KINDS = ["nn", "no-u0", "sliding-mode", "computed-torque", "pd"]


def _both_backends(preset, duration, **changes):
    from nnrobust.config import step_rotation_limit
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import build
    from nnrobust.run.simulation import simulate

    simulation = {"duration": duration, **changes.pop("simulation", {})}
    config = load_preset(preset).replace(simulation=simulation, **changes)
    setup = build(config)
    assert compiled.twin_refusal(setup) == ""
    reference = simulate(
        setup.plant,
        setup.controller,
        setup.q0,
        setup.v0,
        duration,
        config.simulation.control_period,
        setup.substeps,
        max_step_rotation=step_rotation_limit(config),
    )
    setup = build(config)  # fresh sensor noise generator and controller state
    return reference, compiled.simulate_compiled(setup, duration)


@needs_extension
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("preset", PAPER_PRESETS + ARM_PRESETS)
def test_compiled_loop_equals_the_python_loop(preset, kind):
    """q, q', tau, tau_cmd, the controller state and every signal agree to 1e-8 over the first
    0.5 s (0.25 s on the real arms), for every preset with a compiled twin and every controller
    (saturation, stops, noise, quantisation and delay included)."""
    py, cc = _both_backends(preset, 0.5 if preset in PAPER_PRESETS else 0.25, controller={"kind": kind})
    assert cc.status == py.status == "completed"
    for name in ("t", "q", "dq", "tau", "tau_cmd", "z"):
        a, b = getattr(py, name), getattr(cc, name)
        assert a.shape == b.shape, name
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-8, err_msg=name)
    assert py.signals.keys() == cc.signals.keys()
    for name in py.signals:
        np.testing.assert_allclose(cc.signals[name], py.signals[name], rtol=0, atol=1e-8, err_msg=name)


@needs_extension
@pytest.mark.parametrize("preset", ["paper-ellipse"])
def test_compiled_metrics_match_over_a_full_run(preset):
    """Over the full 20 s the metrics agree within 1 %, and metrics.json says which loop ran."""
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import run_experiment

    config = load_preset(preset)
    py = run_experiment(config.replace(simulation={"backend": "python"})).metrics()
    cc = run_experiment(config.replace(simulation={"backend": "compiled"})).metrics()
    assert (py["backend"], cc["backend"]) == ("python", "compiled")
    for key in ("rms_error_after_2s", "max_error", "rms_torque", "torque_chatter", "final_rho_hat"):
        assert cc[key] == pytest.approx(py[key], rel=0.01), key
    assert cc["warnings"] == py["warnings"]


@needs_extension
def test_auto_takes_the_compiled_loop_only_with_a_twin_for_every_component():
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import build, choose_backend

    paper = build(load_preset("paper-ellipse").replace(simulation={"duration": 1.0}))
    assert choose_backend(paper) == "compiled"
    assert (
        choose_backend(build(load_preset("panda-ellipse").replace(simulation={"duration": 1.0})))
        == "compiled"
    )
    stiff = build(load_preset("panda-pose").replace(simulation={"duration": 1.0, "integrator": "solve_ivp"}))
    assert choose_backend(stiff) == "python"
    assert compiled.twin_refusal(stiff) == "the integrator 'solve_ivp' has no compiled twin yet"
    with pytest.raises(NNRobustError, match="simulation.backend: 'compiled' cannot run this experiment"):
        choose_backend(
            build(
                load_preset("panda-pose").replace(
                    simulation={"duration": 1.0, "backend": "compiled", "integrator": "solve_ivp"}
                )
            )
        )


@needs_extension
def test_a_compiled_run_diverges_like_the_python_run():
    """Unstable gains without actuator limits: both loops stop at the same step, naming the joint,
    having cut the same periods' steps as the joints sped up (simulation.max_step_rotation)."""
    changes = {"controller": {"Kp": [1e6], "Kv": [2e3]}, "plant": {"torque_limits": "none"}}
    py, cc = _both_backends("paper-ellipse", 2.0, **changes)
    assert py.status == cc.status == "diverged"
    assert cc.t.size == py.t.size and cc.message == py.message
    assert cc.refined_periods == py.refined_periods > 0


@needs_extension
@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-ellipse"])
def test_the_speed_adaptive_step_is_the_same_on_both_loops(preset):
    """With simulation.max_step_rotation small enough to cut most periods (10 µrad: above 0.01 rad/s),
    both loops cut the same periods into the same steps: the arrays agree to 1e-8, the counts
    exactly (stick-slip events located inside the cut steps included)."""
    py, cc = _both_backends(preset, 0.2, simulation={"max_step_rotation": 1e-5})
    assert cc.status == py.status == "completed"
    assert cc.refined_periods == py.refined_periods > 100
    assert cc.friction_events == py.friction_events
    for name in ("q", "dq", "tau", "z"):
        np.testing.assert_allclose(getattr(cc, name), getattr(py, name), rtol=0, atol=1e-8, err_msg=name)


@needs_extension
def test_the_step_is_cut_at_the_stops_alike_on_both_loops():
    """Computed torque on paper-line throws the wrist into its stops within 2 s: both loops cut
    the same periods for the stops' ring frequencies (simulation.step_rate) and agree to 1e-9."""
    py, cc = _both_backends("paper-line", 2.0, controller={"kind": "computed-torque"})
    assert cc.status == py.status == "completed"
    assert np.max(np.maximum(py.q - 2.8, -2.8 - py.q)[:, 1:]) > 0.01  # in a stop
    assert cc.refined_periods == py.refined_periods > 100
    np.testing.assert_allclose(cc.q, py.q, rtol=0, atol=1e-9)


@needs_extension
@pytest.mark.parametrize("preset", ["paper-ellipse", "paper-line", "panda-ellipse", "panda-pose"])
def test_a_compiled_result_equals_the_python_result(preset):
    """What the compiled loop records for the Result (chain points, x, e, the criterion h and the
    manipulability, from the true robot's kinematics) equals what Result.from_trace computes."""
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import run_experiment

    config = load_preset(preset).replace(simulation={"duration": 0.5})
    py = run_experiment(config.replace(simulation={"backend": "python"}))
    cc = run_experiment(config.replace(simulation={"backend": "compiled"}))
    for name in ("x", "x_d", "e", "chain"):
        np.testing.assert_allclose(getattr(cc, name), getattr(py, name), rtol=0, atol=1e-9, err_msg=name)
    for name in ("h", "manipulability"):
        np.testing.assert_allclose(cc.signals[name], py.signals[name], rtol=0, atol=1e-9, err_msg=name)
    assert cc.metrics()["min_manipulability"] == pytest.approx(py.metrics()["min_manipulability"], rel=1e-9)


@needs_extension
def test_a_batch_on_threads_equals_the_runs_one_by_one():
    """simulate_batch runs experiments on C++ threads with the GIL released: the same traces,
    bit for bit, as running each alone (closed-form and Pinocchio nominal models mixed)."""
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import build

    presets = ["paper-ellipse", "panda-ellipse", "paper-ellipse-noisy", "ur5-ellipse", "panda-pose"]

    def setups():
        return [build(load_preset(p).replace(simulation={"duration": 0.5})) for p in presets]

    alone = [compiled.simulate_compiled(s, 0.5) for s in setups()]
    batch = compiled.simulate_batch(setups(), threads=2)
    assert [t.status for t in batch] == ["completed"] * len(presets)
    for a, b in zip(alone, batch):
        for name in ("q", "dq", "tau", "tau_cmd", "z"):
            np.testing.assert_array_equal(getattr(b, name), getattr(a, name))
        assert b.signals.keys() == a.signals.keys()


@needs_extension
def test_ctrl_c_stops_every_run_of_a_batch():
    """SIGINT while a batch runs: every run stops within a few hundred steps and keeps what it
    computed, marked interrupted; no exception escapes."""
    import os
    import signal
    import threading

    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import build

    setups = [build(load_preset("panda-ellipse").replace(simulation={"duration": 60.0})) for _ in range(3)]
    # Python's own Ctrl-C handler, whatever this process inherited: started in the background by a
    # non-interactive shell, it inherits SIGINT ignored, and Python leaves it so
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        traces = compiled.simulate_batch(setups, threads=2)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert [t.status for t in traces] == ["interrupted"] * 3
    assert all(t.t.size < 60_000 for t in traces)
    assert all("interrupted at t =" in t.message for t in traces)


@needs_extension
@pytest.mark.parametrize("preset", ["paper-ellipse", "planar7-ellipse"])
def test_obstacle_and_smoothness_criteria_are_compiled(preset):
    """The obstacle criterion (with an obstacle inside its influence along the run) and joint
    smoothness, on the closed-form and on a Pinocchio nominal model: equal to Python to 1e-8,
    and the recorded h equals Result.from_trace's."""
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import build, run_experiment

    setup = build(load_preset(preset))
    n, chain = setup.robot.nq, setup.robot.chain_points(setup.q0)
    near = 0.5 * (chain[1] + chain[2]) + np.array([0.0, 0.08, 0.0])  # 8 cm off the second link
    subtasks = {
        "criteria": ["obstacles", "joint_smoothness"],
        "weights": [0.7, 0.3],
        "obstacles": [[*near, 0.03]],
        "obstacle_influence": 0.2,
        "link_radius": 0.01,
        "smoothness_coefficients": [0.5, -1.0, 1.0] + [0.2] * (n - 3),
    }
    py, cc = _both_backends(preset, 0.5, subtasks=subtasks)
    for name in ("q", "dq", "tau", "z"):
        np.testing.assert_allclose(getattr(cc, name), getattr(py, name), rtol=0, atol=1e-8, err_msg=name)
    obstacles_only = dict(subtasks, criteria=["obstacles"], weights=[1.0])
    config = load_preset(preset).replace(simulation={"duration": 0.3}, subtasks=obstacles_only)
    h_py = run_experiment(config.replace(simulation={"backend": "python"})).signals["h"]
    h_cc = run_experiment(config.replace(simulation={"backend": "compiled"})).signals["h"]
    np.testing.assert_allclose(h_cc, h_py, rtol=0, atol=1e-10)
    assert np.min(h_py) < 0  # the obstacle is within its influence: the criterion is not idle


@needs_extension
def test_per_joint_plant_scales_are_the_same_on_both_loops():
    """Per-joint friction and disturbance scales, a disturbance frequency scale and phase shift:
    the compiled loop and the Python loop agree to 1e-8 (both read the built plant)."""
    plant = {
        "joint_friction_scales": [0.5, 2.0, 1.5],
        "joint_disturbance_scales": [2.0, 0.5],
        "disturbance_omega_scale": 1.3,
        "disturbance_phase_shift": 0.7,
    }
    py, cc = _both_backends("paper-ellipse", 0.5, plant=plant)
    assert cc.status == py.status == "completed"
    for name in ("q", "dq", "tau"):
        np.testing.assert_allclose(getattr(cc, name), getattr(py, name), rtol=0, atol=1e-8, err_msg=name)


@needs_extension
def test_a_joint_without_a_compiled_twin_is_named():
    """A joint type the C++ side does not rebuild (a ball joint) is refused by name, never mangled."""
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    model.inertias[joint] = pin.Inertia.Random()
    model.addFrame(pin.Frame("tip", joint, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    with pytest.raises(NNRobustError, match="a joint of type JointModelSpherical has no compiled twin"):
        compiled.load_model(model, "tip")
