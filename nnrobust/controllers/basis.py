"""Basis functions phi(s) of the one-layer network that estimates the uncertainty bound."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class AdditiveRBFBasis:
    """phi(s) = [1, exp(-(s_j - c_jk)^2 / (2 w_j^2)) for each input j and centre k].

    Gaussian radial basis functions along each input coordinate, summed (an additive model):
    the number of units grows linearly with the input size (1 + centres x dim(s)) instead of
    exponentially as a full grid would, so the same basis serves a 3- or a 7-joint arm.
    The constant unit lets rho-hat hold a state-independent bound. All phi_i are in (0, 1], so
    rho-hat = Z^T phi >= 0 whenever Z >= 0, which the paper's adaptive law preserves.

    Attributes:
        low: lower end of each input range (centres span [low, high]).
        high: upper end of each input range.
        centers: number of centres per input.
        width: Gaussian width as a multiple of the centre spacing.
        bias: include the constant unit.
        grid: the centres c_jk, dim(s) x centres (derived).
        inverse_two_width_sq: 1 / (2 w_j^2) per input (derived).

    """

    low: np.ndarray
    high: np.ndarray
    centers: int = 5
    width: float = 1.0
    bias: bool = True
    grid: np.ndarray = field(init=False, repr=False, compare=False)
    inverse_two_width_sq: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        low = np.asarray(self.low, dtype=float)
        high = np.asarray(self.high, dtype=float)
        if low.shape != high.shape or np.any(high <= low):
            raise ValueError(f"basis: need low < high elementwise, got {low} and {high}")
        if self.centers < 1 or self.width <= 0:
            raise ValueError(f"basis: centers ({self.centers}) >= 1 and width ({self.width}) > 0")
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)
        unit = np.linspace(0.0, 1.0, self.centers) if self.centers > 1 else np.array([0.5])
        object.__setattr__(self, "grid", low[:, None] + (high - low)[:, None] * unit)
        spacing = (high - low) / max(self.centers - 1, 1)
        object.__setattr__(self, "inverse_two_width_sq", 1.0 / (2.0 * (self.width * spacing) ** 2))

    @property
    def input_size(self) -> int:
        """dim(s)."""
        return self.low.size

    @property
    def size(self) -> int:
        """Number of units L, the length of phi and of Z."""
        return int(self.bias) + self.centers * self.input_size

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """phi(s), shape L."""
        d = s[:, None] - self.grid
        rbf = np.exp(-(d * d) * self.inverse_two_width_sq[:, None]).ravel()
        return np.concatenate(([1.0], rbf)) if self.bias else rbf


def input_box(
    basis_input: str, lower: np.ndarray, upper: np.ndarray, velocity_range: float, error_range, m: int
) -> tuple[np.ndarray, np.ndarray]:
    """The box phi's centres span: s = [q, q'] over the joint limits clipped to one turn
    [-pi, pi] and +-velocity_range [rad/s] (``joint``), or s = [e, e'] over +-error_range[0] [m]
    and +-error_range[1] [m/s] (``error``, m task coordinates).
    """
    if basis_input == "joint":
        speed = np.full(len(lower), velocity_range)
        return (
            np.concatenate([np.maximum(lower, -np.pi), -speed]),
            np.concatenate([np.minimum(upper, np.pi), speed]),
        )
    r = np.concatenate([np.full(m, error_range[0]), np.full(m, error_range[1])])
    return -r, r
