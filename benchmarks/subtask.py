"""The null-space subtask under uncertainty: h of eq. (19) at the start and end of case (b).

    python benchmarks/subtask.py --json docs/data/subtask.json [--workers 2]

The NN compensator acts through J+ on the task error only (eq. 13 is the task-space error), so a
model error's null-space part disturbs the self-motion unopposed. The rows separate the causes
(model error, friction, disturbance) and show what the self-motion gain k does.
"""

from __future__ import annotations

import argparse

from common import run_rows

from nnrobust.results import write_json_atomic

NO_FRICTION = {"viscous_friction": [0.0] * 3, "coulomb_friction": [0.0] * 3}

VARIANTS = {
    "NN, the paper's uncertainty (defaults)": {},
    "NN, no disturbance": {"plant": {"disturbance": "none"}},
    "NN, true model, true viscous friction, no Coulomb, no disturbance":
        {"nominal": {"kind": "urdf", "viscous_friction": [4.3, 1.4, 0.4]},
         "plant": {"disturbance": "none", "coulomb_friction": [0.0] * 3}},
    "NN, true model, no friction, no disturbance":
        {"nominal": {"kind": "urdf", "viscous_friction": [0.0] * 3},
         "plant": {"disturbance": "none", **NO_FRICTION}},
    "computed-torque (true model and friction)": {"controller": {"kind": "computed-torque"}},
    "NN, k = 30": {"controller": {"k": 30.0}},
    "NN, k = 100": {"controller": {"k": 100.0}},
    "no-u0 baseline": {"controller": {"kind": "no-u0"}},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the rows as JSON to this file")
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    args = parser.parse_args()
    print(f"{'variant':66s} {'h(0)':>8s} {'h(20 s)':>8s} {'rms e [mm]':>10s} {'rms tau':>8s}")

    def echo(r):
        print(f"{r['variant']:66s} {r['h_start']:8.4f} {r['h_end']:8.4f} "
              f"{1e3 * r['rms_error_after_2s']:10.3f} {r['rms_torque']:8.2f}", flush=True)

    jobs = [{"variant": name, "preset": "paper-ellipse", "changes": changes}
            for name, changes in VARIANTS.items()]
    rows = run_rows(jobs, args.workers, echo)
    if args.json:
        write_json_atomic(args.json, {"rows": rows})


if __name__ == "__main__":
    main()
