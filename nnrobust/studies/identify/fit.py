"""The fit: normal equations built in batches, identifiability before anything is solved, weighted
least squares in the base parameters, then the physically consistent estimate (docs/identification.md).

tau_k = Y(q_k, q'_k, q''_k) phi + e_k for every sample k and joint j, with phi every body's ten
inertial parameters, the friction terms and the armature (:class:`ParameterLayout`). Only the
normal equations of each joint are kept (G_j = sum Y_j^T Y_j, b_j = sum Y_j^T tau_j, c_j =
sum tau_j^2), so memory does not grow with the log's length, and any residual or fit of the
segment is a function of them.

1. **Identifiability**: the base regressor's columns scaled to unit norm; its condition number,
   and each direction the log leaves at under :data:`EXCITATION_TOLERANCE` of the best excited one
   named by the base parameter that dominates it.
2. **Weighted least squares** (Gautier): ordinary least squares, each joint's noise variance from
   its residual, then the fit weighted by 1 / sigma_j^2.
3. **Physically consistent estimate** (Sousa and Cortesao 2014; Wensing, Kim and Slotine 2018): the
   same weighted cost over the full parameters with each body's pseudo-inertia positive
   semi-definite (implying the triangle inequalities), friction and armature non-negative; an
   SDP solved by Clarabel through cvxpy. A tie-breaking pull of weight :data:`PRIOR_WEIGHT` towards
   the URDF's parameters fixes what the log cannot see (directions outside the base).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...core.exceptions import LogError
from ...model.regressor import (
    BaseParameters,
    ParameterLayout,
    friction_regressor,
    pseudo_inertia,
    pseudo_inertia_expression,
    slipping,
    strictly_physical,
    torque_regressor,
    typical_sizes,
)
from .signals import States

BATCH = 4096
"""Samples whose regressor rows are built at once (memory: BATCH x n x p doubles)."""

EXCITATION_TOLERANCE = 1e-6
"""A direction of the scaled base regressor whose eigenvalue is below this share of the largest
is not excited by the log (a condition number above 1e3 in singular values)."""

PRIOR_WEIGHT = 1e-8
"""Weight of the pull towards the URDF's parameters, relative to the mean eigenvalue of the fit's
weighted normal matrix: it moves nothing the log excites."""

PSD_MARGIN = 1e-9
"""Each pseudo-inertia's least eigenvalue is at least this [kg m^2]: M(q) stays invertible."""


@dataclass
class NormalEquations:
    """Per joint: G_j = sum_k Y_kj^T Y_kj, b_j = sum_k Y_kj^T tau_kj, c_j = sum_k tau_kj^2 and the
    rows counted, over the samples of one segment (a joint's rows in stick left out).
    """

    G: np.ndarray
    b: np.ndarray
    c: np.ndarray
    rows: np.ndarray

    @classmethod
    def empty(cls, n: int, p: int) -> NormalEquations:
        """Nothing summed yet, for n joints and p parameters."""
        return cls(np.zeros((n, p, p)), np.zeros((n, p)), np.zeros(n), np.zeros(n, dtype=np.int64))

    def add(self, Y: np.ndarray, tau: np.ndarray, used: np.ndarray) -> None:
        """Sum in the rows ``Y`` (N x n x p) and torques ``tau`` (N x n) where ``used`` (N x n)."""
        for j in range(Y.shape[1]):
            rows = Y[used[:, j], j, :]
            target = tau[used[:, j], j]
            self.G[j] += rows.T @ rows
            self.b[j] += rows.T @ target
            self.c[j] += target @ target
            self.rows[j] += len(target)

    def weighted(self, weights: np.ndarray, columns: np.ndarray | None = None) -> np.ndarray:
        """sum_j weights_j G_j, of the ``columns`` given (all where None)."""
        G = self.G if columns is None else self.G[:, columns][:, :, columns]
        return np.einsum("j,jik->ik", weights, G)

    def rss(self, phi: np.ndarray) -> np.ndarray:
        """Each joint's residual sum of squares of the parameters ``phi``."""
        return np.einsum("i,jik,k->j", phi, self.G, phi) - 2 * self.b @ phi + self.c

    def rms(self, phi: np.ndarray) -> np.ndarray:
        """Each joint's residual RMS [N m]."""
        return np.sqrt(np.maximum(self.rss(phi), 0) / np.maximum(self.rows, 1))

    def torque_rms(self) -> np.ndarray:
        """Each joint's torque RMS [N m]."""
        return np.sqrt(self.c / np.maximum(self.rows, 1))


def equation_rows(layout: ParameterLayout, dq: np.ndarray, band: float, reversal=None) -> np.ndarray:
    """Which rows (samples x joints) are equations of the fit: not where a joint sticks (|q'| <
    ``band``, with Coulomb friction in the layout), nor where ``reversal`` marks it near a
    velocity reversal (:func:`.signals.near_reversal`; None: no guard).
    """
    used = slipping(dq, band) if "coulomb" in layout.friction else np.ones(dq.shape, dtype=bool)
    return used if reversal is None else used & ~reversal


def regressor_rows(
    model: pin.Model,
    layout: ParameterLayout,
    states: States,
    band: float,
    segment: slice = slice(None),
    guard: bool = True,
):
    """The full regressor of ``states[segment]``, :data:`BATCH` samples at a time (the states a
    window at a time: :meth:`.signals.States.windows`): (Y, tau, used) per batch, ``used`` false
    where a joint sticks (|q'| < ``band``, with Coulomb friction in the layout) or, with
    ``guard``, is within the reversal guard of a velocity reversal
    (:attr:`.signals.FilterChoice.reversal_guard`): there its row is no equation.
    """
    from ...run.compiled import torque_regressor_of

    inertial = torque_regressor_of(model) or (lambda *x: torque_regressor(model, *x))  # C++, else pin's
    for window in states.windows(segment):
        q, dq, ddq, tau = window.q, window.dq, window.ddq, window.tau
        for start in range(0, len(q), BATCH):
            part = slice(start, start + BATCH)
            Y = np.concatenate(
                [
                    inertial(q[part], dq[part], ddq[part]),
                    friction_regressor(layout, dq[part], ddq[part]),
                ],
                axis=2,
            )
            reversal = window.reversal[part] if guard and window.reversal is not None else None
            yield Y, tau[part], equation_rows(layout, dq[part], band, reversal)


def normal_equations(
    model: pin.Model,
    layout: ParameterLayout,
    states: States,
    band: float,
    segment: slice = slice(None),
    guard: bool = True,
) -> NormalEquations:
    """The normal equations of ``states[segment]`` (:func:`regressor_rows`)."""
    out = NormalEquations.empty(layout.n, layout.size)
    for Y, tau, used in regressor_rows(model, layout, states, band, segment, guard):
        out.add(Y, tau, used)
    return out


def residuals(
    model: pin.Model,
    layout: ParameterLayout,
    states: States,
    band: float,
    segment: slice,
    phi: np.ndarray,
    guard: bool = True,
) -> np.ndarray:
    """The residual tau - Y phi on ``states[segment]``, N x n, NaN where a joint's row is no equation."""
    parts = []
    for Y, tau, used in regressor_rows(model, layout, states, band, segment, guard):
        parts.append(np.where(used, tau - Y @ phi, np.nan))
    return np.concatenate(parts) if parts else np.zeros((0, layout.n))


def base_columns(layout: ParameterLayout, base: BaseParameters) -> np.ndarray:
    """The full vector's columns of the base regressor: the base inertial ones, then every
    friction and armature column.
    """
    return np.concatenate([base.base, np.arange(10 * layout.n, layout.size)])


def unidentifiable_armature(
    model: pin.Model, base: BaseParameters, samples: int = 0, seed: int = 0
) -> list[int]:
    """The joints whose rotor inertia no log can tell from the links' inertia: those whose
    armature column (q''_j on joint j's row) lies in the span of the base inertial columns over
    random states (as :func:`~nnrobust.model.regressor.base_parameters` draws them). These are
    Khalil's regrouping rules: a serial arm's first joint (its axis fixed in the base: its rotor
    inertia adds to the links' moment about that axis), and a second joint perpendicular to the
    first (its link's moment about its own axis moves only its own torque, with q''_2, as its
    rotor inertia does); only the sum moves the torque.
    """
    from ...model.regressor import random_regressor

    Y, a = random_regressor(model, samples, seed)
    W = Y[:, base.base]
    out = []
    for j in range(model.nv):
        column = np.zeros_like(a)
        column[:, j] = a[:, j]
        column = column.reshape(-1)
        c, *_ = np.linalg.lstsq(W, column, rcond=None)
        if np.linalg.norm(column - W @ c) <= 1e-8 * np.linalg.norm(column):
            out.append(j)
    return out


def base_projector(layout: ParameterLayout, base: BaseParameters) -> np.ndarray:
    """The matrix that maps the full parameters to the base ones (friction and armature as they are)."""
    extra = layout.size - 10 * layout.n
    P = np.zeros((base.rank + extra, layout.size))
    P[: base.rank, : 10 * layout.n] = base.projector(10 * layout.n)
    P[base.rank :, 10 * layout.n :] = np.eye(extra)
    return P


@dataclass
class Identifiability:
    """How well the log excites the base parameters.

    Attributes:
        condition: the condition number of the base regressor with unit-norm columns.
        unexcited: the base parameters the log does not excite (named), one per weak direction.

    """

    condition: float
    unexcited: list[str]


def identifiability(normal: NormalEquations, columns: np.ndarray, names: list[str]) -> Identifiability:
    """The condition number and the unexcited directions of the base regressor (module docstring, 1)."""
    G = normal.G.sum(axis=0)[np.ix_(columns, columns)]
    diag = np.diag(G)
    zero = [names[i] for i in np.flatnonzero(diag <= 0)]
    if zero:
        return Identifiability(np.inf, zero)
    scale = 1 / np.sqrt(diag)
    values, vectors = np.linalg.eigh(G * np.outer(scale, scale))
    values = np.maximum(values, 0)
    weak = values < EXCITATION_TOLERANCE * values[-1]
    unexcited = [names[int(np.argmax(np.abs(vectors[:, i])))] for i in np.flatnonzero(weak)]
    condition = float(np.sqrt(values[-1] / values[0])) if values[0] > 0 else np.inf
    return Identifiability(condition, unexcited)


@dataclass
class LeastSquares:
    """The weighted least-squares estimate of the base parameters.

    Attributes:
        beta: the base parameters (base inertial, then friction and armature).
        sigma: each joint's noise standard deviation [N m] (from the ordinary fit's residual).
        covariance: (sum_j G_j / sigma_j^2)^-1, the estimate's covariance if the residuals are white.

    """

    beta: np.ndarray
    sigma: np.ndarray
    covariance: np.ndarray


def weighted_least_squares(
    normal: NormalEquations, columns: np.ndarray, minimum_norm: bool = False
) -> LeastSquares:
    """Ordinary, then weighted least squares in the base parameters (module docstring, 2); with
    ``minimum_norm`` (a log that leaves directions unexcited), the least-norm solutions.
    """
    G = normal.G[:, columns][:, :, columns]
    b = normal.b[:, columns]
    solve = _least_norm if minimum_norm else np.linalg.solve
    beta = solve(G.sum(axis=0), b.sum(axis=0))
    dof = max(int(normal.rows.sum()) - len(columns), 1)
    rss = np.einsum("i,jik,k->j", beta, G, beta) - 2 * b @ beta + normal.c
    sigma = np.sqrt(np.maximum(rss, 1e-30) / np.maximum(normal.rows, 1) * normal.rows.sum() / dof)
    weights = 1 / sigma**2
    Gw = np.einsum("j,jik->ik", weights, G)
    beta = solve(Gw, weights @ b)
    return LeastSquares(
        beta, sigma, np.linalg.pinv(Gw, hermitian=True) if minimum_norm else np.linalg.inv(Gw)
    )


def _least_norm(G: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.linalg.lstsq(G, b, rcond=EXCITATION_TOLERANCE)[0]


def physically_consistent(
    normal: NormalEquations, layout: ParameterLayout, sigma: np.ndarray, prior: np.ndarray, held=()
) -> np.ndarray:
    """The full parameters of least weighted residual with every body physical (module docstring,
    3); the full vector's entries ``held`` stay at the prior (a rotor inertia no log can tell from
    the links', :func:`unidentifiable_armature`).
    """
    try:
        import cvxpy as cp  # here: cvxpy and clarabel are the identify extra's
    except ImportError as err:
        raise LogError("the physically consistent fit needs cvxpy: pip install 'nnrobust[identify]'") from err
    weights = 1 / sigma**2
    H = normal.weighted(weights)
    g = weights @ normal.b
    values, vectors = np.linalg.eigh(H)
    keep = values > 1e-12 * values[-1]
    A = np.sqrt(values[keep])[:, None] * vectors[:, keep].T
    target = (vectors[:, keep].T @ g) / np.sqrt(values[keep])
    mu = PRIOR_WEIGHT * float(values[keep].mean())
    # the parameters in units where the prior is 1 (a body's parameters span 1e-4 to 10)
    scale = np.maximum(np.abs(prior), typical_sizes(layout))
    x = cp.Variable(layout.size)
    phi = cp.multiply(scale, x)
    cost = cp.sum_squares(A @ phi - target) + mu * cp.sum_squares(x - prior / scale)
    constraints = []
    for i in range(layout.n):
        J = pseudo_inertia_expression(phi[10 * i : 10 * i + 10], cp)
        constraints.append(J - PSD_MARGIN * np.eye(4) >> 0)
    for term in layout.friction:
        if term != "offset":
            constraints.append(phi[layout.friction_slice(term)] >= 0)
    if layout.armature:
        constraints.append(phi[layout.armature_slice] >= 0)
    for i in held:
        constraints.append(x[i] == prior[i] / scale[i])
    problem = cp.Problem(cp.Minimize(cost), constraints)
    try:
        problem.solve(solver=cp.CLARABEL)
    except cp.error.SolverError as err:
        raise LogError(f"the physically consistent fit failed in its solver: {err}") from err
    if problem.status not in ("optimal", "optimal_inaccurate") or x.value is None:
        raise LogError(
            f"the physically consistent fit ended {problem.status}: no physical robot fits these torques "
            "(are they the joint torques, in N m, with the sign of q''?)"
        )
    phi_out = np.asarray(scale * x.value, dtype=float)
    phi_out[list(held)] = prior[list(held)]  # exactly, not to the solver's tolerance
    for i in range(layout.n):  # the solver's tolerance can leave a body a hair outside physics
        phi_out[10 * i : 10 * i + 10] = strictly_physical(phi_out[10 * i : 10 * i + 10])
    for term in layout.friction:
        if term != "offset":
            phi_out[layout.friction_slice(term)] = np.maximum(phi_out[layout.friction_slice(term)], 0.0)
    if layout.armature:
        phi_out[layout.armature_slice] = np.maximum(phi_out[layout.armature_slice], 0.0)
    return phi_out


def least_pseudo_inertia_eigenvalues(phi: np.ndarray, n: int) -> np.ndarray:
    """Each body's least pseudo-inertia eigenvalue (>= 0: physical)."""
    return np.array([np.linalg.eigvalsh(pseudo_inertia(phi[10 * i : 10 * i + 10]))[0] for i in range(n)])
