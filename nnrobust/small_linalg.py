"""Small linear algebra the model and the criteria share: the determinant and the adjugate in
closed form for m <= 3 (a leaf module).
"""

from __future__ import annotations

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
