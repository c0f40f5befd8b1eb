"""Joint friction F(q') of eq. (7): viscous plus Coulomb."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Friction:
    """F(q') = F_d q' + F_c sgn(q'), the paper's Sect. 4 friction with F_c = 1 N m.

    At q' = 0 the dry part is set-valued: a joint at rest is held by any torque up to the static
    level F_s >= F_c (stiction; F_s = F_c by default). The plant integrates it as stick-slip
    (:mod:`nnrobust.plant.stick_slip`); :meth:`torque` is the slipping law with sgn(0) = 0.

    A controller that compensates Coulomb friction from sampled velocities uses a smoothed sign,
    sat(q' / v_s) (``smoothing`` = v_s > 0): with the exact sgn, a joint resting near zero speed
    gets +-F_c held for whole control periods, a limit cycle of its own.

    Attributes:
        viscous: F_d, per joint [N m s/rad].
        coulomb: F_c, per joint [N m]; sgn(0) = 0.
        smoothing: v_s [rad/s]: sgn is replaced by sat(q' / v_s) (0: exact sgn, the true plant).
        static: F_s, the most a joint at rest is held by, per joint [N m] (None: F_c).

    """

    viscous: np.ndarray
    coulomb: np.ndarray
    smoothing: float = 0.0
    static: np.ndarray | None = None

    twin_fields = ("viscous", "coulomb", "static", "smoothing")
    """What its compiled twin reads (csrc/plant/friction.hpp)."""

    def __post_init__(self):
        object.__setattr__(self, "viscous", np.asarray(self.viscous, dtype=float))
        object.__setattr__(self, "coulomb", np.asarray(self.coulomb, dtype=float))
        static = self.coulomb if self.static is None else np.asarray(self.static, dtype=float)
        if static.shape != self.coulomb.shape or np.any(~(static >= self.coulomb)):
            raise ValueError(
                f"friction: the static level F_s {static.tolist()} must be >= the Coulomb "
                f"level F_c {self.coulomb.tolist()}, joint by joint"
            )
        object.__setattr__(self, "static", static)

    @classmethod
    def none(cls, n: int) -> Friction:
        """No friction on n joints."""
        return cls(np.zeros(n), np.zeros(n))

    def torque(self, v: np.ndarray) -> np.ndarray:
        """F(q') [N m]."""
        sign = np.sign(v) if self.smoothing <= 0 else np.clip(v / self.smoothing, -1.0, 1.0)
        return self.viscous * v + self.coulomb * sign

    def power(self, v: np.ndarray) -> float:
        """q'^T F(q') >= 0 [W], the power friction dissipates."""
        return float(v @ self.torque(v))
