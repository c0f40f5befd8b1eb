"""A user's trajectory, disturbance and self-motion criterion, built from an experiment's keys and
checked against their contracts before anything runs (docs/extending.md). A user's controller is
built by :mod:`nnrobust.controllers.custom`.

Each is ``Class(robot, **params)``, with ``robot`` the arm's model (:class:`nnrobust.PinocchioModel`
from the URDF: ``nq``, ``m``, ``task_position``, ``lower_limits``, ``mid_configuration``, ...).
"""

from __future__ import annotations

import numpy as np

from .exceptions import ConfigError
from .model.pinocchio_model import PinocchioModel
from .model.tasks import TASK_KINDS
from .plant.disturbance import Disturbance
from .subtasks.base import Criterion
from .trajectories import Trajectory
from .user_code import construct, located


def _vector(key: str, what: str, value, size: int) -> np.ndarray:
    """A call's result as a finite vector of ``size`` entries, or one line naming the class key."""
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ConfigError(key, f"{what} returned {type(value).__name__}, not numbers ({err})") from err
    if out.shape != (size,):
        raise ConfigError(key, f"{what} returned shape {out.shape}; expected ({size},)")
    if not np.all(np.isfinite(out)):
        raise ConfigError(key, f"{what} returned a non-finite value: {out.tolist()}")
    return out


def _call(key: str, what: str, function, *args):
    try:
        return function(*args)
    except Exception as err:
        raise ConfigError(key, f"{what} raised {located(err)}") from err


def build_trajectory(spec: str, params: dict | None, robot: PinocchioModel, task: str) -> Trajectory:
    """``trajectory.kind = "custom"``: the class's trajectory, with m and x_d(0), x_d'(0), x_d''(0)
    of the task's size.
    """
    key = "trajectory.class"
    trajectory = construct(spec, params, Trajectory, key, "trajectory.params", robot, "robot")
    name, m = type(trajectory).__name__, TASK_KINDS[task]
    if getattr(trajectory, "m", None) != m:
        raise ConfigError(key, f"{name}.m is {getattr(trajectory, 'm', None)!r}; the {task} task has m = {m}")
    out = _call(key, f"{name}(0.0)", trajectory, 0.0)
    if not (isinstance(out, tuple) and len(out) == 3):
        raise ConfigError(key, f"{name}(t) must return (x_d, x_d', x_d''), got {type(out).__name__}")
    for value, what in zip(out, ("x_d", "x_d'", "x_d''")):
        _vector(key, f"{name}(0.0)'s {what}", value, m)
    return trajectory


def build_disturbance(spec: str, params: dict | None, robot: PinocchioModel) -> Disturbance:
    """``plant.disturbance = "custom"``: the class's tau_d, one finite torque per joint at t = 0."""
    key = "plant.disturbance_class"
    disturbance = construct(spec, params, Disturbance, key, "plant.disturbance_params", robot, "robot")
    name = type(disturbance).__name__
    _vector(key, f"{name}(0.0)", _call(key, f"{name}(0.0)", disturbance, 0.0), robot.nq)
    return disturbance


def build_criterion(spec: str, params: dict | None, robot: PinocchioModel) -> Criterion:
    """A ``custom`` entry of ``subtasks.criteria``: h(q) a finite number and dh/dq one entry per
    joint, at the middle of the joints' range.
    """
    key = "subtasks.criterion_class"
    criterion = construct(spec, params, Criterion, key, "subtasks.criterion_params", robot, "robot")
    name, q = type(criterion).__name__, robot.mid_configuration
    value = _call(key, f"{name}.value", criterion.value, robot, q)
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)) or not np.isfinite(value):
        raise ConfigError(key, f"{name}.value(model, q) must return a finite number, got {value!r}")
    _vector(
        key,
        f"{name}.gradient(model, q)",
        _call(key, f"{name}.gradient", criterion.gradient, robot, q),
        robot.nq,
    )
    return criterion
