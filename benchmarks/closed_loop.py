"""Simulated seconds per wall second of the full closed loop on the paper's case (b).

    python benchmarks/closed_loop.py --json out/bench/closed_loop.json [--duration 5]
"""

from __future__ import annotations

import argparse
import time

from nnrobust.experiment import build
from nnrobust.presets import load_preset
from nnrobust.results import write_json_atomic
from nnrobust.simulation import simulate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results as JSON to this file")
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per case")
    args = parser.parse_args()
    rows = []
    print(f"{'controller':10s} {'nominal model':14s} {'us / control step':>18s} {'sim s / wall s':>15s}")
    for kind in ("nn", "no-u0", "pd"):
        for nominal in ("closed-form", "urdf"):
            config = load_preset("paper-ellipse").replace(
                controller={"kind": kind}, nominal={"kind": nominal},
                simulation={"duration": args.duration})
            setup = build(config)
            start = time.perf_counter()
            simulate(setup.plant, setup.controller, setup.q0, setup.v0, args.duration)
            wall = time.perf_counter() - start
            steps = args.duration / config.simulation.control_period
            rows.append({"controller": kind, "nominal": nominal, "step_seconds": wall / steps,
                         "realtime_factor": args.duration / wall})
            print(f"{kind:10s} {nominal:14s} {wall / steps * 1e6:18.1f} {args.duration / wall:15.2f}")
    if args.json:
        write_json_atomic(args.json, {"preset": "paper-ellipse", "rows": rows})


if __name__ == "__main__":
    main()
