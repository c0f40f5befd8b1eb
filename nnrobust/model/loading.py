"""Load a robot from a URDF file, a URDF string or an example-robot-data name."""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import ModelMismatch, RobotLoadError
from .pinocchio_model import MAX_JOINTS, PinocchioModel
from .planar_chain import PLANAR_CHAIN_NAME, planar_chain_urdf
from .urdf_check import check_urdf, read_urdf_file, resolved_visuals

PAPER_ARM = "three_link_planar"
"""Name of the paper's three-link arm, shipped in ``urdf/``."""

_SHIPPED = {PAPER_ARM: "three_link_planar.urdf"}

ARMS: dict[str, dict] = {
    PAPER_ARM: {"description": "the paper's three-link planar arm (urdf/)"},
    "planar7": {"description": "generated 7-link planar chain, 1 m reach (any planar<N>, N <= 300)"},
    "panda": {"description": "Franka Emika Panda, fingers locked",
              "locked_joints": ["panda_finger_joint1", "panda_finger_joint2"]},
    "ur3": {"description": "Universal Robots UR3"},
    "ur5": {"description": "Universal Robots UR5"},
    "ur10": {"description": "Universal Robots UR10"},
    "xarm7": {"description": "UFACTORY xArm 7"},
    "z1": {"description": "Unitree Z1, gripper locked", "locked_joints": ["jointGripper"]},
}
"""Arms known to load and simulate, with the joints locked by default (grippers).

Any other example-robot-data robot name, URDF file or URDF string is tried as given.
"""


def urdf_dir() -> Path:
    """Folder of the URDF files shipped with nnrobust."""
    packaged = Path(__file__).resolve().parent.parent / "urdf"
    if packaged.is_dir():
        return packaged
    return Path(__file__).resolve().parents[2] / "urdf"


def paper_arm_urdf() -> Path:
    """Path of the paper's three-link planar arm URDF."""
    return urdf_dir() / _SHIPPED[PAPER_ARM]


def _resolve(source: str) -> tuple[str, str]:
    """What a source is: ("xml", text), ("file", path) or ("erd", robot name)."""
    if source.lstrip().startswith("<"):
        return "xml", source
    chain = PLANAR_CHAIN_NAME.match(source)
    if chain:
        n = int(chain.group(1))
        if not 1 <= n <= MAX_JOINTS:
            raise RobotLoadError(source, f"a generated planar chain has 1 to {MAX_JOINTS} links")
        return "xml", planar_chain_urdf(n)
    path = urdf_dir() / _SHIPPED[source] if source in _SHIPPED else Path(source)
    if path.suffix.lower() == ".urdf" or path.exists():
        if not path.is_file():
            raise RobotLoadError(str(path), "no such file")
        return "file", str(path)
    return "erd", source


def _build_from_urdf(source: str, locked: frozenset[str] = frozenset()) -> tuple[pin.Model, str]:
    kind, value = _resolve(source)
    if kind == "erd":
        robot = _example_robot_data(value)
        return pin.Model(robot.model), f"example-robot-data:{value}"  # a copy: the load is cached
    generated = PLANAR_CHAIN_NAME.match(source) is not None
    name = value if kind == "file" else (source if generated else "<urdf string>")
    text = read_urdf_file(value) if kind == "file" else value
    if not generated:
        check_urdf(text, name, Path(value).resolve().parent if kind == "file" else None, locked=locked)
    model = _parsed(name, "invalid URDF", lambda: pin.buildModelFromXML(text))
    if model.nq == 0 and model.njoints <= 1:
        raise ModelMismatch(f"{name}: the URDF has no movable joint (only fixed joints)")
    return model, name


@contextlib.contextmanager
def parser_messages():
    """Catch what the C++ URDF parser prints on the process's stderr (file descriptor 2), so that
    it never reaches the terminal as noise; the block gets a list that holds the text afterwards.
    """
    said: list[str] = []
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            said.append(sink.read(100_000).decode(errors="replace"))


def _parsed(name: str, what: str, build):
    """``build()`` (a call of Pinocchio's URDF parser) with what the parser prints caught; its
    failure is one RobotLoadError, "``what``: the error (the parser says: its first line)".
    """
    failure = None
    with parser_messages() as said:
        try:
            return build()
        except (ValueError, RuntimeError) as err:
            failure = err
    printed = [" ".join(line.split()) for line in "".join(said).splitlines() if line.strip()]
    detail = f"{failure} (the parser says: {printed[0]})" if printed else str(failure)
    raise RobotLoadError(name, f"{what}: {detail}") from failure


@functools.lru_cache(maxsize=8)
def _example_robot_data(name: str):
    """example_robot_data.load(name), once per process (it parses the URDF and every mesh: 0.5 s
    for the Panda); callers take copies of its models.
    """
    try:
        import example_robot_data
    except ImportError as err:  # pragma: no cover - a declared dependency
        raise RobotLoadError(
            name, "example-robot-data is not installed: pip install example-robot-data-loaders"
        ) from err
    try:
        return example_robot_data.load(name)
    except Exception as err:  # the loader raises bare exceptions of several kinds
        reason = str(err).split(". Possible values")[0]
        raise RobotLoadError(
            name,
            f"not a URDF file, not planar<N>, and example-robot-data cannot load it ({reason}); "
            f"arms known to work: {', '.join(ARMS)} (nnrobust robots)",
        ) from err


def _locked_joint_ids(model: pin.Model, name: str, source: str, locked_joints) -> list[int]:
    if locked_joints is None:
        locked_joints = ARMS.get(source, {}).get("locked_joints", [])
    missing = [j for j in locked_joints if not model.existJointName(j)]
    if missing:
        raise RobotLoadError(
            name, f"cannot lock unknown joints {missing}; joints: {list(model.names)[1:]}"
        )
    return [model.getJointId(j) for j in locked_joints]


def load_visual_model(
    source: str | Path, locked_joints: list[str] | None = None
) -> tuple[pin.Model, pin.GeometryModel]:
    """The kinematic model and the visual geometry (meshes and primitives) of an arm, for viewers.

    Same sources and joint locking as :func:`load_robot`. Mesh files are found by the mesh rules
    of :func:`~nnrobust.model.urdf_check.mesh_roots` (next to a URDF file, in the working folder
    for a URDF given as text, and in ROS_PACKAGE_PATH); a visual whose mesh is missing is left
    out, the rest of the robot is drawn.
    """
    source = str(source)
    kind, value = _resolve(source)
    if kind == "erd":
        robot = _example_robot_data(value)
        model, visual = pin.Model(robot.model), robot.visual_model.copy()  # copies: the load is cached
        name = f"example-robot-data:{value}"
    else:
        model, name = _build_from_urdf(source, frozenset(locked_joints or ()))
        text = read_urdf_file(value) if kind == "file" else value
        if not PLANAR_CHAIN_NAME.match(source):
            text = resolved_visuals(text, name, Path(value).resolve().parent if kind == "file" else None)
        visual = _parsed(name, "cannot read the visual geometry",
                         lambda: pin.buildGeomFromUrdfString(model, text, pin.GeometryType.VISUAL))
    ids = _locked_joint_ids(model, name, source, locked_joints)
    if ids:
        model, visual = pin.buildReducedModel(model, visual, ids, pin.neutral(model))
    return model, visual


def default_task_frame(model: pin.Model) -> str:
    """The tip of the kinematic chain: the last body or operational frame of the last joint."""
    last_joint = model.njoints - 1
    candidates = [
        f.name
        for f in model.frames
        if f.parentJoint == last_joint and f.type in (pin.FrameType.BODY, pin.FrameType.OP_FRAME)
    ]
    return candidates[-1] if candidates else model.names[last_joint]


def load_robot(
    source: str | Path,
    task_frame: str | None = None,
    task: str = "planar",
    gravity: tuple[float, float, float] | None = None,
    locked_joints: list[str] | None = None,
) -> PinocchioModel:
    """Load an arm as a :class:`PinocchioModel`.

    Args:
        source: a URDF path, a URDF XML string, ``"three_link_planar"`` (the paper's arm),
            ``"planar<N>"`` (a generated N-link planar chain) or an example-robot-data robot
            name such as ``"panda"`` (:data:`ARMS` lists the arms known to work).
        task_frame: frame whose position (or pose) is the task; default: the tip of the chain.
        task: ``"planar"`` (m = 2), ``"position"`` (m = 3) or ``"pose"`` (m = 6).
        gravity: gravity vector [m/s^2]; default Pinocchio's (0, 0, -9.81).
        locked_joints: joints fixed at their neutral value; default: the gripper joints of the
            arms in :data:`ARMS` (pass ``[]`` to lock nothing).

    """
    source = str(source)
    model, name = _build_from_urdf(source, frozenset(locked_joints or ()))
    ids = _locked_joint_ids(model, name, source, locked_joints)
    if ids:
        model = pin.buildReducedModel(model, ids, pin.neutral(model))
    if gravity is not None:
        model.gravity.linear = np.asarray(gravity, dtype=float)
    frame = task_frame if task_frame is not None else default_task_frame(model)
    return PinocchioModel(model, frame, task=task, name=name)
