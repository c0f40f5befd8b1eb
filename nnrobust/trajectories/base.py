"""The contract of every desired trajectory x_d(t)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np


class Trajectory(ABC):
    """A desired task trajectory: t -> (x_d, x_d', x_d''), the contract of every trajectory, the
    shipped ones and a user's (``trajectory.kind = "custom"``, docs/extending.md).

    A user's class is built as ``Class(robot, **trajectory.params)``, with ``robot`` the arm's
    model (:class:`nnrobust.DynamicsModel`: ``task_position``, ``mid_configuration``, ...), and
    sets ``m``, the task dimension (2 planar, 3 position; a pose task needs the shipped
    trajectories).
    """

    m: int
    """Task dimension."""

    twin: ClassVar[str | None] = None
    """The name its compiled twin registers under in csrc/trajectories/ (None: Python only)."""

    twin_fields: ClassVar[tuple[str, ...]] = ()
    """The attributes its twin reads, by name (:mod:`nnrobust.core.twins`)."""

    @abstractmethod
    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x_d, x_d', x_d'') at time t [m, m/s, m/s^2]."""

    def position(self, t: np.ndarray) -> np.ndarray:
        """x_d at each time of an array, len(t) x m [m]."""
        t = np.asarray(t, dtype=float)
        return np.array([self(tk)[0] for tk in t]).reshape(t.size, self.m)

    def error(self, x: np.ndarray, x_d: np.ndarray) -> np.ndarray:
        """E = x - x_d [m]."""
        return x - x_d
