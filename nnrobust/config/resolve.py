"""The normalised copy of a checked configuration: :func:`resolve`.

:func:`.checks.validate` only checks; this is the one place where what it accepted is written
out in full (a task gain given once for every task coordinate is repeated m times), so that the
builders, the recorded config.toml and a sweep's samples all read the same explicit values.
"""

from __future__ import annotations

import copy

from ..controllers.section import GAIN_KEYS, full_gain
from .schema import ExperimentConfig, task_rows


def resolve(config: ExperimentConfig) -> ExperimentConfig:
    """A normalised copy of a configuration that :func:`.checks.validate` accepted (the input is
    left as it is): each task gain (``controller.Kp``, ``Kv``, ``pd_Kp``, ``pd_Kd``) with one entry
    per task coordinate. Resolving a resolved configuration changes nothing.
    """
    out = copy.deepcopy(config)
    m, c = task_rows(config), out.controller
    for key in GAIN_KEYS:
        setattr(c, key, full_gain(getattr(c, key), m))
    return out
