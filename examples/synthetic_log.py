"""A robot's log whose truth is known, to try ``nnrobust identify`` on: the paper's arm with every
body's mass and inertia up to 20 % off the URDF's and its centre of mass up to 1 cm off, the URDF's
friction (viscous 4.3, 1.4, 0.4 N m s/rad and Coulomb 1 N m, eq. (7)), following a finite-Fourier
exciting trajectory, logged at 1 kHz with the faults of a real log: torque noise (0.05 N m) and
quantisation (0.01 N m), jittered stamps, 2 % stale samples. The first step of the walkthrough of
docs/identification.md ("From a log to a certified law").

    python examples/synthetic_log.py out/walkthrough

writes out/walkthrough/log.csv (time, q.JOINT, dq.JOINT, tau.JOINT) and truth.json (the true
robot's inertial parameters, ten per body, and friction), and prints the log's size.
"""

import argparse
import json
from pathlib import Path

import numpy as np

from nnrobust.model.loading import load_robot
from nnrobust.model.perturbation import perturb_inertias
from nnrobust.model.regressor import inertial_vector
from nnrobust.plant.friction import Friction
from nnrobust.studies.identify.synthetic import FourierTrajectory, SensorFaults, synthetic_log, write_csv

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("out", help="folder to write log.csv and truth.json in")
parser.add_argument("--seconds", type=float, default=40.0, help="the log's length [s] (default 40)")
parser.add_argument("--seed", type=int, default=7, help="the true robot's and the trajectory's seed")
args = parser.parse_args()

arm = load_robot("three_link_planar")
true = perturb_inertias(arm.model, relative_error=0.2, com_error=0.01, seed=args.seed)
friction = Friction(arm.viscous_friction, arm.coulomb_friction)
trajectory = FourierTrajectory.random(arm.model, seed=args.seed, speed=1.5)
faults = SensorFaults(torque_noise=0.05, torque_quantum=0.01, jitter=1e-4, stale=0.02)
log = synthetic_log(true, trajectory, args.seconds, friction=friction, faults=faults, seed=args.seed)

out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)
joints = list(arm.model.names[1:])
write_csv(log, out / "log.csv", joints)
truth = {
    "joints": joints,
    "inertial": inertial_vector(true).tolist(),
    "viscous": np.asarray(friction.viscous).tolist(),
    "coulomb": np.asarray(friction.coulomb).tolist(),
}
(out / "truth.json").write_text(json.dumps(truth, indent=1) + "\n")
print(f"wrote {out / 'log.csv'}: {log.samples} samples of {len(joints)} joints over {args.seconds:g} s")
print(f"wrote {out / 'truth.json'}: the true robot")
