"""Damped least-squares pseudo-inverse J+ and the null-space projection, eqs. (3), (5), (6)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..numeric_limits import MAX_PINV
from .registry import LawParam, SharedKeys, declare_shared


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


SAME_PSEUDO_INVERSE = "the experiment's damped pseudo-inverse, the same for every law"
"""Why the tuner holds the pseudo-inverse's keys: every law shares it, so no law gets its own."""

KEYS = declare_shared(
    SharedKeys(
        "the damped pseudo-inverse",
        (
            LawParam(
                "controller.pinv_threshold", 0.02, "m/rad",
                "smallest singular value of J below which J+ is damped", low=0.0, low_open=True,
                high=MAX_PINV, fixed=SAME_PSEUDO_INVERSE,
            ),
            LawParam(
                "controller.pinv_max_damping", 0.02, "m/rad", "damping at a singularity", low=0.0,
                low_open=True, high=MAX_PINV, fixed=SAME_PSEUDO_INVERSE,
            ),
        ),
        readers="every shipped law",
    )
)  # fmt: skip
"""Its keys in an experiment file (``[controller]``)."""
