"""Self-motion criteria h_i(q) with analytic gradients, eqs. (3), (4) and (19)."""

from ..core.kinds import import_modules as _import_modules
from .base import Criterion, WeightedCriteria
from .joint_limits import JointCentering, JointLimitAvoidance
from .joint_smoothness import PAPER_SMOOTHNESS, JointSmoothness, PaperCriterion
from .manipulability import HalfDetManipulability, Manipulability
from .obstacles import SphereObstacles
from .registry import CRITERION_KINDS, CriterionKind, criterion_unit, default_criteria, kind_of

_import_modules(__name__, __path__)  # every module declares its criteria at import

CRITERIA = {name: CRITERION_KINDS[name].description for name in sorted(CRITERION_KINDS)}
"""Criteria by the name used in experiment configurations, with a one-line description (from
their declarations, :mod:`nnrobust.subtasks.registry`)."""

__all__ = [
    "CRITERIA",
    "CRITERION_KINDS",
    "Criterion",
    "CriterionKind",
    "HalfDetManipulability",
    "JointCentering",
    "JointLimitAvoidance",
    "JointSmoothness",
    "Manipulability",
    "PAPER_SMOOTHNESS",
    "PaperCriterion",
    "SphereObstacles",
    "WeightedCriteria",
    "criterion_unit",
    "default_criteria",
    "kind_of",
]
