"""Identification (docs/identification.md): from a robot's joint log to its identified model,
``nnrobust identify``. The model side (regressor, base parameters, physical checks) is the model
room's, :mod:`nnrobust.model.regressor` and :mod:`nnrobust.model.identified`.
"""

from .engine import IdentifyOptions, identify

__all__ = ["IdentifyOptions", "identify"]
