"""Rich displays in Jupyter: the summaries of a sweep, a tuning, a falsification and a study
as HTML tables (docs/notebooks.md). Each is the summary's own dict (what summary.json or
report.json holds), with ``_repr_html_``; ``nnrobust.load_summary(DIR)`` reads any of them.
"""

from __future__ import annotations

import html
import math
from pathlib import Path

from .exceptions import NNRobustError
from .results import read_json


def _cell(value, scale: float = 1.0, digits: int = 4) -> str:
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


class SweepSummary(dict):
    """A sweep's summary.json: per controller its rows, success rate and error statistics, and the
    paired comparisons.
    """

    def _repr_html_(self) -> str:
        rows = []
        for name, e in self["controllers"].items():
            err = e.get("rms_error_after_2s") or {}
            rows.append(
                [
                    html.escape(name),
                    _cell(e.get("rows")),
                    _cell(e.get("success_rate"), 100, 3),
                    _cell(err.get("median"), 1e3),
                    _cell(err.get("p95"), 1e3),
                    _cell(err.get("max"), 1e3),
                ]
            )
        out = f"<h4>sweep {html.escape(str(self.get('sweep')))}: {self.get('samples')} samples</h4>"
        out += table(["controller", "rows", "completed %", "median e [mm]", "p95 e [mm]", "max e [mm]"], rows)
        if self.get("paired"):
            from .paired import format_pair

            out += (
                "<ul>" + "".join(f"<li>{html.escape(format_pair(p))}</li>" for p in self["paired"]) + "</ul>"
            )
        return out


class TuneSummary(dict):
    """A tuning's summary.json: each controller's best setting, its training and held-out error."""

    def _repr_html_(self) -> str:
        rows = []
        for name, e in self["controllers"].items():
            best = e.get("best") or {}
            setting = ", ".join(
                f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}"
                for k, v in (best.get("params") or {}).items()
            )
            rows.append(
                [
                    html.escape(name),
                    _cell((best.get("train") or {}).get("rms_error_after_2s"), 1e3),
                    _cell((best.get("train") or {}).get("rms_torque")),
                    _cell((best.get("validation") or {}).get("rms_error_after_2s"), 1e3),
                    _cell((best.get("validation") or {}).get("rms_torque")),
                    _cell(best.get("validation_feasible")),
                    html.escape(setting or e.get("note", "")),
                ]
            )
        target = html.escape(str(self.get("target")))
        out = f"<h4>tuning of {target}: {self.get('budget')} simulations each</h4>"
        head = ["controller", "training e [mm]", "training rms tau [N m]", "held-out e [mm]",
                "held-out rms tau [N m]", "feasible on held-out", "best setting"]  # fmt: skip
        return out + table(head, rows)


class FalsifySummary(dict):
    """A falsification's summary.json: per controller the verdict, the least margin and the worst
    plant's command.
    """

    def _repr_html_(self) -> str:
        from .falsify.summary import replayed_worst

        rows = []
        for name, e in self["controllers"].items():
            worst, found_by = replayed_worst(e)
            verdict = "FALSIFIED" if e.get("falsified") else "not falsified"
            if found_by == "random":
                verdict = "FALSIFIED by random search only"
            rows.append(
                [
                    html.escape(name),
                    verdict,
                    _cell(e.get("simulations")),
                    _cell(worst.get("margin")),
                    _cell(((e.get("random_baseline") or {}).get("worst") or {}).get("margin")),
                    f"<code>{html.escape(str(worst.get('command', '')))}</code>",
                ]
            )
        head = ["controller", "verdict", "simulations", "least margin", "random search", "worst plant"]
        props = ", ".join(html.escape(p) for p in self.get("properties", []))
        return f"<h4>falsification of {props}</h4>" + table(head, rows)


class StudyReport(dict):
    """A study's report.json: the summary table of every case and controller."""

    def _repr_html_(self) -> str:
        from .study.tables import TABLE_COLUMNS, table_rows

        rows = [[_cell(row[k]) for k, _ in TABLE_COLUMNS] for row in table_rows(self)]
        notes = "".join(
            f"<p>{html.escape(name)}: validated on {html.escape(case['validated_on'])}.</p>"
            for name, case in self["cases"].items()
        )
        return (
            f"<h4>study {html.escape(self['study'])}</h4>"
            + table([h for _, h in TABLE_COLUMNS], rows)
            + notes
        )


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
