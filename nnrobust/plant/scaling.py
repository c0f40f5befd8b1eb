"""Friction and disturbance sized to the robot: levels relative to each joint's torque scale."""

from __future__ import annotations

import warnings

import numpy as np

from ..model.pinocchio_model import PinocchioModel
from .disturbance import DisturbanceKind, SinusoidalDisturbance, declare_disturbance
from .friction import Friction

REFERENCE_ACCELERATION = 10.0
"""[rad/s^2] for the torque scale of joints without an effort limit."""

REFERENCE_SPEED = 3.0
"""[rad/s] for the viscous friction of joints without a velocity limit."""

GOLDEN_ANGLE = np.pi * (3 - np.sqrt(5))
"""Phase step between joints of the scaled disturbance [rad] (no two joints in phase)."""


def usable(values: np.ndarray) -> np.ndarray:
    """Which URDF limits are real: finite, positive and below Pinocchio's 'no limit' placeholders."""
    return np.isfinite(values) & (values > 0) & (values < 1e6)


def limits_or_inf(values: np.ndarray) -> np.ndarray:
    """URDF limits with inf where :func:`usable` says there is none (no limit)."""
    values = np.asarray(values, dtype=float)
    return np.where(usable(values), values, np.inf)


def torque_needed(robot: PinocchioModel, q: np.ndarray) -> np.ndarray:
    """M_ii(q) * 10 rad/s^2 + |G_i(q)| [N m]: what each joint needs to move the arm at q."""
    return np.diag(robot.mass(q)) * REFERENCE_ACCELERATION + np.abs(robot.gravity(q))


PLAUSIBLE_EFFORT_RATIO = 100.0
"""An effort limit above this many times the largest torque the arm needs is a placeholder."""

RANGE_SAMPLES = 32
"""Seeded configurations over the working range at which the needed torque is evaluated."""


def torque_needed_over_range(robot: PinocchioModel, samples: int = RANGE_SAMPLES) -> np.ndarray:
    """Per joint, the largest :func:`torque_needed` at mid-range and at seeded configurations
    over the joints' working range [N m].
    """
    low, high = robot.working_range
    rng = np.random.default_rng(0)
    needs = [torque_needed(robot, robot.mid_configuration)]
    needs += [torque_needed(robot, rng.uniform(low, high)) for _ in range(samples)]
    return np.max(needs, axis=0)


def _largest_need(robot: PinocchioModel) -> float:
    """The largest torque any joint needs over the range (0 when no effort limit is to be judged)."""
    return float(np.max(torque_needed_over_range(robot))) if np.any(usable(robot.effort_limits)) else 0.0


def _beyond(effort: np.ndarray, need: float) -> np.ndarray:
    return usable(effort) & (effort > PLAUSIBLE_EFFORT_RATIO * max(need, 1e-9))


def implausible_efforts(robot: PinocchioModel) -> np.ndarray:
    """Which joints' effort limits exceed :data:`PLAUSIBLE_EFFORT_RATIO` times the largest torque
    any joint of the arm needs over its range (URDF placeholders such as 1000 N m on a 2 kg
    leg, or 50,000 N m on a robot's head).
    """
    return _beyond(robot.effort_limits, _largest_need(robot))


def torque_scale(robot: PinocchioModel) -> np.ndarray:
    """tau_ref per joint [N m]: the URDF effort limit where there is a plausible one, else
    M_ii(q_mid) * 10 rad/s^2 + |G_i(q_mid)| at mid-range (the arm's own size). An implausible
    limit (:func:`implausible_efforts`) is named in a warning and not used.
    """
    effort, need = robot.effort_limits, _largest_need(robot)
    bad = _beyond(effort, need)
    if np.any(bad):
        joints = ", ".join(f"{robot.joint_names[i]!r} ({effort[i]:g})" for i in np.flatnonzero(bad))
        warnings.warn(
            f"{robot.name}: effort limits of joints {joints} [N m] are over "
            f"{PLAUSIBLE_EFFORT_RATIO:g}x the {need:.3g} N m the arm needs at most "
            "(M_ii 10 rad/s^2 + |G_i| over its range); the scaled friction and disturbance "
            "size those joints by their own need instead (docs/plant.md)",
            stacklevel=3,
        )
    return np.where(usable(effort) & ~bad, effort, torque_needed(robot, robot.mid_configuration))


def scaled_friction(
    robot: PinocchioModel, viscous_level: float, coulomb_level: float, tau_ref: np.ndarray | None = None
) -> Friction:
    """Coulomb = coulomb_level tau_ref; viscous = viscous_level tau_ref / v_max (v_max from the URDF,
    else 3 rad/s): at top speed the viscous torque is viscous_level of the joint's torque scale
    (``tau_ref``, default :func:`torque_scale`).
    """
    tau = torque_scale(robot) if tau_ref is None else tau_ref
    speed = robot.velocity_limits
    speed = np.where(usable(speed), speed, REFERENCE_SPEED)
    return Friction(viscous_level * tau / speed, coulomb_level * tau)


def scaled_disturbance(
    robot: PinocchioModel, level: float, tau_ref: np.ndarray | None = None
) -> SinusoidalDisturbance:
    """tau_d,i(t) = level tau_ref,i (sin(t + phi_i) + sin(2 t + 2 phi_i)) / 2, phi_i = i x golden
    angle: the paper's two harmonics (1 and 2 rad/s), peak at most level tau_ref on every joint
    (``tau_ref``, default :func:`torque_scale`).
    """
    tau = torque_scale(robot) if tau_ref is None else tau_ref
    phi = GOLDEN_ANGLE * np.arange(robot.nq)
    amplitude = 0.5 * level * np.column_stack([tau, tau])
    return SinusoidalDisturbance(amplitude, np.array([1.0, 2.0]), np.column_stack([phi, 2 * phi]))


declare_disturbance(
    DisturbanceKind(
        "scaled",
        "two harmonics (1 and 2 rad/s) peaking at plant.disturbance_level x each joint's torque scale",
        lambda pc, robot, tau_ref: scaled_disturbance(robot, pc.disturbance_level, tau_ref()),
    )
)
