"""The walkthrough of docs/identification.md ("From a log to a certified law"), run as its commands
are and summed up: the synthetic log's truth against the identified box, the study's certificates
over the box and its composed claim, and the export of the certified law.

    python benchmarks/identify_walkthrough.py --json docs/data/identify_walkthrough.json

It writes into out/walkthrough (``--out``), as the page's commands do, replacing what an earlier
walkthrough left there. tests/studies/identify/test_walkthrough.py runs the same commands with the
study's budgets cut.
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from nnrobust.cli import main as nnrobust
from nnrobust.model.region import read_region
from nnrobust.run.results import write_json_atomic

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the summary here")
    parser.add_argument("--workers", type=int, default=2, help="the study's local workers (default 2)")
    args = parser.parse_args()
    walk = ROOT / "out" / "walkthrough"
    shutil.rmtree(walk, ignore_errors=True)
    started = time.perf_counter()
    subprocess.run([sys.executable, str(ROOT / "examples" / "synthetic_log.py"), str(walk)], check=True)
    identified = walk / "identified"
    steps = [
        ["identify", str(walk / "log.csv"), "--robot", "three_link_planar", "--out", str(identified)],
        ["study", str(ROOT / "examples" / "identified_study.toml"), "--out", str(walk / "study"),
         "--workers", str(args.workers)],
        ["export", str(ROOT / "examples" / "identified.toml"), "--controller", "nn", "--tuned",
         f"{walk / 'study' / 'report.json'}#identified", "--out", str(walk / "law")],
    ]  # fmt: skip
    for argv in steps:
        if nnrobust([*argv, "--quiet"]) != 0:
            raise SystemExit(f"nnrobust {' '.join(argv)} failed")
    doubled = _doubled_budget(walk, args.workers)
    region = read_region(identified / "region.json")
    truth = json.loads((walk / "truth.json").read_text())
    phi = np.concatenate([truth["inertial"], truth["viscous"], truth["coulomb"]])
    truth_z = float(np.max(np.abs(region.coordinates(region.projection @ phi))))
    report = json.loads((walk / "study" / "report.json").read_text())
    laws = _laws(report, walk / "study")
    summary = {
        "coordinates": region.dimension,
        "half_width": region.half_width,
        "level": region.level,
        "truth_largest_coordinate": truth_z,
        "truth_in_box": truth_z <= region.half_width,
        "composed_claim": report["composed_claim"],
        "laws": laws,
        "doubled_budget": doubled,
        "exported": json.loads((walk / "law" / "export.json").read_text())["law"],
        "seconds": time.perf_counter() - started,
        "machine": platform.machine(),
    }
    print(f"the box: {region.dimension} coordinates, each within +-{region.half_width:.4g}")
    print(f"the truth's largest coordinate: {truth_z:.3f} (in the box: {summary['truth_in_box']})")
    for c, law in laws.items():
        print(
            f"{c:4s} {law['N'] - law['failed']} of {law['N']} certification draws pass, P(fail) <= "
            f"{law['p_upper']:.3g}, median error {law['median_error_mm']:.3g} mm: "
            f"{'certified' if law['certified'] else 'not certified'}"
        )
    print(f"composed: with confidence >= {report['composed_claim']['together']:g}")
    more = doubled["laws"]["nn"]
    verdict = "certified" if more["certified"] else "not certified"
    print(
        f"at twice the tuning budget ({doubled['tune']}): nn {more['N'] - more['failed']} of {more['N']} "
        f"pass ({verdict}; failed: {more['failed_properties']})"
    )
    if args.json:
        write_json_atomic(Path(args.json), summary)


def _laws(report: dict, study: Path) -> dict:
    """Per law of the study's report: its whole requirement's certificate, the properties its
    failing draws failed, its median error and its tuning's convergence."""
    laws = {}
    for c, entry in report["cases"]["identified"]["controllers"].items():
        whole = next(x for x in entry["certificates"] if x["property"].startswith("all of"))
        failed = sorted(
            {p for draw in entry.get("failing", {}).get("shown", []) for p in draw.get("failed", {})}
        )
        tuned = entry.get("tuned") or {}
        laws[c] = {
            "N": whole["N"],
            "failed": whole["k"],
            "p_upper": whole["p_upper"],
            "certified": whole["holds"],
            "failed_properties": failed,
            "median_error_mm": _median_error_mm(study, c),
            "convergence": tuned.get("convergence"),
        }
    return laws


def _doubled_budget(walk: Path, workers: int) -> dict:
    """The same study at twice its tuning budget (into walk/study-doubled): its laws' outcome."""
    import re

    text = (ROOT / "examples" / "identified_study.toml").read_text()
    tune = 2 * int(re.search(r"^tune = (\d+)", text, re.M).group(1))
    text = re.sub(r"^tune = \d+", f"tune = {tune}", text, flags=re.M)
    text = text.replace('"../out/walkthrough/', f'"{walk}/').replace(
        '"identified.toml"', f'"{ROOT / "examples" / "identified.toml"}"'
    )
    study = walk / "study-doubled.toml"
    study.write_text(text)
    out = walk / "study-doubled"
    if nnrobust(["study", str(study), "--out", str(out), "--workers", str(workers), "--quiet"]) != 0:
        raise SystemExit("the doubled study failed")
    return {"tune": tune, "laws": _laws(json.loads((out / "report.json").read_text()), out)}


def _median_error_mm(study: Path, controller: str) -> float:
    """The law's median RMS error after 2 s over the certification draws [mm]."""
    import pandas as pd

    rows = pd.read_parquet(study / "cases" / "identified" / "certify" / "results")
    mine = rows[rows["controller"].isin([controller, f"{controller}-tuned"])]
    return float(1000 * mine["rms_error_after_2s"].median())


if __name__ == "__main__":
    main()
