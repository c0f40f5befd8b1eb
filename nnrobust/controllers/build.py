"""How an experiment builds its controller from its own sections, ``[controller]`` and ``[nn]``
(:mod:`.section`): one of the paper's kinds (eq. 9 with its robust terms, the PD; each declared
beside its code, :class:`PaperKind`), a registered law (nnrobust/controllers/laws/) or a user's
class, each from the :class:`ControllerContext` it is handed. What the builders take beyond their
sections is chosen by the composition root (:func:`nnrobust.run.experiment.build`): the control
period, the nominal model and its friction, the trajectory, the criterion, the plant's limits.
"""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from ..core.exceptions import ConfigError
from ..model import DynamicsModel, PinocchioModel
from ..plant import Friction, Plant
from ..subtasks.base import Criterion
from ..trajectories import Trajectory
from .base import Controller, ControllerContext
from .basis import AdditiveRBFBasis, input_box
from .custom import build_custom
from .pseudoinverse import DampedPseudoInverse
from .registry import KindParts, controller_kinds, paper_kind, registered_law
from .section import ControllerConfig, NNConfig


def build_basis(nn: NNConfig, robot: PinocchioModel, m: int) -> AdditiveRBFBasis:
    """phi(s) over [q, q'] (joint limits, +-velocity_range) or [e, e'] (+-error_range)."""
    low, high = input_box(
        nn.basis_input, robot.lower_limits, robot.upper_limits, nn.velocity_range, nn.error_range, m
    )
    return AdditiveRBFBasis(low, high, nn.centers, nn.width, nn.bias)


def build_context(
    c: ControllerConfig,
    robot: PinocchioModel,
    nominal: DynamicsModel,
    trajectory: Trajectory,
    criterion: Criterion | None,
    plant: Plant,
    q0: np.ndarray,
    *,
    period: float,
    nominal_friction: tuple[np.ndarray, np.ndarray],
    trajectory_key: str,
) -> ControllerContext:
    """What a controller is built from (:class:`ControllerContext`): never the true plant's model,
    and nothing the plant or the record reads. The nominal model is the controller's own
    (:func:`nnrobust.model.nominal.build_nominal_model`), its friction F-hat (viscous, Coulomb:
    :func:`nnrobust.model.nominal.nominal_friction`) compensated with
    ``controller.coulomb_smoothing``; the trajectory and the criterion are copies, so that a law
    writing into them changes neither the recorded x_d, e and h nor the run (``trajectory_key``:
    the key an uncopyable trajectory is named by).
    """
    viscous, coulomb = nominal_friction
    return ControllerContext(
        nominal=nominal,
        trajectory=_own_copy(trajectory, trajectory_key),
        criterion=_own_copy(criterion, "subtasks.criterion_class"),
        period=period,
        torque_limits=None if plant.torque_limit is None else plant.torque_limit.copy(),
        q0=q0.copy(),
        lower_limits=robot.lower_limits.copy(),
        upper_limits=robot.upper_limits.copy(),
        nominal_friction=Friction(viscous, coulomb, c.coulomb_smoothing),
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
    c: ControllerConfig,
    nn: NNConfig,
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
    if c.kind == "custom":
        return build_custom(c.class_ or "", c.params, context)
    law = registered_law(c.kind)
    if law is not None:
        built = law.build(context, c.params)
        base = getattr(built, "base_kind", None)
        if base is not None:  # a law on another (a residual policy): that kind as this experiment builds it
            built.base = build_controller(
                dataclasses.replace(c, kind=base, params=None),
                nn,
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
    return kind.build(KindParts(c, nn, robot, nominal, trajectory, criterion, true_friction, context))
