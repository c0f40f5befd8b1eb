"""nnrobust identify on a real robot's log no one here wrote: the Franka Emika Panda's exciting
trajectory of Gaz et al. (RA-L 2019), fitted on its first 70 % in time and judged on the last 30 %,
side by side with the model that paper published, on the same held-out samples.

The log and the published model are GPL-3.0 files of github.com/marcocognetti/FrankaEmikaPandaDynModel;
nnrobust never ships them. Clone the repository anywhere, then:

    git clone https://github.com/marcocognetti/FrankaEmikaPandaDynModel out/FrankaEmikaPandaDynModel
    python benchmarks/identify_panda.py out/FrankaEmikaPandaDynModel --json docs/data/identify_panda.json

Without the clone it prints how to make it and writes nothing (``nnrobust bench`` runs it too).

It reads ``matlab/data/Exciting_Traj/Trajectory_1/rbt_log/`` (time, positions, velocities and
torques, one number per line, 20 544 samples at about 1 kHz with jittered stamps and stale
samples) and the published parameters: masses, centres of mass and inertias from
``matlab/ConvertDynPars2VREP/DynPars2VREP.m`` (the paper's tables VIII and IX) and the sigmoidal
friction of ``matlab/dyn_model_panda/get_FrictionTorque.m``. Both torque treatments are scored:
the torque as logged (its sensor noise included in every residual) and the torque through the
same zero-phase filter as the positions (the residual of the model alone).
"""

from __future__ import annotations

import argparse
import platform
import re
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from nnrobust.model.loading import load_robot
from nnrobust.run.results import write_json_atomic
from nnrobust.studies.identify import IdentifyOptions, identify
from nnrobust.studies.identify.logs import read_log
from nnrobust.studies.identify.signals import FilterChoice, prepare

ROOT = Path(__file__).resolve().parents[1]
URL = "https://github.com/marcocognetti/FrankaEmikaPandaDynModel"
CLONE = ROOT / "out" / "FrankaEmikaPandaDynModel"
"""Where ``make docs-data`` clones the repository."""
LOG = Path("matlab/data/Exciting_Traj/Trajectory_1/rbt_log")
PARAMETERS = Path("matlab/ConvertDynPars2VREP/DynPars2VREP.m")
FRICTION = Path("matlab/dyn_model_panda/get_FrictionTorque.m")
FIT_SHARE = 0.7
FRICTION_TERMS = ("viscous", "coulomb", "offset")
CUTOFF = 10.0
SENSITIVITY_CUTOFFS = (5.0, 20.0)
"""Cut-offs the verdict is also checked at (the filter is a stated choice, not a tuned one)."""


def matrix(text: str, name: str) -> np.ndarray:
    """The numbers of the MATLAB assignment ``name = [ ... ]`` (rows by ';' or new lines)."""
    found = re.search(rf"(?m)^\s*{name}\s*=\s*\[(.*?)\]", text, re.S)
    if found is None:
        raise SystemExit(f"{name} = [...] not found: is this the FrankaEmikaPandaDynModel repository?")
    rows = [r for r in re.split(r"[;\n]", found.group(1).replace("...", "")) if r.strip()]
    return np.array([[float(x) for x in re.split(r"[,\s]+", r.strip()) if x] for r in rows])


def published_model(repository: Path, model: pin.Model):
    """The paper's model: its bodies on the Panda's kinematics, and its friction law."""
    text = (repository / PARAMETERS).read_text()
    inertias, masses, centres = matrix(text, "Il"), matrix(text, "m").ravel(), matrix(text, "CoM_l")
    centres = centres if centres.shape == (7, 3) else centres.T
    published = pin.Model(model)
    for i in range(7):
        xx, xy, xz, yy, yz, zz = inertias[i]
        inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])  # about the centre of mass
        published.inertias[i + 1] = pin.Inertia(masses[i], centres[i], inertia)
    A, _, shift, alpha = matrix((repository / FRICTION).read_text(), "fp")

    def friction(v: np.ndarray) -> np.ndarray:  # get_FrictionTorque.m
        return -A / (1 + np.exp(-alpha * shift)) + A / (1 + np.exp(-alpha * (v + shift)))

    return published, friction


def refitted_friction(published: pin.Model, states, held: slice) -> np.ndarray:
    """The published bodies with nnrobust's friction (viscous, Coulomb, offset) fitted by least
    squares on the same fit segment, joint by joint: the held-out torques it predicts. The published
    model then has the same freedom as nnrobust's (its own sensor offsets included) in everything
    but the bodies."""
    data = published.createData()
    rigid = np.array([pin.rnea(published, data, *s) for s in zip(states.q, states.dq, states.ddq)])
    fit = slice(0, held.start)
    out = np.empty_like(rigid[held])
    for j in range(rigid.shape[1]):
        v = states.dq[:, j]
        columns = np.column_stack([v, np.sign(v), np.ones_like(v)])
        coefficients, *_ = np.linalg.lstsq(columns[fit], (states.tau - rigid)[fit, j], rcond=None)
        out[:, j] = rigid[held, j] + columns[held] @ coefficients
    return out


def rms(x: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(x**2, axis=0))


def scored(files, joints, published, published_friction, cutoff: float, filtered: bool, guard: float = 1.5):
    """Every model's held-out residual RMS per joint at one cut-off, torque treatment and
    reversal guard, the torque RMS, the identification's summary and its seconds."""
    choice = FilterChoice(cutoff, torque=filtered, reversal_guard=guard)
    options = IdentifyOptions(friction=FRICTION_TERMS, filter=choice)
    start = time.perf_counter()
    summary = identify(files, "panda", None, options)
    seconds = time.perf_counter() - start
    states = prepare(read_log(files, joints), options.filter)
    held = slice(int(FIT_SHARE * len(states.t)), None)
    data = published.createData()
    predicted = np.array(
        [pin.rnea(published, data, *s) for s in zip(states.q[held], states.dq[held], states.ddq[held])]
    )
    predicted += published_friction(states.dq[held])
    torque_rms = rms(states.tau[held])
    assert np.allclose(torque_rms, summary["torque_rms"]["held_out"], rtol=1e-3)  # the same samples
    rows = {
        "published (Gaz et al. 2019)": rms(states.tau[held] - predicted),
        "published inertias, friction refitted": rms(
            states.tau[held] - refitted_friction(published, states, held)
        ),
        "URDF (example-robot-data, its damping)": np.array(summary["residuals"]["urdf"]["held_out_rms"]),
        "nnrobust least squares": np.array(summary["residuals"]["least_squares"]["held_out_rms"]),
        "nnrobust physical": np.array(summary["residuals"]["physical"]["held_out_rms"]),
    }
    return rows, torque_rms, summary, seconds


def below_published(rows: dict) -> list[int]:
    """The joints (from 1) where nnrobust's physical model is at or below both published rows."""
    best = np.minimum(rows["published (Gaz et al. 2019)"], rows["published inertias, friction refitted"])
    return [j + 1 for j in range(len(best)) if rows["nnrobust physical"][j] <= best[j]]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "repository",
        type=Path,
        nargs="?",
        default=CLONE,
        help=f"a clone of marcocognetti/FrankaEmikaPandaDynModel (default {CLONE.relative_to(ROOT)})",
    )
    parser.add_argument("--json", help="write the table here")
    args = parser.parse_args()
    if not (args.repository / LOG).is_dir():  # nnrobust bench runs every script: say why, write nothing
        print(f"skipped: no {LOG} in {args.repository}; clone it first: git clone {URL} {args.repository}")
        return
    files = sorted((args.repository / LOG).glob("*.txt"))
    robot = load_robot("panda", task="position")
    joints = tuple(robot.model.names[1:])
    published, published_friction = published_model(args.repository, robot.model)
    out: dict = {"source": "github.com/marcocognetti/FrankaEmikaPandaDynModel " + str(LOG), "treatments": {}}
    out["machine"] = platform.machine()
    out["link7_mass"] = {"published": published.inertias[7].mass, "urdf": robot.model.inertias[7].mass}
    out["cutoffs"] = {}
    for treatment, filtered in (("as logged", False), ("filtered", True)):
        rows, torque_rms, summary, seconds = scored(
            files, joints, published, published_friction, CUTOFF, filtered
        )
        print(
            f"\nheld-out torque residual RMS / torque RMS, torque {treatment} (fit on the first 70 % in time)"
        )
        print(f"{'model':40s}" + "".join(f"{'joint ' + str(j + 1):>9s}" for j in range(7)))
        print(f"{'torque RMS [N m]':40s}" + "".join(f"{x:9.3f}" for x in torque_rms))
        for name, residual in rows.items():
            print(f"{name:40s}" + "".join(f"{100 * x:8.1f}%" for x in residual / torque_rms))
        print(
            f"nnrobust physical at or below both published rows on joints {below_published(rows)}; "
            f"physical: {summary['checks']['physical']}"
        )
        out["treatments"][treatment] = {
            "torque_rms": torque_rms.tolist(),
            "residual_rms": {name: r.tolist() for name, r in rows.items()},
            "residual_share": {name: (r / torque_rms).tolist() for name, r in rows.items()},
            "below_published": below_published(rows),
            "condition_number": summary["identifiability"]["condition_number"],
            "base_parameters": summary["identifiability"]["base_parameters"],
            "physical": summary["checks"]["physical"],
            "mass_matrix_least_eigenvalue": summary["checks"]["mass_matrix_least_eigenvalue"],
            "noise_sigma": summary["noise_sigma"],
            "white": summary["confidence"]["white"],
            "long_run_ratio": summary["confidence"]["long_run_ratio"],
            "log": {
                k: summary["log"][k]
                for k in (
                    "samples",
                    "stale_samples",
                    "stale_with_new_torque",
                    "repeated_positions_kept",
                    "median_step_ms",
                    "step_range_ms",
                )
            },
            "seconds": seconds,
        }
    print(
        "\nthe verdict at other cut-offs: joints where nnrobust physical is at or below both published rows"
    )
    for cutoff in SENSITIVITY_CUTOFFS:
        for treatment, filtered in (("as logged", False), ("filtered", True)):
            rows, torque_rms, summary, _ = scored(
                files, joints, published, published_friction, cutoff, filtered
            )
            key = f"{cutoff:g} Hz, {treatment}"
            out["cutoffs"][key] = {
                "below_published": below_published(rows),
                "residual_share": {name: (r / torque_rms).tolist() for name, r in rows.items()},
                "physical": summary["checks"]["physical"],
            }
            print(f"{key:22s} {below_published(rows)}")
    rows, torque_rms, summary, _ = scored(files, joints, published, published_friction, CUTOFF, True, 0.0)
    out["without_reversal_guard"] = {  # --reversal-guard 0, the torque filtered
        "below_published": below_published(rows),
        "residual_share": {name: (r / torque_rms).tolist() for name, r in rows.items()},
        "physical": summary["checks"]["physical"],
    }
    print(f"{'no reversal guard, filtered':22s} {below_published(rows)}")
    if args.json:
        write_json_atomic(Path(args.json), out)


if __name__ == "__main__":
    main()
