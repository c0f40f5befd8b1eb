"""Sweep throughput: samples per second of 20 s paper-ellipse runs with 1 and 2 workers, and the
share of wall time that is not simulation (scheduling, transfer, writing parts).

    python benchmarks/sweep_throughput.py --json out/bench/sweep_throughput.json [--samples 40]

Each worker count gets its own LocalCluster (nnrobust.studies.base.cluster.local_cluster, the one `nnrobust
sweep` starts), started before the clock runs; the sweep varies the disturbance scale, one
controller (nn). Overhead = 1 - (sum of the rows' task time) / (workers x wall time). "Of loop
rate" is samples per second over workers x the compiled loop's own rate, the loop's time measured
on the same rows run one after another in this process first. The idle cluster's CPU is measured
with the local cluster's settings (nnrobust.studies.base.cluster.QUIET_CLUSTER) and with dask's defaults.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

from nnrobust.run.results import write_json_atomic
from nnrobust.studies.base.cluster import LOOPBACK_HTTP, local_cluster
from nnrobust.studies.sweep import parse_sweep, read_results, run_sweep


def sweep(workers: int, samples: int):
    """The measured sweep: ``samples`` draws of the disturbance scale, the NN on the paper's
    ellipse (20 s)."""
    return parse_sweep(
        {
            "name": f"throughput-{workers}",
            "base": "paper-ellipse",
            "controllers": ["nn"],
            "samples": samples,
            "seed": 3,
            "vary": {"plant.disturbance_scale": {"uniform": [0.5, 2.0]}},
        }
    )


def measure(workers: int, samples: int) -> dict:
    spec = sweep(workers, samples)
    folder = Path(tempfile.mkdtemp(prefix="nnrobust-sweep-"))
    cluster = local_cluster(workers)
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


def in_process(samples: int) -> dict:
    """The same rows run in this process, one after another: the time of a row and of its compiled
    loop alone (``wall_seconds``), the rate that workers x loop rate is measured against."""
    from nnrobust.studies.sweep.engine import plan, run_rows

    spec = sweep(1, samples)
    base_toml, jobs = plan(spec)
    run_rows(spec, base_toml, jobs[:2])  # imports and the per-process caches, as a worker's first row
    rows = run_rows(spec, base_toml, jobs)
    return {
        "samples": samples,
        "task_seconds_mean": sum(r["task_seconds"] for r in rows) / samples,
        "loop_seconds_mean": sum(r["wall_seconds"] for r in rows) / samples,
    }


def idle_cpu(quiet: bool, seconds: float = 10.0) -> float:
    """Share of one core an idle 2-worker cluster takes (this process, with the scheduler, and its
    workers): the local cluster's, or with dask's default settings."""
    import psutil
    from distributed import Client, LocalCluster

    if quiet:
        cluster = local_cluster(2)
    else:
        cluster = LocalCluster(
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=LOOPBACK_HTTP,
        )
    try:
        with Client(cluster):
            time.sleep(2.0)  # started
            processes = [psutil.Process(), *psutil.Process().children(recursive=True)]
            before = [sum(p.cpu_times()[:2]) for p in processes]
            time.sleep(seconds)
            after = [sum(p.cpu_times()[:2]) for p in processes]
    finally:
        cluster.close()
    return (sum(after) - sum(before)) / seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results as JSON to this file")
    parser.add_argument("--samples", type=int, default=40)
    args = parser.parse_args()
    plain = in_process(args.samples)
    rows = [measure(workers, args.samples) for workers in (1, 2)]
    print(
        f"in one process: {plain['task_seconds_mean']:.3f} s per sample, "
        f"of which the compiled loop {plain['loop_seconds_mean']:.3f} s"
    )
    header = ("workers", "samples/s", "s per sample", "overhead", "of loop rate")
    print("{:>7s} {:>10s} {:>13s} {:>9s} {:>13s} backend".format(*header))
    for r in rows:
        r["share_of_loop_rate"] = r["samples_per_second"] * plain["loop_seconds_mean"] / r["workers"]
        print(
            f"{r['workers']:7d} {r['samples_per_second']:10.2f} {r['task_seconds_mean']:13.3f} "
            f"{100 * r['overhead']:8.1f}% {100 * r['share_of_loop_rate']:12.1f}% {','.join(r['backend'])}"
        )
    # last: a cluster with dask's defaults puts MALLOC_TRIM_THRESHOLD_ into this process's environment
    idle = {"quiet_cluster": idle_cpu(True), "dask_defaults": idle_cpu(False)}
    print(
        f"idle 2-worker cluster: {100 * idle['quiet_cluster']:.1f} % of a core "
        f"({100 * idle['dask_defaults']:.1f} % with dask's default settings)"
    )
    speedup = rows[1]["samples_per_second"] / rows[0]["samples_per_second"]
    print(f"2 workers / 1 worker: {speedup:.2f}x")
    if args.json:
        write_json_atomic(
            args.json, {"idle_cpu": idle, "in_process": plain, "rows": rows, "speedup_2_over_1": speedup}
        )


if __name__ == "__main__":
    main()
