import numpy as np
import pytest

from nnrobust.subtasks import (
    HalfDetManipulability,
    JointSmoothness,
    Manipulability,
    PaperCriterion,
    WeightedCriteria,
)
from tests.problems import closed_form_of, finite_difference, paper_robot, random_states


@pytest.mark.parametrize(
    "criterion",
    [PaperCriterion(), HalfDetManipulability(), Manipulability(), JointSmoothness()],
    ids=["eq19", "half_det", "sqrt_det", "smoothness"],
)
@pytest.mark.parametrize("which", ["pinocchio", "closed-form"])
def test_gradient_matches_finite_differences(criterion, which):
    """Analytic gradients equal central differences on 20 random configurations."""
    robot = paper_robot()
    model = robot if which == "pinocchio" else closed_form_of(robot)
    for q, _, _ in random_states(3, 20, seed=7):
        fd = np.array(
            [finite_difference(lambda x: np.array(criterion.value(model, x)), q, d) for d in np.eye(3)]
        ).ravel()
        np.testing.assert_allclose(criterion.gradient(model, q), fd, atol=1e-7)


def test_paper_criterion_is_eq_19():
    """h = 0.5 det(J J^T) - 0.5 ((q3 - 0.5 q2) - 0.5 (q2 - q1))^2, written out."""
    robot = paper_robot()
    q = np.array([0.4, -0.9, 1.3])
    J = robot.task_jacobian(q)
    expected = 0.5 * np.linalg.det(J @ J.T) - 0.5 * ((q[2] - 0.5 * q[1]) - 0.5 * (q[1] - q[0])) ** 2
    assert PaperCriterion().value(robot, q) == pytest.approx(expected, abs=1e-14)


def test_weights_are_scaled_to_sum_to_C():
    """Eq. (4): the weights are normalised so that sum w_i = C."""
    w = WeightedCriteria([HalfDetManipulability(), JointSmoothness()], [3.0, 1.0], C=2.0)
    assert w.weights.sum() == pytest.approx(2.0)
    assert w.weights == pytest.approx([1.5, 0.5])
    with pytest.raises(ValueError, match="weights"):
        WeightedCriteria([HalfDetManipulability()], [1.0, 2.0])


PRISMATIC_ARM = """<robot name="rprr">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="3"/></joint>
  <link name="l1"><inertial><origin xyz="0 0 0.1"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j2" type="prismatic"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.2" rpy="0.3 0 0"/>
    <axis xyz="1 0 0"/><limit lower="-0.3" upper="0.3" effort="50" velocity="1"/></joint>
  <link name="l2"><inertial><origin xyz="0.1 0 0"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0.3 0 0" rpy="0 0.4 0"/>
    <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="3"/></joint>
  <link name="l3"><inertial><origin xyz="0.1 0 0"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/><origin xyz="0.25 0 0"/>
    <axis xyz="0.6 0 0.8"/><limit lower="-3" upper="3" effort="10" velocity="3"/></joint>
  <link name="l4"><inertial><origin xyz="0.1 0 0"/><mass value="0.5"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="tool_joint" type="fixed"><parent link="l4"/><child link="tool"/>
    <origin xyz="0.2 0.05 0"/></joint>
  <link name="tool"/>
</robot>
"""


@pytest.mark.parametrize(
    "source, task",
    [
        ("panda", "position"),
        ("panda", "pose"),
        ("ur5", "position"),
        ("planar12", "planar"),
        ("three_link_planar", "planar"),
        (PRISMATIC_ARM, "position"),
    ],
    ids=["panda-position", "panda-pose", "ur5", "planar12", "paper-arm", "prismatic"],
)
def test_linear_time_manipulability_gradient(source, task):
    """PinocchioModel.det_jjt_gradient (O(n) prefix and suffix sums, docs/equations.md) equals
    central finite differences of det(J J^T) and the kinematic-Hessian form."""
    from nnrobust import load_robot
    from nnrobust.core.small_linalg import det
    from nnrobust.subtasks.manipulability import hessian_det_gradient

    robot = load_robot(source, task=task)
    lower, upper = robot.working_range
    rng = np.random.default_rng(3)

    def value(q):
        J = robot.task_jacobian(q)
        return det(J @ J.T)

    for _ in range(5):
        q = rng.uniform(lower, upper)
        d, grad = robot.det_jjt_gradient(q)
        d_hessian, grad_hessian = hessian_det_gradient(robot, q)
        assert d == pytest.approx(value(q), rel=1e-12)
        np.testing.assert_allclose(grad, grad_hessian, rtol=1e-9, atol=1e-12 * np.abs(grad_hessian).max())
        h = 1e-6
        fd = np.array([(value(q + h * e) - value(q - h * e)) / (2 * h) for e in np.eye(robot.nq)])
        np.testing.assert_allclose(grad, fd, rtol=1e-5, atol=1e-7 * np.abs(fd).max())
