"""The paper's NN compensator beside the field's classics, each at its defaults: task-space
Slotine–Li adaptive control and a function-approximating RBF network (the shipped laws
``slotine-li`` and ``rbf-nn``, docs/controller.md), with the sliding-mode term and no u_0 as
baselines, on the paper's arm and on the Panda.

Defaults are not a fair comparison (docs/fair-comparison.md tunes every law at one budget); they
are what a user gets before tuning.

    python examples/classics.py [--duration S] [--presets paper-ellipse,panda-ellipse]
"""

import argparse

import nnrobust

LAWS = ("nn", "sliding-mode", "no-u0", "slotine-li", "rbf-nn")


def main() -> None:
    """Parse the arguments and run the example."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time per run [s]")
    parser.add_argument("--presets", default="paper-ellipse,panda-ellipse")
    args = parser.parse_args()
    print(f"{'preset':15s} {'controller':13s} {'RMS error after 2 s':>20s} {'RMS torque':>11s}  loop")
    for preset in args.presets.split(","):
        for kind in LAWS:
            config = nnrobust.load_preset(preset).replace(
                controller={"kind": kind}, simulation={"duration": args.duration}
            )
            result = nnrobust.run_experiment(config)
            metrics = result.metrics()
            print(
                f"{preset:15s} {kind:13s} {1e3 * metrics['rms_error_after_2s']:17.3f} mm "
                f"{metrics['rms_torque']:7.2f} N m  {result.backend} ({result.status})"
            )


if __name__ == "__main__":
    main()
