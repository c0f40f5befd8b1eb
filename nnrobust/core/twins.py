"""What crosses to a component's compiled twin (docs/compiled.md): its numbers by name, each a
2-D float array (a number 1 x 1, a vector k x 1), read on the C++ side by the same names
(csrc/fields.hpp). A component lists them once, beside its code, in its ``twin_fields``.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np


def field_array(value) -> np.ndarray:
    """A number, vector or matrix (or a bool) as the C++ side's 2-D float array."""
    array = np.asarray(value, dtype=float)
    return np.ascontiguousarray(array.reshape(-1, 1) if array.ndim < 2 else array)


def twin_values(component, names: Iterable[str]) -> dict[str, np.ndarray]:
    """The attributes ``names`` of a built component, as its twin reads them."""
    return {name: field_array(getattr(component, name)) for name in names}


def twin_parts(component) -> dict[str, dict[str, np.ndarray]]:
    """The fields of each part a component lists in its ``twin_parts``, by the part's attribute
    name (a part that is None is left out: the twin has none).
    """
    parts = {name: getattr(component, name) for name in component.twin_parts}
    return {name: twin_values(part, part.twin_fields) for name, part in parts.items() if part is not None}
