"""Closed-form dynamics of the paper's three-link planar arm (Sect. 4), errata corrected.

The paper's printed M(q) and V_m(q, q') are wrong (docs/errata.md). This module implements the
physical matrices derived by Lagrange's equations for links whose centres of mass lie on the link
axes, in the paper's parameters beta_1..3 and p_1..3. It is the test oracle that the
Pinocchio-backed model must agree with, and, evaluated with the paper's estimates p-hat, the
controller's nominal model of the paper's experiments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..core.exceptions import ModelMismatch


@dataclass(frozen=True)
class ThreeLinkParameters:
    """Inertial parameters of a three-link planar arm.

    Attributes:
        beta: (beta_1, beta_2, beta_3) [kg m^2], the configuration-independent parts of M.
        p: (p_1, p_2, p_3) [kg m^2], with p_1 = l1 (m2 lc2 + m3 l2), p_2 = m3 l1 lc3,
            p_3 = m3 l2 lc3.
        lengths: (l_1, l_2, l_3) [m], joint-to-joint and last joint to the task point.
        gamma: first mass moments (m1 lc1 + (m2 + m3) l1, m2 lc2 + m3 l2, m3 lc3) [kg m].
        gravity: in-plane gravity (g_x, g_y) [m/s^2]; (0, 0) for a horizontal plane.

    """

    beta: tuple[float, ...]
    p: tuple[float, ...]
    lengths: tuple[float, ...]
    gamma: tuple[float, ...] = (0.0, 0.0, 0.0)
    gravity: tuple[float, ...] = (0.0, 0.0)

    twin_fields = ("beta", "p", "lengths", "gamma", "gravity")
    """What the closed form's compiled twin reads (csrc/model/nominal.hpp, ThreeLinkSpec)."""

    @classmethod
    def paper(cls) -> ThreeLinkParameters:
        """The paper's printed values, horizontal plane (G = 0)."""
        return cls(
            beta=(1.1956, 0.3946, 0.0512),
            p=(0.4752, 0.1280, 0.1152),
            lengths=(0.40, 0.36, 0.30),
        )

    @classmethod
    def paper_estimate(cls) -> ThreeLinkParameters:
        """The controller's estimate in the paper: p-hat = (0.4, 0.1, 0.1), beta as printed."""
        return cls(
            beta=(1.1956, 0.3946, 0.0512),
            p=(0.4, 0.1, 0.1),
            lengths=(0.40, 0.36, 0.30),
        )

    @classmethod
    def from_links(
        cls,
        masses: tuple[float, ...],
        lengths: tuple[float, ...],
        com: tuple[float, ...],
        inertia_zz: tuple[float, ...],
        gravity: tuple[float, ...] = (0.0, 0.0),
    ) -> ThreeLinkParameters:
        """Parameters from link masses [kg], lengths [m], centre-of-mass distances lc_i [m] and
        inertias about the centre of mass I_i [kg m^2].
        """
        m1, m2, m3 = masses
        l1, l2, _ = lengths
        c1, c2, c3 = com
        i1, i2, i3 = inertia_zz
        beta3 = i3 + m3 * c3**2
        beta2 = i2 + m2 * c2**2 + i3 + m3 * (l2**2 + c3**2)
        beta1 = i1 + m1 * c1**2 + i2 + m2 * (l1**2 + c2**2) + i3 + m3 * (l1**2 + l2**2 + c3**2)
        p = (l1 * (m2 * c2 + m3 * l2), m3 * l1 * c3, m3 * l2 * c3)
        gamma = (m1 * c1 + (m2 + m3) * l1, m2 * c2 + m3 * l2, m3 * c3)
        return cls((beta1, beta2, beta3), p, tuple(lengths), gamma, tuple(gravity))

    @classmethod
    def from_pinocchio(cls, model: pin.Model, task_frame: str) -> ThreeLinkParameters:
        """Parameters of a Pinocchio model of a planar three-link arm.

        Raises:
            ModelMismatch: the model is not three revolute z-axis joints in a chain with joint
                offsets and centres of mass on the link x-axes.

        """
        if model.nq != 3 or model.njoints != 4:
            raise ModelMismatch(
                f"{model.name}: the closed-form model needs exactly 3 revolute joints, got nq = {model.nq}"
            )
        for j in range(1, 4):
            if model.joints[j].shortname() != "JointModelRZ" or model.parents[j] != j - 1:
                raise ModelMismatch(
                    f"{model.name}: joint {model.names[j]!r} must be revolute about z and "
                    "the joints a serial chain"
                )
        offsets = [model.jointPlacements[j] for j in (2, 3)]
        tip = model.frames[model.getFrameId(task_frame)]
        if tip.parentJoint != 3:
            raise ModelMismatch(f"task frame {task_frame!r} is not on the last link")
        offsets.append(tip.placement)
        for placement in [model.jointPlacements[1], *offsets]:
            if not np.allclose(placement.rotation, np.eye(3)) or abs(placement.translation[1]) > 1e-12:
                raise ModelMismatch(f"{model.name}: joint and task-frame offsets must lie on the link x-axes")
        lengths = tuple(float(pl.translation[0]) for pl in offsets)
        inertias = model.inertias[1:4]
        for j, inertia in enumerate(inertias, start=1):
            if abs(inertia.lever[1]) > 1e-12:
                raise ModelMismatch(f"{model.name}: centre of mass of link {j} is off the link x-axis")
        g = model.gravity.linear
        return cls.from_links(
            masses=tuple(float(i.mass) for i in inertias),
            lengths=lengths,
            com=tuple(float(i.lever[0]) for i in inertias),
            inertia_zz=tuple(float(i.inertia[2, 2]) for i in inertias),
            gravity=(float(g[0]), float(g[1])),
        )


@dataclass
class ThreeLinkPlanarModel:
    """Closed-form M, V_m, G, x, J and J' q' of a three-link planar arm (corrected errata).

    Implements :class:`nnrobust.model.base.DynamicsModel` with nq = 3 and m = 2.
    """

    params: ThreeLinkParameters
    nq: int = field(default=3, init=False)
    m: int = field(default=2, init=False)
    task: str = field(default="planar", init=False)
    joint_names: list[str] = field(default_factory=lambda: ["joint1", "joint2", "joint3"])
    pinocchio_model: None = field(default=None, init=False)
    """No Pinocchio model: the closed form is its own (:class:`DynamicsModel`)."""

    twin = "closed-form"
    """Its compiled twin (csrc/model/nominal.hpp), built from ``params``' ``twin_fields``."""

    def mass(self, q: np.ndarray) -> np.ndarray:
        """M(q) with M11 = b1 + 2 p1 c2 + 2 p2 c23 + 2 p3 c3, ... (docs/errata.md)."""
        b1, b2, b3 = self.params.beta
        p1, p2, p3 = self.params.p
        c2, c3, c23 = math.cos(q[1]), math.cos(q[2]), math.cos(q[1] + q[2])
        m11 = b1 + 2 * p1 * c2 + 2 * p2 * c23 + 2 * p3 * c3
        m12 = b2 + p1 * c2 + p2 * c23 + 2 * p3 * c3
        m13 = b3 + p2 * c23 + p3 * c3
        m22 = b2 + 2 * p3 * c3
        m23 = b3 + p3 * c3
        return np.array([[m11, m12, m13], [m12, m22, m23], [m13, m23, b3]])

    def coriolis_matrix(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """V_m(q, q') from Christoffel symbols (M' - 2 V_m skew-symmetric), docs/errata.md."""
        p1, p2, p3 = self.params.p
        s2, s3, s23 = math.sin(q[1]), math.sin(q[2]), math.sin(q[1] + q[2])
        a = p1 * s2 + p2 * s23
        b = p2 * s23 + p3 * s3
        c = p3 * s3
        v1, v2, v3 = v
        return np.array(
            [
                [-a * v2 - b * v3, -a * (v1 + v2) - b * v3, -b * (v1 + v2 + v3)],
                [a * v1 - c * v3, -c * v3, -c * (v1 + v2 + v3)],
                [b * v1 + c * v2, c * (v1 + v2), 0.0],
            ]
        )

    def gravity(self, q: np.ndarray) -> np.ndarray:
        """G(q) = dU/dq for in-plane gravity (g_x, g_y)."""
        gx, gy = self.params.gravity
        theta = np.cumsum(q)
        dU = np.asarray(self.params.gamma) * (gx * np.sin(theta) - gy * np.cos(theta))
        return np.cumsum(dU[::-1])[::-1]

    def bias(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """V_m(q, q') q' + G(q)."""
        return self.coriolis_matrix(q, v) @ v + self.gravity(q)

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """M(q) a + V_m q' + G."""
        return self.mass(q) @ a + self.bias(q, v)

    def forward_dynamics(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Q'' = M^-1 (tau - V_m q' - G)."""
        return np.linalg.solve(self.mass(q), tau - self.bias(q, v))

    def kinetic_energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """0.5 q'^T M q'."""
        return float(0.5 * v @ self.mass(q) @ v)

    def potential_energy(self, q: np.ndarray) -> float:
        """U(q) = -sum_j gamma_j (g_x cos theta_j + g_y sin theta_j), theta_j = q_1 + .. + q_j."""
        gx, gy = self.params.gravity
        theta = np.cumsum(q)
        return float(-np.sum(np.asarray(self.params.gamma) * (gx * np.cos(theta) + gy * np.sin(theta))))

    def task_position(self, q: np.ndarray) -> np.ndarray:
        """X = (sum l_j cos theta_j, sum l_j sin theta_j)."""
        theta = np.cumsum(q)
        lengths = np.asarray(self.params.lengths)
        return np.array([lengths @ np.cos(theta), lengths @ np.sin(theta)])

    def task_jacobian(self, q: np.ndarray) -> np.ndarray:
        """J[:, k] = sum_{j >= k} l_j (-sin theta_j, cos theta_j)."""
        theta = np.cumsum(q)
        lengths = np.asarray(self.params.lengths)
        cols = lengths * np.array([-np.sin(theta), np.cos(theta)])
        return np.cumsum(cols[:, ::-1], axis=1)[:, ::-1]

    def task_jdot_v(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """J' q' = -sum_j l_j theta'_j^2 (cos theta_j, sin theta_j)."""
        theta = np.cumsum(q)
        w = np.cumsum(v)
        lengths = np.asarray(self.params.lengths)
        return -np.array([np.cos(theta), np.sin(theta)]) @ (lengths * w**2)

    def task_state(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, J, J' q') from one evaluation of the link angles theta_j."""
        theta = np.cumsum(q)
        c, s = np.cos(theta), np.sin(theta)
        lengths = np.asarray(self.params.lengths)
        x = np.array([lengths @ c, lengths @ s])
        cols = lengths * np.array([-s, c])
        J = np.cumsum(cols[:, ::-1], axis=1)[:, ::-1]
        jdot_v = -np.array([c, s]) @ (lengths * np.cumsum(v) ** 2)
        return x, J, jdot_v

    def task_jacobian_derivative(self, q: np.ndarray) -> np.ndarray:
        """H[:, i, k] = dJ_i/dq_k = -sum_{j >= max(i, k)} l_j (cos theta_j, sin theta_j)."""
        theta = np.cumsum(q)
        lengths = np.asarray(self.params.lengths)
        terms = -lengths * np.array([np.cos(theta), np.sin(theta)])  # 2 x 3
        tail = np.cumsum(terms[:, ::-1], axis=1)[:, ::-1]  # tail[:, j] = sum_{l >= j}
        idx = np.maximum.outer(np.arange(3), np.arange(3))
        return tail[:, idx]

    def chain_points(self, q: np.ndarray) -> np.ndarray:
        """World positions of the joint origins and of the tip, 4 x 3 [m] (base at the origin)."""
        theta = np.cumsum(q)
        steps = np.asarray(self.params.lengths)[:, None] * np.array([np.cos(theta), np.sin(theta)]).T
        points = np.zeros((4, 3))
        points[1:, :2] = np.cumsum(steps, axis=0)
        return points

    def chain_jacobians(self, q: np.ndarray) -> np.ndarray:
        """Jacobians of the chain points, 4 x 3 x 3: d p_j / d q_k = sum_{k <= i < j} l_i (-s_i, c_i)."""
        theta = np.cumsum(q)
        cols = np.asarray(self.params.lengths) * np.array([-np.sin(theta), np.cos(theta)])  # 2 x 3
        out = np.zeros((4, 3, 3))
        for j in range(1, 4):
            for k in range(j):
                out[j, :2, k] = cols[:, k:j].sum(axis=1)
        return out
