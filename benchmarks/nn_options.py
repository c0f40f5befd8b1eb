"""What the NN compensator's options do to error and torque on the paper's case (b).

Runs the paper-ellipse preset (20 s) with the no-u0 baseline and with the NN compensator under
several settings, prints a table and writes JSON:

    python benchmarks/nn_options.py --json out/bench/nn_options.json
"""

from __future__ import annotations

import argparse

from nnrobust.experiment import run_experiment
from nnrobust.presets import load_preset
from nnrobust.results import write_json_atomic

VARIANTS = {
    "no-u0 baseline": {"controller": {"kind": "no-u0"}},
    "nn (paper law, default)": {},
    "nn printed eq. (15)": {"nn": {"law": "printed"}},
    "nn eps floor 0.05": {"nn": {"eps_min": 0.05}},
    "nn sigma-mod 0.05": {"nn": {"sigma": 0.05}},
    "nn floor 0.05 + sigma 0.05": {"nn": {"eps_min": 0.05, "sigma": 0.05}},
    "nn F = 1": {"nn": {"F": 1.0}},
    "nn F = 20": {"nn": {"F": 20.0}},
    "nn gamma = 0.2": {"nn": {"gamma": 0.2}},
    "nn basis s = [e, e']": {"nn": {"basis_input": "error"}},
    "nn bias unit only": {"nn": {"centers": 1, "width": 1e-6}},
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the table as JSON to this file")
    parser.add_argument("--preset", default="paper-ellipse")
    args = parser.parse_args()
    base = load_preset(args.preset)
    rows = []
    header = (f"{'variant':30s} {'rms e t>=2s [mm]':>17s} {'max e [mm]':>11s} "
              f"{'rms tau [N m]':>14s} {'chatter [N m]':>14s} {'rho-hat end':>12s}")
    print(header)
    print("-" * len(header))
    for name, changes in VARIANTS.items():
        m = run_experiment(base.replace(**changes)).metrics()
        row = {"variant": name, "changes": changes, **{k: m[k] for k in (
            "status", "rms_error_after_2s", "max_error", "rms_torque", "torque_chatter",
            "final_rho_hat")}}
        rows.append(row)
        rho = "-" if m["final_rho_hat"] is None else f"{m['final_rho_hat']:.3g}"
        print(f"{name:30s} {m['rms_error_after_2s'] * 1e3:17.3f} {m['max_error'] * 1e3:11.2f} "
              f"{m['rms_torque']:14.2f} {m['torque_chatter']:14.2f} {rho:>12s}", flush=True)
    if args.json:
        write_json_atomic(args.json, {"preset": args.preset, "rows": rows})


if __name__ == "__main__":
    main()
