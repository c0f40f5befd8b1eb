"""Closed-loop cost per control step: the library's Python and compiled loops and the two floors
they are measured against, a bare Python + Pinocchio loop and the same loop in C++; and a custom
Python controller (examples/custom_controller.py's TaskPD) on the Python and the hybrid loop, its
compute timed alone, its outputs' contract checks alone (both loops make them at every step), and
the hybrid loop replaying its commands: the loop's own cost; and the
library's loops with MuJoCo as the plant (plant.engine = "mujoco"; the compiled loop calls
MuJoCo's mj_step itself); and Slotine–Li (controller.kind = "slotine-li") on the compiled loop.
`make bench-check` compares the ratios with their goals (benchmarks/bench_check.py).

    python benchmarks/closed_loop.py --json out/bench/closed_loop.json [--duration 2]

Every contender runs in this one process, interleaved (best of 3 repeats each), so the ratios hold
even when the machine is noisy. A floor loop does per 1 ms step what any closed loop must: one RNEA
(the controller's M-hat a + N-hat), one frame-kinematics pass (x, J, J'q') and four ABA calls (RK4
of the plant with the torque held).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from nnrobust import Controller, ControlOutput
from nnrobust.config.presets import load_preset
from nnrobust.run import compiled
from nnrobust.run.experiment import build
from nnrobust.run.results import write_json_atomic
from nnrobust.run.simulation import simulate

PRESETS = ("paper-ellipse", "panda-ellipse")

CUSTOM = Path(__file__).resolve().parents[1] / "examples" / "custom_controller.py"
"""The light custom controller of the hybrid rows: examples/custom_controller.py's TaskPD."""


def cpp_floor_loop(loaded, q, v, steps, dt):
    """The floor loop of benchmarks/floor_loop.cpp (its own module, nnrobust._floor_loop, on a
    model that nnrobust._loop loaded); final [q, v].
    """
    from nnrobust import _floor_loop

    return _floor_loop.floor_loop(loaded, q, v, steps, dt)


def python_floor_loop(model, frame, q, v, steps, dt):
    """The floor loop of benchmarks/floor_loop.cpp with Pinocchio's Python bindings; final [q, v]."""
    data, fid, a = model.createData(), model.getFrameId(frame), np.zeros(model.nv)
    for _ in range(steps):
        pin.forwardKinematics(model, data, q, v, a)
        pin.updateFramePlacement(model, data, fid)
        pin.computeJointJacobians(model, data)
        J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
        jdot_v = pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED).linear
        a = -0.01 * (J[:3].T @ jdot_v) - v
        tau = pin.rnea(model, data, q, v, a).copy()

        def acc(qs, vs):
            return pin.aba(model, data, qs, vs, tau).copy()

        k1q, k1v = v, acc(q, v)
        k2q = v + 0.5 * dt * k1v
        k2v = acc(q + 0.5 * dt * k1q, k2q)
        k3q = v + 0.5 * dt * k2v
        k3v = acc(q + 0.5 * dt * k2q, k3q)
        k4q = v + dt * k3v
        k4v = acc(q + dt * k3q, k4q)
        q = q + (dt / 6) * (k1q + 2 * k2q + 2 * k3q + k4q)
        v = v + (dt / 6) * (k1v + 2 * k2v + 2 * k3v + k4v)
        a = np.zeros(model.nv)
    return np.concatenate([q, v])


def _contenders(preset: str, duration: float) -> dict:
    """name -> (callable running `duration` simulated seconds, control steps)."""
    config = load_preset(preset).replace(simulation={"duration": duration})
    setup = build(config)
    dt = config.simulation.control_period
    steps = int(round(duration / dt))
    robot = setup.robot
    out = {
        "nnrobust, Python loop": lambda: simulate(
            setup.plant, setup.controller, setup.q0, setup.v0, duration, dt
        ),
        "floor, Python + pin": lambda: python_floor_loop(
            robot.model, robot.task_frame, setup.q0, setup.v0, steps, dt
        ),
    }
    mujoco = _mujoco_setup(config)
    if compiled.available():
        if not compiled.twin_refusal(setup):
            out["nnrobust, compiled loop"] = lambda: compiled.simulate_compiled(setup, duration)
        slotine_li = build(config.replace(controller={"kind": "slotine-li"}))
        if not compiled.twin_refusal(slotine_li):
            out["slotine-li, compiled loop"] = lambda: compiled.simulate_compiled(slotine_li, duration)
        if mujoco is not None:
            out["nnrobust, compiled, MuJoCo"] = lambda: compiled.simulate_compiled(mujoco, duration)
        loaded = compiled.load_model(robot.model, robot.task_frame)
        out["floor, C++"] = lambda: cpp_floor_loop(loaded, setup.q0, setup.v0, steps, dt)
    if mujoco is not None:
        out["nnrobust, Python, MuJoCo"] = lambda: simulate(
            mujoco.plant, mujoco.controller, mujoco.q0, mujoco.v0, duration, dt
        )
    custom = build(config.replace(controller={"kind": "custom", "class": f"{CUSTOM}:TaskPD"}))
    out["TaskPD, Python loop"] = lambda: simulate(
        custom.plant, custom.controller, custom.q0, custom.v0, duration, dt
    )
    if compiled.available():
        out["TaskPD, hybrid loop"] = lambda: compiled.simulate_hybrid(custom, duration)
        trace = compiled.simulate_hybrid(custom, duration)  # the run its compute is timed on, and replayed
        out["TaskPD, compute alone"] = lambda: _compute_alone(custom.controller, trace, dt)
        out["TaskPD, output checks"] = lambda: _checks_alone(custom.controller, trace, dt)
        replayed = build(config.replace(controller={"kind": "custom", "class": f"{CUSTOM}:TaskPD"}))

        def hybrid_replayed():
            replayed.controller = Replay(trace)
            compiled.simulate_hybrid(replayed, duration)

        out["hybrid loop, law replayed"] = hybrid_replayed
    return out, steps


def _mujoco_setup(config):
    """The experiment with MuJoCo as the plant (plant.engine = "mujoco"), or None without MuJoCo."""
    try:
        import mujoco  # noqa: F401
    except ImportError:
        print("(no MuJoCo contender: pip install 'nnrobust[mujoco]')")
        return None
    return build(config.replace(plant={"engine": "mujoco"}))


def _compute_alone(controller, trace, period: float) -> None:
    """The controller's own time: its compute at every state of a run, with no loop around it."""
    for t, q, v in zip(trace.t, trace.q, trace.dq):
        controller.compute(t, q, v, np.zeros(0), period)


def _checks_alone(controller, trace, period: float) -> None:
    """What both loops add to a user's law at every step: its output checked against the contract
    (nnrobust.controllers.custom.checked_output), on the outputs of a run.
    """
    from nnrobust.controllers.custom import checked_output

    outputs = [
        controller.compute(t, q, v, np.zeros(0), period) for t, q, v in zip(trace.t, trace.q, trace.dq)
    ]
    start = time.perf_counter()
    for t, out in zip(trace.t, outputs):
        checked_output(controller, out, out.tau.size, 0, t)
    return time.perf_counter() - start


class Replay(Controller):
    """A law that costs nothing: the recorded commands of a run, handed back in order; the hybrid
    loop around it is the same run, so its time is the loop's own cost beyond the controller's.
    """

    signal_names = ("effort",)

    def __init__(self, trace):
        self.outputs, self.k = [ControlOutput(tau, {"effort": 0.0}) for tau in trace.tau_cmd], 0

    def compute(self, t, q, v, z, period=0.0):
        """The k-th recorded command."""
        self.k += 1
        return self.outputs[self.k - 1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results as JSON to this file")
    parser.add_argument("--duration", type=float, default=2.0, help="simulated seconds per timing")
    parser.add_argument("--repeats", type=int, default=3, help="timings per contender (best is kept)")
    args = parser.parse_args()
    if not compiled.available():
        print(f"(no C++ floor: {compiled.unavailable_reason()})")
    rows = []
    print(f"{'preset':14s} {'contender':24s} {'us / step':>10s} {'x real time':>12s} {'/ C++ floor':>12s}")
    for preset in PRESETS:
        contenders, steps = _contenders(preset, args.duration)
        best = {name: np.inf for name in contenders}
        for _ in range(args.repeats):  # interleaved: every contender once per round
            for name, run in contenders.items():
                start = time.perf_counter()
                timed = run()  # a float: the contender timed its own part
                wall = timed if isinstance(timed, float) else time.perf_counter() - start
                best[name] = min(best[name], wall)
        floor = best.get("floor, C++")
        for name, wall in best.items():
            step = wall / steps
            ratio = wall / floor if floor else None
            rows.append(
                {
                    "preset": preset,
                    "contender": name,
                    "step_seconds": step,
                    "realtime_factor": args.duration / wall,
                    "ratio_to_cpp_floor": ratio,
                }
            )
            print(
                f"{preset:14s} {name:24s} {step * 1e6:10.1f} {args.duration / wall:12.1f} "
                f"{'-' if ratio is None else f'{ratio:.1f}':>12s}",
                flush=True,
            )
    if args.json:
        stamp = {"date": time.strftime("%Y-%m-%d"), "duration": args.duration, "repeats": args.repeats}
        write_json_atomic(args.json, {**stamp, "rows": rows})


if __name__ == "__main__":
    main()
