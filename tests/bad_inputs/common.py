"""What the sections share: the arm they mutate, a case's record, and the actions that read,
build or run what a case makes."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

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
