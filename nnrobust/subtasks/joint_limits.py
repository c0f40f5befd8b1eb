"""Joint-range criteria: limit avoidance (a barrier) and centering (a quadratic)."""

from __future__ import annotations

import numpy as np

from ..core.exceptions import ConfigError
from ..model.base import DynamicsModel
from .base import Criterion
from .registry import CriterionKind, declare


def _finite_range(lower, upper) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lower, upper, limited): a joint without limits (a continuous joint: -inf, inf) takes no
    part; any other joint needs a finite, positive range.
    """
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if lower.shape != upper.shape or lower.ndim != 1:
        raise ValueError(
            f"joint limits: lower {lower.shape} and upper {upper.shape} must be vectors of the same length"
        )
    unlimited = (lower == -np.inf) & (upper == np.inf)
    finite = np.isfinite(lower) & np.isfinite(upper) & (upper - lower > 0) & (upper - lower <= 1e3)
    bad = ~unlimited & ~finite
    if np.any(bad):
        raise ValueError(
            f"joint limits: joints {np.flatnonzero(bad).tolist()} have no finite range "
            f"(lower {lower[bad].tolist()}, upper {upper[bad].tolist()}); set <limit> in the URDF"
        )
    if np.all(unlimited):
        raise ValueError(
            "joint limits: no joint has limits (all are continuous); the criterion has nothing to do"
        )
    return np.where(unlimited, -1.0, lower), np.where(unlimited, 1.0, upper), ~unlimited


class JointLimitAvoidance(Criterion):
    """h = -(1/n) sum_i b_i(q_i), b_i = (u_i - l_i)^2 / (4 (u_i - q_i)(q_i - l_i)) (Zghal, Dubey and
    Euler 1990), continued linearly near and beyond the limits.

    b equals 1 with every joint mid-range and grows like a barrier towards a limit, so that the
    self-motion q' = k grad h pushes hardest on the joints closest to their limits. Within
    ``margin`` x range of a limit (and beyond it) b is continued by its tangent line at that
    point: value and gradient stay finite and continuous, and the gradient keeps pointing back
    into the range, so an arm that starts on a limit, or is pushed past it by a stop, gets a
    bounded push (at most the barrier's slope at the margin) instead of a blow-up. A joint
    without limits (a continuous joint) has b_i = 1: it is never pushed.
    """

    margin: float = 0.05
    """Fraction of the range at each end where the barrier turns linear."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray):
        self.limits = (np.asarray(lower, dtype=float), np.asarray(upper, dtype=float))
        self.lower, self.upper, self.limited = _finite_range(lower, upper)
        self.span = self.upper - self.lower
        self._low_knot = self.lower + self.margin * self.span
        self._high_knot = self.upper - self.margin * self.span

    def _barrier(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(b(q), b'(q)) per joint, with the linear continuation outside the knots."""
        knot = np.clip(q, self._low_knot, self._high_knot)
        s = (self.upper - knot) * (knot - self.lower)
        b = self.span**2 / (4 * s)
        db = -(self.span**2) * (self.upper + self.lower - 2 * knot) / (4 * s**2)
        return np.where(self.limited, b + db * (q - knot), 1.0), np.where(self.limited, db, 0.0)

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """h(q) <= -1."""
        return -float(np.mean(self._barrier(q)[0]))

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """dh/dq_i = -b_i'(q_i) / n (= (u - l)^2 (u + l - 2 q) / (4 n ((u - q)(q - l))^2) inside)."""
        return -self._barrier(q)[1] / q.size


class JointCentering(Criterion):
    """h = -(1/(2n)) sum_i ((q_i - c_i) / (u_i - l_i))^2 with c the mid-range (Liegeois 1977)."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray):
        self.limits = (np.asarray(lower, dtype=float), np.asarray(upper, dtype=float))
        lower, upper, limited = _finite_range(lower, upper)
        self.center = 0.5 * (lower + upper)
        self.span = np.where(limited, upper - lower, np.inf)  # a joint without limits: no term

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """h(q) <= 0, zero at mid-range."""
        return -0.5 * float(np.mean(((q - self.center) / self.span) ** 2))

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """-(q - c) / (n (u - l)^2)."""
        return -(q - self.center) / (q.size * self.span**2)


def _from_limits(name: str, cls):
    def build(sc, robot):
        try:
            return cls(robot.lower_limits, robot.upper_limits)
        except ValueError as err:
            raise ConfigError("subtasks.criteria", f"{name!r}: {err}") from err

    return build


declare(
    CriterionKind(
        "joint_limits",
        JointLimitAvoidance,
        "limit-avoidance barrier, -1 mid-range, -inf at a limit",
        lambda m: "1",
        _from_limits("joint_limits", JointLimitAvoidance),
        lambda c: {"lower": c.limits[0], "upper": c.limits[1], "margin": c.margin},
    ),
    CriterionKind(
        "joint_centering",
        JointCentering,
        "-(1/2n) sum ((q - mid) / range)^2",
        lambda m: "1",
        _from_limits("joint_centering", JointCentering),
        lambda c: {"lower": c.limits[0], "upper": c.limits[1]},
    ),
)
