"""The controller contract: a sampled torque law with explicit internal state, what it returns,
and what it is given to build itself (docs/extending.md).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..model.base import DynamicsModel
    from ..plant.friction import Friction
    from ..subtasks.base import Criterion
    from ..trajectories import Trajectory
    from .pseudoinverse import DampedPseudoInverse


@dataclass
class ControlOutput:
    """What a controller returns at a control instant.

    Attributes:
        tau: commanded joint torques [N m].
        signals: scalar signals to record (e.g. rho_hat, eps, damping).
        state: the internal state z at the next control instant (None: unchanged).

    """

    tau: np.ndarray
    signals: dict[str, float] = field(default_factory=dict)
    state: np.ndarray | None = None


class Controller(ABC):
    """A sampled control law: at t_k it maps the measured (q, q') and its state z_k to a torque
    held over [t_k, t_k + T) and to z_{k+1}.

    A real controller knows the state only at its sampling instants, so an adaptive law is
    advanced over each period with its inputs held (exactly, where the law allows). The state is
    explicit, so a run is reproducible and restartable from (t, q, q', z).
    """

    state_size: int = 0
    signal_names: tuple[str, ...] = ()

    def initial_state(self) -> np.ndarray:
        """z(0)."""
        return np.zeros(self.state_size)

    def scale_gains(self, position: float, velocity: float) -> bool:
        """From the next :meth:`compute` on, the law's position and velocity gains are its own
        times ``position`` and ``velocity`` (a policy's ``gains`` action, docs/learning.md);
        False for a law without such a pair of gains (this default).
        """
        return False

    @abstractmethod
    def compute(
        self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray, period: float = 0.0
    ) -> ControlOutput:
        """Torque, signals and (for a stateful law) z after ``period`` [s] at time t [s]."""


@dataclass(frozen=True)
class ControllerContext:
    """What an experiment hands a controller's constructor: ``Class(context, **params)``.

    Everything here is what a real controller may know: the nominal model (never the true
    plant), the desired motion, the sampling period and the actuators' limits. All of it is the
    controller's own copy: a law may change it (adapt its model in place) without reaching the
    true plant or the recorded x_d, e and h.

    Attributes:
        nominal: the controller's model of the arm (:class:`nnrobust.DynamicsModel`: ``mass``,
            ``bias``, ``gravity``, ``inverse_dynamics``, ``task_state``, ``task_jacobian``,
            ``task_jdot_v``, ...; ``nominal.pinocchio_model`` is its ``pin.Model``, or None for
            the closed-form arm).
        trajectory: t -> (x_d, x_d', x_d'') [m, m/s, m/s^2; rad for a pose's angles], with
            ``trajectory.error(x, x_d)`` the task error e = x - x_d (a rotation error for a pose).
        criterion: the self-motion criterion h(q) of eq. (4) (``value(model, q)``,
            ``gradient(model, q)``), or None when the experiment has none.
        period: the control period T [s]; ``compute`` is called at t_k = k T.
        torque_limits: effort limits per joint [N m or N] (commands beyond them are clipped by the
            plant), or None.
        q0: the initial joint positions [rad or m].
        lower_limits, upper_limits: joint position limits [rad or m] (+-inf where there is none).
        nominal_friction: F-hat, the friction the experiment's nominal section declares.
        null_space_gain: k of eq. (3) [1/s] (``controller.k``).
        pseudo_inverse: the damped J+ of the experiment (``controller.pinv_*``).

    """

    nominal: DynamicsModel
    trajectory: Trajectory
    criterion: Criterion | None
    period: float
    torque_limits: np.ndarray | None
    q0: np.ndarray
    lower_limits: np.ndarray
    upper_limits: np.ndarray
    nominal_friction: Friction
    null_space_gain: float
    pseudo_inverse: DampedPseudoInverse

    @property
    def n(self) -> int:
        """Number of joints."""
        return self.nominal.nq

    @property
    def m(self) -> int:
        """Task dimension."""
        return self.nominal.m
