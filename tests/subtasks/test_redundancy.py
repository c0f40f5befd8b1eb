"""The redundancy toolbox on real arms: gradients by finite differences, and null-space behaviour.

The null-space term must never disturb the task: J (I - J+ J) = 0; with a perfect model the task
error of a run follows e'' + Kv e' + Kp e = 0 whatever the subtasks do; and under pure self-motion
(fixed target) the criterion improves while the task frame stays put.
"""

import numpy as np
import pytest

from nnrobust.controllers import DampedPseudoInverse, TaskSpaceController, project_null_space
from nnrobust.model import PinocchioModel
from nnrobust.model.ik import solve_ik
from nnrobust.plant import Friction, Plant, SinusoidalDisturbance
from nnrobust.run.simulation import simulate
from nnrobust.subtasks import (
    HalfDetManipulability,
    JointCentering,
    JointLimitAvoidance,
    JointSmoothness,
    Manipulability,
    SphereObstacles,
    WeightedCriteria,
)
from nnrobust.trajectories import EllipseTrajectory
from tests.arms import ARM_CASES, arm, random_configurations

GRADIENT_ARMS = [("panda", "position"), ("panda", "pose"), ("ur5", "position"), ("planar7", "planar")]


def _criteria(robot, q):
    """Every criterion, with spheres placed 3-6 cm from two links at q so that they act."""
    points = robot.chain_points(q)
    mids = 0.5 * (points[1:] + points[:-1])
    rng = np.random.default_rng(1)
    near = [mids[len(mids) // 2], mids[-2]]
    centers = [p + 0.05 * rng.normal(size=3) / np.sqrt(3) for p in near]
    return {
        "half_det_manipulability": HalfDetManipulability(),
        "manipulability": Manipulability(),
        "joint_limits": JointLimitAvoidance(robot.lower_limits, robot.upper_limits),
        "joint_centering": JointCentering(robot.lower_limits, robot.upper_limits),
        "joint_smoothness": JointSmoothness(tuple(rng.normal(size=robot.nq))),
        "obstacles": SphereObstacles(centers, [0.02, 0.01], influence=0.1, link_radius=0.01),
    }


@pytest.mark.parametrize(("name", "task"), GRADIENT_ARMS)
def test_every_gradient_matches_finite_differences(name, task):
    robot = arm(name, task)
    for q in random_configurations(robot, 3, seed=11):
        for label, criterion in _criteria(robot, q).items():
            fd = np.empty(robot.nq)
            for k in range(robot.nq):
                e = np.zeros(robot.nq)
                e[k] = 1e-6
                fd[k] = (criterion.value(robot, q + e) - criterion.value(robot, q - e)) / 2e-6
            grad = criterion.gradient(robot, q)
            assert np.any(grad != 0), label
            np.testing.assert_allclose(
                grad, fd, rtol=1e-5, atol=1e-7 * max(1.0, np.abs(fd).max()), err_msg=f"{name} {task} {label}"
            )


def test_joint_criteria_values():
    lower, upper = np.array([-1.0, 0.0]), np.array([1.0, 4.0])
    q_mid = np.array([0.0, 2.0])
    assert JointLimitAvoidance(lower, upper).value(None, q_mid) == pytest.approx(-1.0)
    assert JointCentering(lower, upper).value(None, q_mid) == 0.0
    barrier = JointLimitAvoidance(lower, upper)
    # inside the 5 % margin the barrier is linear: the push back is the barrier's slope at the knot
    # q = 0.9, dh/dq = (u - l)^2 (u + l - 2 q) / (4 n ((u - q)(q - l))^2) = 4 (-1.8) / (8 (0.19)^2)
    knot_slope = 4 * (-1.8) / (8 * 0.19**2)
    for q1 in (0.95, 0.999, 1.0, 1.5):  # near, on and beyond the limit
        grad = barrier.gradient(None, np.array([q1, 2.0]))
        assert grad[0] == pytest.approx(knot_slope) and grad[1] == 0.0  # pushes back, bounded
        assert np.isfinite(barrier.value(None, np.array([q1, 2.0])))
    # the value continues linearly, so it keeps falling beyond the limit (C1 at the knot)
    h = [barrier.value(None, np.array([q1, 2.0])) for q1 in (0.9, 1.0, 1.1)]
    assert h[0] > h[1] > h[2] and h[1] - h[2] == pytest.approx(h[0] - h[1])
    assert barrier.gradient(None, np.array([0.5, 2.0]))[0] < 0  # the barrier itself inside
    with pytest.raises(ValueError, match=r"joints \[1\] have no finite range"):
        JointCentering(lower, np.array([1.0, np.inf]))


def test_obstacle_clearance_of_a_known_segment():
    """A sphere 0.2 m above the middle of a straight planar chain: clearance 0.2 - r - link radius."""
    robot = arm("planar7", "planar")
    q = np.zeros(robot.nq)
    obstacle = SphereObstacles([[0.5, 0.0, 0.2]], [0.05], influence=0.3, link_radius=0.01)
    assert obstacle.clearance(robot, q) == pytest.approx(0.14)
    ends = np.linspace(0.0, 1.0, 8)  # joint origins and the tool along x
    dx = np.maximum(0.0, np.maximum(ends[:-1] - 0.5, 0.5 - ends[1:]))
    depth = np.maximum(0.0, 0.3 - (np.hypot(dx, 0.2) - 0.06))
    assert obstacle.value(robot, q) == pytest.approx(-0.5 * np.sum(depth**2), rel=1e-8)
    assert SphereObstacles([[0.5, 0.0, 2.0]], [0.05]).gradient(robot, q) == pytest.approx(0.0)


# planar7 with a 3-D position task is left out: its z row is zero, so J J^T is singular and the
# damped pseudo-inverse (deliberately) no longer gives an exact projector.
@pytest.mark.parametrize(("name", "task"), [c for c in ARM_CASES if c != ("planar7", "position")])
def test_null_space_projection_annihilates_the_task(name, task):
    robot = arm(name, task)
    pinv = DampedPseudoInverse()
    rng = np.random.default_rng(12)
    for q in random_configurations(robot, 5, seed=13):
        J = robot.task_jacobian(q)
        Jp = pinv.matrix(J)
        z = rng.normal(size=robot.nq)
        projected = project_null_space(J, Jp, z)
        np.testing.assert_allclose(J @ projected, 0.0, atol=1e-12 * np.abs(z).sum())
        np.testing.assert_allclose(projected, (np.eye(robot.nq) - Jp @ J) @ z, atol=1e-12)


def _perfect_run(robot, criterion, k, trajectory, q0, duration=2.0):
    plant = Plant(robot, Friction.none(robot.nq), SinusoidalDisturbance.none(robot.nq))
    nominal = PinocchioModel(robot.model, robot.task_frame, robot.task)
    Kp, Kv = np.diag(np.full(robot.m, 25.0)), np.diag(np.full(robot.m, 10.0))
    controller = TaskSpaceController(nominal, trajectory, Kp, Kv, k, criterion)
    trace = simulate(plant, controller, q0, np.zeros(robot.nq), duration, control_period=1e-3)
    assert trace.status == "completed"
    e = np.array(
        [trajectory.error(robot.task_position(q), trajectory(t)[0]) for t, q in zip(trace.t, trace.q)]
    )
    return trace, e


@pytest.mark.parametrize(
    ("name", "task"), [("panda", "position"), ("ur5", "position"), ("planar7", "planar")]
)
def test_subtasks_do_not_disturb_the_task_error(name, task):
    """Fixed target, start 5 cm off: e(t) = e0 (1 + 5 t) exp(-5 t) (Kp = 25, Kv = 10, critical)."""
    robot = arm(name, task)
    q0 = random_configurations(robot, 1, seed=14)[0]
    x0 = robot.task_position(q0)
    offset = np.full(robot.m, 0.05 / np.sqrt(robot.m))
    target = EllipseTrajectory(x0 - offset, np.zeros(robot.m), np.zeros(robot.m))
    criterion = WeightedCriteria(
        [Manipulability(), JointCentering(robot.lower_limits, robot.upper_limits)], [1, 1], 1.0
    )
    trace, e_with = _perfect_run(robot, criterion, 10.0, target, q0)
    _, e_without = _perfect_run(robot, None, 0.0, target, q0)
    t = trace.t[:, None]
    analytic = offset * (1 + 5 * t) * np.exp(-5 * t)
    assert np.abs(trace.q - trace.q[0]).max() > 0.05  # the subtasks did move the arm
    np.testing.assert_allclose(e_with, analytic, atol=2e-4)
    np.testing.assert_allclose(e_without, analytic, atol=2e-4)
    np.testing.assert_allclose(e_with, e_without, atol=2e-4)


@pytest.mark.parametrize(
    ("name", "task", "which"),
    [
        ("panda", "position", "manipulability"),
        ("panda", "pose", "joint_centering"),
        ("ur5", "position", "joint_limits"),
        ("planar7", "planar", "manipulability"),
    ],
)
def test_pure_self_motion_improves_the_criterion(name, task, which):
    robot = arm(name, task)
    q0 = random_configurations(robot, 1, seed=15)[0]
    x0 = robot.task_position(q0)
    criterion = _criteria(robot, q0)[which]
    if task == "pose":
        from nnrobust.model.tasks import split_pose
        from nnrobust.trajectories import PoseTrajectory

        p, R = split_pose(x0)
        target = PoseTrajectory(EllipseTrajectory(p, np.zeros(3), np.zeros(3)), R, [0, 0, 1.0])
    else:
        target = EllipseTrajectory(x0, np.zeros(robot.m), np.zeros(robot.m))
    # scale h (the C of eq. 4) so that the projected gradient has norm 0.3 at the start
    J = robot.task_jacobian(q0)
    grad0 = project_null_space(J, DampedPseudoInverse().matrix(J), criterion.gradient(robot, q0))
    weighted = WeightedCriteria([criterion], [1.0], C=0.3 / np.linalg.norm(grad0))
    trace, e = _perfect_run(robot, weighted, 10.0, target, q0, duration=3.0)
    h = np.array([weighted.value(robot, q) for q in trace.q])
    assert h[-1] - h[0] > 0.05  # about 0.09 per second at the start
    assert np.diff(h).min() > -1e-9  # never decreases
    # The task frame stays put: exactly in continuous time; with the 1 ms zero-order hold the
    # held null-space acceleration leaks O(T) into the task, a tenth of a millimetre here.
    assert np.abs(e).max() < 2e-4


@pytest.mark.parametrize("name, task", [("panda", "pose"), ("ur5", "position"), ("planar7", "planar")])
def test_ik_reaches_a_reachable_target_from_another_seed(name, task):
    """The target is the forward kinematics of one random configuration, the seed another one
    0.3 rad away: IK reaches it (residual < 1e-10), within the limits, at a configuration whose
    forward kinematics is the target (checked independently of the solver's own residual)."""
    robot = arm(name, task)
    (q_true,) = random_configurations(robot, 1, seed=15)
    seed = np.clip(
        q_true + 0.3 * np.sign(np.sin(np.arange(robot.nq) + 1.0)), robot.lower_limits, robot.upper_limits
    )
    target = robot.task_position(q_true)
    q, residual = solve_ik(robot, target, seed, robot.lower_limits, robot.upper_limits)
    assert residual < 1e-10
    assert np.all(q >= robot.lower_limits) and np.all(q <= robot.upper_limits)
    np.testing.assert_allclose(robot.task_position(q), target, atol=1e-9)
    assert np.abs(q - seed).max() > 1e-3  # it moved: the seed was not the answer


def test_initial_state_keeps_a_margin_inside_the_limits():
    """A q_seed on a joint limit: the initial inverse kinematics starts 2 % of the range inside."""
    from nnrobust.config.presets import load_preset
    from nnrobust.model.ik import IK_LIMIT_MARGIN
    from nnrobust.run.experiment import build

    setup = build(
        load_preset("paper-ellipse").replace(simulation={"q_seed": [0.2, 2.8, 1.0], "duration": 1.0})
    )
    lower, upper = setup.robot.lower_limits, setup.robot.upper_limits
    margin = IK_LIMIT_MARGIN * (upper - lower)
    assert np.all(setup.q0 >= lower + margin - 1e-12) and np.all(setup.q0 <= upper - margin + 1e-12)
