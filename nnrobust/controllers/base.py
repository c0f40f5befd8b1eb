"""The controller interface: a torque law with explicit internal state."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np


@dataclass
class ControlOutput:
    """What a controller returns at a control instant.

    Attributes:
        tau: joint torques [N m].
        signals: scalar signals to record (e.g. rho_hat, eps, damping).

    """

    tau: np.ndarray
    signals: dict[str, float] = field(default_factory=dict)


class Controller(ABC):
    """A control law tau = k(t, q, q', z) whose internal state z obeys z' = g(t, q, q', z).

    The simulator integrates z together with (q, q'), so a run is reproducible and restartable
    from (t, q, q', z).
    """

    state_size: int = 0
    signal_names: tuple[str, ...] = ()

    def initial_state(self) -> np.ndarray:
        """z(0)."""
        return np.zeros(self.state_size)

    @abstractmethod
    def compute(self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray) -> ControlOutput:
        """Torque and recorded signals at time t [s]."""

    def state_derivative(
        self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray
    ) -> np.ndarray:
        """z'(t); stateless controllers return an empty array."""
        return np.zeros(self.state_size)
