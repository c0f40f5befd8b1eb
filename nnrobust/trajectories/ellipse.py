"""The ellipse of eq. (18) (``trajectory.kind = "ellipse"``; compiled twin
csrc/trajectories/ellipse.cpp).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.exceptions import ConfigError
from .base import Trajectory
from .registry import PathKind, declare


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

    twin = "ellipse"
    twin_fields = ("center", "axis_a", "axis_b", "omega", "phase")

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


def _check(tc) -> None:
    size = len(tc.center)
    for key, values in (("axis_a", tc.axis_a), ("axis_b", tc.axis_b)):
        if len(values) != size:
            raise ConfigError(f"trajectory.{key}", f"has {len(values)} entries, trajectory.center has {size}")


def _build(tc, robot, q_seed) -> EllipseTrajectory:
    return EllipseTrajectory(
        np.asarray(tc.center, float),
        np.asarray(tc.axis_a, float),
        np.asarray(tc.axis_b, float),
        tc.omega,
        tc.phase,
    )


declare(
    PathKind(
        "ellipse",
        "eq. (18): c + a cos(ωt + φ) + b sin(ωt + φ); b = 0 is the paper's line",
        ("center", "axis_a", "axis_b", "omega", "phase"),
        "`center`, `axis_a`, `axis_b`, `omega`, `phase`",
        _check,
        lambda tc: len(tc.center),
        _build,
    )
)
