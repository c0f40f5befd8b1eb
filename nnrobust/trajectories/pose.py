"""The pose trajectory: a position path with an orientation rocking about a fixed axis (the
orientation's compiled twin is csrc/trajectories/pose.cpp).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..model.tasks import pose_vector, task_error
from .base import Trajectory
from .ellipse import EllipseTrajectory
from .piecewise import PiecewisePolynomialPath

PositionPath = EllipseTrajectory | PiecewisePolynomialPath
"""A position path x_d(t), m = 2 or 3."""


@dataclass(frozen=True)
class PoseTrajectory(Trajectory):
    """A 6-D pose path: the position follows a path, the orientation rocks about a fixed axis.

    p_d(t) = path(t) (the ellipse of eq. 18 in 3-D, a point-to-point move or a waypoint spline)
    and R_d(t) = exp(theta(t) [u]x) R_0 with
    theta(t) = amplitude sin(omega t + phase), so that the world-frame angular velocity is
    w_d = theta' u and its rate w_d' = theta'' u. Task coordinates are [p, R row by row]
    (:mod:`nnrobust.model.tasks`); velocities and accelerations are [p', w] and [p'', w'].

    Attributes:
        path: the position path (m = 3).
        rotation0: R_0, 3 x 3.
        axis: rotation axis u (normalised here).
        amplitude: rocking amplitude [rad].
        omega: rocking angular frequency [rad/s].
        phase: rocking phase at t = 0 [rad].

    """

    path: PositionPath
    rotation0: np.ndarray
    axis: np.ndarray
    amplitude: float = 0.0
    omega: float = 1.0
    phase: float = 0.0

    twin_fields = ("rotation0", "axis", "amplitude", "omega", "phase")  # csrc/trajectories/pose.cpp

    def __post_init__(self):
        if self.path.m != 3:
            raise ValueError(f"trajectory: a pose needs a 3-D position path, got m = {self.path.m}")
        R0 = np.asarray(self.rotation0, dtype=float)
        if R0.shape != (3, 3) or not np.allclose(R0 @ R0.T, np.eye(3), atol=1e-9) or np.linalg.det(R0) < 0:
            raise ValueError("trajectory: rotation0 must be a 3 x 3 rotation matrix")
        axis = np.asarray(self.axis, dtype=float)
        norm = float(np.linalg.norm(axis)) if axis.shape == (3,) else 0.0
        if norm == 0.0:
            raise ValueError(f"trajectory: the rotation axis must be a non-zero 3-vector, got {axis}")
        object.__setattr__(self, "rotation0", R0)
        object.__setattr__(self, "axis", axis / norm)

    m = 6

    def _angle(self, t):
        arg = self.omega * t + self.phase
        return self.amplitude * np.sin(arg), self.amplitude * self.omega * np.cos(arg), arg

    def rotation(self, t: float) -> np.ndarray:
        """R_d(t)."""
        return pin.exp3(self._angle(t)[0] * self.axis) @ self.rotation0

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """([p_d, R_d], [p_d', w_d], [p_d'', w_d']) at time t."""
        p, dp, ddp = self.path(t)
        theta, dtheta, arg = self._angle(t)
        ddtheta = -self.amplitude * self.omega**2 * math.sin(arg)
        R = pin.exp3(theta * self.axis) @ self.rotation0
        return (
            pose_vector(p, R),
            np.concatenate([dp, dtheta * self.axis]),
            np.concatenate([ddp, ddtheta * self.axis]),
        )

    def position(self, t: np.ndarray) -> np.ndarray:
        """[p_d, log3(R_d)] at each time of an array, len(t) x 6 [m, rad]."""
        t = np.asarray(t, dtype=float)
        rotvec = np.array([pin.log3(self.rotation(tk)) for tk in t]).reshape(t.size, 3)
        return np.hstack([self.path.position(t), rotvec])

    def error(self, x: np.ndarray, x_d: np.ndarray) -> np.ndarray:
        """[p - p_d, log3(R R_d^T)] [m, rad]."""
        return task_error("pose", x, x_d)
