"""Task kinds on real arms: x, J and J'q' against finite differences, the pose trajectory, IK."""

import numpy as np
import pinocchio as pin
import pytest

from nnrobust.model import planar_chain_urdf
from nnrobust.model.ik import solve_ik
from nnrobust.model.tasks import pose_vector, split_pose, task_error
from nnrobust.trajectories import EllipseTrajectory, PoseTrajectory
from tests.arms import ARM_CASES, arm, random_configurations

H = 1e-6


def _jacobian_fd(robot, q):
    """Columns d x / d q_k: position by central differences, orientation as log3(R+ R-^T) / 2h."""
    cols = []
    for k in range(robot.nq):
        dq = np.zeros(robot.nq)
        dq[k] = H
        xp, xm = robot.task_position(q + dq), robot.task_position(q - dq)
        if robot.task == "pose":
            (pp, Rp), (pm, Rm) = split_pose(xp), split_pose(xm)
            cols.append(np.concatenate([pp - pm, pin.log3(Rp @ Rm.T)]) / (2 * H))
        else:
            cols.append((xp - xm) / (2 * H))
    return np.array(cols).T


@pytest.mark.parametrize(("name", "task"), ARM_CASES)
def test_jacobian_and_jdot_v_match_finite_differences(name, task):
    robot = arm(name, task)
    rng = np.random.default_rng(4)
    for q in random_configurations(robot, 5, seed=3):
        v = rng.uniform(-2, 2, robot.nq)
        x, J, jdot_v = robot.task_state(q, v)
        assert J.shape == (robot.m, robot.nq)
        np.testing.assert_allclose(x, robot.task_position(q), atol=1e-12)
        np.testing.assert_allclose(J, robot.task_jacobian(q), atol=1e-12)
        np.testing.assert_allclose(J, _jacobian_fd(robot, q), atol=1e-7)
        jdot_fd = (robot.task_jacobian(q + H * v) - robot.task_jacobian(q - H * v)) @ v / (2 * H)
        np.testing.assert_allclose(jdot_v, jdot_fd, atol=1e-6)


@pytest.mark.parametrize(("name", "task"), [("panda", "pose"), ("ur5", "position"), ("planar7", "planar")])
def test_jacobian_derivative_matches_finite_differences(name, task):
    robot = arm(name, task)
    q = random_configurations(robot, 1, seed=5)[0]
    H3 = robot.task_jacobian_derivative(q)
    for k in range(robot.nq):
        e = np.zeros(robot.nq)
        e[k] = H
        fd = (robot.task_jacobian(q + e) - robot.task_jacobian(q - e)) / (2 * H)
        np.testing.assert_allclose(H3[:, :, k], fd, atol=1e-7)


@pytest.mark.parametrize(
    ("name", "task"), [("panda", "position"), ("planar7", "planar"), ("three_link_planar", "planar")]
)
def test_chain_jacobians_match_finite_differences(name, task):
    robot = arm(name, task)
    q = random_configurations(robot, 1, seed=6)[0]
    Js = robot.chain_jacobians(q)
    assert Js.shape == (robot.nq + 1, 3, robot.nq)
    np.testing.assert_allclose(robot.chain_points(q)[-1][: robot.m], robot.task_position(q)[: robot.m])
    for k in range(robot.nq):
        e = np.zeros(robot.nq)
        e[k] = H
        fd = (robot.chain_points(q + e) - robot.chain_points(q - e)) / (2 * H)
        np.testing.assert_allclose(Js[:, :, k], fd, atol=1e-7)


def test_closed_form_chain_jacobians_match_pinocchio():
    from tests.problems import closed_form_of, paper_robot

    robot = paper_robot()
    oracle = closed_form_of(robot)
    for q in random_configurations(robot, 5, seed=7):
        np.testing.assert_allclose(oracle.chain_points(q), robot.chain_points(q)[:, :], atol=1e-12)
        np.testing.assert_allclose(oracle.chain_jacobians(q), robot.chain_jacobians(q), atol=1e-12)


def test_pose_error_is_the_rotation_between_the_frames():
    rng = np.random.default_rng(8)
    R_d = pin.exp3(rng.normal(size=3))
    w = np.array([0.1, -0.2, 0.3])
    x = pose_vector(np.array([1.0, 2.0, 3.0]), pin.exp3(w) @ R_d)
    x_d = pose_vector(np.array([0.5, 2.0, 3.5]), R_d)
    np.testing.assert_allclose(task_error("pose", x, x_d), [0.5, 0.0, -0.5, *w], atol=1e-12)
    np.testing.assert_allclose(task_error("pose", x_d, x_d), np.zeros(6), atol=1e-12)


def test_pose_trajectory_derivatives_match_finite_differences():
    path = EllipseTrajectory([0.4, 0.1, 0.5], [0.1, 0.0, 0.0], [0.0, 0.1, 0.05], omega=1.3)
    traj = PoseTrajectory(path, pin.rpy.rpyToMatrix(np.pi, 0.2, 0.1), [1.0, 1.0, 0.0], 0.4, 2.0, 0.3)
    for t in (0.0, 0.7, 2.9):
        x, dx, ddx = traj(t)
        (pp, Rp), (pm, Rm) = split_pose(traj(t + H)[0]), split_pose(traj(t - H)[0])
        np.testing.assert_allclose(dx[:3], (pp - pm) / (2 * H), atol=1e-7)
        np.testing.assert_allclose(dx[3:], pin.log3(Rp @ Rm.T) / (2 * H), atol=1e-7)
        np.testing.assert_allclose(ddx, (traj(t + H)[1] - traj(t - H)[1]) / (2 * H), atol=1e-6)
        np.testing.assert_allclose(traj.position(np.array([t]))[0, 3:], pin.log3(split_pose(x)[1]))


@pytest.mark.parametrize(("name", "task"), [("panda", "pose"), ("ur5", "position"), ("planar7", "planar")])
def test_ik_reaches_a_reachable_target(name, task):
    """A target made by forward kinematics from a random q is reached from another seed."""
    robot = arm(name, task)
    q_true, seed = random_configurations(robot, 2, seed=9)
    q_seed = q_true + 0.3 * (seed - q_true) / np.linalg.norm(seed - q_true)
    target = robot.task_position(q_true)
    q, residual = solve_ik(robot, target, q_seed, robot.lower_limits, robot.upper_limits)
    assert residual < 1e-9
    np.testing.assert_allclose(task_error(task, robot.task_position(q), target), 0.0, atol=1e-9)


@pytest.mark.parametrize("n", [3, 30, 120])
def test_generated_planar_chain(n):
    """The generated chain has n joints, reach = sum of lengths, and the rod inertia about joint 1."""
    from nnrobust import load_robot

    lengths = np.linspace(0.2, 0.1, n)
    masses = np.linspace(2.0, 1.0, n)
    robot = load_robot(planar_chain_urdf(n, lengths, masses, damping=0.3, friction=0.1))
    assert robot.nq == n and robot.task_frame == "tool"
    np.testing.assert_allclose(robot.task_position(np.zeros(n)), [lengths.sum(), 0.0], atol=1e-12)
    starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    izz = masses * (lengths**2 + 0.03**2) / 12
    inertia_about_base = np.sum(masses * (starts + lengths / 2) ** 2 + izz)
    assert robot.mass(np.zeros(n))[0, 0] == pytest.approx(inertia_about_base, rel=1e-8)  # URDF keeps 9 digits
    np.testing.assert_allclose(robot.viscous_friction, 0.3)
    np.testing.assert_allclose(robot.coulomb_friction, 0.1)
    np.testing.assert_allclose(robot.gravity(np.full(n, 0.3)), 0.0, atol=1e-12)
    assert np.all(robot.effort_limits > 0)


def test_generated_chain_rejects_bad_parameters():
    with pytest.raises(ValueError, match="lengths has 2 entries"):
        planar_chain_urdf(3, lengths=[0.1, 0.2])
    with pytest.raises(ValueError, match="masses must be positive"):
        planar_chain_urdf(3, masses=0.0)
    with pytest.raises(ValueError, match="n must be a positive integer"):
        planar_chain_urdf(0)


def test_joint_count_is_bounded_by_pinocchio_memory():
    """pin.Data grows as n^3; more than MAX_JOINTS joints is refused with the reason."""
    from nnrobust import load_robot
    from nnrobust.core.exceptions import ModelMismatch, RobotLoadError
    from nnrobust.model.pinocchio_model import MAX_JOINTS

    with pytest.raises(RobotLoadError, match="1 to 300 links"):
        load_robot(f"planar{MAX_JOINTS + 1}")
    with pytest.raises(ModelMismatch, match="at most 300 are supported"):
        load_robot(planar_chain_urdf(MAX_JOINTS + 1))
