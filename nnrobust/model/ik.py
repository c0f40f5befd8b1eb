"""Inverse kinematics for the initial configuration, and the seed it starts from."""

from __future__ import annotations

import numpy as np

from ..core.arrays import joint_vector
from ..core.exceptions import ConfigError
from ..core.small_linalg import DampedPseudoInverse
from .base import DynamicsModel
from .pinocchio_model import PinocchioModel
from .tasks import split_pose, task_error


def solve_ik(
    model: DynamicsModel,
    target: np.ndarray,
    q_seed: np.ndarray,
    lower: np.ndarray | None = None,
    upper: np.ndarray | None = None,
    tol: float = 1e-10,
    max_iter: int = 200,
) -> tuple[np.ndarray, float]:
    """Q with f(q) = target, reached from q_seed by damped Gauss-Newton steps -J+ e(f(q), target).

    Works for every task kind: e is the task error of :func:`nnrobust.model.tasks.task_error`
    (for a pose, position and rotation-vector error). Minimum-norm steps keep the solution near
    the seed. Joint limits, when given, clip each iterate.

    Returns:
        (q, residual) where residual = |e| [m, or m and rad for a pose]; the caller decides what
        is too large.

    """
    pinv = DampedPseudoInverse(threshold=0.05, max_damping=0.05)
    q = np.array(q_seed, dtype=float)
    residual = np.inf
    for _ in range(max_iter):
        err = -task_error(model.task, model.task_position(q), np.asarray(target))
        residual = float(np.linalg.norm(err))
        if residual < tol:
            break
        step = pinv.matrix(model.task_jacobian(q)) @ err
        scale = min(1.0, 0.5 / max(np.max(np.abs(step)), 1e-300))  # at most 0.5 rad a step
        q = q + scale * step
        if lower is not None and upper is not None:
            q = np.clip(q, lower, upper)
    return q, residual


IK_LIMIT_MARGIN = 0.02
"""The initial configuration keeps this fraction of each joint's range inside its limits."""


def finite_limits(values: np.ndarray) -> np.ndarray:
    """URDF limits with absent ones (not finite, or Pinocchio's huge placeholders) as inf."""
    return np.where(np.isfinite(values) & (np.abs(values) < 1e6), values, np.copysign(np.inf, values))


def seed_configuration(q_seed: list[float] | None, robot: PinocchioModel) -> np.ndarray:
    """``simulation.q_seed`` (default: mid-range), refused outside the joint limits."""
    lower, upper = robot.lower_limits, robot.upper_limits
    seed = joint_vector("simulation.q_seed", q_seed, robot.nq, robot.mid_configuration)
    outside = np.flatnonzero((seed < lower) | (seed > upper))
    if outside.size:
        i = int(outside[0])
        more = f" (and {outside.size - 1} more joints)" if outside.size > 1 else ""
        raise ConfigError(
            "simulation.q_seed",
            f"joint {robot.joint_names[i]!r} = {seed[i]:g} is "
            f"outside its limits [{lower[i]:g}, {upper[i]:g}]{more}",
        )
    return seed


def reach(robot: PinocchioModel, target: np.ndarray, seed: np.ndarray, what: str, key: str) -> np.ndarray:
    """Q with f(q) = target, from ``seed`` and inside the limits by :data:`IK_LIMIT_MARGIN`; a
    target out of reach is a ConfigError naming ``key`` (``what`` says which target it is).
    """
    lower, upper = finite_limits(robot.lower_limits), finite_limits(robot.upper_limits)
    margin = np.where(np.isfinite(upper - lower), IK_LIMIT_MARGIN * (upper - lower), 0.0)
    seed = np.clip(seed, lower + margin, upper - margin)
    q, residual = solve_ik(robot, target, seed, robot.lower_limits + margin, robot.upper_limits - margin)
    if residual > 1e-6:
        p = split_pose(target)[0] if robot.task == "pose" else target
        raise ConfigError(
            key,
            f"{what} (position {np.round(p, 4).tolist()} m) is out of reach from q_seed = "
            f"{np.round(seed, 3).tolist()} (task error {residual:.3g} left)",
        )
    return q
