"""How an experiment builds its desired trajectory from ``[trajectory]``: the declared path
(nnrobust/trajectories/registry.py), with a rocking or held orientation for a pose task, or a
user's class.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from .base import Trajectory
from .pose import PoseTrajectory, PositionPath
from .registry import PATH_KINDS, path_key


def build_path(config, robot) -> PositionPath:
    """The position path of ``trajectory.kind`` (its declaration's builder)."""
    return PATH_KINDS[config.trajectory.kind].build(config, robot)  # type: ignore[return-value]


def build_trajectory(config, robot) -> Trajectory:
    """The position path (:func:`build_path`), with a rocking or held orientation for a pose task;
    or a user's trajectory (``kind = "custom"``).
    """
    from .. import user_parts
    from ..ik import reach, seed_configuration
    from ..model import PinocchioModel
    from ..model.tasks import split_pose

    tc = config.trajectory
    if tc.kind == "custom":
        return user_parts.build_trajectory(tc.class_ or "", tc.params, robot, robot.task)
    path = build_path(config, robot)
    if robot.task != "pose":
        return path
    if tc.orientation_rpy is not None:
        R0 = pin.rpy.rpyToMatrix(*tc.orientation_rpy)
    else:  # the orientation the arm has when its tip is at p_d(0)
        position_task = PinocchioModel(robot.model, robot.task_frame, "position", robot.name)
        seed = seed_configuration(config, robot)
        q = reach(position_task, path(0.0)[0], seed, "p_d(0)", f"trajectory.{path_key(tc)}")
        R0 = split_pose(robot.task_position(q))[1].copy()
    return PoseTrajectory(
        path,
        R0,
        np.asarray(tc.rotation_axis, dtype=float),
        tc.rotation_amplitude,
        tc.rotation_omega,
        tc.rotation_phase,
    )
