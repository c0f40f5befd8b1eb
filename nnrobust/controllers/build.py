"""How an experiment builds its controller from ``[controller]`` and ``[nn]``: the paper's laws
(eq. 9 with its robust terms, the PD), a registered law (nnrobust/controllers/laws/) or a user's
class, each from the :class:`ControllerContext` it is handed.
"""

from __future__ import annotations

import numpy as np

from ..config import ExperimentConfig
from ..config.arrays import joint_vector
from ..model import DynamicsModel, PinocchioModel
from ..plant import Friction, Plant
from ..subtasks.base import Criterion
from ..trajectories import Trajectory
from .base import Controller, ControllerContext
from .basis import AdditiveRBFBasis, input_box
from .custom import build_custom
from .nn_compensator import NNCompensator
from .pseudoinverse import DampedPseudoInverse
from .registry import registered_law
from .sliding_mode import SlidingModeCompensator
from .task_space import TaskSpaceController, TaskSpacePD, sized_null_damping


def build_basis(config: ExperimentConfig, robot: PinocchioModel, m: int) -> AdditiveRBFBasis:
    """phi(s) over [q, q'] (joint limits, +-velocity_range) or [e, e'] (+-error_range)."""
    nn = config.nn
    low, high = input_box(
        nn.basis_input, robot.lower_limits, robot.upper_limits, nn.velocity_range, nn.error_range, m
    )
    return AdditiveRBFBasis(low, high, nn.centers, nn.width, nn.bias)


def build_nominal_friction(config: ExperimentConfig, n: int) -> Friction:
    """F-hat as the nominal section declares it, compensated with controller.coulomb_smoothing."""
    return Friction(
        joint_vector("nominal.viscous_friction", config.nominal.viscous_friction, n, np.zeros(n)),
        joint_vector("nominal.coulomb_friction", config.nominal.coulomb_friction, n, np.zeros(n)),
        config.controller.coulomb_smoothing,
    )


def build_context(
    config: ExperimentConfig,
    robot: PinocchioModel,
    nominal: DynamicsModel,
    trajectory: Trajectory,
    criterion: Criterion | None,
    plant: Plant,
    q0: np.ndarray,
) -> ControllerContext:
    """What a controller is built from (:class:`ControllerContext`): never the true plant's model."""
    c = config.controller
    return ControllerContext(
        nominal=nominal,
        trajectory=trajectory,
        criterion=criterion,
        period=config.simulation.control_period,
        torque_limits=None if plant.torque_limit is None else plant.torque_limit.copy(),
        q0=q0.copy(),
        lower_limits=robot.lower_limits.copy(),
        upper_limits=robot.upper_limits.copy(),
        nominal_friction=build_nominal_friction(config, robot.nq),
        null_space_gain=c.k,
        pseudo_inverse=DampedPseudoInverse(c.pinv_threshold, c.pinv_max_damping),
    )


def build_controller(
    config: ExperimentConfig,
    robot: PinocchioModel,
    nominal: DynamicsModel,
    trajectory: Trajectory,
    criterion: Criterion | None,
    true_friction: Friction | None,
    context: ControllerContext,
) -> Controller:
    """The control law named by controller.kind (computed-torque takes ``true_friction`` as F-hat;
    a custom law is built from ``context``, and the PD's null-space damping sized from it).
    """
    c = config.controller
    if c.kind == "custom":
        return build_custom(c.class_ or "", c.params, context)
    law = registered_law(c.kind)
    if law is not None:
        return law.build(context, c.params)
    pinv = DampedPseudoInverse(c.pinv_threshold, c.pinv_max_damping)
    if c.kind == "pd":
        Kd = np.diag(c.pd_Kd)
        damping = c.pd_null_damping
        if damping is None:
            damping = sized_null_damping(nominal, context.q0, Kd, context.period)
        return TaskSpacePD(nominal, trajectory, np.diag(c.pd_Kp), Kd, damping, pinv)
    Kp, Kv = np.diag(c.Kp), np.diag(c.Kv)
    compensator: NNCompensator | SlidingModeCompensator | None = None
    if c.kind == "nn":
        nn = config.nn
        compensator = NNCompensator(
            Kp,
            Kv,
            build_basis(config, robot, trajectory.m),
            nn.basis_input,
            nn.F,
            nn.gamma,
            nn.eps0,
            nn.eps_min,
            nn.sigma,
            nn.law,
        )
    elif c.kind == "sliding-mode":
        compensator = SlidingModeCompensator(Kp, Kv, c.sliding_gain, c.sliding_boundary)
    if c.kind == "computed-torque":
        if true_friction is None:
            raise ValueError("computed-torque needs the true friction")
        nominal_friction = Friction(true_friction.viscous, true_friction.coulomb, c.coulomb_smoothing)
    else:
        nominal_friction = build_nominal_friction(config, robot.nq)
    return TaskSpaceController(
        nominal, trajectory, Kp, Kv, c.k, criterion, nominal_friction, compensator, pinv
    )
