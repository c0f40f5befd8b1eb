"""Is nnrobust identify's confidence region true to its level? 100 synthetic logs of the Panda,
each of a different true robot (masses and inertias up to 20 % and centres of mass up to 1 cm off
the URDF's, friction drawn per joint) following a different finite-Fourier trajectory, with the
faults of a real log (white torque noise, quantisation, a known 2 ms torque delay, jittered
stamps, 2 % stale samples); each identified by the whole command (``identify``), its 95 % region
checked for the truth, and so is its box (``box.toml``: the region's principal coordinates, each
within +-c, nnrobust.model.region).

    python benchmarks/identify_calibration.py --json docs/data/identify_calibration.json

Also per log: whether the physical model passed its checks, and the held-out torque residual
RMS against the noise floor (the injected noise with the quantisation's, sqrt(s^2 + q^2 / 12)).
The logs follow their trajectory exactly (their torque is the inverse dynamics of the truth,
friction by its slipping law): a joint that sticks is not simulated here.
"""

from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

import numpy as np

from nnrobust.model.loading import load_robot
from nnrobust.model.perturbation import perturb_inertias
from nnrobust.model.region import region_from_fit
from nnrobust.model.regressor import ParameterLayout, base_parameters, inertial_vector
from nnrobust.plant.friction import Friction
from nnrobust.run.results import write_json_atomic
from nnrobust.studies.identify import IdentifyOptions, identify
from nnrobust.studies.identify.fit import base_projector
from nnrobust.studies.identify.signals import FilterChoice
from nnrobust.studies.identify.synthetic import FourierTrajectory, SensorFaults, synthetic_log

ROBOT = "panda"
DURATION = 30.0
LEVEL = 0.95
FAULTS = SensorFaults(torque_noise=0.05, torque_quantum=0.01, delay=0.002, jitter=1e-4, stale=0.02)


def score(summary: dict, truth: np.ndarray, layout: ParameterLayout, floor: float) -> dict:
    """One log's identification against its truth: in the region, in the box, physical, the
    held-out residual over the noise floor.
    """
    beta = np.array([p["least_squares"] for p in summary["parameters"]])
    covariance = np.array(summary["confidence"]["covariance"])
    d = truth - beta
    distance2 = float(d @ np.linalg.solve(covariance, d))
    # the box (nnrobust.model.region): the region's principal coordinates, each within +-c
    box = region_from_fit(
        ROBOT, layout, [], LEVEL, "", beta, covariance, np.zeros((len(beta), 0)), np.zeros(0)
    )
    worst_z = float(np.max(np.abs(box.coordinates(truth))))
    held = np.array(summary["residuals"]["physical"]["held_out_rms"])
    return {
        "inside": distance2 <= summary["confidence"]["radius2"],
        "distance2": distance2,
        "inside_box": worst_z <= box.half_width,
        "box_coordinate": worst_z,
        "physical": summary["checks"]["physical"],
        "held_out_over_floor": float(np.max(held / floor)),
        "white": summary["confidence"]["white"],
    }


def summary_of(rows: list[dict], p: int, logs: str, floor: float, started: float) -> dict:
    """The calibration's figures over its logs, printed and returned (the JSON's content)."""
    coverage = np.mean([r["inside"] for r in rows])
    box_coverage = np.mean([r["inside_box"] for r in rows])
    physical = np.mean([r["physical"] for r in rows])
    worst = max(r["held_out_over_floor"] for r in rows)
    print(f"\n{len(rows)} logs of {ROBOT} ({p} base parameters), {DURATION:g} s each, {logs}")
    print(f"{100 * LEVEL:g} % region holds the truth in {100 * coverage:.0f} % of the logs")
    print(f"{100 * LEVEL:g} % box holds the truth in {100 * box_coverage:.0f} % of the logs")
    print(f"median distance^2 / p {np.median([r['distance2'] for r in rows]) / p:.3f} (chi2_p's: about 1)")
    print(f"physical checks passed: {100 * physical:.0f} %")
    print(f"held-out residual RMS / noise floor, worst joint of the worst log: {worst:.3f}")
    return {
        "robot": ROBOT,
        "logs": len(rows),
        "source": logs,
        "duration": DURATION,
        "level": LEVEL,
        "parameters": p,
        "coverage": float(coverage),
        "box_coverage": float(box_coverage),
        "physical_share": float(physical),
        "worst_held_out_over_floor": worst,
        "noise_floor": float(floor),
        "rows": rows,
        "seconds": time.perf_counter() - started,
        "machine": platform.machine(),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--logs", type=int, default=100, help="synthetic logs (default 100)")
    parser.add_argument("--json", help="write the results here")
    args = parser.parse_args()
    model = load_robot(ROBOT, task="position").model
    n = model.nv
    layout = ParameterLayout(tuple(model.names[1:]))
    base = base_parameters(model, layout.names[: 10 * n])  # the one identify computes (same seed)
    P = base_projector(layout, base)
    options = IdentifyOptions(filter=FilterChoice(delay=FAULTS.delay), confidence=LEVEL)
    floor = np.sqrt(FAULTS.torque_noise**2 + FAULTS.torque_quantum**2 / 12)
    rows = []
    start = time.perf_counter()
    for s in range(args.logs):
        rng = np.random.default_rng(1000 + s)
        true = perturb_inertias(model, relative_error=0.2, com_error=0.01, seed=1000 + s)
        friction = Friction(rng.uniform(0.02, 0.2, n), rng.uniform(0.1, 0.6, n))
        trajectory = FourierTrajectory.random(model, seed=s, speed=1.5)
        log = synthetic_log(true, trajectory, DURATION, friction=friction, faults=FAULTS, seed=s)
        summary = identify(log, ROBOT, None, options)
        truth = P @ np.concatenate([inertial_vector(true), friction.viscous, friction.coulomb])
        rows.append(score(summary, truth, layout, floor))
        if (s + 1) % 10 == 0:
            print(f"{s + 1}/{args.logs} logs, {time.perf_counter() - start:.0f} s", flush=True)
    result = summary_of(rows, P.shape[0], "inverse dynamics", floor, start)
    if args.json:
        write_json_atomic(Path(args.json), result)


if __name__ == "__main__":
    main()
