"""What the NN compensator's options do to error and torque on the paper's case (b).

    python benchmarks/nn_options.py --json docs/data/nn_options.json [--workers 2]

Runs the paper-ellipse preset (20 s, the URDF's effort limits) with the no-u0 baseline and with the
NN compensator under several settings, each one change from the defaults.
"""

from __future__ import annotations

import argparse

from common import run_rows

from nnrobust.results import write_json_atomic

VARIANTS = {
    "no-u0 baseline": {"controller": {"kind": "no-u0"}},
    "nn, defaults (sigma 0.05, eps = 1)": {},
    "nn, paper's law (sigma 0, eps -> 0)": {"nn": {"sigma": 0.0, "eps_min": 0.0}},
    "nn, printed eq. (15)": {"nn": {"law": "printed"}},
    "nn, eps floor 0.05": {"nn": {"eps_min": 0.05}},
    "nn, no leakage (sigma 0)": {"nn": {"sigma": 0.0}},
    "nn, sigma 0.5": {"nn": {"sigma": 0.5}},
    "nn, F = 1": {"nn": {"F": 1.0}},
    "nn, F = 20": {"nn": {"F": 20.0}},
    "nn, basis s = [e, e']": {"nn": {"basis_input": "error"}},
    "nn, constant unit only": {"nn": {"centers": 1, "width": 1e-6}},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the table as JSON to this file")
    parser.add_argument("--preset", default="paper-ellipse")
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    args = parser.parse_args()
    header = (f"{'variant':36s} {'rms e t>=2s [mm]':>17s} {'max e [mm]':>11s} "
              f"{'rms tau [N m]':>14s} {'chatter [N m]':>14s} {'sat %':>6s} {'rho-hat end':>12s}")
    print(header)
    print("-" * len(header))

    def echo(r):
        rho = "-" if r["final_rho_hat"] is None else f"{r['final_rho_hat']:.3g}"
        print(f"{r['variant']:36s} {r['rms_error_after_2s'] * 1e3:17.3f} {r['max_error'] * 1e3:11.2f} "
              f"{r['rms_torque']:14.2f} {r['torque_chatter']:14.2f} {100 * r['saturated_fraction']:6.2f} "
              f"{rho:>12s}", flush=True)

    jobs = [{"variant": name, "preset": args.preset, "changes": changes}
            for name, changes in VARIANTS.items()]
    rows = run_rows(jobs, args.workers, echo)
    if args.json:
        write_json_atomic(args.json, {"preset": args.preset, "rows": rows})


if __name__ == "__main__":
    main()
