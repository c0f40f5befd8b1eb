"""Write the tables of README.md and docs/ from the benchmark results in docs/data/.

    python benchmarks/docs_tables.py            # rewrite the tables in place
    python benchmarks/docs_tables.py --check    # exit 1 if a table differs from its data

Each table sits between ``<!-- table: NAME -->`` and ``<!-- /table -->`` in a Markdown file and
is rendered from docs/data/*.json, which the benchmark scripts write (each table says which
command made its data). tests/test_docs_numbers.py runs the check and re-runs one row of every
data file, so the numbers in the docs are those the current code produces.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "docs" / "data"
DOCUMENTS = ("README.md", "docs/controller.md", "docs/plant.md", "docs/fair-comparison.md",
             "docs/robots.md")
TABLE = re.compile(r"(<!-- table: (?P<name>[\w-]+) -->\n)(?P<body>.*?)(<!-- /table -->)", re.S)
TORQUE_BUDGET = 10.0
"""[N m] RMS torque within which the headline compares the controllers' best errors."""


def _data(name: str) -> dict:
    return json.loads((DATA / f"{name}.json").read_text())


def _mm(value: float) -> str:
    return f"{1e3 * value:.3g}" if value is not None else "–"


def _warn(row: dict) -> str:
    kinds = [w.split(":")[0] for w in row["warnings"]]
    return ", ".join(kinds) if kinds else "none"


def paper_reproduction() -> str:
    rows = _data("paper_reproduction")["rows"]
    lines = ["| case | controller | RMS error, t ≥ 2 s [mm] | RMS torque [N m] | chatter [N m] | "
             "saturated steps [%] | warnings |", "|---|---|---:|---:|---:|---:|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['variant']} | {_mm(r['rms_error_after_2s'])} | "
                     f"{r['rms_torque']:.3g} | {r['torque_chatter']:.3g} | "
                     f"{100 * r['saturated_fraction']:.1f} | {_warn(r)} |")
    return "\n".join(lines) + ("\n\nMade by `python benchmarks/paper_reproduction.py "
                               "--json docs/data/paper_reproduction.json`.\n")


def _best_within_budget(rows: list[dict]) -> dict[tuple, dict]:
    best: dict[tuple, dict] = {}
    for r in rows:
        over = r["rms_torque"] > TORQUE_BUDGET or r["saturated_fraction"] > 0.01
        if r["status"] != "completed" or over:
            continue
        key = (r["case"], r["sensing"], r["controller"])
        if key not in best or r["rms_error_after_2s"] < best[key]["rms_error_after_2s"]:
            best[key] = r
    return best


def fair_headline() -> str:
    rows = _data("fair_comparison")["rows"]
    best = _best_within_budget(rows)
    cases = list(dict.fromkeys(r["case"] for r in rows))
    sensings = list(dict.fromkeys(r["sensing"] for r in rows))
    controllers = list(dict.fromkeys(r["controller"] for r in rows))
    head = " | ".join(f"{c}, {s}" for c in cases for s in sensings)
    lines = [f"| controller | {head} |", "|---|" + "---:|" * (len(cases) * len(sensings))]
    for ctrl in controllers:
        cells = []
        for c in cases:
            for s in sensings:
                r = best.get((c, s, ctrl))
                cells.append("–" if r is None else
                             f"{_mm(r['rms_error_after_2s'])} mm ({r['rms_torque']:.2g} N m)")
        lines.append(f"| {ctrl} | " + " | ".join(cells) + " |")
    return ("\n".join(lines) + "\n\nBest RMS task error (t ≥ 2 s) of each controller over its gain grid "
            f"among the settings with RMS torque ≤ {TORQUE_BUDGET:g} N m and at most 1 % saturated steps "
            "(RMS torque in brackets); 20 s runs with the URDF's effort limits. Made by "
            "`python benchmarks/fair_comparison.py --json docs/data/fair_comparison.json "
            "--figure docs/img/fair_comparison.png`.\n")


def fair_pareto() -> str:
    rows = _data("fair_comparison")["rows"]
    lines = ["| case | sensing | controller | setting | RMS error [mm] | RMS torque [N m] | "
             "chatter [N m] | saturated [%] |", "|---|---|---|---|---:|---:|---:|---:|"]
    for r in rows:
        if r.get("pareto"):
            lines.append(f"| {r['case']} | {r['sensing']} | {r['controller']} | {r['setting']} | "
                         f"{_mm(r['rms_error_after_2s'])} | {r['rms_torque']:.3g} | "
                         f"{r['torque_chatter']:.3g} | {100 * r['saturated_fraction']:.1f} |")
    return "\n".join(lines) + "\n"


def nn_options() -> str:
    rows = _data("nn_options")["rows"]
    lines = ["| variant | RMS e, t ≥ 2 s [mm] | max e [mm] | RMS τ [N m] | chatter [N m] | "
             "saturated [%] | ρ̂ at 20 s |", "|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        rho = "–" if r["final_rho_hat"] is None else f"{r['final_rho_hat']:.3g}"
        lines.append(f"| {r['variant']} | {_mm(r['rms_error_after_2s'])} | {_mm(r['max_error'])} | "
                     f"{r['rms_torque']:.3g} | {r['torque_chatter']:.3g} | "
                     f"{100 * r['saturated_fraction']:.1f} | {rho} |")
    return "\n".join(lines) + ("\n\nMade by `python benchmarks/nn_options.py "
                               "--json docs/data/nn_options.json`.\n")


def subtask() -> str:
    rows = _data("subtask")["rows"]
    lines = ["| variant | h(0) | h(20 s) | RMS e, t ≥ 2 s [mm] | RMS τ [N m] |", "|---|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['variant']} | {r['h_start']:.4f} | {r['h_end']:.4f} | "
                     f"{_mm(r['rms_error_after_2s'])} | {r['rms_torque']:.3g} |")
    return "\n".join(lines) + "\n\nMade by `python benchmarks/subtask.py --json docs/data/subtask.json`.\n"


def arm_presets() -> str:
    rows = _data("arm_presets")["rows"]
    lines = ["| preset | controller | RMS e, t ≥ 2 s [mm] | RMS rotation error [mrad] | RMS τ [N m] | "
             "chatter [N m] | saturated [%] | warnings |", "|---|---|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        rot = r["rms_orientation_error_after_2s"]
        lines.append(f"| {r['preset']} | {r['controller']} | {_mm(r['rms_error_after_2s'])} | "
                     f"{'–' if rot is None else f'{1e3 * rot:.3g}'} | {r['rms_torque']:.3g} | "
                     f"{r['torque_chatter']:.3g} | {100 * r['saturated_fraction']:.1f} | {_warn(r)} |")
    return "\n".join(lines) + ("\n\nMade by `python benchmarks/arm_presets.py "
                               "--json docs/data/arm_presets.json`.\n")


RENDERERS = {"arm-presets": arm_presets, "paper-reproduction": paper_reproduction,
             "fair-headline": fair_headline, "fair-pareto": fair_pareto, "nn-options": nn_options,
             "subtask": subtask}


def render(text: str) -> str:
    """The document with every table re-rendered from its data."""
    def replace(match):
        name = match["name"]
        if name not in RENDERERS:
            raise SystemExit(f"unknown table {name!r}; known: {', '.join(RENDERERS)}")
        return match.group(1) + RENDERERS[name]() + match.group(4)

    return TABLE.sub(replace, text)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 when a table is out of date")
    args = parser.parse_args()
    stale = []
    for name in DOCUMENTS:
        path = ROOT / name
        text = path.read_text()
        new = render(text)
        if new != text:
            stale.append(name)
            if not args.check:
                path.write_text(new)
    if args.check and stale:
        print(f"out of date: {', '.join(stale)}; run python benchmarks/docs_tables.py", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
