"""A user's self-motion criterion (a ``custom`` entry of ``subtasks.criteria``, docs/extending.md):
``Class(robot, **params)`` with ``robot`` the arm's model, held in a checked wrapper: every h(q) (a
finite number) and dh/dq (one finite entry per joint) of the run is checked as the first one is, a
breach one line naming the class key.
"""

from __future__ import annotations

import numpy as np

from ..core.exceptions import ConfigError
from ..core.numeric_limits import finite_number
from ..model.pinocchio_model import PinocchioModel
from ..plugins.checked import checked_call, checked_vector
from ..plugins.user_code import construct
from .base import Criterion


class CheckedCriterion(Criterion):
    """A user's criterion with every h(q) (a finite number) and dh/dq (n finite numbers) checked."""

    KEY = "subtasks.criterion_class"

    def __init__(self, inner: Criterion, n: int):
        self.inner, self.n, self._name = inner, n, type(inner).__name__

    def value(self, model, q: np.ndarray) -> float:
        """The inner class's h(q), checked."""
        value = checked_call(self.KEY, f"{self._name}.value", self.inner.value, model, q)
        if not isinstance(value, (int, float, np.floating)) or not finite_number(value):
            raise ConfigError(
                self.KEY,
                f"{self._name}.value(model, q) must return a finite number, got {value!r} at q = {q}",
            )
        return float(value)

    def gradient(self, model, q: np.ndarray) -> np.ndarray:
        """The inner class's dh/dq, checked."""
        what = f"{self._name}.gradient(model, q)"
        return checked_vector(
            self.KEY, what, checked_call(self.KEY, what, self.inner.gradient, model, q), self.n
        )

    def __getattr__(self, name: str):
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)


def build_criterion(spec: str, params: dict | None, robot: PinocchioModel) -> Criterion:
    """A ``custom`` entry of ``subtasks.criteria``: h(q) a finite number and dh/dq one entry per
    joint, at the middle of the joints' range.
    """
    key = CheckedCriterion.KEY
    criterion = construct(spec, params, Criterion, key, "subtasks.criterion_params", robot, "robot")
    checked = CheckedCriterion(criterion, robot.nq)
    checked.value(robot, robot.mid_configuration)  # before anything runs, as at every call
    checked.gradient(robot, robot.mid_configuration)
    return checked
