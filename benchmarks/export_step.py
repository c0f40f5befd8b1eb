"""The exported law's step (nnrobust export, docs/export.md) out of Python: its time per step
(p50, p99, max) and its heap allocations per step, on the paper's arm and on the Panda, idle and
with both cores loaded by other processes.

    python benchmarks/export_step.py --json docs/data/export_step.json [--seconds 5] [--repeats 5]

For each arm: a compiled run of the preset (``seconds`` of simulated time) is recorded as the law
sees it (nnrobust.outputs.export.recorded_steps), the preset's controller is exported, and the export's
bin/time_step (example/time_step.c, with allocation-counting wrappers around glibc's malloc
family; nnrobust.outputs.export.time_steps) steps the law through the recorded states ``repeats`` times,
timing each step with CLOCK_MONOTONIC. "loaded" runs the same with two busy-looping processes on
the machine; "rt" adds SCHED_FIFO priority 80 (chrt) where the machine allows it, else the row
says it was not allowed.
The allocation count covers the steps only (never create).
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from nnrobust.config.presets import load_preset
from nnrobust.outputs.export import export_law, recorded_steps, time_steps
from nnrobust.run.results import write_json_atomic

ARMS = ("paper-ellipse", "panda-ellipse")


def busy_loops(count: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while 1: pass"]) for _ in range(count)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="write the rows here")
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds recorded per arm")
    parser.add_argument("--repeats", type=int, default=5, help="passes through the recorded states")
    args = parser.parse_args()
    rows = []
    chrt = shutil.which("chrt")
    with tempfile.TemporaryDirectory() as tmp:
        for arm in ARMS:
            config = load_preset(arm).replace(simulation={"duration": args.seconds})
            inputs, _ = recorded_steps(config)
            folder = Path(tmp) / arm
            export_law(config, folder)
            for load in ("idle", "loaded"):
                busy = busy_loops(2) if load == "loaded" else []
                try:
                    for scheduling, prefix in (("normal", []), ("rt", [chrt, "-f", "80"] if chrt else None)):
                        row = time_steps(folder, inputs, args.repeats, prefix) if prefix is not None else None
                        if row is None and scheduling == "rt":
                            rows.append({"arm": arm, "load": load, "scheduling": "rt", "allowed": False})
                            continue
                        rows.append(
                            {"arm": arm, "load": load, "scheduling": scheduling, "allowed": True, **row}
                        )
                finally:
                    for process in busy:
                        process.kill()
                        process.wait()
    head = ("arm", "load", "sched", "p50 us", "p99 us", "max us", "allocs/step")
    print(f"{head[0]:15s} {head[1]:7s} {head[2]:7s} {head[3]:>8s} {head[4]:>8s} {head[5]:>8s} {head[6]:>12s}")
    for row in rows:
        if not row["allowed"]:
            print(
                f"{row['arm']:15s} {row['load']:7s} {row['scheduling']:7s} (real-time scheduling not allowed)"
            )
            continue
        print(
            f"{row['arm']:15s} {row['load']:7s} {row['scheduling']:7s} {row['p50_us']:8.2f} "
            f"{row['p99_us']:8.2f} {row['max_us']:8.1f} {row['allocations_per_step']:12.1f}"
        )
    if args.json:
        write_json_atomic(Path(args.json), {"seconds": args.seconds, "repeats": args.repeats, "rows": rows})


if __name__ == "__main__":
    main()
