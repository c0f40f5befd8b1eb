"""The shipped experiments' files: one TOML file each in ``nnrobust/preset_files``, found by name
(an experiment file's ``base``, the command line's target). :mod:`nnrobust.config.presets` loads them.
"""

from __future__ import annotations

import difflib
from pathlib import Path

from ..core.exceptions import ConfigError

PRESET_DIR = Path(__file__).resolve().parents[1] / "preset_files"


def preset_names() -> list[str]:
    """Names of the shipped presets."""
    return sorted(p.stem for p in PRESET_DIR.glob("*.toml"))


def presets_hint(name: object) -> str:
    """'did you mean X? ' for a name close to a preset's (a typo), then the presets."""
    names = preset_names()
    close = difflib.get_close_matches(name, names, n=1) if isinstance(name, str) else []
    return (f"did you mean {close[0]!r}? " if close else "") + f"presets: {', '.join(names)}"


def preset_path(name: str) -> Path:
    """The TOML file of a preset."""
    if name not in preset_names():
        raise ConfigError("preset", f"unknown preset {name!r}; {presets_hint(name)}")
    return PRESET_DIR / f"{name}.toml"
