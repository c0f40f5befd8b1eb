"""Task-space Slotine–Li adaptive control of a redundant arm (``controller.kind = "slotine-li"``;
compiled twin csrc/controllers/laws/slotine_li.cpp; docs/controller.md).

With J⁺ the experiment's damped pseudo-inverse and N = I − J⁺J:

    q̇_r = J⁺ (ẋ_d − Λ e) + N (k_h ∇h(q) − k_n q̇)       q̈_r = J⁺ (ẍ_d − Λ ė − J̇ q̇)
    s   = q̇ − q̇_r
    τ   = Y(q, q̇, q̇_r, q̈_r) θ̂ − K_D s + F̂(q̇)
    θ̂⁺  = θ̂ + T (−γ Yᵀ s − σ (θ̂ − θ̂(0)))                (explicit Euler over the period T)

Y θ = M(q) q̈_r + C(q, q̇) q̇_r + G(q) with C the Christoffel Coriolis matrix (Ṁ − 2C skew), the
one the Lyapunov argument needs; θ̂ is the state z. On a Pinocchio nominal model θ holds 10
parameters per joint (``Inertia.toDynamicParameters``) and Y comes from three calls of
``computeJointTorqueRegressor``, by polarisation (C(q, v) w is a symmetric bilinear form):

    Y = Y(q, 0, q̈_r) + ¼ [Y(q, q̇ + q̇_r, 0) − Y(q, q̇ − q̇_r, 0)]

(the compiled twin takes the same identity in two passes that share the kinematics, gravity and
q̈_r doubled in one and negated in the other: 4 Y = Y(q, q̇ + q̇_r, 2q̈_r; 2g) − Y(q, q̇ − q̇_r, −2q̈_r;
−2g), csrc/model/regressor.hpp christoffel_regressor; equal within rounding),
and, with ``project``, each link's 4×4 pseudo-inertia is kept positive definite after every
step (its eigenvalues clipped at 1e-5 × the link's nominal mass), so that θ̂ stays physical. On
the paper's closed-form arm θ = (β₁, β₂, β₃, p₁, p₂, p₃, γ₁, γ₂, γ₃), in which M, C and G are
linear (docs/errata.md); column i of Y is that arm's M q̈_r + C q̇_r + G with θ = e_i. There
``project`` keeps each parameter within a factor ``bound`` of its nominal value (a box, onto which
clipping is the projection in Γ = γ I's metric), so that M̂ cannot grow without limit.

Sized from the arm when unset: K_D(q) = (K_D_step / T) M̂(q), the nominal's own mass matrix at the
measured q (M̂(q) s by RNEA), so that every mode of the sampled s-loop has T λ(M̂⁻¹ K_D) = K_D_step;
γ by :meth:`SlotineLi.sized_gamma`. A diagonal K_D ∝ diag M̂(q0) with only its fastest mode at
K_D_step (the former default) left the slowest 6 (UR5) to 4900 (planar7) times slower; friction
and disturbance then held s at about 2 rad/s on planar7-ellipse, the adaptation integrated it
until M̂ was 10-20 times M in one direction, and the sampled M̂ Λ J⁺ ė term ran away (planar7 at
2.9 s, panda-pose at 0.4 s). Sensor noise in both Y (through Λ ė) and s biases the gradient
towards larger inertias (γ Λ nᵀ ∂M/∂θ n > 0): the box bounds that drift on the closed form.

Deliberate approximations: q̈_r uses J̇ q̇ (not J̇ q̇_r) and drops the derivatives of J⁺ outside
the task and of the null-space term, so q̈_r is exact in the task directions only.
"""

from __future__ import annotations

from typing import Any, cast

import numpy as np
import pinocchio as pin

from ...core.exceptions import ConfigError
from ...core.search_coordinates import bandwidth_range
from ...model.three_link import ThreeLinkParameters, ThreeLinkPlanarModel
from ..base import Controller, ControllerContext, ControlOutput
from ..registry import Law, LawParam, register_law

K_D_STEP_WARN = 1.0
"""T λ_max(M̂⁻¹ K_D) at q(0) of a given K_D beyond which the sampled s-loop goes unstable."""

ADAPTATION_STEP = 0.5
"""T sqrt(γ λ_max(Yᵀ M̂⁻¹ Y)) at q(0) and the reference motion: the step of the coupled s-θ̂ loop
that an unset γ is kept under (light arms; γ = 1 is under it on the paper's arm, 0.19, the Panda,
0.25, and the UR5, 0.29; planar7-ellipse gets 0.059)."""

REFERENCE_SPEED, REFERENCE_ACCELERATION = 1.0, 10.0
"""[rad/s, rad/s²] The reference motion of every joint at which Y sizes γ (q' = q'_r, q''_r)."""

PSEUDO_FLOOR = 1e-5
"""A link's pseudo-inertia eigenvalues are kept above this fraction of its nominal mass [m²]."""

BOUND = 2.0
"""The closed form's box: each of θ̂'s parameters within this factor of its nominal value."""


def pseudo_inertia(pi: np.ndarray) -> np.ndarray:
    """[[tr(I)/2 − I, m c], [m cᵀ, m]] of one link's 10 parameters (m, m c, Ixx, Ixy, Iyy, Ixz,
    Iyz, Izz about the joint frame); positive definite iff they are a physical body's.
    """
    m, h = pi[0], pi[1:4]
    inertia = np.array([[pi[4], pi[5], pi[7]], [pi[5], pi[6], pi[8]], [pi[7], pi[8], pi[9]]])
    P = np.empty((4, 4))
    P[:3, :3] = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    P[:3, 3] = P[3, :3] = h
    P[3, 3] = m
    return P


def from_pseudo_inertia(P: np.ndarray) -> np.ndarray:
    """The 10 parameters of a pseudo-inertia (the inverse of :func:`pseudo_inertia`)."""
    inertia = np.trace(P[:3, :3]) * np.eye(3) - P[:3, :3]
    return np.array([P[3, 3], *P[:3, 3], *inertia[[0, 0, 1, 0, 1, 2], [0, 1, 1, 2, 2, 2]]])


class SlotineLi(Controller):
    """Task-space Slotine–Li adaptive law (see the module docstring)."""

    signal_names = ("param_drift", "s_norm", "min_inertia_eigenvalue")

    def __init__(
        self,
        context: ControllerContext,
        Lambda=100.0,
        K_D=None,
        K_D_step=0.3,
        gamma=None,
        leakage=0.0,
        null_damping=1.0,
        criterion_gain=0.0,
        regressor="exact",
        project=True,
        bound=BOUND,
    ):
        ctx = self.context = context
        nominal, n, m = ctx.nominal, ctx.n, ctx.m
        self.pinv, self.nominal_friction = ctx.pseudo_inverse, ctx.nominal_friction
        self.Lambda = np.broadcast_to(np.asarray(Lambda, dtype=float), (m,)).copy()
        model: Any = nominal.pinocchio_model
        if model is not None:
            if model.nq != n or model.nv != n:
                raise ConfigError(
                    "controller.kind", f"slotine-li needs nq = nv; the nominal model has nq = {model.nq}"
                )
            self.model, self.data = model, model.createData()
            self.theta0 = np.concatenate(
                [model.inertias[j].toDynamicParameters() for j in range(1, model.njoints)]
            )
            self.armature = np.asarray(model.armature, dtype=float).copy()
            self.pseudo_floor = PSEUDO_FLOOR * np.maximum(self.theta0[0::10], 1e-3)
        else:  # the closed-form arm: theta = (beta, p, gamma), one unit model per column of Y
            params = cast(ThreeLinkPlanarModel, nominal).params
            self.theta0 = np.array([*params.beta, *params.p, *params.gamma], dtype=float)
            self.units = []
            for i in range(9):
                e = np.eye(9)[i]
                unit = ThreeLinkParameters(
                    tuple(e[:3]), tuple(e[3:6]), params.lengths, tuple(e[6:]), params.gravity
                )
                self.units.append(ThreeLinkPlanarModel(unit))
            self.armature = np.zeros(n)
            self.pseudo_floor = np.zeros(0)
        M0 = np.asarray(nominal.mass(np.asarray(ctx.q0, dtype=float)), dtype=float)
        # K_D unset: K_D(q) = K_D_step / T · M̂(q), every mode of the s-loop at T λ(M̂⁻¹ K_D) = K_D_step
        self.K_D_mass = float(K_D_step) / ctx.period if K_D is None else 0.0
        self.K_D = np.broadcast_to(np.asarray(0.0 if K_D is None else K_D, dtype=float), (n,)).copy()
        step = ctx.period * np.max(np.linalg.eigvals(np.linalg.solve(M0, np.diag(self.K_D))).real)
        if step > K_D_STEP_WARN:
            raise ConfigError(
                "controller.params.K_D",
                f"T lambda_max(M^-1 K_D) = {step:.3g} at q(0) > {K_D_STEP_WARN:g}: the sampled loop "
                "is unstable there; lower K_D or leave it out (sized by K_D_step)",
            )
        self.leakage = float(leakage)
        self.null_damping, self.criterion_gain = float(null_damping), float(criterion_gain)
        self.exact, self.project = float(regressor == "exact"), float(bool(project))
        self.lower = np.minimum(self.theta0 / bound, self.theta0 * bound)  # the closed form's box
        self.upper = np.maximum(self.theta0 / bound, self.theta0 * bound)
        self.state_size = self.theta0.size
        self._zero, self._eye = np.zeros(n), np.eye(n)
        self.gamma = (
            float(gamma) if gamma is not None else self.sized_gamma(np.asarray(ctx.q0, dtype=float), M0)
        )

    def sized_gamma(self, q0: np.ndarray, M0: np.ndarray) -> float:
        """γ for an unset ``gamma``: 1, or less where T sqrt(γ λ_max(Yᵀ M̂⁻¹ Y)) at q(0) and the
        reference motion would exceed :data:`ADAPTATION_STEP` (the adaptation outruns the sampled
        loop: on a 0.1 kg-per-link arm γ = 1 commanded 1e10 times the effort limits).
        """
        n = q0.size
        v, a = np.full(n, REFERENCE_SPEED), np.full(n, REFERENCE_ACCELERATION)
        Y = self.regressor(q0, v, v, a)
        rate = float(np.max(np.linalg.eigvalsh(Y.T @ np.linalg.solve(M0, Y))))
        step = self.context.period * np.sqrt(max(rate, 0.0))
        return 1.0 if step <= ADAPTATION_STEP else (ADAPTATION_STEP / step) ** 2

    def damping(self, q, s) -> np.ndarray:
        """K_D s: the given diagonal K_D, or K_D_step / T · M̂(q) s (as M̂(q) s + G − G by RNEA)."""
        out = self.K_D * s
        if self.K_D_mass:
            nominal = self.context.nominal
            out = out + self.K_D_mass * (nominal.inverse_dynamics(q, self._zero, s) - nominal.gravity(q))
        return out

    def initial_state(self) -> np.ndarray:
        """θ̂(0): the nominal model's parameters."""
        return self.theta0.copy()

    def regressor(self, q, v, v_r, a_r) -> np.ndarray:
        """Y with Y θ = M(q) a_r + C(q, v) v_r + G(q) (C(q, v_r) v_r with ``regressor = "approx"``)."""
        if hasattr(self, "units"):
            w = v if self.exact else v_r
            return np.column_stack(
                [u.mass(q) @ a_r + u.coriolis_matrix(q, w) @ v_r + u.gravity(q) for u in self.units]
            )

        def Y(vel, acc):
            return pin.computeJointTorqueRegressor(self.model, self.data, q, vel, acc).copy()

        if not self.exact:
            return Y(v_r, a_r)
        return Y(self._zero, a_r) + 0.25 * (Y(v + v_r, self._zero) - Y(v - v_r, self._zero))

    def min_inertia_eigenvalue(self, q, theta) -> float:
        """The smallest eigenvalue of the links' pseudo-inertias (Pinocchio) or of M̂(q) (closed form)."""
        if hasattr(self, "units"):
            return float(np.linalg.eigvalsh(sum(t * u.mass(q) for t, u in zip(theta, self.units))).min())
        return float(
            min(np.linalg.eigvalsh(pseudo_inertia(theta[i : i + 10])).min() for i in range(0, theta.size, 10))
        )

    def projected(self, theta: np.ndarray) -> np.ndarray:
        """θ̂ with every link's pseudo-inertia eigenvalues clipped at its floor (closed form: θ̂
        clipped to its box, θ̂(0) / bound to θ̂(0) bound).
        """
        if hasattr(self, "units"):
            return np.clip(theta, self.lower, self.upper)
        out = theta.copy()
        for k, i in enumerate(range(0, theta.size, 10)):
            w, V = np.linalg.eigh(pseudo_inertia(theta[i : i + 10]))
            if w[0] < self.pseudo_floor[k]:
                out[i : i + 10] = from_pseudo_inertia((V * np.maximum(w, self.pseudo_floor[k])) @ V.T)
        return out

    def compute(self, t, q, v, z, period=0.0) -> ControlOutput:
        """τ at the measured (q, q̇) with θ̂ = z, and θ̂ after ``period``."""
        ctx = self.context
        theta = np.asarray(z, dtype=float)
        x, J, jdot_v = ctx.nominal.task_state(q, v)
        x_d, dx_d, ddx_d = ctx.trajectory(t)
        e = ctx.trajectory.error(x, x_d)
        de = J @ v - dx_d
        J_pinv = self.pinv.matrix(J)
        null = -self.null_damping * v
        if self.criterion_gain and ctx.criterion is not None:
            null = null + self.criterion_gain * ctx.criterion.gradient(ctx.nominal, q)
        v_r = J_pinv @ (dx_d - self.Lambda * e) + (null - J_pinv @ (J @ null))
        a_r = J_pinv @ (ddx_d - self.Lambda * de - jdot_v)
        s = v - v_r
        Y = self.regressor(q, v, v_r, a_r)
        tau = Y @ theta + self.armature * a_r - self.damping(q, s) + self.nominal_friction.torque(v)
        theta_next = theta + period * (-self.gamma * (Y.T @ s) - self.leakage * (theta - self.theta0))
        if self.project:
            theta_next = self.projected(theta_next)
        signals = {
            "param_drift": float(np.linalg.norm(theta - self.theta0)),
            "s_norm": float(np.linalg.norm(s)),
            "min_inertia_eigenvalue": self.min_inertia_eigenvalue(q, theta),
        }
        return ControlOutput(tau, signals, theta_next)


_PARAMS = (
    LawParam(
        "Lambda",
        100.0,
        "1/s",
        "task-error bandwidth of s = q' − q'_r",
        0.0,
        1e6,
        "m",
        search=bandwidth_range,
        high_reason="sampling: Lambda (1/2 + delay) T = 1",
    ),
    LawParam(
        "K_D",
        None,
        "N m s/rad",
        "damping of s (diagonal); unset: K_D_step / T · M̂(q), at every q",
        0.0,
        1e6,
        "n",
        fixed="unset: sized by K_D_step, which is searched (a diagonal K_D is the experiment's alternative)",
    ),
    LawParam(
        "K_D_step",
        0.3,
        "-",
        "T λ(M̂⁻¹ K_D) of every mode of s when K_D is unset",
        1e-6,
        1.0,
        search=(0.01, 1.0),
        high_reason="sampling: T λ(M̂⁻¹ K_D) = 1, beyond which the law refuses a K_D",
    ),
    LawParam(
        "gamma",
        None,
        "-",
        "adaptation gain Γ = γ I; unset: 1, or less where T √(γ λmax(Yᵀ M̂⁻¹ Y)) > 0.5 at q0 "
        "(Y at 1 rad/s, 10 rad/s² on every joint)",
        0.0,
        1e6,
        search=(1e-3, 1e2),
        weak="low",
    ),
    LawParam(
        "leakage", 0.0, "1/s", "σ-modification towards θ̂(0)", 0.0, 1e3, search=(1e-3, 10.0), weak="high"
    ),
    LawParam(
        "null_damping",
        1.0,
        "-",
        "k_n: null-space velocity damping inside q'_r (the null-space part of s is (1 + k_n) N q', "
        "its sampled step K_D_step (1 + k_n))",
        0.0,
        1e3,
        search=(1e-3, 1e2),
        low_reason="1 + k_n within 0.1 % of k_n = 0",
    ),
    LawParam(
        "criterion_gain",
        0.0,
        "-",
        "k_h: ascent of the self-motion criterion in q'_r",
        0.0,
        1e3,
        fixed="the subtask's weight, the experiment's: no tuning objective scores the self-motion criterion",
    ),
    LawParam("regressor", "exact", "-", "C(q, q') q'_r, or C(q, q'_r) q'_r", choices=("exact", "approx")),
    LawParam("project", True, "-", "keep θ̂ physically consistent (Pinocchio), or in its box (closed form)"),
    LawParam(
        "bound",
        BOUND,
        "-",
        "closed form: project keeps each of θ̂'s β, p, γ within this factor of θ̂(0)",
        1.0,
        1e6,
        fixed="the experiment's prior on the parameters, as its nominal model is (not a gain)",
    ),
)

LAW = register_law(
    Law(
        "slotine-li",
        SlotineLi,
        "task-space Slotine–Li adaptive control, Y θ̂ − K_D s with θ̂' = −γ Yᵀ s (Pinocchio's "
        "joint-torque regressor, or the paper's β, p, γ on the closed-form arm)",
        _PARAMS,
        twin="slotine_li",
        twin_fields=(
            "Lambda",
            "K_D",
            "K_D_mass",
            "gamma",
            "leakage",
            "null_damping",
            "criterion_gain",
            "exact",
            "project",
            "theta0",
            "armature",
            "pseudo_floor",
            "lower",
            "upper",
        ),  # fmt: skip
    )
)
