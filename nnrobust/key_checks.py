"""The one-line checks every room's rules are written with: a value among its choices, a
positive or non-negative number, a physical coefficient, a seed. Each raises a
:class:`~nnrobust.exceptions.ConfigError` naming the key (a leaf module).
"""

from __future__ import annotations

from collections.abc import Sequence

from .exceptions import ConfigError
from .numeric_limits import MAX_PHYSICAL


def check_choice(path: str, value: object, valid: Sequence[str]) -> None:
    """``value`` is one of ``valid``."""
    if value not in valid:
        raise ConfigError(path, f"{value!r} is not one of {', '.join(valid)}")


def require_positive(path: str, values) -> None:
    """A number, or every entry of a list, > 0."""
    seq = values if isinstance(values, list) else [values]
    if any(v <= 0 for v in seq):
        raise ConfigError(path, f"must be positive, got {values}")


def require_non_negative(path: str, value: float) -> None:
    """A number >= 0."""
    if value < 0:
        raise ConfigError(path, f"must be >= 0, got {value}")


def require_physical(path: str, values: list[float] | None, unit: str) -> None:
    """Each entry of a coefficient list (friction, inertial parameter) in [0, MAX_PHYSICAL]."""
    if values is not None and any(not 0 <= v <= MAX_PHYSICAL for v in values):
        raise ConfigError(path, f"each entry must be in [0, {MAX_PHYSICAL:g}] {unit}, got {values}")


def require_seed(path: str, seed: int) -> None:
    """A seed of numpy's generators: an integer in [0, 2^63)."""
    if not 0 <= seed < 2**63:
        raise ConfigError(path, f"must be an integer in [0, 2^63), got {seed}")
