"""The virtual robot at wall-clock rate (nnrobust serve, docs/serve.md) with an exported law's
driver in another process: deadline misses, round-trip latency and the robot's own lateness, and
the served run's tracking against the same experiment simulated.

    python benchmarks/serve_misses.py --json out/bench/serve_misses.json [--seconds 60]

For each arm (the paper's, the Panda; each preset's own controller, exported): ``seconds`` of the
experiment served at its 1 kHz control period, idle and with two busy-looping processes on the
machine, with normal scheduling and with the robot's thread and the driver under SCHED_FIFO
(``--rt`` and ``chrt -f 80``, where the machine allows it). ``tracking`` is the served run's
rms_error_after_2s over the simulated run's.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from nnrobust.config.presets import load_preset
from nnrobust.outputs.export import export_law
from nnrobust.outputs.serve import serve
from nnrobust.run.results import write_json_atomic

ARMS = ("paper-ellipse", "panda-ellipse")


def busy_loops(count: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while 1: pass"]) for _ in range(count)]


def run(config, law: Path, folder: Path, realtime: bool) -> dict:
    chrt = shutil.which("chrt")
    prefix = [chrt, "-f", "80"] if realtime and chrt else []
    drivers = []

    def ready(port: int) -> None:
        drivers.append(subprocess.Popen([*prefix, law / "bin" / "drive", str(port)]))

    record = serve(config, folder, plots=False, realtime=realtime, watchdog=10**6, on_ready=ready)
    for driver in drivers:
        driver.wait(timeout=600)
    return record


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="write the rows here")
    parser.add_argument("--seconds", type=float, default=60.0, help="served seconds per row")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for arm in ARMS:
            config = load_preset(arm).replace(simulation={"duration": args.seconds})
            law = Path(tmp) / f"{arm}-law"
            export_law(config, law)
            for load in ("idle", "loaded"):
                for realtime in (False, True):
                    busy = busy_loops(2) if load == "loaded" else []
                    try:
                        folder = Path(tmp) / f"{arm}-{load}-{realtime}"
                        record = run(config, law, folder, realtime)
                    finally:
                        for process in busy:
                            process.kill()
                            process.wait()
                    rows.append(
                        {
                            "arm": arm,
                            "load": load,
                            "scheduling": record["scheduling"],
                            "periods": record["periods"],
                            "misses": record["deadline_misses"],
                            "latency_us": record["round_trip_latency_us"],
                            "lateness_us": record["period_lateness_us"],
                            "rejected": record["rejected"],
                            "tracking": record["tracking_ratio"],
                            "served": record["served"],
                            "simulated": record["simulated"],
                        }
                    )
    print(f"{'arm':14s} {'load':7s} {'scheduling':14s} {'misses':>7s} {'rt p50':>8s} {'rt p99':>8s} "
          f"{'rt max':>8s} {'late p99':>9s} {'tracking':>9s}")  # fmt: skip
    for row in rows:
        latency, late = row["latency_us"], row["lateness_us"]
        print(
            f"{row['arm']:14s} {row['load']:7s} {row['scheduling'][:14]:14s} {row['misses']:7d} "
            f"{latency['p50'] or 0:8.0f} {latency['p99'] or 0:8.0f} {latency['max'] or 0:8.0f} "
            f"{late['p99'] or 0:9.0f} {row['tracking'] or float('nan'):9.4f}"
        )
    if args.json:
        write_json_atomic(Path(args.json), {"seconds": args.seconds, "rows": rows})


if __name__ == "__main__":
    main()
