"""The compiled backend: the extension module ``nnrobust._loop`` (C++ against Pinocchio, built
during ``pip install`` when a C++ compiler is there; docs/compiled.md).

The package works without it: :func:`available` says whether it loaded and :func:`unavailable_reason`
why not, and everything else runs on the Python reference implementation.
"""

from __future__ import annotations

import importlib

import pinocchio as pin

from .exceptions import NNRobustError

_MODULE = None
_REASON = ""


def _load():
    global _MODULE, _REASON
    if _MODULE is None and not _REASON:
        try:
            _MODULE = importlib.import_module("nnrobust._loop")
        except ImportError as err:
            _REASON = (f"the compiled loop is not built ({err}); reinstall nnrobust with a C++ compiler "
                       "(g++ and cmake) to build it")
    return _MODULE


def available() -> bool:
    """Whether the compiled extension loaded."""
    return _load() is not None


def unavailable_reason() -> str:
    """Why the compiled extension is not available ("" when it is)."""
    _load()
    return _REASON


def load_model(model: pin.Model, frame: str):
    """The C++ copy of a Pinocchio model (exactly this model: serialized with Pinocchio's own
    ``saveToString``), with ``frame`` as its task frame.
    """
    module = _load()
    if module is None:
        raise NNRobustError(_REASON)
    return module.LoadedModel(model.saveToString(), frame)


def floor_loop(model, q0, v0, steps: int, dt: float):
    """The bare C++ loop of benchmarks/closed_loop.py: final [q, v] after ``steps`` steps of ``dt``."""
    module = _load()
    if module is None:
        raise NNRobustError(_REASON)
    return module.floor_loop(model, q0, v0, steps, dt)
