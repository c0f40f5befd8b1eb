"""Pinocchio-backed dynamics and task kinematics for any URDF arm."""

from __future__ import annotations

from functools import cached_property

import numpy as np
import pinocchio as pin

from ..core.exceptions import FrameNotFound, ModelMismatch
from ..core.small_linalg import adjugate, det
from .tasks import TASK_KINDS, pose_vector

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

MAX_JOINTS = 300
"""Most joints a model may have: pin.Data's memory grows as n^3 (1.8 GB at 300, 7.8 GB at 500)."""


LINK_FRAME_TYPES = (pin.FrameType.BODY, pin.FrameType.OP_FRAME)
"""Frames that a task frame or a chain end may be: links and operational frames."""


def frame_id(model: pin.Model, name: str) -> int:
    """The id of frame ``name``: a body or operational frame when joints or links share the name."""
    for kind in LINK_FRAME_TYPES:
        if model.existFrame(name, kind):
            return model.getFrameId(name, kind)
    return model.getFrameId(name)


class PinocchioModel:
    """Dynamics (RNEA, CRBA, ABA) and task kinematics of the frame ``task_frame``.

    Args:
        model: a Pinocchio model with one configuration coordinate per joint (nq == nv).
        task_frame: name of the frame whose position (or pose) is the task x.
        task: ``"planar"`` (world x-y position, m = 2), ``"position"`` (x-y-z, m = 3) or
            ``"pose"`` (position and orientation, m = 6; see :mod:`nnrobust.model.tasks`).
        name: where the model came from (file or robot name), for messages.

    """

    twin = "pinocchio"
    """Its compiled twin (csrc/model/nominal.hpp), built from the model itself (compiled.load_model)."""

    def __init__(self, model: pin.Model, task_frame: str, task: str = "planar", name: str = ""):
        if task not in TASK_KINDS:
            raise ModelMismatch(f"unknown task kind {task!r}; valid kinds: {', '.join(TASK_KINDS)}")
        if model.nq != model.nv:
            raise ModelMismatch(
                f"{name or model.name}: nq = {model.nq} != nv = {model.nv}; joints with a "
                "non-Euclidean configuration (continuous, free-flyer, spherical) are not supported"
            )
        if model.nv == 0:
            raise ModelMismatch(f"{name or model.name}: the model has no movable joint")
        if model.nv > MAX_JOINTS:
            raise ModelMismatch(
                f"{name or model.name}: {model.nv} joints; at most {MAX_JOINTS} are supported "
                "(Pinocchio's Data holds n x n x n derivative tensors: 1.8 GB at n = 300)"
            )
        if not model.existFrame(task_frame):
            raise FrameNotFound(task_frame, [f.name for f in model.frames])
        self.model = model
        self.data = model.createData()
        self.name = name or model.name
        self.urdf_text: str | None = None
        """The URDF text Pinocchio parsed (for a second engine); None when code built the model."""
        self.task = task
        self.task_frame = task_frame
        self.frame_id = frame_id(model, task_frame)
        self.nq = model.nq
        self.m = TASK_KINDS[task]
        self.joint_names = [model.names[i] for i in range(1, model.njoints)]
        self._zero = np.zeros(self.nq)
        self._rows = [0, 1] if task == "planar" else list(range(self.m))

    @property
    def pinocchio_model(self) -> pin.Model:
        """The ``pin.Model`` (read it; its :attr:`data` is this model's workspace)."""
        return self.model

    @cached_property
    def _lower_indices(self) -> tuple[np.ndarray, np.ndarray]:
        """Indices below the diagonal of M, made on first use (n^2 of them)."""
        return np.tril_indices(self.nq, -1)

    # -- dynamics -------------------------------------------------------------------------
    def mass(self, q: np.ndarray) -> np.ndarray:
        """M(q) by CRBA (lower triangle copied from the upper: older pin fills only that one)."""
        M = pin.crba(self.model, self.data, q).copy()
        lower = self._lower_indices
        M[lower] = M.T[lower]
        return M

    def bias(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """V_m(q, q') q' + G(q) by RNEA at zero acceleration."""
        return pin.nonLinearEffects(self.model, self.data, q, v).copy()

    def gravity(self, q: np.ndarray) -> np.ndarray:
        """G(q)."""
        return pin.computeGeneralizedGravity(self.model, self.data, q).copy()

    def coriolis_matrix(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """V_m(q, q') built from Christoffel symbols, so that M' - 2 V_m is skew-symmetric."""
        return pin.computeCoriolisMatrix(self.model, self.data, q, v).copy()

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """M a + V_m q' + G in one RNEA pass (no M is built)."""
        return pin.rnea(self.model, self.data, q, v, a).copy()

    def forward_dynamics(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Q'' by the articulated-body algorithm."""
        return pin.aba(self.model, self.data, q, v, tau).copy()

    def kinetic_energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """0.5 q'^T M q' [J]."""
        return float(pin.computeKineticEnergy(self.model, self.data, q, v))

    def potential_energy(self, q: np.ndarray) -> float:
        """Gravitational potential energy [J], zero at the world origin."""
        return float(pin.computePotentialEnergy(self.model, self.data, q))

    # -- task kinematics ------------------------------------------------------------------
    def _coordinates(self, placement: pin.SE3) -> np.ndarray:
        if self.task == "pose":
            return pose_vector(placement.translation, placement.rotation)
        return placement.translation[: self.m].copy()

    def task_position(self, q: np.ndarray) -> np.ndarray:
        """X = f(q), eq. (1): the frame's position, or [p, R] (12 numbers) for a pose task."""
        pin.forwardKinematics(self.model, self.data, q)
        return self._coordinates(pin.updateFramePlacement(self.model, self.data, self.frame_id))

    def task_jacobian(self, q: np.ndarray) -> np.ndarray:
        """J(q), eq. (2): the frame Jacobian in the world-aligned frame, first m rows.

        Rows: linear velocity of the frame origin (x, y[, z]) then, for a pose task, the angular
        velocity, all in world axes.
        """
        J = pin.computeFrameJacobian(self.model, self.data, q, self.frame_id, _LWA)
        return J[: self.m].copy()

    def task_jdot_v(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """J' q': the frame's classical acceleration at zero joint acceleration (linear, angular)."""
        return self.task_state(q, v)[2]

    def task_state(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, J, J' q') from one kinematics pass; what the controller calls once per step."""
        model, data, fid = self.model, self.data, self.frame_id
        pin.forwardKinematics(model, data, q, v, self._zero)
        pin.computeJointJacobians(model, data)
        x = self._coordinates(pin.updateFramePlacement(model, data, fid))
        J = pin.getFrameJacobian(model, data, fid, _LWA)[: self.m].copy()
        jdot_v = pin.getFrameClassicalAcceleration(model, data, fid, _LWA).vector[: self.m].copy()
        return x, J, jdot_v

    def task_jacobian_derivative(self, q: np.ndarray) -> np.ndarray:
        """H[:, :, k] = dJ/dq_k, the kinematic Hessian, from one Jacobian pass.

        In world coordinates the column S_i of joint i moves only with the joints k before it
        (its ancestors in a chain): dS_i/dq_k = ad(S_k) S_i = (w_k x v_i + v_k x w_i, w_k x w_i)
        for k < i, else 0. The world-aligned linear rows follow from J_lin = v + w x p with
        dp/dq_k = J_lin[:, k]. (Pinocchio 4.1's getJointKinematicHessian did not match finite
        differences for the Panda, so this evaluates the same formula from the world Jacobian.)
        """
        model, data, fid = self.model, self.data, self.frame_id
        pin.computeJointJacobians(model, data, q)
        p = pin.updateFramePlacement(model, data, fid).translation
        Jw = pin.getFrameJacobian(model, data, fid, pin.WORLD)
        V, W = Jw[:3].T, Jw[3:].T  # n x 3
        # pairs[i, k] = ad(S_k) S_i, kept for k < i
        dV = np.cross(W[None, :, :], V[:, None, :]) + np.cross(V[None, :, :], W[:, None, :])
        dW = np.cross(W[None, :, :], W[:, None, :])
        mask = np.tri(self.nq, k=-1)[:, :, None]
        dV *= mask
        dW *= mask
        J_lin = V + np.cross(W, p)  # n x 3: world-aligned linear Jacobian, transposed
        # d(v_i + w_i x p)/dq_k = dv_i + dw_i x p + w_i x J_lin[k]
        dL = dV + np.cross(dW, p) + np.cross(W[:, None, :], J_lin[None, :, :])
        H = np.concatenate([dL, dW], axis=2).transpose(2, 0, 1)  # 6 x n(i) x n(k)
        return np.ascontiguousarray(H[self._rows])

    def det_jjt_gradient(self, q: np.ndarray) -> tuple[float, np.ndarray]:
        """det(J J^T) and its gradient in O(n), without the kinematic Hessian (docs/equations.md,
        "Manipulability gradient").

        d det(A)/dq_k = 2 sum_l <w_l, dJ_l/dq_k> with A = J J^T and W = adj(A) J. In world-aligned
        axes, with columns J_l = (u_l, w_l) (linear velocity of the frame origin, angular velocity)
        of a serial chain, dJ_l/dq_k = (w_min(k,l) x u_max(k,l), w_k x w_l [k < l]), so
        grad_k = 2 (<u_k, P_k> + <w_k, S_k>) with the prefix sum P_k = sum_{l<k} Wu_l x w_l and
        the suffix sum S_k = sum_{l>=k} (u_l x Wu_l + w_l x Ww_l). Joints off the frame's branch
        have zero columns and get zero.
        """
        J6 = pin.computeFrameJacobian(self.model, self.data, q, self.frame_id, _LWA)
        J = J6[self._rows]
        A = J @ J.T
        W6 = np.zeros_like(J6)
        W6[self._rows] = adjugate(A) @ J
        u, w = J6[:3].T, J6[3:].T  # n x 3
        Wu, Ww = W6[:3].T, W6[3:].T
        before = np.cross(Wu, w)
        prefix = np.cumsum(before, axis=0) - before
        after = np.cross(u, Wu) + np.cross(w, Ww)
        suffix = np.cumsum(after[::-1], axis=0)[::-1]
        grad = 2.0 * (np.einsum("ij,ij->i", u, prefix) + np.einsum("ij,ij->i", w, suffix))
        return det(A), grad

    def chain_points(self, q: np.ndarray) -> np.ndarray:
        """World positions of the joint origins and of the task frame, (n + 1) x 3 [m]."""
        pin.forwardKinematics(self.model, self.data, q)
        frame = pin.updateFramePlacement(self.model, self.data, self.frame_id)
        points = [self.data.oMi[j].translation for j in range(1, self.model.njoints)]
        return np.array([*points, frame.translation])

    def chain_jacobians(self, q: np.ndarray) -> np.ndarray:
        """Position Jacobians of the chain points in world axes, (n + 1) x 3 x n [m/rad]."""
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacement(model, data, self.frame_id)
        out = np.empty((model.njoints, 3, self.nq))
        for j in range(1, model.njoints):
            out[j - 1] = pin.getJointJacobian(model, data, j, _LWA)[:3]
        out[-1] = pin.getFrameJacobian(model, data, self.frame_id, _LWA)[:3]
        return out

    # -- limits ---------------------------------------------------------------------------
    @property
    def working_range(self) -> tuple[np.ndarray, np.ndarray]:
        """The joint limits clipped to [-pi, pi] (one turn for unbounded revolute joints)."""
        return np.maximum(self.lower_limits, -np.pi), np.minimum(self.upper_limits, np.pi)

    @property
    def mid_configuration(self) -> np.ndarray:
        """The middle of :attr:`working_range`: the default IK seed and reference posture."""
        low, high = self.working_range
        return 0.5 * (low + high)

    @property
    def lower_limits(self) -> np.ndarray:
        """Lower joint position limits [rad or m] from the URDF."""
        return np.asarray(self.model.lowerPositionLimit).copy()

    @property
    def upper_limits(self) -> np.ndarray:
        """Upper joint position limits [rad or m] from the URDF."""
        return np.asarray(self.model.upperPositionLimit).copy()

    @cached_property
    def prismatic(self) -> np.ndarray:
        """Whether each joint is prismatic (positions in m, efforts in N) rather than revolute."""
        return np.array(
            ["Prismatic" in j.shortname() or j.shortname()[-2:-1] == "P" for j in self.model.joints[1:]]
        )

    @property
    def velocity_limits(self) -> np.ndarray:
        """Joint velocity limits [rad/s or m/s] from the URDF."""
        return np.asarray(self.model.velocityLimit).copy()

    @property
    def effort_limits(self) -> np.ndarray:
        """Joint effort limits [N m or N] from the URDF."""
        return np.asarray(self.model.effortLimit).copy()

    @property
    def viscous_friction(self) -> np.ndarray:
        """URDF <dynamics damping>: viscous friction coefficients [N m s/rad]."""
        return np.asarray(self.model.damping).copy()

    @property
    def coulomb_friction(self) -> np.ndarray:
        """URDF <dynamics friction>: Coulomb friction levels [N m]."""
        return np.asarray(self.model.friction).copy()

    def __repr__(self) -> str:
        return f"PinocchioModel({self.name!r}, n={self.nq}, task={self.task!r}, frame={self.task_frame!r})"
