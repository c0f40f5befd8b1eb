"""How an experiment builds its self-motion criterion from its own section, ``[subtasks]``
(:mod:`.section`): the weighted sum of eq. (4) over the declared criteria
(nnrobust/subtasks/registry.py) and a user's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.exceptions import ConfigError
from .base import Criterion, WeightedCriteria
from .custom import build_criterion as build_custom_criterion
from .registry import CRITERION_KINDS, default_criteria
from .section import SubtaskConfig

if TYPE_CHECKING:
    from ..model import PinocchioModel


def build_criterion(sc: SubtaskConfig, robot: PinocchioModel) -> Criterion | None:
    """Weighted sum of the named criteria, eq. (4), or None."""
    names = default_criteria(robot.nq, robot.task) if sc.criteria is None else sc.criteria
    if not names:
        return None
    unknown = [c for c in names if c not in CRITERION_KINDS and c != "custom"]
    if unknown:
        valid = ", ".join(sorted(CRITERION_KINDS))
        raise ConfigError("subtasks.criteria", f"unknown {unknown}; valid: {valid}, custom")
    criteria = [
        build_custom_criterion(sc.criterion_class or "", sc.criterion_params, robot)
        if name == "custom"
        else CRITERION_KINDS[name].build(sc, robot)
        for name in names
    ]
    return WeightedCriteria(criteria, sc.weights, sc.C)
