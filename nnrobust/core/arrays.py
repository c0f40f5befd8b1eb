"""Configuration values as arrays sized to the robot, each size error naming its key (a leaf
module: every room that reads a per-joint key uses it).
"""

from __future__ import annotations

import numpy as np

from .exceptions import ConfigError


def joint_vector(path: str, values, n: int, default: np.ndarray | None = None) -> np.ndarray:
    """``values`` as n floats (``default`` when they are not given)."""
    if values is None:
        if default is None:
            raise ConfigError(path, f"needs {n} values")
        return default
    arr = np.asarray(values, dtype=float)
    if arr.shape != (n,):
        raise ConfigError(path, f"has {arr.size} entries, the robot has {n} joints")
    return arr


def per_joint(path: str, values: list[float], n: int) -> np.ndarray:
    """One value for every joint, or one per joint."""
    return np.full(n, float(values[0])) if len(values) == 1 else joint_vector(path, values, n)


def padded(path: str, factors: list[float], size: int, refusal: str) -> list[float]:
    """A list of factors (``nominal.factors``, per-joint scales) with the entries not given as 1;
    more than ``size`` is refused, the key ``path`` named with ``refusal``.
    """
    if len(factors) > size:
        raise ConfigError(path, refusal)
    return list(factors) + [1.0] * (size - len(factors))
