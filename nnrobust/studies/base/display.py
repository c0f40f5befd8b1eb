"""What the summaries' rich displays in Jupyter share: a cell and an HTML table. Each command's
summary class lives with its command (SweepSummary in nnrobust.studies.sweep.summary, TuneSummary in
nnrobust.studies.tune.summary, FalsifySummary in nnrobust.studies.falsify.summary, StudyReport in
nnrobust.studies.study.tables); ``nnrobust.load_summary(DIR)`` reads any of them
(nnrobust.studies.study.summaries).
"""

from __future__ import annotations

import html
import math


def html_cell(value, scale: float = 1.0, digits: int = 4) -> str:
    """A value as an HTML table cell: "-" for none, yes/no, ``digits`` significant digits."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, float)):
        value = float(value) * scale
        return "-" if math.isnan(value) else f"{value:.{digits}g}"
    return html.escape(str(value))


def table(head: list[str], rows: list[list]) -> str:
    """An HTML table of already formatted cells (escaped here)."""
    top = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return f"<table><tr>{top}</tr>{body}</table>"
