"""The paper's M(q) and V_m(q, q') exactly as printed in Sect. 4 (wrong: see docs/errata.md).

Kept only to show, in tests, that they fail basic properties; never used by the library.
"""

from __future__ import annotations

import numpy as np


def printed_mass(q, beta, p) -> np.ndarray:
    """M(q) as printed."""
    b1, b2, b3 = beta
    p1, p2, p3 = p
    c2, c3, c23 = np.cos(q[1]), np.cos(q[2]), np.cos(q[1] + q[2])
    m11 = b1 + 2 * p1 * c2 + p2 * c23 + p3 * c3
    m12 = b2 + p1 * c2 + p2 * c23
    return np.array([[m11, m12, b3], [m12, b2 + 2 * p3 * c3, b3 + p3 * c3], [b3, b3 + p3 * c3, b3]])


def printed_coriolis(q, v, p) -> np.ndarray:
    """V_m(q, q') as printed (s_12 where s_23 is meant, and the printed signs)."""
    p1, p2, p3 = p
    s2, s3, s12 = np.sin(q[1]), np.sin(q[2]), np.sin(q[0] + q[1])
    v1, v2, v3 = v
    a = p1 * s2 + p2 * s12
    b = p2 * s12 + p3 * s12
    return np.array(
        [
            [-a * v2 - b * v3, -a * (v1 + v2) - b * v3, b * (-v1 + v2 + v3)],
            [a * v1 + p3 * s3 * v3, -b * v3, -p3 * s3 * (3 * v1 + v2 + v3)],
            [a * v1 - p3 * s3 * v2, p3 * s3 * (v1 + v2), 0.0],
        ]
    )
