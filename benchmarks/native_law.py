"""A user's law in C++ (docs/extending.md#a-law-in-c) against a shipped law of similar cost, both
on the compiled loop: examples/controllers/task_pd.cpp's TaskPD (a task-space PD through the
nominal inverse dynamics, with null-space damping) against the shipped task-space PD (``pd``),
and the same TaskPD in Python (examples/custom_controller.py, the hybrid loop).

    python benchmarks/native_law.py --json out/bench/native_law.json [--seconds 5] [--repeats 5]

For each arm (the paper's, the Panda): the three built once, then run ``repeats`` times each,
interleaved, ``seconds`` of simulated time per run; the median wall time per control step, and
the C++ law's over the shipped PD's (within one run of this script).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from nnrobust.config.presets import load_preset
from nnrobust.run.experiment import build, run_experiment
from nnrobust.run.results import write_json_atomic

ROOT = Path(__file__).resolve().parent.parent
ARMS = ("paper-ellipse", "panda-ellipse")
PARAMS = {"Kp": 100.0, "Kd": 20.0, "damping": 5.0}
CPP, PY = ROOT / "examples" / "controllers" / "task_pd.cpp", ROOT / "examples" / "custom_controller.py"
CONTENDERS = {
    "TaskPD in C++": {"kind": "custom", "class": f"{CPP}:TaskPD", "params": PARAMS},
    "shipped pd": {"kind": "pd"},
    "TaskPD in Python": {"kind": "custom", "class": f"{PY}:TaskPD", "params": PARAMS},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="write the rows here")
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    rows = []
    for arm in ARMS:
        configs = {
            name: load_preset(arm).replace(simulation={"duration": args.seconds}, controller=controller)
            for name, controller in CONTENDERS.items()
        }
        setups = {name: build(config) for name, config in configs.items()}  # compiles the C++ law once
        times: dict[str, list[float]] = {name: [] for name in configs}
        backends = {}
        for _ in range(args.repeats):
            for name, config in configs.items():
                setup = build(config)
                start = time.perf_counter()
                result = run_experiment(config, setup=setup)
                times[name].append((time.perf_counter() - start) / result.t.size)
                backends[name] = result.backend
        del setups
        cpp, pd = float(np.median(times["TaskPD in C++"])), float(np.median(times["shipped pd"]))
        for name in configs:
            rows.append(
                {
                    "arm": arm,
                    "law": name,
                    "backend": backends[name],
                    "us_per_step": float(np.median(times[name])) * 1e6,
                }
            )
        rows.append({"arm": arm, "law": "C++ / shipped pd", "ratio": cpp / pd})
    for row in rows:
        if "ratio" in row:
            print(f"{row['arm']:14s} {row['law']:18s} {row['ratio']:8.2f}")
        else:
            print(f"{row['arm']:14s} {row['law']:18s} {row['us_per_step']:8.2f} us/step ({row['backend']})")
    if args.json:
        write_json_atomic(Path(args.json), {"seconds": args.seconds, "repeats": args.repeats, "rows": rows})


if __name__ == "__main__":
    main()
