"""Bounded external disturbances tau_d(t) of eq. (7)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.exceptions import ConfigError
from ..core.kinds import Kinds


class Disturbance(ABC):
    """tau_d(t) of eq. (7), a torque per joint that the plant subtracts from the actuators': the
    contract of the shipped disturbance and a user's (``plant.disturbance = "custom"``,
    docs/extending.md), built as ``Class(robot, **plant.disturbance_params)`` with ``robot`` the
    arm's model (``nq``, ``joint_names``, ``effort_limits``, ...).
    """

    @abstractmethod
    def __call__(self, t: float) -> np.ndarray:
        """tau_d(t), one torque per joint [N m or N]."""


@dataclass(frozen=True)
class SinusoidalDisturbance(Disturbance):
    """tau_d,i(t) = sum_k A[i, k] sin(omega[k] t + phase[i, k]).

    Attributes:
        amplitude: A, n x K [N m].
        omega: angular frequencies, K [rad/s].
        phase: n x K [rad].

    """

    amplitude: np.ndarray
    omega: np.ndarray
    phase: np.ndarray

    twin = "sinusoid"
    """Its compiled twin's name (csrc/plant/disturbance.hpp, ``NNROBUST_DISTURBANCE``)."""
    twin_fields = ("amplitude", "omega", "phase")
    """What its compiled twin reads."""

    def __post_init__(self):
        for name in ("amplitude", "omega", "phase"):
            object.__setattr__(self, name, np.atleast_1d(np.asarray(getattr(self, name), float)))
        if self.amplitude.ndim == 1:
            object.__setattr__(self, "amplitude", self.amplitude[:, None])
        if self.phase.shape != self.amplitude.shape or self.omega.shape != self.amplitude.shape[1:]:
            raise ValueError(
                f"disturbance: amplitude {self.amplitude.shape}, omega {self.omega.shape} and "
                f"phase {self.phase.shape} must be n x K, K and n x K"
            )

    @classmethod
    def paper(cls) -> SinusoidalDisturbance:
        """tau_d = [4 cos 2t, sin t + cos 2t, 2 sin t]^T N m (Sect. 4, errata reading)."""
        half_pi = np.pi / 2
        return cls(
            amplitude=np.array([[0.0, 4.0], [1.0, 1.0], [2.0, 0.0]]),
            omega=np.array([1.0, 2.0]),
            phase=np.array([[0.0, half_pi], [0.0, half_pi], [0.0, 0.0]]),
        )

    @classmethod
    def none(cls, n: int) -> SinusoidalDisturbance:
        """tau_d = 0 on n joints."""
        return cls(np.zeros((n, 1)), np.zeros(1), np.zeros((n, 1)))

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.amplitude.shape[0]

    def bound(self) -> np.ndarray:
        """Per-joint bound sum_k |A[i, k]| [N m]."""
        return np.abs(self.amplitude).sum(axis=1)

    def __call__(self, t: float) -> np.ndarray:
        """tau_d(t) [N m]."""
        return (self.amplitude * np.sin(self.omega * t + self.phase)).sum(axis=1)


@dataclass(frozen=True)
class ScaledDisturbance(Disturbance):
    """Another disturbance with joint i's torque times ``rows[i]`` (``plant.disturbance_scale`` and
    ``plant.joint_disturbance_scales`` on a custom disturbance).
    """

    inner: Disturbance
    rows: np.ndarray

    def __call__(self, t: float) -> np.ndarray:
        """The scaled torque, rows * tau_d(t) [N m]."""
        return self.rows * np.asarray(self.inner(t), dtype=float)


@dataclass(frozen=True)
class DisturbanceKind:
    """A shipped disturbance, declared beside its code: its name in ``plant.disturbance``, one
    line for the docs and errors, and ``build(plant_section, robot, tau_ref)`` -> the Disturbance
    (``tau_ref()`` the robot's torque scale, computed once if asked for; a ConfigError names the
    key at fault). ``plant.disturbance_scale``, the per-joint scales, the frequency scale and the
    phase shift then apply to whatever it builds. ``params``: the ``[plant]`` keys it reads beyond
    the section's fields, each declared (:class:`nnrobust.core.key_checks.LawParam`, named
    ``plant.KEY``): defaulted, range-checked, inert under another disturbance.
    """

    name: str
    description: str
    build: Callable[[Any, Any, Callable[[], np.ndarray]], Disturbance]
    params: tuple[Any, ...] = ()


DISTURBANCE_KINDS: Kinds[DisturbanceKind] = Kinds("disturbance")
"""The shipped disturbances by name (``auto`` and ``custom`` are choices of the experiment)."""

declare_disturbance = DISTURBANCE_KINDS.declare
"""Register disturbances (in the module that builds them)."""


def _paper(pc, robot, tau_ref) -> SinusoidalDisturbance:
    if robot.nq != 3:
        raise ConfigError("plant.disturbance", f"'paper' is for 3 joints, the robot has {robot.nq}")
    return SinusoidalDisturbance.paper()


def _sinusoid(pc, robot, tau_ref) -> SinusoidalDisturbance:
    amplitude = np.asarray(pc.disturbance_amplitude, dtype=float)
    omega = np.asarray(pc.disturbance_omega, dtype=float)
    phase = (
        np.zeros_like(amplitude)
        if pc.disturbance_phase is None
        else np.asarray(pc.disturbance_phase, dtype=float)
    )
    try:
        disturbance = SinusoidalDisturbance(amplitude, omega, phase)
    except ValueError as err:
        raise ConfigError("plant.disturbance_amplitude", str(err)) from err
    if disturbance.n != robot.nq:
        raise ConfigError("plant.disturbance_amplitude", f"has {disturbance.n} rows, need {robot.nq}")
    return disturbance


declare_disturbance(
    DisturbanceKind("paper", "the paper's tau_d of its experiments (three joints)", _paper),
    DisturbanceKind(
        "none", "no disturbance", lambda pc, robot, tau_ref: SinusoidalDisturbance.none(robot.nq)
    ),
    DisturbanceKind(
        "sinusoid",
        "sum_k A[i, k] sin(omega_k t + phi[i, k]) from plant.disturbance_amplitude, _omega, _phase",
        _sinusoid,
    ),
)
