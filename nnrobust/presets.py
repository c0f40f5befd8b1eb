"""Shipped experiments: one TOML file each in ``nnrobust/preset_files``."""

from __future__ import annotations

from pathlib import Path

from .config import ExperimentConfig, load_config
from .exceptions import ConfigError

PRESET_DIR = Path(__file__).resolve().parent / "preset_files"


def preset_names() -> list[str]:
    """Names of the shipped presets."""
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


def preset_path(name: str) -> Path:
    """The TOML file of a preset."""
    path = PRESET_DIR / f"{name}.toml"
    if not path.is_file():
        raise ConfigError("preset", f"unknown preset {name!r}; presets: {', '.join(preset_names())}")
    return path


def load_preset(name: str) -> ExperimentConfig:
    """The configuration of a preset."""
    return load_config(preset_path(name))
