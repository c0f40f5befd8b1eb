"""The model room's sections of an experiment file: ``[robot]`` (the true robot) and ``[nominal]``
(the controller's model M-hat, N-hat), with their keys, types and defaults. Their builders:
:func:`nnrobust.model.loading.load_robot` and :func:`nnrobust.model.nominal.build_nominal_model`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from ..core.exceptions import ConfigError
from ..core.key_checks import check_choice, require_physical, require_positive, require_seed
from ..core.numeric_limits import MAX_FACTOR
from .tasks import TASK_KINDS


@dataclass
class RobotConfig:
    """The true robot.

    Attributes:
        source: URDF path, ``three_link_planar`` (the paper's arm), ``planar<N>`` (generated
            N-link planar chain) or an example-robot-data name (``panda``, ``ur5``, ...).
        task_frame: frame whose position (or pose) is the task x (default: by the rule of
            docs/robots.md, a tool, end-effector or hand frame at the end of the longest chain).
        task: ``planar`` (m = 2), ``position`` (m = 3) or ``pose`` (m = 6).
        gravity: gravity vector [m/s^2] (default Pinocchio's (0, 0, -9.81)).
        locked_joints: joints held fixed at their neutral value (default: every joint off the
            default chain, and grippers, fingers and mimic joints; ``[]`` locks nothing).
        chain: ``[base frame, tip frame]``: the arm is the joints between them, every other
            joint is locked; the tip is the default task frame.
        mesh_folders: folders the viewer may also read visual meshes from, besides the URDF's
            folder and the one above it (relative paths from the experiment file's folder);
            the dynamics never read a mesh (docs/robots.md, "Meshes").

    """

    source: str = "three_link_planar"
    task_frame: str | None = None
    task: str = "planar"
    gravity: list[float] | None = None
    locked_joints: list[str] | None = None
    chain: list[str] | None = None
    mesh_folders: list[str] | None = None


@dataclass
class NominalConfig:
    """The controller's model M-hat, N-hat.

    Attributes:
        kind: ``closed-form`` (three-link closed form with beta and p below), ``urdf`` (the true
            robot's Pinocchio model, perfect unless perturbed by the fields below),
            ``identified`` (the robot's kinematics with the bodies, friction and armature of
            ``file``, an identified model ``nnrobust identify`` wrote; perturbed like urdf) or
            ``auto`` (the default: closed-form on the paper's arm, urdf on any other;
            :func:`nominal_kind`).
        file: ``identified``: the identified model's file (``nominal.json``; a relative path is
            read from the experiment file's folder).
        beta: beta-hat [kg m^2] (closed form; default the true robot's).
        p: p-hat [kg m^2] (closed form; default the true robot's).
        mass_scale: every body's mass times this (urdf).
        inertia_scale: every body's rotational inertia times this (urdf).
        relative_error: urdf: each body's mass and inertia also scaled by its own seeded random
            factor in [1 - relative_error, 1 + relative_error]; closed-form: each of the six
            beta-hat and p-hat entries scaled so (< 1).
        com_error: each centre of mass moved by a seeded random vector up to this long [m] (urdf).
        seed: seed of the random perturbation.
        factors: one multiplicative factor per perturbed inertial parameter, applied after the
            perturbations above, so that a model error has a direction a search can move along
            (docs/falsification.md): closed-form, 6 factors on (beta_1, beta_2, beta_3, p_1,
            p_2, p_3); urdf, 2 per body with mass, the masses first, then the rotational inertias.
            A single entry is set as ``nominal.factors[i]``; the others are then 1.
        viscous_friction: F_d-hat [N m s/rad] (default 0, or the identified model's).
        coulomb_friction: Coulomb friction in N-hat [N m] (default 0: Coulomb friction unmodelled;
            or the identified model's).

    """

    kind: str = "auto"
    file: str | None = None
    beta: list[float] | None = None
    p: list[float] | None = None
    mass_scale: float = 1.0
    inertia_scale: float = 1.0
    relative_error: float = 0.0
    com_error: float = 0.0
    seed: int = 0
    factors: list[float] | None = None
    viscous_friction: list[float] | None = None
    coulomb_friction: list[float] | None = None

    @property
    def perturbed(self) -> bool:
        """Whether any inertial perturbation of the URDF model is asked for."""
        scales = (self.mass_scale, self.inertia_scale, self.relative_error, self.com_error) != (1, 1, 0, 0)
        return scales or self.factors is not None


def resolved_nominal_kind(nc: NominalConfig, rc: RobotConfig) -> str:
    """``nominal.kind`` resolved: ``auto`` is the closed form on the paper's arm
    (``three_link_planar``, planar task), the URDF model on every other arm.
    """
    if nc.kind == "auto":
        paper = rc.source == "three_link_planar" and rc.task == "planar"
        return "closed-form" if paper else "urdf"
    return nc.kind


NOMINAL_KINDS = ("auto", "closed-form", "urdf", "identified")
"""The choices of ``nominal.kind``."""


def check_model(rc: RobotConfig, nc: NominalConfig) -> None:
    """The rules that read only ``[robot]`` and ``[nominal]`` (values a type alone does not
    constrain; the robot itself is checked when it is loaded). Changes nothing.
    """
    gravity = rc.gravity
    if gravity is not None and (len(gravity) != 3 or math.hypot(*gravity) > 1e3):
        raise ConfigError(
            "robot.gravity", f"needs 3 entries (x, y, z) [m/s^2] of at most 1000 m/s^2 in all, got {gravity}"
        )
    if rc.chain is not None and len(rc.chain) != 2:
        raise ConfigError("robot.chain", f"needs 2 frame names, [base, tip], got {rc.chain}")
    for folder in rc.mesh_folders or ():
        if not folder.strip() or os.path.abspath(folder) == os.path.abspath(os.sep):
            raise ConfigError(
                "robot.mesh_folders",
                f"{folder!r} is not a folder to read meshes from: name the folders that hold the "
                'URDF\'s meshes (e.g. ["../meshes"]), never the filesystem root',
            )
    check_choice("robot.task", rc.task, tuple(TASK_KINDS))
    check_choice("nominal.kind", nc.kind, NOMINAL_KINDS)
    if (nc.kind == "identified") != (nc.file is not None):
        raise ConfigError(
            "nominal.file" if nc.file is not None else "nominal.kind",
            "an identified model needs both kind = 'identified' and file = the model's nominal.json "
            "(nnrobust identify writes it)",
        )
    require_positive("nominal.mass_scale", nc.mass_scale)
    require_positive("nominal.inertia_scale", nc.inertia_scale)
    if not 0 <= nc.relative_error < 1:
        raise ConfigError(
            "nominal.relative_error", f"must be in [0, 1) so masses stay positive, got {nc.relative_error}"
        )
    if nc.com_error < 0:
        raise ConfigError("nominal.com_error", f"must be >= 0 [m], got {nc.com_error}")
    if nc.factors is not None and any(not 0 < f <= MAX_FACTOR for f in nc.factors):
        raise ConfigError("nominal.factors", f"each factor must be in (0, {MAX_FACTOR:g}], got {nc.factors}")
    closed_form = resolved_nominal_kind(nc, rc) == "closed-form"
    if closed_form and (nc.mass_scale, nc.inertia_scale, nc.com_error) != (1, 1, 0):
        raise ConfigError(
            "nominal.kind",
            "mass_scale, inertia_scale and com_error perturb the URDF "
            "model: set kind = 'urdf' (closed-form takes beta, p and relative_error)",
        )
    for key, values, unit in (
        ("viscous_friction", nc.viscous_friction, "N m s/rad"),
        ("coulomb_friction", nc.coulomb_friction, "N m"),
        ("beta", nc.beta, "kg m^2"),
        ("p", nc.p, "kg m^2"),
    ):
        require_physical(f"nominal.{key}", values, unit)
    require_seed("nominal.seed", nc.seed)


def inert_model_keys(rc: RobotConfig, nc: NominalConfig) -> dict[str, str]:
    """The ``[nominal]`` keys the resolved nominal model does not read, each with the reason."""
    kind = resolved_nominal_kind(nc, rc)
    if kind in ("urdf", "identified"):
        why = f"nominal.kind = '{kind}' (beta and p are the closed form's)"
        return {"nominal.beta": why, "nominal.p": why}
    return {}
