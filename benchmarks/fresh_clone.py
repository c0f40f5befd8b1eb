"""The README's set-up figures: a fresh clone of this repository's last commit, `make test` in it,
timed, optionally beside busy processes (CI shares its machine).

    python benchmarks/fresh_clone.py --json docs/data/fresh_clone.json [--busy 2]

Two phases, each a make target run in the clone: the environment (``make .venv/.installed-test``:
the venv, the build requirements, the C++ extension and the test extras), then ``make test``
itself (the browser check, ruff, mypy and the suite on one pytest-xdist process per core); the
suite's own seconds as pytest prints them. ``--busy N`` starts N processes that keep a core busy
each for the whole measurement. The clone is deleted afterwards.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from nnrobust.run.results import write_json_atomic

ROOT = Path(__file__).resolve().parent.parent


def _timed(command: list[str], cwd: Path) -> tuple[float, str]:
    """(seconds, output) of a command that must succeed."""
    start = time.perf_counter()
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        tail = (done.stdout + done.stderr)[-3000:]
        sys.exit(f"{' '.join(command)} failed ({done.returncode}):\n{tail}")
    return seconds, done.stdout + done.stderr


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="write the result here")
    parser.add_argument("--busy", type=int, default=0, help="processes keeping a core busy beside it")
    args = parser.parse_args()
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout
    busy = [subprocess.Popen([sys.executable, "-c", "while 1: pass"]) for _ in range(args.busy)]
    try:
        with tempfile.TemporaryDirectory() as tmp:
            clone = Path(tmp) / "clone"
            subprocess.run(["git", "clone", "--quiet", str(ROOT), str(clone)], check=True)
            environment, _ = _timed(["make", ".venv/.installed-test"], clone)
            test, output = _timed(["make", "test"], clone)
    finally:
        for process in busy:
            process.kill()
            process.wait()
    suite = re.search(r"(\d+) passed.* in ([\d.]+)s", output)
    if suite is None:
        sys.exit(f"no pytest summary in make test's output:\n{output[-3000:]}")
    result = {
        "commit": commit.strip(),
        "cores": os.cpu_count(),
        "busy_processes": args.busy,
        "environment_seconds": environment,
        "test_seconds": test,
        "suite_seconds": float(suite.group(2)),
        "passed": int(suite.group(1)),
        "total_seconds": environment + test,
    }
    print(json.dumps(result, indent=1))
    if args.json:
        write_json_atomic(args.json, result)


if __name__ == "__main__":
    main()
