"""The controller interface: a sampled torque law with explicit internal state."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np


@dataclass
class ControlOutput:
    """What a controller returns at a control instant.

    Attributes:
        tau: commanded joint torques [N m].
        signals: scalar signals to record (e.g. rho_hat, eps, damping).
        state: the internal state z at the next control instant (None: unchanged).

    """

    tau: np.ndarray
    signals: dict[str, float] = field(default_factory=dict)
    state: np.ndarray | None = None


class Controller(ABC):
    """A sampled control law: at t_k it maps the measured (q, q') and its state z_k to a torque
    held over [t_k, t_k + T) and to z_{k+1}.

    A real controller knows the state only at its sampling instants, so an adaptive law is
    advanced over each period with its inputs held (exactly, where the law allows). The state is
    explicit, so a run is reproducible and restartable from (t, q, q', z).
    """

    state_size: int = 0
    signal_names: tuple[str, ...] = ()

    def initial_state(self) -> np.ndarray:
        """z(0)."""
        return np.zeros(self.state_size)

    @abstractmethod
    def compute(self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray,
                period: float = 0.0) -> ControlOutput:
        """Torque, signals and (for a stateful law) z after ``period`` [s] at time t [s]."""
