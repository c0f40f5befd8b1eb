"""Shipped experiments: one TOML file each in ``nnrobust/preset_files`` (found by
:mod:`nnrobust.config.shipped`), loaded as configurations.
"""

from __future__ import annotations

from . import ExperimentConfig, load_config
from .shipped import PRESET_DIR, preset_names, preset_path, presets_hint

__all__ = ["PRESET_DIR", "load_preset", "preset_names", "preset_path", "presets_hint"]


def load_preset(name: str) -> ExperimentConfig:
    """The configuration of a preset."""
    return load_config(preset_path(name))
