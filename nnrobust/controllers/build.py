"""How an experiment builds its controller from ``[controller]`` and ``[nn]``: one of the paper's
kinds (eq. 9 with its robust terms, the PD; each declared beside its code, :class:`PaperKind`), a
registered law (nnrobust/controllers/laws/) or a user's class, each from the
:class:`ControllerContext` it is handed.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

import numpy as np

from ..arrays import joint_vector
from ..exceptions import ConfigError
from ..model import DynamicsModel, PinocchioModel
from ..plant import Friction, Plant
from ..subtasks.base import Criterion
from ..trajectories import Trajectory
from .base import Controller, ControllerContext
from .basis import AdditiveRBFBasis, input_box
from .custom import build_custom
from .pseudoinverse import DampedPseudoInverse
from .registry import KindParts, controller_kinds, paper_kind, registered_law

if TYPE_CHECKING:
    from ..config import ExperimentConfig


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
    """What a controller is built from (:class:`ControllerContext`): never the true plant's model,
    and nothing the plant or the record reads. The nominal model is the controller's own
    (:func:`nnrobust.model.nominal.build_nominal`); the trajectory and the criterion are copies,
    so that a law writing into them changes neither the recorded x_d, e and h nor the run.
    """
    c = config.controller
    trajectory_key = "trajectory.class" if config.trajectory.kind == "custom" else "trajectory.kind"
    return ControllerContext(
        nominal=nominal,
        trajectory=_own_copy(trajectory, trajectory_key),
        criterion=_own_copy(criterion, "subtasks.criterion_class"),
        period=config.simulation.control_period,
        torque_limits=None if plant.torque_limit is None else plant.torque_limit.copy(),
        q0=q0.copy(),
        lower_limits=robot.lower_limits.copy(),
        upper_limits=robot.upper_limits.copy(),
        nominal_friction=build_nominal_friction(config, robot.nq),
        null_space_gain=c.k,
        pseudo_inverse=DampedPseudoInverse(c.pinv_threshold, c.pinv_max_damping),
    )


def _own_copy(part, key: str):
    """A deep copy of a part for the controller, or one line naming the key of a part that
    cannot be copied (a user's class holding a lock, an open file, ...).
    """
    try:
        return copy.deepcopy(part)
    except Exception as err:
        raise ConfigError(
            key,
            f"{type(getattr(part, 'inner', part)).__name__} cannot be copied for the controller "
            f"({type(err).__name__}: {err}); "
            "a controller is given its own copy (copy.deepcopy) so that it cannot change the run or "
            "its record: hold nothing that cannot be copied, or define __deepcopy__",
        ) from err


def build_controller(
    config: ExperimentConfig,
    robot: PinocchioModel,
    nominal: DynamicsModel,
    trajectory: Trajectory,
    criterion: Criterion | None,
    true_friction: Friction | None,
    context: ControllerContext,
) -> Controller:
    """The control law named by controller.kind: a user's class or a registered law built from
    ``context``, or one of the paper's kinds by its declared builder (computed torque takes
    ``true_friction`` as F-hat).
    """
    c = config.controller
    if c.kind == "custom":
        return build_custom(c.class_ or "", c.params, context)
    law = registered_law(c.kind)
    if law is not None:
        built = law.build(context, c.params)
        base = getattr(built, "base_kind", None)
        if base is not None:  # a law on another (a residual policy): that kind as this experiment builds it
            built.base = build_controller(
                config.replace(controller={"kind": base, "params": None}),
                robot,
                nominal,
                trajectory,
                criterion,
                true_friction,
                context,
            )
        return built
    kind = paper_kind(c.kind)
    if kind is None:  # validate refuses it first
        raise ConfigError("controller.kind", f"{c.kind!r} is not one of {', '.join(controller_kinds())}")
    return kind.build(KindParts(config, robot, nominal, trajectory, criterion, true_friction, context))
