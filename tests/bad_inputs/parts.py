"""Bad inputs: a user's trajectory, disturbance and criterion parts."""

from __future__ import annotations

from pathlib import Path

from nnrobust.core import exceptions as ex

from .common import (
    Case,
    _file,
    _toml,
)
from .custom import (
    PARTS,
    RunExperiment,
)
from .urdf import (
    PAPER,
)


def _part(folder: Path, body: str) -> RunExperiment:
    """An experiment file using a class of tests/parts/again.py (copied beside it), then run."""
    (folder / "parts.py").write_text(PARTS.read_text())
    return RunExperiment(
        _toml(folder, f'base = "paper-ellipse"\n{body}\n[simulation]\nduration = 0.1\n').path
    )


def _effort_zero(folder: Path) -> RunExperiment:
    """The paper's arm with joint1's effort limit written as 0, run with the URDF's limits."""
    from nnrobust import paper_arm_urdf

    urdf = Path(paper_arm_urdf()).read_text().replace('effort="60"', 'effort="0"', 1)
    _file(folder, "arm.urdf", urdf)
    return RunExperiment(
        _toml(folder, f'{PAPER}[robot]\nsource = "arm.urdf"\n[simulation]\nduration = 0.1\n').path
    )


PART_CASES = [
    Case(
        "custom disturbance: wrong size",
        lambda d: _part(d, '[plant]\ndisturbance = "custom"\ndisturbance_class = "parts.py:WrongSize"'),
        ex.ConfigError,
        "plant.disturbance_class: WrongSize(0.0) returned shape (2,); expected (3,)",
    ),
    Case(
        "custom trajectory: not a Trajectory",
        lambda d: _part(d, '[trajectory]\nkind = "custom"\nclass = "parts.py:NotATrajectory"'),
        ex.ConfigError,
        "NotATrajectory is not a subclass of nnrobust.Trajectory",
    ),
    Case(
        "custom trajectory: cannot be copied for the controller",
        lambda d: _part(
            d,
            '[trajectory]\nkind = "custom"\nclass = "parts.py:Locked"\n'
            "params = {center = [0.30, 0.40], a = [0.20, 0.0], b = [0.0, 0.10]}",
        ),
        ex.ConfigError,
        "trajectory.class: Locked cannot be copied for the controller (TypeError: cannot pickle",
    ),
    Case(
        "custom criterion: no class",
        lambda d: _part(d, '[subtasks]\ncriteria = ["custom"]\nweights = [1.0]'),
        ex.ConfigError,
        "subtasks.criterion_class: criteria = [..., 'custom'] needs the class",
    ),
    Case(
        "load: time between control instants",
        lambda d: _part(d, '[[plant.loads]]\nkind = "step"\ntime = 0.0105\ntorque = [1.0, 0.0, 0.0]'),
        ex.ConfigError,
        "plant.loads[0].time: 0.0105 s is not a whole number (>= 0) of control periods",
    ),
    Case(
        "load: a time of 1e308 s",
        lambda d: _part(d, '[[plant.loads]]\nkind = "step"\ntime = 1e308\ntorque = [1.0, 0.0, 0.0]'),
        ex.ConfigError,
        "plant.loads[0].time: 1e+308 s is more than 1e+12 control periods (0.001 s)",
    ),
    Case(
        "load: a time of a 300-digit integer (np.isfinite raised TypeError)",
        lambda d: _part(d, f'[[plant.loads]]\nkind = "step"\ntime = {"9" * 300}\ntorque = [1.0, 0.0, 0.0]'),
        ex.ConfigError,
        "plant.loads[0].time: 1e+300 s is more than 1e+12 control periods (0.001 s)",
    ),
    Case(
        "load: starting after the run ends",
        lambda d: _part(d, '[[plant.loads]]\nkind = "step"\ntime = 5.0\ntorque = [1.0, 0.0, 0.0]'),
        None,
        "plant.loads[0].time: 5 s is not before the run ends (simulation.duration = 0.1 s): the load never",
        UserWarning,
    ),
    Case(
        "URDF <limit effort=\"0\"> under plant.torque_limits = 'urdf' (taken as unlimited, silently)",
        lambda d: _effort_zero(d),
        None,
        'gives <limit effort="0">, read as no effort limit (as a joint without one)',
        UserWarning,
    ),
    Case(
        "load: torque for the wrong arm",
        lambda d: _part(d, '[[plant.loads]]\nkind = "impulse"\ntime = 0.01\nimpulse = [1.0, 0.0]'),
        ex.ConfigError,
        "plant.loads[0].impulse: has 2 entries; give 3",
    ),
    Case(
        "load: a key of another kind",
        lambda d: _part(
            d, '[[plant.loads]]\nkind = "payload"\ntime = 0.01\nmass = 1.0\nforce = [1.0, 0.0, 0.0]'
        ),
        ex.ConfigError,
        "plant.loads[0].force: is not a key of a 'payload' load",
    ),
]
