"""What the controller measures: encoder quantisation and seeded Gaussian noise on q and q'."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Sensor:
    """q_m = Q(q + n_q), q'_m = q' + n_v with n ~ N(0, std^2) per joint and Q the encoder's rounding.

    Quantisation rounds to the nearest multiple of ``resolution`` (one encoder count); the velocity
    is not quantised (drives estimate it from many counts). The noise is drawn from a generator
    seeded with ``seed``, once per control period, so a run is reproducible.

    Attributes:
        position_noise: standard deviation of n_q per joint [rad or m] (0: none).
        velocity_noise: standard deviation of n_v per joint [rad/s or m/s] (0: none).
        resolution: encoder resolution per joint [rad or m] (0: continuous).
        seed: seed of the noise.

    """

    position_noise: np.ndarray
    velocity_noise: np.ndarray
    resolution: np.ndarray
    seed: int = 0
    _rng: np.random.Generator = field(init=False, repr=False)

    twin_fields = ("position_noise", "velocity_noise", "resolution")
    """What its compiled twin reads (csrc/plant/sensing.hpp), beside :meth:`twin_draws`."""

    def __post_init__(self):
        for name in ("position_noise", "velocity_noise", "resolution"):
            value = np.asarray(getattr(self, name), dtype=float)
            if np.any(value < 0) or not np.all(np.isfinite(value)):
                raise ValueError(f"sensing: {name} must be finite and >= 0, got {value.tolist()}")
            setattr(self, name, value)
        self._rng = np.random.default_rng(self.seed)

    def reset(self) -> None:
        """Draw again from the seed: every run of one Sensor sees the same noise."""
        self._rng = np.random.default_rng(self.seed)

    @classmethod
    def ideal(cls, n: int) -> Sensor:
        """Exact measurements of n joints."""
        return cls(np.zeros(n), np.zeros(n), np.zeros(n))

    def twin_draws(self, steps: int) -> dict[str, np.ndarray]:
        """The standard normal draws :meth:`measure` makes over ``steps`` control periods from the
        seed, in its order, for the compiled twin: ``noise_q`` and ``noise_v``, n x steps (n x 0
        for an ideal sensor, which draws nothing).
        """
        n = self.position_noise.size
        if self.is_ideal:
            return {"noise_q": np.zeros((n, 0)), "noise_v": np.zeros((n, 0))}
        draws = np.random.default_rng(self.seed).standard_normal((steps, 2, n))
        return {"noise_q": draws[:, 0, :].T.copy(), "noise_v": draws[:, 1, :].T.copy()}

    @property
    def is_ideal(self) -> bool:
        """Whether measurements equal the true state."""
        return not (self.position_noise.any() or self.velocity_noise.any() or self.resolution.any())

    def measure(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q_m, q'_m) for the true state (q, q')."""
        if self.is_ideal:
            return q, v
        q_m = q + self.position_noise * self._rng.standard_normal(q.size)
        v_m = v + self.velocity_noise * self._rng.standard_normal(v.size)
        r = self.resolution
        q_m = np.where(r > 0, np.round(q_m / np.where(r > 0, r, 1.0)) * r, q_m)
        return q_m, v_m
