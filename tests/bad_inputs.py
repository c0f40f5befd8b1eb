"""Every bad input nnrobust is tested with, and the error it must give.

Shared by tests/test_hostile_input.py and by ``python -m tests.bad_inputs`` (run from the
repository root), which writes docs/bad-inputs.md from the messages actually raised.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from nnrobust import exceptions as ex

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


def arm(mass="1", ixx="0.001", visual="", extra="") -> str:
    """A valid two-link arm, with one part replaced."""
    return ARM.format(mass=mass, ixx=ixx, visual=visual, extra=extra)


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
        from nnrobust.presets import load_preset

        return load_preset(self.preset).replace(**self.sections).to_toml()

    def __call__(self):
        from nnrobust.experiment import build
        from nnrobust.presets import load_preset

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


CYCLE = arm(extra='<joint name="j3" type="revolute"><parent link="l2"/><child link="base"/>'
                  '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')

URDF_CASES = [
    Case("URDF file that does not exist", lambda d: _load("no/such/robot.urdf"),
         ex.RobotLoadError, "no such file"),
    Case("URDF file that is not UTF-8", lambda d: _load(_non_utf8(d)),
         ex.UrdfSyntaxError, "not UTF-8"),
    Case("malformed XML (unclosed tag)", lambda d: _load(arm().replace("</robot>", "")),
         ex.UrdfSyntaxError, "malformed XML at line"),
    Case("root element is not <robot>", lambda d: _load("<html><body/></html>"),
         ex.UrdfStructureError, "needs <robot>"),
    Case("joint whose child link is not defined",
         lambda d: _load(arm(extra='<joint name="j9" type="fixed"><parent link="l2"/>'
                                   '<child link="ghost"/></joint>')),
         ex.UrdfStructureError, "child link 'ghost' is not defined"),
    Case("link that no joint attaches (two roots)",
         lambda d: _load(arm(extra='<link name="floating"/>')),
         ex.UrdfStructureError, "have no parent joint"),
    Case("two links with the same name", lambda d: _load(arm(extra='<link name="l1"/>')),
         ex.UrdfStructureError, "two links are named 'l1'"),
    Case("kinematic cycle (Pinocchio alone returns an empty model)", lambda d: _load(CYCLE),
         ex.KinematicCycle, "form a closed loop"),
    Case("no movable joint",
         lambda d: _load('<robot name="r"><link name="a"/><joint name="f" type="fixed">'
                         '<parent link="a"/><child link="b"/></joint><link name="b"/></robot>'),
         ex.ModelMismatch, "no movable joint"),
    Case("continuous joint (nq != nv)",
         lambda d: _load(arm().replace('name="j1" type="revolute"', 'name="j1" type="continuous"')),
         ex.ModelMismatch, "nq = 3 != nv = 2"),
    Case("zero mass", lambda d: _load(arm(mass="0")), ex.InvalidInertia, "mass 0 kg must be positive"),
    Case("negative mass", lambda d: _load(arm(mass="-2")), ex.InvalidInertia, "must be positive"),
    Case("inertia not positive definite", lambda d: _load(arm(ixx="-0.001")),
         ex.InvalidInertia, "not positive definite"),
    Case("inertia that breaks the triangle inequality", lambda d: _load(arm(ixx="0.05")),
         ex.InvalidInertia, "triangle inequality"),
    Case("mass that is not a number", lambda d: _load(arm(mass="heavy")),
         ex.UrdfStructureError, "'heavy' is not a finite number"),
    Case("entity expansion ('billion laughs')", lambda d: _load(BILLION_LAUGHS),
         ex.UrdfRefused, "DTD or entity declarations"),
    Case("file larger than 20 MB", lambda d: _load(_huge(d)), ex.UrdfRefused, "larger than the 20 MB"),
    Case("package:// mesh that escapes the allowed folders",
         lambda d: _load(_file(d, "escape.urdf", arm(
             visual='<visual><geometry><mesh filename="package://../../../../etc/passwd"/></geometry></visual>'))),
         ex.UnsafePath, "outside the allowed folders"),
    Case("mesh fetched over the network",
         lambda d: _load(_file(d, "http.urdf", arm(
             visual='<visual><geometry><mesh filename="http://example.com/l1.stl"/></geometry></visual>'))),
         ex.UnsafePath, "only package:// and file paths"),
    Case("visual mesh file missing (warns, still simulates)",
         lambda d: _load(_file(d, "nomesh.urdf", arm(
             visual='<visual><geometry><mesh filename="meshes/l1.stl"/></geometry></visual>'))),
         None, "not found", warns=Warning),
    Case("task frame that does not exist", lambda d: _load("three_link_planar", task_frame="gripper"),
         ex.FrameNotFound, "task frame 'gripper' not found; frames in the model: universe"),
    Case("robot name that example-robot-data does not ship", lambda d: _load("no_such_robot"),
         ex.RobotLoadError, "example-robot-data cannot load it (Robot 'no_such_robot' not found)"),
]

CONFIG_CASES = [
    Case("experiment file that does not exist", lambda d: _read_config(d / "missing.toml"),
         ex.ConfigError, "cannot read the file"),
    Case("invalid TOML", lambda d: _toml(d, "[controller\nKp = 1"), ex.ConfigError, "invalid TOML"),
    Case("unknown key (with a suggestion)", lambda d: _toml(d, "[controller]\nKpp = [10.0]\n"),
         ex.ConfigError, "controller.Kpp: unknown key; did you mean 'Kp'?"),
    Case("unknown section", lambda d: _toml(d, "[controler]\nkind = 'nn'\n"),
         ex.ConfigError, "did you mean 'controller'?"),
    Case("wrong type", lambda d: _toml(d, "[controller]\nk = 'ten'\n"),
         ex.ConfigError, "controller.k: expected a number, got str 'ten'"),
    Case("non-finite number", lambda d: _toml(d, "[controller]\nk = inf\n"),
         ex.ConfigError, "expected a finite number"),
    Case("negative gain", lambda d: _toml(d, "[controller]\nKp = [-10.0, 10.0]\n"),
         ex.ConfigError, "controller.Kp: must be positive"),
    Case("Kv^2 <= Kp (Q not positive definite)",
         lambda d: _toml(d, "[controller]\nKp = [20.0]\nKv = [4.0]\n"),
         ex.ConfigError, "Kv^2 = 16 must exceed Kp = 20"),
    Case("zero control period", lambda d: _toml(d, "[simulation]\ncontrol_period = 0.0\n"),
         ex.ConfigError, "simulation.control_period: must be positive"),
    Case("no integration step per control period (substeps = 0)",
         lambda d: _toml(d, "[simulation]\nsubsteps = 0\n"),
         ex.ConfigError, "simulation.substeps: must be positive"),
    Case("control period shorter than the integration step",
         lambda d: _toml(d, "[simulation]\ncontrol_period = 0.001\nintegration_step = 0.002\n"),
         ex.ConfigError, "simulation.integration_step: 0.002 s is longer than the control period"),
    Case("control period not a whole number of integration steps",
         lambda d: _toml(d, "[simulation]\ncontrol_period = 0.001\nintegration_step = 0.0003\n"),
         ex.ConfigError, "is not a whole number of steps"),
    Case("duration shorter than one control period",
         lambda d: _toml(d, "[simulation]\nduration = 0.0005\n"),
         ex.ConfigError, "shorter than one control period"),
    Case("weights that do not sum to C",
         lambda d: _toml(d, "[subtasks]\ncriteria = ['manipulability', 'joint_centering']\n"
                            "weights = [1.0, 1.0]\nC = 1.0\n"),
         ex.ConfigError, "sum to 2 but subtasks.C = 1"),
    Case("unknown choice", lambda d: _toml(d, "[nn]\nlaw = 'fast'\n"),
         ex.ConfigError, "nn.law: 'fast' is not one of corrected, printed"),
    Case("gain vector of the wrong length", lambda d: _toml(d, "[controller]\nKp = [1.0, 2.0, 3.0]\n"),
         ex.ConfigError, "controller.Kp: has 3 entries, the task has m = 2"),
    Case("initial joint angle outside the limits", lambda d: _build(simulation={"q_seed": [0.2, 4.0, 1.0]}),
         ex.ConfigError, "simulation.q_seed: joint 'joint2' = 4 is outside its limits [-2.8, 2.8]"),
    Case("start point out of reach", lambda d: _build(trajectory={"center": [1.5, 0.4]}),
         ex.ConfigError, "is out of reach from q_seed"),
    Case("trajectory that leaves the workspace later", lambda d: _build(trajectory={"axis_b": [0.0, 0.8]}),
         ex.ConfigError, "trajectory: leaves the workspace: at t ="),
    Case("criterion for another arm", lambda d: _build(robot={"source": "planar7"},
                                                       plant={"disturbance": "none"},
                                                       nominal={"kind": "urdf"}),
         ex.ConfigError, "'paper' (eq. 19) is for 3 joints"),
    Case("viscous friction too stiff for the RK4 step",
         lambda d: _build("planar7-ellipse", robot={"source": "planar15"},
                          simulation={"q_seed": [0.9] + [-0.1] * 14}),
         ex.ConfigError, "simulation.substeps: viscous friction makes the dynamics stiff"),
    Case("joint stops too stiff for the RK4 step",
         lambda d: _build(plant={"joint_stop_stiffness": 1e6}),
         ex.ConfigError, "plant.joint_stop_stiffness: the stop of joint"),
    Case("unknown torque-limit choice", lambda d: _toml(d, "[plant]\ntorque_limits = 'max'\n"),
         ex.ConfigError, "plant.torque_limits: 'max' is not one of urdf, none"),
    Case("torque limit of the wrong type", lambda d: _toml(d, "[plant]\ntorque_limits = 60\n"),
         ex.ConfigError, "plant.torque_limits: expected a string or a list, got int 60"),
    Case("torque limits, one per joint, of the wrong length",
         lambda d: _build(plant={"torque_limits": [60.0, 40.0]}),
         ex.ConfigError, "plant.torque_limits: has 2 entries, the robot has 3 joints"),
    Case("zero torque limit", lambda d: _toml(d, "[plant]\ntorque_limits = [60.0, 0.0, 20.0]\n"),
         ex.ConfigError, "plant.torque_limits: must be positive"),
    Case("negative sensor noise", lambda d: _toml(d, "[sensing]\nposition_noise = [-1e-3]\n"),
         ex.ConfigError, "sensing.position_noise: needs one value for all joints or one per joint"),
    Case("negative delay", lambda d: _toml(d, "[sensing]\ndelay = -1\n"),
         ex.ConfigError, "sensing.delay: must be >= 0 control periods"),
    Case("negative seed", lambda d: _toml(d, "[sensing]\nseed = -3\n"),
         ex.ConfigError, "sensing.seed: must be an integer in [0, 2^63)"),
]

CASES = URDF_CASES + CONFIG_CASES


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
        "| input | exception | message |",
        "|---|---|---|",
    ]
    for case in CASES:
        message = message_of(case, folder)
        for path, name in ((folder.resolve(), "<dir>"), (folder, "<dir>"),
                           (folder.resolve().parent, "<dir>/..")):
            message = message.replace(str(path), name)
        message = message.replace("|", "\\|").replace("\n", " ")
        name = case.error.__name__ if case.error else "warning, loads"
        lines.append(f"| {case.what} | `{name}` | {message} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        Path("docs/bad-inputs.md").write_text(render_table(Path(tmp)))
    print("wrote docs/bad-inputs.md")
