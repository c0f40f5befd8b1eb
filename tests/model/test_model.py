import numpy as np
import pytest

from nnrobust import load_robot
from nnrobust.core.exceptions import FrameNotFound, ModelMismatch, NNRobustError, RobotLoadError
from nnrobust.model import DynamicsModel, ThreeLinkParameters, ThreeLinkPlanarModel, paper_arm_urdf
from tests.paper_printed import printed_coriolis, printed_mass
from tests.problems import (
    VERTICAL_GRAVITY,
    closed_form_of,
    finite_difference,
    paper_robot,
    random_states,
)

TOL = 1e-10


@pytest.mark.parametrize("gravity", [None, VERTICAL_GRAVITY], ids=["horizontal", "vertical"])
def test_pinocchio_agrees_with_closed_form(gravity):
    """On 100 random states M, V_m q', G, x, J, J'q', dJ/dq agree to 1e-10."""
    robot = paper_robot(gravity)
    oracle = closed_form_of(robot)
    for q, v, a in random_states(3, 100, seed=1):
        np.testing.assert_allclose(robot.mass(q), oracle.mass(q), atol=TOL)
        np.testing.assert_allclose(robot.bias(q, v), oracle.bias(q, v), atol=TOL)
        np.testing.assert_allclose(robot.gravity(q), oracle.gravity(q), atol=TOL)
        np.testing.assert_allclose(robot.coriolis_matrix(q, v), oracle.coriolis_matrix(q, v), atol=TOL)
        np.testing.assert_allclose(robot.task_position(q), oracle.task_position(q), atol=TOL)
        np.testing.assert_allclose(robot.task_jacobian(q), oracle.task_jacobian(q), atol=TOL)
        np.testing.assert_allclose(robot.task_jdot_v(q, v), oracle.task_jdot_v(q, v), atol=TOL)
        np.testing.assert_allclose(
            robot.task_jacobian_derivative(q), oracle.task_jacobian_derivative(q), atol=TOL
        )
        np.testing.assert_allclose(
            robot.inverse_dynamics(q, v, a), oracle.inverse_dynamics(q, v, a), atol=TOL
        )
        np.testing.assert_allclose(
            robot.forward_dynamics(q, v, a), oracle.forward_dynamics(q, v, a), atol=1e-8
        )


def test_potential_energy_gradient_is_gravity():
    """G = dU/dq for both models (finite differences of U)."""
    robot = paper_robot(VERTICAL_GRAVITY)
    oracle = closed_form_of(robot)
    for q, _, _ in random_states(3, 10, seed=2):
        for model in (robot, oracle):
            grad = np.array(
                [finite_difference(lambda x: np.array(model.potential_energy(x)), q, d) for d in np.eye(3)]
            ).ravel()
            np.testing.assert_allclose(grad, model.gravity(q), atol=1e-6)


@pytest.mark.parametrize("which", ["pinocchio", "closed-form"])
def test_mdot_minus_2v_is_skew_symmetric(which):
    """M' - 2 V_m is skew-symmetric (M' by finite differences along q')."""
    robot = paper_robot()
    model = robot if which == "pinocchio" else closed_form_of(robot)
    for q, v, _ in random_states(3, 20, seed=3):
        Mdot = finite_difference(model.mass, q, v)
        S = Mdot - 2 * model.coriolis_matrix(q, v)
        np.testing.assert_allclose(S + S.T, 0, atol=1e-7)


def test_jdot_v_matches_finite_difference_of_jacobian():
    """J'q' equals (d/dt J(q + t q')) q' by central differences, for both models."""
    robot = paper_robot()
    for model in (robot, closed_form_of(robot)):
        for q, v, _ in random_states(3, 20, seed=4):
            np.testing.assert_allclose(
                model.task_jdot_v(q, v), finite_difference(model.task_jacobian, q, v) @ v, atol=1e-7
            )


def test_jacobian_is_derivative_of_task_position():
    """J = dx/dq column by column."""
    robot = paper_robot()
    for q, _, _ in random_states(3, 10, seed=5):
        fd = np.column_stack([finite_difference(robot.task_position, q, d) for d in np.eye(3)])
        np.testing.assert_allclose(robot.task_jacobian(q), fd, atol=1e-8)


def test_both_models_implement_the_interface():
    """The Protocol is satisfied by both implementations."""
    robot = paper_robot()
    assert isinstance(robot, DynamicsModel)
    assert isinstance(closed_form_of(robot), DynamicsModel)


# ---- errata: the printed matrices ---------------------------------------------------------


def test_printed_mass_matrix_is_wrong():
    """Printed M is not positive definite at q = 0 and differs from Pinocchio's M."""
    robot = paper_robot()
    params = ThreeLinkParameters.from_pinocchio(robot.model, robot.task_frame)
    q0 = np.zeros(3)
    M = printed_mass(q0, params.beta, params.p)
    assert np.min(np.linalg.eigvalsh(M)) < -0.03  # an inertia matrix must be positive definite
    worst = max(
        np.abs(printed_mass(q, params.beta, params.p) - robot.mass(q)).max()
        for q, _, _ in random_states(3, 20, seed=6)
    )
    assert worst > 0.1


def test_printed_coriolis_matrix_is_wrong():
    """Printed V_m breaks the skew-symmetry of M' - 2 V_m and differs from Pinocchio's."""
    robot = paper_robot()
    params = ThreeLinkParameters.from_pinocchio(robot.model, robot.task_frame)
    q, v = np.array([0.3, 0.7, -0.5]), np.array([1.0, -0.5, 0.8])
    V = printed_coriolis(q, v, params.p)
    Mdot = finite_difference(robot.mass, q, v)
    S = Mdot - 2 * V
    assert np.abs(S + S.T).max() > 0.05
    assert np.abs(V @ v - robot.coriolis_matrix(q, v) @ v).max() > 0.05


# ---- loading ------------------------------------------------------------------------------


def test_load_by_path_string_and_name_agree():
    """A URDF path, its XML text and the shipped name give the same model."""
    q = np.array([0.1, 0.2, 0.3])
    a = load_robot(paper_arm_urdf())
    b = load_robot(paper_arm_urdf().read_text())
    c = load_robot("three_link_planar")
    for other in (b, c):
        np.testing.assert_allclose(a.mass(q), other.mass(q))
    assert a.task_frame == "tool" and a.m == 2 and a.nq == 3


def test_example_robot_data_arm_loads_with_position_task():
    """An example-robot-data arm (UR5) loads with a 3-D position task."""
    ur5 = load_robot("ur5", task="position")
    assert ur5.nq == 6 and ur5.m == 3
    assert ur5.task_jacobian(np.zeros(6)).shape == (3, 6)


def test_load_errors_are_clear(tmp_path):
    """Missing file, bad XML, unknown robot and unknown frame raise the library's errors."""
    with pytest.raises(RobotLoadError, match="no such file"):
        load_robot(tmp_path / "missing.urdf")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'></robot>")
    with pytest.raises(RobotLoadError, match="bad.urdf"):
        load_robot(bad)
    with pytest.raises(RobotLoadError, match="not a URDF file"):
        load_robot("no_such_robot_anywhere")
    with pytest.raises(FrameNotFound, match="tool") as info:
        load_robot("three_link_planar", task_frame="gripper")
    assert "link3" in info.value.available
    with pytest.raises(ModelMismatch, match="valid kinds"):
        load_robot("three_link_planar", task="orientation")
    assert issubclass(RobotLoadError, NNRobustError)


def test_closed_form_rejects_a_non_planar_arm():
    """The closed form refuses a robot it cannot represent."""
    ur5 = load_robot("ur5", task="position")
    with pytest.raises(ModelMismatch):
        ThreeLinkParameters.from_pinocchio(ur5.model, ur5.task_frame)


def test_closed_form_with_paper_estimate_differs_from_truth():
    """The paper's p-hat gives a different (still positive definite) mass matrix."""
    truth = ThreeLinkPlanarModel(ThreeLinkParameters.paper())
    estimate = ThreeLinkPlanarModel(ThreeLinkParameters.paper_estimate())
    q = np.array([0.2, 0.4, 0.6])
    assert np.abs(truth.mass(q) - estimate.mass(q)).max() > 0.05
    assert np.min(np.linalg.eigvalsh(estimate.mass(q))) > 0
