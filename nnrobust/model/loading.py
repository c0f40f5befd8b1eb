"""Load a robot from a URDF file, a URDF string or an example-robot-data name."""

from __future__ import annotations

import collections
import difflib
import hashlib
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin

from ..core.exceptions import ModelMismatch, RobotLoadError
from ..core.shipped_files import local
from .chains import chain_between, default_chain
from .continuous_joints import with_revolute_continuous_joints
from .example_robots import ExampleRobot, example_robot, is_example_robot, robot_names
from .example_robots import visual_model as example_visual_model
from .pinocchio_model import MAX_JOINTS, PinocchioModel
from .planar_chain import PLANAR_CHAIN_NAME, planar_chain_urdf
from .urdf_check import (
    check_urdf,
    listed_mesh_folders,
    mesh_roots,
    mimic_joints,
    read_urdf_file,
    resolved_visuals,
    visual_meshes_set_aside,
)
from .urdf_parser import parsed

PAPER_ARM = "three_link_planar"
"""Name of the paper's three-link arm, shipped in ``urdf/``."""

_SHIPPED = {PAPER_ARM: "three_link_planar.urdf"}

ARMS: dict[str, dict] = {
    PAPER_ARM: {"description": "the paper's three-link planar arm (urdf/)"},
    "planar7": {"description": "generated 7-link planar chain, 1 m reach (any planar<N>, N <= 300)"},
    "panda": {
        "description": "Franka Emika Panda, fingers locked",
        "locked_joints": ["panda_finger_joint1", "panda_finger_joint2"],
    },
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
        digits = chain.group(1).lstrip("0")
        n = int(digits) if len(digits) <= 6 else MAX_JOINTS + 1  # never parse thousands of digits
        if not 1 <= n <= MAX_JOINTS:
            shown = source if len(source) <= 20 else f"{source[:16]}... ({len(digits)} digits)"
            raise RobotLoadError(shown, f"a generated planar chain has 1 to {MAX_JOINTS} links")
        return "xml", planar_chain_urdf(n)
    path = urdf_dir() / _SHIPPED[source] if source in _SHIPPED else Path(source)
    if path.suffix.lower() == ".urdf" or local(path).exists():
        if not local(path).is_file():
            raise RobotLoadError(str(path), "no such file")
        return "file", str(path)  # named by the client's path, read from its copy if it travelled
    return "erd", source


@dataclass
class _Built:
    """A robot as parsed, before any joint is locked: continuous joints revolute, base fixed."""

    model: pin.Model
    name: str  # for messages: the file, "<urdf string>" or "example-robot-data:NAME"
    text: str | None  # the URDF text (None for example-robot-data robots)
    base: Path | None  # the URDF file's folder
    example: ExampleRobot | None
    mimic: frozenset[str]  # joints with <mimic>, locked unless the user lists the locked joints
    renamed: dict[int, str]  # link frames renamed by unique_frame_names: {frame id: URDF name}


def unique_frame_names(model: pin.Model) -> dict[int, str]:
    """Rename, in ``model``, a link frame ``<name>_link`` where a joint has its name (Pinocchio
    cannot reduce a model whose frames share a name); returns {frame id: its old name}.
    """
    names = collections.Counter(f.name for f in model.frames)
    old = {}
    for i, frame in enumerate(model.frames):
        if names[frame.name] > 1 and frame.type == pin.FrameType.BODY:
            renamed = pin.Frame(frame)
            renamed.name = frame.name + "_link"
            while names[renamed.name]:
                renamed.name += "_"
            names[renamed.name] += 1
            old[i] = frame.name
            model.frames[i] = renamed
    return old


def _build(source: str, locked_joints=None, chain=None, say_notes: bool = True) -> _Built:
    """Parse a source. Mimic joints are locked, except where the user lists the locked joints
    and no chain: then a mimic joint must be among them (the URDF check says so). A floating base
    is said in a warning (``say_notes``: the viewer loads the robot a second time, quietly).
    """
    kind, value = _resolve(source)
    if kind == "erd":
        if not is_example_robot(value):
            close = difflib.get_close_matches(value, robot_names(), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise RobotLoadError(
                value,
                f"not a URDF file, not planar<N>, and not a robot example-robot-data "
                f"ships{hint} (nnrobust robots --all lists them)",
            )
        example = example_robot(value)
        model = with_revolute_continuous_joints(pin.Model(example.model))  # a copy: the load is cached
        if example.note and say_notes:
            warnings.warn(f"{value}: {example.note}", stacklevel=3)
        return _Built(
            model, f"example-robot-data:{value}", None, None, example, frozenset(), unique_frame_names(model)
        )
    generated = PLANAR_CHAIN_NAME.match(source) is not None
    name = value if kind == "file" else (source if generated else "<urdf string>")
    text = read_urdf_file(value) if kind == "file" else value
    base = Path(value).resolve().parent if kind == "file" else None
    mimic = frozenset() if generated else mimic_joints(text)
    if not generated:
        user = frozenset(locked_joints or ())
        explicit = locked_joints is not None and chain is None
        with warnings.catch_warnings():
            if not say_notes:  # said when the robot was loaded for its dynamics
                warnings.simplefilter("ignore")
            text = check_urdf(text, name, locked=user if explicit else user | mimic)
    model = parsed(name, "invalid URDF", lambda: pin.buildModelFromXML(text))
    if model.nq == 0 and model.njoints <= 1:
        raise ModelMismatch(f"{name}: the URDF has no movable joint (only fixed joints)")
    model = with_revolute_continuous_joints(model)
    return _Built(model, name, text, base, None, mimic, unique_frame_names(model))


def _locks(built: _Built, source: str, locked_joints, chain) -> tuple[list[str], str]:
    """The joints to lock and the default task frame (module :mod:`.chains`)."""
    model = built.model
    missing = [j for j in locked_joints or () if not model.existJointName(j)]
    if missing:
        raise RobotLoadError(
            built.name, f"cannot lock unknown joints {missing}; joints: {list(model.names)[1:]}"
        )
    if chain is not None:
        base, tip = chain
        names = chain_between(model, base, tip) + list(locked_joints or [])
        return sorted(set(names) | built.mimic, key=model.getJointId), tip
    if locked_joints is None and "locked_joints" in ARMS.get(source, {}):
        locked_joints = ARMS[source]["locked_joints"]
    if locked_joints is not None:
        return list(locked_joints), ""
    frame, names = default_chain(model)
    return sorted(set(names) | built.mimic, key=model.getJointId), frame


def locked_joint_names(source: str | Path, locked_joints=None, chain=None) -> list[str]:
    """The joints :func:`load_robot` locks (held at their neutral value) for these arguments."""
    _check_names(str(source), locked_joints, chain)
    built = _build(str(source), locked_joints, chain, say_notes=False)
    return _locks(built, str(source), locked_joints, chain)[0]


def _reduced(built: _Built, locked: list[str], visual: pin.GeometryModel | None = None):
    """The model (and visual geometry) with ``locked`` held at their neutral value; a joint
    that is still not one angle or one length is refused by name.
    """
    ids = [built.model.getJointId(j) for j in locked]
    model = built.model
    if ids and visual is None:
        model = pin.buildReducedModel(model, ids, pin.neutral(model))
    elif ids:
        model, visual = pin.buildReducedModel(model, visual, ids, pin.neutral(model))
    odd = [
        f"{model.names[i]!r} ({model.joints[i].shortname().removeprefix('JointModel')})"
        for i in range(1, model.njoints)
        if model.joints[i].nq != model.joints[i].nv
    ]
    if odd:
        raise ModelMismatch(
            f"{built.name}: joints {', '.join(odd)} have no single angle or length; lock "
            "them (robot.locked_joints) or choose a chain without them (robot.chain)"
        )
    if model.nv == 0:
        raise ModelMismatch(f"{built.name}: every joint is locked; nothing is left to move")
    return model, visual


def load_visual_model(
    source: str | Path,
    locked_joints: list[str] | None = None,
    chain: Sequence[str] | None = None,
    mesh_folders: Sequence[str | Path] = (),
) -> tuple[pin.Model, pin.GeometryModel]:
    """The kinematic model and the visual geometry (meshes and primitives) of an arm, for viewers.

    Same sources, joint locking and chain as :func:`load_robot`. Mesh files are read only from
    the folders of :func:`~nnrobust.model.urdf_check.mesh_roots` (next to a URDF file, in the
    working folder for a URDF given as text, in ROS_PACKAGE_PATH, and in ``mesh_folders``:
    ``robot.mesh_folders``); a visual whose mesh lies elsewhere or is missing is left out (one
    warning each), the rest of the robot is drawn.
    """
    source = str(source)
    _check_names(source, locked_joints, chain)
    built = _build(source, locked_joints, chain, say_notes=False)
    locked, _ = _locks(built, source, locked_joints, chain)
    return _reduced(built, locked, _visual_geometry(built, source, mesh_folders))


def _visual_geometry(
    built: _Built, source: str, mesh_folders: Sequence[str | Path] = ()
) -> pin.GeometryModel:
    """The visual geometry of a parsed robot. Mesh files are left for the viewer to read: the
    parser sees each mesh as a point (it would otherwise build a collision structure of every
    mesh, unused by a viewer), and the objects get the files back afterwards.
    """
    example = built.example
    base: Path | None
    if example is not None:
        if example.urdf is None:  # built by example-robot-data's own code
            return example_visual_model(example)
        text, base = read_urdf_file(example.urdf), example.urdf.parent
        roots = [Path(d).resolve() for d in example.package_dirs] + listed_mesh_folders(mesh_folders)
    else:
        text, base = built.text or "", built.base
        roots = mesh_roots(base, mesh_folders)
    if not PLANAR_CHAIN_NAME.match(source):
        text = resolved_visuals(text, built.name, base, roots)
    text, meshes = visual_meshes_set_aside(text)
    model = pin.Model(built.model)
    for fid, name in built.renamed.items():  # the parser finds links by their URDF names
        frame = pin.Frame(model.frames[fid])
        frame.name = name
        model.frames[fid] = frame
    visual = parsed(
        built.name,
        "cannot read the visual geometry",
        lambda: pin.buildGeomFromUrdfString(model, text, pin.GeometryType.VISUAL),
    )
    for obj in visual.geometryObjects:
        if obj.name in meshes:
            path, scale = meshes[obj.name]
            obj.geometry = coal.BVHModelOBBRSS()  # a mesh, read from meshPath by the viewer
            obj.meshPath = path
            obj.meshScale = np.asarray(scale, dtype=float)
    return visual


def urdf_digest(source: str) -> str:
    """SHA-256 of the URDF text a source reads (a file, the text itself, a shipped or generated
    arm, an example-robot-data robot's file); "" for a robot built by example-robot-data's code.
    """
    kind, value = _resolve(str(source))
    if kind == "erd":
        robot = example_robot(value) if is_example_robot(value) else None
        if robot is None or robot.urdf is None:
            return ""
        data = robot.urdf.read_bytes()
    elif kind == "file":
        data = local(value).read_bytes()
    else:
        data = value.encode("utf-8")
    return hashlib.sha256(data).hexdigest()


def default_task_frame(model: pin.Model) -> str:
    """The task frame the rule of :mod:`nnrobust.model.chains` picks (the tool frame at the end
    of the longest chain, else the chain's tip).
    """
    return default_chain(model)[0]


MAX_GRAVITY = 1e3
"""Largest gravity component accepted [m/s^2] (100 g)."""


def _check_names(source: str, locked_joints: object, chain: object) -> None:
    """``chain`` is None or 2 frame names, ``locked_joints`` None or a list of joint names."""

    def names(value: object) -> bool:
        return isinstance(value, (list, tuple)) and all(isinstance(x, str) and x.strip() for x in value)

    if chain is not None and not (names(chain) and len(chain) == 2):  # type: ignore[arg-type]
        raise RobotLoadError(source, f"chain needs 2 frame names, (base, tip), got {_shown(chain)}")
    if locked_joints is not None and not names(locked_joints):
        raise RobotLoadError(
            source,
            f"locked_joints needs a list of joint names ([] locks nothing, None the default rule), "
            f"got {_shown(locked_joints)}",
        )


def _shown(value: object) -> str:
    """A value as a message shows it: its repr, at most 80 characters, with its type."""
    text = repr(value)
    text = text if len(text) <= 80 else text[:77] + "..."
    return f"{type(value).__name__} {text}"


def load_robot(
    source: str | Path,
    task_frame: str | None = None,
    task: str = "planar",
    gravity: tuple[float, ...] | None = None,
    locked_joints: list[str] | None = None,
    chain: Sequence[str] | None = None,
) -> PinocchioModel:
    """Load an arm as a :class:`PinocchioModel`.

    Args:
        source: a URDF path, a URDF XML string, ``"three_link_planar"`` (the paper's arm),
            ``"planar<N>"`` (a generated N-link planar chain) or an example-robot-data robot
            name such as ``"panda"`` (``nnrobust robots --all`` lists them).
        task_frame: frame whose position (or pose) is the task; default: the rule of
            :mod:`nnrobust.model.chains` (a tool, end-effector or hand frame at the end of the
            longest chain), or the tip of ``chain``.
        task: ``"planar"`` (m = 2), ``"position"`` (m = 3) or ``"pose"`` (m = 6).
        gravity: gravity vector [m/s^2]; default Pinocchio's (0, 0, -9.81).
        locked_joints: joints held at their neutral value (zero angle or length); default: every
            joint off the default chain, and gripper, finger and mimic joints
            (``[]`` locks nothing).
        chain: ``(base frame, tip frame)``: the arm is the joints between them, every other joint
            is locked (and so are ``locked_joints``).

    Continuous joints become revolute joints without limits (one angle each); a floating base
    is fixed to the world (a warning says so).

    """
    source = str(source)
    if task_frame is not None and (not isinstance(task_frame, str) or not task_frame.strip()):
        raise RobotLoadError(
            source, f"task_frame needs a frame's name (or None for the default rule), got {task_frame!r}"
        )
    _check_names(source, locked_joints, chain)
    if gravity is not None:
        entries = list(gravity) if isinstance(gravity, (list, tuple, np.ndarray)) else []
        if len(entries) != 3 or not all(
            isinstance(x, (int, float, np.floating))
            and not isinstance(x, bool)
            and abs(float(x)) <= MAX_GRAVITY
            for x in entries
        ):
            raise RobotLoadError(
                source, f"gravity needs 3 finite numbers of at most {MAX_GRAVITY:g} m/s^2, got {gravity!r}"
            )
    built = _build(source, locked_joints, chain)
    locked, frame = _locks(built, source, locked_joints, chain)
    model, _ = _reduced(built, locked)
    if gravity is not None:
        model.gravity.linear = np.asarray(gravity, dtype=float)
    frame = task_frame or frame or default_task_frame(model)
    robot = PinocchioModel(model, frame, task=task, name=built.name)
    robot.urdf_text = (
        built.text
        if built.example is None
        else (read_urdf_file(built.example.urdf) if built.example.urdf is not None else None)
    )
    return robot
