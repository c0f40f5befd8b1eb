"""A study's summary tables, read off report.json: error *and* effort per law and case (RMS task
error, RMS torque, chatter, saturated share), the share of draws that met the whole requirement and
its sampled bound on P(fail), which properties failed, then the verdicts and the provenance (the
falsification, the kept seed and the seeds' spread, convergence at the budget, the training budget
in simulated seconds, the second engine, the step costs). The same rows make the HTML, CSV, LaTeX
and console tables. A statistic is shown only where its N supports it: a 95th percentile needs
N >= 59 draws for a distribution-free statement at 95 % (the sample maximum bounds the 95 %
quantile with confidence 1 - 0.95^N >= 0.95 from N = 59 on, Wilks); below, the cell says so.
"""

from __future__ import annotations

import csv
import html
import io
import math
from pathlib import Path

from ...core.folders import own_folder
from ...core.table_text import csv_cell, tex_text
from ...run.properties import overall_certificate
from ...run.results import write_text_atomic
from ..base.display import html_cell, table

P95_DRAWS = 59
"""The fewest draws whose sample maximum bounds the 95 % quantile with 95 % confidence (Wilks):
below, no 95th percentile is printed."""

SMALL_N = f"N < {P95_DRAWS}"
"""The cell of a 95th percentile its N cannot support."""

EFFORT_COLUMNS = (
    ("case", "case"),
    ("controller", "controller"),
    ("draws", "draws N"),
    ("median_mm", "median e [mm]"),
    ("p95_mm", "p95 e [mm]"),
    ("torque_median", "median RMS tau [N m]"),
    ("torque_p95", "p95 RMS tau [N m]"),
    ("chatter_median", "median chatter [N m]"),
    ("saturated", "saturated [%]"),
    ("passed", "passed [%]"),
    ("p_fail_upper", "P(fail) <= (sampled, 1 - beta)"),
    ("failed", "failed properties (draws)"),
)
"""The first table: error and effort on the certification draws, and what the draws show."""

VERDICT_COLUMNS = (
    ("case", "case"),
    ("controller", "controller"),
    ("falsified", "falsified"),
    ("least_margin", "least margin"),
    ("kept_seed", "kept seed"),
    ("seed_spread_mm", "feasible seeds' medians [mm]"),
    ("converged", "converged at its budget"),
    ("training_seconds", "training [simulated s]"),
    ("mujoco_median_mm", "MuJoCo median e [mm]"),
    ("step_cost_us", "us / step"),
    ("export_p99_us", "exported p99 [us]"),
)
"""The second table: the falsification, the tuning's provenance, the second engine and the costs."""

TABLE_COLUMNS = EFFORT_COLUMNS + VERDICT_COLUMNS[2:]
"""Every column (the CSV's, and the notebook display's)."""


def _stat(stats: dict | None, key: str, scale: float = 1.0, draws: int = 0):
    value = (stats or {}).get(key)
    if key == "p95" and value is not None and draws < P95_DRAWS:
        return SMALL_N
    return None if value is None else scale * value


def property_label(text: str, names: dict[str, str]) -> str:
    """A property's short name in a table: the design part it stands for, else its metric."""
    return names.get(text) or text.split("<")[0].split(">")[0].split("=")[0].split("!")[0]


def table_rows(report: dict) -> list[dict]:
    """One row per (case, controller), every column of :data:`TABLE_COLUMNS`."""
    names = report.get("property_names", {})
    rows = []
    for name, case in report["cases"].items():
        for c, e in case["controllers"].items():
            stats = e["statistics"]
            certs = e["certificates"]
            whole = overall_certificate(certs)
            draws = whole["N"] if whole else int(stats.get("rows") or 0)
            tuned = e["tuned"] or {}
            spread = tuned.get("seed_spread")
            convergence = tuned.get("convergence") or {}
            singles = [cert for cert in certs if cert is not whole] or certs
            failed = ", ".join(f"{property_label(cert['property'], names)} {cert['k']}"
                               for cert in singles if cert["k"])  # fmt: skip
            rows.append(
                {
                    "case": name,
                    "controller": c,
                    "draws": draws,
                    "median_mm": _stat(stats.get("rms_error_after_2s"), "median", 1e3),
                    "p95_mm": _stat(stats.get("rms_error_after_2s"), "p95", 1e3, draws),
                    "torque_median": _stat(stats.get("rms_torque"), "median"),
                    "torque_p95": _stat(stats.get("rms_torque"), "p95", 1.0, draws),
                    "chatter_median": _stat(stats.get("torque_chatter"), "median"),
                    "saturated": None
                    if stats.get("saturated_fraction_mean") is None
                    else 100 * stats["saturated_fraction_mean"],
                    "passed": None
                    if whole is None or not whole["N"]
                    else 100 * (1 - whole["k"] / whole["N"]),
                    "p_fail_upper": None if whole is None else whole["p_upper"],
                    "failed": failed or ("none" if certs else None),
                    "falsified": (e.get("worst") or {}).get("falsified"),
                    "least_margin": (e.get("worst") or {}).get("margin"),
                    "kept_seed": tuned.get("kept_seed"),
                    "seed_spread_mm": None if not spread else f"{1e3 * spread[0]:.4g}-{1e3 * spread[1]:.4g}",
                    "converged": None
                    if not e["tuned"]
                    else ("yes" if convergence.get("converged") else _not_converged(convergence)),
                    "training_seconds": (e.get("training") or {}).get("simulated_seconds"),
                    "mujoco_median_mm": _median_mm(e["engines"].get("mujoco")),
                    "step_cost_us": e["step_cost_us"],
                    "export_p99_us": (e.get("realtime") or {}).get("p99_us"),
                }
            )
    return rows


def _median_mm(stats: dict | None) -> float | None:
    median = ((stats or {}).get("rms_error_after_2s") or {}).get("median")
    return None if median is None else 1e3 * median


def cell(value) -> str:
    """A table cell as text: "-" for none, yes/no, four significant digits."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.4g}" if math.isfinite(value) else str(value)
    return str(value)


def _tex_head(text: str) -> str:  # our own headings: escaped, then their symbols typeset
    return tex_text(text).replace("<=", r"$\le$").replace("us / step", r"$\mu$s / step")


def _tabular(rows: list[dict], columns) -> list[str]:
    return [
        r"\begin{tabular}{" + "l" * 2 + "r" * (len(columns) - 2) + "}",
        r"\toprule",
        " & ".join(_tex_head(h) for _, h in columns) + r" \\",
        r"\midrule",
        *(" & ".join(tex_text(cell(row[k])) for k, _ in columns) + r" \\" for row in rows),
        r"\bottomrule",
        r"\end{tabular}",
    ]


def write_tables(report: dict, folder: Path) -> list[Path]:
    """tables/summary.csv (every column) and tables/summary.tex (booktabs: the error and effort
    table, then the verdicts table).
    """
    rows = table_rows(report)
    out = own_folder(folder / "tables")
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow([key for key, _ in TABLE_COLUMNS])
    for row in rows:  # names come from the user's files: no cell a spreadsheet evaluates
        writer.writerow([csv_cell(row[k]) for k, _ in TABLE_COLUMNS])
    write_text_atomic(out / "summary.csv", buffer.getvalue())
    lines = [*_tabular(rows, EFFORT_COLUMNS), "", *_tabular(rows, VERDICT_COLUMNS)]
    write_text_atomic(out / "summary.tex", "\n".join(lines) + "\n")
    return [out / "summary.csv", out / "summary.tex"]


def console_line(row: dict) -> str:
    """One controller of one case for the command's closing lines: error and effort, the
    requirement's verdict, the falsification, and convergence.
    """
    converged = row["converged"]
    return (
        f"{row['case']:24s} {row['controller']:18s} e median {cell(row['median_mm'])} mm, p95 "
        f"{cell(row['p95_mm'])}; RMS tau median {cell(row['torque_median'])} N m, chatter "
        f"{cell(row['chatter_median'])} N m, saturated {cell(row['saturated'])} %; passed "
        f"{cell(row['passed'])} % of {row['draws']} draws (failed: {cell(row['failed'])}), P(fail) <= "
        f"{cell(row['p_fail_upper'])}; falsified: {cell(row['falsified'])}, least margin "
        f"{cell(row['least_margin'])}"
        + ("" if converged in (None, "yes") else f"; NOT CONVERGED ({converged})")
    )


class StudyReport(dict):
    """A study's report.json: the summary table of every case and controller."""

    def _repr_html_(self) -> str:
        rows = [[html_cell(row[k]) for k, _ in TABLE_COLUMNS] for row in table_rows(self)]
        notes = "".join(
            f"<p>{html.escape(name)}: validated on {html.escape(case['validated_on'])}.</p>"
            for name, case in self["cases"].items()
        )
        return (
            f"<h4>study {html.escape(self['study'])}</h4>"
            + table([h for _, h in TABLE_COLUMNS], rows)
            + notes
        )


def _not_converged(convergence: dict) -> str:
    """The convergence column of a law whose budget did not converge: "no, at" its budget (a
    tuning's simulations, a training's simulated seconds).
    """
    budget = convergence.get("budget")
    unit = " simulated s" if convergence.get("unit") else ""
    return f"no, at {budget:g}{unit}" if isinstance(budget, int | float) else f"no, at {budget}"
