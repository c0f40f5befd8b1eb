"""A push, a hammer tap, a hand on the tool and a parcel picked up: the paper's arm under loads that
switch during the run, and a disturbance of your own, with and without them.

The loads are ``[[plant.loads]]`` tables (docs/plant.md); the square wave below follows the
Disturbance contract of docs/extending.md, built as ``Class(robot, **params)`` and run in place of
the paper's tau_d. For each event the table gives the largest tracking error in the second after
it, in the run with the load and in the run without.

    python examples/disturbances.py [--duration S] [--controller KIND]
"""

import argparse
import math
from pathlib import Path

import numpy as np

import nnrobust


class SquareWave(nnrobust.Disturbance):
    """tau_d = amplitude * sign(sin(2 pi t / period)) on every joint [N m]: a bang-bang load."""

    def __init__(self, robot, amplitude=1.0, period=4.0):
        self.amplitude = amplitude * np.ones(robot.nq)
        self.period = period

    def __call__(self, t):
        """The torque on every joint at t [N m]."""
        return self.amplitude * np.sign(math.sin(2 * math.pi * t / self.period))


def events(duration: float) -> list[tuple[str, float, dict]]:
    """The loads, at fractions of the run (whole control periods)."""
    at = [round(duration * f, 3) for f in (0.25, 0.4, 0.55, 0.7)]
    return [
        ("push: 2 N m step on joint 2", at[0], {"kind": "step", "torque": [0.0, 2.0, 0.0], "duration": 1.0}),
        (
            "tap: 0.05 N m s on joint 1",
            at[1],
            {"kind": "impulse", "impulse": [0.05, 0.0, 0.0], "duration": 0.005},
        ),
        (
            "hand: 10 N on the tool, 1 s",
            at[2],
            {"kind": "wrench", "force": [0.0, -10.0, 0.0], "duration": 1.0},
        ),
        ("parcel: 0.5 kg picked up", at[3], {"kind": "payload", "mass": 0.5}),
    ]


def worst_after(result, starts: list[float]) -> list[float]:
    """The largest tracking error in the second after each start [mm]."""
    error = 1e3 * np.linalg.norm(result.e, axis=1)
    return [float(error[(result.t >= s) & (result.t < s + 1.0)].max()) for s in starts]


def main() -> None:
    """Parse the arguments and run the example."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0, help="simulated time [s]")
    parser.add_argument(
        "--controller", default="nn", help="a built-in law (nn, no-u0, sliding-mode, pd, ...)"
    )
    args = parser.parse_args()
    base = nnrobust.load_preset("paper-ellipse").replace(
        simulation={"duration": args.duration}, controller={"kind": args.controller}
    )
    happenings = events(args.duration)
    loads = [{**load, "time": time} for _, time, load in happenings]
    square = {
        "disturbance": "custom",
        "disturbance_class": f"{Path(__file__).resolve()}:SquareWave",
        "disturbance_params": {"amplitude": 1.0, "period": args.duration / 4},
    }
    starts = [time for _, time, _ in happenings]
    quiet = worst_after(nnrobust.run_experiment(base), [*starts, args.duration / 2])
    loaded = worst_after(nnrobust.run_experiment(base.replace(plant={"loads": loads})), starts)
    squared = worst_after(nnrobust.run_experiment(base.replace(plant=square)), [args.duration / 2])
    print(f"controller {args.controller}: largest tracking error in the second after each event [mm]")
    print(f"{'event':<32} {'time [s]':>8} {'without':>8} {'with':>8}")
    rows = [(name, time) for name, time, _ in happenings] + [
        ("square wave instead of tau_d", args.duration / 2)
    ]
    for (name, time), before, after in zip(rows, quiet, loaded + squared):
        print(f"{name:<32} {time:>8.2f} {before:>8.3f} {after:>8.3f}")


if __name__ == "__main__":
    main()
