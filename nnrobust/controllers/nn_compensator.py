"""The adaptive neural-network robust compensator u_0, eqs. (15)-(17)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.numeric_limits import MAX_CENTERS, MAX_GAIN, RANGE_LIMITS
from ..core.search_coordinates import Param
from .basis import AdditiveRBFBasis
from .registry import KindParts, LawParam, PaperKind, declare_kind

U0_LAWS = ("corrected", "printed")
"""u_0 = -rho^2 w / (rho |w| + eps) (corrected, default) or -rho w / (rho |w| + eps) (printed)."""

BASIS_INPUTS = ("joint", "error")
"""Network input s: joint state [q, q'] or task error y = [e, e']."""

DEFAULTS = {"F": 5.0, "gamma": 1.0, "eps0": 1.0, "eps_min": 1.0, "sigma": 0.05}
"""The one set of defaults of :class:`NNCompensator` and of ``[nn]`` in an experiment file: the
corrected eq. (15) with sigma-modification (rho-hat stays bounded) and a boundary layer that does
not vanish (eps stays at eps0 = eps_min = 1, so the sampled loop does not chatter; docs/controller.md).
``sigma = 0, eps_min = 0`` is the paper's law exactly."""


def error_dynamics(Kp: np.ndarray, Kv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A = [[0, I], [-Kp, -Kv]] and B = [0; I] of the error system y' = A y + B (u_0 + eta), eq. (13)."""
    m = Kp.shape[0]
    I, Z = np.eye(m), np.zeros((m, m))
    A = np.block([[Z, I], [-Kp, -Kv]])
    B = np.vstack([Z, I])
    return A, B


def lyapunov_Q(Kp: np.ndarray, Kv: np.ndarray) -> np.ndarray:
    """Q = diag(2 Kp^2, 2 Kv^2 - 2 Kp), eq. (17); positive definite iff Kv^2 > Kp."""
    Z = np.zeros_like(Kp)
    return np.block([[2 * Kp @ Kp, Z], [Z, 2 * Kv @ Kv - 2 * Kp]])


def lyapunov_P(Kp: np.ndarray, Kv: np.ndarray) -> np.ndarray:
    """P solving A^T P + P A + Q = 0, eq. (16); equals [[2 Kp Kv, Kp], [Kp, Kv]] for diagonal gains."""
    A, _ = error_dynamics(Kp, Kv)
    return solve_lyapunov(A, lyapunov_Q(Kp, Kv))


def solve_lyapunov(A: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """The P with A^T P + P A + Q = 0, by its Kronecker form (I (x) A^T + A^T (x) I) vec P = -vec Q
    (column-major vec; unique when no two eigenvalues of A sum to zero, as for a Hurwitz A).
    """
    n = A.shape[0]
    eye = np.eye(n)
    kron = np.kron(eye, A.T) + np.kron(A.T, eye)
    P = np.linalg.solve(kron, -Q.reshape(-1, order="F")).reshape(n, n, order="F")
    return (P + P.T) / 2


@dataclass
class NNCompensator:
    """u_0 with rho-hat = Z^T phi(s), Z' = F (|w| phi(s) - sigma Z), eps' = -gamma (eps - eps_min).

    With sigma = 0 and eps_min = 0 this is the paper's law exactly (eq. 15 and the adaptive law
    after it); sigma > 0 is the sigma-modification (leakage) and eps_min > 0 an epsilon floor.
    The state z = [Z (L entries), eps].

    Attributes:
        Kp, Kv: task gains (m x m, diagonal positive).
        basis: phi(s).
        basis_input: "joint" (s = [q, q']) or "error" (s = [e, e']).
        F: adaptation gain (> 0) [scalar].
        gamma: decay rate of eps [1/s].
        eps0: eps(0) > 0.
        eps_min: eps floor (>= 0).
        sigma: leakage (>= 0).
        law: "corrected" or "printed" (docs/errata.md).
        Z0: initial weights (default 0).

    """

    Kp: np.ndarray
    Kv: np.ndarray
    basis: AdditiveRBFBasis
    basis_input: str = "joint"
    F: float = DEFAULTS["F"]
    gamma: float = DEFAULTS["gamma"]
    eps0: float = DEFAULTS["eps0"]
    eps_min: float = DEFAULTS["eps_min"]
    sigma: float = DEFAULTS["sigma"]
    law: str = "corrected"
    Z0: np.ndarray | None = None

    def __post_init__(self):
        if self.law not in U0_LAWS:
            raise ValueError(f"nn.law: {self.law!r} is not one of {U0_LAWS}")
        if self.basis_input not in BASIS_INPUTS:
            raise ValueError(f"nn.basis_input: {self.basis_input!r} is not one of {BASIS_INPUTS}")
        if (
            self.F <= 0
            or self.gamma < 0
            or self.eps0 <= 0
            or not 0 <= self.eps_min <= self.eps0
            or self.sigma < 0
        ):
            raise ValueError(
                "nn: need F > 0, gamma >= 0, eps0 > 0, 0 <= eps_min <= eps0, sigma >= 0; got "
                f"F={self.F}, gamma={self.gamma}, eps0={self.eps0}, eps_min={self.eps_min}, "
                f"sigma={self.sigma}"
            )
        self.P = lyapunov_P(self.Kp, self.Kv)
        _, B = error_dynamics(self.Kp, self.Kv)
        self.BtP = B.T @ self.P  # omega = B^T P y
        self.L = self.basis.size

    signal_names = ("rho_hat", "eps", "z_norm")
    twin = "nn_compensator"  # csrc/controllers/nn_compensator.cpp
    twin_fields = (
        "BtP",
        "centers",
        "inv2w2",
        "bias",
        "joint_input",
        "corrected",
        "F",
        "gamma",
        "eps_min",
        "sigma",
    )

    @property
    def centers(self) -> np.ndarray:
        """The basis's centres, dim(s) x K."""
        return self.basis.grid

    @property
    def inv2w2(self) -> np.ndarray:
        """1 / (2 width^2) of each input coordinate."""
        return self.basis.inverse_two_width_sq

    @property
    def bias(self) -> bool:
        """Whether phi has its constant unit."""
        return self.basis.bias

    @property
    def joint_input(self) -> bool:
        """Whether s = [q, q'] (else [e, e'])."""
        return self.basis_input == "joint"

    @property
    def corrected(self) -> bool:
        """Whether u_0 is the corrected form of eq. (15) (else the printed one)."""
        return self.law == "corrected"

    @property
    def state_size(self) -> int:
        """len(Z) + 1."""
        return self.L + 1

    def initial_state(self) -> np.ndarray:
        """[Z0, eps0]."""
        Z0 = np.zeros(self.L) if self.Z0 is None else np.asarray(self.Z0, dtype=float)
        return np.concatenate([Z0, [self.eps0]])

    def network_input(self, q: np.ndarray, v: np.ndarray, y: np.ndarray) -> np.ndarray:
        """s, the input of phi."""
        return np.concatenate([q, v]) if self.basis_input == "joint" else y

    def omega(self, y: np.ndarray) -> np.ndarray:
        """Omega = B^T P y (= Kp e + Kv e' for the paper's Q)."""
        return self.BtP @ y

    def u0(self, q: np.ndarray, v: np.ndarray, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, float]:
        """u_0 of eq. (15) (corrected or printed form) and rho-hat."""
        w = self.omega(y)
        rho = float(z[: self.L] @ self.basis(self.network_input(q, v, y)))
        eps = max(float(z[self.L]), 0.0)
        denom = rho * np.linalg.norm(w) + eps
        if denom <= 0.0:
            return np.zeros_like(w), rho
        gain = rho * rho if self.law == "corrected" else rho
        return -gain * w / denom, rho

    def state_derivative(self, q: np.ndarray, v: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """[Z', eps'] = [F (|w| phi(s) - sigma Z), -gamma (eps - eps_min)]."""
        Z = z[: self.L]
        phi = self.basis(self.network_input(q, v, y))
        dZ = self.F * (np.linalg.norm(self.omega(y)) * phi - self.sigma * Z)
        deps = -self.gamma * (z[self.L] - self.eps_min)
        return np.concatenate([dZ, [deps]])

    def advance(
        self, q: np.ndarray, v: np.ndarray, y: np.ndarray, z: np.ndarray, period: float
    ) -> np.ndarray:
        """z(t + T) for the adaptive law with its inputs held over the period T (exact solution).

        A sampled controller knows (q, q', y) only at the sampling instants, so |w| and phi(s)
        are constant over [t, t + T) and the law is linear in z:
        Z(t + T) = Z e^(-F sigma T) + (|w| phi / sigma)(1 - e^(-F sigma T)) (Z + F T |w| phi
        for sigma = 0) and eps(t + T) = eps_min + (eps - eps_min) e^(-gamma T).
        """
        if period <= 0.0:
            return z
        Z, eps = z[: self.L], z[self.L]
        drive = np.linalg.norm(self.omega(y)) * self.basis(self.network_input(q, v, y))
        if self.sigma > 0.0:
            decay = np.exp(-self.F * self.sigma * period)
            Z_next = Z * decay + (drive / self.sigma) * (1.0 - decay)
        else:
            Z_next = Z + self.F * period * drive
        eps_next = self.eps_min + (eps - self.eps_min) * np.exp(-self.gamma * period)
        return np.concatenate([Z_next, [eps_next]])

    def output(self, q: np.ndarray, v: np.ndarray, y: np.ndarray, z: np.ndarray, period: float):
        """(u_0, z after the period, signals) for the task-space law."""
        u0, rho = self.u0(q, v, y, z)
        signals = {"rho_hat": rho, "eps": float(z[self.L]), "z_norm": float(np.linalg.norm(z[: self.L]))}
        return u0, self.advance(q, v, y, z, period), signals


def _build(parts: KindParts):
    """Eq. (9) with the NN compensator of ``[nn]``."""
    from .build import build_basis  # here: build reads the declared defaults (section.py) first

    # here: at the top, task_space's kinds would be declared before this one (the order listed)
    from .task_space import eq9_law

    c, nn = parts.controller, parts.nn
    basis = build_basis(nn, parts.robot, parts.trajectory.m)
    term = NNCompensator(
        np.diag(c.Kp),
        np.diag(c.Kv),
        basis,
        nn.basis_input,
        nn.F,
        nn.gamma,
        nn.eps0,
        nn.eps_min,
        nn.sigma,
        nn.law,
    )
    return eq9_law(parts, term)


def _search(scales: dict) -> list:
    """The tuner's coordinates of the NN term (nnrobust/studies/tune/space.py): F, the leakage rate F
    sigma from 1 % over the run to one control period, and the eps floor up to the arm's task
    acceleration.
    """
    D, T, a = scales["duration"], scales["period"], scales["task_acceleration"]
    return [
        Param("nn.F", 1e-2, 1e3, "-", weak="low"),
        Param(
            "leakage_rate",
            0.01 / D,
            1.0 / T,
            "1/s",
            weak="high",
            low_reason=f"run length: F sigma D = 0.01, {0.01 / D:.3g} 1/s",
            high_reason=f"sampling: F sigma T = 1, {1.0 / T:.4g} 1/s",
        ),
        Param("nn.eps_min", 1e-5 * a, a, "m/s^2", weak="high"),
    ]


def _search_keys(values: dict) -> dict:
    """The keys the NN term's coordinates set: sigma-modification's rate F sigma gives nn.sigma
    (Z' = F |w| phi - F sigma Z), and the boundary layer is held at its floor (eps0 = eps_min).
    """
    out = {}
    if "leakage_rate" in values:
        out["nn.sigma"] = values["leakage_rate"] / values["nn.F"]
    if "nn.eps_min" in values:
        out["nn.eps0"] = values["nn.eps_min"]
    return out


_LOW, _HIGH = RANGE_LIMITS
BASIS = "the network's structure, the experiment's (rbf-nn's basis has the same defaults)"
"""Why the tuner holds the basis' keys: the network's structure, not a gain (docs/controller.md)."""

declare_kind(
    PaperKind(
        "nn", "the NN compensator, eq. (15)", "the experiment's (the paper's p̂, f̂_d)", _build, keys=("nn.",),
        search=_search,
        search_keys=_search_keys,
        lyapunov=True,
        params=(
            LawParam("nn.law", "corrected", "-", "u_0 = -ρ̂² ω / (ρ̂ ‖ω‖ + ε) (`corrected`) or -ρ̂ ω / (...) "
                     "(`printed`, the paper's eq. 15 as printed)", choices=U0_LAWS),
            LawParam("nn.F", DEFAULTS["F"], "-", "adaptation gain F", low=0.0, low_open=True, high=MAX_GAIN),
            LawParam("nn.gamma", DEFAULTS["gamma"], "1/s", "decay rate γ of ε", low=0.0, high=MAX_GAIN,
                     fixed="inert in a tuning: ε(0) is held at its floor nn.eps_min, so ε never decays"),
            LawParam("nn.eps0", DEFAULTS["eps0"], "m/s^2", "ε(0)", low=0.0, low_open=True, high=MAX_GAIN),
            LawParam("nn.eps_min", DEFAULTS["eps_min"], "m/s^2", "floor of ε (0: the paper's vanishing "
                     "boundary layer; at most nn.eps0)", low=0.0),
            LawParam("nn.sigma", DEFAULTS["sigma"], "-", "σ-modification leakage (0: the paper's law)",
                     low=0.0, high=MAX_GAIN),
            LawParam("nn.basis_input", "joint", "-", "s = [q, q'] (`joint`) or [e, e'] (`error`)",
                     choices=BASIS_INPUTS),
            LawParam("nn.centers", 5, "-", "Gaussian centres per input coordinate", low=1, high=MAX_CENTERS,
                     integer=True, fixed=BASIS),
            LawParam("nn.width", 1.0, "-", "Gaussian width as a multiple of the centre spacing", low=_LOW,
                     high=_HIGH, fixed=BASIS),
            LawParam("nn.bias", True, "-", "include a constant unit"),
            LawParam("nn.velocity_range", 3.0, "rad/s", "q' centres span ±velocity_range (q's span the "
                     "joint limits)", low=_LOW, high=_HIGH, fixed=BASIS),
            LawParam("nn.error_range", (0.05, 0.5), "m, m/s", "e and e' centres span ±error_range",
                     low=_LOW, high=_HIGH, size="2", fixed=BASIS),
        ),
    )
)  # fmt: skip
