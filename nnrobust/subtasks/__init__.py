"""Self-motion criteria h_i(q) with analytic gradients, eqs. (3), (4) and (19)."""

from .base import Criterion, WeightedCriteria
from .joint_smoothness import PAPER_SMOOTHNESS, JointSmoothness, PaperCriterion
from .manipulability import HalfDetManipulability, Manipulability

CRITERIA = {
    "paper": PaperCriterion,
    "half_det_manipulability": HalfDetManipulability,
    "manipulability": Manipulability,
    "joint_smoothness": JointSmoothness,
}
"""Criteria by the name used in experiment configurations."""

__all__ = [
    "CRITERIA",
    "Criterion",
    "HalfDetManipulability",
    "JointSmoothness",
    "Manipulability",
    "PAPER_SMOOTHNESS",
    "PaperCriterion",
    "WeightedCriteria",
]
