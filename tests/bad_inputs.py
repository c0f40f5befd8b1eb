"""Every bad input nnrobust is tested with, and the error it must give.

Shared by tests/test_hostile_input.py and by ``python -m tests.bad_inputs`` (run from the
repository root), which writes docs/bad-inputs.md from the messages actually raised.
"""

from __future__ import annotations

import datetime
import json
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from nnrobust.core import exceptions as ex
from nnrobust.model.urdf_check import (
    InertiaAssumptionWarning,
    MeshOutsideFoldersWarning,
    MissingMeshWarning,
    UndeclaredPrefixWarning,
)
from nnrobust.outputs.run_folder import RunFolderError

ARM = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="3"/></joint>
  <link name="l1"><inertial><origin xyz="0.2 0 0"/><mass value="1"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>{visual}</link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="3"/></joint>
  <link name="l2"><inertial><origin xyz="0.15 0 0"/><mass value="{mass}"/>
    <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  {extra}
</robot>
"""


FLANGE = (
    '<joint name="flange_joint" type="fixed"><parent link="l2"/><child link="flange"/>'
    '<origin xyz="0.3 0 0"/></joint><link name="flange"><inertial><mass value="0"/>'
    '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>'
)
"""A flange frame with mass 0 and an inertia of 0.1 kg m^2, as pybullet's Panda has."""

CAD_PRODUCTS = (
    'ixx="0.0053694" ixy="0.0014185" ixz="-0.00092094" iyy="0.0032423" iyz="-0.00169178" izz="0.00501731"'
)
"""pybullet's xarm6 link3: 13 % past the triangle inequality as written, physical with the
products' sign flipped."""


def arm(mass="1", ixx="0.001", visual="", extra="") -> str:
    """A valid two-link arm, with one part replaced."""
    return ARM.format(mass=mass, ixx=ixx, visual=visual, extra=extra)


def _l2_inertia(attributes: str | None) -> str:
    """The arm with link l2's <inertia> attributes replaced (None: l2 without <inertial>)."""
    text = arm()
    head, tail = text.rsplit('<inertial><origin xyz="0.15 0 0"/>', 1)
    old = tail[: tail.index("</inertial>") + len("</inertial>")]
    new = (
        ""
        if attributes is None
        else (f'<inertial><origin xyz="0.15 0 0"/><mass value="1"/><inertia {attributes}/></inertial>')
    )
    return head + tail.replace(old, new, 1)


def _first_axis_then(element: str) -> str:
    """The arm with an element added after joint j1's <axis>."""
    return arm().replace('<axis xyz="0 0 1"/>', f'<axis xyz="0 0 1"/>{element}', 1)


PREFIXED = arm(
    extra='<gazebo:plugin name="ros2_control"><parameters>x.yaml</parameters></gazebo:plugin>'
).replace('effort="10"', 'drake:acceleration="2.5" effort="10"')
"""The arm as projects publish URDFs: attributes and elements of prefixes no xmlns declares."""


BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
<!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">]>
<robot name="&lol3;"><link name="base"/></robot>
"""


@dataclass
class Case:
    """One bad input: how to make it (in a scratch folder), what it is, what must be raised."""

    what: str
    make: Callable[[Path], Callable[[], object]]
    error: type | None  # None: must load, with a warning of class ``warns``
    fragment: str
    warns: type | None = None


def _load(text_or_path, **kwargs):
    from nnrobust import load_robot

    return lambda: load_robot(text_or_path, **kwargs)


def _visual(text_or_path, **kwargs):
    from nnrobust.model.loading import load_visual_model

    return lambda: load_visual_model(text_or_path, **kwargs)


def _working_in(folder: Path, action):
    """The action, run with ``folder`` as the working folder (the root of a text URDF's meshes)."""
    import os

    def run():
        before = os.getcwd()
        os.chdir(folder)
        try:
            return action()
        finally:
            os.chdir(before)

    return run


def _file(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


class ReadConfig:
    """Read an experiment file (``path`` is what the command line would be given)."""

    def __init__(self, path: Path):
        self.path = path

    def __call__(self):
        from nnrobust.config import load_config

        return load_config(self.path)


class BuildExperiment:
    """Build a preset with some sections changed (the file is ``self.toml()``)."""

    def __init__(self, preset: str, sections: dict):
        self.preset, self.sections = preset, sections

    def toml(self) -> str:
        from nnrobust.config.presets import load_preset

        return load_preset(self.preset).replace(**self.sections).to_toml()

    def __call__(self):
        from nnrobust.config.presets import load_preset
        from nnrobust.run.experiment import build

        return build(load_preset(self.preset).replace(**self.sections))


def _read_config(path: Path) -> ReadConfig:
    return ReadConfig(path)


def _toml(folder: Path, text: str) -> ReadConfig:
    return ReadConfig(_file(folder, "experiment.toml", text))


def _build(preset: str = "paper-ellipse", **sections) -> BuildExperiment:
    return BuildExperiment(preset, sections)


def _huge(folder: Path) -> Path:
    path = folder / "huge.urdf"
    with open(path, "w") as fh:
        fh.write('<robot name="huge">')
        fh.write("<!-- padding -->" * 1_400_000)
        fh.write("</robot>")
    return path


def _non_utf8(folder: Path) -> Path:
    path = folder / "latin1.urdf"
    path.write_bytes(arm().replace('name="arm"', 'name="bras\xe9"').encode("latin-1"))
    return path


CYCLE = arm(
    extra='<joint name="j3" type="revolute"><parent link="l2"/><child link="base"/>'
    '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
)

URDF_CASES = [
    Case(
        "URDF file that does not exist",
        lambda d: _load("no/such/robot.urdf"),
        ex.RobotLoadError,
        "no such file",
    ),
    Case("URDF file that is not UTF-8", lambda d: _load(_non_utf8(d)), ex.UrdfSyntaxError, "not UTF-8"),
    Case(
        "malformed XML (unclosed tag)",
        lambda d: _load(arm().replace("</robot>", "")),
        ex.UrdfSyntaxError,
        "malformed XML at line",
    ),
    Case(
        "root element is not <robot>",
        lambda d: _load("<html><body/></html>"),
        ex.UrdfStructureError,
        "needs <robot>",
    ),
    Case(
        "joint whose child link is not defined",
        lambda d: _load(
            arm(extra='<joint name="j9" type="fixed"><parent link="l2"/><child link="ghost"/></joint>')
        ),
        ex.UrdfStructureError,
        "child link 'ghost' is not defined",
    ),
    Case(
        "link that no joint attaches (two roots)",
        lambda d: _load(arm(extra='<link name="floating"/>')),
        ex.UrdfStructureError,
        "have no parent joint",
    ),
    Case(
        "two links with the same name",
        lambda d: _load(arm(extra='<link name="l1"/>')),
        ex.UrdfStructureError,
        "two links are named 'l1'",
    ),
    Case(
        "kinematic cycle (Pinocchio alone returns an empty model)",
        lambda d: _load(CYCLE),
        ex.KinematicCycle,
        "form a closed loop",
    ),
    Case(
        "no movable joint",
        lambda d: _load(
            '<robot name="r"><link name="a"/><joint name="f" type="fixed">'
            '<parent link="a"/><child link="b"/></joint><link name="b"/></robot>'
        ),
        ex.ModelMismatch,
        "no movable joint",
    ),
    Case(
        "planar joint (no single angle or length)",
        lambda d: _load(arm().replace('name="j1" type="revolute"', 'name="j1" type="planar"')),
        ex.ModelMismatch,
        "joints 'j1' (Planar) have no single angle or length",
    ),
    Case(
        "the last link massless (its inertia is dropped: then nothing moves)",
        lambda d: _load(arm(mass="0")),
        ex.InvalidInertia,
        "joint 'j2' moves no mass",
    ),
    Case(
        "a massless frame link with an inertia (an exporter's convention)",
        lambda d: _load(arm(extra=FLANGE)),
        None,
        "massless link flange read with no inertia (a rotational inertia without mass is no body",
        warns=InertiaAssumptionWarning,
    ),
    Case(
        "products of inertia in the CAD sign convention",
        lambda d: _load(_l2_inertia(CAD_PRODUCTS)),
        None,
        "products of inertia read with the opposite sign (+integral of x y dm, the CAD convention; "
        "URDF's ixy is -integral of x y dm): as written, link l2 break",
        warns=InertiaAssumptionWarning,
    ),
    Case(
        "a triangle inequality broken by rounding (0.5 %)",
        lambda d: _load(arm(ixx="0.0201")),
        None,
        "link l2 break the triangle inequality by at most 1 % (rounding), taken as given",
        warns=InertiaAssumptionWarning,
    ),
    Case("negative mass", lambda d: _load(arm(mass="-2")), ex.InvalidInertia, "must not be negative"),
    Case(
        "inertia not positive definite",
        lambda d: _load(arm(ixx="-0.001")),
        ex.InvalidInertia,
        "not positive semi-definite",
    ),
    Case(
        "inertia that breaks the triangle inequality",
        lambda d: _load(arm(ixx="0.05")),
        ex.InvalidInertia,
        "1 link with impossible inertial data: 'l2': principal moments "
        "[0.01, 0.01, 0.05] break the triangle inequality I1 + I2 >= I3 by 60 % of I3",
    ),
    Case(
        "two impossible links, named at once",
        lambda d: _load(
            arm(ixx="0.05").replace(
                'ixx="0.001" ixy="0" ixz="0" iyy="0.01"', 'ixx="-0.001" ixy="0" ixz="0" iyy="0.01"'
            )
        ),
        ex.InvalidInertia,
        "2 links with impossible inertial data: 'l1': the inertia is not positive semi-definite",
    ),
    Case(
        "NaN in an inertial origin",
        lambda d: _load(arm().replace('<origin xyz="0.15 0 0"/>', '<origin xyz="nan 0 0"/>')),
        ex.UrdfStructureError,
        "link 'l2' <origin> xyz: 'nan 0 0' is not 3 finite numbers",
    ),
    Case(
        "inertia with only ixx, iyy, izz (the parser would zero it)",
        lambda d: _load(_l2_inertia('ixx="0.001" iyy="0.01" izz="0.01"')),
        ex.InvalidInertia,
        "link 'l2': <inertia> needs all six of ixx, ixy, ixz, iyy, iyz, izz (missing ixy, ixz, iyz",
    ),
    Case(
        "mass of 1e308 kg",
        lambda d: _load(arm(mass="1e308")),
        ex.InvalidInertia,
        "mass 1e+308 kg is beyond any robot link",
    ),
    Case(
        "inertia of 1e300 kg m^2",
        lambda d: _load(_l2_inertia('ixx="0.001" ixy="0" ixz="0" iyy="1e300" iyz="0" izz="1e300"')),
        ex.InvalidInertia,
        "beyond any robot link (at most 100000 kg m^2)",
    ),
    Case(
        "zero joint axis",
        lambda d: _load(arm().replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>', 1)),
        ex.UrdfStructureError,
        "joint 'j1' <axis>: xyz = '0 0 0' is zero",
    ),
    Case(
        "reversed joint limits",
        lambda d: _load(arm().replace('<limit lower="-3" upper="3"', '<limit lower="2" upper="-2"', 1)),
        ex.UrdfStructureError,
        "joint 'j1' <limit>: lower = 2 is above upper = -2",
    ),
    Case(
        "NaN joint limit",
        lambda d: _load(arm().replace('<limit lower="-3"', '<limit lower="nan"', 1)),
        ex.UrdfStructureError,
        "joint 'j1' <limit> lower: 'nan' is not a finite number",
    ),
    Case(
        "revolute joint without <limit>",
        lambda d: _load(arm().replace('<limit lower="-3" upper="3" effort="10" velocity="3"/>', "", 1)),
        ex.UrdfStructureError,
        "joint 'j1': a revolute joint needs <limit",
    ),
    Case(
        "negative joint damping",
        lambda d: _load(_first_axis_then('<dynamics damping="-1"/>')),
        ex.UrdfStructureError,
        "joint 'j1' <dynamics> damping: -1 is outside [0, 1e+07]",
    ),
    Case(
        "unknown joint type",
        lambda d: _load(arm().replace('type="revolute"', 'type="hinge"', 1)),
        ex.UrdfStructureError,
        "joint 'j1': type 'hinge' is not one of revolute",
    ),
    Case(
        "mimic joint left out of the locked joints",
        lambda d: _load(
            arm()
            .replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/><mimic joint="j1"/>', 2)
            .replace('<mimic joint="j1"/>', "", 1),
            locked_joints=[],
        ),
        ex.UrdfStructureError,
        "joint 'j2' mimics joint 'j1': nnrobust does not model mimic joints",
    ),
    Case(
        "moving link with no mass after it",
        lambda d: _load(_l2_inertia(None)),
        ex.InvalidInertia,
        "joint 'j2' moves no mass",
    ),
    Case(
        "value the C++ parser refuses (its message made one line)",
        lambda d: _load(_first_axis_then('<calibration rising="x"/>')),
        ex.RobotLoadError,
        "the parser says: Error: rising value (x) is not a valid float",
    ),
    Case(
        "mass that is not a number",
        lambda d: _load(arm(mass="heavy")),
        ex.UrdfStructureError,
        "'heavy' is not a finite number",
    ),
    Case(
        "entity expansion ('billion laughs')",
        lambda d: _load(BILLION_LAUGHS),
        ex.UrdfRefused,
        "DTD or entity declarations",
    ),
    Case("file larger than 20 MB", lambda d: _load(_huge(d)), ex.UrdfRefused, "larger than the 20 MB"),
    Case(
        "package:// mesh that escapes the allowed folders (simulates; the viewer leaves it out)",
        lambda d: _visual(
            _file(
                d,
                "escape.urdf",
                arm(
                    visual='<visual><geometry><mesh filename="package://../../../../etc/passwd"/></geometry></visual>'
                ),
            )
        ),
        None,
        "1 visual mesh lies outside the folders meshes are read from (first: "
        "'package://../../../../etc/passwd'); the run's dynamics do not need it",
        warns=MeshOutsideFoldersWarning,
    ),
    Case(
        "URDF text with a mesh outside the working folder (read and embedded before)",
        lambda d: _working_in(
            d, _visual(arm(visual='<visual><geometry><mesh filename="/etc/passwd"/></geometry></visual>'))
        ),
        None,
        "1 visual mesh lies outside the folders meshes are read from (first: '/etc/passwd')",
        warns=MeshOutsideFoldersWarning,
    ),
    Case(
        "URDF text with a file:// mesh outside the working folder",
        lambda d: _working_in(
            d,
            _visual(
                arm(visual='<visual><geometry><mesh filename="file:///etc/hostname"/></geometry></visual>')
            ),
        ),
        None,
        "the viewer draws it only from folders listed in robot.mesh_folders",
        warns=MeshOutsideFoldersWarning,
    ),
    Case(
        "mesh fetched over the network",
        lambda d: _visual(
            _file(
                d,
                "http.urdf",
                arm(
                    visual='<visual><geometry><mesh filename="http://example.com/l1.stl"/></geometry></visual>'
                ),
            )
        ),
        None,
        "a URL: only package:// and file paths are read",
        warns=MeshOutsideFoldersWarning,
    ),
    Case(
        "visual mesh file missing (simulates; the viewer leaves it out)",
        lambda d: _visual(
            _file(
                d,
                "nomesh.urdf",
                arm(visual='<visual><geometry><mesh filename="meshes/l1.stl"/></geometry></visual>'),
            )
        ),
        None,
        "not found",
        warns=MissingMeshWarning,
    ),
    Case(
        "undeclared XML namespace prefixes (drake:, gazebo:, as projects publish them)",
        lambda d: _load(_file(d, "prefixed.urdf", PREFIXED)),
        None,
        "prefixed.urdf: undeclared XML namespace prefixes drake, gazebo: their elements and attributes "
        "are ignored",
        warns=UndeclaredPrefixWarning,
    ),
    Case(
        "undeclared prefix, and a mismatched tag further on",
        lambda d: _load(_file(d, "prefixed.urdf", PREFIXED.replace("</gazebo:plugin>", "</plugin>"))),
        ex.UrdfSyntaxError,
        "prefixed.urdf: malformed XML at line 12, column 71: mismatched tag",
    ),
    Case(
        "task frame that does not exist",
        lambda d: _load("three_link_planar", task_frame="gripper"),
        ex.FrameNotFound,
        "task frame 'gripper' not found; frames in the model: universe",
    ),
    Case(
        "robot name that example-robot-data does not ship",
        lambda d: _load("no_such_robot"),
        ex.RobotLoadError,
        "not a URDF file, not planar<N>, and not a robot example-robot-data ships",
    ),
]

PAPER = 'base = "paper-ellipse"\n'
"""An experiment file's first line: start from the paper's case (b)."""

CONFIG_CASES = [
    Case(
        "a TOML date-time in controller.params",
        lambda d: _toml(
            d,
            'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "laws.py:Eq9"\n'
            "params = {Kp = 10.0, Kv = 4.0, when = 1979-05-27T07:32:00Z}\n",
        ),
        ex.ConfigError,
        "experiment.toml: controller.params.when: is a TOML date-time (1979-05-27T07:32:00+00:00), "
        'which no key takes; to pass text, quote it: "1979-05-27T07:32:00+00:00"',
    ),
    Case(
        "a TOML date for a number",
        lambda d: _toml(d, 'base = "paper-ellipse"\n[simulation]\nduration = 1979-05-27\n'),
        ex.ConfigError,
        "experiment.toml: simulation.duration: is a TOML date (1979-05-27), which no key takes",
    ),
    Case(
        "a point-to-point move of 1e-300 s",
        lambda d: _toml(
            d, f"{PAPER}[trajectory]\nkind = 'point_to_point'\ngoal = [0.3, 0.4]\nmove_time = 1e-300\n"
        ),
        ex.ConfigError,
        "trajectory.move_time: must be in [0.001, 1e+09] s, got 1e-300",
    ),
    Case(
        "a base preset with a typo",
        lambda d: _toml(d, 'base = "paper-elipse"\n'),
        ex.ConfigError,
        "experiment.toml: base: unknown preset 'paper-elipse'; did you mean 'paper-ellipse'? presets: ",
    ),
    Case(
        "an integer of 5000 digits (Python reads at most 4300)",
        lambda d: _toml(d, f"{PAPER}[plant]\npayload = {'9' * 5000}\n"),
        ex.ConfigError,
        "experiment.toml: invalid TOML: an integer of 5000 digits (at most 4300 are read, and no key "
        "takes one of more than 19)",
    ),
    Case(
        "a point-to-point move of 1e300 s (its quintic overflowed)",
        lambda d: _toml(
            d, f"{PAPER}[trajectory]\nkind = 'point_to_point'\ngoal = [0.3, 0.4]\nmove_time = 1e300\n"
        ),
        ex.ConfigError,
        "trajectory.move_time: must be in [0.001, 1e+09] s, got 1e+300",
    ),
    Case(
        "a rotation axis of [1e-320, 0, 0] (no length to normalise)",
        lambda d: _toml(d, 'base = "panda-pose"\n[trajectory]\nrotation_axis = [1e-320, 0.0, 0.0]\n'),
        ex.ConfigError,
        "trajectory.rotation_axis: [9.99989e-321, 0, 0] is too short to give a direction "
        "(length below 1e-09)",
    ),
    Case(
        "waypoint times 1e-300 s apart",
        lambda d: _toml(
            d,
            f"{PAPER}[trajectory]\nkind = 'waypoints'\nwaypoints = [[0.3, 0.4], [0.3, 0.5]]\n"
            "waypoint_times = [0.0, 1e-300]\n",
        ),
        ex.ConfigError,
        "trajectory.waypoint_times: must start at 0 or later and increase by at least 0.001 s",
    ),
    Case(
        "a goal at 1e308 m",
        lambda d: _toml(d, f"{PAPER}[trajectory]\nkind = 'point_to_point'\ngoal = [1e308, 0.4]\n"),
        ex.ConfigError,
        "trajectory.goal: [1e+308, 0.4] has a coordinate beyond 1000 m",
    ),
    Case(
        "an ellipse at omega = 1e300 rad/s",
        lambda d: _toml(d, f"{PAPER}[trajectory]\nomega = 1e300\n"),
        ex.ConfigError,
        "trajectory.omega: 1e+300 rad/s is beyond 10000 rad/s",
    ),
    Case(
        "a rocking amplitude of 1e300 rad",
        lambda d: _toml(d, f"{PAPER}[trajectory]\nrotation_amplitude = 1e300\n"),
        ex.ConfigError,
        "trajectory.rotation_amplitude: 1e+300 rad is more than half a turn",
    ),
    Case(
        "experiment file that does not exist",
        lambda d: _read_config(d / "missing.toml"),
        ex.ConfigError,
        "cannot read the file",
    ),
    Case("invalid TOML", lambda d: _toml(d, "[controller\nKp = 1"), ex.ConfigError, "invalid TOML"),
    Case(
        "unknown key (with a suggestion)",
        lambda d: _toml(d, "[controller]\nKpp = [10.0]\n"),
        ex.ConfigError,
        "controller.Kpp: unknown key; did you mean 'Kp'?",
    ),
    Case(
        "unknown section",
        lambda d: _toml(d, "[controler]\nkind = 'nn'\n"),
        ex.ConfigError,
        "did you mean 'controller'?",
    ),
    Case(
        "wrong type",
        lambda d: _toml(d, "[controller]\nk = 'ten'\n"),
        ex.ConfigError,
        "controller.k: expected a number, got str 'ten'",
    ),
    Case(
        "non-finite number",
        lambda d: _toml(d, "[controller]\nk = inf\n"),
        ex.ConfigError,
        "expected a finite number",
    ),
    Case(
        "negative gain",
        lambda d: _toml(d, "[controller]\nKp = [-10.0, 10.0]\n"),
        ex.ConfigError,
        "controller.Kp: -10 is outside (0, 1e+12] 1/s^2",
    ),
    Case(
        "Kv^2 <= Kp (Q not positive definite)",
        lambda d: _toml(d, "[controller]\nKp = [20.0]\nKv = [4.0]\n"),
        ex.ConfigError,
        "Kv^2 = 16 must exceed Kp = 20",
    ),
    Case(
        "zero control period",
        lambda d: _toml(d, "[simulation]\ncontrol_period = 0.0\n"),
        ex.ConfigError,
        "simulation.control_period: must be positive",
    ),
    Case(
        "no integration step per control period (substeps = 0)",
        lambda d: _toml(d, "[simulation]\nsubsteps = 0\n"),
        ex.ConfigError,
        "simulation.substeps: must be positive",
    ),
    Case(
        "no rotation allowed per plant step (max_step_rotation = 0)",
        lambda d: _toml(d, "[simulation]\nmax_step_rotation = 0.0\n"),
        ex.ConfigError,
        "simulation.max_step_rotation: must be at least 1e-06 rad (or m), got 0; to keep",
    ),
    Case(
        "a plant step allowed to turn 1e-300 rad (every period cut to the most steps)",
        lambda d: _toml(d, "[simulation]\nmax_step_rotation = 1e-300\n"),
        ex.ConfigError,
        "simulation.max_step_rotation: must be at least 1e-06 rad (or m), got 1e-300",
    ),
    Case(
        "a sensing delay as long as the run",
        lambda d: _toml(d, "[simulation]\nduration = 0.1\n[sensing]\ndelay = 100000000\n"),
        ex.ConfigError,
        "sensing.delay: 100000000 control periods is the whole run (0.1 s) or more",
    ),
    Case(
        "an NN basis width of 1e-308 (the loops would disagree)",
        lambda d: _toml(d, "[nn]\nwidth = 1e-308\n"),
        ex.ConfigError,
        "nn.width: 1e-308 is outside [1e-09, 1e+09]",
    ),
    Case(
        "an initial task offset of 1e308 m",
        lambda d: _toml(d, "[simulation]\ninitial_task_offset = [1e308, 0.0]\n"),
        ex.ConfigError,
        "simulation.initial_task_offset: [1e+308, 0.0] has an entry beyond 1000 m",
    ),
    Case(
        "control period shorter than the integration step",
        lambda d: _toml(d, "[simulation]\ncontrol_period = 0.001\nintegration_step = 0.002\n"),
        ex.ConfigError,
        "simulation.integration_step: 0.002 s is longer than the control period",
    ),
    Case(
        "control period not a whole number of integration steps",
        lambda d: _toml(d, "[simulation]\ncontrol_period = 0.001\nintegration_step = 0.0003\n"),
        ex.ConfigError,
        "is not a whole number of steps",
    ),
    Case(
        "duration shorter than one control period",
        lambda d: _toml(d, "[simulation]\nduration = 0.0005\n"),
        ex.ConfigError,
        "shorter than one control period",
    ),
    Case(
        "weights that do not sum to C",
        lambda d: _toml(
            d, "[subtasks]\ncriteria = ['manipulability', 'joint_centering']\nweights = [1.0, 1.0]\nC = 1.0\n"
        ),
        ex.ConfigError,
        "sum to 2 but subtasks.C = 1",
    ),
    Case(
        "unknown choice",
        lambda d: _toml(d, "[nn]\nlaw = 'fast'\n"),
        ex.ConfigError,
        "nn.law: expected one of 'corrected', 'printed', got 'fast'",
    ),
    Case(
        "gain vector of the wrong length",
        lambda d: _toml(d, "[controller]\nKp = [1.0, 2.0, 3.0]\n"),
        ex.ConfigError,
        "controller.Kp: has 3 entries, the task has m = 2",
    ),
    Case(
        "initial joint angle outside the limits",
        lambda d: _build(simulation={"q_seed": [0.2, 4.0, 1.0]}),
        ex.ConfigError,
        "simulation.q_seed: joint 'joint2' = 4 is outside its limits [-2.8, 2.8]",
    ),
    Case(
        "start point out of reach",
        lambda d: _build(trajectory={"center": [1.5, 0.4]}),
        ex.ConfigError,
        "is out of reach from q_seed",
    ),
    Case(
        "trajectory that leaves the workspace later",
        lambda d: _build(trajectory={"axis_b": [0.0, 0.8]}),
        ex.ConfigError,
        "trajectory: leaves the workspace: at t =",
    ),
    Case(
        "criterion for another arm",
        lambda d: _build(
            robot={"source": "planar7"}, plant={"disturbance": "none"}, nominal={"kind": "urdf"}
        ),
        ex.ConfigError,
        "'paper' (eq. 19) is for 3 joints",
    ),
    Case(
        "viscous friction too stiff for the RK4 step (substeps = 1 set)",
        lambda d: _build(
            "planar7-ellipse",
            robot={"source": "planar15"},
            simulation={"q_seed": [0.9] + [-0.1] * 14, "substeps": 1},
        ),
        ex.ConfigError,
        "simulation.substeps: viscous friction makes the dynamics stiff",
    ),
    Case(
        "viscous friction too stiff for the RK4 step (substeps unset: chosen)",
        lambda d: _build(
            "planar7-ellipse", robot={"source": "planar15"}, simulation={"q_seed": [0.9] + [-0.1] * 14}
        ),
        None,
        "simulation.substeps = 2 chosen (plant step 0.0005 s)",
        warns=UserWarning,
    ),
    Case(
        "joint stops too stiff for the RK4 step (substeps = 1 set)",
        lambda d: _build(plant={"joint_stop_stiffness": 1e6}, simulation={"substeps": 1}),
        ex.ConfigError,
        "plant.joint_stop_stiffness: the stop of joint",
    ),
    Case(
        "joint stops too stiff for the RK4 step (substeps unset: the stops are sized)",
        lambda d: _build(plant={"joint_stop_stiffness": 1e6}),
        None,
        "joint stops sized to the plant step: the stops of 'joint1'",
        warns=UserWarning,
    ),
    Case(
        "unknown torque-limit choice",
        lambda d: _toml(d, "[plant]\ntorque_limits = 'max'\n"),
        ex.ConfigError,
        "plant.torque_limits: 'max' is not one of urdf, none",
    ),
    Case(
        "torque limit of the wrong type",
        lambda d: _toml(d, "[plant]\ntorque_limits = 60\n"),
        ex.ConfigError,
        "plant.torque_limits: expected a string or a list, got int 60",
    ),
    Case(
        "torque limits, one per joint, of the wrong length",
        lambda d: _build(plant={"torque_limits": [60.0, 40.0]}),
        ex.ConfigError,
        "plant.torque_limits: has 2 entries, the robot has 3 joints",
    ),
    Case(
        "zero torque limit",
        lambda d: _toml(d, "[plant]\ntorque_limits = [60.0, 0.0, 20.0]\n"),
        ex.ConfigError,
        "plant.torque_limits: must be positive",
    ),
    Case(
        "negative sensor noise",
        lambda d: _toml(d, "[sensing]\nposition_noise = [-1e-3]\n"),
        ex.ConfigError,
        "sensing.position_noise: needs one value for all joints or one per joint",
    ),
    Case(
        "negative delay",
        lambda d: _toml(d, "[sensing]\ndelay = -1\n"),
        ex.ConfigError,
        "sensing.delay: must be >= 0 control periods",
    ),
    Case(
        "negative seed",
        lambda d: _toml(d, "[sensing]\nseed = -3\n"),
        ex.ConfigError,
        "sensing.seed: must be an integer in [0, 2^63)",
    ),
    Case(
        "gravity with two entries",
        lambda d: _toml(d, "[robot]\ngravity = [0.0, -9.81]\n"),
        ex.ConfigError,
        "robot.gravity: needs 3 entries",
    ),
    Case(
        "mesh folder that is the filesystem root",
        lambda d: _toml(d, '[robot]\nmesh_folders = ["meshes", "../../../../../../../../../.."]\n'),
        ex.ConfigError,
        "robot.mesh_folders: '/' is not a folder to read meshes from: name the folders that hold the "
        'URDF\'s meshes (e.g. ["../meshes"]), never the filesystem root',
    ),
    Case(
        "400-digit integer",
        lambda d: _toml(d, "[sensing]\nseed = " + "9" * 400 + "\n"),
        ex.ConfigError,
        "sensing.seed: expected an integer in (-2^63, 2^63), got one of 400 digits",
    ),
    Case(
        "400-digit integer for a number",
        lambda d: _toml(d, "[controller]\nk = " + "9" * 400 + "\n"),
        ex.ConfigError,
        "controller.k: expected a finite number of sensible size",
    ),
    Case(
        "TOML nested 5000 deep",
        lambda d: _toml(d, "x = " + "[" * 5000 + "]" * 5000 + "\n"),
        ex.ConfigError,
        "invalid TOML: nested too deeply",
    ),
    Case(
        "experiment file that is a device (/dev/zero)",
        lambda d: _read_config(Path("/dev/zero")),
        ex.ConfigError,
        "/dev/zero: not a regular file",
    ),
    Case(
        "experiment file that is a FIFO",
        lambda d: _read_config(_fifo(d)),
        ex.ConfigError,
        "not a regular file",
    ),
    Case(
        "experiment file over 1 MB",
        lambda d: _toml(d, "# padding\n" * 200_000),
        ex.ConfigError,
        "larger than 1000 kB, the most read for an experiment file",
    ),
    Case(
        "name with a control character",
        lambda d: _toml(d, 'name = "run\\u001b[2J"\n'),
        ex.ConfigError,
        "name: 'run\\x1b[2J' is not a valid name",
    ),
    Case(
        "name that climbs out of out/",
        lambda d: _toml(d, 'name = "../../escape"\n'),
        ex.ConfigError,
        "name: '../../escape' is not a valid name",
    ),
    Case(
        "closed-form nominal model with a URDF perturbation",
        lambda d: _toml(d, "[nominal]\nkind = 'closed-form'\nmass_scale = 1.1\n"),
        ex.ConfigError,
        "nominal.kind: mass_scale, inertia_scale and com_error perturb the URDF model",
    ),
    Case(
        "negative friction scale",
        lambda d: _toml(d, "[plant]\nfriction_scale = -1.0\n"),
        ex.ConfigError,
        "plant.friction_scale: must be in [0, 100], got -1",
    ),
    Case(
        "a per-joint friction scale below zero",
        lambda d: _toml(d, "[plant]\njoint_friction_scales = [1.0, -0.5]\n"),
        ex.ConfigError,
        "plant.joint_friction_scales: each factor must be in [0, 100]",
    ),
    Case(
        "more per-joint disturbance scales than joints",
        lambda d: _build(plant={"joint_disturbance_scales": [1.0, 1.0, 1.0, 1.0]}),
        ex.ConfigError,
        "plant.joint_disturbance_scales: has 4 entries; the robot has 3 joints",
    ),
    Case(
        "a negative payload",
        lambda d: _toml(d, "[plant]\npayload = -1.0\n"),
        ex.ConfigError,
        "plant.payload: must be in [0, 1000] kg, got -1",
    ),
    Case(
        "a disturbance frequency scale of zero",
        lambda d: _toml(d, "[plant]\ndisturbance_omega_scale = 0.0\n"),
        ex.ConfigError,
        "plant.disturbance_omega_scale: must be in (0, 100]",
    ),
    Case(
        "static friction below the Coulomb level",
        lambda d: _toml(d, "[plant]\nstiction = 0.5\n"),
        ex.ConfigError,
        "plant.stiction: the static / Coulomb friction ratio must be in [1, 1e6)",
    ),
    Case(
        "plant engine that does not exist",
        lambda d: _toml(d, "[plant]\nengine = 'bullet'\n"),
        ex.ConfigError,
        "plant.engine: 'bullet' is not one of pinocchio, mujoco",
    ),
    Case(
        "MuJoCo integrator that does not exist",
        lambda d: _toml(d, "[plant]\nmujoco_integrator = 'verlet'\n"),
        ex.ConfigError,
        "plant.mujoco_integrator: 'verlet' is not one of rk4, implicitfast, euler",
    ),
    Case(
        "static friction on MuJoCo (one friction level)",
        lambda d: _build(plant={"engine": "mujoco", "stiction": 1.5}),
        ex.ConfigError,
        "plant.stiction: MuJoCo's frictionloss has one level",
    ),
    Case(
        "negative armature",
        lambda d: _toml(d, "[plant]\narmature = [-0.1]\n"),
        ex.ConfigError,
        "plant.armature: needs one value for all joints or one per joint, each in [0, 1e6)",
    ),
    Case(
        "substeps beyond any need",
        lambda d: _toml(d, "[simulation]\nsubsteps = 100000\n"),
        ex.ConfigError,
        "simulation.substeps: 100000 integration steps per control period; at most 10000",
    ),
    Case(
        "control rate of a terahertz",
        lambda d: _toml(d, "[simulation]\ncontrol_period = 1e-12\n"),
        ex.ConfigError,
        "simulation.duration: 20 s at a control period of 1e-12 s is 2e+13 steps",
    ),
    Case(
        "basis of a million centres",
        lambda d: _toml(d, "[nn]\ncenters = 1000000\n"),
        ex.ConfigError,
        "nn.centers: 1000000 is outside [1, 1000]",
    ),
    Case(
        "run that needs more memory than simulation.memory_limit",
        lambda d: _build(simulation={"duration": 1e5}),
        ex.ConfigError,
        "simulation.memory_limit: this run needs about 211 GB",
    ),
]


def _fifo(folder: Path) -> Path:
    import os

    path = folder / "pipe.toml"
    os.mkfifo(path)
    return path


def _check_out(folder: Path, overwrite: bool = False):
    from nnrobust.outputs.run_folder import check_out_folder

    return lambda: check_out_folder(folder, overwrite)


def _user_folder(folder: Path) -> Path:
    path = folder / "mine"
    path.mkdir()
    (path / "notes.txt").write_text("my notes")
    return path


def _symlink(folder: Path) -> Path:
    (folder / "real").mkdir()
    (folder / "link").symlink_to(folder / "real")
    return folder / "link"


def _locked_twice(folder: Path):
    from nnrobust.outputs.run_folder import locked

    def action():
        with locked(folder / "run"), locked(folder / "run"):
            pass

    return action


def _damaged_run(folder: Path, damage: str):
    """A run folder written by a short run, then damaged; the action reads it back."""
    import numpy as np

    from nnrobust.config.presets import load_preset
    from nnrobust.outputs.run_folder import load_run, write_run
    from nnrobust.run.experiment import run_experiment

    run = folder / damage
    write_run(
        run,
        run_experiment(load_preset("paper-line").replace(simulation={"duration": 0.05})),
        plots=False,
        animation=False,
    )
    if damage == "truncated":
        data = (run / "result.npz").read_bytes()
        (run / "result.npz").write_bytes(data[: len(data) // 2])
    elif damage == "garbled":
        (run / "metrics.json").write_text("{not json")
    elif damage == "fifo":
        (run / "config.toml").unlink()
        os.mkfifo(run / "config.toml")
    elif damage == "zero":
        (run / "metrics.json").unlink()
        (run / "metrics.json").symlink_to("/dev/zero")
    elif damage == "bomb":  # a member whose central directory says it expands to 4.29 GB
        import zipfile

        with zipfile.ZipFile(run / "result.npz", "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("t.npy", bytes(1 << 16))
        data = bytearray((run / "result.npz").read_bytes())
        entry = data.rindex(b"PK\x01\x02")  # the central directory record; its size field at +24
        data[entry + 24 : entry + 28] = (0xFFFFFFF0).to_bytes(4, "little")
        (run / "result.npz").write_bytes(bytes(data))
    elif damage == "claims":  # t.npy's header claims 10^13 samples (80 TB); 64 bytes follow it
        import io
        import zipfile

        header = io.BytesIO()
        np.lib.format.write_array_header_1_0(
            header, {"descr": "<f8", "fortran_order": False, "shape": (10**13,)}
        )
        with zipfile.ZipFile(run / "result.npz") as archive:
            members = {name: archive.read(name) for name in archive.namelist()}
        members["t.npy"] = header.getvalue() + bytes(64)
        with zipfile.ZipFile(run / "result.npz", "w") as archive:
            for name, data in members.items():
                archive.writestr(name, data)
    elif damage == "shape":
        arrays = dict(np.load(run / "result.npz"))
        arrays["q"] = arrays["q"][:-1]
        np.savez(run / "result.npz", **arrays)
    elif damage in ("text", "complex"):
        arrays = dict(np.load(run / "result.npz"))
        arrays["t"] = arrays["t"].astype(str if damage == "text" else complex)
        np.savez(run / "result.npz", **arrays)
    elif damage == "deep":
        (run / "metrics.json").write_text("[" * 200_000 + "]" * 200_000)
    elif damage == "string":
        metrics = json.loads((run / "metrics.json").read_text())
        metrics["rms_error"] = "small"
        (run / "metrics.json").write_text(json.dumps(metrics))
    else:
        np.savez(run / "result.npz", t=np.array([object()], dtype=object))
    return lambda: load_run(run)


def _viewer(host: str = "127.0.0.1", port: int | None = None):
    from nnrobust.outputs.viewer.server import check_listen_address

    return lambda: check_listen_address(host, port)


VIEWER_CASES = [
    Case(
        "viewer --port 0", lambda d: _viewer(port=0), ex.NNRobustError, "--port 0: a TCP port is 1 to 65535"
    ),
    Case(
        "viewer --port 99999",
        lambda d: _viewer(port=99999),
        ex.NNRobustError,
        "--port 99999: a TCP port is 1 to 65535",
    ),
    Case(
        "viewer --host that does not resolve",
        lambda d: _viewer("no-such-host.invalid"),
        ex.NNRobustError,
        "--host 'no-such-host.invalid' is not an address or host name this machine can resolve",
    ),
    Case(
        "viewer --host of another machine",
        lambda d: _viewer("203.0.113.1", 7999),
        ex.NNRobustError,
        "the viewer cannot listen on 203.0.113.1:7999",
    ),
]

RUN_FOLDER_CASES = [
    Case(
        "--out naming a file",
        lambda d: _check_out(_file(d, "taken", "x")),
        RunFolderError,
        "taken exists and is not a folder",
    ),
    Case(
        "--out naming a symbolic link",
        lambda d: _check_out(_symlink(d)),
        RunFolderError,
        "link is a symbolic link",
    ),
    Case("--out .", lambda d: _check_out(Path(".")), RunFolderError, "not '.' or '..'"),
    Case(
        "--out inside a file",
        lambda d: _check_out(_file(d, "plain", "x") / "run"),
        RunFolderError,
        "plain is a file, not a folder",
    ),
    Case(
        "existing run folder without --overwrite",
        lambda d: _check_out(_file(d, "old", "x").parent),
        ex.RunFolderExists,
        "exists; pass --overwrite",
    ),
    Case(
        "--overwrite on a folder of the user's",
        lambda d: _check_out(_user_folder(d), True),
        RunFolderError,
        "mine is not a run folder (no .nnrobust-run)",
    ),
    Case(
        "a second run into a folder another run is writing",
        _locked_twice,
        RunFolderError,
        "another nnrobust run (pid ",
    ),
    Case(
        "truncated result.npz",
        lambda d: _damaged_run(d, "truncated"),
        RunFolderError,
        "a damaged run folder (result.npz is not an .npz archive: File is not a zip file)",
    ),
    Case(
        "garbled metrics.json",
        lambda d: _damaged_run(d, "garbled"),
        RunFolderError,
        "a damaged run folder (metrics.json cannot be read",
    ),
    Case(
        "object array in result.npz (would need unpickling)",
        lambda d: _damaged_run(d, "pickled"),
        RunFolderError,
        "a damaged run folder (result.npz: t.npy holds Python objects, which are never unpickled)",
    ),
    Case(
        "a received run whose config.toml is a FIFO",
        lambda d: _damaged_run(d, "fifo"),
        RunFolderError,
        "config.toml is not a regular file; a run folder holds regular files",
    ),
    Case(
        "a received run whose metrics.json links to /dev/zero",
        lambda d: _damaged_run(d, "zero"),
        RunFolderError,
        "metrics.json is a symbolic link; a run folder holds regular files",
    ),
    Case(
        "a zip bomb as result.npz (a few kB said to expand to 4.29 GB)",
        lambda d: _damaged_run(d, "bomb"),
        RunFolderError,
        "result.npz would expand to 4.29 GB; at most 4 GB is read",
    ),
    Case(
        "q shorter than t",
        lambda d: _damaged_run(d, "shape"),
        RunFolderError,
        "a damaged run folder (result.npz: q has shape",
    ),
    Case(
        "an array header claiming 80 TB (numpy would allocate it before reading)",
        lambda d: _damaged_run(d, "claims"),
        RunFolderError,
        "a damaged run folder (result.npz: t.npy's header claims shape (10000000000000,) of float64, "
        "8e+04 GB, but holds 64 bytes)",
    ),
    Case(
        "t saved as text",
        lambda d: _damaged_run(d, "text"),
        RunFolderError,
        "a damaged run folder (result.npz: t holds <U",
    ),
    Case(
        "t saved as complex numbers",
        lambda d: _damaged_run(d, "complex"),
        RunFolderError,
        "a damaged run folder (result.npz: t holds complex128 values, not real numbers)",
    ),
    Case(
        "metrics.json nested 200,000 deep",
        lambda d: _damaged_run(d, "deep"),
        RunFolderError,
        "metrics.json is nested too deeply",
    ),
    Case(
        "a string where metrics.json holds a number",
        lambda d: _damaged_run(d, "string"),
        RunFolderError,
        "metrics.json: rms_error is str 'small', not a number",
    ),
]


def _tune(folder: Path, *args: str, **kwargs):
    """nnrobust tune's checks, as the command line calls them (nothing runs: each is refused first)."""

    def run():
        from nnrobust.studies.tune import TuneSpec, run_tune

        return run_tune(TuneSpec(*args, **kwargs), folder / "tuning", workers=1)

    return run


def _tune_into(folder: Path, make) -> Callable[[], object]:
    """A tuning into a folder ``make`` prepares."""

    def run():
        from nnrobust.studies.tune import TuneSpec, run_tune

        return run_tune(TuneSpec("paper-ellipse", ["pd"], 4), make(folder), workers=1)

    return run


def _grid_sweep(folder: Path) -> str:
    return str(
        _file(
            folder,
            "grid.toml",
            'name = "g"\nbase = "paper-ellipse"\ncontrollers = ["pd"]\n'
            '[vary]\n"plant.friction_scale" = [0.5, 2.0]\n',
        )
    )


def _user_folder_for_tune(folder: Path) -> Path:
    (folder / "my-study").mkdir(exist_ok=True)
    (folder / "my-study" / "notes.md").write_text("mine")
    return folder / "my-study"


TUNE_CASES = [
    Case(
        "tune: a budget of 0",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 0),
        ex.ConfigError,
        "--budget: must be an integer in [2, 100000]",
    ),
    Case(
        "tune: a budget of 10^9",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 10**9),
        ex.ConfigError,
        "--budget: must be an integer in [2, 100000]",
    ),
    Case(
        "tune: an unknown controller",
        lambda d: _tune(d, "paper-ellipse", ["lqr"], 10),
        ex.ConfigError,
        "--controllers: 'lqr' is not one of nn, sliding-mode, no-u0, computed-torque, pd, ",
    ),
    Case(
        "tune: a class without a search space",
        lambda d: _tune(d, "paper-ellipse", [f"{LAWS}:Counter"], 10),
        ex.ConfigError,
        "--controllers Counter: Counter declares no search space",
    ),
    Case(
        "tune: a controller named twice",
        lambda d: _tune(d, "paper-ellipse", ["pd", "pd"], 10),
        ex.ConfigError,
        "--controllers: needs distinct names",
    ),
    Case(
        "tune: a NaN torque limit",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 10, max_rms_torque=float("nan")),
        ex.ConfigError,
        "--max-rms-torque: must be > 0 [N m]",
    ),
    Case(
        "tune: a saturated fraction above 1",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 10, max_saturated=2.0),
        ex.ConfigError,
        "--max-saturated: must be in [0, 1]",
    ),
    Case(
        "tune: fewer simulations than training samples",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 3, train_samples=4),
        ex.ConfigError,
        "--budget: 3 simulations cannot run one setting on 4 training samples",
    ),
    Case(
        "tune: a sweep file with a grid",
        lambda d: _tune(d, _grid_sweep(d), ["pd"], 10),
        ex.ConfigError,
        "tuning draws its samples from [vary] distributions",
    ),
    Case(
        "tune: --out a folder of the user's",
        lambda d: _tune_into(d, _user_folder_for_tune),
        ex.NNRobustError,
        "my-study exists and is not a tuning folder (no .nnrobust-tune); choose another --out",
    ),
    Case(
        "tune (sweep, falsify): --out inside a file",
        lambda d: _tune_into(d, lambda f: _file(f, "plain-file", "x") / "study"),
        ex.NNRobustError,
        "plain-file is a file, not a folder; choose another --out",
    ),
]

LAWS = Path(__file__).parent / "controllers" / "eq9_again.py"


def _custom(folder: Path, cls: str, params: str = "", duration: float = 0.1) -> ReadConfig:
    """An experiment file with a custom controller from a copy of tests/controllers/eq9_again.py."""
    (folder / "laws.py").write_text(LAWS.read_text())
    return _toml(
        folder,
        f'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "laws.py:{cls}"\n'
        f"{params}\n[simulation]\nduration = {duration}\n",
    )


class RunExperiment(ReadConfig):
    """Read an experiment file and run it."""

    def __call__(self):
        from nnrobust.run.experiment import run_experiment

        return run_experiment(super().__call__())


def _custom_run(folder: Path, cls: str, params: str = "", duration: float = 0.1) -> RunExperiment:
    return RunExperiment(_custom(folder, cls, params, duration).path)


def _late(breach: str) -> str:
    return f'[controller.params]\nbreach = "{breach}"'


CUSTOM_CASES = [
    Case(
        "custom: no class",
        lambda d: _toml(d, 'base = "paper-ellipse"\n[controller]\nkind = "custom"\n'),
        ex.ConfigError,
        "controller.class: kind = 'custom' needs the class",
    ),
    Case(
        "custom: class with a built-in kind",
        lambda d: _toml(d, 'base = "paper-ellipse"\n[controller]\nclass = "laws.py:Eq9"\n'),
        ex.ConfigError,
        "controller.class: is read only with kind = 'custom' (kind is 'nn')",
    ),
    Case(
        "custom: a file that is not there",
        lambda d: RunExperiment(
            _toml(d, 'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "nope.py:Eq9"\n').path
        ),
        ex.ConfigError,
        "nope.py' is not a file",
    ),
    Case(
        "custom: a class not in the file",
        lambda d: _custom_run(d, "Eq"),
        ex.ConfigError,
        "has no 'Eq'; did you mean 'Eq9'?",
    ),
    Case(
        "custom: not a Controller",
        lambda d: _custom_run(d, "NotAController"),
        ex.ConfigError,
        "is not a subclass of nnrobust.Controller",
    ),
    Case(
        "custom: compute not implemented",
        lambda d: _custom_run(d, "Abstract"),
        ex.ConfigError,
        "does not implement compute",
    ),
    Case(
        "custom: an unknown parameter",
        lambda d: _custom_run(d, "Eq9", "[controller.params]\nKp = 1.0\nKvv = 2.0"),
        ex.ConfigError,
        "controller.params.Kvv: Eq9 takes no such parameter; did you mean 'Kv'?",
    ),
    Case(
        "custom: a missing parameter",
        lambda d: _custom_run(d, "Eq9", "[controller.params]\nKp = 1.0"),
        ex.ConfigError,
        "controller.params: Eq9 needs Kv",
    ),
    Case(
        "custom: the constructor refuses a value",
        lambda d: _custom_run(d, "NeedsGain", "[controller.params]\ngain = -1.0"),
        ex.ConfigError,
        "NeedsGain(context, **params) raised ValueError: gain must be >= 0, got -1.0 (laws.py, line",
    ),
    Case(
        "custom: an undeclared signal",
        lambda d: _custom_run(d, "Undeclared"),
        ex.ControllerError,
        "returned signal 'surprise', which is not in its signal_names",
    ),
    Case(
        "custom: a torque of the wrong size",
        lambda d: _custom_run(d, "WrongShape"),
        ex.ControllerError,
        "returned a torque of shape (4,) at t = 0 s; the arm has 3 joints",
    ),
    Case(
        "custom: an exception in compute",
        lambda d: _custom_run(d, "Raises"),
        ex.ControllerError,
        "Raises.compute raised at t = 0.011 s: IndexError: list index out of range (laws.py, line",
    ),
    Case(
        "custom: compute ends the process (sys.exit)",
        lambda d: _custom_run(d, "Exits"),
        ex.ControllerError,
        "Exits.compute raised at t = 0.011 s: SystemExit: 0 (laws.py, line",
    ),
    Case(
        "custom: a scalar torque after the first step",
        lambda d: _custom_run(d, "LateBreach", _late("scalar")),
        ex.ControllerError,
        "LateBreach.compute returned a torque of shape () at t = 0.051 s; the arm has 3 joints",
    ),
    Case(
        "custom: a tuple instead of a ControlOutput after the first step",
        lambda d: _custom_run(d, "LateBreach", _late("tuple")),
        ex.ControllerError,
        "LateBreach.compute must return a ControlOutput, got tuple at t = 0.051 s",
    ),
    Case(
        "custom: a signal that is not a number after the first step",
        lambda d: _custom_run(d, "LateBreach", _late("signal")),
        ex.ControllerError,
        "LateBreach.compute returned signal 'elapsed' = 'soon' at t = 0.051 s; a signal is one number",
    ),
    Case(
        "custom: a state whose record passes simulation.memory_limit",
        lambda d: _custom_run(d, "BigState", duration=20.0),
        ex.ConfigError,
        "simulation.memory_limit: this run needs about 96 GB (20 s at 0.001 s per step, 3 joints, a state "
        "of 200000 and 1 signals per step)",
    ),
    Case(
        "custom: a signal named like one every run records",
        lambda d: _custom_run(d, "NamesH"),
        ex.ConfigError,
        "controller.class: NamesH.signal_names: 'h' is a signal every run records itself (h, manipulability)",
    ),
    Case(
        "custom: a signal name that is a path",
        lambda d: _custom_run(d, "NamesAPath"),
        ex.ConfigError,
        "controller.class: NamesAPath.signal_names: '../../../evil' is not a signal name",
    ),
    Case(
        "custom: a state no run could hold",
        lambda d: _custom_run(d, "HugeState"),
        ex.ConfigError,
        "controller.class: HugeState.state_size must be a whole number in [0, 1e+07], got 1000000000",
    ),
]


PARTS = Path(__file__).parent / "parts" / "again.py"


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


def _require(*texts: str):
    def check():
        from nnrobust.run.properties import run_properties

        return run_properties(list(texts))

    return check


def _claim(epsilon, beta, failures=0):
    def check():
        from nnrobust.run.properties import samples_needed

        return samples_needed(epsilon, beta, failures)

    return check


def _mutated(change):
    def run():
        from nnrobust.config.presets import load_preset
        from nnrobust.run.experiment import build

        config = load_preset("paper-ellipse")
        change(config)
        return build(config)

    return run


def _scheduler(address: str):
    def check():
        from nnrobust.studies.base.cluster import check_scheduler

        return check_scheduler(address)

    return check


def _workers(count: int):
    def check():
        from nnrobust.studies.base.cluster import cluster_client as _client

        with _client(count, None):
            pass

    return check


SCHEDULER_CASES = [
    Case(
        "--scheduler 'not a url'",
        lambda d: _scheduler("not a url"),
        ex.NNRobustError,
        "--scheduler 'not a url': not a dask scheduler's address; give tcp://HOST:PORT",
    ),
    Case(
        "--scheduler with TLS",
        lambda d: _scheduler("tls://127.0.0.1:8786"),
        ex.NNRobustError,
        "tls:// is not supported (a TLS cluster needs dask's security settings",
    ),
    Case(
        "--scheduler at a refused port",
        lambda d: _scheduler("tcp://127.0.0.1:1"),
        ex.NNRobustError,
        "--scheduler tcp://127.0.0.1:1: cannot connect (Connection refused)",
    ),
    Case(
        "--workers -1", lambda d: _workers(-1), ex.NNRobustError, "--workers -1: give at least 1 local worker"
    ),
]


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

PROPERTY_CASES = [
    Case(
        "--require: a property of the machine, not the run",
        lambda d: _require("wall_seconds<=0.01"),
        ex.ConfigError,
        "wall_seconds measures the machine and its load, not the controller",
    ),
    Case(
        "--require: not an expression",
        lambda d: _require("rms_error < 0.05 mm"),
        ex.ConfigError,
        "is not METRIC OP VALUE with OP one of <= >= == != < >",
    ),
    Case(
        "--require: an unknown metric",
        lambda d: _require("rms_eror_after_2s<=0.05"),
        ex.ConfigError,
        "no metric 'rms_eror_after_2s'; did you mean 'rms_error_after_2s'?",
    ),
    Case(
        "--require: a NaN bound",
        lambda d: _require("rms_error<=nan"),
        ex.ConfigError,
        "the bound must be a finite number, got nan",
    ),
    Case(
        "--require: a flag compared by size",
        lambda d: _require("runaway<=1"),
        ex.ConfigError,
        "runaway is true or false: compare it with == or != to true or false",
    ),
    Case(
        "--epsilon of 0",
        lambda d: _claim(0.0, 0.05),
        ex.ConfigError,
        "--epsilon: must be a probability in (0, 1)",
    ),
    Case(
        "--beta of 1", lambda d: _claim(0.05, 1.0), ex.ConfigError, "--beta: must be a probability in (0, 1)"
    ),
    Case(
        "--failures of 10^9",
        lambda d: _claim(0.05, 0.05, 10**9),
        ex.ConfigError,
        "--failures: must be an integer in [0, 10000]",
    ),
    Case(
        "--epsilon of 1e-300",
        lambda d: _claim(1e-300, 0.05),
        ex.ConfigError,
        "--epsilon: P(fail) <= 1e-300 with confidence 0.95 needs more than 1,000,000 samples",
    ),
    Case(
        "--epsilon 1e-6 with --failures 10000",
        lambda d: _claim(1e-6, 0.05, 10_000),
        ex.ConfigError,
        "give --epsilon >= 0.0102 or fewer --failures",
    ),
    Case(
        "--epsilon of 0.9999999",
        lambda d: _claim(0.9999999, 0.05),
        ex.ConfigError,
        "--epsilon: P(fail) <= 0.9999999 says next to nothing",
    ),
    Case(
        "--beta of 1e-300",
        lambda d: _claim(0.05, 1e-300),
        ex.ConfigError,
        "--beta: 1e-300 asks a confidence closer to 1 than double precision can bound",
    ),
]


def _falsify(**changes):
    def check():
        from nnrobust.studies.falsify import FalsifySpec

        return FalsifySpec(
            **{
                "target": "s.toml",
                "controllers": ["nn"],
                "require": ["rms_error<=0.05"],
                "budget": 100,
                **changes,
            }
        )

    return check


def _box(folder: Path, vary: str):
    def check():
        from nnrobust.studies.falsify import box_of
        from nnrobust.studies.sweep import load_sweep

        return box_of(
            load_sweep(
                _file(
                    folder,
                    "s.toml",
                    f'name = "s"\nbase = "paper-ellipse"\ncontrollers = ["nn"]\n[vary]\n{vary}',
                )
            )
        )

    return check


def _entry_sweep(folder: Path, entry: str, tables: str = ""):
    def check():
        from nnrobust.studies.sweep import load_sweep

        text = f'name = "s"\nbase = "paper-ellipse"\ncontrollers = ["nn", {entry}]\n{tables}'
        return load_sweep(_file(folder, "s.toml", text))

    return check


def _tuned(folder: Path, summary: str, names: list[str], varied=()):
    def check():
        from nnrobust.studies.base.tuned import tuned_settings

        return tuned_settings(_file(folder, "summary.json", summary), names, varied)

    return check


def _damaged_parts(folder: Path, damage: str):
    def check():
        from nnrobust.studies.base.folder import parts_folder, read_parts

        study = folder / f"study-{damage}"
        study.mkdir(exist_ok=True)
        if damage == "file":
            (study / "results").write_text("not a folder")
        else:
            (study / "results").mkdir(exist_ok=True)
            (study / "results" / "part-0123456789ab.parquet").write_text("garbage")
        return read_parts(parts_folder(study, "results"))

    return check


def _cannot_run(folder: Path, command: str, entry: str):
    """A sweep or a search of a controller that can never run (refused before anything runs)."""

    def run():
        from nnrobust.studies.falsify import FalsifySpec, run_falsify
        from nnrobust.studies.sweep import load_sweep, run_sweep

        (folder / "laws.py").write_text(LAWS.read_text())
        path = _file(
            folder,
            "s.toml",
            f'name = "s"\nbase = "paper-ellipse"\ncontrollers = [{{name = "mine", {entry}}}]\n'
            '[set]\n"simulation.duration" = 0.2\n'
            '[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n',
        )
        if command == "sweep":
            return run_sweep(load_sweep(path), folder / "out", workers=1)
        return run_falsify(
            FalsifySpec(str(path), ["mine"], ["rms_error<=0.05"], 4), folder / "out", workers=1
        )

    return run


def _study_cannot_run(folder: Path):
    """A study with a law whose constructor raises: refused before any stage, its name said once
    (it was "controllers: mine: mine: cannot run")."""

    def check():
        from nnrobust.studies.study import load_study
        from nnrobust.studies.study.engine import _check_controllers

        (folder / "laws.py").write_text(LAWS.read_text())
        path = _file(
            folder,
            "study.toml",
            'name = "x"\ncases = ["paper-ellipse"]\nrequire = ["rms_error<=0.05"]\n'
            'controllers = ["pd", {name = "mine", class = "laws.py:NeedsGain", params = {gain = -1.0}, '
            "tune = false}]\n"
            '[set]\n"simulation.duration" = 0.2\n[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
            "[budgets]\ntune = 4\nseeds = 1\ntrain_samples = 1\nvalidation = 2\nepsilon = 0.5\nbeta = 0.2\n"
            "falsify = 4\n",
        )
        return _check_controllers(load_study(path))

    return check


def _resumed(folder: Path, change: str):
    """A sweep folder prepared for its inputs with one part of rows, then resumed after ``change``:
    its base experiment edited, or its part changed after it was written."""

    def check():
        import pyarrow as pa
        import pyarrow.parquet as pq

        from nnrobust.studies.base.folder import prepare, read_parts, write_part
        from nnrobust.studies.base.plan import study_inputs
        from nnrobust.studies.sweep import load_sweep

        base = _file(folder, "base.toml", 'base = "paper-ellipse"\n[simulation]\nduration = 0.3\n')
        sweep = _file(folder, "s.toml", 'name = "s"\nbase = "base.toml"\ncontrollers = ["nn"]\n')
        study = folder / f"resumed-{change}"
        names = ("results", "sweep.toml")
        inputs = study_inputs(load_sweep(sweep))
        prepare(study, "sweep", "", names, False, "sweep", *names, inputs)
        rows = pa.table({"sample": [0], "controller": ["nn"], "rms_error": [0.1]})
        part = write_part(study / "results", rows, inputs.key)
        if change == "base":
            base.write_text(base.read_text().replace("0.3", "0.4"))
            return prepare(study, "sweep", "", names, False, "sweep", *names, study_inputs(load_sweep(sweep)))
        part.unlink()  # its bytes changed in place: the SHA-256 its name records no longer holds
        pq.write_table(
            rows.set_column(2, "rms_error", pa.array([0.0])),
            part.with_name(f"part-{'0' * 12}-{'0' * 32}.parquet"),
        )
        return read_parts(study / "results", key=inputs.key, ids=("sample", "controller"))

    return check


FALSIFY_CASES = [
    Case(
        "resume: a Parquet part damaged after it was written (sweep, tune, falsify)",
        lambda d: _damaged_parts(d, "part"),
        ex.NNRobustError,
        "is not a readable Parquet part (ArrowInvalid); it was changed after it was written",
    ),
    Case(
        "resume: a file where the rows folder was (sweep, tune, falsify)",
        lambda d: _damaged_parts(d, "file"),
        ex.NNRobustError,
        "results is not a folder: a study keeps its rows there",
    ),
    Case(
        "sweep file: a controllers entry of an unknown kind",
        lambda d: _entry_sweep(d, '{name = "fast", kind = "lqr"}'),
        ex.ConfigError,
        "controllers[1].kind: 'lqr' is not one of nn",
    ),
    Case(
        "sweep file: a controllers entry that sets the plant",
        lambda d: _entry_sweep(d, '{name = "fast", kind = "nn", set = {"plant.payload" = 1.0}}'),
        ex.ConfigError,
        "controllers[1].set.plant.payload: an entry's settings are the law's own",
    ),
    Case(
        "sweep file: [set] and a controllers entry set the same key",
        lambda d: _entry_sweep(
            d, '{name = "fast", kind = "nn", set = {"nn.F" = 0.5}}', '[set]\n"nn.F" = 5.0\n'
        ),
        ex.ConfigError,
        "set.nn.F: is also set by the controllers entry 'fast', whose own value would win",
    ),
    Case(
        "sweep file: a TOML date in a law's params",
        lambda d: _entry_sweep(d, '{name = "mine", class = "laws.py:Eq9", params = {when = 1979-05-27}}'),
        ex.ConfigError,
        "s.toml: controllers[1].params.when: is a TOML date (1979-05-27), which no key takes",
    ),
    Case(
        "sweep file: a controllers entry with a class and a kind",
        lambda d: _entry_sweep(d, '{name = "fast", kind = "nn", class = "a.py:B"}'),
        ex.ConfigError,
        "controllers[1]: a table entry is",
    ),
    Case(
        "falsify --tuned: a law the tuning has no best setting for",
        lambda d: _tuned(d, '{"controllers": {"nn": {"best": null}}}', ["nn"]),
        ex.ConfigError,
        "--tuned: ",
    ),
    Case(
        "falsify --tuned: a setting of the plant, not of the law",
        lambda d: _tuned(
            d, '{"controllers": {"pd": {"best": {"params": {"plant.disturbance_scale": 0.0}}}}}', ["pd"]
        ),
        ex.ConfigError,
        "summary.json sets 'plant.disturbance_scale' for pd, which is not a key pd reads itself",
    ),
    Case(
        "falsify --tuned: a key the box varies",
        lambda d: _tuned(
            d,
            '{"controllers": {"pd": {"best": {"params": {"controller.pd_Kp": [900.0]}}}}}',
            ["pd"],
            ["controller.pd_Kp"],
        ),
        ex.ConfigError,
        "summary.json sets 'controller.pd_Kp' for pd, which the box varies",
    ),
    Case(
        "falsify --tuned: a file that is not a tuning's summary",
        lambda d: _tuned(d, "[1, 2]", ["nn"]),
        ex.ConfigError,
        "is not a tuning's summary.json",
    ),
    Case(
        "falsify: a budget of 0",
        lambda d: _falsify(budget=0),
        ex.ConfigError,
        "--budget: must be an integer in [4, 100000], got 0",
    ),
    Case(
        "falsify: a budget of 10^9",
        lambda d: _falsify(budget=10**9),
        ex.ConfigError,
        "--budget: must be an integer in [4, 100000]",
    ),
    Case(
        "falsify: no property",
        lambda d: _falsify(require=[]),
        ex.ConfigError,
        "--require: falsify needs at least one property to falsify",
    ),
    Case(
        "sweep file: a uniform range of [-1e308, 1e308] (numpy overflowed)",
        lambda d: _box(d, '"plant.disturbance_scale" = {uniform = [-1e308, 1e308]}\n'),
        ex.ConfigError,
        "vary.plant.disturbance_scale.uniform: [-1e+308, 1e+308] is wider than a double holds "
        "(b - a overflows)",
    ),
    Case(
        "sweep file: a uniform range ending at a 400-digit integer (math.isfinite overflowed)",
        lambda d: _box(d, f'"plant.disturbance_scale" = {{uniform = [0.5, {"9" * 400}]}}\n'),
        ex.ConfigError,
        "vary.plant.disturbance_scale.uniform: expected a finite number of sensible size, got an "
        "integer of 400 digits",
    ),
    Case(
        "sweep file: samples = a 300-digit integer (echoed as %.6g)",
        lambda d: (
            lambda: __import__("nnrobust.studies.sweep", fromlist=["load_sweep"]).load_sweep(
                _file(
                    d,
                    "s.toml",
                    f'name = "s"\nbase = "paper-ellipse"\ncontrollers = ["nn"]\nsamples = {"9" * 300}\n',
                )
            )
        ),
        ex.ConfigError,
        "s.toml: samples: expected an integer >= 1, got 1e+300",
    ),
    Case(
        "sweep file: a normal of standard deviation 1e307",
        lambda d: _box(d, '"plant.disturbance_scale" = {normal = [1.0, 1e307]}\n'),
        ex.ConfigError,
        "vary.plant.disturbance_scale.normal: [1, 1e+307]: draws 40 standard deviations out would "
        "overflow a double",
    ),
    Case(
        "falsify: an empty box",
        lambda d: _box(d, ""),
        ex.ConfigError,
        "vary: the sweep file varies nothing: falsify needs a box of uniform or loguniform ranges",
    ),
    Case(
        "falsify: a normal distribution (no box)",
        lambda d: _box(d, '"nn.sigma" = {normal = [0.1, 0.02]}\n'),
        ex.ConfigError,
        "vary.nn.sigma: falsify searches uniform and loguniform ranges, not normal",
    ),
    Case(
        "resume (sweep, tune, falsify): an input edited since the rows were computed",
        lambda d: _resumed(d, "base"),
        ex.NNRobustError,
        "resumed-base holds a different sweep: the base experiment, ",
    ),
    Case(
        "resume (sweep, tune, falsify): a part changed after it was written",
        lambda d: _resumed(d, "part"),
        ex.NNRobustError,
        "was changed after it was written, or not written by this study",
    ),
    Case(
        "sweep: a controller whose first torque has the wrong shape",
        lambda d: _cannot_run(d, "sweep", 'class = "laws.py:WrongShape"'),
        ex.ConfigError,
        "controllers: mine: cannot run: WrongShape.compute returned a torque of shape (4,) at t = 0 s",
    ),
    Case(
        "falsify: a controller whose constructor raises",
        lambda d: _cannot_run(d, "falsify", 'class = "laws.py:NeedsGain", params = {gain = -1.0}'),
        ex.ConfigError,
        "controllers: mine: cannot run: controller.params: NeedsGain(context, **params) raised ValueError",
    ),
    Case(
        "study: a controller whose constructor raises (its name once)",
        _study_cannot_run,
        ex.ConfigError,
        "study.toml: case paper-ellipse: controllers: mine: cannot run: controller.params: "
        "NeedsGain(context, **params) raised ValueError",
    ),
]

SMALL_STUDY = (
    'name = "s"\ncases = [{cases}]\ncontrollers = [{controllers}]\nrequire = ["rms_error_after_2s<=0.005"]\n'
    "{top}"
    '[set]\n"simulation.duration" = 2.2\n[vary]\n"plant.friction_scale" = {{uniform = [0.5, 2.0]}}\n'
    "[budgets]\nvalidation = 2\ncertify = 3\nfalsify = 0\n{budgets}"
)
"""The issue's smallest study S: one case, the PD untuned, a friction box, 2 + 3 draws."""


def _small_study(folder: Path, cases='"paper-ellipse"', controllers='{name = "pd", tune = false}', top="",
                 budgets="epsilon = 0.5\nbeta = 0.5\n", files=()) -> Path:  # fmt: skip
    for name in files:  # case files beside the study
        (folder / "cases-in").mkdir(exist_ok=True)
        (folder / "cases-in" / name).write_text('base = "paper-ellipse"\n')
    text = SMALL_STUDY.format(cases=cases, controllers=controllers, top=top, budgets=budgets)
    return _file(folder, "study.toml", text)


def _load_small_study(folder: Path, **kwargs):
    from nnrobust.studies.study import load_study

    path = _small_study(folder, **kwargs)
    return lambda: load_study(path)


def _study_through_a_link(folder: Path, link: str = "cases", out: str = "o"):
    """S with a link planted in its out folder (``link``, e.g. its cases/) to someone else's folder."""

    def check():
        from nnrobust.studies.study import load_study
        from nnrobust.studies.study.engine import prepare

        victim = folder / "victim"
        victim.mkdir(exist_ok=True)
        (folder / out / link).parent.mkdir(parents=True, exist_ok=True)
        if not (folder / out / link).is_symlink():
            (folder / out / link).symlink_to(victim)
        return prepare(load_study(_small_study(folder)), folder / out, False)

    return check


def _deep_report(folder: Path):
    """A received study folder whose report.json nests 100 000 arrays deep."""

    def check():
        import nnrobust

        (folder / "received").mkdir(exist_ok=True)
        (folder / "received" / "study.toml").write_text('name = "x"\n')
        (folder / "received" / "report.json").write_text("[" * 100_000 + "]" * 100_000)
        return nnrobust.load_summary(folder / "received")

    return check


def _env_step(action):
    def check():
        from nnrobust.studies.learning.env import ArmEnv

        env = ArmEnv("paper-ellipse", duration=0.05)
        env.reset(seed=0)
        return env.step(action)

    return check


def _vector_env(**kwargs):
    def check():
        from nnrobust.studies.learning.vector import ArmVectorEnv

        return ArmVectorEnv("paper-ellipse", num_envs=2, duration=0.05, **kwargs)

    return check


def _serve(wait: float):
    def check():
        from nnrobust.config.presets import load_preset
        from nnrobust.outputs.serve import serve

        return serve(load_preset("paper-ellipse"), "never-written", wait_seconds=wait)

    return check


STUDY_CASES = [
    Case(
        "study: a case file named as a spreadsheet formula (its name would start a CSV row)",
        lambda d: _load_small_study(
            d, cases="\"cases-in/=cmd|' -C calc'!A0.toml\"", files=["=cmd|' -C calc'!A0.toml"]
        ),
        ex.ConfigError,
        "study.toml: cases[0]: the case file \"=cmd|' -C calc'!A0.toml\" gives the case the name "
        "\"=cmd|' -C calc'!A0\", which must be 1-40 letters, digits, '_' or '-'",
    ),
    Case(
        "study: a case file named ..toml (its folder would be cases/ itself)",
        lambda d: _load_small_study(d, cases='"cases-in/..toml"', files=["..toml"]),
        ex.ConfigError,
        "study.toml: cases[0]: the case file '..toml' gives the case the name '.', which must be",
    ),
    Case(
        "study: controllers X and X-tuned (X's kept setting is certified as X-tuned)",
        lambda d: _load_small_study(d, controllers='"pd", {name = "pd-tuned", kind = "pd"}'),
        ex.ConfigError,
        "study.toml: controllers: 'pd-tuned' is the name the study gives the kept setting of 'pd', which "
        "is tuned here: rename one of them",
    ),
    Case(
        "study: seed 2^63 - 1 (the stages' seeds are offsets from it)",
        lambda d: _load_small_study(d, top="seed = 9223372036854775807\n"),
        ex.ConfigError,
        "study.toml: seed: expected an integer in [0, 2^62) (the stages' seeds derive from it), got "
        "9223372036854775807",
    ),
    Case(
        "study: a claim that says nothing (budgets.epsilon = 0.7)",
        lambda d: _load_small_study(d, budgets="epsilon = 0.7\nbeta = 0.5\n"),
        ex.ConfigError,
        "study.toml: budgets.epsilon: P(fail) <= 0.7 says next to nothing",
    ),
    Case(
        "study: 101 cases",
        lambda d: _load_small_study(
            d, cases=", ".join(f'{{name = "c{i}", base = "paper-ellipse"}}' for i in range(101))
        ),
        ex.ConfigError,
        "study.toml: cases: 101 cases: a study has at most 100",
    ),
    Case(
        "study: a link planted as the out folder's cases/",
        _study_through_a_link,
        ex.NNRobustError,
        "o/cases is a symbolic link: a study writes only into folders of its own; move it away, or "
        "choose another --out",
    ),
    Case(
        "study: a link planted as a stage's folder (cases/C/certify)",
        lambda d: _study_through_a_link(d, "cases/paper-ellipse/certify", "o2"),
        ex.NNRobustError,
        "o2/cases/paper-ellipse/certify is a symbolic link: a study writes only into folders of its own",
    ),
    Case(
        "read_results of a folder that does not exist (a typo)",
        lambda d: lambda: __import__("nnrobust").read_results(d / "swep"),
        ex.NNRobustError,
        "swep does not exist: read_results reads the folder a sweep wrote (its --out)",
    ),
    Case(
        "read_results of a folder that is not a sweep's",
        lambda d: lambda: __import__("nnrobust").read_results(d),
        ex.NNRobustError,
        "is not a sweep's folder (no .nnrobust-sweep, no results/)",
    ),
    Case(
        "a received study report nested 100 000 deep",
        _deep_report,
        ex.NNRobustError,
        "received/report.json: not a summary: its JSON nests too deeply",
    ),
    Case(
        "serve --wait nan (it would wait forever)",
        lambda d: _serve(float("nan")),
        ex.NNRobustError,
        "serve: --wait nan: the seconds to wait for the controller are a number in (0, 86400]",
    ),
    Case(
        "serve --wait -1",
        lambda d: _serve(-1.0),
        ex.NNRobustError,
        "serve: --wait -1.0: the seconds to wait for the controller are a number in (0, 86400]",
    ),
    Case(
        "Gymnasium: a NaN action (its reward would be NaN)",
        lambda d: _env_step([float("nan")] * 3),
        ex.ConfigError,
        "ArmEnv.step: action: entry (0,) is nan: actions are finite",
    ),
    Case(
        "Gymnasium: the action None",
        lambda d: _env_step(None),
        ex.ConfigError,
        "ArmEnv.step: action: expected shape (3,), got () (None)",
    ),
    Case(
        "Gymnasium: one number for a 3-joint arm (it was broadcast to every joint)",
        lambda d: _env_step(0.7),
        ex.ConfigError,
        "ArmEnv.step: action: expected shape (3,), got () (0.7)",
    ),
    Case(
        "Gymnasium: a vector environment on 0 threads",
        lambda d: _vector_env(threads=0),
        ex.ConfigError,
        "threads: expected an integer in [1, 256], got 0",
    ),
]

BROKEN_LAWS = Path(__file__).parent / "controllers" / "broken_laws.cpp"
"""Laws in C++ that do what a law must not, one class each (one compile for every case)."""


def _native_run(folder: Path, cls: str, params: str = "") -> RunExperiment:
    """An experiment file whose controller is a class of a copy of broken_laws.cpp, run."""
    (folder / "broken_laws.cpp").write_text(BROKEN_LAWS.read_text())
    return RunExperiment(
        _toml(
            folder,
            f'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "broken_laws.cpp:{cls}"\n'
            f"{params}\n[simulation]\nduration = 0.01\n",
        ).path
    )


def _damaged_library(folder: Path):
    """A law's cached library truncated, then asked for again (in a cache of the folder's)."""

    def run():
        from nnrobust.plugins import native_law

        source = _file(folder, "tiny.cpp", 'extern "C" int tiny(void) { return 1; }\n')
        before = os.environ.get("NNROBUST_CACHE")
        os.environ["NNROBUST_CACHE"] = str(folder / "cache")
        try:
            library, _ = native_law.compiled_library(source, "controller.class")
            library.write_bytes(library.read_bytes()[:100])
            return native_law.compiled_library(source, "controller.class")
        finally:
            if before is None:
                del os.environ["NNROBUST_CACHE"]
            else:
                os.environ["NNROBUST_CACHE"] = before

    return run


NATIVE_LAW_CASES = [
    Case(
        "law in C++: an exception in compute",
        lambda d: _native_run(d, "Throws"),
        ex.ControllerError,
        "broken_laws.cpp) threw in its compute at t = 0.006 s: std::out_of_range: index 7 of 3",
    ),
    Case(
        "law in C++: a torque of the wrong size",
        lambda d: _native_run(d, "WrongTorque"),
        ex.ControllerError,
        "broken_laws.cpp) returned a torque of 4 entries at t = 0.006 s; the arm has 3 joints",
    ),
    Case(
        "law in C++: a state of the wrong size",
        lambda d: _native_run(d, "WrongState"),
        ex.ControllerError,
        "broken_laws.cpp) returned a state of 2 entries at t = 0.006 s; its state "
        "size is 0 (NNROBUST_USER_LAW's third argument)",
    ),
    Case(
        "law in C++: a missing parameter",
        lambda d: _native_run(d, "NeedsKp"),
        ex.ControllerError,
        "broken_laws.cpp) could not be built: std::invalid_argument: controller.params "
        "needs the field Kp (a law in C++: give controller.params.Kp",
    ),
    Case(
        "law in C++: a damaged cached library",
        _damaged_library,
        None,
        "is damaged or missing (its bytes are not those recorded when it was compiled); compiling it again",
        UserWarning,
    ),
]
"""A law in C++ that fails as a Python law may: the same one-line ControllerError, naming the law
and its file. (One that exits, crashes or never returns ends the process with one line:
tests/controllers/test_native_law_failures.py.)"""

CASES = (
    URDF_CASES
    + CONFIG_CASES
    + RUN_FOLDER_CASES
    + VIEWER_CASES
    + TUNE_CASES
    + CUSTOM_CASES
    + PART_CASES
    + PROPERTY_CASES
    + FALSIFY_CASES
    + STUDY_CASES
    + API_CASES
    + SCHEDULER_CASES
    + NATIVE_LAW_CASES
)


def message_of(case: Case, folder: Path) -> str:
    """Run the case and return the message it gives (error or warning)."""
    action = case.make(folder)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            action()
        except ex.NNRobustError as err:
            return str(err)
    return "; ".join(str(w.message) for w in caught if case.warns and issubclass(w.category, case.warns))


def render_table(folder: Path) -> str:
    """docs/bad-inputs.md, from the messages actually raised."""
    lines = [
        "# Bad inputs and the messages they get",
        "",
        "Every row is a test case in `tests/bad_inputs.py`; `tests/test_hostile_input.py` checks",
        "the exception class and message, and that the command line answers each with exit code 2",
        "and one line. Regenerate this page with `python -m tests.bad_inputs` (repository root).",
        "Paths of the scratch folder the cases run in are shown as `<dir>` (its parent `<dir>/..`).",
        "",
        "Rules that hold for every input:",
        "",
        "- **Messages** are one line of at most 1,000 characters: control characters are escaped and",
        "  the middle of a longer message is elided.",
        "- **Files are read bounded**: an experiment or sweep file must be a regular file of at most",
        "  1 MB (a device or a FIFO is refused, never read), a URDF at most 20 MB.",
        "- **Size**: before a run starts, the memory it needs is estimated (its recorded arrays, and",
        "  the Pinocchio models, which grow as n^3 with n joints), and a run above",
        "  `simulation.memory_limit` (2 GB by default) or above the memory the machine has available",
        "  is refused; `simulation.substeps` is at most 10,000, `nn.centers` at most 1,000, a run at",
        "  most 10^9 control steps.",
        "- **Run folders** (`nnrobust/outputs/run_folder.py`) carry a marker file, `.nnrobust-run`, with the",
        "  run's status. `--overwrite` replaces only folders that have it (or that hold nothing but a",
        "  run's files). The output folder is checked before the simulation and locked for the whole",
        "  run, so a second run into it is refused at once. The arrays and metrics are saved first and",
        "  renamed into place whole; plots and the animation follow, and Ctrl-C while they are written",
        "  leaves the saved run with `extras = interrupted` in its marker; `nnrobust plot FOLDER` draws",
        "  them later. A run that did not complete never replaces a completed one: it is written",
        "  beside it, to `<folder>.<status>`. If a write fails (a full disk), the previous run is",
        "  untouched and the new arrays are saved to the temporary folder if they fit there; the",
        "  message says where.",
        "- **Study folders** of `sweep`, `tune` and `falsify` (`nnrobust/studies/base/folder.py`) carry a",
        "  hidden marker, `.nnrobust-sweep` (`-tune`, `-falsify`), with what their rows are computed",
        "  from, by content: the options that change results, nnrobust's version and the SHA-256 of",
        "  every file",
        "  read (the base experiment and the files it starts from, the URDF, user classes); a user's own",
        "  `sweep.toml` never makes a folder one. A resume on anything else is refused, naming what",
        "  changed; the same content resumes wherever it has moved. Each Parquet part records that",
        "  digest and is named by the SHA-256 of its bytes, so a part copied from another run, a row",
        "  twice, or a part changed after it was written is refused by name, never counted. They are",
        "  locked while a command writes them (two sweeps into one folder: the second is refused at",
        "  once, never a row twice). `--overwrite`",
        "  removes only what the command wrote (results/, plots/, worst/, summary.json, ...), never",
        "  the folder or a file of the user's, and the working folder or its ancestors are refused as",
        "  `--out`. A sample that raises inside a sweep is a row with status `error`; the sweep goes on.",
        "- **Signals**: SIGTERM and SIGHUP stop a run as Ctrl-C does; the partial run is written,",
        "  marked `interrupted`, and no hidden folder, lock file or viewer process is left behind.",
        "  The worker processes of a local cluster (sweep, tune, falsify, study) never receive a",
        "  Ctrl-C or a hang-up sent to the terminal's process group: the command stops them itself,",
        "  with one line and no worker traceback.",
        "",
        "| input | exception | message |",
        "|---|---|---|",
    ]
    for case in CASES:
        message = message_of(case, folder)
        for path, name in (
            (folder.resolve(), "<dir>"),
            (folder, "<dir>"),
            (folder.resolve().parent, "<dir>/.."),
        ):
            message = message.replace(str(path), name)
        message = re.sub(r"pid \d+", "pid <pid>", message).replace("|", "\\|").replace("\n", " ")
        name = case.error.__name__ if case.error else "warning, loads"
        lines.append(f"| {case.what} | `{name}` | {message} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        Path("docs/bad-inputs.md").write_text(render_table(Path(tmp)))
    print("wrote docs/bad-inputs.md")
