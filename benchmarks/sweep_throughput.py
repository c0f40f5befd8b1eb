"""Sweep throughput: samples per second of 20 s paper-ellipse runs with 1 and 2 workers, and the
share of wall time that is not simulation (scheduling, transfer, writing parts).

    python benchmarks/sweep_throughput.py --json out/bench/sweep_throughput.json [--samples 40]

Each worker count gets its own LocalCluster, started before the clock runs; the sweep varies the
disturbance scale, one controller (nn). Overhead = 1 - (sum of the rows' task time) / (workers x
wall time).
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

from nnrobust.results import write_json_atomic
from nnrobust.sweep import parse_sweep, read_results, run_sweep
from nnrobust.sweep.engine import LOOPBACK_HTTP


def measure(workers: int, samples: int) -> dict:
    from distributed import LocalCluster

    spec = parse_sweep(
        {
            "name": f"throughput-{workers}",
            "base": "paper-ellipse",
            "controllers": ["nn"],
            "samples": samples,
            "seed": 3,
            "vary": {"plant.disturbance_scale": {"uniform": [0.5, 2.0]}},
        }
    )
    folder = Path(tempfile.mkdtemp(prefix="nnrobust-sweep-"))
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=LOOPBACK_HTTP,
    )
    try:
        start = time.perf_counter()
        run_sweep(spec, folder / "out", scheduler=cluster.scheduler_address)
        wall = time.perf_counter() - start
        frame = read_results(folder / "out")
    finally:
        cluster.close()
        shutil.rmtree(folder, ignore_errors=True)
    busy = float(frame["task_seconds"].sum())
    return {
        "workers": workers,
        "samples": samples,
        "wall_seconds": wall,
        "samples_per_second": samples / wall,
        "task_seconds_mean": busy / samples,
        "overhead": 1.0 - busy / (workers * wall),
        "backend": sorted(set(frame["backend"])),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results as JSON to this file")
    parser.add_argument("--samples", type=int, default=40)
    args = parser.parse_args()
    rows = [measure(workers, args.samples) for workers in (1, 2)]
    print(f"{'workers':>7s} {'samples/s':>10s} {'s per sample':>13s} {'overhead':>9s} backend")
    for r in rows:
        print(
            f"{r['workers']:7d} {r['samples_per_second']:10.2f} {r['task_seconds_mean']:13.3f} "
            f"{100 * r['overhead']:8.1f}% {','.join(r['backend'])}"
        )
    speedup = rows[1]["samples_per_second"] / rows[0]["samples_per_second"]
    print(f"2 workers / 1 worker: {speedup:.2f}x")
    if args.json:
        write_json_atomic(args.json, {"rows": rows, "speedup_2_over_1": speedup})


if __name__ == "__main__":
    main()
