"""Task-space Slotine–Li adaptive control of a redundant arm, written against nnrobust's
controller contract (docs/extending.md) from the context alone.

Law (n joints, m task coordinates, J⁺ the experiment's damped pseudo-inverse, N = I − J⁺J):

    e   = trajectory.error(x, x_d)            ė = J q̇ − ẋ_d
    q̇_r = J⁺ (ẋ_d − Λ e) + N (k_h ∇h(q) − k_null q̇)
    q̈_r = J⁺ (ẍ_d − Λ ė − J̇ q̇)
    s   = q̇ − q̇_r
    τ   = Y(q, q̇, q̇_r, q̈_r) θ̂ − K_D s + F̂(q̇)
    θ̂̇  = −Γ Yᵀ s − σ (θ̂ − θ̂(0)),   Γ = γ I,   θ̂(0) = the nominal model's inertial parameters

Parameters (keyword arguments after the context):
  Lambda          1/s, task-error bandwidth (scalar or one per task coordinate); default 100.
                  Keep Λ·T ≲ 0.3: M̂ q̈_r contains the velocity feedback −M̂ J⁺ Λ ė.
  K_D             N m s/rad, scalar or one per joint; default None = automatic: K_D ∝ diag M̂(q0)
                  scaled so that T·λ_max(M̂(q0)⁻¹ K_D) = ``K_D_step`` (0.3).  With a zero-order
                  hold over T the fast mode of M ṡ = −K_D s goes unstable near T·λ_max ≈ 1 (the
                  Panda's wrist, M_77 ≈ 0.007 kg m², is unstable at K_D = 20); an explicit K_D
                  above 0.6 gets a warning.
  gamma           adaptation gain, Γ = γ I on the 10 n parameters; default 1.
  leakage         σ of a σ-modification towards θ̂(0), 1/s; default 0 (the textbook law).
  null_damping    k_null, 1/s; default 1.
  criterion_gain  k_h on the experiment's self-motion criterion; default 0.  Gradient *ascent*
                  (h is maximised): checked by running, not stated in docs/extending.md.
  regressor       "exact" (default) or "approx", below.
  project         keep θ̂ physically consistent (default True), below.

Adaptation limits seen on the paper's arm (disturbance and friction the model lacks): with
Λ = 300, γ = 1 the estimate soaks up the disturbance, link 3's I_zz grows ~8× in 4 s, M̂ Λ then
exceeds the sampled-data limit above and the loop blows up at ~4.6 s (seen with leakage = 1 and
no projection, and with the projection and no leakage).  γ = 0.1 with leakage = 0.5 is stable
over 20 s; Λ = 100, γ = 1 is stable too but about three times less accurate.

``project``: after every step each link's 4×4 pseudo-inertia [[tr(I)/2·1 − I, m c], [m cᵀ, m]]
(positive definite iff the 10 numbers are a real body's) has its eigenvalues clipped to a small
floor (1e-5 × nominal mass).  This is the Frobenius-norm projection onto that cone, not the
Γ⁻¹-weighted one a Lyapunov argument would ask for.  Without it, at Λ = 300 and γ = 1, the paper
arm's θ̂ left the consistent set within the first second (its URDF links are rods, already on
the cone's edge).

θ̂ is the controller's explicit state z (10 parameters per joint, Pinocchio's
``Inertia.toDynamicParameters`` order: m, m c, I about the joint frame), advanced by explicit
Euler over ``period`` inside ``compute``.

Regressor: Y(q, q̇, q̇_r, q̈_r) θ = M(q) q̈_r + C(q, q̇) q̇_r + g(q) with C the Christoffel-symbol
Coriolis matrix (the one with Ṁ − 2C skew-symmetric, which the Slotine–Li Lyapunov argument
needs).  Pinocchio's ``computeJointTorqueRegressor(q, v, a)`` only gives Y for v = a single
velocity, i.e. the quadratic form c(q, v) = C(q, v) v.  Because C(q, v) w is a *symmetric*
bilinear form in (v, w) for the Christoffel C, polarisation gives it exactly from two calls:

    C(q, v) w = ¼ [c(q, v + w) − c(q, v − w)]

so  Y_exact = Y(q, 0, q̈_r) + ¼ [Y(q, q̇ + q̇_r, 0) − Y(q, q̇ − q̇_r, 0)]   (three calls;
gravity cancels in the difference).  This is the default (``regressor = "exact"``): it is the
law the stability proof is about, and costs two extra regressor calls (tens of µs).  The common
shortcut Y(q, q̇_r, q̈_r), i.e. C(q, q̇_r) q̇_r instead of C(q, q̇) q̇_r, is available as
``regressor = "approx"`` for comparison; it differs by C(q, s) q̇_r, which vanishes with s but
breaks the skew-symmetry argument.

Approximations in q̈_r (documented, deliberate):
  * J̇ q̇ instead of J̇ q̇_r (that is what ``nominal.task_state`` returns); they differ by J̇ s.
  * The time derivative of J⁺ acting outside the task (the null-space part of d/dt J⁺) and the
    derivative of the null-space term N(k_h ∇h − k_null q̇) are dropped: q̈_r is exact only in
    the task directions (J q̈_r = ẍ_d − Λ ė − J̇ q̇ while J⁺ is undamped).  The null-space
    motion is then governed by K_D and the damping term rather than by an exact reference.
    On the Panda run "exact" and "approx" agree to 3 digits (0.104 mm): C(q, s) q̇_r is tiny
    at these speeds.

Friction: the nominal friction F̂(q̇) of the experiment's ``[nominal]`` section is added as a
feedforward at the measured velocity.

Needs a Pinocchio nominal model (``context.nominal.pinocchio_model``); on the closed-form paper
arm set ``[nominal] kind = "urdf"``.
"""

import warnings

import numpy as np
import pinocchio as pin

from nnrobust import Controller, ControlOutput


def _pseudo_inertia(pi):
    """4x4 pseudo-inertia [[tr(I)/2 - I, h], [h^T, m]] of one link's 10 parameters
    (m, h = m c, Ixx, Ixy, Iyy, Ixz, Iyz, Izz about the joint frame); positive definite iff the
    parameters are those of a physical body.
    """
    m, h = pi[0], pi[1:4]
    inertia = np.array([[pi[4], pi[5], pi[7]], [pi[5], pi[6], pi[8]], [pi[7], pi[8], pi[9]]])
    P = np.empty((4, 4))
    P[:3, :3] = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    P[:3, 3] = P[3, :3] = h
    P[3, 3] = m
    return P


def _from_pseudo_inertia(P):
    sigma = P[:3, :3]
    inertia = np.trace(sigma) * np.eye(3) - sigma
    return np.array(
        [
            P[3, 3],
            *P[:3, 3],
            inertia[0, 0],
            inertia[0, 1],
            inertia[1, 1],
            inertia[0, 2],
            inertia[1, 2],
            inertia[2, 2],
        ]
    )


def _vector(name, value, size):
    """A scalar or a list of `size` entries, as a positive vector."""
    arr = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
    if arr.size == 1:
        arr = np.full(size, arr[0])
    if arr.size != size:
        raise ValueError(f"{name} needs 1 or {size} entries, got {arr.size}")
    if np.any(~np.isfinite(arr)) or np.any(arr < 0.0):
        raise ValueError(f"{name} must be finite and >= 0, got {arr.tolist()}")
    return arr


class SlotineLi(Controller):
    """Task-space Slotine–Li adaptive law with a Pinocchio joint-torque regressor."""

    signal_names = ("param_drift", "s_norm", "effort", "min_pseudo_inertia")
    state_size = 0  # set per instance in __init__: 10 inertial parameters per joint

    def __init__(
        self,
        context,
        Lambda=100.0,
        K_D=None,
        gamma=1.0,
        null_damping=1.0,
        criterion_gain=0.0,
        regressor="exact",
        K_D_step=0.3,
        leakage=0.0,
        project=True,
    ):
        ctx = self.ctx = context
        pm = ctx.nominal.pinocchio_model
        if pm is None:
            raise ValueError(
                "SlotineLi needs the nominal model as a Pinocchio model for its regressor, but "
                "context.nominal.pinocchio_model is None (the closed-form paper arm); set "
                '[nominal] kind = "urdf" in the experiment file'
            )
        if pm.nq != ctx.n or pm.nv != ctx.n:
            raise ValueError(
                f"SlotineLi supports arms with nq = nv = n; the nominal model has nq = {pm.nq}, "
                f"nv = {pm.nv}, n = {ctx.n}"
            )
        if regressor not in ("exact", "approx"):
            raise ValueError(f"regressor must be 'exact' or 'approx', got {regressor!r}")
        self.model, self.data = pm, pm.createData()
        self.Lambda = _vector("Lambda", Lambda, ctx.m)
        # Sampled-data limit on K_D (see the module docstring).
        M0 = np.asarray(ctx.nominal.mass(np.asarray(ctx.q0, dtype=float)), dtype=float)
        T = float(ctx.period)
        if K_D is None:
            shape = np.diag(M0).copy()
            lam = np.max(np.linalg.eigvals(np.linalg.solve(M0, np.diag(shape))).real)
            self.K_D = shape * float(K_D_step) / (T * lam)
        else:
            self.K_D = _vector("K_D", K_D, ctx.n)
        self.kd_step = float(T * np.max(np.linalg.eigvals(np.linalg.solve(M0, np.diag(self.K_D))).real))
        if self.kd_step > 0.6:
            warnings.warn(
                f"SlotineLi: T*lambda_max(M^-1 K_D) = {self.kd_step:.2f} at q0 (K_D = "
                f"{np.round(self.K_D, 3).tolist()}); above about 1 the sampled loop goes unstable",
                stacklevel=2,
            )
        self.gamma = float(_vector("gamma", gamma, 1)[0])
        self.null_damping = float(_vector("null_damping", null_damping, 1)[0])
        self.criterion_gain = float(criterion_gain)
        self.leakage = float(_vector("leakage", leakage, 1)[0])
        self.project = bool(project)
        self.regressor = regressor
        self.theta0 = np.concatenate([pm.inertias[i].toDynamicParameters() for i in range(1, pm.njoints)])
        self.state_size = self.theta0.size
        # floor of each link's pseudo-inertia eigenvalues: a radius of gyration of ~3 mm
        self.pseudo_floor = 1e-5 * np.maximum(self.theta0[0::10], 1e-3)
        self.armature = np.asarray(pm.armature, dtype=float).copy()  # not in the regressor
        self._zero = np.zeros(ctx.n)
        self._eye = np.eye(ctx.n)

    def initial_state(self):
        """θ̂(0): the nominal model's inertial parameters."""
        return self.theta0.copy()

    def project_consistent(self, theta):
        """Clip each link's pseudo-inertia eigenvalues to a small positive floor, so that θ̂
        stays the parameters of physical bodies (M̂(q) positive definite).
        """
        out = theta.copy()
        for k, i in enumerate(range(0, theta.size, 10)):
            P = _pseudo_inertia(theta[i : i + 10])
            w, V = np.linalg.eigh(P)
            if w[0] < self.pseudo_floor[k]:
                clipped = (V * np.maximum(w, self.pseudo_floor[k])) @ V.T
                out[i : i + 10] = _from_pseudo_inertia(clipped)
        return out

    def _Y(self, q, v, a):
        return pin.computeJointTorqueRegressor(self.model, self.data, q, v, a).copy()

    def regressor_matrix(self, q, v, v_r, a_r):
        """Y with Y θ = M(q) a_r + C(q, v) v_r + g(q) (``exact``) or with v_r for v (``approx``)."""
        if self.regressor == "approx":
            return self._Y(q, v_r, a_r)
        return self._Y(q, self._zero, a_r) + 0.25 * (
            self._Y(q, v + v_r, self._zero) - self._Y(q, v - v_r, self._zero)
        )

    def compute(self, t, q, v, z, period=0.0):
        """τ at the measured (q, q̇) with θ̂ = z; θ̂ advanced by explicit Euler over `period`."""
        ctx = self.ctx
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        theta = np.asarray(z, dtype=float)

        x, J, jdot_v = ctx.nominal.task_state(q, v)
        x_d, dx_d, ddx_d = ctx.trajectory(t)
        e = ctx.trajectory.error(x, x_d)
        de = J @ v - dx_d
        J_pinv = ctx.pseudo_inverse.matrix(J)
        N = self._eye - J_pinv @ J

        null = -self.null_damping * v
        if self.criterion_gain and ctx.criterion is not None:
            null = null + self.criterion_gain * ctx.criterion.gradient(ctx.nominal, q)
        v_r = J_pinv @ (dx_d - self.Lambda * e) + N @ null
        a_r = J_pinv @ (ddx_d - self.Lambda * de - jdot_v)
        s = v - v_r

        Y = self.regressor_matrix(q, v, v_r, a_r)
        tau = Y @ theta + self.armature * a_r - self.K_D * s + ctx.nominal_friction.torque(v)

        dtheta = -self.gamma * (Y.T @ s) - self.leakage * (theta - self.theta0)
        theta_next = theta + period * dtheta
        if self.project:
            theta_next = self.project_consistent(theta_next)
        return ControlOutput(
            tau,
            {
                "param_drift": float(np.linalg.norm(theta - self.theta0)),
                "s_norm": float(np.linalg.norm(s)),
                "effort": float(np.linalg.norm(tau)),
                "min_pseudo_inertia": float(
                    min(
                        np.linalg.eigvalsh(_pseudo_inertia(theta[i : i + 10])).min()
                        for i in range(0, theta.size, 10)
                    )
                ),
            },
            state=theta_next,
        )
