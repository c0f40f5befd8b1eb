"""The NN's worst plant of the paper's falsification (docs/data/falsify_paper.json), run on the
compiled loop and on the Python loop: once the actuators saturate the run is chaotic, and the two
loops, whose rounding differs, end at different errors (docs/falsification.md quotes both).

    python benchmarks/worst_plant_loops.py --json docs/data/worst_plant_loops.json

The Python loop's run of that 25 s plant takes about a minute, which is why it is measured here
and not in the suite: tests/docs_numbers/test_falsification.py checks the page against this file, reruns the
compiled loop, and checks that the Python loop's error is past the requirement too.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

from _common import worst_config

from nnrobust.run.experiment import run_experiment
from nnrobust.run.results import write_json_atomic

ROOT = Path(__file__).resolve().parents[1]
FALSIFIED = ROOT / "docs" / "data" / "falsify_paper.json"
KEPT = ("rms_error_after_2s", "saturated_fraction", "max_joint_limit_violation", "status")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the runs' metrics here")
    args = parser.parse_args()
    (case,) = json.loads(FALSIFIED.read_text())["cases"].values()  # the study's one case
    command = case["controllers"]["nn"]["falsification"]["worst"]["command"]
    config = worst_config(command)
    out: dict = {"command": command, "machine": platform.machine(), "loops": {}}
    header = ("rms error t>=2s [mm]", "saturated [%]", "stop [rad]", "wall [s]")
    print(f"{'loop':10s} {header[0]:>22s} {header[1]:>14s} {header[2]:>11s} {header[3]:>9s}")
    for loop in ("compiled", "python"):
        start = time.perf_counter()
        metrics = run_experiment(config.replace(simulation={"backend": loop})).metrics()
        wall = time.perf_counter() - start
        out["loops"][loop] = {**{k: metrics[k] for k in KEPT}, "wall_seconds": wall}
        print(
            f"{loop:10s} {1e3 * metrics['rms_error_after_2s']:22.1f} "
            f"{100 * metrics['saturated_fraction']:14.1f} "
            f"{metrics['max_joint_limit_violation']:11.4f} {wall:9.1f}"
        )
    if args.json:
        write_json_atomic(Path(args.json), out)


if __name__ == "__main__":
    main()
