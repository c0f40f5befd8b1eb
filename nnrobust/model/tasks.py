"""Task kinds: what the task coordinates x are, their dimension m, and the task error e(x, x_d).

A position task (``planar``, m = 2; ``position``, m = 3) has x = the task frame's world position
and e = x - x_d. A ``pose`` task (m = 6) carries x as 12 numbers, the position p and the rotation
matrix R row by row, and its error is

    e = [p - p_d, log3(R R_d^T)]

with the orientation error a rotation vector in the world frame. Its rate is the world-frame
angular velocity error w - w_d to first order, which is why the pose Jacobian is the frame
Jacobian in the world-aligned (LOCAL_WORLD_ALIGNED) convention: its linear rows give p' and its
angular rows give w, both in world axes, so that J q' - x_d' = [p' - p_d', w - w_d].
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

TASK_KINDS = {"planar": 2, "position": 3, "pose": 6}
"""Task kinds and their dimension m."""

COORDINATE_SIZE = {"planar": 2, "position": 3, "pose": 12}
"""Length of the task coordinate vector x of each kind (the pose carries R as 9 numbers)."""


def pose_vector(translation: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """X of a pose task: [p, R row by row], 12 numbers."""
    return np.concatenate([translation, np.asarray(rotation).reshape(9)])


def split_pose(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(p, R) from the 12 pose coordinates."""
    return x[:3], x[3:12].reshape(3, 3)


def task_error(kind: str, x: np.ndarray, x_d: np.ndarray) -> np.ndarray:
    """E = x - x_d, or [p - p_d, log3(R R_d^T)] for a pose (m numbers)."""
    if kind != "pose":
        return x - x_d
    p, R = split_pose(x)
    p_d, R_d = split_pose(x_d)
    return np.concatenate([p - p_d, pin.log3(R @ R_d.T)])


def display_coordinates(kind: str, x: np.ndarray) -> np.ndarray:
    """M numbers for plots and files: x itself, or [p, log3(R)] (rotation vector) for a pose."""
    if kind != "pose":
        return np.asarray(x, dtype=float)
    p, R = split_pose(x)
    return np.concatenate([p, pin.log3(R)])
