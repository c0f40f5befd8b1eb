"""Studies: one file of cases, controllers, uncertainty set, properties and budgets run through
tune, validation, certification and falsification into one report (docs/study.md).

The names below are imported on first use, so that a leaf module of the package (the stage
table, which the command line's help reads) loads without the engines.
"""

from __future__ import annotations

import importlib

_NAMES = {
    "read_report": ".engine",
    "run_study": ".engine",
    "StudySpec": ".spec",
    "load_study": ".spec",
    "parse_study": ".spec",
}

__all__ = ["StudySpec", "load_study", "parse_study", "read_report", "run_study"]


def __getattr__(name: str):
    if name not in _NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(_NAMES[name], __name__), name)
    globals()[name] = value
    return value
