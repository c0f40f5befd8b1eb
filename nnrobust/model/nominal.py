"""The controller's nominal model built from the ``[nominal]`` section: the paper's closed form
with beta-hat and p-hat, or the robot's own Pinocchio model (perturbed, or scaled by
``nominal.factors``), or the true model for computed-torque control. The builder takes its own
section and what the composition root (:func:`nnrobust.run.experiment.build`) decides: the resolved
kind and, for computed torque, the true model.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ..core.arrays import joint_vector, padded
from ..core.exceptions import ConfigError
from .base import DynamicsModel
from .identified import read_identified
from .loading import load_robot
from .perturbation import bodies_with_mass, perturb_inertias
from .pinocchio_model import PinocchioModel
from .section import NominalConfig, RobotConfig
from .three_link import ThreeLinkParameters, ThreeLinkPlanarModel


def build_nominal_model(
    nc: NominalConfig, robot: PinocchioModel, kind: str, exact: pin.Model | None = None
) -> DynamicsModel:
    """The controller's model from ``[nominal]`` (``nc``) of ``kind`` (``nominal.kind`` resolved:
    ``closed-form``, ``urdf`` or ``identified``): closed form with beta-hat, p-hat, the robot's own
    or its identified model (perturbed if asked); a copy of ``exact``, the true model, when given
    (computed-torque control). Always a ``pin.Model`` of its own, never the true plant's: a law
    that adapts its model in place changes only its own.
    """
    if exact is not None:  # the true model, armature included
        return PinocchioModel(pin.Model(exact), robot.task_frame, robot.task, robot.name)
    if kind in ("urdf", "identified"):
        own = (
            robot.model
            if kind == "urdf"
            else read_identified(str(nc.file)).pinocchio(robot.model, robot.name)
        )
        if nc.perturbed:
            model = perturb_inertias(
                own, nc.mass_scale, nc.inertia_scale, nc.relative_error, nc.com_error, nc.seed
            )
            if nc.factors is not None:
                model = _with_factors(model, nc.factors)
        else:
            model = pin.Model(own)  # a copy: the plant's stays out of the controller's reach
        return PinocchioModel(model, robot.task_frame, robot.task, robot.name)
    if robot.task != "planar":
        raise ConfigError("nominal.kind", "'closed-form' is the planar three-link model; use 'urdf'")
    true = ThreeLinkParameters.from_pinocchio(robot.model, robot.task_frame)
    beta = true.beta if nc.beta is None else tuple(joint_vector("nominal.beta", nc.beta, 3))
    p = true.p if nc.p is None else tuple(joint_vector("nominal.p", nc.p, 3))
    if nc.relative_error:
        drawn = 1 + np.random.default_rng(nc.seed).uniform(
            -nc.relative_error, nc.relative_error, CLOSED_FORM_FACTORS
        )
        beta, p = tuple(np.multiply(beta, drawn[:3])), tuple(np.multiply(p, drawn[3:]))
    if nc.factors is not None:
        given = padded(
            "nominal.factors",
            nc.factors,
            CLOSED_FORM_FACTORS,
            f"the closed-form model has {CLOSED_FORM_FACTORS} parameters (beta_1..3, p_1..3); got "
            f"{len(nc.factors)} factors",
        )
        beta, p = tuple(np.multiply(beta, given[:3])), tuple(np.multiply(p, given[3:]))
    return ThreeLinkPlanarModel(
        ThreeLinkParameters(beta, p, true.lengths, true.gamma, true.gravity),
        joint_names=robot.joint_names,
    )


def nominal_friction(nc: NominalConfig, n: int) -> tuple[np.ndarray, np.ndarray]:
    """F-hat's viscous [N m s/rad] and Coulomb [N m] coefficients per joint, as ``[nominal]``
    gives them (where not given: the identified model's, or zero: friction unmodelled).
    """
    if nc.kind == "identified" and nc.file is not None:
        identified = read_identified(nc.file)
        viscous, coulomb = identified.viscous, identified.coulomb
    else:
        viscous = coulomb = np.zeros(n)
    return (
        joint_vector("nominal.viscous_friction", nc.viscous_friction, n, viscous),
        joint_vector("nominal.coulomb_friction", nc.coulomb_friction, n, coulomb),
    )


CLOSED_FORM_FACTORS = 6
"""Entries of ``nominal.factors`` on the closed-form model: beta-hat_1..3, p-hat_1..3."""


def nominal_factor_count(kind: str, rc: RobotConfig) -> int:
    """The entries of ``nominal.factors`` for a nominal model of ``kind`` (``nominal.kind``
    resolved) of the ``[robot]`` section ``rc``: the closed form's beta-hat and p-hat, or two per
    body with mass of the robot's model (masses, then inertias), which ``nominal.relative_error``
    draws its factors for.
    """
    if kind not in ("urdf", "identified"):
        return CLOSED_FORM_FACTORS
    model = load_robot(rc.source, rc.task_frame, rc.task, None, rc.locked_joints, rc.chain).model
    return 2 * len(bodies_with_mass(model))


def _with_factors(model: pin.Model, factors: list[float]) -> pin.Model:
    """The model with each body's mass and rotational inertia (about its centre of mass) times its
    factor of ``nominal.factors``: the masses first, then the inertias, bodies with mass in order.
    """
    bodies = bodies_with_mass(model)
    factors = padded(
        "nominal.factors",
        factors,
        2 * len(bodies),
        f"the URDF model has {len(bodies)} bodies with mass: {2 * len(bodies)} factors, masses then "
        f"inertias; got {len(factors)} factors",
    )
    out = pin.Model(model)
    for i, j in enumerate(bodies):
        body = model.inertias[j]
        out.inertias[j] = pin.Inertia(
            body.mass * factors[i],
            np.asarray(body.lever),
            np.asarray(body.inertia) * factors[len(bodies) + i],
        )
    return out
