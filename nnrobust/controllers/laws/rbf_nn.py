"""A function-approximating adaptive RBF network in eq. (9) (``controller.kind = "rbf-nn"``;
compiled twin csrc/controllers/laws/rbf_nn.cpp; docs/controller.md), after Lewis, Jagannathan and Yeşildirek:
the network learns the uncertainty η itself, where the paper's network learns a bound on |η|.

The task-space law of eq. (9) leaves the error system y' = A y + B (u₀ + η), y = [e, ė] (eq. 13).
With w = Bᵀ P y (P of eq. 16), Ŵ an L × m weight matrix over the paper's basis φ(s) and
V = yᵀ P y + tr(W̃ᵀ F⁻¹ W̃):

    u₀  = −Ŵᵀ φ(s) − k_z (‖Ŵ‖_F + W_B) w               (the estimate of η, and the robustifying term)
    Ŵ'  = F (φ wᵀ − κ ‖w‖ Ŵ)                            (e-modification)

so that V' = −yᵀ Q y + 2 wᵀ (ε − k_z (‖Ŵ‖_F + W_B) w) + 2 κ ‖w‖ tr(W̃ᵀ Ŵ) for η = Wᵀ φ + ε:
y and W̃ are uniformly ultimately bounded. A sampled controller holds (w, φ) over the period,
where Ŵ' is linear in Ŵ and is solved exactly: Ŵ⁺ = Ŵ d + (φ wᵀ / (κ ‖w‖)) (1 − d), d =
e^(−F κ ‖w‖ T) (Ŵ + F T φ wᵀ when κ ‖w‖ = 0). K_p = ω² I, K_v = 2 ζ ω I; the state z is Ŵ by
columns.
"""

from __future__ import annotations

import math

import numpy as np

from ...core.search_coordinates import bandwidth_range
from ..base import ControllerContext
from ..basis import AdditiveRBFBasis, input_box
from ..nn_compensator import error_dynamics, lyapunov_P
from ..registry import Law, LawParam, register_law
from ..task_space import TaskSpaceController


class RBFCompensator:
    """u₀ = −Ŵᵀ φ(s) − k_z (‖Ŵ‖_F + W_B) w with Ŵ' = F (φ wᵀ − κ ‖w‖ Ŵ) (the module docstring)."""

    signal_names = ("eta_hat_norm", "weights_norm")

    def __init__(self, Kp, Kv, basis: AdditiveRBFBasis, joint_input: bool, F, kappa, k_z, W_B):
        _, B = error_dynamics(Kp, Kv)
        self.BtP = B.T @ lyapunov_P(Kp, Kv)
        self.basis, self.joint_input = basis, joint_input
        self.F, self.kappa, self.k_z, self.W_B = F, kappa, k_z, W_B
        self.L, self.m = basis.size, Kp.shape[0]
        self.state_size = self.L * self.m

    def initial_state(self) -> np.ndarray:
        """Ŵ(0) = 0."""
        return np.zeros(self.state_size)

    def output(self, q, v, y, z, period):
        """(u₀, Ŵ after the period, signals)."""
        W = z.reshape(self.L, self.m, order="F")
        w = self.BtP @ y
        phi = self.basis(np.concatenate([q, v]) if self.joint_input else y)
        eta_hat = W.T @ phi
        size = np.linalg.norm(W)
        u0 = -eta_hat - self.k_z * (size + self.W_B) * w
        drive, rate = np.outer(phi, w), self.F * self.kappa * np.linalg.norm(w)
        if rate > 0.0:
            decay = math.exp(-rate * period)
            W_next = W * decay + (drive / (self.kappa * np.linalg.norm(w))) * (1.0 - decay)
        else:
            W_next = W + self.F * period * drive
        signals = {"eta_hat_norm": float(np.linalg.norm(eta_hat)), "weights_norm": float(size)}
        return u0, W_next.reshape(-1, order="F"), signals


class RBFNN(TaskSpaceController):
    """Eq. (9) with the function-approximating RBF network as u₀ (the module docstring)."""

    def __init__(
        self,
        context: ControllerContext,
        bandwidth=math.sqrt(10.0),
        damping_ratio=2 / math.sqrt(10.0),
        k=10.0,
        F=30.0,
        kappa=0.1,
        k_z=1.0,
        W_B=1.0,
        basis_input="joint",
        centers=5,
        width=1.0,
        velocity_range=3.0,
        error_range=(0.05, 0.5),
    ):
        m = context.m
        Kp, Kv = np.eye(m) * bandwidth**2, np.eye(m) * (2 * damping_ratio * bandwidth)
        low, high = input_box(
            basis_input, context.lower_limits, context.upper_limits, velocity_range, error_range, m
        )
        basis = AdditiveRBFBasis(low, high, int(centers), width, True)
        compensator = RBFCompensator(Kp, Kv, basis, basis_input == "joint", F, kappa, k_z, W_B)
        super().__init__(
            context.nominal,
            context.trajectory,
            Kp,
            Kv,
            k,
            context.criterion,
            context.nominal_friction,
            compensator,
            context.pseudo_inverse,
        )
        self.BtP, self.F, self.kappa, self.k_z, self.W_B = compensator.BtP, F, kappa, k_z, W_B
        self.centers, self.inv2w2 = basis.grid, basis.inverse_two_width_sq
        self.joint_input = float(basis_input == "joint")


def _null_gain(scales: dict) -> tuple[float, float]:
    """The self-motion gain up to k T = 1 (as eq. 9's)."""
    return 0.1, 1.0 / scales["period"]


BASIS = "the network's structure, the experiment's (the same defaults as the NN compensator's, nn.*)"
"""Why the tuner holds the basis' parameters: the network's structure, not a gain."""

_PARAMS = (
    LawParam(
        "bandwidth", math.sqrt(10.0), "rad/s", "ω: K_p = ω² I", 1e-6, 1e6, search=bandwidth_range,
        high_reason="sampling: w (1/2 + delay) T = 1",
    ),
    LawParam(
        "damping_ratio", 2 / math.sqrt(10.0), "-", "ζ: K_v = 2 ζ ω I", 0.501, 1e3, search=(0.51, 5.0),
        low_reason="eq. (17): K_v^2 > K_p",
    ),
    LawParam(
        "k", 10.0, "1/s", "self-motion gain of eq. (3)", 0.0, 1e6, search=_null_gain,
        high_reason="sampling: k T <= 1",
    ),
    LawParam("F", 30.0, "-", "adaptation gain", 0.0, 1e6, search=(1e-2, 1e4), weak="low"),
    LawParam("kappa", 0.1, "-", "e-modification κ", 0.0, 1e6, search=(1e-4, 10.0), weak="high"),
    LawParam("k_z", 1.0, "-", "robustifying gain k_z", 0.0, 1e6, search=(1e-4, 10.0), weak="low"),
    LawParam(
        "W_B", 1.0, "m/s^2", "bound on the ideal weights' norm in the robustifying term", 0.0, 1e6,
        fixed="the theory's prior bound; the robustifying term's level k_z (|W| + W_B) is searched by k_z",
    ),
    LawParam("basis_input", "joint", "-", "s = [q, q'] or [e, e']", choices=("joint", "error")),
    LawParam(
        "centers", 5, "-", "Gaussian centres per input coordinate", 1.0, 1000.0, integer=True, fixed=BASIS
    ),
    LawParam("width", 1.0, "-", "Gaussian width as a multiple of the centre spacing", 1e-9, 1e9, fixed=BASIS),
    LawParam("velocity_range", 3.0, "rad/s", "q' centres span ±velocity_range", 1e-9, 1e9, fixed=BASIS),
    LawParam(
        "error_range", (0.05, 0.5), "m, m/s", "e and e' centres span ±error_range", 1e-9, 1e9, size="2",
        fixed=BASIS,
    ),
)  # fmt: skip

LAW = register_law(
    Law(
        "rbf-nn",
        RBFNN,
        "eq. (9) with an adaptive RBF network that learns the uncertainty itself, e-modification "
        "and a robustifying term (after Lewis, Jagannathan and Yeşildirek)",
        _PARAMS,
        twin="rbf_nn",
        twin_fields=("Kp", "Kv", "k", "BtP", "F", "kappa", "k_z", "W_B", "centers", "inv2w2", "joint_input"),
    )
)
