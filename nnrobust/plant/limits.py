"""What a real arm cannot do: actuator torque saturation, the torque-speed envelope and hard
joint-limit stops.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def saturate(tau: np.ndarray, limit: np.ndarray | None) -> np.ndarray:
    """The torque an actuator applies for the command ``tau``: clipped to [-limit, limit] [N m].

    ``limit`` is None for ideal actuators; an entry may be inf for an unlimited joint.
    """
    return tau if limit is None else np.clip(tau, -limit, limit)


def available_torque(
    limit: np.ndarray, tau_cmd: np.ndarray, v: np.ndarray, speed_limit: np.ndarray, knee: float
) -> np.ndarray:
    """The torque an actuator can give in the direction of ``tau_cmd`` at joint speed ``v`` [N m].

    The torque-speed envelope of a current- and voltage-limited motor (``plant.torque_speed``,
    docs/plant.md#torque-speed-envelope): driving the joint (tau_cmd q' > 0) the actuator gives

        tau_avail = limit min(1, max(0, (1 - |q'| / q'_max) / (1 - knee)))

    (the full effort up to ``knee`` q'_max, falling linearly to zero at the velocity limit
    q'_max), and its full effort when braking (tau_cmd q' <= 0). ``knee`` < 0 switches the envelope
    off (the limit at every speed); an inf ``speed_limit`` or ``limit`` leaves that joint's limit
    alone (an unlimited actuator stays unlimited).
    """
    if knee < 0.0:
        return limit
    driving = tau_cmd * v > 0.0
    factor = np.clip((1.0 - np.abs(v) / speed_limit) / (1.0 - knee), 0.0, 1.0)
    finite = np.isfinite(limit)
    return np.where(driving & finite, np.where(finite, limit, 0.0) * factor, limit)


@dataclass(frozen=True)
class JointStops:
    """Hard joint-limit stops: a stiff, dissipative contact outside [lower, upper].

    Beyond a limit by the penetration delta > 0 (moving into the stop at delta' [rad/s]) the stop
    pushes back with the Hunt-Crossley torque (Hunt and Crossley 1975)

        tau_stop = max(0, K delta (1 + alpha delta')),

    directed back into the range, and nothing inside it. The spring part K delta stores and
    returns energy, the damping part K alpha delta delta'^2 >= 0 only dissipates, and the clamp at
    zero only removes a pull, so a stop never adds energy to the arm (tests/plant/test_plant.py). The
    force is continuous at contact (zero at delta = 0), which keeps RK4 accurate. With
    alpha v_in small the coefficient of restitution is about 1 - (2/3) alpha v_in.

    Attributes:
        lower, upper: the joint limits [rad or m]; +-inf for a joint without a stop.
        stiffness: K per joint [N m/rad or N/m].
        alpha: Hunt-Crossley damping [s/rad or s/m].
        ring: per joint, the frequency [rad/s] at which the arm rings against the stop, sqrt(K_i
            (M^-1)_ii) at q(0) (0 for a joint without a stop); the plant step resolves it while
            the joint is at its stop (:func:`nnrobust.run.simulation.step_rate`). None: not known.

    """

    lower: np.ndarray
    upper: np.ndarray
    stiffness: np.ndarray
    alpha: float = 1.0
    ring: np.ndarray | None = None

    twin_fields = ("lower", "upper", "stiffness", "alpha", "ring_frequencies")
    """What its compiled twin reads (csrc/plant/limits.hpp)."""

    def __post_init__(self):
        for name in ("lower", "upper", "stiffness", "ring"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))

    @property
    def ring_frequencies(self) -> np.ndarray:
        """``ring`` with 0 where it is not known (a stop that does not ring) [rad/s]."""
        return self.ring if self.ring is not None else np.zeros(self.lower.size)

    def ringing(self, q: np.ndarray, v: np.ndarray, period: float) -> float:
        """The highest ring frequency [rad/s] among the joints at their stop, or that would reach
        it within ``period`` at their speed (0 if none, or the frequencies are not known).
        """
        if self.ring is None:
            return 0.0
        beyond = np.maximum(q - self.upper, self.lower - q)  # > 0 at the stop; -inf without one
        near = beyond + np.abs(v) * period > 0.0
        return float(np.max(self.ring[near])) if near.any() else 0.0

    def penetration(self, q: np.ndarray) -> np.ndarray:
        """Signed distance beyond the limits, per joint: > 0 above upper, < 0 below lower, else 0."""
        return np.maximum(q - self.upper, 0.0) + np.minimum(q - self.lower, 0.0)

    def torque(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """tau_stop(q, q') [N m], acting on the arm (add it to the actuator torque)."""
        d = self.penetration(q)
        if not d.any():
            return np.zeros_like(q)
        # with s = sign(d): delta = |d|, delta' = s q', push = -s K delta (1 + alpha delta')
        s = np.sign(d)
        magnitude = np.maximum(self.stiffness * np.abs(d) * (1.0 + self.alpha * s * v), 0.0)
        return -s * magnitude

    def potential(self, q: np.ndarray) -> float:
        """Energy stored in the stops' springs, sum K delta^2 / 2 [J]."""
        d = self.penetration(q)
        return 0.5 * float(np.sum(self.stiffness * d * d))
