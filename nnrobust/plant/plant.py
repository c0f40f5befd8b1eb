"""The true robot: rigid-body dynamics, friction and disturbance, eq. (7)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.base import DynamicsModel
from .disturbance import SinusoidalDisturbance
from .friction import Friction


@dataclass
class Plant:
    """M(q) q'' + V_m q' + G + F(q') + tau_d(t) = tau, eq. (7).

    Attributes:
        model: the true dynamics (normally Pinocchio, from the URDF).
        friction: the true friction F(q').
        disturbance: the external disturbance tau_d(t).

    """

    model: DynamicsModel
    friction: Friction
    disturbance: SinusoidalDisturbance

    def __post_init__(self):
        n = self.model.nq
        for name, size in (
            ("friction.viscous", self.friction.viscous.size),
            ("friction.coulomb", self.friction.coulomb.size),
            ("disturbance", self.disturbance.n),
        ):
            if size != n:
                raise ValueError(f"plant: {name} has {size} entries, the robot has {n} joints")

    @property
    def nq(self) -> int:
        """Number of joints n."""
        return self.model.nq

    def acceleration(self, t: float, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Q'' = M^-1 (tau - V_m q' - G - F(q') - tau_d(t)), by ABA for Pinocchio models."""
        return self.model.forward_dynamics(
            q, v, tau - self.friction.torque(v) - self.disturbance(t)
        )

    def energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic plus potential energy [J]."""
        return self.model.kinetic_energy(q, v) + self.model.potential_energy(q)
