"""The model's linearity in its parameters, for identification: tau = Y(q, q', q'') phi + F(q').

Eq. (1)'s M(q) q'' + N(q, q') is linear in each body's ten inertial parameters (Pinocchio's joint
torque regressor Y), and the plant's friction of eq. (7) (:class:`nnrobust.plant.friction.Friction`)
is linear in its viscous and Coulomb coefficients. Not every parameter moves the torque: the
*base parameters* are the combinations that do (Gautier and Khalil's numerical reduction, here by
QR with column pivoting of Y stacked over random states). A body's parameters are physical when its
pseudo-inertia is positive semi-definite (Wensing, Kim and Slotine, RA-L 2018), which implies the
triangle inequalities of its principal moments.

A body's ten parameters, in Pinocchio's order (``pin.Inertia.toDynamicParameters``), about its
joint frame's origin: m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import scipy.linalg

from .perturbation import rotational_inertia_problem

BODY_PARAMETERS = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
"""A body's ten inertial parameters, in Pinocchio's order (about the joint frame's origin)."""

FRICTION_TERMS = ("viscous", "coulomb", "offset")
"""The friction terms a joint may have, each linear in its coefficient: F_d q', F_c sgn(q') (the
plant's law, eq. (7)), and a constant torque (a sensor's offset)."""


@dataclass(frozen=True)
class ParameterLayout:
    """Where each identified parameter sits in the full parameter vector: every moving body's ten
    inertial parameters (joint order), then per joint its friction terms, then (if asked) its
    rotor inertia (armature, the q''_i column).

    Attributes:
        joints: the joints' names, in the model's order.
        friction: the friction terms of every joint (a subset of :data:`FRICTION_TERMS`).
        armature: whether each joint's armature is a parameter.

    """

    joints: tuple[str, ...]
    friction: tuple[str, ...] = ("viscous", "coulomb")
    armature: bool = False

    def __post_init__(self):
        unknown = [f for f in self.friction if f not in FRICTION_TERMS]
        if unknown:
            raise ValueError(f"friction terms {unknown}: each must be one of {list(FRICTION_TERMS)}")

    @property
    def n(self) -> int:
        """Joints."""
        return len(self.joints)

    @property
    def inertial(self) -> slice:
        """The inertial parameters' slice."""
        return slice(0, 10 * self.n)

    def friction_slice(self, term: str) -> slice:
        """The ``term`` coefficients' slice (one per joint)."""
        start = 10 * self.n + self.n * self.friction.index(term)
        return slice(start, start + self.n)

    @property
    def armature_slice(self) -> slice:
        """The armature coefficients' slice (empty without armature)."""
        start = 10 * self.n + self.n * len(self.friction)
        return slice(start, start + (self.n if self.armature else 0))

    @property
    def size(self) -> int:
        """Entries of the full parameter vector."""
        return self.n * (10 + len(self.friction) + int(self.armature))

    @property
    def names(self) -> list[str]:
        """Each parameter's name: ``m@panda_joint2``, ``viscous@panda_joint1``, ..."""
        names = [f"{p}@{j}" for j in self.joints for p in BODY_PARAMETERS]
        names += [f"{term}@{j}" for term in self.friction for j in self.joints]
        return names + ([f"armature@{j}" for j in self.joints] if self.armature else [])


def inertial_vector(model: pin.Model) -> np.ndarray:
    """The model's inertial parameters, ten per moving body (:data:`BODY_PARAMETERS`)."""
    return np.concatenate([model.inertias[j].toDynamicParameters() for j in range(1, model.njoints)])


def with_inertial_vector(model: pin.Model, phi: np.ndarray) -> pin.Model:
    """A copy of ``model`` whose bodies have the inertial parameters ``phi`` (10 per body)."""
    out = pin.Model(model)
    for j in range(1, model.njoints):
        out.inertias[j] = pin.Inertia.FromDynamicParameters(
            np.asarray(phi[10 * (j - 1) : 10 * j], dtype=float)
        )
    return out


def torque_regressor(model: pin.Model, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Y(q, q', q'') for each of N samples: N x n x 10 n, with Y phi = M(q) q'' + N(q, q')."""
    data = model.createData()
    out = np.empty((len(q), model.nv, 10 * (model.njoints - 1)))
    for k in range(len(q)):
        out[k] = pin.computeJointTorqueRegressor(model, data, q[k], v[k], a[k])
    return out


def friction_regressor(layout: ParameterLayout, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The friction and armature columns for each of N samples: N x n x (terms + armature) n.

    The Coulomb column is sgn(q') (the plant's slipping law; a joint at rest is in stick, where
    friction is any torque up to F_s, so its rows are left out of the fit, :func:`slipping`).
    """
    N, n = v.shape
    blocks = {"viscous": v, "coulomb": np.sign(v), "offset": np.ones_like(v)}
    columns = [blocks[term] for term in layout.friction] + ([a] if layout.armature else [])
    out = np.zeros((N, n, n * len(columns)))
    for c, values in enumerate(columns):
        out[:, np.arange(n), c * n + np.arange(n)] = values
    return out


def slipping(v: np.ndarray, band: float) -> np.ndarray:
    """Where each joint slips (|q'| >= ``band`` [rad/s]): N x n booleans. Below it the dry
    friction is set-valued (stick-slip, :mod:`nnrobust.plant.stick_slip`) and no law holds.
    """
    return np.abs(v) >= band


@dataclass(frozen=True)
class BaseParameters:
    """The combinations of the inertial parameters that move the torque: beta = phi[base] +
    K phi[dependent], and Y phi = Y[:, base] beta for every state.

    Attributes:
        base: indices (into the inertial vector) of the parameters kept, in pivot order.
        dependent: indices of the others.
        K: r x (10 n - r) combination matrix.
        names: each base parameter's name, with the dependent parameters it absorbs.

    """

    base: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    names: tuple[str, ...]

    @property
    def rank(self) -> int:
        """Base parameters."""
        return len(self.base)

    def of(self, phi: np.ndarray) -> np.ndarray:
        """Beta of the inertial vector ``phi``."""
        return phi[self.base] + self.K @ phi[self.dependent]

    def projector(self, size: int) -> np.ndarray:
        """The r x ``size`` matrix P with beta = P phi (``size`` = 10 n)."""
        P = np.zeros((self.rank, size))
        P[:, self.base] = np.eye(self.rank)
        P[:, self.dependent] = self.K
        return P


def random_regressor(model: pin.Model, samples: int = 0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The torque regressor stacked over random states, (samples n) x 10 n, and their q'' (samples
    x n): positions within the joint limits, velocities and accelerations standard normal;
    ``samples`` 0 is max(40, 4 n). What the base parameters are computed from.
    """
    n = model.nv
    rng = np.random.default_rng(seed)
    samples = samples or max(40, 4 * n)
    low, high = position_ranges(model)
    q = rng.uniform(np.maximum(low, -np.pi), np.minimum(high, np.pi), (samples, n))
    v, a = rng.standard_normal((samples, n)), rng.standard_normal((samples, n))
    return torque_regressor(model, q, v, a).reshape(-1, 10 * n), a


def base_parameters(
    model: pin.Model, names: list[str], samples: int = 0, seed: int = 0, rel_tol: float = 1e-8
) -> BaseParameters:
    """The base parameters of ``model`` (Gautier's numerical method): Y stacked over random
    states (positions within the joint limits, velocities and accelerations standard normal),
    QR-factored with column pivoting; the columns whose pivots exceed ``rel_tol`` times the first
    are the base, the others their combinations. ``names``: the inertial parameters' names.
    """
    W = random_regressor(model, samples, seed)[0]
    _, R, pivots = scipy.linalg.qr(W, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    rank = int(np.sum(diag > rel_tol * diag[0]))
    base, dependent = np.sort(pivots[:rank]), pivots[rank:]
    # K from a least-squares fit of the dependent columns on the base ones (exact to rounding)
    K, *_ = np.linalg.lstsq(W[:, base], W[:, dependent], rcond=None)
    K[np.abs(K) < 1e-9 * max(1.0, np.abs(K).max(initial=0.0))] = 0.0
    labels = []
    for row, i in enumerate(base):
        terms = [f"{K[row, c]:+.3g} {names[d]}" for c, d in enumerate(dependent) if K[row, c] != 0]
        labels.append(names[i] + (" " + " ".join(terms) if terms else ""))
    return BaseParameters(base, dependent, K, tuple(labels))


def position_ranges(model: pin.Model) -> tuple[np.ndarray, np.ndarray]:
    """Each joint's position limits, a joint without them taken as [-pi, pi]."""
    low = np.where(np.isfinite(model.lowerPositionLimit), model.lowerPositionLimit, -np.pi)
    high = np.where(np.isfinite(model.upperPositionLimit), model.upperPositionLimit, np.pi)
    return low, high


def from_pseudo_inertia(J: np.ndarray) -> np.ndarray:
    """A body's ten parameters of its pseudo-inertia (:func:`pseudo_inertia`'s inverse)."""
    sigma = J[:3, :3]
    inertia = np.trace(sigma) * np.eye(3) - sigma  # J's block is tr(I)/2 1 - I
    return np.array(
        [
            J[3, 3],
            *J[:3, 3],
            inertia[0, 0],
            inertia[0, 1],
            inertia[1, 1],
            inertia[0, 2],
            inertia[1, 2],
            inertia[2, 2],
        ]
    )


def pseudo_inertia(phi10: np.ndarray) -> np.ndarray:
    """A body's 4 x 4 pseudo-inertia J = [[tr(I)/2 1 - I, h], [h^T, m]] of its ten parameters
    (about the joint frame's origin); J >= 0 if and only if some density has these moments.
    """
    m, h = phi10[0], phi10[1:4]
    Ixx, Ixy, Iyy, Ixz, Iyz, Izz = phi10[4:]
    inertia = np.array([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
    J = np.empty((4, 4))
    J[:3, :3] = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    J[:3, 3] = J[3, :3] = h
    J[3, 3] = m
    return J


def pseudo_inertia_expression(phi10, cp):
    """:func:`pseudo_inertia` as a cvxpy expression (``cp``: the cvxpy module)."""
    m, hx, hy, hz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz = (phi10[k] for k in range(10))
    half = (Ixx + Iyy + Izz) / 2
    return cp.bmat(
        [
            [half - Ixx, -Ixy, -Ixz, hx],
            [-Ixy, half - Iyy, -Iyz, hy],
            [-Ixz, -Iyz, half - Izz, hz],
            [hx, hy, hz, m],
        ]
    )


STRICT_MARGIN = 1e-6
"""A body's pseudo-inertia eigenvalues are raised to at least this share of its largest."""


def strictly_physical(phi10: np.ndarray) -> np.ndarray:
    """The body's ten parameters with its pseudo-inertia's eigenvalues raised to at least
    :data:`STRICT_MARGIN` of the largest (a change within a solver's tolerance): J > 0, so the
    body's mass is positive and its inertia about the centre of mass positive definite, with the
    triangle inequalities strict.
    """
    J = pseudo_inertia(phi10)
    values, vectors = np.linalg.eigh(J)
    floor = STRICT_MARGIN * max(values[-1], 1e-12)
    if values[0] >= floor:
        return phi10
    return from_pseudo_inertia((vectors * np.maximum(values, floor)) @ vectors.T)


def typical_sizes(layout: ParameterLayout) -> np.ndarray:
    """A typical magnitude of each parameter of ``layout`` (kg, kg m, kg m^2, N m s/rad, N m,
    kg m^2): the scale of the physical fit's pull and of a region's parameter metric.
    """
    body = np.array([1.0, 0.1, 0.1, 0.1] + [0.01] * 6)
    return np.concatenate([np.tile(body, layout.n), np.full(layout.size - 10 * layout.n, 0.1)])


def body_problems(model: pin.Model, rel_tol: float = 1e-9) -> list[str]:
    """What is not physical in each moving body (mass <= 0, an inertia about the centre of mass
    not positive definite or breaking the triangle inequalities), one line each.
    """
    problems = []
    for j in range(1, model.njoints):
        body = model.inertias[j]
        if not body.mass > 0:
            problems.append(f"{model.names[j]}: mass {body.mass:.6g} kg is not positive")
            continue
        why = rotational_inertia_problem(np.asarray(body.inertia), rel_tol, point_mass=True)
        if why:
            problems.append(f"{model.names[j]}: {why}")
    return problems


def mass_matrix_audit(model: pin.Model, armature: np.ndarray | None = None, poses: int = 1000, seed: int = 0):
    """The least eigenvalue of M(q) over ``poses`` random poses within the joint limits, and the
    pose it was found at: a model fit for simulation has it positive everywhere.
    """
    rng = np.random.default_rng(seed)
    data = model.createData()
    low, high = position_ranges(model)
    extra = np.zeros(model.nv) if armature is None else np.asarray(armature, dtype=float)
    least, where = np.inf, None
    for _ in range(poses):
        q = rng.uniform(np.maximum(low, -np.pi), np.minimum(high, np.pi))
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T + np.diag(extra)
        value = float(np.linalg.eigvalsh(M)[0])
        if value < least:
            least, where = value, q
    return least, where
