"""Continuous joints as plain revolute joints: one angle per joint, the same dynamics.

Pinocchio gives a continuous (unbounded revolute) joint two configuration coordinates,
(cos θ, sin θ), so that nq > nv. The closed loop, the plant, the criteria and every result
speak of one angle per joint. A continuous joint is therefore rebuilt as the revolute joint
about the same axis with no position limit: its kinematics and dynamics are those of the
unbounded joint at the same angle (tests/model/test_any_robot.py checks M, the bias forces and the
frame Jacobians at random states), and its angle is not wrapped, so it counts turns.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

_REVOLUTE = {
    "JointModelRUBX": pin.JointModelRX,
    "JointModelRUBY": pin.JointModelRY,
    "JointModelRUBZ": pin.JointModelRZ,
}

_V_SIZED = (
    "effortLimit",
    "velocityLimit",
    "lowerEffortLimit",
    "upperEffortLimit",
    "lowerVelocityLimit",
    "upperVelocityLimit",
    "lowerDryFrictionLimit",
    "upperDryFrictionLimit",
    "friction",
    "damping",
    "armature",
    "rotorInertia",
    "rotorGearRatio",
)
"""Per-velocity-coordinate arrays of a Model that carry over unchanged (those this Pinocchio has)."""


def _revolute_twin(joint) -> pin.JointModel | None:
    """The bounded revolute joint model for an unbounded one, else None."""
    kind = joint.shortname()
    if kind in _REVOLUTE:
        return _REVOLUTE[kind]()
    if kind == "JointModelRevoluteUnboundedUnaligned":
        return pin.JointModelRevoluteUnaligned(joint.extract().axis)
    return None


def continuous_joint_names(model: pin.Model) -> list[str]:
    """The joints Pinocchio represents by (cos, sin)."""
    return [model.names[i] for i in range(1, model.njoints) if _revolute_twin(model.joints[i]) is not None]


def angles_from_configuration(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """A configuration of ``model`` (cos/sin pairs for continuous joints) as one angle per joint."""
    out = np.empty(model.nv)
    for i in range(1, model.njoints):
        joint = model.joints[i]
        if _revolute_twin(joint) is not None:
            c, s = q[joint.idx_q], q[joint.idx_q + 1]
            out[joint.idx_v] = np.arctan2(s, c)
        else:
            out[joint.idx_v : joint.idx_v + joint.nv] = q[joint.idx_q : joint.idx_q + joint.nq]
    return out


def configuration_from_angles(model: pin.Model, angles: np.ndarray) -> np.ndarray:
    """The inverse of :func:`angles_from_configuration`: ``model``'s configuration for the angles."""
    q = np.empty(model.nq)
    for i in range(1, model.njoints):
        joint = model.joints[i]
        if _revolute_twin(joint) is not None:
            a = angles[joint.idx_v]
            q[joint.idx_q : joint.idx_q + 2] = np.cos(a), np.sin(a)
        else:
            q[joint.idx_q : joint.idx_q + joint.nq] = angles[joint.idx_v : joint.idx_v + joint.nv]
    return q


def with_revolute_continuous_joints(model: pin.Model) -> pin.Model:
    """``model`` with every continuous joint rebuilt as a revolute joint without position limits
    (the same model when it has none). Joint and frame indices, names, inertias, limits,
    friction and reference configurations carry over.
    """
    if not continuous_joint_names(model):
        return model
    new = pin.Model()
    new.name = model.name
    new.gravity = model.gravity
    lower, upper = [], []
    for i in range(1, model.njoints):
        joint = model.joints[i]
        twin = _revolute_twin(joint)
        added = new.addJoint(
            model.parents[i], joint if twin is None else twin, model.jointPlacements[i], model.names[i]
        )
        assert added == i
        new.appendBodyToJoint(i, model.inertias[i], pin.SE3.Identity())
        if twin is None:
            lower.append(model.lowerPositionLimit[joint.idx_q : joint.idx_q + joint.nq])
            upper.append(model.upperPositionLimit[joint.idx_q : joint.idx_q + joint.nq])
        else:
            lower.append([-np.inf])
            upper.append([np.inf])
    for frame in list(model.frames)[1:]:  # the universe frame is there already
        new.addFrame(pin.Frame(frame), False)  # the inertias are in the joints' bodies already
    for attribute in _V_SIZED:
        if hasattr(model, attribute):
            setattr(new, attribute, np.array(getattr(model, attribute), dtype=float))
    new.lowerPositionLimit = np.concatenate(lower).astype(float)
    new.upperPositionLimit = np.concatenate(upper).astype(float)
    for entry in model.referenceConfigurations:
        new.referenceConfigurations[entry.key()] = angles_from_configuration(model, np.asarray(entry.data()))
    return new
