"""How ``nnrobust identify`` scales with the log's length: synthetic Panda logs (7 joints, 1 kHz,
the faults of benchmarks/identify_calibration.py) of 15, 30 and 60 minutes, each identified by the
command in a process of its own, its wall time and peak memory (resident set) measured.

    python benchmarks/identify_hour.py --json docs/data/identify_hour.json [--minutes 15 30 60]

The logs are written as Parquet a minute at a time (the writer's memory does not grow with the
log). Issue 55 asks for a one-hour log in at most 60 s on 2 cores with memory flat in the log's
length; the table says how far the command is from both.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from nnrobust.model.loading import load_robot
from nnrobust.model.perturbation import perturb_inertias
from nnrobust.plant.friction import Friction
from nnrobust.run.results import write_json_atomic
from nnrobust.studies.identify.synthetic import FourierTrajectory, SensorFaults, synthetic_log

FAULTS = SensorFaults(torque_noise=0.05, torque_quantum=0.01, delay=0.002, jitter=1e-4, stale=0.02)
CHUNK = 60.0
"""Seconds of log written at a time."""


def write_log(path: Path, minutes: float, seed: int = 0) -> int:
    """A synthetic Panda log of ``minutes`` as Parquet, a chunk at a time; returns its samples."""
    import pyarrow as pa
    from pyarrow import parquet

    model = load_robot("panda", task="position").model
    rng = np.random.default_rng(seed)
    true = perturb_inertias(model, relative_error=0.2, com_error=0.01, seed=seed)
    friction = Friction(rng.uniform(0.02, 0.2, model.nv), rng.uniform(0.1, 0.6, model.nv))
    trajectory = FourierTrajectory.random(model, seed=seed, speed=1.5)  # periodic: 10 s
    joints = list(model.names[1:])
    writer, samples = None, 0
    for k in range(int(round(minutes * 60 / CHUNK))):
        log = synthetic_log(true, trajectory, CHUNK, friction=friction, faults=FAULTS, seed=seed + k)
        columns = {"time": log.t + k * CHUNK}
        for signal, values in (("q", log.q), ("dq", log.dq), ("tau", log.tau)):
            columns.update({f"{signal}.{j}": values[:, i] for i, j in enumerate(joints)})
        table = pa.table(columns)
        writer = writer or parquet.ParquetWriter(path, table.schema)
        writer.write_table(table)
        samples += len(log.t)
    writer.close()
    return samples


def identify_measured(log: Path, out: Path) -> dict:
    """``nnrobust identify`` of ``log`` in a process of its own: wall seconds, peak resident MB."""
    code = (
        "import resource, sys\nfrom nnrobust.cli import main\n"
        f"rc = main(['identify', {str(log)!r}, '--robot', 'panda', '--out', {str(out)!r}, '--quiet'])\n"
        "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)\nsys.exit(rc)\n"
    )
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"identify failed: {done.stderr[-2000:]}")
    summary = json.loads((out / "identification.json").read_text())
    return {
        "seconds": seconds,
        "identify_seconds": summary["seconds"],
        "peak_mb": int(done.stdout.split()[-1]) / 1024,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, nargs="+", default=[15.0, 30.0, 60.0])
    parser.add_argument("--json", help="write the table here")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory(prefix="identify-hour-") as scratch:
        for minutes in args.minutes:
            log = Path(scratch) / f"log-{minutes:g}.parquet"
            started = time.perf_counter()
            samples = write_log(log, minutes)
            written = time.perf_counter() - started
            measured = identify_measured(log, Path(scratch) / f"out-{minutes:g}")
            rows.append({"minutes": minutes, "samples": samples, "log_mb": log.stat().st_size / 2**20,
                         "write_seconds": written, **measured})  # fmt: skip
            print(
                f"{minutes:5g} min  {samples:>9d} samples  identify {measured['seconds']:6.1f} s  "
                f"peak {measured['peak_mb']:7.0f} MB",
                flush=True,
            )
            os.remove(log)
    if args.json:
        write_json_atomic(
            Path(args.json),
            {"robot": "panda", "rows": rows, "cpus": os.cpu_count(), "machine": platform.machine()},
        )


if __name__ == "__main__":
    main()
