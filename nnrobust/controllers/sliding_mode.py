"""The classical non-adaptive robust alternative: a boundary-layer sliding-mode term u_0."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .nn_compensator import error_dynamics, lyapunov_P


@dataclass
class SlidingModeCompensator:
    """u_0 = -K w / max(|w|, Phi), w = B^T P y = Kp e + Kv e' (the NN compensator's w).

    The unit-vector sliding-mode law (Slotine and Li, Ch. 7; Corless and Leitmann 1981) with a
    boundary layer of width Phi: |u_0| = K outside the layer (|w| >= Phi) and a linear
    high-gain term K w / Phi inside it, so u_0 is continuous. With a fixed gain K >= |eta| the
    Lyapunov function y^T P y decreases outside the layer. It is what the NN compensator is
    measured against: the same w and the same bound structure, but a fixed, hand-tuned K
    instead of the adapted rho-hat. Stateless.

    Attributes:
        Kp, Kv: task gains (m x m).
        gain: K [m/s^2].
        boundary: Phi [m/s^2] (> 0).

    """

    Kp: np.ndarray
    Kv: np.ndarray
    gain: float = 20.0
    boundary: float = 0.5

    state_size = 0
    signal_names = ()
    twin = "sliding_mode"  # csrc/controllers/sliding_mode.cpp
    twin_fields = ("BtP", "gain", "boundary")

    def __post_init__(self):
        if self.gain < 0 or self.boundary <= 0:
            raise ValueError(
                f"sliding_mode: need gain >= 0 and boundary > 0, got {self.gain}, {self.boundary}"
            )
        _, B = error_dynamics(self.Kp, self.Kv)
        self.BtP = B.T @ lyapunov_P(self.Kp, self.Kv)

    def initial_state(self) -> np.ndarray:
        """No state."""
        return np.zeros(0)

    def output(self, q: np.ndarray, v: np.ndarray, y: np.ndarray, z: np.ndarray, period: float):
        """(u_0, z, signals)."""
        w = self.BtP @ y
        return -self.gain * w / max(float(np.linalg.norm(w)), self.boundary), z, {}
