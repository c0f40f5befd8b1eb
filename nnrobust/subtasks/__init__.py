"""Self-motion criteria h_i(q) with analytic gradients, eqs. (3), (4) and (19)."""

from .base import Criterion, WeightedCriteria
from .joint_limits import JointCentering, JointLimitAvoidance
from .joint_smoothness import PAPER_SMOOTHNESS, JointSmoothness, PaperCriterion
from .manipulability import HalfDetManipulability, Manipulability
from .obstacles import SphereObstacles

CRITERIA = {
    "paper": "eq. (19): 0.5 det(J J^T) - 0.5 (0.5 q1 - q2 + q3)^2 (three joints)",
    "half_det_manipulability": "0.5 det(J J^T)",
    "manipulability": "sqrt(det(J J^T)) (Yoshikawa)",
    "joint_limits": "limit-avoidance barrier, -1 mid-range, -inf at a limit",
    "joint_centering": "-(1/2n) sum ((q - mid) / range)^2",
    "joint_smoothness": "-0.5 (c^T q)^2 with c = subtasks.smoothness_coefficients",
    "obstacles": "-0.5 sum max(0, d0 - clearance)^2 over links and subtasks.obstacles",
}
"""Criteria by the name used in experiment configurations, with a one-line description."""

__all__ = [
    "CRITERIA",
    "Criterion",
    "HalfDetManipulability",
    "JointCentering",
    "JointLimitAvoidance",
    "JointSmoothness",
    "Manipulability",
    "PAPER_SMOOTHNESS",
    "PaperCriterion",
    "SphereObstacles",
    "WeightedCriteria",
]
