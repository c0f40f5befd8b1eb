"""Wall time of the whole command `nnrobust run PRESET` (imports, build, simulation, run folder with
figures and animation), as a user runs it, with the figures and animation drawn in forked
processes (the default) and in this process alone, and without them.

    python benchmarks/run_command.py --json out/bench/run_command.json [--preset panda-ellipse] [--repeat 5]

The contenders are interleaved, each repetition running each once, and each run is a fresh
process into a fresh folder; the table gives the median and the fastest run, and the ratios of
medians.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from nnrobust.core.forked import WORKERS_VARIABLE, default_workers
from nnrobust.run.results import write_json_atomic

CONTENDERS = {
    "forked drawing (default)": ([], {}),
    "drawing in one process": ([], {WORKERS_VARIABLE: "1"}),
    "--no-plots --no-animation": (["--no-plots", "--no-animation"], {}),
}


def _once(preset: str, flags: list[str], env: dict, folder: Path) -> float:
    command = [sys.executable, "-m", "nnrobust.cli", "run", preset, "--out", str(folder), "--quiet", *flags]
    start = time.perf_counter()
    subprocess.run(
        command, check=True, env={**os.environ, **env}, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="panda-ellipse")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json", help="write the results as JSON to this file")
    args = parser.parse_args()
    times: dict[str, list[float]] = {name: [] for name in CONTENDERS}
    work = Path(tempfile.mkdtemp(prefix="nnrobust-run-bench-"))
    try:
        _once(args.preset, [], {}, work / "warm-up")  # page cache, __pycache__
        for k in range(args.repeat):
            for i, (name, (flags, env)) in enumerate(CONTENDERS.items()):
                times[name].append(_once(args.preset, flags, env, work / f"run-{k}-{i}"))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    first = statistics.median(times[next(iter(CONTENDERS))])
    rows = [
        {
            "contender": name,
            "median_seconds": statistics.median(t),
            "fastest_seconds": min(t),
            "seconds": t,
            "ratio_to_default": statistics.median(t) / first,
        }
        for name, t in times.items()
    ]
    print(
        f"nnrobust run {args.preset}: wall time per command, {args.repeat} interleaved runs each "
        f"({default_workers()} drawing processes by default on this machine)"
    )
    print(f"{'contender':28s} {'median [s]':>10s} {'fastest [s]':>11s} {'/ default':>9s}")
    for r in rows:
        print(
            f"{r['contender']:28s} {r['median_seconds']:10.2f} {r['fastest_seconds']:11.2f} "
            f"{r['ratio_to_default']:9.2f}"
        )
    if args.json:
        write_json_atomic(
            args.json,
            {
                "preset": args.preset,
                "repeat": args.repeat,
                "drawing_processes": default_workers(),
                "rows": rows,
            },
        )


if __name__ == "__main__":
    main()
