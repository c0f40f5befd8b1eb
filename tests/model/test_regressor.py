"""The torque regressor and the base parameters, against independent references: Pinocchio's RNEA,
the paper's closed-form three-link model (linear in beta and p), an SVD's rank, and bodies whose
physical validity is known."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from nnrobust.model import ThreeLinkParameters, ThreeLinkPlanarModel
from nnrobust.model.loading import load_robot
from nnrobust.model.regressor import (
    ParameterLayout,
    base_parameters,
    body_problems,
    friction_regressor,
    inertial_vector,
    mass_matrix_audit,
    pseudo_inertia,
    torque_regressor,
    with_inertial_vector,
)


def _states(n, count=20, seed=0):
    rng = np.random.default_rng(seed)
    return rng.uniform(-2, 2, (count, n)), rng.standard_normal((count, n)), rng.standard_normal((count, n))


@pytest.mark.parametrize(
    "source, task", [("three_link_planar", "planar"), ("panda", "position"), ("ur5", "position")]
)
def test_the_regressor_times_the_parameters_is_the_inverse_dynamics(source, task):
    model = load_robot(source, task=task).model
    q, v, a = _states(model.nv)
    Y = torque_regressor(model, q, v, a)
    data = model.createData()
    rnea = np.array([pin.rnea(model, data, *s) for s in zip(q, v, a)])
    assert np.allclose(Y @ inertial_vector(model), rnea, atol=1e-10)
    # and the base parameters carry the same torques
    layout = ParameterLayout(tuple(model.names[1:]))
    base = base_parameters(model, layout.names[: 10 * model.nv])
    phi = inertial_vector(model)
    assert np.allclose(Y[:, :, base.base] @ base.of(phi), rnea, atol=1e-9)
    # the rank is the SVD's of a larger, independent stack
    W = torque_regressor(model, *_states(model.nv, 200, seed=7)).reshape(-1, 10 * model.nv)
    s = np.linalg.svd(W, compute_uv=False)
    assert base.rank == int(np.sum(s > 1e-8 * s[0]))


@pytest.mark.parametrize(
    "source, task", [("three_link_planar", "planar"), ("panda", "position"), ("ur5", "position")]
)
def test_the_compiled_regressor_rows_are_pinocchios(source, task):
    """identify's rows in one C++ call per batch (csrc/model/regressor.hpp) are
    pinocchio.computeJointTorqueRegressor's, state by state."""
    from nnrobust.run import compiled

    if not compiled.available():
        pytest.skip(compiled.unavailable_reason())
    model = load_robot(source, task=task).model
    q, v, a = _states(model.nv, count=50, seed=3)
    rows = compiled.torque_regressor_of(model)(q, v, a)
    reference = torque_regressor(model, q, v, a)
    assert rows.shape == reference.shape
    assert np.abs(rows - reference).max() <= 1e-12 * max(1.0, np.abs(reference).max())


def test_the_base_parameters_give_the_paper_closed_forms_torques():
    """For random links (masses, centres of mass on the link axes, inertias), the closed form of
    the paper (from_links) and Y_b beta of the base parameters give the same torques; the planar
    arm has 7 base parameters (Khalil: ZZ1R, ZZ2R, ZZ3, MX2R, MY2, MX3, MY3)."""
    robot = load_robot("three_link_planar")
    lengths = ThreeLinkParameters.from_pinocchio(robot.model, robot.task_frame).lengths
    rng = np.random.default_rng(5)
    q, v, a = _states(3, 10, seed=3)
    layout = ParameterLayout(tuple(robot.model.names[1:]))
    for _ in range(5):
        masses, com, izz = rng.uniform(0.5, 3, 3), rng.uniform(0.05, 0.2, 3), rng.uniform(0.01, 0.1, 3)
        model = pin.Model(robot.model)
        for j in range(3):
            model.inertias[j + 1] = pin.Inertia(masses[j], np.array([com[j], 0, 0]), np.diag([izz[j]] * 3))
        closed = ThreeLinkPlanarModel(
            ThreeLinkParameters.from_links(tuple(masses), lengths, tuple(com), tuple(izz))
        )
        base = base_parameters(model, layout.names[:30])
        Y = torque_regressor(model, q, v, a)[:, :, base.base]
        expected = np.array([closed.inverse_dynamics(*s) for s in zip(q, v, a)])
        assert np.allclose(Y @ base.of(inertial_vector(model)), expected, atol=1e-10)
        assert base.rank == 7


def test_with_inertial_vector_round_trips():
    model = load_robot("panda", task="position").model
    phi = inertial_vector(model)
    again = with_inertial_vector(model, phi)
    assert np.allclose(inertial_vector(again), phi)
    assert again is not model and body_problems(again) == []


def test_the_pseudo_inertia_is_positive_exactly_for_physical_bodies():
    rng = np.random.default_rng(0)
    for _ in range(50):  # point masses spread around: a physical body
        points, masses = rng.normal(0, 0.1, (6, 3)), rng.uniform(0.1, 1, 6)
        body = sum((pin.Inertia(m, p, np.zeros((3, 3))) for m, p in zip(masses, points)), pin.Inertia.Zero())
        assert np.linalg.eigvalsh(pseudo_inertia(body.toDynamicParameters()))[0] > -1e-12
    # principal moments 1, 1, 3: no density has them (the triangle inequality fails)
    bad = pin.Inertia(1.0, np.zeros(3), np.diag([1.0, 1.0, 3.0]))
    assert np.linalg.eigvalsh(pseudo_inertia(bad.toDynamicParameters()))[0] < 0
    model = pin.Model(load_robot("three_link_planar").model)  # a copy: the loaded model is shared
    model.inertias[2] = bad
    assert "triangle inequality" in body_problems(model)[0]


def test_the_friction_columns_are_the_plants_law():
    from nnrobust.plant.friction import Friction

    layout = ParameterLayout(("a", "b"), ("viscous", "coulomb", "offset"), armature=True)
    v, a = np.array([[0.5, -0.2], [0.0, 1.0]]), np.array([[1.0, 2.0], [3.0, 4.0]])
    F = friction_regressor(layout, v, a)
    fd, fc, off, arm = (
        np.array([0.1, 0.2]),
        np.array([0.3, 0.4]),
        np.array([0.05, -0.05]),
        np.array([0.01, 0.02]),
    )
    coefficients = np.concatenate([fd, fc, off, arm])
    assert np.allclose(F @ coefficients, Friction(fd, fc).torque(v) + off + arm * a)
    assert layout.names[20:22] == ["viscous@a", "viscous@b"] and layout.size == 28


def test_the_mass_matrix_audit_finds_a_body_that_breaks_it():
    model = load_robot("three_link_planar").model
    assert mass_matrix_audit(model, poses=20)[0] > 0
    negative = pin.Model(model)
    negative.inertias[3] = pin.Inertia.FromDynamicParameters(np.array([1.0, 0, 0, 0, -1, 0, -1, 0, 0, -1]))
    assert mass_matrix_audit(negative, poses=20)[0] < 0
