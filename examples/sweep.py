"""A robustness sweep from Python: the paper's arm under a disturbance drawn from a range, with
the NN compensator, the no-u0 baseline and the TaskPD law of custom_controller.py, on a local
Dask cluster (127.0.0.1 only).

Every sample runs with every controller (common random numbers); the rows land in Parquet parts
under OUT/results, a run of the same sweep into the same folder computes only what is missing,
and summary.json holds each controller's median, 95th percentile and worst sample with the
command that reruns it.

    python examples/sweep.py [--samples N] [--duration S] [--workers N] [--out DIR]
"""

import argparse
from pathlib import Path

import nnrobust
from nnrobust.studies.sweep import parse_sweep
from nnrobust.studies.sweep.summary import summarize, write_summary


def main() -> None:
    """Parse the arguments and run the example."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=20)
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time per run [s]")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default="out/examples/sweep")
    args = parser.parse_args()
    here = Path(__file__).resolve().parent
    spec = parse_sweep(
        {
            "name": "disturbance-range",
            "base": "paper-ellipse",
            "controllers": [
                "nn",
                "no-u0",
                {
                    "name": "taskpd",
                    "class": f"{here / 'custom_controller.py'}:TaskPD",
                    "params": {"Kp": 400.0, "Kd": 40.0},
                },
            ],
            "samples": args.samples,
            "seed": 7,
            "set": {"simulation.duration": args.duration},
            "vary": {
                "plant.disturbance_scale": {"uniform": [0.0, 3.0]},
                "plant.friction_scale": {"uniform": [0.5, 1.5]},
            },
        }
    )

    def progress(done, total):
        print(f"\r{done}/{total} rows", end="", flush=True)

    nnrobust.run_sweep(spec, args.out, workers=args.workers, progress=progress)
    print()
    summary = summarize(spec, nnrobust.read_results(args.out))  # what `nnrobust sweep` prints and saves
    write_summary(args.out, summary)
    print(f"{'controller':<10} {'rows':>5} {'median [mm]':>12} {'p95 [mm]':>9} {'worst [mm]':>11}")
    for name, entry in summary["controllers"].items():
        error = entry["rms_error_after_2s"]
        print(
            f"{name:<10} {entry['rows']:>5} {1e3 * error['median']:>12.3f} {1e3 * error['p95']:>9.3f} "
            f"{1e3 * error['max']:>11.3f}"
        )
    print("rerun the worst taskpd sample:", summary["controllers"]["taskpd"]["worst"]["command"])


if __name__ == "__main__":
    main()
