"""The compiled loop's speed goals, checked: `make bench-check` (not a unit test: timings are noisy,
so this is run by hand on a quiet machine, and fails loudly).

    python benchmarks/bench_check.py out/bench/closed_loop.json out/bench/loop_profile.json

Reads the JSON of benchmarks/closed_loop.py and benchmarks/loop_profile.py (made in the same
session) and checks, on each of the paper's arm and the Panda:

- the compiled loop's step, for the NN law and for Slotine–Li, at most GOAL_RATIO times the bare
  C++ floor's (benchmarks/floor_loop.cpp), the two measured interleaved in one process;
- a Python law's cost on the hybrid loop beyond its own compute (examples/custom_controller.py's
  TaskPD: `TaskPD, hybrid loop` minus `TaskPD, compute alone`) at most GOAL_HYBRID_US.

Then it compares the step's parts with the stored breakdown (docs/data/loop_profile.json, the
table of docs/compiled.md) and names each part that grew, in time or in allocations. Exit status
1 when a goal is missed.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

GOAL_RATIO = 1.6
"""Compiled loop / C++ floor, per step, at most (issue 53)."""

GOAL_HYBRID_US = 10.0
"""A Python law's hybrid-loop step minus its compute alone, at most [µs]."""

STORED = Path(__file__).resolve().parents[1] / "docs" / "data" / "loop_profile.json"
"""The breakdown the parts are compared with (benchmarks/loop_profile.py --json, committed)."""

GREW = 1.25
"""A part grew when its time is over this multiple of the stored one (and 0.2 µs more)."""

COMPILED_ROWS = {"nn": "nnrobust, compiled loop", "slotine-li": "slotine-li, compiled loop"}


def goals(loop: dict) -> list[tuple[str, float, float, bool]]:
    """(what, measured, goal, met) of each goal, from benchmarks/closed_loop.py's JSON."""
    us = {(r["preset"], r["contender"]): 1e6 * r["step_seconds"] for r in loop["rows"]}
    out = []
    for preset in sorted({p for p, _ in us}):
        floor = us.get((preset, "floor, C++"))
        for law, contender in COMPILED_ROWS.items():
            if floor and (preset, contender) in us:
                ratio = us[preset, contender] / floor
                out.append((f"{preset}: {law} compiled / C++ floor", ratio, GOAL_RATIO, ratio <= GOAL_RATIO))
        hybrid, alone = us.get((preset, "TaskPD, hybrid loop")), us.get((preset, "TaskPD, compute alone"))
        if hybrid is not None and alone is not None:
            extra = hybrid - alone
            out.append((f"{preset}: hybrid overhead [µs]", extra, GOAL_HYBRID_US, extra <= GOAL_HYBRID_US))
    return out


def grown_parts(profile: dict, stored: dict) -> list[str]:
    """The parts of a step that take longer or allocate more than in the stored breakdown."""
    then = {(r["preset"], r["law"], r["part"]): r for r in stored["rows"]}
    said = []
    for r in profile["rows"]:
        old = then.get((r["preset"], r["law"], r["part"]))
        if old is None:
            continue
        where = f"{r['preset']}, {r['law']}, {r['part']}"
        if r["us_per_step"] > GREW * old["us_per_step"] and r["us_per_step"] > old["us_per_step"] + 0.2:
            said.append(f"{where}: {old['us_per_step']:.2f} -> {r['us_per_step']:.2f} µs per step")
        calls, old_calls = r["allocations_per_step"], old["allocations_per_step"]
        if calls is not None and old_calls is not None and calls > old_calls:
            said.append(f"{where}: {old_calls:.1f} -> {calls:.1f} allocations per step")
    return said


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("closed_loop", help="benchmarks/closed_loop.py's JSON")
    parser.add_argument("loop_profile", help="benchmarks/loop_profile.py's JSON")
    parser.add_argument("--stored", default=str(STORED), help="the breakdown to compare with")
    args = parser.parse_args(argv)
    results = goals(json.loads(Path(args.closed_loop).read_text()))
    if not results:
        print(f"{args.closed_loop}: no compiled rows (is the compiled loop built?)")
        return 1
    for what, measured, goal, met in results:
        print(f"{'ok  ' if met else 'MISS'} {what}: {measured:.2f} (goal <= {goal:g})")
    stored = Path(args.stored)
    if stored.exists():
        grown = grown_parts(json.loads(Path(args.loop_profile).read_text()), json.loads(stored.read_text()))
        print(f"parts grown since {stored}:" if grown else f"no part grew since {stored}")
        for line in grown:
            print(f"  {line}")
    else:
        print(f"(no stored breakdown at {stored}: the parts are not compared)")
    missed = [r for r in results if not r[3]]
    print(f"{len(missed)} of {len(results)} goals missed" if missed else f"all {len(results)} goals met")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
