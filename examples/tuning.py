"""Tuning controllers at an equal budget from Python: the same optimiser (Optuna's TPE) gives each
controller the same number of simulations on the same samples, under the same constraints, then
checks each best setting on held-out samples (docs/tuning.md).

    python examples/tuning.py [--budget N] [--controllers pd,no-u0,FILE.py:CLASS] [--out DIR]

The default tunes the PD and no-u0 baselines and custom_controller.py's TaskPD, whose class
declares the space it is searched in (``search_space``).

A fair verdict needs a budget large enough that each best setting is interior to its search
space; the summary says, per controller, whether it hit a bound of the space.
"""

import argparse
from pathlib import Path

import nnrobust


def main() -> None:
    """Parse the arguments and run the example."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--budget", type=int, default=60, help="simulations per controller")
    here = Path(__file__).resolve().parent
    parser.add_argument(
        "--controllers",
        default=f"pd,no-u0,{here / 'custom_controller.py'}:TaskPD",
        help="shipped kinds and custom classes (file.py:Class, with a search_space)",
    )
    parser.add_argument("--target", default="paper-line", help="a preset, an experiment file or a sweep file")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default="out/examples/tuning")
    args = parser.parse_args()
    spec = nnrobust.TuneSpec(
        args.target,
        args.controllers.split(","),
        args.budget,
        train_samples=1,
        validation=2,
        max_rms_torque=10.0,
        max_saturated=0.01,
    )
    summary = nnrobust.run_tune(
        spec,
        args.out,
        workers=args.workers,
        progress=lambda done, total: print(f"\r{done}/{total} simulations", end=""),
    )
    print()
    for name, entry in summary["controllers"].items():
        best = entry["best"]
        if best is None:
            print(f"{name}: {entry['note']}")
            continue
        print(
            f"{name}: train {1e3 * best['train']['rms_error_after_2s']:.4f} mm at "
            f"{best['train']['rms_torque']:.2f} N m with {best['params']}"
        )
        if best["at_bound"]:
            print(f"  not yet a fair verdict: {best['at_bound']} at a bound of the search space")
    print(f"everything, with the Pareto fronts and the trials, is in {args.out}")


if __name__ == "__main__":
    main()
