"""Is nnrobust identify's confidence region true to its level on logs of nnrobust's own plant?
As benchmarks/identify_calibration.py, but each log is a run of the bench, not the inverse
dynamics of a trajectory: the Panda's true plant a different robot per log (masses and inertias
up to 20 % and centres of mass up to 1 cm off the URDF's, viscous and Coulomb friction drawn per
joint, static friction 1.3 times the Coulomb level: the plant integrates stick-slip), driven by
the joint-space law along a random finite-Fourier trajectory at the limits (controller.kind =
"joint-fourier", its model the URDF's), its sensors a 19-bit encoder; the run folder is the log,
then a real log's faults on it: white torque noise, quantisation, a 2 ms torque delay, 2 % stale
samples. Each identified by the whole command, its 95 % region and box checked for the truth.

    python benchmarks/identify_calibration_plant.py --json docs/data/identify_calibration_plant.json

Each log is identified three times (:data:`VARIANTS`): with identify's defaults, without its
reversal guard, and without it but with a stick band of 0.2 rad/s. Near a velocity reversal the
log's samples are not the model's: Coulomb friction flips there, the commanded torque does not,
so the acceleration jumps by 2 F_c / M, and the 10 Hz zero-phase filter smears that jump over
about a cut-off period on each side; the guard (or, more crudely, a wide stick band) leaves those
samples out.

The true plant is the one an identified box's point describes (``plant.region`` with its
coordinates at zero: a region file whose centre is the true robot's base parameters and whose
axes are zero), so the truth is exactly the plant's.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np
from identify_calibration import DURATION, FAULTS, LEVEL, ROBOT, score, summary_of

from nnrobust.cli import main as cli
from nnrobust.config import dump_toml
from nnrobust.model.loading import load_robot
from nnrobust.model.perturbation import perturb_inertias
from nnrobust.model.region import IdentifiedRegion, box_half_width
from nnrobust.model.regressor import ParameterLayout, base_parameters, inertial_vector
from nnrobust.run.results import write_json_atomic
from nnrobust.studies.identify import IdentifyOptions, identify
from nnrobust.studies.identify.design import (
    Design,
    DesignOptions,
    ExcitationProblem,
    design_record,
    experiment_toml,
    task_path,
)
from nnrobust.studies.identify.fit import base_projector
from nnrobust.studies.identify.logs import read_log
from nnrobust.studies.identify.signals import FilterChoice

ENCODER = 2 * np.pi / 2**19
"""The plant's encoder count [rad]: q is logged rounded to it."""

STICTION = 1.3
"""Static friction over the Coulomb level: a joint at rest is held by up to 1.3 F_c."""

VARIANTS = {
    "defaults": {"stick_band": 0.01, "reversal_guard": 1.5},
    "no reversal guard": {"stick_band": 0.01, "reversal_guard": 0.0},
    "no guard, wide stick band": {"stick_band": 0.2, "reversal_guard": 0.0},
}
"""identify's options tried on every log: its defaults (--stick-band 0.01 rad/s,
--reversal-guard 1.5 cut-off periods), without the reversal guard, and without it but with a
stick band wide enough to leave out most samples near a reversal (module docstring)."""


def true_robot_region(model, layout, base, seed: int, folder: Path) -> tuple[Path, np.ndarray]:
    """A region file whose point z = 0 is a robot drawn around the URDF, and its base parameters."""
    n = model.nv
    rng = np.random.default_rng(3000 + seed)
    true = perturb_inertias(model, relative_error=0.2, com_error=0.01, seed=3000 + seed)
    phi = np.concatenate([inertial_vector(true), rng.uniform(0.02, 0.2, n), rng.uniform(0.1, 0.6, n)])
    P = base_projector(layout, base)
    beta = P @ phi
    names = [f"beta{i}" for i in range(len(beta))]
    region = IdentifiedRegion(
        ROBOT, tuple(layout.joints), layout, tuple(names), LEVEL, "the truth", beta,
        np.zeros((len(beta), len(beta))), box_half_width(LEVEL, len(beta)), P, phi,
    )  # fmt: skip
    path = folder / f"truth-{seed}.json"
    path.write_text(json.dumps(region.to_dict()))
    return path, beta


def plant_log(model, arm, layout, base, seed: int, folder: Path):
    """One log of the bench's plant (module docstring) and its truth."""
    joints = tuple(model.names[1:])
    region, truth = true_robot_region(model, layout, base, seed, folder)
    problem = ExcitationProblem(model, DesignOptions(), joints)
    trajectory = problem.random_at_limits(np.random.default_rng(seed))
    design = Design(joints, trajectory, np.nan, np.nan, 0, "random", [], {})
    periods = round(DURATION * trajectory.frequency)
    record = folder / f"traj-{seed}.json"
    record.write_text(json.dumps(design_record(design, ROBOT, joints, DesignOptions(), periods, None)))
    times, points = task_path(arm, trajectory, periods / trajectory.frequency)
    data = tomllib.loads(
        experiment_toml(design, ROBOT, "position", None, periods, times, points, str(record))
    )
    data["plant"] = {
        "region": str(region),
        "region_coordinates": [0.0] * len(truth),
        "disturbance": "none",
        "stiction": STICTION,
    }
    data["sensing"] = {"encoder_resolution": [ENCODER]}
    experiment = folder / f"log-{seed}.toml"
    experiment.write_text(dump_toml(data))
    run = folder / f"run-{seed}"
    if cli(["run", str(experiment), "--out", str(run), "--no-plots", "--no-animation", "--quiet"]) != 0:
        raise SystemExit(f"log {seed}: the run failed ({run})")
    log = read_log([run], joints)
    rng = np.random.default_rng(seed)
    q = ENCODER * np.round(np.asarray(log.q) / ENCODER)
    dq = np.asarray(log.dq, dtype=float).copy()
    tau = np.asarray(log.tau, dtype=float)
    lag = int(round(FAULTS.delay / (log.t[1] - log.t[0])))
    tau = np.concatenate([np.repeat(tau[:1], lag, axis=0), tau[:-lag]])  # logged 2 ms late
    tau = tau + rng.normal(0, FAULTS.torque_noise, tau.shape)
    tau = FAULTS.torque_quantum * np.round(tau / FAULTS.torque_quantum)
    stale = np.flatnonzero(rng.random(len(log.t)) < FAULTS.stale)
    for k in stale[stale > 0]:
        q[k], dq[k], tau[k] = q[k - 1], dq[k - 1], tau[k - 1]
    log.q, log.dq, log.tau = q, dq, tau
    return log, truth


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", type=int, default=100, help="plant logs (default 100)")
    parser.add_argument("--json", help="write the results here")
    args = parser.parse_args()
    arm = load_robot(ROBOT, task="position")
    model = arm.model
    layout = ParameterLayout(tuple(model.names[1:]))
    base = base_parameters(model, layout.names[: 10 * model.nv])
    floor = np.sqrt(FAULTS.torque_noise**2 + FAULTS.torque_quantum**2 / 12)
    rows: dict[str, list] = {name: [] for name in VARIANTS}
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        for s in range(args.logs):
            log, truth = plant_log(model, arm, layout, base, s, Path(folder))
            for name, v in VARIANTS.items():
                choice = FilterChoice(delay=FAULTS.delay, reversal_guard=v["reversal_guard"])
                options = IdentifyOptions(filter=choice, confidence=LEVEL, stick_band=v["stick_band"])
                summary = identify(log, ROBOT, None, options)
                rows[name].append(score(summary, truth, layout, floor))
            if (s + 1) % 10 == 0:
                print(f"{s + 1}/{args.logs} logs, {time.perf_counter() - start:.0f} s", flush=True)
    result = {
        "logs": args.logs,
        "stiction": STICTION,
        "encoder": ENCODER,
        "variants": {
            name: {
                **VARIANTS[name],
                **summary_of(rows[name], len(truth), f"the plant's runs, {name}", floor, start),
            }
            for name in VARIANTS
        },
    }
    if args.json:
        write_json_atomic(Path(args.json), result)


if __name__ == "__main__":
    main()
