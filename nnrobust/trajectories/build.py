"""How an experiment builds its desired trajectory from its own section, ``[trajectory]``
(:mod:`.section`): the declared path (nnrobust/trajectories/registry.py), with a rocking or held
orientation for a pose task, or a user's class. Beyond its section a builder takes
``simulation.q_seed``, chosen by the composition root (:func:`nnrobust.run.experiment.build`): where
a path without a start, or a pose without an orientation, is read from.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..model import PinocchioModel
from ..model.ik import reach, seed_configuration
from ..model.tasks import split_pose
from .base import Trajectory
from .custom import build_trajectory as build_custom_trajectory
from .pose import PoseTrajectory, PositionPath
from .registry import PATH_KINDS, path_key
from .section import TrajectoryConfig


def build_path(tc: TrajectoryConfig, robot, q_seed: list[float] | None) -> PositionPath:
    """The position path of ``trajectory.kind`` (its declaration's builder)."""
    return PATH_KINDS[tc.kind].build(tc, robot, q_seed)  # type: ignore[return-value]


def build_trajectory(tc: TrajectoryConfig, robot, q_seed: list[float] | None) -> Trajectory:
    """The position path (:func:`build_path`), with a rocking or held orientation for a pose task;
    or a user's trajectory (``kind = "custom"``).
    """
    if tc.kind == "custom":
        return build_custom_trajectory(tc.class_ or "", tc.params, robot, robot.task)
    path = build_path(tc, robot, q_seed)
    if robot.task != "pose":
        return path
    if tc.orientation_rpy is not None:
        R0 = pin.rpy.rpyToMatrix(*tc.orientation_rpy)
    else:  # the orientation the arm has when its tip is at p_d(0)
        position_task = PinocchioModel(robot.model, robot.task_frame, "position", robot.name)
        seed = seed_configuration(q_seed, robot)
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
