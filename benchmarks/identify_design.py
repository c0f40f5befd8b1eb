"""What does ``nnrobust identify design`` buy? On the paper's arm and the Panda: the designed
excitation's condition number at a budget of evaluations and at twice it (has the search
converged?), for each criterion (identify's condition number, and D-optimality: the confidence
region's volume), against 20 random trajectories of the same form at the same limits (each scaled until
its tightest limit is just reached); then synthetic logs of the designed trajectory and of five of
the random ones (the calibration's faults and a true robot 20 % off the URDF), each identified by
the whole command, and the standard errors of the base parameters compared.

    python benchmarks/identify_design.py --json docs/data/identify_design.json

The logs follow their joint trajectory exactly (as a robot's joint controller would): the
identification's precision depends on the motion, and this compares motions. Last, the design run
on the bench as its experiment file runs it (each arm's preset law and plant along the designed
task path, the disturbance off), the run folder identified: a task-space law follows the joint
trajectory in the task's directions only, and this measures what that costs.
"""

from __future__ import annotations

import argparse
import json
import platform
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from nnrobust.model.loading import load_robot
from nnrobust.model.perturbation import perturb_inertias
from nnrobust.plant.friction import Friction
from nnrobust.run.results import write_json_atomic
from nnrobust.studies.identify import IdentifyOptions, identify
from nnrobust.studies.identify.design import CRITERIA, DesignOptions, ExcitationProblem, design_excitation
from nnrobust.studies.identify.signals import FilterChoice
from nnrobust.studies.identify.synthetic import SensorFaults, synthetic_log

FAULTS = SensorFaults(torque_noise=0.05, torque_quantum=0.01, delay=0.002, jitter=1e-4, stale=0.02)
RANDOM = 20
LOGGED_RANDOM = 5
PERIODS = 3
PRESETS = {"three_link_planar": "paper-ellipse", "panda": "panda-ellipse"}


def standard_errors(model, robot, trajectory, seed) -> tuple[np.ndarray, float]:
    """The base parameters' standard errors and the condition number identify reports, on a
    synthetic log of ``PERIODS`` periods of ``trajectory`` by one true robot (the same for every
    trajectory), its sensor noise drawn from ``seed``.
    """
    n = model.nv
    rng = np.random.default_rng(500)
    true = perturb_inertias(model, relative_error=0.2, com_error=0.01, seed=500)
    friction = Friction(rng.uniform(0.02, 0.2, n), rng.uniform(0.1, 0.6, n))
    log = synthetic_log(
        true, trajectory, PERIODS / trajectory.frequency, friction=friction, faults=FAULTS, seed=seed
    )
    summary = identify(
        log, robot, None, IdentifyOptions(filter=FilterChoice(delay=FAULTS.delay), allow_unexcited=True)
    )
    se = np.array([p["standard_error"] for p in summary["parameters"]])
    return se, float(summary["identifiability"]["condition_number"])


def bench_run(robot: str, preset: str, design, folder: Path, law: str) -> dict:
    """The design run on the bench on the preset's plant (its disturbance off): with the
    experiment's joint-space law (``law = "joint-fourier"``, as identify design writes it) or the
    preset's own task-space law (``"preset"``); the run folder identified, and how far its joints
    went from the design.
    """
    from nnrobust.cli import main as cli
    from nnrobust.config import dump_toml
    from nnrobust.studies.identify.design import design_record, experiment_toml, task_path

    arm = load_robot(robot, task="position")
    task = "planar" if robot == "three_link_planar" else "position"
    record = folder / f"{robot}.json"
    options = DesignOptions(evaluations=design.evaluations)
    record.write_text(json.dumps(design_record(design, robot, design.joints, options, PERIODS, None)))
    times, points = task_path(arm, design.trajectory, PERIODS / design.trajectory.frequency)
    data = tomllib.loads(experiment_toml(design, robot, task, None, PERIODS, times, points, str(record)))
    data = {"base": preset, "trajectory": data["trajectory"], "simulation": data["simulation"]}
    if law == "joint-fourier":
        data["controller"] = {"kind": "joint-fourier", "params": {"file": str(record)}}
    data["plant"] = {"disturbance": "none"}
    experiment = folder / f"{robot}-{law}.toml"
    experiment.write_text(dump_toml(data))
    run = folder / f"{robot}-{law}-run"
    if cli(["run", str(experiment), "--out", str(run), "--no-plots", "--no-animation", "--quiet"]) != 0:
        raise SystemExit(f"the bench run of {robot}'s design ({law}) failed")
    summary = identify([run], robot, None, IdentifyOptions(allow_unexcited=True))
    result = np.load(run / "result.npz")
    planned, _, _ = design.trajectory.states(result["t"])
    metrics = json.loads((run / "metrics.json").read_text())
    return {
        "law": law,
        "condition": float(summary["identifiability"]["condition_number"]),
        "unexcited": summary["identifiability"].get("unexcited", []),
        "joint_deviation_rms": np.sqrt(np.mean((result["q"] - planned) ** 2, axis=0)).tolist(),
        "rms_error_mm": 1e3 * metrics["rms_error"],
    }


def robot_row(robot: str, evaluations: int, folder: Path) -> dict:
    """One arm: each criterion's design at the budget and at twice it, the random trajectories,
    the logs' standard errors, the bench runs.
    """
    model = load_robot(robot, task="position").model
    joints = tuple(model.names[1:])
    designs: dict[str, dict[int, object]] = {}
    for criterion in CRITERIA:
        designs[criterion] = {}
        for budget in (evaluations, 2 * evaluations):
            d = design_excitation(model, joints, DesignOptions(evaluations=budget, criterion=criterion))
            designs[criterion][budget] = d
            print(
                f"{robot}: {criterion}, {d.evaluations} evaluations: criterion {d.value:.4g}, condition "
                f"number {d.condition:.4g} ({d.seconds:.1f} s)"
            )
    problem = ExcitationProblem(model, DesignOptions(), joints)
    rng = np.random.default_rng(7)
    randoms = [problem.random_at_limits(rng) for _ in range(RANDOM)]
    conditions = []
    for trajectory in randoms:
        q, dq, ddq = trajectory.states(problem.sample_times)
        conditions.append(problem.condition(problem.regressor(q, dq, ddq), dq))
    order = np.argsort(conditions)
    logged = order[np.linspace(0, RANDOM - 1, LOGGED_RANDOM).astype(int)]  # best to worst, spread
    random_se = [standard_errors(model, robot, randoms[k], 1 + i) for i, k in enumerate(logged)]
    rows = {}
    for criterion in CRITERIA:
        design = designs[criterion][evaluations]  # at the budget: the command's, by default
        se, logged_condition = standard_errors(model, robot, design.trajectory, 0)
        # the geometric mean over the base parameters of se(design) / se(random), one per random log
        ratios = [float(np.exp(np.mean(np.log(se / other)))) for other, _ in random_se]
        first, second = (designs[criterion][b] for b in (evaluations, 2 * evaluations))
        rows[criterion] = {
            "budget": {
                str(b): {"evaluations": d.evaluations, "value": d.value, "condition": d.condition}
                for b, d in designs[criterion].items()
            },
            "doubling_change": abs(second.value - first.value),
            "condition": design.condition,
            "value": design.value,
            "peaks": design.peaks,
            "logged_condition": logged_condition,
            "standard_error_ratio": ratios,
            "standard_error_ratio_median": float(np.median(ratios)),
        }
        print(
            f"{robot}: {criterion} design's standard errors {np.median(ratios):.3g} x a random "
            "trajectory's (geometric mean over the parameters, median over the random logs)"
        )
    design = designs["condition"][evaluations]
    runs = {law: bench_run(robot, PRESETS[robot], design, folder, law) for law in ("joint-fourier", "preset")}
    for law, run in runs.items():
        print(
            f"{robot}: on the bench ({law} law, {PRESETS[robot]}'s plant): condition number "
            f"{run['condition']:.4g}, joints off the design by "
            f"{np.round(run['joint_deviation_rms'], 3).tolist()} rad RMS"
        )
    print(
        f"{robot}: random at the same limits: condition number median {np.median(conditions):.4g} "
        f"(best {min(conditions):.4g})"
    )
    return {
        "robot": robot,
        "joints": len(joints),
        "searched": problem.dimension,
        "criteria": rows,
        "random_conditions": [float(c) for c in conditions],
        "random_condition_median": float(np.median(conditions)),
        "random_condition_best": float(min(conditions)),
        "random_logged_conditions": [c for _, c in random_se],
        "preset": PRESETS[robot],
        "bench_runs": runs,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--evaluations",
        type=int,
        default=DesignOptions().evaluations,
        help="the smaller budget (default: the command's)",
    )
    parser.add_argument("--json", help="write the results here")
    args = parser.parse_args()
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        rows = [robot_row(robot, args.evaluations, Path(folder)) for robot in PRESETS]
    print(
        f"{'robot':<18} {'criterion':<10} {'cond.':>7} {'2x budget':>9} {'random median':>14} "
        f"{'se / random':>12} {'on the bench':>13}"
    )
    for r in rows:
        for criterion, c in r["criteria"].items():
            b = list(c["budget"].values())
            bench = (
                r["bench_runs"]["joint-fourier"]["condition"] if criterion == "condition" else float("nan")
            )
            print(
                f"{r['robot']:<18} {criterion:<10} {b[0]['condition']:>7.4g} {b[1]['condition']:>9.4g} "
                f"{r['random_condition_median']:>14.4g} {c['standard_error_ratio_median']:>11.3g}x "
                f"{bench:>13.4g}"
            )
    if args.json:
        faults = ("torque_noise", "torque_quantum", "delay", "jitter", "stale")
        write_json_atomic(
            args.json,
            {
                "command": "python benchmarks/identify_design.py --json docs/data/identify_design.json",
                "machine": platform.processor() or platform.machine(),
                "seconds": time.perf_counter() - started,
                "evaluations": args.evaluations,
                "periods": PERIODS,
                "faults": {k: getattr(FAULTS, k) for k in faults},
                "robots": rows,
            },
        )


if __name__ == "__main__":
    main()
