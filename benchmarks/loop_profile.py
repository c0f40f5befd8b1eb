"""Where a compiled step goes: each part of the compiled loop's step (the law, the loop's
bookkeeping, the recorded kinematics, the plant's integration, the sensor), in microseconds and in
calls to the system allocator per step, for the NN law and Slotine–Li on the paper's arm and the
Panda.

    python benchmarks/loop_profile.py --json out/bench/loop_profile.json [--duration 5]

The loop times its own parts (``LoopSpec.profile``: a clock read between parts, about 20 ns
each); the allocations are counted by ``benchmarks/allocation_counter.cpp``, preloaded: the
script runs itself again with ``LD_PRELOAD`` set. Best of ``--repeats`` runs by total time; the
allocation counts are the same in every run. docs/compiled.md's breakdown table is this output.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

from nnrobust.config.presets import load_preset
from nnrobust.run import compiled
from nnrobust.run.experiment import build
from nnrobust.run.results import write_json_atomic

CASES = (
    ("paper-ellipse", "nn"),
    ("paper-ellipse", "slotine-li"),
    ("panda-ellipse", "nn"),
    ("panda-ellipse", "slotine-li"),
)
"""(preset, law) of each row: the laws issue 53's goal names, on both shipped arms."""


def profile_rows(duration: float, repeats: int) -> list[dict]:
    """One row per case and part: µs per step (best total of the repeats) and allocations per step."""
    rows = []
    for preset, law in CASES:
        setup = build(
            load_preset(preset).replace(controller={"kind": law}, simulation={"duration": duration})
        )
        best = None
        for _ in range(repeats):
            parts, _trace = compiled.profile_compiled(setup, duration)
            if best is None or sum(us for us, _ in parts.values()) < sum(us for us, _ in best.values()):
                best = parts
        for part, (us, calls) in best.items():
            rows.append(
                {"preset": preset, "law": law, "part": part, "us_per_step": us, "allocations_per_step": calls}
            )
    return rows


def print_table(rows: list[dict]) -> None:
    print(f"{'preset':14s} {'law':11s} {'part':12s} {'us / step':>10s} {'allocations / step':>19s}")
    for r in rows:
        calls = "-" if r["allocations_per_step"] is None else f"{r['allocations_per_step']:.1f}"
        print(f"{r['preset']:14s} {r['law']:11s} {r['part']:12s} {r['us_per_step']:10.2f} {calls:>19s}")
    for preset, law in CASES:
        mine = [r for r in rows if (r["preset"], r["law"]) == (preset, law)]
        total = sum(r["us_per_step"] for r in mine)
        calls = [r["allocations_per_step"] for r in mine]
        shown = "-" if None in calls else f"{sum(calls):.1f}"
        print(f"{preset:14s} {law:11s} {'step':12s} {total:10.2f} {shown:>19s}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the rows as JSON to this file")
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per run")
    parser.add_argument("--repeats", type=int, default=3, help="runs per case (the fastest is kept)")
    parser.add_argument("--counted", action="store_true", help=argparse.SUPPRESS)  # the preloaded child
    args = parser.parse_args()
    if not compiled.available():
        sys.exit(f"loop_profile: {compiled.unavailable_reason()}")
    counter = compiled.allocation_counter()
    if counter and not args.counted:  # run again with the counter preloaded
        env = {**os.environ, "LD_PRELOAD": counter}
        command = [
            sys.executable,
            __file__,
            "--counted",
            "--duration",
            str(args.duration),
            "--repeats",
            str(args.repeats),
        ]
        if args.json:
            command += ["--json", args.json]
        sys.exit(subprocess.run(command, env=env).returncode)
    if not counter:
        print("(no allocation counter: it is built on Linux only; allocations are not counted)")
    rows = profile_rows(args.duration, args.repeats)
    print_table(rows)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        write_json_atomic(Path(args.json), {"duration": args.duration, "repeats": args.repeats, "rows": rows})
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
