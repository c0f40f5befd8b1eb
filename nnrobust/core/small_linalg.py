"""Small linear algebra the model, the criteria, the laws and inverse kinematics share: the
determinant and the adjugate in closed form for m <= 3, and the damped least-squares
pseudo-inverse J+ with the null-space projection of eqs. (3), (5), (6) (a leaf module).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def adjugate(A: np.ndarray) -> np.ndarray:
    """adj(A) = det(A) A^-1, by cofactors (valid for singular A)."""
    m = A.shape[0]
    if m == 1:
        return np.ones((1, 1))
    if m == 2:
        return np.array([[A[1, 1], -A[0, 1]], [-A[1, 0], A[0, 0]]])
    if m == 3:  # rows of adj(A)^T are cross products of the columns of A
        a0, a1, a2 = A[:, 0], A[:, 1], A[:, 2]
        return np.array([np.cross(a1, a2), np.cross(a2, a0), np.cross(a0, a1)])
    cof = np.empty_like(A)
    for i in range(m):
        for j in range(m):
            minor = np.delete(np.delete(A, i, axis=0), j, axis=1)
            cof[i, j] = (-1) ** (i + j) * np.linalg.det(minor)
    return cof.T


def det(A: np.ndarray) -> float:
    """The determinant, in closed form for m <= 3 (no LU: exact zero, no warning when singular)."""
    m = A.shape[0]
    if m == 1:
        return float(A[0, 0])
    if m == 2:
        return float(A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0])
    if m == 3:
        return float(A[:, 0] @ np.cross(A[:, 1], A[:, 2]))
    return float(np.linalg.det(A))


@dataclass(frozen=True)
class DampedPseudoInverse:
    """J+ = J^T (J J^T + lambda^2 I)^-1 with damping only near singularities.

    lambda^2 = max_damping^2 (1 - (sigma_min / threshold)^2) when the smallest singular value
    sigma_min of J is below ``threshold``, else 0, so that J+ = J^T (J J^T)^-1 exactly (the
    paper's J+) away from singularities and stays bounded at them (Nakamura; Maciejewski).

    Attributes:
        threshold: sigma_min below which damping starts [m/rad].
        max_damping: lambda at sigma_min = 0 [m/rad].

    """

    threshold: float = 0.02
    max_damping: float = 0.02

    def damping(self, JJt: np.ndarray) -> float:
        """lambda^2 for the given J J^T."""
        sigma_min_sq = max(float(np.linalg.eigvalsh(JJt)[0]), 0.0)
        thr_sq = self.threshold**2
        if sigma_min_sq >= thr_sq:
            return 0.0
        return self.max_damping**2 * (1.0 - sigma_min_sq / thr_sq)

    def factor(self, J: np.ndarray) -> tuple[np.ndarray, float]:
        """(J J^T + lambda^2 I)^-1 applied as a matrix (m x m), and lambda^2."""
        JJt = J @ J.T
        lam2 = self.damping(JJt)
        return np.linalg.inv(JJt + lam2 * np.eye(J.shape[0])), lam2

    def matrix(self, J: np.ndarray) -> np.ndarray:
        """J+ as an n x m matrix."""
        inv, _ = self.factor(J)
        return J.T @ inv


def project_null_space(J: np.ndarray, J_pinv: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(I - J+ J) z computed as z - J+ (J z): O(n m), no n x n matrix."""
    return z - J_pinv @ (J @ z)
