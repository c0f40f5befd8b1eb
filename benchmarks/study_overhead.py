"""A study's cost beyond its simulations: the wall time of ``nnrobust study`` on 2 workers against
the time its simulations take, and the time a finished study takes to write its report again.

    python benchmarks/study_overhead.py --json out/bench/study_overhead.json [--cut] [--workers 2]

The study is examples/study.toml (``--cut``: with the budgets tests/test_study.py cuts it to, for
a quick look). It runs from scratch into a temporary folder; then:

- ``simulations``: the seconds of worker time the runs take. A sweep stage's rows carry their
  own time (``task_seconds``: build, run and metrics of one run); a tuning's trial runs and a
  falsification's simulations do not, and are counted at the median ``task_seconds`` of the same
  controller's runs on the certification draws (the same case, duration and settings' kind);
- ``overhead``: 1 - simulations / (workers x wall): the share of the study's wall time its
  workers did not spend simulating (scheduling, stage set-up, the cluster, writing the report,
  the realtime stage's exports, idle workers at a stage's end);
- ``report``: the wall time of the study run again in the same folder (every stage resumes to
  "nothing to do"; the report is written again).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

from nnrobust.results import write_json_atomic
from nnrobust.study import load_study, run_study

ROOT = Path(__file__).resolve().parent.parent
CUT = {"tune": 4, "seeds": 2, "train_samples": 1, "validation": 2, "epsilon": 0.5, "beta": 0.2,
       "falsify": 4, "margin": "false"}  # fmt: skip
"""tests/test_study.py's budgets."""


def study_file(folder: Path, cut: bool) -> Path:
    """examples/study.toml (cut down with ``cut``) in ``folder``, with the files it names."""
    text = (ROOT / "examples" / "study.toml").read_text()
    text = text.replace("custom_controller.py:TaskPD", f"{ROOT / 'examples' / 'custom_controller.py'}:TaskPD")
    text = text.replace('file = "policies/', f'file = "{ROOT / "examples" / "policies"}/')
    if cut:
        text = re.sub(r'"simulation.duration" = [0-9.]+', '"simulation.duration" = 2.5', text)
        for key, value in CUT.items():
            text = re.sub(rf"^{key} = .*$", f"{key} = {value}", text, flags=re.M)
    path = folder / "study.toml"
    path.write_text(text)
    return path


def _frames(folder: Path, kind: str) -> pd.DataFrame:
    parts = sorted(folder.glob(f"cases/*/{kind}/part-*.parquet"))
    return pd.concat([pd.read_parquet(p) for p in parts], ignore_index=True) if parts else pd.DataFrame()


def simulation_seconds(out: Path) -> dict:
    """Worker seconds of the study's simulations, by stage (see the module's docstring)."""
    sweeps = {
        stage: _frames(out, f"{stage}/results")
        for stage in ("validate", "certify", "certify-mujoco")
        if list(out.glob(f"cases/*/{stage}/results"))
    }
    certify = sweeps["certify"]
    per_run = certify.groupby("controller")["task_seconds"].median().to_dict()
    fallback = float(certify["task_seconds"].median())

    def base(label: str) -> str:  # a certification entry of a tuned law: 'nn-tuned'
        for name in (label, f"{label}-tuned"):
            if name in per_run:
                return name
        return ""

    out_seconds = {stage: float(frame["task_seconds"].sum()) for stage, frame in sweeps.items()}
    trials = _frames(out, "tune-seed*/trials")
    runs = 0.0
    for _, trial in trials.iterrows():
        count = len(json.loads(trial["row"]).get("runs", [])) or 1
        runs += count * per_run.get(base(str(trial["controller"])), fallback)
    out_seconds["tune"] = runs
    history = _frames(out, "falsify/history")
    out_seconds["falsify"] = float(
        sum(per_run.get(base(str(c)), fallback) for c in history["controller"]) if len(history) else 0.0
    )
    out_seconds["runs_without_their_own_time"] = int(
        sum(len(json.loads(r).get("runs", [])) or 1 for r in trials["row"]) + len(history)
    )
    return out_seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="write the result here")
    parser.add_argument("--cut", action="store_true", help="the suite's cut budgets (a quick look)")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        spec = load_study(study_file(folder, args.cut))
        start = time.perf_counter()
        marks: list = [(start, "checks, the cluster")]  # (time, what starts): each stage's wall time
        run_study(
            spec,
            folder / "out",
            workers=args.workers,
            say=lambda line: marks.append((time.perf_counter(), line)),
        )
        wall = time.perf_counter() - start
        marks.append((start + wall, "end"))
        stages = [(line, b[0] - a[0]) for (a, b), line in zip(zip(marks, marks[1:]), (m[1] for m in marks))]
        start = time.perf_counter()
        run_study(spec, folder / "out", workers=args.workers)
        again = time.perf_counter() - start
        seconds = simulation_seconds(folder / "out")
    simulated = sum(v for k, v in seconds.items() if k != "runs_without_their_own_time")
    result = {
        "study": "examples/study.toml" + (" (cut)" if args.cut else ""),
        "workers": args.workers,
        "wall_seconds": wall,
        "simulation_seconds": seconds,
        "overhead": 1.0 - simulated / (args.workers * wall),
        "rerun_seconds": again,
        "stage_wall_seconds": stages,
    }
    print(f"study {result['study']} on {args.workers} workers: {wall:.1f} s wall")
    for stage, value in seconds.items():
        if stage != "runs_without_their_own_time":
            print(f"  {stage:16s} {value:8.1f} worker s of simulation")
    print(
        f"  ({seconds['runs_without_their_own_time']} tuning and falsification runs counted at their "
        "law's median)"
    )
    print(f"overhead: {100 * result['overhead']:.1f} % of {args.workers} x {wall:.1f} s")
    for line, seconds_ in stages:
        print(f"  {seconds_:7.1f} s wall  {line}")
    print(f"run again (nothing to compute, the report written again): {again:.1f} s")
    if args.json:
        write_json_atomic(args.json, result)


if __name__ == "__main__":
    sys.exit(main())
