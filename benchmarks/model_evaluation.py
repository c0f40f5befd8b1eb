"""Time per evaluation of M, N, J and J'q': Pinocchio vs the closed-form three-link model.

python benchmarks/model_evaluation.py --json out/bench/model_evaluation.json
"""

from __future__ import annotations

import argparse
import timeit

import numpy as np

from nnrobust import load_robot
from nnrobust.model import ThreeLinkParameters, ThreeLinkPlanarModel
from nnrobust.run.results import write_json_atomic


def time_call(fn, number: int = 20000) -> float:
    """Best of 5 repeats, seconds per call."""
    return min(timeit.repeat(fn, number=number, repeat=5)) / number


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results as JSON to this file")
    args = parser.parse_args()
    robot = load_robot("three_link_planar")
    closed = ThreeLinkPlanarModel(ThreeLinkParameters.from_pinocchio(robot.model, robot.task_frame))
    rng = np.random.default_rng(0)
    q, v, a = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3)
    ops = {
        "M(q)": lambda m: m.mass(q),
        "N(q, q') = V q' + G": lambda m: m.bias(q, v),
        "M a + N (inverse dynamics)": lambda m: m.inverse_dynamics(q, v, a),
        "forward dynamics": lambda m: m.forward_dynamics(q, v, a),
        "J(q)": lambda m: m.task_jacobian(q),
        "J'q'": lambda m: m.task_jdot_v(q, v),
        "(x, J, J'q') together": lambda m: m.task_state(q, v),
    }
    rows = []
    print(f"{'quantity':30s} {'Pinocchio [us]':>15s} {'closed form [us]':>17s} {'ratio':>7s}")
    for name, op in ops.items():
        tp = time_call(lambda: op(robot))
        tc = time_call(lambda: op(closed))
        rows.append({"quantity": name, "pinocchio_s": tp, "closed_form_s": tc})
        print(f"{name:30s} {tp * 1e6:15.2f} {tc * 1e6:17.2f} {tc / tp:7.2f}")
    if args.json:
        write_json_atomic(args.json, {"robot": "three_link_planar", "rows": rows})


if __name__ == "__main__":
    main()
