"""report.html: one self-contained file (no network; figures inline as SVG), read off report.json
and the figures of :mod:`nnrobust.studies.study.figures`: the claim and the box, the warnings, the error
and effort table and the verdicts table, then per case the figures (error CDF with the
requirement, tuning curves, falsification curves, time responses), the kept settings with their
search spaces and widened bounds, the failing draws, the paired comparisons, the sampled bounds,
the worst plants, the exported step and the commands; the reproducibility appendix last.
"""

from __future__ import annotations

import html
import json
from pathlib import Path

from ...run.results import write_text_atomic
from ..tune.space import fixed_text
from .spec import kept_name
from .tables import EFFORT_COLUMNS, VERDICT_COLUMNS, cell, table_rows

STYLE = (
    "<style>body{font-family:sans-serif;max-width:1180px;margin:2em auto;padding:0 1em}"
    "table{border-collapse:collapse;margin:1em 0}td,th{border-bottom:1px solid #ccc;padding:3px 8px;"
    "text-align:right;vertical-align:top}td:first-child,th:first-child,td:nth-child(2){text-align:left}"
    "code{font-size:85%;word-break:break-all}.note{color:#555}svg{max-width:100%;height:auto}"
    ".warn{background:#fff4d6;padding:4px 8px}</style>"
)

e = html.escape


def _table(columns, rows: list[dict]) -> str:
    head = "".join(f"<th>{e(h)}</th>" for _, h in columns)
    body = "".join("<tr>" + "".join(f"<td>{e(cell(r[k]))}</td>" for k, _ in columns) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _codes(texts) -> str:
    return ", ".join(f"<code>{e(t)}</code>" for t in texts)


def claim_text(report: dict) -> str:
    """The certificate named for what it is: a sampled bound over the box, not a proof."""
    b = report["budgets"]
    box = ", ".join(f"{k} ~ {json.dumps(v)}" for k, v in report.get("box", {}).items()) or "no box"
    return (
        f"Sampled bound over the box: P(fail) <= epsilon = {b['epsilon']:g} with confidence 1 - beta = "
        f"{1 - b['beta']:g}, from the certification draws of each case (independent draws of the box; "
        f"a statement about this distribution of plants, not a stability proof). The box: {box}."
    )


def composed_text(claim: dict) -> str:
    """The composed claim in words (report.html and the console), with both numbers."""
    if not claim["stated"]:
        return f"Not composed with the identified box: {claim['why']}."
    held = [
        f"{c} on {name}: {'certified' if v and v['holds'] else 'not certified'}"
        for name, laws in claim["cases"].items()
        for c, v in laws.items()
    ]
    return (
        f"With confidence >= {1 - claim['alpha']:g} the robot is in the identified box ({claim['box']}; "
        f"{claim['method']}), and with confidence {1 - claim['beta']:g} plants drawn from the box fail "
        f"with probability at most {claim['epsilon']:g} (the certificate); by the union bound both hold "
        f"together with confidence >= {claim['together']:g} (1 - alpha - beta), for each certified law. "
        "It bounds the share of the box's plants that fail, not the robot's own outcome: that is the "
        "worst case over the box (the falsification). " + "; ".join(held) + "."
    )


def _untuned(report: dict, c: str, entry: dict) -> str:
    """The settings cell of a controller the study did not tune."""
    if not entry["fixed"]:
        return "-"
    if report.get("tuned_from") and c.endswith(kept_name("")):
        return f"the kept setting of {report['tuned_from']} (tuned = ...)"
    return "its own settings (tune = false)"


def _kept_settings(report: dict, case: dict) -> list[str]:
    parts = [
        "<h3>Kept settings</h3><table><tr><th>controller</th><th>kept seed</th><th>setting</th>"
        "<th>seeds' validation medians [mm] (feasible on validation?)</th><th>on a bound</th>"
        "<th>search space (bounds, why physical, how the tuner widened them)</th>"
        "<th>not searched, and why</th></tr>"
    ]
    for c, entry in case["controllers"].items():
        tuned = entry["tuned"] or {}
        setting = ", ".join(f"{k} = {cell(v)}" for k, v in (tuned.get("settings") or {}).items())
        medians = ", ".join(
            f"seed {s['seed']}: {cell(None if s['median_error'] is None else 1e3 * s['median_error'])}"
            + ("" if s.get("feasible", True) else f" (infeasible: {s.get('why_infeasible', '')})")
            for s in tuned.get("seeds", [])
        )
        bound = (
            ", ".join(
                f"{b['param']} at its {b['side']} bound {cell(b['bound'])}"
                + (f" ({b['physical']})" if b.get("physical") else "")
                for b in tuned.get("at_bound") or []
            )
            or "-"
        )
        space = tuned.get("space") or {}
        searched = "; ".join(
            f"{k} [{cell(v['low'])}, {cell(v['high'])}] {v['unit']}"
            + "".join(f", {s} physical: {v[f'{s}_reason']}" for s in ("low", "high") if v.get(f"{s}_reason"))
            for k, v in space.items()
        )
        moved = "; ".join(
            f"seed {s}: {w['param']} {w['side']} {cell(w['old'])} -> {cell(w['bound'])} "
            f"(after setting {w['trial']})"
            for s, widened in (tuned.get("widened") or {}).items()
            for w in widened
        )
        held = "; ".join(fixed_text((tuned.get("fixed") or {}).items())) or "-"
        widened = "<br>widened: " + e(moved) if moved else ""
        parts.append(
            f"<tr><td>{e(c)}</td><td>{e(cell(tuned.get('kept_seed')))}</td>"
            f"<td>{e(setting or _untuned(report, c, entry))}</td><td>{e(medians or '-')}</td>"
            f"<td>{e(bound)}</td><td>{e(searched or '-')}{widened}</td><td>{e(held)}</td></tr>"
        )
    parts.append("</table>")
    return parts


def _failing(case: dict) -> list[str]:
    rows = []
    for c, entry in case["controllers"].items():
        failing = entry.get("failing") or {}
        for draw in failing.get("shown", []):
            values = ", ".join(f"{k} = {cell(v)}" for k, v in draw["values"].items()) or "(no box)"
            failed = ", ".join(f"{p} (margin {cell(m)})" for p, m in draw["failed"].items())
            status = draw["status"] + (f": {draw['message']}" if draw["status"] != "completed" else "")
            rows.append(
                f"<tr><td>{e(c)}</td><td>{draw['sample']}</td><td>{e(values)}</td><td>{e(failed)}</td>"
                f"<td>{e(status)}</td><td><code>{e(draw['command'])}</code></td></tr>"
            )
    tally = {c: entry.get("failing") or {} for c, entry in case["controllers"].items()}
    counts = "; ".join(f"{c}: {f.get('failing', 0)} of {f.get('draws', 0)}" for c, f in tally.items())
    out = [
        "<h3>Failing certification draws</h3>"
        f"<p class='note'>Draws that failed the requirement: {e(counts)}.</p>"
    ]
    if rows:
        out.append(
            "<table><tr><th>controller</th><th>sample</th><th>drawn values</th><th>failed (margin)</th>"
            "<th>status</th><th>replay</th></tr>" + "".join(rows) + "</table>"
        )
    return out


def write_html(report: dict, folder: Path, figures: dict[str, dict[str, str | None]]) -> Path:
    """report.html: one file, no network; ``figures``: case -> figure name -> inline SVG."""
    rows = table_rows(report)
    parts = [
        "<!DOCTYPE html><html><head><meta charset='utf-8'>",
        f"<title>{e(report['study'])}: nnrobust study</title>{STYLE}</head><body>",
        f"<h1>{e(report['study'])}</h1><p>{e(report['description'])}</p>",
        f"<p>{e(claim_text(report))}</p>",
        *(
            [f"<p><b>Composed with the identified box.</b> {e(composed_text(report['composed_claim']))}</p>"]
            if report.get("composed_claim")
            else []
        ),
        f"<p>Required (the falsification's properties): {_codes(report['require'])}; certified (the "
        f"whole requirement): {_codes(report.get('certified_properties', report['require']))}. "
        f"Budgets: {e(json.dumps(report['budgets']))}.</p>",
        *(f"<p class='warn'><b>Warning:</b> {e(w)}</p>" for w in report.get("warnings", [])),
        "<h2>Error and effort on the certification draws</h2>",
        _table(EFFORT_COLUMNS, rows),
        "<p class='note'>RMS task error after 2 s, RMS torque and chatter: median (and 95th percentile where "
        "N >= 59 draws support one) over the certification draws; saturated: the mean share of saturated "
        "steps; passed: the share of draws that met every certified property; P(fail): the one-sided "
        "Clopper-Pearson bound on the share of plants of the box that fail any of them.</p>",
        "<h2>Verdicts and provenance</h2>",
        _table(VERDICT_COLUMNS, rows),
    ]
    for name, case in report["cases"].items():
        shown = figures.get(name, {})
        parts.append(f"<h2>Case {e(name)}</h2><p class='note'>Validated on {e(case['validated_on'])}.</p>")
        for key, title in (
            ("cdf", "Error distribution on the certification draws"),
            ("tuning", "Tuning: best feasible setting against simulations, every seed"),
            ("learning", "Learning: validation error against simulated seconds of training, every seed"),
            ("falsification", "Falsification: worst plant found against simulations"),
            ("responses", "Time responses of the kept settings (median and worst certification draw)"),
        ):
            if shown.get(key):
                parts.append(f"<h3>{e(title)}</h3>{shown[key]}")
        stages = ", ".join(f"{k}: {v}" for k, v in case["stages"].items())
        parts.append(f"<p class='note'>Stages: {e(stages)}.</p>")
        for c, reason in case["not_kept"].items():
            parts.append(f"<p><b>{e(c)}: not kept.</b> {e(reason)}</p>")
        parts += _kept_settings(report, case)
        parts += _failing(case)
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
            from ..base.paired import format_pair

            parts.append("<h3>Paired comparisons (certification draws)</h3><ul>")
            parts += [f"<li>{e(format_pair(p))}</li>" for p in case["paired"]]
            parts.append(f"</ul><p class='note'>Method: {e(case['paired'][0]['method'])}.</p>")
        parts.append("<h3>Sampled bounds over the box, per property</h3><ul>")
        for c, entry in case["controllers"].items():
            for cert in entry["certificates"]:
                parts.append(
                    f"<li>{e(c)}: P(<code>{e(cert['property'])}</code> fails) &le; {cert['p_upper']:.4g} "
                    f"over the box, sampled (N = {cert['N']}, k = {cert['k']}), confidence "
                    f"{1 - cert['beta']:.4g}; {e(cert['method'])}</li>"
                )
        parts.append("</ul><h3>Worst plants found</h3><ul>")
        for c, entry in case["controllers"].items():
            if "worst" in entry:
                w = entry["worst"]
                verdict = "FALSIFIED" if w["falsified"] else "not falsified"
                status = (w.get("metrics") or {}).get("status", "completed")
                margin = (
                    cell(w["margin"])
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
                    f"<li>{e(c)}: p50 {cell(r['p50_us'])} us, p99 {cell(r['p99_us'])} us, max "
                    f"{cell(r['max_us'])} us over {r['steps']} steps: p99 is "
                    f"{cell(100 * r['p99_share'])} % of the {cell(r['period_us'])} us period; "
                    f"{cell(r['allocations_per_step'])} heap allocations per step</li>"
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
