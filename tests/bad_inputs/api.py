"""Bad inputs: the Python API."""

from __future__ import annotations

import datetime
from pathlib import Path

from nnrobust.core import exceptions as ex
from nnrobust.outputs.run_folder import RunFolderError

from .common import (
    Case,
    _build,
    _load,
    _toml,
)
from .scheduler import (
    _mutated,
)
from .urdf import (
    PAPER,
)


def _set(text: str):
    def check():
        from nnrobust.config import parse_override

        return parse_override(text)

    return check


def _hand_made_result(folder: Path):
    def write():
        import numpy as np

        from nnrobust import write_run
        from nnrobust.run.results import Result

        zeros = np.zeros((3, 2))
        made = Result(t=np.zeros(3), q=zeros, dq=zeros, tau=zeros, x=zeros, x_d=zeros, e=zeros,
                      signals={}, status="completed", message="", config="")  # fmt: skip
        return write_run(folder / "run", made, plots=False, animation=False)

    return write


API_CASES = [
    Case(
        "--set: a TOML date-time",
        lambda d: _set("controller.params.when=1979-05-27T07:32:00Z"),
        ex.ConfigError,
        "--set controller.params.when: is a TOML date-time (1979-05-27T07:32:00+00:00), which no key takes",
    ),
    Case(
        "--set: a TOML time in a list",
        lambda d: _set("controller.params.times=[1.0, 07:32:00]"),
        ex.ConfigError,
        "--set controller.params.times[1]: is a TOML time (07:32:00), which no key takes",
    ),
    Case(
        "Python API: a datetime in controller.params",
        lambda d: _build(
            controller={
                "kind": "custom",
                "class": "laws.py:Eq9",
                "params": {"when": datetime.date(1979, 5, 27)},
            }
        ),
        ex.ConfigError,
        "controller.params.when: is a TOML date (1979-05-27), which no key takes",
    ),
    Case(
        "a friction scale of 1e10 (a plant no step resolves)",
        lambda d: _toml(d, f"{PAPER}[plant]\nfriction_scale = 1e10\n"),
        ex.ConfigError,
        "plant.friction_scale: must be in [0, 100], got 1e+10",
    ),
    Case(
        "viscous friction of 1e6 N m s/rad (stiffer than any practical step)",
        lambda d: _build(plant={"viscous_friction": [1e6, 1e6, 1e6]}),
        ex.ConfigError,
        "simulation.substeps: the plant is too stiff for RK4 at any practical step",
    ),
    Case(
        "a negative Coulomb friction",
        lambda d: _toml(d, f"{PAPER}[plant]\ncoulomb_friction = [-1.0, 0.0, 0.0]\n"),
        ex.ConfigError,
        "plant.coulomb_friction: each entry must be in [0, 1e+06] N m",
    ),
    Case(
        "a stop stiffness of 1e308",
        lambda d: _toml(d, f"{PAPER}[plant]\njoint_stop_stiffness = 1e308\n"),
        ex.ConfigError,
        "plant.joint_stop_stiffness: must be in (0, 1e+06]",
    ),
    Case(
        "a pseudo-inverse threshold of 1e155 m/rad",
        lambda d: _toml(d, f"{PAPER}[controller]\npinv_threshold = 1e155\n"),
        ex.ConfigError,
        "controller.pinv_threshold: 1e+155 is outside (0, 1000] m/rad",
    ),
    Case(
        "substeps and an integration step that disagree",
        lambda d: _toml(d, f"{PAPER}[simulation]\nsubsteps = 5\nintegration_step = 0.0005\n"),
        ex.ConfigError,
        "simulation.substeps: 5 disagrees with simulation.integration_step = 0.0005 s",
    ),
    Case(
        "a planar chain named with 5000 digits",
        lambda d: _load("planar" + "9" * 5000),
        ex.RobotLoadError,
        "a generated planar chain has 1 to 300 links",
    ),
    Case(
        "Python API: load_robot with 2 gravity entries",
        lambda d: _load("three_link_planar", gravity=(0.0, -9.81)),
        ex.RobotLoadError,
        "gravity needs 3 finite numbers of at most 1000 m/s^2, got (0.0, -9.81)",
    ),
    Case(
        "Python API: load_robot with a chain of 3 frames",
        lambda d: _load("three_link_planar", chain=["a", "b", "c"]),
        ex.RobotLoadError,
        "chain needs 2 frame names, (base, tip)",
    ),
    Case(
        "nn.error_range of 1e-300 (the loops would disagree)",
        lambda d: _toml(d, f"{PAPER}[nn]\nbasis_input = 'error'\nerror_range = [1e-300, 1e-300]\n"),
        ex.ConfigError,
        "nn.error_range: 1e-300 is outside [1e-09, 1e+09] m, m/s",
    ),
    Case(
        "gains of 1e300 (the loops would disagree)",
        lambda d: _toml(d, f"{PAPER}[controller]\nKp = [1e300]\nKv = [1e300]\n"),
        ex.ConfigError,
        "controller.Kp: 1e+300 is outside (0, 1e+12] 1/s^2",
    ),
    Case(
        "Python API: controller.kind changed to 'lqr' after loading",
        lambda d: _mutated(lambda c: setattr(c.controller, "kind", "lqr")),
        ex.ConfigError,
        "controller.kind: 'lqr' is not one of nn, sliding-mode, no-u0",
    ),
    Case(
        "Python API: a section replaced by None after loading",
        lambda d: _mutated(lambda c: setattr(c, "nominal", None)),
        ex.ConfigError,
        "nominal: expected a NominalConfig section, got NoneType None",
    ),
    Case(
        "Python API: a negative Kp set after loading",
        lambda d: _mutated(lambda c: setattr(c.controller, "Kp", [-1.0, -1.0])),
        ex.ConfigError,
        "controller.Kp: -1 is outside (0, 1e+12] 1/s^2",
    ),
    Case(
        "Python API: duration = nan set after loading",
        lambda d: _mutated(lambda c: setattr(c.simulation, "duration", float("nan"))),
        ex.ConfigError,
        "simulation.duration: expected a finite number, got nan",
    ),
    Case(
        "Python API: control_period = 0 set after loading",
        lambda d: _mutated(lambda c: setattr(c.simulation, "control_period", 0.0)),
        ex.ConfigError,
        "simulation.control_period: must be positive, got 0.0",
    ),
    Case(
        "Python API: substeps = 0 set after loading",
        lambda d: _mutated(lambda c: setattr(c.simulation, "substeps", 0)),
        ex.ConfigError,
        "simulation.substeps: must be positive, got 0",
    ),
    Case(
        "Python API: load_robot with an empty task frame",
        lambda d: (
            lambda: __import__("nnrobust").load_robot(
                __import__("shutil").copy(__import__("nnrobust").paper_arm_urdf(), d / "arm.urdf"),
                task_frame="",
            )
        ),
        ex.RobotLoadError,
        "task_frame needs a frame's name (or None for the default rule), got ''",
    ),
    Case(
        "Python API: load_robot with a chain of ints",
        lambda d: _load("three_link_planar", chain=[1, 2]),
        ex.RobotLoadError,
        "chain needs 2 frame names, (base, tip), got list [1, 2]",
    ),
    Case(
        "Python API: load_robot with a chain of 3",
        lambda d: _load("three_link_planar", chain=3),
        ex.RobotLoadError,
        "chain needs 2 frame names, (base, tip), got int 3",
    ),
    Case(
        "Python API: load_robot with locked_joints of ints",
        lambda d: _load("three_link_planar", locked_joints=[1, 2]),
        ex.RobotLoadError,
        "locked_joints needs a list of joint names ([] locks nothing, None the default rule), "
        "got list [1, 2]",
    ),
    Case(
        "Python API: load_robot with locked_joints one name, not a list",
        lambda d: _load("three_link_planar", locked_joints="joint1"),
        ex.RobotLoadError,
        "locked_joints needs a list of joint names ([] locks nothing, None the default rule), "
        "got str 'joint1'",
    ),
    Case(
        "Python API: write_run given a bytes path",
        lambda d: lambda: __import__("nnrobust").write_run(bytes(d / "run"), 3),
        RunFolderError,
        "the run folder needs a str or pathlib.Path, got bytes b'",
    ),
    Case(
        "Python API: write_run given a hand-made Result (no signals)",
        lambda d: _hand_made_result(d),
        RunFolderError,
        "write_run: this Result cannot be summarised (KeyError: 'manipulability'); give it the Result "
        "run_experiment returns",
    ),
    Case(
        "Python API: write_run given something else than a Result",
        lambda d: lambda: __import__("nnrobust").write_run(d / "run", 3),
        RunFolderError,
        "write_run needs a Result (what run_experiment returns), got int",
    ),
]
