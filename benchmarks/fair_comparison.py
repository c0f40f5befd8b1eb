"""Fair comparison: every controller tuned over a gain grid on both paper cases, with saturation,
with and without realistic sensing; the Pareto points of RMS error against RMS torque.

    python benchmarks/fair_comparison.py --json docs/data/fair_comparison.json \
        --figure docs/img/fair_comparison.png [--workers 2] [--duration 20]
    python benchmarks/fair_comparison.py --replot docs/data/fair_comparison.json --figure F.png

Every run has the URDF's effort limits and joint stops (the default plant). "noisy" adds the
sensing of the paper-ellipse-noisy preset (17-bit encoders with one count of noise, 0.01 rad/s on
the velocity, 1 ms delay). A run is on the Pareto front of its controller when no other setting
of the same controller has both a smaller RMS error (t >= 2 s) and a smaller RMS torque. 180 runs
of 20 s: about 10 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path

from _common import run_rows

from nnrobust.presets import load_preset
from nnrobust.results import write_json_atomic

CASES = {"case (a) line": "paper-line", "case (b) ellipse": "paper-ellipse"}
SENSING = {"ideal": {}, "noisy": load_preset("paper-ellipse-noisy").to_dict()["sensing"]}
GAINS = [(10.0, 4.0), (100.0, 20.0), (400.0, 40.0), (2500.0, 100.0), (10000.0, 200.0)]
"""(Kp, Kv) of the task-space law: the paper's, then stiffer (Kv^2 > Kp throughout)."""


def settings() -> list[tuple[str, str, dict]]:
    """(controller, setting label, configuration changes) of the grid."""
    out = []
    for kind in ("no-u0", "computed-torque"):
        for kp, kv in GAINS:
            out.append((kind, f"Kp={kp:g} Kv={kv:g}",
                        {"controller": {"kind": kind, "Kp": [kp], "Kv": [kv]}}))
    for (kp, kv), gain, boundary in itertools.product(GAINS, (10.0, 40.0), (0.5, 5.0)):
        out.append(("sliding-mode", f"Kp={kp:g} Kv={kv:g} K={gain:g} Phi={boundary:g}",
                    {"controller": {"kind": "sliding-mode", "Kp": [kp], "Kv": [kv],
                                    "sliding_gain": gain, "sliding_boundary": boundary}}))
    for (kp, kv), sigma in [(GAINS[0], 0.05)] + list(itertools.product(GAINS, (0.5, 5.0))):
        out.append(("nn", f"Kp={kp:g} Kv={kv:g} sigma={sigma:g}",
                    {"controller": {"kind": "nn", "Kp": [kp], "Kv": [kv]},
                     "nn": {"sigma": sigma}}))
    out.append(("nn", "paper's law (sigma=0 eps_min=0), Kp=10 Kv=4",
                {"controller": {"kind": "nn"}, "nn": {"sigma": 0.0, "eps_min": 0.0}}))
    for kp, kd in ((400.0, 40.0), (4000.0, 200.0), (20000.0, 400.0), (80000.0, 800.0)):
        out.append(("pd", f"Kp={kp:g} N/m Kd={kd:g} N s/m",
                    {"controller": {"kind": "pd", "pd_Kp": [kp], "pd_Kd": [kd]}}))
    return out


def jobs(duration: float) -> list[dict]:
    """One job per case, sensing and controller setting."""
    out = []
    for (case, preset), (sensing, table) in itertools.product(CASES.items(), SENSING.items()):
        for controller, label, changes in settings():
            changes = dict(changes, simulation={"duration": duration})
            if table:
                changes["sensing"] = table
            out.append({"case": case, "preset": preset, "sensing": sensing, "controller": controller,
                        "setting": label, "changes": changes})
    return out


def mark_pareto(rows: list[dict]) -> None:
    """Set row["pareto"]: not dominated in (RMS error, RMS torque) by a completed run of the same
    controller, case and sensing."""
    for row in rows:
        peers = [r for r in rows if (r["case"], r["sensing"], r["controller"]) ==
                 (row["case"], row["sensing"], row["controller"]) and r["status"] == "completed"]
        row["pareto"] = row["status"] == "completed" and not any(
            p["rms_error_after_2s"] <= row["rms_error_after_2s"] and p["rms_torque"] <= row["rms_torque"]
            and (p["rms_error_after_2s"], p["rms_torque"]) != (row["rms_error_after_2s"], row["rms_torque"])
            for p in peers)


def plot(rows: list[dict], path: str) -> None:
    """Error against torque, one panel per case and sensing, Pareto fronts as lines."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases, sensings = list(CASES), list(SENSING)
    fig, axes = plt.subplots(len(sensings), len(cases), figsize=(11, 8), sharex=True, sharey=True)
    colors = {"nn": "C3", "no-u0": "C0", "computed-torque": "C2", "sliding-mode": "C1", "pd": "C7"}
    for (i, sensing), (j, case) in itertools.product(enumerate(sensings), enumerate(cases)):
        ax = axes[i, j]
        for controller, color in colors.items():
            pts = [r for r in rows if (r["case"], r["sensing"], r["controller"], r["status"]) ==
                   (case, sensing, controller, "completed")]
            if not pts:
                continue
            ax.scatter([r["rms_torque"] for r in pts], [1e3 * r["rms_error_after_2s"] for r in pts],
                       s=14, color=color, alpha=0.5)
            front = sorted((r for r in pts if r["pareto"]), key=lambda r: r["rms_torque"])
            ax.plot([r["rms_torque"] for r in front], [1e3 * r["rms_error_after_2s"] for r in front],
                    "-o", color=color, ms=4, label=controller)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xticks([3, 5, 10, 20, 50])
        ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_title(f"{case}, {sensing} sensing", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        if i == len(sensings) - 1:
            ax.set_xlabel("RMS torque [N m]")
        if j == 0:
            ax.set_ylabel("RMS task error, t >= 2 s [mm]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Each controller tuned over a gain grid, with saturation at 60/40/20 N m "
                 "(benchmarks/fair_comparison.py)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write every row as JSON to this file")
    parser.add_argument("--figure", help="write the Pareto figure (PNG) to this file")
    parser.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    parser.add_argument("--duration", type=float, default=20.0, help="simulated seconds per run")
    parser.add_argument("--replot", metavar="JSON", help="only draw --figure from rows written before")
    args = parser.parse_args()
    if args.replot:
        plot(json.loads(Path(args.replot).read_text())["rows"], args.figure)
        return
    header = f"{'case':17s} {'sensing':7s} {'controller':16s} {'setting':46s} {'rms e [mm]':>10s} " \
             f"{'rms tau':>8s} {'chatter':>8s} {'sat %':>6s}"
    print(header)
    print("-" * len(header))

    def echo(r):
        print(f"{r['case']:17s} {r['sensing']:7s} {r['controller']:16s} {r['setting']:46s} "
              f"{1e3 * r['rms_error_after_2s']:10.3f} {r['rms_torque']:8.2f} {r['torque_chatter']:8.2f} "
              f"{100 * r['saturated_fraction']:6.2f}", flush=True)

    rows = run_rows(jobs(args.duration), args.workers, echo)
    mark_pareto(rows)
    if args.json:
        write_json_atomic(args.json, {"duration": args.duration, "rows": rows})
    if args.figure:
        plot(rows, args.figure)


if __name__ == "__main__":
    main()
