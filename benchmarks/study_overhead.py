"""A study's cost beyond its simulations: the wall time of ``nnrobust study`` on 2 workers against
the time its simulations take, and the time a finished study takes to write its report again.

    python benchmarks/study_overhead.py --json out/bench/study_overhead.json [--cut] [--workers 2]
        [--study benchmarks/studies/falsify-panda.toml]

The study is examples/study.toml without its PPO rows (``--cut``: with the budgets that
tests/studies/study/test_engine.py cuts it to, for a quick look), or ``--study FILE``, a study
file of the repository's. It runs from scratch into a
temporary folder; then:

- ``simulations``: the seconds of worker time the runs take, each run's own ``task_seconds``
  (build, run and metrics of one run, measured on its worker): a sweep stage's rows, a tuning's
  trial runs and a falsification's simulations all carry it (a run that ended its worker does
  not: ``runs_without_their_own_time`` counts them);
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

from nnrobust.run.results import write_json_atomic
from nnrobust.studies.study import load_study, run_study

ROOT = Path(__file__).resolve().parent.parent
CUT = {"tune": 4, "seeds": 2, "train_samples": 1, "validation": 2, "epsilon": 0.5, "beta": 0.2,
       "falsify": 4, "margin": "false"}  # fmt: skip
"""tests/studies/study/test_engine.py's budgets."""


def study_file(folder: Path, cut: bool) -> Path:
    """examples/study.toml (cut down with ``cut``) in ``folder``, with the files it names, without
    its PPO rows (an hour of training, which no run's ``task_seconds`` counts)."""
    text = (ROOT / "examples" / "study.toml").read_text()
    text = "".join(line for line in text.splitlines(keepends=True) if "train = {" not in line)
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
    """Worker seconds of the study's simulations, by stage: each run's own task_seconds."""
    out_seconds = {
        stage: float(_frames(out, f"{stage}/results")["task_seconds"].sum())
        for stage in ("validate", "certify", "certify-mujoco")
        if list(out.glob(f"cases/*/{stage}/results"))
    }
    trials = _frames(out, "tune-seed*/trials")
    runs = [run for row in trials["row"] for run in json.loads(row).get("runs", [])] if len(trials) else []
    history = _frames(out, "falsify/history")
    simulations = [json.loads(row) for row in history["row"]] if len(history) else []
    out_seconds["tune"] = float(sum(r.get("task_seconds", 0.0) for r in runs))
    out_seconds["falsify"] = float(sum(r.get("task_seconds", 0.0) for r in simulations))
    out_seconds["runs_without_their_own_time"] = sum("task_seconds" not in r for r in [*runs, *simulations])
    return out_seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="write the result here")
    parser.add_argument("--cut", action="store_true", help="the suite's cut budgets (a quick look)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--study", help="another study file (default: examples/study.toml)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        spec = load_study(args.study if args.study else study_file(folder, args.cut))
        start = time.perf_counter()
        marks: list = [(start, "checks, the cluster")]  # (time, what starts): the wall time to the next
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
    name = Path(args.study).resolve().relative_to(ROOT) if args.study else "examples/study.toml"
    result = {
        "study": str(name) + (" (cut)" if args.cut and not args.study else ""),
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
    print(f"  ({seconds['runs_without_their_own_time']} runs without their own time: each ended its worker)")
    print(f"overhead: {100 * result['overhead']:.1f} % of {args.workers} x {wall:.1f} s")
    for line, seconds_ in stages:
        print(f"  {seconds_:7.1f} s wall  {line}")
    print(f"run again (nothing to compute, the report written again): {again:.1f} s")
    if args.json:
        write_json_atomic(args.json, result)


if __name__ == "__main__":
    sys.exit(main())
