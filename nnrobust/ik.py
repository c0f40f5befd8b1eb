"""Inverse kinematics for the initial configuration."""

from __future__ import annotations

import numpy as np

from .controllers.pseudoinverse import DampedPseudoInverse
from .model.base import DynamicsModel
from .model.tasks import task_error


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
