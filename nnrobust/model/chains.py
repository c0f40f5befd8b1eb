"""Which joints are the arm: the default chain and task frame of a robot, or a chosen sub-chain.

The rule (docs/robots.md, "The default chain"):

1. The task frame is a body or operational frame whose name says it is a tool: by preference
   ``tcp``, then ``tool``, then ``ee``/``eef``/``end_effector``, ``hand``, ``gripper``,
   ``wrist``, and for legs ``foot``/``toe``. Among those, the frame with the most arm joints
   between it and the root wins, then the earlier preference, then the frame that comes last
   in the model (the deepest). A robot with no such frame takes the tip of its longest chain.
2. The arm joints are the moving joints from the root to that frame, except gripper and finger
   joints (names with finger, gripper, thumb, knuckle, jaw or hand), unless the robot is a
   hand or a finger and has no other joints. Every other joint (other arms,
   legs, a head, wheels, fingers) is locked at its neutral value.

``robot.chain = ["base_link", "tool0"]`` picks the joints between two frames instead.
"""

from __future__ import annotations

import re

import pinocchio as pin

from ..core.exceptions import RobotLoadError
from .pinocchio_model import LINK_FRAME_TYPES, frame_id

TIP_PREFERENCE = (
    ("tcp", re.compile(r"tcp")),
    ("tool", re.compile(r"tool")),
    ("ee", re.compile(r"(^|_)(ee|eef|end_?effector)(_|$|\d)|endeffector")),
    ("hand", re.compile(r"hand")),
    ("gripper", re.compile(r"gripper|grasp")),
    ("wrist", re.compile(r"wrist")),
    ("foot", re.compile(r"foot|feet|toe")),
)
"""Frame-name patterns that mark a task frame, most preferred first (matched lower-cased)."""

HAND_JOINT = re.compile(r"finger|gripper|thumb|knuckle|jaw|hand", re.IGNORECASE)
"""Joint names of grippers and fingers: never arm joints by default."""


def _path_joints(model: pin.Model, frame_id: int) -> list[int]:
    """The moving joints from the root to the frame, root first."""
    return [j for j in model.supports[model.frames[frame_id].parentJoint] if j > 0]


def _arm_joints(model: pin.Model, joints: list[int]) -> list[int]:
    return [j for j in joints if not HAND_JOINT.search(model.names[j])]


def _preference(name: str) -> int | None:
    lowered = name.lower()
    for rank, (_, pattern) in enumerate(TIP_PREFERENCE):
        if pattern.search(lowered):
            return rank
    return None


def default_chain(model: pin.Model) -> tuple[str, list[str]]:
    """(task frame, joints to lock) by the rule of this module's docstring."""
    best, best_key = None, None
    for fid, frame in enumerate(model.frames):
        if frame.type not in LINK_FRAME_TYPES or frame.parentJoint == 0:
            continue
        rank = _preference(frame.name)
        path = _path_joints(model, fid)
        joints = _arm_joints(model, path) or path
        # keyword frames before all others; then more arm joints, the earlier keyword, the last frame
        key = (rank is None, -len(joints), rank if rank is not None else 0, -fid)
        if best_key is None or key < best_key:
            best, best_key = fid, key
    if best is None:
        raise RobotLoadError(
            model.name, "no movable joint: nothing to control (a floating base alone is fixed to the world)"
        )
    path = _path_joints(model, best)
    keep = set(_arm_joints(model, path) or path)  # a robot that is a hand or a finger keeps its joints
    locked = [model.names[j] for j in range(1, model.njoints) if j not in keep]
    return model.frames[best].name, locked


def _frame_id(model: pin.Model, name: str, role: str) -> int:
    if not model.existFrame(name):
        names = sorted({f.name for f in model.frames if f.type in LINK_FRAME_TYPES})
        raise RobotLoadError(
            model.name,
            f"robot.chain: {role} frame {name!r} is not in the model; body "
            f"frames: {', '.join(names[:60])}{' ...' if len(names) > 60 else ''}",
        )
    return frame_id(model, name)


def chain_between(model: pin.Model, base: str, tip: str) -> list[str]:
    """The joints to lock so that the arm is the joints between frames ``base`` and ``tip``
    (``base`` must be on the way from the root to ``tip``).
    """
    base_id, tip_id = _frame_id(model, base, "base"), _frame_id(model, tip, "tip")
    below_base = set(_path_joints(model, base_id))
    tip_path = _path_joints(model, tip_id)
    base_joint = model.frames[base_id].parentJoint
    if base_joint and base_joint not in tip_path:
        raise RobotLoadError(
            model.name,
            f"robot.chain: frame {base!r} is not between the root and "
            f"{tip!r}; the chain runs from a frame to one of its descendants",
        )
    keep = [j for j in tip_path if j not in below_base]
    if not keep:
        raise RobotLoadError(model.name, f"robot.chain: no moving joint between {base!r} and {tip!r}")
    return [model.names[j] for j in range(1, model.njoints) if j not in keep]
