"""``nnrobust learn``: a learned policy trained on an experiment or a sweep's box, one per seed,
with its learning curve (docs/learning.md#ppo-and-sac).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..core.exceptions import ConfigError
from .common import Command, say_unless_quiet


def learn_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust learn``."""
    parser.add_argument(
        "experiment",
        metavar="EXPERIMENT|SWEEP.toml",
        help="a preset, an experiment file, or a sweep file (its [vary] box is the training's "
        "domain randomisation, its first controller the base law)",
    )
    parser.add_argument(
        "--algorithm", default="ppo", choices=("ppo", "sac"), help="the trainer (default ppo)"
    )
    parser.add_argument(
        "--budget",
        type=float,
        required=True,
        metavar="SECONDS",
        help="simulated seconds of training per seed (each environment step is one control period)",
    )
    parser.add_argument("--seeds", type=int, default=1, metavar="K", help="train seeds 0 .. K-1 (default 1)")
    parser.add_argument(
        "--out", required=True, help="folder to write (seed-K/policy.onnx and its record, curves)"
    )
    parser.add_argument(
        "--action",
        default="residual",
        choices=("residual", "torque", "gains"),
        help="what the policy commands (default residual: added to the base law's torque)",
    )
    parser.add_argument("--controller", help="the base law's kind (default: the experiment's)")
    parser.add_argument(
        "--tuned",
        metavar="DIR|REPORT.json#CASE",
        help="run the base law at its tuned setting: a tuning's folder or summary.json, or a study's "
        "report and case (a residual then learns on the best model-based law found; curves.png then "
        "marks each tuned law's own training, in simulated seconds, on its axis)",
    )
    parser.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="an episode's length [s] (default: the experiment's simulation.duration, the horizon "
        "it is scored on)",
    )
    parser.add_argument(
        "--num-envs", type=int, default=8, metavar="N", help="episodes stepped together (default 8)"
    )
    parser.add_argument(
        "--validation-episodes",
        type=int,
        default=8,
        metavar="N",
        help="fixed validation plants of the learning curve, drawn apart from training's (default 8)",
    )
    parser.add_argument(
        "--hyper",
        action="append",
        metavar="KEY=VALUE",
        help="one hyper-parameter of the algorithm over its default (TOML value), e.g. --hyper n_steps=64 "
        "--hyper 'net_arch=[32, 32]'; repeatable (docs/learning.md#ppo-and-sac lists them)",
    )
    parser.add_argument(
        "--eval-every",
        type=float,
        metavar="SECONDS",
        help="simulated seconds of training between the curve's points (default: a tenth of the budget)",
    )
    parser.add_argument("--quiet", action="store_true", help="print nothing but errors")


def cmd_learn(args) -> int:
    """Train one policy per seed and write their curves."""
    from ..config.toml_io import parse_override
    from ..studies.learning.rl import (
        experiment_sha256,
        hyper_settings,
        stored_training,
        train,
        tuned_budgets,
        write_curves,
    )

    for option, value, low in (("--seeds", args.seeds, 1), ("--num-envs", args.num_envs, 1),
                               ("--validation-episodes", args.validation_episodes, 1)):  # fmt: skip
        if value < low:
            raise ConfigError(option, f"must be at least {low}, got {value}")
    out = Path(args.out)
    hyper = dict(parse_override(item, "--hyper", "n_steps=64") for item in args.hyper or ())
    say = say_unless_quiet(args.quiet)
    records = []
    # what a seed's stored record must match to be kept (the same for every seed)
    wanted = {"algorithm": args.algorithm, "budget_seconds": args.budget, "action": args.action,
              "experiment_sha256": experiment_sha256(args.experiment), "tuned_file": args.tuned}  # fmt: skip
    wanted["hyper"] = hyper_settings(args.algorithm, hyper)  # every hyper-parameter the training runs with
    if args.controller:
        wanted["controller"] = args.controller
    if args.duration is not None:
        wanted["duration"] = args.duration
    for seed in range(args.seeds):
        folder = out / f"seed-{seed}"
        folder.mkdir(parents=True, exist_ok=True)
        stored = stored_training(folder / "policy.onnx", wanted)
        if stored is not None:
            say(f"seed {seed}: trained before ({folder / 'policy.onnx'}), kept")
            records.append(stored)
            continue
        records.append(
            train(
                args.experiment,
                folder / "policy.onnx",
                algorithm=args.algorithm,
                budget=args.budget,
                action=args.action,
                controller=args.controller,
                duration=args.duration,
                seed=seed,
                tuned=args.tuned,
                num_envs=args.num_envs,
                validation_episodes=args.validation_episodes,
                eval_every=args.eval_every,
                hyper=hyper or None,
                progress=say,
            )  # fmt: skip
        )
    write_curves(out, records, tuned_budgets(args.tuned))  # the tuned laws' training, marked
    if not args.quiet:
        print(f"{'seed':>4} {'simulated s':>12} {'wall s':>8} {'validation error [mm]':>22} {'at 0 s':>10}")
        for record in records:
            last, first = record["curve"][-1], record["curve"][0]
            error, start = (1e3 * p["median_rms_error_after_2s"] for p in (last, first))
            print(
                f"{record['seed']:>4} {record['simulated_seconds']:>12.4g} {record['wall_seconds']:>8.1f} "
                f"{error:>22.4g} {start:>10.4g}"
            )
        print(f"wrote {out / 'curves.csv'} and {out}/seed-*/policy.onnx ([controller] kind = 'policy')")
    return 0


LEARN = Command(
    "learn",
    help="train a learned policy (PPO or SAC, Stable-Baselines3) on an experiment, per seed",
    description="Train a policy with Stable-Baselines3's PPO or SAC on the experiment's vector "
    "environment (the compiled loop), for a budget of simulated seconds per seed, with its learning "
    "curve on validation plants the training never sees; write each seed's ONNX policy file and "
    "record, and the curves (docs/learning.md). Needs the rl extra: pip install 'nnrobust[rl]'.",
    arguments=learn_arguments,
    run=cmd_learn,
)
