"""The fair comparison's figure: each case's Pareto fronts (RMS error against RMS torque) of every
controller, from the seed-0 tunings of the tuned studies (benchmarks/studies/tuned-*.toml), each
controller's best setting under the constraints starred.

    python benchmarks/studies/fronts.py out/tuned-paper out/tuned-panda --figure docs/img/tuned_comparison.png

Each argument is a finished study's folder (``nnrobust study ... --out DIR``); the cases and the
controllers are the studies' own.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from nnrobust.studies.tune.engine import error_torque_front


def seed_zero_tunings(folders: list[Path]) -> list[tuple[str, dict]]:
    """(case, tuning summary of optimiser seed 0) of every case of the studies, in their order."""
    out = []
    for folder in folders:
        report = json.loads((folder / "report.json").read_text())
        for case in report["cases"]:
            summary = folder / "cases" / case / "tune-seed0" / "summary.json"
            if not summary.is_file():
                raise SystemExit(f"{summary} is missing: run the study {folder} to its end first")
            out.append((case, json.loads(summary.read_text())))
    return out


def plot(tunings: list[tuple[str, dict]], path: str) -> None:
    """One panel per case: each controller's Pareto front, its best setting under the constraints
    starred, the torque limit dotted."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(n for _, summary in tunings for n in summary["controllers"]))
    colors = {name: f"C{i}" for i, name in enumerate(names)}
    rows = math.ceil(len(tunings) / 2)
    fig, axes = plt.subplots(rows, 2, figsize=(10, 3.7 * rows), squeeze=False)
    for ax, (case, summary) in zip(axes.flat, tunings):
        for name, entry in summary["controllers"].items():
            points = error_torque_front(entry["pareto"])
            if points:
                ax.plot(*zip(*points), "o-", ms=3, color=colors[name], label=name)
            if entry["best"]:
                best = entry["best"]["train"]
                ax.plot(best["rms_torque"], 1e3 * best["rms_error_after_2s"], "*", ms=12, color=colors[name],
                        markeredgecolor="k")  # fmt: skip
        ax.axvline(summary["constraints"]["max_rms_torque"], color="0.5", ls=":")
        ax.set_yscale("log")
        ax.set_title(case, fontsize=10)
        ax.set_xlabel("RMS torque [N m]")
        ax.set_ylabel("RMS error, t ≥ 2 s [mm]")
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes.flat[len(tunings) :]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=8)
    fig.suptitle(
        f"Pareto fronts at {tunings[0][1]['budget']} simulations per controller, optimiser seed 0 "
        "(★ best under the constraints; dotted: the torque limit)",
        fontsize=10,
    )
    fig.tight_layout()
    tmp = Path(path).with_name(f".{Path(path).name}.partial.png")
    fig.savefig(tmp, dpi=110)
    tmp.replace(path)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("studies", nargs="+", type=Path, help="the finished studies' folders")
    parser.add_argument("--figure", required=True, help="the PNG to write")
    args = parser.parse_args()
    plot(seed_zero_tunings(args.studies), args.figure)
    print(f"wrote {args.figure}")


if __name__ == "__main__":
    sys.exit(main())
