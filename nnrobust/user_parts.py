"""A user's trajectory, disturbance and self-motion criterion, built from an experiment's keys and
checked against their contracts before anything runs (docs/extending.md). A user's controller is
built by :mod:`nnrobust.controllers.custom`.

Each is ``Class(robot, **params)``, with ``robot`` the arm's model (:class:`nnrobust.PinocchioModel`
from the URDF: ``nq``, ``m``, ``task_position``, ``lower_limits``, ``mid_configuration``, ...).

The experiment holds each one inside a checked wrapper (:class:`CheckedTrajectory`,
:class:`CheckedDisturbance`, :class:`CheckedCriterion`): every call during the run is checked as
the first one is (finite numbers of the right shape), and a breach is a one-line error naming the
class key and the time, never a NaN that a divergence message would blame on the gains. The
checks cost about 2 us a call (the custom parts run on the Python loop only).
"""

from __future__ import annotations

import numpy as np

from .exceptions import ConfigError
from .model.pinocchio_model import PinocchioModel
from .model.tasks import TASK_KINDS
from .numeric_limits import finite_number
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
    except (Exception, SystemExit) as err:  # a part may not end the process either
        raise ConfigError(key, f"{what} raised {located(err)}") from err


class CheckedTrajectory(Trajectory):
    """A user's trajectory with every x_d, x_d', x_d'' checked (m finite numbers each)."""

    KEY = "trajectory.class"

    def __init__(self, inner: Trajectory):
        self.inner, self.m = inner, inner.m
        self._name = type(inner).__name__

    def __call__(self, t: float):
        """The inner class's (x_d, x_d', x_d''), checked."""
        return self.checked(t, f"{self._name}({t:g})")

    def checked(self, t: float, what: str):
        """(x_d, x_d', x_d'') at t, each m finite numbers, or one line naming ``what``."""
        out = _call(self.KEY, what, self.inner, t)
        if not (isinstance(out, tuple) and len(out) == 3):
            raise ConfigError(self.KEY, f"{what} must return (x_d, x_d', x_d''), got {type(out).__name__}")
        m = self.m
        return tuple(_vector(self.KEY, f"{what}'s {w}", v, m) for v, w in zip(out, ("x_d", "x_d'", "x_d''")))

    def error(self, x: np.ndarray, x_d: np.ndarray) -> np.ndarray:
        """The inner class's task error, checked (m finite numbers)."""
        what = f"{self._name}.error"
        return _vector(self.KEY, what, _call(self.KEY, what, self.inner.error, x, x_d), self.m)

    def __getattr__(self, name: str):  # the class's own attributes, read through
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)


class CheckedDisturbance(Disturbance):
    """A user's disturbance with every tau_d(t) checked (n finite torques)."""

    KEY = "plant.disturbance_class"

    def __init__(self, inner: Disturbance, n: int):
        self.inner, self.n, self._name = inner, n, type(inner).__name__

    def __call__(self, t: float) -> np.ndarray:
        """The inner class's tau_d(t), checked."""
        return self.checked(t, f"{self._name}({t:g})")

    def checked(self, t: float, what: str) -> np.ndarray:
        """tau_d(t), n finite numbers, or one line naming ``what``."""
        return _vector(self.KEY, what, _call(self.KEY, what, self.inner, t), self.n)

    def __getattr__(self, name: str):
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)


class CheckedCriterion(Criterion):
    """A user's criterion with every h(q) (a finite number) and dh/dq (n finite numbers) checked."""

    KEY = "subtasks.criterion_class"

    def __init__(self, inner: Criterion, n: int):
        self.inner, self.n, self._name = inner, n, type(inner).__name__

    def value(self, model, q: np.ndarray) -> float:
        """The inner class's h(q), checked."""
        value = _call(self.KEY, f"{self._name}.value", self.inner.value, model, q)
        if not isinstance(value, (int, float, np.floating)) or not finite_number(value):
            raise ConfigError(
                self.KEY,
                f"{self._name}.value(model, q) must return a finite number, got {value!r} at q = {q}",
            )
        return float(value)

    def gradient(self, model, q: np.ndarray) -> np.ndarray:
        """The inner class's dh/dq, checked."""
        what = f"{self._name}.gradient(model, q)"
        return _vector(self.KEY, what, _call(self.KEY, what, self.inner.gradient, model, q), self.n)

    def __getattr__(self, name: str):
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)


def build_trajectory(spec: str, params: dict | None, robot: PinocchioModel, task: str) -> Trajectory:
    """``trajectory.kind = "custom"``: the class's trajectory, with m and x_d(0), x_d'(0), x_d''(0)
    of the task's size.
    """
    key = CheckedTrajectory.KEY
    trajectory = construct(spec, params, Trajectory, key, "trajectory.params", robot, "robot")
    name, m = type(trajectory).__name__, TASK_KINDS[task]
    if getattr(trajectory, "m", None) != m:
        raise ConfigError(key, f"{name}.m is {getattr(trajectory, 'm', None)!r}; the {task} task has m = {m}")
    checked = CheckedTrajectory(trajectory)
    checked.checked(0.0, f"{name}(0.0)")  # before anything runs, as at every call
    return checked


def build_disturbance(spec: str, params: dict | None, robot: PinocchioModel) -> Disturbance:
    """``plant.disturbance = "custom"``: the class's tau_d, one finite torque per joint at t = 0."""
    key = CheckedDisturbance.KEY
    disturbance = construct(spec, params, Disturbance, key, "plant.disturbance_params", robot, "robot")
    checked = CheckedDisturbance(disturbance, robot.nq)
    checked.checked(0.0, f"{type(disturbance).__name__}(0.0)")  # before anything runs, as at every call
    return checked


def build_criterion(spec: str, params: dict | None, robot: PinocchioModel) -> Criterion:
    """A ``custom`` entry of ``subtasks.criteria``: h(q) a finite number and dh/dq one entry per
    joint, at the middle of the joints' range.
    """
    key = CheckedCriterion.KEY
    criterion = construct(spec, params, Criterion, key, "subtasks.criterion_params", robot, "robot")
    checked = CheckedCriterion(criterion, robot.nq)
    checked.value(robot, robot.mid_configuration)  # before anything runs, as at every call
    checked.gradient(robot, robot.mid_configuration)
    return checked
