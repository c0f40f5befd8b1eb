"""Property-based tests (hypothesis): physics and controller invariants on random states, and
the URDF and TOML readers fed random and mutated files."""

import time

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from nnrobust.config import from_dict, load_config
from nnrobust.config.presets import load_preset, preset_path
from nnrobust.controllers import DampedPseudoInverse, project_null_space
from nnrobust.core.exceptions import NNRobustError
from nnrobust.model import load_robot, paper_arm_urdf
from nnrobust.plant import Friction, Plant, SinusoidalDisturbance
from nnrobust.run.experiment import build
from nnrobust.run.simulation import simulate
from tests.arms import arm
from tests.problems import ConstantTorque

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _angles(n):
    return st.lists(st.floats(-np.pi, np.pi), min_size=n, max_size=n).map(np.array)


@pytest.mark.parametrize("name", ["panda", "planar7"])
def test_mass_matrix_is_symmetric_positive_definite(name):
    robot = arm(name, "planar" if name == "planar7" else "position")

    @SETTINGS
    @given(_angles(robot.nq))
    def check(q):
        M = robot.mass(q)
        np.testing.assert_array_equal(M, M.T)
        assert np.linalg.eigvalsh(M)[0] > 0

    check()


@pytest.mark.parametrize(("name", "task"), [("panda", "pose"), ("ur5", "position"), ("planar7", "planar")])
def test_null_space_projection_annihilates_the_task(name, task):
    robot = arm(name, task)
    pinv = DampedPseudoInverse()

    @SETTINGS
    @given(_angles(robot.nq), st.lists(st.floats(-1e3, 1e3), min_size=robot.nq, max_size=robot.nq))
    def check(q, z):
        J = robot.task_jacobian(q)
        assume(np.linalg.svd(J, compute_uv=False)[-1] > pinv.threshold)  # undamped region
        z = np.array(z)
        assert np.linalg.norm(J @ project_null_space(J, pinv.matrix(J), z)) <= 1e-9 * (1 + np.abs(z).sum())

    check()


@settings(max_examples=12, deadline=None)
@given(_angles(3), st.lists(st.floats(-3, 3), min_size=3, max_size=3).map(np.array))
def test_energy_balance_with_friction(q0, v0):
    """Unforced arm with viscous friction: E(0) - E(T) equals the friction work to 1e-6 relative."""
    robot = load_robot("three_link_planar")
    friction = Friction(np.array([0.5, 0.3, 0.1]), np.zeros(3))
    plant = Plant(robot, friction, SinusoidalDisturbance.none(3))
    trace = simulate(plant, ConstantTorque(np.zeros(3)), q0, v0, 0.3, control_period=2.5e-4)
    energy = np.array([plant.energy(q, v) for q, v in zip(trace.q, trace.dq)])
    power = np.array([friction.power(v) for v in trace.dq])
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * 2.5e-4)])
    scale = max(energy[0], 1e-3)
    assert np.all(np.diff(energy) <= 1e-9 * scale)  # never gains energy
    np.testing.assert_allclose(energy[0] - energy, work, atol=2e-4 * scale)


@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-pose"])
def test_controller_output_is_finite_for_any_finite_state(preset):
    """The NN branch included: random adapted weights Z >= 0 (rho-hat up to 1e4) and eps, the
    torque and the next state are finite, u_0 is active (the torque differs from u_0 = 0's), and
    the next weights stay >= 0."""
    setup = build(load_preset(preset).replace(simulation={"duration": 1.0}))
    controller, n = setup.controller, setup.robot.nq
    L = controller.compensator.L

    @SETTINGS
    @given(
        _angles(n),
        st.lists(st.floats(-50, 50), min_size=n, max_size=n).map(np.array),
        st.floats(0, 100),
        st.lists(st.floats(0, 1e3), min_size=L, max_size=L).map(np.array),
        st.floats(0, 2),
    )
    def check(q, v, t, Z, eps):
        z = np.concatenate([Z, [eps]])
        out = controller.compute(t, q, v, z, 1e-3)
        assert out.tau.shape == (n,) and np.all(np.isfinite(out.tau))
        assert np.all(np.isfinite(out.state)) and np.all(out.state[:L] >= 0)
        rho = out.signals["rho_hat"]
        assert np.isfinite(rho) and rho >= 0
        if rho > 1.0 and eps > 0:
            no_u0 = controller.compute(t, q, v, np.zeros_like(z), 1e-3).tau
            assert not np.allclose(out.tau, no_u0)

    check()


def _mutations(text: str):
    """Strategy: the text with a slice deleted, duplicated or replaced by random characters."""
    n = len(text)
    return st.tuples(
        st.integers(0, n),
        st.integers(0, 200),
        st.sampled_from(["delete", "dup", "junk"]),
        st.text(max_size=40),
    ).map(lambda a: _mutate(text, *a))


def _mutate(text, start, length, how, junk):
    end = min(len(text), start + length)
    if how == "delete":
        return text[:start] + text[end:]
    if how == "dup":
        return text[:end] + text[start:end] + text[end:]
    return text[:start] + junk + text[end:]


PAPER_URDF = paper_arm_urdf().read_text()
TIME_BOUND = 5.0  # seconds per input


@settings(max_examples=150, deadline=None)
@given(st.one_of(_mutations(PAPER_URDF), st.text(max_size=300)))
def test_urdf_reader_raises_only_its_own_errors_and_never_hangs(text):
    start = time.perf_counter()
    try:
        robot = load_robot(text if text.lstrip().startswith("<") else "<" + text)
    except NNRobustError:
        pass
    else:
        assert robot.nq >= 1
    assert time.perf_counter() - start < TIME_BOUND


@settings(max_examples=150, deadline=None)
@given(st.one_of(_mutations(preset_path("panda-pose").read_text()), st.text(max_size=300)))
def test_toml_reader_raises_only_its_own_errors_and_never_hangs(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("toml") / "experiment.toml"
    path.write_bytes(text.encode("utf-8", errors="replace"))
    start = time.perf_counter()
    try:
        load_config(path)
    except NNRobustError:
        pass
    assert time.perf_counter() - start < TIME_BOUND


def _field_names():
    """Every key of every configuration section."""
    import dataclasses

    from nnrobust.config import ExperimentConfig

    sections = [
        f.default_factory
        for f in dataclasses.fields(ExperimentConfig)
        if f.default_factory is not dataclasses.MISSING
    ]
    return sorted({f.name for section in sections for f in dataclasses.fields(section)})


@settings(max_examples=100, deadline=None)
@given(
    st.dictionaries(
        st.sampled_from(
            ["controller", "nn", "simulation", "subtasks", "trajectory", "nominal", "plant", "robot"]
        ),
        st.dictionaries(
            st.one_of(st.sampled_from(_field_names()), st.text(max_size=8)),
            st.one_of(
                st.floats(allow_nan=True),
                st.integers(),
                st.text(max_size=5),
                st.lists(st.floats(), max_size=4),
                st.booleans(),
            ),
            max_size=3,
        ),
        max_size=3,
    )
)
def test_configuration_from_random_tables_raises_only_config_errors(data):
    """Real keys with random values (and random keys): from_dict and, when that accepts them,
    building the experiment (robot-dependent checks) raise nothing but the library's errors, and
    an experiment that builds gives a finite first torque."""
    try:
        config = from_dict(data)
        setup = build(config.replace(simulation={"duration": min(config.simulation.duration, 1.0)}))
    except NNRobustError:
        return
    out = setup.controller.compute(0.0, setup.q0, setup.v0, setup.controller.initial_state(), 1e-3)
    assert np.all(np.isfinite(out.tau))
