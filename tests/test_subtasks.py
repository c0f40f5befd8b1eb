import numpy as np
import pytest

from nnrobust.subtasks import (
    HalfDetManipulability,
    JointSmoothness,
    Manipulability,
    PaperCriterion,
    WeightedCriteria,
)

from .problems import closed_form_of, finite_difference, paper_robot, random_states


@pytest.mark.parametrize("criterion", [PaperCriterion(), HalfDetManipulability(),
                                       Manipulability(), JointSmoothness()],
                         ids=["eq19", "half_det", "sqrt_det", "smoothness"])
@pytest.mark.parametrize("which", ["pinocchio", "closed-form"])
def test_gradient_matches_finite_differences(criterion, which):
    """Analytic gradients equal central differences on 20 random configurations."""
    robot = paper_robot()
    model = robot if which == "pinocchio" else closed_form_of(robot)
    for q, _, _ in random_states(3, 20, seed=7):
        fd = np.array([finite_difference(lambda x: np.array(criterion.value(model, x)), q, d)
                       for d in np.eye(3)]).ravel()
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
