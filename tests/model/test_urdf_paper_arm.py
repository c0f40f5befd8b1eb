import numpy as np
import pytest

from nnrobust.model import ThreeLinkParameters
from tests.problems import paper_robot


def test_urdf_reproduces_printed_parameters_to_four_decimals():
    """beta_1..3 and p_1..3 computed from the URDF round to the paper's printed values."""
    robot = paper_robot()
    params = ThreeLinkParameters.from_pinocchio(robot.model, robot.task_frame)
    printed = ThreeLinkParameters.paper()
    assert np.round(params.beta, 4) == pytest.approx(printed.beta, abs=0)
    assert np.round(params.p, 4) == pytest.approx(printed.p, abs=0)
    assert params.lengths == pytest.approx((0.40, 0.36, 0.30))


def test_urdf_masses_lengths_friction_and_limits():
    """Masses 3.6/2.6/2.0 kg, the paper's true friction, finite limits, positive inertias."""
    robot = paper_robot()
    masses = [robot.model.inertias[j].mass for j in (1, 2, 3)]
    assert masses == pytest.approx([3.6, 2.6, 2.0])
    assert robot.viscous_friction == pytest.approx([4.3, 1.4, 0.4])
    assert robot.coulomb_friction == pytest.approx([1.0, 1.0, 1.0])
    assert np.all(robot.lower_limits < 0) and np.all(robot.upper_limits > 0)
    assert np.all(robot.effort_limits > 0)
    for j in (1, 2, 3):
        assert np.all(np.linalg.eigvalsh(robot.model.inertias[j].inertia) > 0)


def test_horizontal_plane_has_no_gravity_torque_and_vertical_has():
    """Default gravity is normal to the arm's plane (G = 0); the vertical variant is not."""
    q = np.array([0.3, -0.4, 0.5])
    assert np.abs(paper_robot().gravity(q)).max() < 1e-12
    assert np.abs(paper_robot(gravity=(0, -9.81, 0)).gravity(q)).max() > 1.0
