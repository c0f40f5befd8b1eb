"""Train a learned controller with CMA-ES on the vector environment and export it to ONNX
(docs/learning.md#training): the learned rows of examples/study.toml.

    python examples/train_policy.py                  # both policies, into examples/policies/
    python examples/train_policy.py --generations 2  # a quick look

Two policies on the paper's arm with real encoders (paper-ellipse-noisy), trained over the study's
box of disturbance and friction (its [vary]); the episodes are the box's draws with seed 1000,
a stream the study's stages do not use (they draw with seeds 0-19, 1000003 and 2000003):
- ``residual.onnx``: a residual on eq. (9) without u_0 (no-u0), bounded by 10 % of the effort
  limits: the learned counterpart of the paper's NN compensator;
- ``torque.onnx``: the whole command, a ⊙ τ_max, from the observation alone.
Each writes its training record beside it (``.onnx.json``: settings, budget in simulations,
returns per generation). The default budget is the one the study states.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from nnrobust.studies.learning.es import train

HERE = Path(__file__).resolve().parent
BOX = {
    "plant.disturbance_scale": {"uniform": [0.5, 2.0]},
    "plant.friction_scale": {"loguniform": [0.5, 2.0]},
}
POLICIES = {
    "residual": {"action": "residual", "controller": "no-u0", "residual_scale": 0.1},
    "torque": {"action": "torque", "controller": "no-u0"},
}


def main() -> None:
    """Train the policies named on the command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(HERE / "policies"), help="folder of the ONNX files")
    parser.add_argument("--only", choices=sorted(POLICIES), help="train one of the two")
    parser.add_argument("--generations", type=int, default=30)
    parser.add_argument("--population", type=int, default=12)
    parser.add_argument("--episodes", type=int, default=4, help="plants per candidate and generation")
    parser.add_argument("--duration", type=float, default=4.0, help="episode length [s] (the study's)")
    parser.add_argument("--threads", type=int, default=None)
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name, settings in POLICIES.items():
        if args.only and name != args.only:
            continue
        record = train(
            "paper-ellipse-noisy",
            out / f"{name}.onnx",
            vary=BOX,
            seed=1000,
            duration=args.duration,
            hidden=16,
            population=args.population,
            episodes=args.episodes,
            generations=args.generations,
            threads=args.threads,
            progress=lambda line, name=name: print(f"{name}: {line}", flush=True),
            **settings,
        )
        print(
            f"{name}: {record['simulations']} simulations of {record['duration']:g} s "
            f"({record['simulated_seconds']:g} simulated s) in {record['wall_seconds']:.0f} s -> "
            f"{out / (name + '.onnx')}"
        )


if __name__ == "__main__":
    main()
