"""A study's report: ``report.json`` (the numbers, under the schema of docs/study.md),
``report.html`` (one self-contained file: tables, figures inside, the reproducibility appendix),
``tables/`` (CSV and LaTeX booktabs) and ``figures/`` (PNG, SVG, PDF), all from the stages'
own folders.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import platform
from pathlib import Path

import numpy as np

from ..drawing import drawn_alone
from ..properties import overall_certificate
from ..results import write_json_atomic, write_text_atomic
from ..study_folder import own_folder
from ..table_text import csv_cell, tex_text
from ..tune.engine import STUDY_REPORT
from ..tune.space import fixed_text
from .spec import DESIGN, StudySpec, kept_name

SCHEMA = f"{STUDY_REPORT}1"
STATISTICS = (
    "rows",
    "success_rate",
    "statuses",
    "rms_error_after_2s",
    "rms_torque",
    "saturated_fraction_mean",
    "rows_with_warnings",
)
"""The keys of a certification sweep's summary each controller's statistics hold (either engine)."""


def _versions() -> dict:
    import numpy
    import pinocchio
    import scipy

    from .. import __version__

    return {
        "nnrobust": __version__,
        "python": platform.python_version(),
        "pinocchio": pinocchio.__version__,
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "platform": platform.platform(),
    }


def _inputs(spec: StudySpec) -> dict:
    """SHA-256 of every input file: the study file, and per case what its rows are computed from
    (the experiment files, the URDF, the custom classes: :func:`nnrobust.sweep.spec.study_inputs`).
    """
    from ..study_folder import file_sha256
    from ..sweep.spec import study_inputs

    out = {_shown(spec.path): file_sha256(spec.path)}
    if spec.tuned:  # the tuning the settings come from
        from ..tune.engine import tuned_file

        source, _ = tuned_file(spec.tuned)
        out[_shown(source)] = file_sha256(source)
    for case in spec.cases:
        for path, digest in study_inputs(spec.case_sweep(case)).files.values():
            out[_shown(path)] = digest
    return out


def _shown(path) -> str:
    """A path as the report shows it: relative to the folder the study was run from when it lies
    beneath it (a report read on another machine names the project's files, not this one's
    folders), else as given; a robot's name (a built-in URDF) unchanged.
    """
    p = Path(path)
    if not p.is_absolute():
        return str(path)
    try:
        return str(p.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def _commands(spec: StudySpec, folder: Path, name: str, case: dict) -> dict:
    """The command that recomputes each stage's numbers from its own folder's input file."""
    here = folder / "cases" / name
    b = spec.budgets
    tuned = [c for c in spec.controllers if c not in spec.fixed]
    out = {}
    for s, path in case.get("tunings", {}).items():
        out[f"tune seed {s}"] = (
            f"nnrobust tune {here / 'case.toml'} --controllers {','.join(tuned)} --budget {b['tune']} "
            f"--train-samples {case.get('train_samples', b['train_samples'])} --validation 0 "
            f"--seed {spec.seed + int(s)}"
            + (f" --max-rms-torque {b['max_rms_torque']:g}" if math.isfinite(b["max_rms_torque"]) else "")
            + (f" --max-saturated {b['max_saturated']:g}" if b["max_saturated"] < 1 else "")
            + f" --out {path}"
        )
    out["validate"] = f"nnrobust sweep {here / 'validate.toml'} --out {here / 'validate'}"
    require = " ".join(f"--require '{r}'" for r in spec.certified_properties())
    searched = " ".join(f"--require '{r}'" for r in spec.require)
    out["certify"] = (
        f"nnrobust sweep {here / 'certify.toml'} {require} --epsilon {b['epsilon']:g} --beta {b['beta']:g} "
        f"--out {here / 'certify'}"
    )
    if case["stages"].get("engine") == "finished":
        out["engine"] = (
            f"nnrobust sweep {here / 'certify-mujoco.toml'} {require} --epsilon {b['epsilon']:g} "
            f"--beta {b['beta']:g} --out {here / 'certify-mujoco'}"
        )
    if case["stages"].get("falsify") == "finished":
        kept = ",".join(case["kept"])
        out["falsify"] = (
            f"nnrobust falsify {here / 'case.toml'} --controllers {kept} {searched} --budget {b['falsify']} "
            f"--seed {spec.seed} --tuned {here / 'kept.json'} --epsilon {b['epsilon']:g} --beta {b['beta']:g}"
            + (" --margin" if b["margin"] else "")
            + f" --out {here / 'falsify'}"
        )
    return out


def _controller_entry(spec: StudySpec, case: dict, c: str) -> dict:
    label = c if c in spec.fixed else kept_name(c)
    certify = case["certify"]["controllers"].get(label, {})
    kept = case["kept"].get(c)
    per_seed = case["per_seed"].get(c, [])
    medians = [e["median_error"] for e in per_seed if math.isfinite(e["median_error"])]
    entry: dict = {
        "label": label,
        "tuned": None
        if c in spec.fixed
        else {
            "seeds": per_seed,
            "kept_seed": kept["seed"] if kept else None,
            "settings": kept["settings"] if kept else None,
            "seed_spread": [min(medians), max(medians)] if medians else None,
            "seed_median": float(np.median(medians)) if medians else None,
            "at_bound": kept["at_bound"] if kept else None,
            "fixed": case.get("fixed", {}).get(c, {}),
            "convergence": case.get("convergence", {}).get(c),
        },
        "fixed": c in spec.fixed,
        "validation": {
            "median_error": kept["median_error"],
            "rows": kept["rows"],
            "completed": kept["completed"],
            "feasible": kept.get("feasible"),
            **(kept.get("validation") or {}),
        }
        if kept
        else None,
        "statistics": {k: certify.get(k) for k in STATISTICS},
        "certificates": certify.get("certificates", []),
        "quantile_bounds": certify.get("quantile_bounds", []),
        "warnings": certify.get("warnings_by_kind", {}),
        "failures": case.get("failures", {}).get(label, {}),
    }
    cost = case.get("step_cost", {}).get(label, {})
    entry["step_cost_us"], entry["backend"] = cost.get("step_cost_us"), cost.get("backend")
    entry["realtime"] = (case.get("realtime") or {}).get(label)
    engines = {"pinocchio": entry["statistics"]}
    second = (case.get("engine") or {}).get("controllers", {}).get(label)
    if second:
        engines["mujoco"] = {
            **{k: second.get(k) for k in STATISTICS},
            "certificates": second.get("certificates", []),
        }
    entry["engines"] = engines
    falsified = (case.get("falsify") or {}).get("controllers", {})
    found = falsified.get(label) or falsified.get(c)
    if found:
        from ..falsify.summary import replayed_worst

        worst, found_by = replayed_worst(found)  # the plant whose command replays the verdict
        entry["worst"] = {
            "falsified": found["falsified"],
            "found_by": found_by,
            "simulations": found["simulations"],
            "margin": worst["margin"],
            "metrics": worst["metrics"],
            "command": worst["command"],
        }
        entry["falsification"] = found  # the stage's record: both searches, the baseline's certificate
    margins = (case.get("falsify") or {}).get("margin", {})
    if label in margins or c in margins:
        entry["margin"] = margins.get(label) or margins.get(c)
    return entry


def _untuned(report: dict, c: str, entry: dict) -> str:
    """The settings cell of a controller the study did not tune."""
    if not entry["fixed"]:
        return "-"
    if report.get("tuned_from") and c.endswith(kept_name("")):
        return f"the kept setting of {report['tuned_from']} (tuned = ...)"
    return "its own settings (tune = false)"


def study_warnings(spec: StudySpec) -> list[str]:
    """What a reader of the report must know before its numbers: no torque or saturation
    constraint (kept settings may saturate), each part of the design's requirement the file
    waives, and each policy scored outside the horizon it was trained on.
    """
    from ..controllers.laws.policy import horizon_warning
    from ..results import SETTLED_AFTER
    from ..sweep.spec import base_config

    b = spec.budgets
    out = []
    if not math.isfinite(b["max_rms_torque"]) and b["max_saturated"] >= 1:
        out.append(
            "no torque or saturation constraint (budgets.max_rms_torque, budgets.max_saturated): kept "
            "settings may saturate the actuators"
        )
    out += [f"waived by the study file: {DESIGN[w]}" for w in spec.waive]
    for case in spec.cases:
        duration = base_config(spec.case_sweep(case)).simulation.duration
        for c in spec.controllers:
            params = spec.entries.get(c, {}).get("params") or {}
            if spec.entries.get(c, {}).get("kind") == "policy" and isinstance(params.get("file"), str):
                said = horizon_warning(c, params["file"], duration, SETTLED_AFTER)
                if said:
                    out.append(f"{spec.case_name(case)}: {said}")
    return out


def build_report(spec: StudySpec, folder: Path, cases: dict) -> dict:
    """report.json's content (docs/study.md's schema)."""
    report: dict = {
        "schema": SCHEMA,
        "study": spec.name,
        "description": spec.description,
        "versions": _versions(),
        "inputs": _inputs(spec),
        "require": spec.require,
        "tuned_from": spec.tuned or None,
        "budgets": {
            k: (None if isinstance(v, float) and math.isinf(v) else v) for k, v in spec.budgets.items()
        },
        "certified_properties": spec.certified_properties(),
        "waived": {w: DESIGN[w] for w in spec.waive},
        "warnings": study_warnings(spec),
        "cases": {},
    }
    for name, case in cases.items():
        label_of = {(c if c in spec.fixed else kept_name(c)): c for c in spec.controllers}
        paired = [
            {**p, "a": label_of.get(p["a"], p["a"]), "b": label_of.get(p["b"], p["b"])}
            for p in case["certify"].get("paired", [])
        ]
        report["cases"][name] = {
            "case": case["case"],
            "set": case.get("set", {}),
            "stages": case["stages"],
            "held_out": case["held_out"],
            "validated_on": "fresh draws of the uncertainty set, independent of the training draws"
            if case["held_out"]
            else "the training plant: the case has no randomness (every draw is the same plant)",
            "controllers": {
                c: _controller_entry(spec, case, c) for c in spec.controllers if c in case["kept"]
            },
            "not_kept": case.get("not_kept", {}),
            "paired": paired,
            "commands": _commands(spec, folder, name, case),
        }
    return report


TABLE_COLUMNS = (
    ("case", "case"),
    ("controller", "controller"),
    ("median_mm", "median e [mm]"),
    ("p95_mm", "p95 e [mm]"),
    ("success", "completed %"),
    ("passed", "passed %"),
    ("p_fail_upper", "P(fail) <="),
    ("falsified", "falsified"),
    ("least_margin", "least margin"),
    ("kept_seed", "kept seed"),
    ("seed_spread_mm", "seeds' medians [mm]"),
    ("converged", "converged"),
    ("mujoco_median_mm", "MuJoCo median e [mm]"),
    ("step_cost_us", "us / step"),
    ("export_p99_us", "exported p99 [us]"),
)


def table_rows(report: dict) -> list[dict]:
    """One row per (case, controller): the certification draws' error statistics, the
    certificate's bound, the falsification's verdict and the seeds' spread.
    """
    rows = []
    for name, case in report["cases"].items():
        for c, e in case["controllers"].items():
            err = e["statistics"].get("rms_error_after_2s") or {}
            certs = e["certificates"]
            spread = (e["tuned"] or {}).get("seed_spread")
            whole = overall_certificate(certs)
            convergence = (e["tuned"] or {}).get("convergence") or {}
            rows.append(
                {
                    "case": name,
                    "controller": c,
                    "median_mm": None if err.get("median") is None else 1e3 * err["median"],
                    "p95_mm": None if err.get("p95") is None else 1e3 * err["p95"],
                    "success": None
                    if e["statistics"].get("success_rate") is None
                    else 100 * e["statistics"]["success_rate"],
                    "passed": None
                    if whole is None or not whole["N"]
                    else 100 * (1 - whole["k"] / whole["N"]),
                    "p_fail_upper": None if whole is None else whole["p_upper"],
                    "converged": convergence.get("converged") if e["tuned"] else None,
                    "falsified": (e.get("worst") or {}).get("falsified"),
                    "least_margin": (e.get("worst") or {}).get("margin"),
                    "kept_seed": (e["tuned"] or {}).get("kept_seed"),
                    "seed_spread_mm": None if not spread else f"{1e3 * spread[0]:.4g}-{1e3 * spread[1]:.4g}",
                    "mujoco_median_mm": _median_mm(e["engines"].get("mujoco")),
                    "step_cost_us": e["step_cost_us"],
                    "export_p99_us": (e.get("realtime") or {}).get("p99_us"),
                }
            )
    return rows


def _median_mm(stats: dict | None) -> float | None:
    median = ((stats or {}).get("rms_error_after_2s") or {}).get("median")
    return None if median is None else 1e3 * median


def _cell(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def write_tables(report: dict, folder: Path) -> list[Path]:
    """tables/summary.csv and tables/summary.tex (booktabs)."""
    import csv

    rows = table_rows(report)
    out = own_folder(folder / "tables")
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow([key for key, _ in TABLE_COLUMNS])
    for row in rows:  # names come from the user's files: no cell a spreadsheet evaluates
        writer.writerow([csv_cell(row[k]) for k, _ in TABLE_COLUMNS])
    write_text_atomic(out / "summary.csv", buffer.getvalue())

    def head(text: str) -> str:  # our own headings: escaped, then their two symbols typeset
        return tex_text(text).replace("<=", r"$\le$").replace("us / step", r"$\mu$s / step")

    lines = [
        r"\begin{tabular}{" + "l" * 2 + "r" * (len(TABLE_COLUMNS) - 2) + "}",
        r"\toprule",
        " & ".join(head(h) for _, h in TABLE_COLUMNS) + r" \\",
        r"\midrule",
        *(" & ".join(tex_text(_cell(row[k])) for k, _ in TABLE_COLUMNS) + r" \\" for row in rows),
        r"\bottomrule",
        r"\end{tabular}",
    ]
    write_text_atomic(out / "summary.tex", "\n".join(lines) + "\n")
    return [out / "summary.csv", out / "summary.tex"]


@drawn_alone
def _figure(name: str, case: dict, folder: Path) -> str:
    """The certification draws' error CDF per controller: saved as PNG, SVG and PDF, and returned
    as a base64 PNG for the HTML.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    import pandas as pd

    frame = pd.read_parquet(folder / "cases" / name / "certify" / "results")
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for label, rows in frame.groupby("controller", sort=False):
        done = rows[rows["status"] == "completed"]
        e = np.sort(1e3 * done["rms_error_after_2s"].to_numpy(dtype=float))
        e = e[np.isfinite(e)]
        if e.size:
            ax.step(e, np.arange(1, e.size + 1) / len(rows), where="post", label=str(label))
    ax.set_xscale("log")
    ax.set_xlabel("RMS task error, t >= 2 s [mm]")
    ax.set_ylabel("fraction of draws")
    ax.set_title(f"{name}: certification draws")
    ax.grid(True, which="both", alpha=0.3)
    if ax.get_legend_handles_labels()[0]:  # no completed draw: no line, no legend
        ax.legend(fontsize=8)
    fig.tight_layout()
    out = own_folder(folder / "figures")
    for ext in ("png", "svg", "pdf"):  # drawn beside, renamed into place: never through a link
        tmp = out / f".{name}-error-cdf.partial.{ext}"
        fig.savefig(tmp, dpi=120)
        tmp.replace(out / f"{name}-error-cdf.{ext}")
    plt.close(fig)
    return base64.b64encode((out / f"{name}-error-cdf.png").read_bytes()).decode()


def write_html(report: dict, folder: Path, figures: dict[str, str]) -> Path:
    """report.html: one file, no network, figures inside as data URIs."""
    e = html.escape
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'>",
        f"<title>{e(report['study'])}: nnrobust study</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}"
        "table{border-collapse:collapse;margin:1em 0}td,th{border-bottom:1px solid #ccc;padding:3px 8px;"
        "text-align:right}td:first-child,th:first-child,td:nth-child(2){text-align:left}"
        "code{font-size:85%;word-break:break-all}.note{color:#555}</style></head><body>",
        f"<h1>{e(report['study'])}</h1><p>{e(report['description'])}</p>",
        f"<p>Required: {', '.join(f'<code>{e(r)}</code>' for r in report['require'])}; certified: "
        f"{', '.join(f'<code>{e(r)}</code>' for r in report.get('certified_properties', report['require']))}"
        f". Budgets: {e(json.dumps(report['budgets']))}.</p>",
        *(f"<p><b>Warning:</b> {e(w)}</p>" for w in report.get("warnings", [])),
        "<h2>Summary</h2><table><tr>" + "".join(f"<th>{e(head)}</th>" for _, head in TABLE_COLUMNS) + "</tr>",
    ]
    for row in table_rows(report):
        parts.append("<tr>" + "".join(f"<td>{e(_cell(row[k]))}</td>" for k, _ in TABLE_COLUMNS) + "</tr>")
    parts.append("</table>")
    for name, case in report["cases"].items():
        parts.append(f"<h2>Case {e(name)}</h2><p class='note'>Validated on {e(case['validated_on'])}.</p>")
        if name in figures:
            parts.append(f"<img alt='error CDF of {e(name)}' src='data:image/png;base64,{figures[name]}'>")
        stages = ", ".join(f"{k}: {v}" for k, v in case["stages"].items())
        parts.append(f"<p class='note'>Stages: {e(stages)}.</p>")
        for c, reason in case["not_kept"].items():
            parts.append(f"<p><b>{e(c)}: not kept.</b> {e(reason)}</p>")
        parts.append(
            "<h3>Kept settings</h3><table><tr><th>controller</th><th>kept seed</th><th>setting</th>"
            "<th>seeds' validation medians [mm]</th><th>on a bound</th><th>not searched, and why</th></tr>"
        )
        for c, entry in case["controllers"].items():
            tuned = entry["tuned"] or {}
            setting = ", ".join(f"{k} = {_cell(v)}" for k, v in (tuned.get("settings") or {}).items())
            medians = ", ".join(
                f"seed {s['seed']}: {_cell(None if s['median_error'] is None else 1e3 * s['median_error'])}"
                for s in tuned.get("seeds", [])
            )
            bound = (
                ", ".join(
                    f"{b['param']} at its {b['side']} bound {_cell(b['bound'])}"
                    + (f" ({b['physical']})" if b.get("physical") else "")
                    for b in tuned.get("at_bound") or []
                )
                or "-"
            )
            held = "; ".join(fixed_text((tuned.get("fixed") or {}).items())) or "-"
            parts.append(
                f"<tr><td>{e(c)}</td><td>{e(_cell(tuned.get('kept_seed')))}</td>"
                f"<td>{e(setting or _untuned(report, c, entry))}</td>"
                f"<td>{e(medians or '-')}</td><td>{e(bound)}</td><td>{e(held)}</td></tr>"
            )
        parts.append("</table>")
        for c, entry in case["controllers"].items():
            for status, failed in entry["failures"].items():
                parts.append(
                    f"<p><b>{e(c)}: {failed['runs']} certification runs {e(status)}</b>, the first: "
                    f"{e(failed['first_message'])}</p>"
                )
            if entry["warnings"]:
                fired = ", ".join(f"{k} ({n} runs)" for k, n in entry["warnings"].items())
                parts.append(f"<p>{e(c)}: warnings on the certification draws: {e(fired)}.</p>")
        if case["paired"]:
            from ..paired import format_pair

            parts.append("<h3>Paired comparisons (certification draws)</h3><ul>")
            parts += [f"<li>{e(format_pair(p))}</li>" for p in case["paired"]]
            parts.append(f"</ul><p class='note'>Method: {e(case['paired'][0]['method'])}.</p>")
        parts.append("<h3>Certificates</h3><ul>")
        for c, entry in case["controllers"].items():
            for cert in entry["certificates"]:
                parts.append(
                    f"<li>{e(c)}: P(<code>{e(cert['property'])}</code> fails) &le; {cert['p_upper']:.4g} "
                    "with "
                    f"confidence {1 - cert['beta']:.4g} (N = {cert['N']}, k = {cert['k']}; "
                    f"{e(cert['method'])})</li>"
                )
        parts.append("</ul><h3>Worst plants found</h3><ul>")
        for c, entry in case["controllers"].items():
            if "worst" in entry:
                w = entry["worst"]
                verdict = "FALSIFIED" if w["falsified"] else "not falsified"
                status = (w.get("metrics") or {}).get("status", "completed")
                margin = (
                    _cell(w["margin"])
                    if w["margin"] is not None
                    else f"-inf (the run ended {status}: {(w.get('metrics') or {}).get('message', '')})"
                )
                parts.append(
                    f"<li>{e(c)}: {verdict} in {w['simulations']} simulations, least margin {e(margin)}: "
                    f"<code>{e(w['command'])}</code></li>"
                )
        timed = {c: entry["realtime"] for c, entry in case["controllers"].items() if entry.get("realtime")}
        if timed:
            parts.append("</ul><h3>Out of Python (the exported law's step)</h3><ul>")
            for c, r in timed.items():
                parts.append(
                    f"<li>{e(c)}: p50 {_cell(r['p50_us'])} us, p99 {_cell(r['p99_us'])} us, max "
                    f"{_cell(r['max_us'])} us over {r['steps']} steps: p99 is "
                    f"{_cell(100 * r['p99_share'])} % of the {_cell(r['period_us'])} us period; "
                    f"{_cell(r['allocations_per_step'])} heap "
                    "allocations per step</li>"
                    if "p99_us" in r
                    else f"<li>{e(c)}: {'not timed' if r.get('exported') else 'no export'} "
                    f"({e(r.get('reason', ''))})</li>"
                )
        parts.append("</ul><h3>Commands</h3><ul>")
        parts += [f"<li>{e(k)}: <code>{e(v)}</code></li>" for k, v in case["commands"].items()]
        parts.append("</ul>")
    parts.append("<h2>Reproducibility</h2><h3>Versions</h3><ul>")
    parts += [f"<li>{e(k)}: {e(str(v))}</li>" for k, v in report["versions"].items()]
    parts.append("</ul><h3>Inputs (SHA-256)</h3><ul>")
    parts += [f"<li><code>{e(d)}</code> {e(p)}</li>" for p, d in report["inputs"].items()]
    parts.append("</ul></body></html>")
    return write_text_atomic(folder / "report.html", "\n".join(parts))


def finite(value):
    """``value`` with every non-finite float as null, so that report.json is standard JSON (a
    margin of -inf, a run that did not complete, is null beside the status that says why).
    """
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    return value


def write_report(spec: StudySpec, folder: Path, cases: dict) -> dict:
    """report.json, tables/, figures/ and report.html; returns the report."""
    for name, case in cases.items():  # the kept settings, as --tuned reads them (the falsify command)
        kept = {  # a fixed controller runs at its own settings: --tuned leaves it untuned
            c: {"fixed": True} if c in spec.fixed else {"best": {"params": k["settings"]}}
            for c, k in case["kept"].items()
        }
        write_json_atomic(folder / "cases" / name / "kept.json", {"controllers": kept})
    report = build_report(spec, folder, cases)
    report = finite(report)
    write_json_atomic(folder / "report.json", report)
    write_tables(report, folder)
    figures = {name: _figure(name, case, folder) for name, case in cases.items()}
    write_html(report, folder, figures)
    from ..display import StudyReport

    return StudyReport(report)
