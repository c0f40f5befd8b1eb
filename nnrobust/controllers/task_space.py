"""The task-space control law with null-space subtasks, eq. (9)."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from ..core.numeric_limits import MAX_GAIN
from ..model.base import DynamicsModel
from ..plant.friction import Friction
from ..subtasks.base import Criterion
from ..trajectories import Trajectory
from .base import Controller, ControlOutput
from .pseudoinverse import DampedPseudoInverse, project_null_space
from .registry import KindParts, LawParam, PaperKind, SharedKeys, declare_kind, declare_shared


class RobustTerm(Protocol):
    """A robust term u_0 of eq. (9) (NNCompensator, SlidingModeCompensator, the RBF network's):
    ``output(q, q', y, z, T) -> (u_0, z_next, signals)`` with state z of ``state_size`` entries.
    A shipped term with a compiled twin (csrc/controllers/) also names it, ``twin``, and lists
    the attributes it reads, ``twin_fields``.
    """

    @property
    def state_size(self) -> int:
        """Entries of its state z."""

    @property
    def signal_names(self) -> tuple[str, ...]:
        """The scalar signals ``output`` returns."""

    def initial_state(self) -> np.ndarray:
        """z(0)."""

    def output(self, q: np.ndarray, v: np.ndarray, y: np.ndarray, z: np.ndarray, period: float):
        """(u_0, z after ``period``, signals) at the measured (q, q') and y = [e, e']."""


class TaskSpaceController(Controller):
    """tau = M-hat a + N-hat with a = J+ (x_d'' - J'q' - Kv e' - Kp e + u_0) + k (I - J+J)(grad h - q').

    Eq. (9). M-hat a + N-hat is one call of the nominal model's inverse dynamics (one RNEA pass for
    a Pinocchio model) plus the nominal friction. u_0 comes from the NN compensator (eq. 15), a
    sliding-mode term, or is zero: the "no-u0" baseline, which with the true model and friction
    as nominal is computed-torque control.

    Args:
        nominal: the controller's model (M-hat, N-hat, kinematics).
        trajectory: x_d(t).
        Kp, Kv: task gains, m x m diagonal positive [1/s^2, 1/s].
        k: self-motion gain of eq. (3).
        criterion: h(q) (already weighted, eq. 4); None for pure null-space damping.
        nominal_friction: F-hat(q') in N-hat.
        compensator: the robust term (NN or sliding mode); None for u_0 = 0.
        pinv: the damped pseudo-inverse.

    """

    twin = "task_space"  # csrc/controllers/task_space.cpp, with its robust term's twin
    twin_fields = ("Kp", "Kv", "k")

    def __init__(
        self,
        nominal: DynamicsModel,
        trajectory: Trajectory,
        Kp: np.ndarray,
        Kv: np.ndarray,
        k: float,
        criterion: Criterion | None = None,
        nominal_friction: Friction | None = None,
        compensator: RobustTerm | None = None,
        pinv: DampedPseudoInverse | None = None,
    ):
        self.nominal = nominal
        self.trajectory = trajectory
        self.Kp = np.asarray(Kp, dtype=float)
        self.Kv = np.asarray(Kv, dtype=float)
        self._own_gains = (self.Kp, self.Kv)
        self.k = float(k)
        self.criterion = criterion
        self.nominal_friction = nominal_friction or Friction.none(nominal.nq)
        self.compensator = compensator
        self.pinv = pinv or DampedPseudoInverse()
        self.state_size = compensator.state_size if compensator else 0
        self.signal_names = (compensator.signal_names if compensator else ()) + ("damping",)

    def initial_state(self) -> np.ndarray:
        """Compensator state [Z, eps], or nothing."""
        return self.compensator.initial_state() if self.compensator else np.zeros(0)

    def scale_gains(self, position: float, velocity: float) -> bool:
        """K_p and K_v are the law's own times ``position`` and ``velocity`` from now on."""
        Kp, Kv = self._own_gains
        self.Kp, self.Kv = position * Kp, velocity * Kv
        return True

    def _error(self, t: float, x: np.ndarray, J: np.ndarray, v: np.ndarray):
        xd, dxd, ddxd = self.trajectory(t)
        return self.trajectory.error(x, xd), J @ v - dxd, ddxd

    def compute(
        self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray, period: float = 0.0
    ) -> ControlOutput:
        """Eq. (9); the compensator's state is advanced over ``period``."""
        x, J, jdot_v = self.nominal.task_state(q, v)
        e, de, ddxd = self._error(t, x, J, v)
        signals: dict[str, float] = {}
        u0, z_next = 0.0, z
        if self.compensator is not None:
            u0, z_next, signals = self.compensator.output(q, v, np.concatenate([e, de]), z, period)
        inv, lam2 = self.pinv.factor(J)
        J_pinv = J.T @ inv
        signals["damping"] = lam2
        task_acc = ddxd - jdot_v - self.Kv @ de - self.Kp @ e + u0
        a = J_pinv @ task_acc
        if self.k != 0.0:
            grad = self.criterion.gradient(self.nominal, q) if self.criterion else 0.0
            a = a + self.k * project_null_space(J, J_pinv, grad - v)
        tau = self.nominal.inverse_dynamics(q, v, a) + self.nominal_friction.torque(v)
        return ControlOutput(tau, signals, z_next)


def sized_null_damping(nominal: DynamicsModel, q0: np.ndarray, Kd: np.ndarray, period: float) -> float:
    """The PD's null-space damping D sized from the arm at q(0) [N m s/rad].

    The self-motion q' = N s (N an orthonormal basis of ker J) has inertia M_s = N^T M N, and
    D (I - J+J) q' damps it at the rates eig(D M_s^-1). D is chosen so that it decays at the task
    damping's rate r, the geometric mean of eig(Lambda^-1 K_d) with Lambda^-1 = J M^-1 J^T (the
    rate at which K_d damps the task error), D = r m_s (m_s the geometric mean of eig M_s), and
    never faster than half the sampling rate on the lightest self-motion, D <= lambda_min(M_s) /
    (2 T): a damping torque held for a period T overshoots past D T / m = 1. An arm without
    self-motion (n = m) is damped at r times its mean joint inertia (the term then does nothing).
    """
    from scipy.linalg import null_space  # here: scipy, imported on first use (import time)

    M, J = nominal.mass(q0), nominal.task_jacobian(q0)
    rates = np.linalg.eigvals(J @ np.linalg.solve(M, J.T) @ np.asarray(Kd, dtype=float)).real
    rate = float(np.exp(np.mean(np.log(np.clip(rates, 1e-12, None)))))
    N = null_space(J)
    if N.shape[1] == 0:
        return rate * float(np.mean(np.diag(M)))
    inertia = np.clip(np.linalg.eigvalsh(N.T @ M @ N), 1e-12, None)
    return float(min(rate * np.exp(np.mean(np.log(inertia))), 0.5 * inertia[0] / period))


class TaskSpacePD(Controller):
    """PD with gravity compensation in task space: tau = J^T (-Kp e - Kd e') + G-hat - D (I - J+J) q'.

    The baseline without a dynamic model beyond gravity; the null-space damping D keeps the
    self-motion of a redundant arm from drifting.

    Args:
        nominal: the controller's model (G-hat and kinematics).
        trajectory: x_d(t).
        Kp: task stiffness, m x m [N/m].
        Kd: task damping, m x m [N s/m].
        null_damping: D [N m s/rad].

    """

    signal_names = ("damping",)
    twin = "task_space_pd"  # csrc/controllers/task_space.cpp
    twin_fields = ("Kp", "Kd", "null_damping")

    def __init__(
        self,
        nominal: DynamicsModel,
        trajectory: Trajectory,
        Kp: np.ndarray,
        Kd: np.ndarray,
        null_damping: float = 1.0,
        pinv: DampedPseudoInverse | None = None,
    ):
        self.nominal = nominal
        self.trajectory = trajectory
        self.Kp = np.asarray(Kp, dtype=float)
        self.Kd = np.asarray(Kd, dtype=float)
        self._own_gains = (self.Kp, self.Kd)
        self.null_damping = float(null_damping)
        self.pinv = pinv or DampedPseudoInverse()

    def scale_gains(self, position: float, velocity: float) -> bool:
        """K_p and K_d are the law's own times ``position`` and ``velocity`` from now on."""
        Kp, Kd = self._own_gains
        self.Kp, self.Kd = position * Kp, velocity * Kd
        return True

    def compute(
        self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray, period: float = 0.0
    ) -> ControlOutput:
        """Task-space PD plus G-hat(q) and null-space damping."""
        x, J, _ = self.nominal.task_state(q, v)
        xd, dxd, _ = self.trajectory(t)
        e, de = self.trajectory.error(x, xd), J @ v - dxd
        inv, lam2 = self.pinv.factor(J)
        tau = J.T @ (-self.Kp @ e - self.Kd @ de) + self.nominal.gravity(q)
        tau -= self.null_damping * project_null_space(J, J.T @ inv, v)
        return ControlOutput(tau, {"damping": lam2})


def eq9_law(
    parts: KindParts, term: RobustTerm | None = None, friction: Friction | None = None
) -> TaskSpaceController:
    """Eq. (9) as ``[controller]`` sets it (Kp, Kv, k; the context's pseudo-inverse) with the
    robust term ``term`` (None: u_0 = 0) and F-hat ``friction`` (None: the context's, the nominal
    section's).
    """
    c, context = parts.controller, parts.context
    return TaskSpaceController(
        parts.nominal,
        parts.trajectory,
        np.diag(c.Kp),
        np.diag(c.Kv),
        c.k,
        parts.criterion,
        friction or context.nominal_friction,
        term,
        context.pseudo_inverse,
    )


def _computed_torque(parts: KindParts) -> TaskSpaceController:
    """Eq. (9) with u_0 = 0 and the true friction as F-hat (the experiment makes the nominal model
    the true one).
    """
    true = parts.true_friction
    if true is None:
        raise ValueError("computed-torque needs the true friction")
    smoothing = parts.controller.coulomb_smoothing
    return eq9_law(parts, friction=Friction(true.viscous, true.coulomb, smoothing))


def _pd(parts: KindParts) -> TaskSpacePD:
    """The PD of ``controller.pd_Kp``, ``pd_Kd`` and ``pd_null_damping`` (sized from the arm at
    q(0) when unset).
    """
    c, context = parts.controller, parts.context
    Kd = np.diag(c.pd_Kd)
    damping = c.pd_null_damping
    if damping is None:
        damping = sized_null_damping(parts.nominal, context.q0, Kd, context.period)
    return TaskSpacePD(parts.nominal, parts.trajectory, np.diag(c.pd_Kp), Kd, damping, context.pseudo_inverse)


declare_shared(
    SharedKeys(
        "eq. (9)",
        (
            LawParam(
                "controller.Kp", (10.0,), "1/s^2", "task stiffness K_p (eq. 17 needs K_v^2 > K_p)", low=0.0,
                low_open=True, high=MAX_GAIN, size="m",
            ),
            LawParam(
                "controller.Kv", (4.0,), "1/s", "task damping K_v", low=0.0, low_open=True, high=MAX_GAIN,
                size="m",
            ),
            LawParam("controller.k", 10.0, "1/s", "self-motion gain k of eq. (3)", low=0.0, high=MAX_GAIN),
            LawParam(
                "controller.coulomb_smoothing", 0.0, "rad/s", "v_s: F-hat's Coulomb part uses sat(q' / v_s) "
                "(0: the exact sgn of the sampled velocity; docs/plant.md)", low=0.0,
                fixed="part of the nominal model F-hat, the experiment's, as p-hat and f-hat_d are",
            ),
        ),
    )
)  # fmt: skip
declare_kind(PaperKind("no-u0", "0", "the experiment's", eq9_law))
declare_kind(
    PaperKind(
        "computed-torque",
        "0",
        "the true robot's model and friction: what perfect model knowledge buys",
        _computed_torque,
        ignores=(("nominal.", "computed torque uses the true model"),),
    )
)
declare_kind(
    PaperKind(
        "pd",
        "task-space PD with gravity compensation and null-space damping (no eq. 9)",
        "Ĝ only",
        _pd,
        eq9=False,
        keys=("controller.pd_Kp", "controller.pd_Kd", "controller.pd_null_damping"),
        params=(
            LawParam(
                "controller.pd_Kp",
                (400.0,),
                "N/m",
                "task stiffness (N m/rad on a pose's orientation rows)",
                low=0.0,
                low_open=True,
                high=MAX_GAIN,
                size="m",
            ),
            LawParam(
                "controller.pd_Kd",
                (40.0,),
                "N s/m",
                "task damping (N m s/rad on a pose's orientation rows)",
                low=0.0,
                low_open=True,
                high=MAX_GAIN,
                size="m",
            ),
            LawParam(
                "controller.pd_null_damping",
                None,
                "N m s/rad",
                "null-space joint damping D; unset: sized from the arm at q(0)",
                low=0.0,
                high=MAX_GAIN,
            ),
        ),
    )
)
