"""Piecewise-polynomial paths: the quintic point-to-point move (``trajectory.kind =
"point_to_point"``) and the waypoint spline (``"waypoints"``), one class evaluated by Horner's rule
here and in its compiled twin (csrc/trajectories/piecewise.cpp).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.exceptions import ConfigError
from ..model.ik import seed_configuration
from ..model.tasks import split_pose
from .base import Trajectory
from .registry import PathKind, declare

MAX_WAYPOINTS = 10_000
"""Most waypoints of a spline."""

MIN_MOVE_TIME = 1e-3
"""Shortest point-to-point move or waypoint interval [s]: a quintic over less than a millisecond
asks for more than any actuator gives, and below about 1e-60 s its coefficients overflow."""

MAX_MOVE_TIME = 1e9
"""Longest point-to-point move [s] (32 years): above about 1e61 s the quintic's T^5 overflows."""


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

    twin = "piecewise"
    twin_fields = ("breaks", "stacked_coefficients")

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

    @property
    def stacked_coefficients(self) -> np.ndarray:
        """The coefficients as P (degree + 1) x m: row p (degree + 1) + j is c[p, j]."""
        pieces, order, m = self.coefficients.shape
        return self.coefficients.reshape(pieces * order, m)

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
    from scipy.interpolate import CubicSpline  # here: scipy, imported on first use (import time)

    points, times = np.asarray(points, dtype=float), np.asarray(times, dtype=float)
    if points.ndim != 2 or points.shape[0] != times.size or times.size < 2:
        raise ValueError(
            f"trajectory: {points.shape[0] if points.ndim == 2 else '?'} waypoints for "
            f"{times.size} times; give at least 2 of each, as many of one as of the other"
        )
    spline = CubicSpline(times, points, bc_type="clamped")
    coefficients = np.transpose(spline.c[::-1], (1, 0, 2))  # scipy: c[k] multiplies (t - b)^(3 - k)
    return PiecewisePolynomialPath(times, coefficients)


def _check_point_to_point(tc) -> None:
    if tc.goal is None:
        raise ConfigError(
            "trajectory.goal", "a point_to_point move needs its goal, e.g. goal = [0.5, 0.1, 0.4]"
        )
    if tc.start is not None and len(tc.start) != len(tc.goal):
        raise ConfigError(
            "trajectory.start", f"has {len(tc.start)} entries, trajectory.goal has {len(tc.goal)}"
        )
    if not MIN_MOVE_TIME <= tc.move_time <= MAX_MOVE_TIME:
        raise ConfigError(
            "trajectory.move_time",
            f"must be in [{MIN_MOVE_TIME:g}, {MAX_MOVE_TIME:g}] s, got {tc.move_time:.6g}",
        )


def _build_point_to_point(tc, robot, q_seed) -> PiecewisePolynomialPath:
    """From ``start``, or from where the task frame is at ``simulation.q_seed``, to ``goal``."""
    goal = tc.goal or []
    if tc.start is None:
        p = robot.task_position(seed_configuration(q_seed, robot))
        start = (split_pose(p)[0] if robot.task == "pose" else p)[: len(goal)]
    else:
        start = np.asarray(tc.start, dtype=float)
    return quintic_point_to_point(start, goal, tc.move_time)


def _check_waypoints(tc) -> None:
    points, times = tc.waypoints, tc.waypoint_times
    if not points or len(points) < 2:
        raise ConfigError(
            "trajectory.waypoints",
            "a waypoint path needs at least 2 points, e.g. waypoints = [[0.4, 0.0, 0.5], [0.4, 0.2, 0.5]]",
        )
    if len(points) > MAX_WAYPOINTS:
        raise ConfigError("trajectory.waypoints", f"{len(points)} points; at most {MAX_WAYPOINTS}")
    sizes = {len(p) for p in points}
    if len(sizes) != 1:
        raise ConfigError(
            "trajectory.waypoints", f"every point needs as many entries; got sizes {sorted(sizes)}"
        )
    if times is None or len(times) != len(points):
        raise ConfigError(
            "trajectory.waypoint_times",
            f"needs one time per waypoint ({len(points)}), got {None if times is None else len(times)}",
        )
    if times[0] < 0 or any(b - a < MIN_MOVE_TIME for a, b in zip(times, times[1:])):
        raise ConfigError(
            "trajectory.waypoint_times",
            f"must start at 0 or later and increase by at least "
            f"{MIN_MOVE_TIME:g} s from one point to the next, got {times}",
        )


declare(
    PathKind(
        "point_to_point",
        "start + (goal − start) s(t/T), s(τ) = 10τ³ − 15τ⁴ + 6τ⁵, then held at the goal",
        ("goal", "start", "move_time"),
        "`goal`, `start` (default: where the task frame is at `simulation.q_seed`), `move_time` T",
        _check_point_to_point,
        lambda tc: len(tc.goal) if tc.goal is not None else len(tc.center),
        _build_point_to_point,
    ),
    PathKind(
        "waypoints",
        "the cubic spline through the waypoints at their times, at rest at both ends (clamped), then held",
        ("waypoints", "waypoint_times"),
        "`waypoints` (2 or 3 entries each), `waypoint_times` (strictly increasing from 0)",
        _check_waypoints,
        lambda tc: len(tc.waypoints[0]) if tc.waypoints else len(tc.center),
        lambda tc, robot, q_seed: spline_through(tc.waypoints, tc.waypoint_times),
    ),
)
