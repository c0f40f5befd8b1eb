"""The checks every call of a user's part goes through (a trajectory, a disturbance, a criterion:
nnrobust.trajectories.custom, nnrobust.plant.custom, nnrobust.subtasks.custom): what it returns is
finite numbers of the right shape, and what it raises is one line naming its class key, never a
NaN that a divergence message would blame on the gains. About 2 us a call.
"""

from __future__ import annotations

import numpy as np

from ..core.exceptions import ConfigError
from .user_code import located


def checked_vector(key: str, what: str, value, size: int) -> np.ndarray:
    """A call's result as a finite vector of ``size`` entries, or one line naming the class key."""
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ConfigError(key, f"{what} returned {type(value).__name__}, not numbers ({err})") from err
    if out.shape != (size,):
        raise ConfigError(key, f"{what} returned shape {out.shape}; expected ({size},)")
    if not np.all(np.isfinite(out)):
        raise ConfigError(key, f"{what} returned a non-finite value: {out.tolist()}")
    return out


def checked_call(key: str, what: str, function, *args):
    """``function(*args)``, or one line naming ``key`` and ``what`` raised (SystemExit too)."""
    try:
        return function(*args)
    except (Exception, SystemExit) as err:  # a part may not end the process either
        raise ConfigError(key, f"{what} raised {located(err)}") from err
