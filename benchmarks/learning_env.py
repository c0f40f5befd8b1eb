"""The learning environment's speed: env-steps per second of the vector environment against the
compiled loop's own steps per second (simulate_batch) on the same arm, and a single environment's
step overhead over the compiled plant step.

    python benchmarks/learning_env.py --json docs/data/learning_env.json [--envs 32] [--seconds 2]

For each arm (the paper's, the Panda), in one process, interleaved:
- ``batch``: simulate_batch of ``envs`` runs of ``seconds`` simulated time each, one C++ thread
  per core: the loop's steps per second (build excluded);
- ``vector``: ArmVectorEnv(num_envs=envs) stepped with a zero residual (the trivial policy: the
  base law's own command) for the same number of periods, episode ends and restarts included;
- ``single``: ArmEnv stepped likewise, one episode; its time per step minus the compiled loop's
  time per step (batch on one thread) is the environment's overhead per step;
- ``policy``: a zero residual ONNX policy on the preset's law as ``controller.kind = "policy"``
  (the hybrid path: the base law compiled, the inference in Python) against the base law's own
  compiled run: the policy's time per step beyond the base law's step and its own inference.
  Each is a marginal cost: the wall time of a run of 3 ``seconds`` less that of a run of
  ``seconds``, over the steps between them, so what a run costs once (building the loop, the
  network's first call) is not spread over its steps. ``glue`` is the same hybrid run with the
  network replaced by a Python function returning zeros: the loop's own cost of handing each
  step to Python. What remains (``interference``) is the base law's and the network's steps
  slowing each other when they alternate on one core (caches, branch predictors).
The base law is each preset's own. Ratios are within one run of this script: ``batch`` and
``vector`` alternate ``repeats`` times, and the ratio is the median of the pairs' ratios (the
machine's speed drifts by tens of percent between runs; the range is printed beside).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from nnrobust.config.presets import load_preset
from nnrobust.run.compiled import simulate_batch
from nnrobust.run.experiment import build
from nnrobust.run.results import write_json_atomic
from nnrobust.studies.learning.env import ArmEnv
from nnrobust.studies.learning.vector import ArmVectorEnv

ARMS = ("paper-ellipse", "panda-ellipse")


def batch_rate(preset: str, envs: int, seconds: float, threads: int) -> float:
    """Steps per second of simulate_batch over ``envs`` runs (builds excluded)."""
    setups = [build(load_preset(preset).replace(simulation={"duration": seconds})) for _ in range(envs)]
    start = time.perf_counter()
    traces = simulate_batch(setups, threads=threads)
    wall = time.perf_counter() - start
    return sum(t.t.size for t in traces) / wall


def vector_rate(preset: str, envs: int, seconds: float) -> float:
    """Env-steps per second of the vector environment under a zero residual."""
    vec = ArmVectorEnv(preset, envs, action="residual", duration=seconds, verdicts=False)
    vec.reset(seed=0)
    steps = int(round(seconds / vec.episodes.period))
    zeros = np.zeros((envs, vec.episodes.n), dtype=np.float32)
    start = time.perf_counter()
    for _ in range(steps):
        vec.step(zeros)
    wall = time.perf_counter() - start
    return envs * steps / wall


def single_step(preset: str, seconds: float) -> float:
    """Seconds per step of one environment under a zero residual."""
    env = ArmEnv(preset, action="residual", duration=seconds, verdicts=False)
    env.reset(seed=0)
    steps = int(round(seconds / env.episodes.period)) - 1
    zeros = np.zeros(env.episodes.n, dtype=np.float32)
    start = time.perf_counter()
    for _ in range(steps):
        env.step(zeros)
    return (time.perf_counter() - start) / steps


def policy_overhead(preset: str, seconds: float, folder: Path) -> dict:
    """(µs per step, marginal: runs of 3 ``seconds`` less runs of ``seconds``) of a zero residual
    policy's run beyond its base law's compiled run, less the inference time it recorded; and the
    inference's mean wall time."""
    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.learning import ObservationLayout

    base = load_preset(preset)
    setup = build(base)
    layout = ObservationLayout(setup.robot.nq, setup.robot.m)
    file = zero_policy(folder / f"{preset}.onnx", layout.size, layout.n)
    policy = {
        "kind": "policy",
        "params": {"file": str(file), "action": "residual", "base": base.controller.kind},
    }
    runs = {
        (law, duration): run_experiment(
            base.replace(simulation={"duration": duration}, controller=policy if law == "policy" else {})
        )
        for duration in (seconds, 3 * seconds)
        for law in ("base", "policy")
    }
    from nnrobust.controllers.laws import policy as module

    real = module.OnnxPolicy.on_buffer

    def no_network(self, obs):
        zeros = np.zeros(self.n)

        def call(t):
            self.seconds = 0.0
            return zeros

        return call

    module.OnnxPolicy.on_buffer = no_network  # type: ignore[method-assign]
    try:
        for duration in (seconds, 3 * seconds):
            runs[("glue", duration)] = run_experiment(
                base.replace(simulation={"duration": duration}, controller=policy)
            )
    finally:
        module.OnnxPolicy.on_buffer = real  # type: ignore[method-assign]

    def marginal(law: str) -> tuple[float, float]:
        short, long = runs[(law, seconds)], runs[(law, 3 * seconds)]
        steps = long.t.size - short.t.size
        inference = 0.0
        if law == "policy":
            inference = float(
                np.nansum(long.signals["inference_time"]) - np.nansum(short.signals["inference_time"])
            )
        return (long.wall_seconds - short.wall_seconds) / steps, inference / steps

    law_step, _ = marginal("base")
    policy_step, inference = marginal("policy")
    glue_step, _ = marginal("glue")
    return {
        "base_step_us": 1e6 * law_step,
        "policy_step_us": 1e6 * policy_step,
        "inference_us": 1e6 * inference,
        "overhead_us": 1e6 * (policy_step - law_step - inference),
        "glue_us": 1e6 * (glue_step - law_step),
        "interference_us": 1e6 * (policy_step - glue_step - inference),
    }


def zero_policy(path: Path, d: int, n: int) -> Path:
    """a = tanh(obs 0 + 0): the trivial policy, as an ONNX file."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    graph = helper.make_graph(
        [helper.make_node("MatMul", ["obs", "W"], ["h"]), helper.make_node("Tanh", ["h"], ["action"])],
        "zero",
        [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", d])],
        [helper.make_tensor_value_info("action", TensorProto.FLOAT, ["batch", n])],
        [numpy_helper.from_array(np.zeros((d, n), np.float32), "W")],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, str(path))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results as JSON to this file")
    parser.add_argument("--envs", type=int, default=32)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=5, help="batch/vector pairs, interleaved")
    args = parser.parse_args()
    rows = []
    for preset in ARMS:
        batch_rate(preset, 2, 0.2, args.threads)  # warm-up: imports, caches
        pairs = [
            (
                batch_rate(preset, args.envs, args.seconds, args.threads),
                vector_rate(preset, args.envs, args.seconds),
            )
            for _ in range(args.repeats)
        ]
        batch = float(np.median([b for b, _ in pairs]))
        vector = float(np.median([v for _, v in pairs]))
        ratios = sorted(v / b for b, v in pairs)
        loop_step = 1.0 / batch_rate(preset, 4, args.seconds, 1)
        single = single_step(preset, args.seconds)
        with tempfile.TemporaryDirectory() as folder:
            policy = policy_overhead(preset, args.seconds, Path(folder))
        rows.append(
            {
                "preset": preset,
                "envs": args.envs,
                "threads": args.threads,
                "batch_steps_per_second": batch,
                "vector_steps_per_second": vector,
                "vector_over_batch": float(np.median(ratios)),  # of the interleaved pairs
                "vector_over_batch_range": [ratios[0], ratios[-1]],
                "repeats": args.repeats,
                "loop_step_us": 1e6 * loop_step,
                "single_env_step_us": 1e6 * single,
                "single_env_overhead_us": 1e6 * (single - loop_step),
                "policy": policy,
            }
        )
    print(f"{'arm':15s} {'batch steps/s':>14s} {'vector steps/s':>15s} {'ratio':>6s} {'(range)':>11s} "
          f"{'loop µs':>8s} {'env µs':>8s} {'overhead µs':>12s}")  # fmt: skip
    for r in rows:
        low, high = r["vector_over_batch_range"]
        print(
            f"{r['preset']:15s} {r['batch_steps_per_second']:14.0f} {r['vector_steps_per_second']:15.0f} "
            f"{r['vector_over_batch']:6.2f} {f'({low:.2f}-{high:.2f})':>11s} {r['loop_step_us']:8.1f} "
            f"{r['single_env_step_us']:8.1f} {r['single_env_overhead_us']:12.1f}"
        )
    print(
        f"\n{'arm':15s} {'law µs':>8s} {'policy µs':>10s} {'inference µs':>13s} {'overhead µs':>12s} "
        f"{'glue µs':>8s} {'interference µs':>16s}"
    )
    for r in rows:
        p = r["policy"]
        print(
            f"{r['preset']:15s} {p['base_step_us']:8.1f} {p['policy_step_us']:10.1f} "
            f"{p['inference_us']:13.1f} {p['overhead_us']:12.1f} {p['glue_us']:8.1f} "
            f"{p['interference_us']:16.1f}"
        )
    if args.json:
        write_json_atomic(args.json, {"rows": rows})


if __name__ == "__main__":
    main()
