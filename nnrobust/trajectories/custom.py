"""A user's trajectory (``trajectory.kind = "custom"``, docs/extending.md): ``Class(robot,
**params)`` with ``robot`` the arm's model, held in a checked wrapper: every x_d, x_d', x_d'' of
the run is checked as the first one is (m finite numbers each), a breach one line naming the class
key and the time.
"""

from __future__ import annotations

import numpy as np

from ..core.exceptions import ConfigError
from ..model.pinocchio_model import PinocchioModel
from ..model.tasks import TASK_KINDS
from ..plugins.checked import checked_call, checked_vector
from ..plugins.user_code import construct
from .base import Trajectory


class CheckedTrajectory(Trajectory):
    """A user's trajectory with every x_d, x_d', x_d'' checked (m finite numbers each)."""

    KEY = "trajectory.class"

    def __init__(self, inner: Trajectory):
        self.inner, self.m = inner, inner.m
        self._name = type(inner).__name__

    def __call__(self, t: float):
        """The inner class's (x_d, x_d', x_d''), checked."""
        return self.checked(t, f"{self._name}({t:g})")

    def checked(self, t: float, what: str):
        """(x_d, x_d', x_d'') at t, each m finite numbers, or one line naming ``what``."""
        out = checked_call(self.KEY, what, self.inner, t)
        if not (isinstance(out, tuple) and len(out) == 3):
            raise ConfigError(self.KEY, f"{what} must return (x_d, x_d', x_d''), got {type(out).__name__}")
        m = self.m
        return tuple(
            checked_vector(self.KEY, f"{what}'s {w}", v, m) for v, w in zip(out, ("x_d", "x_d'", "x_d''"))
        )

    def error(self, x: np.ndarray, x_d: np.ndarray) -> np.ndarray:
        """The inner class's task error, checked (m finite numbers)."""
        what = f"{self._name}.error"
        return checked_vector(self.KEY, what, checked_call(self.KEY, what, self.inner.error, x, x_d), self.m)

    def __getattr__(self, name: str):  # the class's own attributes, read through
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)


def build_trajectory(spec: str, params: dict | None, robot: PinocchioModel, task: str) -> Trajectory:
    """``trajectory.kind = "custom"``: the class's trajectory, with m and x_d(0), x_d'(0), x_d''(0)
    of the task's size.
    """
    key = CheckedTrajectory.KEY
    trajectory = construct(spec, params, Trajectory, key, "trajectory.params", robot, "robot")
    name, m = type(trajectory).__name__, TASK_KINDS[task]
    if getattr(trajectory, "m", None) != m:
        raise ConfigError(key, f"{name}.m is {getattr(trajectory, 'm', None)!r}; the {task} task has m = {m}")
    checked = CheckedTrajectory(trajectory)
    checked.checked(0.0, f"{name}(0.0)")  # before anything runs, as at every call
    return checked
