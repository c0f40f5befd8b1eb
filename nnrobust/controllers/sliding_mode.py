"""The classical non-adaptive robust alternative: a boundary-layer sliding-mode term u_0."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.numeric_limits import MAX_GAIN
from ..core.search_coordinates import Param
from .nn_compensator import error_dynamics, lyapunov_P
from .registry import KindParts, LawParam, PaperKind, declare_kind


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


def _build(parts: KindParts):
    """Eq. (9) with the sliding-mode term of ``controller.sliding_gain`` and ``sliding_boundary``."""
    # here: at the top, task_space's kinds would be declared before this one (the order listed)
    from .task_space import eq9_law

    c = parts.controller
    return eq9_law(
        parts, SlidingModeCompensator(np.diag(c.Kp), np.diag(c.Kv), c.sliding_gain, c.sliding_boundary)
    )


def _search(scales: dict) -> list:
    """The tuner's coordinates of the sliding-mode term: K and Phi, scaled by the arm's task
    acceleration a (nnrobust/studies/tune/space.py).
    """
    a = scales["task_acceleration"]
    return [
        Param("controller.sliding_gain", 1e-3 * a, 10 * a, "m/s^2", weak="low"),
        Param("controller.sliding_boundary", 1e-5 * a, a, "m/s^2", weak="high"),
    ]


declare_kind(
    PaperKind(
        "sliding-mode",
        "−K ω / max(‖ω‖, Φ): fixed gain K (`sliding_gain`), boundary layer Φ (`sliding_boundary`)",
        "the experiment's",
        _build,
        keys=("controller.sliding_gain", "controller.sliding_boundary"),
        search=_search,
        lyapunov=True,
        params=(
            LawParam(
                "controller.sliding_gain",
                20.0,
                "m/s^2",
                "fixed gain K",
                low=0.0,
                low_open=True,
                high=MAX_GAIN,
            ),
            LawParam(
                "controller.sliding_boundary",
                0.5,
                "m/s^2",
                "boundary-layer width Φ",
                low=0.0,
                low_open=True,
                high=MAX_GAIN,
            ),
        ),
    )
)
