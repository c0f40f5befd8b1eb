"""Studies: one file of cases, controllers, uncertainty set, properties and budgets run through
tune, validation, certification and falsification into one report (docs/study.md).
"""

from .engine import read_report, run_study
from .spec import StudySpec, load_study, parse_study

__all__ = ["StudySpec", "load_study", "parse_study", "read_report", "run_study"]
