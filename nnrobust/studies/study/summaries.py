"""Any study command's folder read back: ``nnrobust.load_summary(DIR)`` gives the summary of a
sweep, a tuning, a falsification or a study, shown as HTML in Jupyter.
"""

from __future__ import annotations

from pathlib import Path

from ...core.exceptions import NNRobustError
from ...run.results import read_json
from ..falsify.summary import FalsifySummary
from ..sweep.summary import SweepSummary
from ..tune.summary import TuneSummary
from .tables import StudyReport

KINDS = {
    ".nnrobust-sweep": ("summary.json", SweepSummary),
    ".nnrobust-tune": ("summary.json", TuneSummary),
    ".nnrobust-falsify": ("summary.json", FalsifySummary),
    "study.toml": ("report.json", StudyReport),
}
"""A folder's marker -> the file its summary is in and its display."""


def load_summary(folder: str | Path) -> dict:
    """The summary of a sweep, tuning, falsification or study folder, displayed as HTML in
    Jupyter (``SweepSummary``, ``TuneSummary``, ``FalsifySummary`` or ``StudyReport``).
    """
    folder = Path(folder)
    for marker, (name, kind) in KINDS.items():
        if (folder / marker).is_file() and (folder / name).is_file():
            data = read_json(folder / name, "summary")
            if not isinstance(data, dict):
                raise NNRobustError(f"{folder / name}: not a summary (its JSON is not a table)")
            return kind(data)
    raise NNRobustError(
        f"{folder} holds no finished sweep, tuning, falsification or study (no summary.json or report.json "
        "beside its marker); run the command into it first"
    )
