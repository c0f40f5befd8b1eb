"""Cost of one closed-loop control step against the number of joints n (planar chains).

    python benchmarks/step_scaling.py --json out/bench/step_scaling.json [--plot FILE.png]

For n = 3, 7, 15, 30, 60, 120, 300 the generated planar chain tracks the planar7-ellipse task
(m = 2) with the full NN controller (joint-space basis, so the network grows with n), a perturbed
URDF nominal model and the manipulability and joint-centering subtasks (the manipulability
gradient in O(n), docs/equations.md). The plant has no friction, no disturbance
and no joint stops: on chains of 30 and more light links, per-joint Coulomb friction and
disturbance torques excite modes with M^-1 eigenvalues up to 1e6 and the run diverges within
0.25 s at any control period, and the stops of the light distal joints ring too fast for a 1 ms
RK4 step (docs/robots.md, docs/plant.md); their cost per step is one O(n) vector expression either
way. One control step is the controller's output (which advances the adaptive law once) plus one
RK4 step of the plant (four ABA calls). The exponent is the least-squares slope of log(step time)
against log(n) for n >= 15, for the Python loop and the compiled loop, timed in turn at each size.
The compiled loop is timed alone (run_loop); its set-up per run is not a step cost and is printed
apart: the loop's spec and the C++ copies of the plant and nominal models (csrc/model/model.cpp), whose
cost is mostly Pinocchio's Data constructor, steep in n (the Python loop builds the same Data).

The self-motion gain is k = 2 here, not the preset's 10: with k = 10 the 300-link chain's
self-motion diverges within 0.07 s at the 1 ms control period (n = 200 does not).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from nnrobust.config.presets import load_preset
from nnrobust.run import compiled
from nnrobust.run.experiment import build
from nnrobust.run.results import write_json_atomic
from nnrobust.run.simulation import simulate

SIZES = (3, 7, 15, 30, 60, 120, 300)


def step_seconds(n: int, steps: int, repeats: int, backend: str = "python") -> float:
    """Best of ``repeats`` runs of ``steps`` control steps on ``backend``, per step [s]."""
    seed = [0.9] + [-1.2 / (n - 1)] * (n - 1)
    config = load_preset("planar7-ellipse").replace(
        robot={"source": f"planar{n}"},
        nn={"basis_input": "joint"},
        plant={"friction": "urdf", "disturbance": "none", "joint_stops": False},  # module docstring
        subtasks={"criteria": ["manipulability", "joint_centering"], "weights": [0.5, 0.5]},
        controller={"k": 2.0},  # module docstring
        simulation={"q_seed": seed, "duration": steps * 1e-3, "memory_limit": 16.0},  # 300 joints: 5 GB
    )
    setup = build(config)
    best, set_up = np.inf, np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        if backend == "compiled":  # the loop alone (module docstring)
            spec = compiled.loop_spec(setup, steps * 1e-3)
            models = [compiled.load_model(m.model, m.task_frame) for m in (setup.robot, setup.nominal)]
            set_up = min(set_up, time.perf_counter() - start)
            start = time.perf_counter()
            trace = compiled._module().run_loop(models[0], spec, models[1])
        else:
            trace = simulate(setup.plant, setup.controller, setup.q0, setup.v0, steps * 1e-3)
        best = min(best, (time.perf_counter() - start) / steps)
        if trace.status != "completed":
            raise RuntimeError(f"n = {n}: the run {trace.status}: {trace.message}")
    return best, set_up


def growth_exponent(sizes, seconds, smallest: int = 15) -> float:
    """Slope of log(seconds) against log(n) over n >= smallest."""
    sizes, seconds = np.asarray(sizes, float), np.asarray(seconds, float)
    keep = sizes >= smallest
    return float(np.polyfit(np.log(sizes[keep]), np.log(seconds[keep]), 1)[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write {n, step_seconds, exponent} to this file")
    parser.add_argument("--plot", help="write a log-log plot to this PNG file")
    parser.add_argument("--steps", type=int, default=300, help="control steps per timing (1 ms each)")
    parser.add_argument("--repeats", type=int, default=3, help="timings per size; the best is kept")
    args = parser.parse_args()
    backends = ["python"] + (["compiled"] if compiled.available() else [])
    seconds: dict[str, list[float]] = {b: [] for b in backends}
    set_up: list[float] = []
    print(
        f"{'n':>5s} " + " ".join(f"{b + ' us/step':>18s}" for b in backends) + f" {'compiled set-up ms':>19s}"
    )
    for n in SIZES:
        for backend in backends:
            step, first = step_seconds(n, args.steps, args.repeats, backend)
            seconds[backend].append(step)
            if backend == "compiled":
                set_up.append(first)
        shown = f" {set_up[-1] * 1e3:19.2f}" if set_up else ""
        print(f"{n:5d} " + " ".join(f"{seconds[b][-1] * 1e6:18.1f}" for b in backends) + shown, flush=True)
    exponents = {b: growth_exponent(SIZES, seconds[b]) for b in backends}
    for backend, exponent in exponents.items():
        print(f"{backend}: fitted exponent for n = {SIZES[2]}..{SIZES[-1]}: {exponent:.3f} (1 = linear)")
    if args.json:
        write_json_atomic(
            args.json,
            {
                "n": list(SIZES),
                "step_seconds": seconds,
                "exponent": exponents,
                "compiled_set_up_seconds": set_up,
            },
        )
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 3.6))
        ref = np.array(SIZES, float)
        for backend in backends:
            ax.loglog(
                SIZES,
                np.array(seconds[backend]) * 1e6,
                "o-",
                label=f"{backend} loop (exponent {exponents[backend]:.2f})",
            )
            ax.loglog(ref, seconds[backend][2] * 1e6 * ref / SIZES[2], "k--", lw=0.8)
        ax.set_xlabel("joints n")
        ax.set_ylabel("closed-loop step [us]")
        ax.set_title("Cost per control step (dashed: slope 1)")
        ax.legend(fontsize=8)
        fig.savefig(args.plot, dpi=120, bbox_inches="tight")


if __name__ == "__main__":
    main()
