"""Desired task trajectories x_d(t) with analytic derivatives."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .model.tasks import pose_vector, task_error


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


@dataclass(frozen=True)
class EllipseTrajectory(Trajectory):
    """x_d(t) = c + a cos(omega t + phase) + b sin(omega t + phase), eq. (18).

    A zero ``b`` gives the paper's straight line of case (a). Works in any task dimension m.

    Attributes:
        center: c [m].
        axis_a: a [m].
        axis_b: b [m].
        omega: angular frequency [rad/s].
        phase: phase at t = 0 [rad].

    """

    center: np.ndarray
    axis_a: np.ndarray
    axis_b: np.ndarray
    omega: float = 1.0
    phase: float = 0.0

    def __post_init__(self):
        for name in ("center", "axis_a", "axis_b"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))
        if not (self.center.shape == self.axis_a.shape == self.axis_b.shape):
            raise ValueError(
                f"trajectory: center {self.center.shape}, axis_a {self.axis_a.shape} and "
                f"axis_b {self.axis_b.shape} must have the same length"
            )
        object.__setattr__(self, "m", self.center.size)

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x_d, x_d', x_d'') at time t [m, m/s, m/s^2]."""
        w = self.omega
        c, s = math.cos(w * t + self.phase), math.sin(w * t + self.phase)
        x = self.center + self.axis_a * c + self.axis_b * s
        dx = w * (-self.axis_a * s + self.axis_b * c)
        ddx = -(w**2) * (self.axis_a * c + self.axis_b * s)
        return x, dx, ddx

    def position(self, t: np.ndarray) -> np.ndarray:
        """x_d at each time of an array, shape len(t) x m [m]."""
        arg = self.omega * np.asarray(t)[:, None] + self.phase
        return self.center + self.axis_a * np.cos(arg) + self.axis_b * np.sin(arg)

    def error(self, x: np.ndarray, x_d: np.ndarray) -> np.ndarray:
        """E = x - x_d [m]."""
        return x - x_d


@dataclass(frozen=True)
class PiecewisePolynomialPath(Trajectory):
    """x_d(t) = sum_j c[p, j] (t - b_p)^j for b_p <= t < b_{p+1}, held at its end values (with zero
    velocity and acceleration) before b_0 and after b_P. The form of both the quintic
    point-to-point motion and the waypoint spline, evaluated the same way by the compiled loop.

    Attributes:
        breaks: b_0 < ... < b_P [s].
        coefficients: c, P x (degree + 1) x m: c[p, j] multiplies (t - b_p)^j [m / s^j].

    """

    breaks: np.ndarray
    coefficients: np.ndarray

    def __post_init__(self):
        b = np.asarray(self.breaks, dtype=float)
        c = np.asarray(self.coefficients, dtype=float)
        if b.ndim != 1 or b.size < 2 or np.any(np.diff(b) <= 0) or not np.all(np.isfinite(b)):
            raise ValueError(f"trajectory: the break times must increase strictly, got {b.tolist()}")
        if c.ndim != 3 or c.shape[0] != b.size - 1 or not np.all(np.isfinite(c)):
            raise ValueError(f"trajectory: coefficients of shape {c.shape} for {b.size - 1} pieces")
        object.__setattr__(self, "breaks", b)
        object.__setattr__(self, "coefficients", c)
        object.__setattr__(self, "m", c.shape[2])

    def _piece(self, t: float) -> tuple[int, float, bool]:
        """(piece, local time t - b_p, inside [b_0, b_P])."""
        b = self.breaks
        if t <= b[0]:
            return 0, 0.0, False
        if t >= b[-1]:
            last = b.size - 2
            return last, b[-1] - b[last], False
        p = int(np.searchsorted(b, t, side="right")) - 1
        return p, t - b[p], True

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x_d, x_d', x_d'') at time t (Horner's rule, as in the compiled loop)."""
        p, h, moving = self._piece(float(t))
        c = self.coefficients[p]
        x, dx, ddx = c[-1].copy(), np.zeros(self.m), np.zeros(self.m)
        for j in range(c.shape[0] - 2, -1, -1):
            ddx = ddx * h + 2 * dx
            dx = dx * h + x
            x = x * h + c[j]
        if not moving:
            dx[:], ddx[:] = 0.0, 0.0
        return x, dx, ddx

    def position(self, t: np.ndarray) -> np.ndarray:
        """x_d at each time of an array, shape len(t) x m [m]."""
        return np.array([self(tk)[0] for tk in np.asarray(t, dtype=float)]).reshape(-1, self.m)

    def error(self, x: np.ndarray, x_d: np.ndarray) -> np.ndarray:
        """E = x - x_d [m]."""
        return x - x_d


def quintic_point_to_point(start, goal, duration: float) -> PiecewisePolynomialPath:
    """From ``start`` to ``goal`` in ``duration`` [s] along the straight line, with the quintic time
    law s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5, tau = t / T: zero velocity and acceleration at
    both ends, peak speed 1.875 |goal - start| / T at T / 2.
    """
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    if start.shape != goal.shape or start.ndim != 1:
        raise ValueError(f"trajectory: start {start.shape} and goal {goal.shape} must be vectors of one size")
    if not duration > 0:
        raise ValueError(f"trajectory: the move time must be positive, got {duration}")
    delta, T = goal - start, float(duration)
    c = np.zeros((1, 6, start.size))
    c[0, 0], c[0, 3], c[0, 4], c[0, 5] = start, 10 * delta / T**3, -15 * delta / T**4, 6 * delta / T**5
    return PiecewisePolynomialPath(np.array([0.0, T]), c)


def spline_through(points, times) -> PiecewisePolynomialPath:
    """The cubic spline through ``points`` (k x m) at ``times`` (k, increasing), at rest at both
    ends (clamped: zero velocity), twice continuously differentiable in between. Its
    acceleration is not zero at the ends, so it steps there.
    """
    from scipy.interpolate import CubicSpline

    points, times = np.asarray(points, dtype=float), np.asarray(times, dtype=float)
    if points.ndim != 2 or points.shape[0] != times.size or times.size < 2:
        raise ValueError(
            f"trajectory: {points.shape[0] if points.ndim == 2 else '?'} waypoints for "
            f"{times.size} times; give at least 2 of each, as many of one as of the other"
        )
    spline = CubicSpline(times, points, bc_type="clamped")
    coefficients = np.transpose(spline.c[::-1], (1, 0, 2))  # scipy: c[k] multiplies (t - b)^(3 - k)
    return PiecewisePolynomialPath(times, coefficients)


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
