"""Reading results with pandas: a sweep's rows (Parquet) and a run folder's arrays and metrics.

Run examples/sweep.py first (or give --sweep any sweep folder); --run takes any run folder.

    python examples/read_results.py [--sweep DIR] [--run DIR]
"""

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd

import nnrobust


def main() -> None:
    """Parse the arguments and run the example."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweep", default="out/examples/sweep", help="a sweep folder")
    parser.add_argument("--run", help="a run folder (e.g. one written by examples/custom_robot.py)")
    args = parser.parse_args()

    try:
        rows = nnrobust.read_results(args.sweep)  # one row per (sample, controller): varied values, metrics
    except nnrobust.NNRobustError as err:  # no sweep there yet: run examples/sweep.py first
        raise SystemExit(f"{err} (run examples/sweep.py first, or give --sweep)") from None
    if not (rows.get("status") == "completed").any():
        raise SystemExit(f"{args.sweep}: the sweep has no completed row (run examples/sweep.py)")
    print(f"{len(rows)} rows, columns: {', '.join(rows.columns[:8])}, ...")
    rows["error_mm"] = 1e3 * rows["rms_error_after_2s"]
    table = rows.pivot_table(index="sample", columns="controller", values="error_mm")
    print("\nRMS error after 2 s [mm] by controller (quantiles over samples):")
    print(table.quantile([0.5, 0.95, 1.0]).round(3).to_string())
    if "nn" in table and len(table.columns) > 1:
        wins = (table.drop(columns="nn").min(axis=1) > table["nn"]).mean()
        print(f"\nthe NN compensator is best on {100 * wins:.0f} % of the samples")
    heavy = rows["plant.disturbance_scale"] > rows["plant.disturbance_scale"].median()
    print("\nmedian error [mm] with the disturbance below / above its median scale:")
    side = heavy.map({False: "below", True: "above"}).rename("disturbance")
    print(rows.groupby([side, "controller"])["error_mm"].median().unstack().round(3).to_string())

    if args.run:
        result = nnrobust.Result.load(args.run)  # every recorded array, as numpy
        metrics = json.loads((Path(args.run) / "metrics.json").read_text())
        frame = pd.DataFrame(
            {
                "t": result.t,
                "error_mm": 1e3 * result.position_error(),
                **{f"tau{i + 1}": result.tau[:, i] for i in range(result.tau.shape[1])},
            }
        )
        peak = frame["error_mm"].idxmax()
        print(
            f"\n{args.run}: {len(frame)} samples, status {metrics['status']}, "
            f"peak error {frame.loc[peak, 'error_mm']:.3f} mm at t = {frame.loc[peak, 't']:.3f} s"
        )
        print(frame.describe().loc[["mean", "max"]].round(3).to_string())
        assert np.isfinite(result.q).all()


if __name__ == "__main__":
    main()
