"""Peak memory and time of each compiler process that builds the compiled loop (csrc/ and below).

Each translation unit's own compile command, as CMake wrote it for Ninja in the build folder that
`make` uses, is run again under GNU time (``/usr/bin/time -v``), one after the other, into a
scratch object file; the table gives its maximum resident set size. The target (docs/compiled.md):
every unit under 1.5 GB, so that a 4 GB laptop builds the package.

    python benchmarks/compile_memory.py [--build build/cp311-cp311-linux_x86_64] [--json FILE] [UNIT ...]
"""

from __future__ import annotations

import argparse
import glob
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from nnrobust.run.results import write_json_atomic

ROOT = Path(__file__).resolve().parent.parent
TARGET_GB = 1.5


def _tool(name: str, *places: str) -> str:
    """A program the measurement needs, or a one-line exit naming it."""
    found = next((p for p in places if Path(p).is_file()), None) or shutil.which(name)
    if found is None:
        sys.exit(f"compile_memory: needs {name} ({' or '.join(places) or 'on PATH'}); install it")
    return found


def unit_commands(build: Path) -> dict[str, list[str]]:
    """Unit name -> its compile command (argv), from Ninja's record of the build."""
    ninja = _tool("ninja", str(Path(sys.executable).parent / "ninja"))
    listing = subprocess.run(
        [ninja, "-C", str(build), "-t", "commands"], capture_output=True, text=True, check=True
    ).stdout
    commands = {}
    for line in listing.splitlines():
        match = re.search(r"-c (\S+?/(csrc|benchmarks)/(\S+\.cpp))", line)
        if match:  # a unit of csrc/ by its path there (laws/rbf_nn.cpp), the benchmark's by its own
            unit = match.group(3) if match.group(2) == "csrc" else f"benchmarks/{match.group(3)}"
            commands[unit] = shlex.split(line)
    return commands


def measure(argv: list[str]) -> tuple[float, float]:
    """(peak resident memory [GB], wall time [s]) of one compile, into a scratch object."""
    with tempfile.TemporaryDirectory() as scratch:
        argv = list(argv)
        argv[argv.index("-o") + 1] = str(Path(scratch) / "unit.o")
        argv = [a for a in argv if a not in ("-MD", "-MMD")]
        start = time.perf_counter()
        done = subprocess.run(
            [_tool("GNU time", "/usr/bin/time"), "-v", *argv], capture_output=True, text=True
        )
        wall = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"compile failed:\n{done.stderr[-3000:]}")
    kb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr).group(1))
    return kb / 1024**2, wall


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    found = sorted(glob.glob(str(ROOT / "build" / "*" / "build.ninja")))
    p.add_argument(
        "--build", type=Path, default=Path(found[0]).parent if found else None, help="CMake build folder"
    )
    p.add_argument("--json", help="write the table to this file")
    p.add_argument("units", nargs="*", help="only these units (e.g. laws/slotine_li.cpp; default: all)")
    args = p.parse_args()
    if args.build is None or not (args.build / "build.ninja").is_file():
        sys.exit("no build folder with build.ninja: run `make test` (or pass --build)")
    commands = unit_commands(args.build)
    unknown = sorted(set(args.units) - set(commands))
    if unknown:
        sys.exit(f"compile_memory: no unit {unknown[0]}; units: {', '.join(sorted(commands))}")
    commands = {u: argv for u, argv in commands.items() if not args.units or u in args.units}
    # -MD/-MF/-MT take a following path: drop the dependency-file arguments pairwise
    rows = []
    print(f"{'unit':<30s} {'peak memory [GB]':>17s} {'time [s]':>9s}  under {TARGET_GB} GB")
    for unit, argv in sorted(commands.items()):
        cleaned, skip = [], False
        for a in argv:
            if skip:
                skip = False
                continue
            if a in ("-MF", "-MT"):
                skip = True
                continue
            cleaned.append(a)
        gb, wall = measure(cleaned)
        rows.append({"unit": unit, "peak_memory_gb": round(gb, 3), "seconds": round(wall, 1)})
        print(f"{unit:<30s} {gb:17.2f} {wall:9.1f}  {'yes' if gb < TARGET_GB else 'NO'}")
    if args.json:
        write_json_atomic(args.json, {"target_gb": TARGET_GB, "units": rows})


if __name__ == "__main__":
    main()
