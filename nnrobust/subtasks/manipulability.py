"""Manipulability criteria: det(J J^T) and its square root (Yoshikawa)."""

from __future__ import annotations

import numpy as np

from ..core.small_linalg import adjugate, det
from ..model.base import DynamicsModel
from .base import Criterion
from .registry import CriterionKind, declare

MANIPULABILITY_UNITS = {2: "m$^2$", 3: "m$^3$", 6: "m$^3$"}
"""Units of sqrt det(J J^T) by task size m, for revolute joints (a pose's angular rows are
dimensionless: rad per rad)."""


def hessian_det_gradient(model: DynamicsModel, q: np.ndarray) -> tuple[float, np.ndarray]:
    """det(J J^T) and its gradient d/dq_k = 2 tr(adj(J J^T) (dJ/dq_k) J^T) from the kinematic
    Hessian dJ/dq (O(m n^2)): the reference form, for models without a faster one.
    """
    J = model.task_jacobian(q)
    H = model.task_jacobian_derivative(q)  # m x n x n, H[:, :, k] = dJ/dq_k
    A = J @ J.T
    return det(A), 2.0 * np.einsum("ij,jlk,il->k", adjugate(A), H, J)


def det_and_gradient(model: DynamicsModel, q: np.ndarray) -> tuple[float, np.ndarray]:
    """det(J J^T) and its gradient: in O(n) where the model offers ``det_jjt_gradient``
    (:class:`~nnrobust.model.PinocchioModel`), else :func:`hessian_det_gradient`.
    """
    fast = getattr(model, "det_jjt_gradient", None)
    return fast(q) if fast is not None else hessian_det_gradient(model, q)


class HalfDetManipulability(Criterion):
    """h = 0.5 det(J J^T), the first term of the paper's eq. (19)."""

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """0.5 det(J J^T)."""
        J = model.task_jacobian(q)
        return 0.5 * det(J @ J.T)

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """0.5 d det(J J^T)/dq."""
        return 0.5 * det_and_gradient(model, q)[1]


class Manipulability(Criterion):
    """h = sqrt(det(J J^T)), Yoshikawa's manipulability measure."""

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """sqrt(det(J J^T))."""
        J = model.task_jacobian(q)
        return float(np.sqrt(max(det(J @ J.T), 0.0)))

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """D det / dq / (2 sqrt(det)); zero at a singularity, where it is not defined."""
        det, grad = det_and_gradient(model, q)
        if det <= 1e-300:
            return np.zeros_like(q)
        return grad / (2.0 * np.sqrt(det))


declare(
    CriterionKind(
        "half_det_manipulability",
        HalfDetManipulability,
        "0.5 det(J J^T)",
        lambda m: {2: "m$^4$", 3: "m$^6$", 6: "m$^6$"}.get(m, "mixed"),
        lambda sc, robot: HalfDetManipulability(),
        lambda criterion: {},
        det=True,
    ),
    CriterionKind(
        "manipulability",
        Manipulability,
        "sqrt(det(J J^T)) (Yoshikawa)",
        lambda m: MANIPULABILITY_UNITS.get(m, "mixed"),
        lambda sc, robot: Manipulability(),
        lambda criterion: {},
        det=True,
    ),
)
