"""Self-motion criteria h_i(q) with analytic gradients, eqs. (3), (4) and (19)."""

import pkgutil as _pkgutil
from importlib import import_module as _import_module

from .base import Criterion, WeightedCriteria
from .joint_limits import JointCentering, JointLimitAvoidance
from .joint_smoothness import PAPER_SMOOTHNESS, JointSmoothness, PaperCriterion
from .manipulability import HalfDetManipulability, Manipulability
from .obstacles import SphereObstacles
from .registry import CRITERION_KINDS, CriterionKind, criterion_unit, default_criteria, kind_of

for _module in _pkgutil.iter_modules(__path__):  # every module declares its criteria at import
    _import_module(f"{__name__}.{_module.name}")

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
