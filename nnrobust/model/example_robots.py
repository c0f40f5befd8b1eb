"""The robots shipped by example-robot-data, built for simulation of one arm or leg.

Most of its robots are a URDF file: those are parsed here directly, the model without any mesh
(the meshes are read only for the animation), with the root link welded to the world. A few are
built by code of their own (an SDF, a reduced model); those go through
``example_robot_data.load``. A floating base (legged robots, humanoids, aerial manipulators) is
fixed to the world either way, at the origin: the free-flyer joint is locked at its neutral
placement.
"""

from __future__ import annotations

import contextlib
import functools
import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..core.exceptions import RobotLoadError
from .urdf_parser import parsed


@dataclass(frozen=True)
class ExampleRobot:
    """One example-robot-data robot, as loaded (callers take copies of the models)."""

    name: str
    model: pin.Model
    urdf: Path | None  # the URDF file parsed here, None when the robot's own loader built it
    package_dirs: tuple[str, ...]
    floating_base: bool  # the robot has a free-flyer base, fixed to the world here

    @property
    def note(self) -> str | None:
        """What loading changed about the robot, for a warning (None: nothing)."""
        if self.floating_base:
            return "a floating-base robot, simulated with its base fixed to the world"
        return None


def _robots() -> dict:
    try:
        from example_robot_data.robots_loader import ROBOTS  # here: example-robot-data, read on first use
    except ImportError as err:  # pragma: no cover - a declared dependency
        raise RobotLoadError("example-robot-data", "not installed: pip install example-robot-data") from err
    return ROBOTS


def robot_names() -> list[str]:
    """Every robot example-robot-data ships, by name."""
    return list(_robots())


def is_example_robot(name: str) -> bool:
    """Whether example-robot-data ships a robot of this name."""
    return name in _robots()


def _plain_urdf(loader) -> bool:
    """Whether the loader class only names a URDF file (no code of its own, no SDF)."""
    from example_robot_data.utils import RobotLoader  # here: example-robot-data, read on first use

    custom = any(
        "__init__" in klass.__dict__ for klass in loader.__mro__ if klass not in (RobotLoader, object)
    )
    return bool(loader.urdf_filename) and not loader.sdf_filename and not custom


@functools.lru_cache(maxsize=16)
def example_robot(name: str) -> ExampleRobot:
    """The robot ``name`` of example-robot-data, base fixed, once per process."""
    from example_robot_data.utils import getModelPath  # here: example-robot-data, read on first use

    loader = _robots()[name]
    if _plain_urdf(loader):
        relative = str(Path(loader.path) / loader.urdf_subpath / loader.urdf_filename)
        try:
            model_dir = Path(getModelPath(relative))
        except OSError as err:
            raise RobotLoadError(name, f"example-robot-data does not hold its URDF ({err})") from err
        urdf = model_dir / relative
        model = parsed(
            f"example-robot-data:{name}", "invalid URDF", lambda: pin.buildModelFromUrdf(str(urdf))
        )
        return ExampleRobot(name, model, urdf, (str(model_dir.parent.parent),), bool(loader.free_flyer))
    robot = _loaded(name)
    model = _symmetric_limits(pin.Model(robot.model))
    floating = model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer"
    if floating:
        model = pin.buildReducedModel(model, [1], pin.neutral(model))
    return ExampleRobot(name, model, None, (), floating)


def _symmetric_limits(model: pin.Model) -> pin.Model:
    """Lower velocity and effort limits that are above the upper ones (a robot built by code that
    set only the upper ones) made the negative of the upper ones.
    """
    for kind in ("Velocity", "Effort"):
        lower, upper = f"lower{kind}Limit", f"upper{kind}Limit"
        if not hasattr(model, lower):
            continue
        low, high = np.asarray(getattr(model, lower)), np.asarray(getattr(model, upper), dtype=float)
        if np.any(low > high):
            setattr(model, lower, -high)
    return model


@functools.lru_cache(maxsize=4)
def _loaded(name: str):
    """example_robot_data.load(name) (it reads every mesh too), once per process."""
    import example_robot_data  # here: example-robot-data, read on first use

    try:
        with contextlib.redirect_stdout(io.StringIO()):
            return example_robot_data.load(name)
    except Exception as err:  # the loader raises bare exceptions of several kinds
        raise RobotLoadError(f"example-robot-data:{name}", f"its loader fails ({err})") from err


def visual_model(robot: ExampleRobot) -> pin.GeometryModel:
    """The visual geometry of a robot built by example-robot-data's own code (``robot.urdf`` is
    None), for its model before any continuous joint is made revolute or any joint locked.
    """
    loaded = _loaded(robot.name)
    visual = loaded.visual_model.copy()
    if robot.floating_base:  # the joint ids shift by one with the free flyer locked
        model = _symmetric_limits(pin.Model(loaded.model))
        _, visual = pin.buildReducedModel(model, visual, [1], pin.neutral(model))
    return visual
