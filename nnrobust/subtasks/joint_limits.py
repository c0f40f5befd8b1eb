"""Joint-range criteria: limit avoidance (a barrier) and centering (a quadratic)."""

from __future__ import annotations

import numpy as np

from ..model.base import DynamicsModel
from .base import Criterion


def _finite_range(lower, upper) -> tuple[np.ndarray, np.ndarray]:
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    if lower.shape != upper.shape or lower.ndim != 1:
        raise ValueError(f"joint limits: lower {lower.shape} and upper {upper.shape} must be vectors "
                         "of the same length")
    bad = ~(np.isfinite(lower) & np.isfinite(upper) & (upper - lower > 0)) | (upper - lower > 1e3)
    if np.any(bad):
        raise ValueError(
            f"joint limits: joints {np.flatnonzero(bad).tolist()} have no finite range "
            f"(lower {lower[bad].tolist()}, upper {upper[bad].tolist()}); set <limit> in the URDF"
        )
    return lower, upper


class JointLimitAvoidance(Criterion):
    """h = -(1/n) sum_i (u_i - l_i)^2 / (4 (u_i - q_i)(q_i - l_i)) (Zghal, Dubey and Euler 1990).

    Equals -1 with every joint mid-range and tends to -infinity at a limit, so that the self-motion
    q' = k grad h pushes hardest on the joints closest to their limits. Outside the range the
    value and gradient are those at 1e-6 of the range inside it (finite, pointing back in).
    """

    def __init__(self, lower: np.ndarray, upper: np.ndarray):
        self.lower, self.upper = _finite_range(lower, upper)
        self.span = self.upper - self.lower
        self._margin = 1e-6 * self.span

    def _clip(self, q: np.ndarray) -> np.ndarray:
        return np.clip(q, self.lower + self._margin, self.upper - self._margin)

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """h(q) <= -1."""
        q = self._clip(q)
        return -float(np.mean(self.span**2 / (4 * (self.upper - q) * (q - self.lower))))

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """dh/dq_i = (u - l)^2 (u + l - 2 q) / (4 n ((u - q)(q - l))^2)."""
        q = self._clip(q)
        s = (self.upper - q) * (q - self.lower)
        return self.span**2 * (self.upper + self.lower - 2 * q) / (4 * q.size * s**2)


class JointCentering(Criterion):
    """h = -(1/(2n)) sum_i ((q_i - c_i) / (u_i - l_i))^2 with c the mid-range (Liegeois 1977)."""

    def __init__(self, lower: np.ndarray, upper: np.ndarray):
        lower, upper = _finite_range(lower, upper)
        self.center = 0.5 * (lower + upper)
        self.span = upper - lower

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """h(q) <= 0, zero at mid-range."""
        return -0.5 * float(np.mean(((q - self.center) / self.span) ** 2))

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """-(q - c) / (n (u - l)^2)."""
        return -(q - self.center) / (q.size * self.span**2)
