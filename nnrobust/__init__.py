"""nnrobust: robust neural-network control of redundant manipulators, built on Pinocchio.

The names below are imported on first use, so that ``import nnrobust`` (and the command line's
start) stays fast and interruptible.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_EXPORTS = {
    "DynamicsModel": ".model",
    "NNRobustError": ".exceptions",
    "PinocchioModel": ".model",
    "ThreeLinkParameters": ".model",
    "ThreeLinkPlanarModel": ".model",
    "load_robot": ".model",
    "paper_arm_urdf": ".model",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'nnrobust' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
