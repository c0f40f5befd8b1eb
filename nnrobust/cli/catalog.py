"""What ships: presets, robots, bench."""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from pathlib import Path

from ..core.exceptions import NNRobustError
from .common import (
    Command,
    no_arguments,
)


def cmd_presets(args) -> int:
    """List the shipped presets."""
    from ..config.presets import load_preset, preset_names

    for name in preset_names():
        print(f"{name:28s} {load_preset(name).description}")
    return 0


def cmd_robots(args) -> int:
    """List the arms known to work (or, with --all, every example-robot-data robot): joint
    count, default chain and task frame.
    """
    from ..model import ARMS, load_robot
    from ..model.example_robots import example_robot, is_example_robot, robot_names

    names = robot_names() if args.all else list(ARMS)
    print(f"{'name':26s} {'n':>3s}  {'default chain':44s} {'task frame':28s} note")
    failed = 0
    for name in names:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the note column says what a warning would
            try:
                robot = load_robot(name)
            except NNRobustError as err:
                failed += 1
                print(f"{name:26s} {'-':>3s}  {'refused: ' + str(err)}")
                continue
        joints = robot.joint_names
        chain = joints[0] if len(joints) == 1 else f"{joints[0]} .. {joints[-1]}"
        note = ARMS.get(name, {}).get("description", "")
        if is_example_robot(name) and example_robot(name).floating_base:
            note = "floating base fixed to the world"
        print(f"{name:26s} {robot.nq:3d}  {chain:44s} {robot.task_frame:28s} {note}".rstrip())
    if args.all:
        print(f"\n{len(names) - failed} of {len(names)} load.")
    else:
        print(
            "\nAlso: planar<N> for N up to 300 (generated chain), any example-robot-data name "
            "(nnrobust robots --all), a URDF file."
        )
    return 1 if failed and not args.all else 0


def cmd_bench(args) -> int:
    """Run the benchmark scripts of benchmarks/ and write their JSON into a folder."""
    import subprocess

    root = Path(__file__).resolve().parents[2] / "benchmarks"
    if not root.is_dir():
        raise NNRobustError(f"{root} not found: 'bench' runs from a source checkout of nnrobust")
    available = sorted(p.stem for p in root.glob("*.py") if not p.stem.startswith("_"))  # _: helpers
    names = args.names or available
    unknown = [n for n in names if n not in available]
    if unknown:
        raise NNRobustError(f"unknown benchmarks {unknown}; available: {', '.join(available)}")
    out = _bench_folder(Path(args.out), names)
    code = 0
    for name in names:
        print(f"== {name}", flush=True)
        # its own process group: a stop signal here ends the script and every worker it started
        command = [sys.executable, str(root / f"{name}.py"), "--json", str(out / f"{name}.json")]
        child = subprocess.Popen(command, start_new_session=True)
        try:
            code = code or child.wait()
        except KeyboardInterrupt:
            _stop_group(child)
            raise
    return 1 if code else 0


def _bench_folder(out: Path, names: list[str]) -> Path:
    """The --out folder of ``bench``, checked (and made) before any benchmark runs: each one
    writes ``<name>.json`` into it, after minutes of work that a file in its place would lose.
    """
    if out.exists() and not out.is_dir():
        raise NNRobustError(
            f"--out {out}: exists and is not a folder; bench writes one <name>.json per benchmark "
            "into a folder (e.g. --out out/bench)"
        )
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise NNRobustError(f"--out {out}: cannot make the folder ({err.strerror or err})") from err
    if not os.access(out, os.W_OK | os.X_OK):
        raise NNRobustError(f"--out {out}: the folder is not writable")
    taken = [f"{name}.json" for name in names if (out / f"{name}.json").is_dir()]
    if taken:
        raise NNRobustError(f"--out {out}: {', '.join(taken)} is a folder; the benchmark writes a file there")
    return out


def _stop_group(child, grace: float = 10.0) -> None:
    """SIGTERM to a child's process group (the child and every process it started), SIGKILL to
    what is left of it after ``grace`` seconds: no orphan workers.
    """
    import signal
    import subprocess

    try:
        os.killpg(child.pid, signal.SIGTERM)
    except ProcessLookupError:
        return
    try:
        child.wait(grace)
    except subprocess.TimeoutExpired:
        pass
    try:
        os.killpg(child.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    child.wait()


PRESETS = Command(
    "presets",
    help="list the shipped presets",
    arguments=no_arguments,
    run=cmd_presets,
)


def robots_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust robots``."""
    parser.add_argument(
        "--all", action="store_true", help="every example-robot-data robot, not only the arms known to work"
    )


ROBOTS = Command(
    "robots",
    help="list the arms known to work (n, chain, task frame)",
    description="Load every arm nnrobust knows (the paper's arm, a generated "
    "planar chain and example-robot-data arms) and print its joint count, "
    "default chain and task frame. With --all: every robot example-robot-data "
    "ships, loaded or refused with the reason (docs/robots.md).",
    arguments=robots_arguments,
    run=cmd_robots,
)


def bench_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust bench``."""
    parser.add_argument("names", nargs="*", help="benchmark names, e.g. step_scaling (default: all)")
    parser.add_argument("--out", default="out/bench", help="folder for the JSON files")


BENCH = Command(
    "bench",
    help="run the benchmarks (source checkout)",
    description="Run the scripts in benchmarks/ (all, or those named) and "
    "write each one's JSON into --out; docs/benchmarks.md explains them.",
    arguments=bench_arguments,
    run=cmd_bench,
)
