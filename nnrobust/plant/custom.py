"""A user's disturbance (``plant.disturbance = "custom"``, docs/extending.md): ``Class(robot,
**params)`` with ``robot`` the arm's model, held in a checked wrapper: every tau_d(t) of the run is
checked as the first one is (one finite torque per joint), a breach one line naming the class key
and the time.
"""

from __future__ import annotations

import numpy as np

from ..model.pinocchio_model import PinocchioModel
from ..plugins.checked import checked_call, checked_vector
from ..plugins.user_code import construct
from .disturbance import Disturbance


class CheckedDisturbance(Disturbance):
    """A user's disturbance with every tau_d(t) checked (n finite torques)."""

    KEY = "plant.disturbance_class"

    def __init__(self, inner: Disturbance, n: int):
        self.inner, self.n, self._name = inner, n, type(inner).__name__

    def __call__(self, t: float) -> np.ndarray:
        """The inner class's tau_d(t), checked."""
        return self.checked(t, f"{self._name}({t:g})")

    def checked(self, t: float, what: str) -> np.ndarray:
        """tau_d(t), n finite numbers, or one line naming ``what``."""
        return checked_vector(self.KEY, what, checked_call(self.KEY, what, self.inner, t), self.n)

    def __getattr__(self, name: str):
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)


def build_disturbance(spec: str, params: dict | None, robot: PinocchioModel) -> Disturbance:
    """``plant.disturbance = "custom"``: the class's tau_d, one finite torque per joint at t = 0."""
    key = CheckedDisturbance.KEY
    disturbance = construct(spec, params, Disturbance, key, "plant.disturbance_params", robot, "robot")
    checked = CheckedDisturbance(disturbance, robot.nq)
    checked.checked(0.0, f"{type(disturbance).__name__}(0.0)")  # before anything runs, as at every call
    return checked
