"""How fast identify builds its regressor rows: Pinocchio's computeJointTorqueRegressor called
once per sample from Python (nnrobust.model.regressor.torque_regressor) against one C++ call per
batch of samples (nnrobust.run.compiled.torque_regressor_of, csrc/model/regressor.hpp), on random
states of the Panda, the two interleaved and the best of the repeats kept.

    python benchmarks/identify_rows.py --json out/bench/identify_rows.json [--samples 20000]

A one-hour log at 1 kHz is 3.6 million samples: the table's µs per sample times that is the
rows' share of identifying it (fit.BATCH samples at a time, so their memory is one batch's).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from nnrobust.model.loading import load_robot
from nnrobust.model.regressor import torque_regressor
from nnrobust.run import compiled
from nnrobust.run.results import write_json_atomic
from nnrobust.studies.identify.fit import BATCH


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20000, help="states per timing (default 20000)")
    parser.add_argument("--repeats", type=int, default=3, help="timings per contender (best is kept)")
    parser.add_argument("--json", help="write the results here")
    args = parser.parse_args()
    model = load_robot("panda", task="position").model
    rng = np.random.default_rng(0)
    q, v, a = (rng.uniform(-1.5, 1.5, (args.samples, model.nv)) for _ in range(3))
    rows_of = compiled.torque_regressor_of(model)
    if rows_of is None:
        raise SystemExit(f"the compiled loop is not built: {compiled.unavailable_reason()}")
    contenders = {
        "Python, one pin call per sample": lambda s: torque_regressor(model, q[s], v[s], a[s]),
        "C++, one call per batch": lambda s: rows_of(q[s], v[s], a[s]),
    }
    best = dict.fromkeys(contenders, np.inf)
    for _ in range(args.repeats):
        for name, build in contenders.items():
            start = time.perf_counter()
            for first in range(0, args.samples, BATCH):
                build(slice(first, first + BATCH))
            best[name] = min(best[name], time.perf_counter() - start)
    rows = [{"contender": name, "us_per_sample": 1e6 * wall / args.samples} for name, wall in best.items()]
    print(f"{'contender':34s} {'us / sample':>12s} {'one hour at 1 kHz [s]':>22s}")
    for r in rows:
        print(f"{r['contender']:34s} {r['us_per_sample']:12.2f} {3.6e6 * r['us_per_sample'] * 1e-6:22.1f}")
    if args.json:
        stamp = {"date": time.strftime("%Y-%m-%d"), "samples": args.samples, "repeats": args.repeats}
        write_json_atomic(args.json, {**stamp, "robot": "panda", "rows": rows})


if __name__ == "__main__":
    main()
