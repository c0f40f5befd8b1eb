"""Damped least-squares pseudo-inverse J+ and the null-space projection, eqs. (3), (5), (6): the
keys every law shares in an experiment file. The linear algebra itself lives in
:mod:`nnrobust.core.small_linalg` (inverse kinematics uses it too).
"""

from __future__ import annotations

from ..core.numeric_limits import MAX_PINV
from ..core.small_linalg import DampedPseudoInverse, project_null_space
from .registry import LawParam, SharedKeys, declare_shared

__all__ = ["KEYS", "SAME_PSEUDO_INVERSE", "DampedPseudoInverse", "project_null_space"]


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
