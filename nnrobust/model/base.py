"""The dynamics interface shared by the Pinocchio-backed and the closed-form models."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class DynamicsModel(Protocol):
    """Rigid-body dynamics and task kinematics of an n-joint arm, eqs. (1), (2) and (7).

    Attributes:
        nq: number of joints n.
        m: task dimension m.
        task: task kind (``planar``, ``position`` or ``pose``; :mod:`nnrobust.model.tasks`).
        joint_names: names of the n joints.
        pinocchio_model: the ``pin.Model`` behind a Pinocchio-backed model (for Pinocchio's own
            algorithms: regressors, derivatives), None for the closed-form arm.

    """

    nq: int
    m: int
    task: str
    joint_names: list[str]

    @property
    def pinocchio_model(self) -> object | None:
        """The ``pin.Model`` behind the model, or None."""

    def mass(self, q: np.ndarray) -> np.ndarray:
        """Joint-space inertia matrix M(q), n x n [kg m^2]."""
        ...

    def bias(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """V_m(q, q') q' + G(q) [N m] (no friction)."""
        ...

    def gravity(self, q: np.ndarray) -> np.ndarray:
        """G(q) [N m]."""
        ...

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """M(q) a + V_m(q, q') q' + G(q) [N m]."""
        ...

    def forward_dynamics(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Q'' = M(q)^-1 (tau - V_m q' - G) [rad/s^2]."""
        ...

    def task_position(self, q: np.ndarray) -> np.ndarray:
        """Task coordinates x = f(q), eq. (1) [m]."""
        ...

    def task_jacobian(self, q: np.ndarray) -> np.ndarray:
        """Task Jacobian J(q) = df/dq, m x n, eq. (2)."""
        ...

    def task_jdot_v(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """J'(q, q') q', the task acceleration at zero joint acceleration [m/s^2]."""
        ...

    def task_jacobian_derivative(self, q: np.ndarray) -> np.ndarray:
        """dJ/dq as an array H with H[:, :, k] = dJ/dq_k, shape m x n x n."""
        ...

    def kinetic_energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """0.5 q'^T M(q) q' [J]."""
        ...

    def potential_energy(self, q: np.ndarray) -> float:
        """Gravitational potential energy [J] (zero reference is model dependent)."""
        ...

    def task_state(self, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, J, J' q') from one kinematics pass."""
        ...

    def chain_points(self, q: np.ndarray) -> np.ndarray:
        """World positions of the joint origins and of the task frame, (n + 1) x 3 [m]."""
        ...

    def chain_jacobians(self, q: np.ndarray) -> np.ndarray:
        """Position Jacobians of the chain points, (n + 1) x 3 x n [m/rad]."""
        ...
