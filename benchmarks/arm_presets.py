"""Every controller on the real-arm presets (Panda, UR5, a 7-link planar chain), 10 s each.

    python benchmarks/arm_presets.py --json docs/data/arm_presets.json [--workers 2]

Each preset has a +-20 % inertial model error, unmodelled scaled friction, a scaled disturbance,
the URDF's effort limits and joint stops; every controller runs with the preset's gains.
"""

from __future__ import annotations

import argparse
import itertools

from common import run_rows

from nnrobust.results import write_json_atomic

PRESETS = ("panda-ellipse", "panda-pose", "ur5-ellipse", "planar7-ellipse")
CONTROLLERS = ("nn", "no-u0", "sliding-mode", "computed-torque", "pd")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the rows as JSON to this file")
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    args = parser.parse_args()
    print(f"{'preset':16s} {'controller':16s} {'rms e [mm]':>10s} {'rms rot [mrad]':>14s} {'rms tau':>8s} "
          f"{'chatter':>8s} {'sat %':>6s}")

    def echo(r):
        rot = r["rms_orientation_error_after_2s"]
        rot = "-" if rot is None else f"{1e3 * rot:.3g}"
        print(f"{r['preset']:16s} {r['controller']:16s} {1e3 * r['rms_error_after_2s']:10.3f} {rot:>14s} "
              f"{r['rms_torque']:8.2f} {r['torque_chatter']:8.2f} {100 * r['saturated_fraction']:6.2f}",
              flush=True)

    jobs = [{"preset": preset, "controller": kind, "changes": {"controller": {"kind": kind}}}
            for preset, kind in itertools.product(PRESETS, CONTROLLERS)]
    rows = run_rows(jobs, args.workers, echo)
    if args.json:
        write_json_atomic(args.json, {"rows": rows})


if __name__ == "__main__":
    main()
