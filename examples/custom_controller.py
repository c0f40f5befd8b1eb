"""A controller of your own, run on the paper's arm beside the shipped NN law.

The class below follows the contract of docs/extending.md: built as ``Class(context, **params)``,
called at every control instant with the measured state. The experiment names it by this file's
path, so the same class runs from an experiment file, from ``nnrobust run --controller
custom_controller.py:TaskPD`` and in sweeps.

    python examples/custom_controller.py [--duration S] [--out DIR]
"""

import argparse
from pathlib import Path

import numpy as np

import nnrobust


class TaskPD(nnrobust.Controller):
    """Task-space PD through the nominal inverse dynamics, with null-space damping:
    a = J+ (x_d'' - J'q' - Kd e' - Kp e) - D (I - J+J) q',  tau = M-hat a + N-hat.
    """

    signal_names = ("effort",)
    search_space = {  # what `nnrobust tune` searches, log-uniformly (bounds it finds the best on are widened)
        "Kp": (10.0, 1e5, "1/s^2"),
        "Kd": (1.0, 1e3, "1/s"),
        "damping": (0.1, 100.0, "1/s"),
    }

    def __init__(self, context, Kp=400.0, Kd=40.0, damping=5.0):
        self.ctx, self.Kp, self.Kd, self.damping = context, Kp, Kd, damping

    def compute(self, t, q, v, z, period=0.0):
        """The torque at t from the measured q, q'."""
        ctx = self.ctx
        x, J, jdot_v = ctx.nominal.task_state(q, v)
        x_d, dx_d, ddx_d = ctx.trajectory(t)
        e, de = ctx.trajectory.error(x, x_d), J @ v - dx_d
        J_pinv = ctx.pseudo_inverse.matrix(J)
        a = J_pinv @ (ddx_d - jdot_v - self.Kd * de - self.Kp * e)
        a -= self.damping * (np.eye(ctx.n) - J_pinv @ J) @ v
        tau = ctx.nominal.inverse_dynamics(q, v, a) + ctx.nominal_friction.torque(v)
        return nnrobust.ControlOutput(tau, {"effort": float(np.linalg.norm(tau))})


def main() -> None:
    """Parse the arguments and run the example."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="simulated time [s]")
    parser.add_argument("--out", default="out/examples", help="folder of the two run folders")
    args = parser.parse_args()
    base = nnrobust.load_preset("paper-ellipse").replace(simulation={"duration": args.duration})
    mine = base.replace(
        controller={
            "kind": "custom",
            "class": f"{Path(__file__).resolve()}:TaskPD",
            "params": {"Kp": 400.0, "Kd": 40.0},
        }
    )
    print(f"{'controller':<12} {'RMS error t>=2s [mm]':>21} {'RMS torque [N m]':>17}")
    for name, config in (("TaskPD", mine), ("nn", base)):
        result = nnrobust.run_experiment(config)
        metrics = result.metrics()
        print(f"{name:<12} {1e3 * metrics['rms_error_after_2s']:>21.3f} {metrics['rms_torque']:>17.3f}")
        nnrobust.write_run(Path(args.out) / f"paper-ellipse-{name}", result, overwrite=True, animation=False)


if __name__ == "__main__":
    main()
