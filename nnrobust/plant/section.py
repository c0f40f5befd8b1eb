"""The plant room's sections of an experiment file: ``[plant]`` (friction, disturbance, actuators,
stops, loads, engine) and ``[sensing]`` (noise, quantisation, delay), with their keys, types and
defaults. Their builder: :func:`nnrobust.plant.build.build_plant`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from ..core.exceptions import ConfigError
from ..core.key_checks import (
    DeclaredKeys,
    check_choice,
    require_non_negative,
    require_physical,
    require_positive,
    require_seed,
)
from ..core.numeric_limits import MAX_FACTOR, MAX_PAYLOAD, MAX_PHYSICAL, MAX_STOP_STIFFNESS
from .disturbance import DISTURBANCE_KINDS
from .mujoco_engine import ENGINES, MUJOCO_INTEGRATORS


@dataclass
class PlantConfig(DeclaredKeys):
    """Friction and disturbance of the true robot.

    Attributes:
        friction: ``urdf`` (the URDF's <dynamics damping, friction>) or ``scaled`` (levels below
            relative to each joint's torque scale, docs/robots.md).
        viscous_level: ``scaled``: viscous torque at the joint's top speed / torque scale.
        coulomb_level: ``scaled``: Coulomb friction / torque scale.
        viscous_friction: F_d [N m s/rad]; overrides the ``friction`` choice when given.
        coulomb_friction: [N m]; overrides the ``friction`` choice when given.
        disturbance: ``paper`` (tau_d of Sect. 4), ``none``, ``scaled`` (two harmonics of peak
            disturbance_level x torque scale per joint), ``sinusoid`` (the fields below),
            ``custom`` (``Class(robot, **disturbance_params)`` of ``disturbance_class``, a
            :class:`nnrobust.Disturbance`; docs/extending.md) or
            ``auto`` (the default: ``paper`` on the paper's arm, ``three_link_planar``, else
            ``scaled``).
        disturbance_level: ``scaled``: peak disturbance / torque scale.
        disturbance_amplitude: n x K amplitudes [N m] (``sinusoid``).
        disturbance_omega: K angular frequencies [rad/s] (``sinusoid``).
        disturbance_phase: n x K phases [rad] (``sinusoid``; default 0).
        disturbance_class: for ``custom``, the class (``"file.py:Class"`` or
            ``"package.module:Class"``).
        disturbance_params: for ``custom``, the keyword arguments of its constructor.
        disturbance_scale: factor applied to the disturbance.
        friction_scale: factor applied to the plant's viscous and Coulomb friction (after the
            choice above; the controller's nominal friction is not scaled).
        joint_friction_scales: one more factor per joint on the plant's friction (after
            friction_scale); entries not given are 1, so one can be set or searched alone as
            ``plant.joint_friction_scales[i]`` (docs/falsification.md).
        joint_disturbance_scales: one factor per joint on its disturbance torque (after
            disturbance_scale), set like joint_friction_scales.
        disturbance_omega_scale: factor on every angular frequency of the disturbance.
        disturbance_phase_shift: added to every phase of the disturbance [rad].
        stiction: static friction level F_s / Coulomb level F_c (>= 1; 1: the plain Coulomb
            law): a joint at rest stays held until it needs more than F_s (docs/plant.md).
        torque_limits: ``urdf`` (the URDF's effort limits; joints without one are unlimited),
            ``none`` (ideal actuators) or one value per joint [N m or N]; the commanded torque
            is clipped to +-limit.
        torque_speed: the actuators' torque-speed envelope: ``none`` (the default: the effort
            limit at every speed) or ``urdf`` (the effort limit up to ``torque_speed_knee`` times
            the URDF's velocity limit, falling linearly to zero at the limit while the torque
            drives the joint; docs/plant.md#torque-speed-envelope).
        torque_speed_knee: ``urdf`` envelope: the fraction of the velocity limit below which the
            full effort is available, in [0, 1).
        joint_stops: hard stops at the URDF's position limits (docs/plant.md).
        joint_stop_stiffness: stop stiffness / the joint's torque scale [1/rad]: the stop
            pushes back with the joint's full effort at 1/joint_stop_stiffness beyond the limit.
        joint_stop_damping: Hunt-Crossley damping alpha of the stops [s/rad].
        payload: a load at the task frame [kg], a solid sphere of 2 cm radius centred on the
            frame's origin, carried by the true plant only (the controller's nominal model does
            not know it), on either engine; searchable like any key (docs/falsification.md).
        loads: external loads that switch at control instants (``[[plant.loads]]``, one table
            each; docs/plant.md): ``kind = "step"`` (``torque``: one value per joint [N m], from
            ``time`` [s] for ``duration`` [s], default to the end), ``"impulse"`` (``impulse``
            per joint [N m s] spread over ``duration``, default one control period),
            ``"wrench"`` (``force`` [N] and ``moment`` [N m] in world axes at the task frame,
            from ``time`` for ``duration``) or ``"payload"`` (from ``time`` on the task frame
            carries ``mass`` [kg] beside ``payload``; the nominal model does not know it).
            Times and durations are whole numbers of control periods.
        armature: rotor inertia added to the diagonal of M, one value for all joints or one per
            joint [kg m^2 or kg] (none: 0); the true plant's alone, on either engine (a
            nominal model from the URDF does not know it).
        region: an identified robot's box (``region.json``, which ``nnrobust identify`` writes
            beside ``box.toml``; a relative path is read from the experiment file's folder): the
            true plant's bodies, viscous and Coulomb friction (and armature, where identified)
            are those of the point ``region_coordinates`` of the box (docs/identification.md,
            "The box"), in place of the URDF's.
        region_coordinates: the point z of ``region``'s box, one coordinate per fitted parameter
            (entries not given are 0, the estimate); set or searched alone as
            ``plant.region_coordinates[i]``, as box.toml's ``[vary]`` does.
        engine: the true plant's physics: ``pinocchio`` (this package's plant, docs/plant.md) or
            ``mujoco`` (MuJoCo built from the same URDF and audited against Pinocchio;
            docs/engines.md; needs ``pip install 'nnrobust[mujoco]'``).
        mujoco_integrator: MuJoCo's integrator: ``rk4`` (the default: fourth order, converged at
            the plant step as this package's RK4 is), ``implicitfast`` (MuJoCo's own advice,
            damping implicit), ``euler`` or ``implicit`` (first order: at a 1 ms step they break
            laws tuned to the sampling limit; docs/engines.md).

    """

    friction: str = "urdf"
    viscous_level: float = 0.02
    coulomb_level: float = 0.01
    viscous_friction: list[float] | None = None
    coulomb_friction: list[float] | None = None
    disturbance: str = "auto"
    disturbance_level: float = 0.02
    disturbance_amplitude: list[list[float]] | None = None
    disturbance_omega: list[float] | None = None
    disturbance_phase: list[list[float]] | None = None
    disturbance_class: str | None = None
    disturbance_params: dict | None = None
    disturbance_scale: float = 1.0
    friction_scale: float = 1.0
    joint_friction_scales: list[float] | None = None
    joint_disturbance_scales: list[float] | None = None
    disturbance_omega_scale: float = 1.0
    disturbance_phase_shift: float = 0.0
    stiction: float = 1.0
    torque_limits: str | list[float] = "urdf"
    torque_speed: str = "none"
    torque_speed_knee: float = 0.5
    joint_stops: bool = True
    joint_stop_stiffness: float = 100.0
    joint_stop_damping: float = 1.0
    armature: list[float] | None = None
    payload: float = 0.0
    loads: list[dict] | None = None
    region: str | None = None
    region_coordinates: list[float] | None = None
    engine: str = "pinocchio"
    mujoco_integrator: str = "rk4"
    SECTION: ClassVar[str] = "plant"

    @classmethod
    def kind_params(cls):
        """The keys the disturbances declare."""
        return (p for kind in DISTURBANCE_KINDS.values() for p in kind.params)


@dataclass
class SensingConfig:
    """What the controller measures, and when its torque arrives (docs/plant.md).

    Attributes:
        position_noise: standard deviation of the Gaussian noise on q, one value for all joints
            or one per joint [rad or m].
        velocity_noise: standard deviation of the noise on q' [rad/s or m/s] (one or n values).
        encoder_resolution: q is rounded to multiples of this (one encoder count) [rad or m]
            (one or n values; 0 = continuous).
        delay: control periods between a measurement and the torque computed from it.
        seed: seed of the noise.

    """

    position_noise: list[float] = field(default_factory=lambda: [0.0])
    velocity_noise: list[float] = field(default_factory=lambda: [0.0])
    encoder_resolution: list[float] = field(default_factory=lambda: [0.0])
    delay: int = 0
    seed: int = 0


def check_plant(pc: PlantConfig, se: SensingConfig) -> None:
    """The rules that read only ``[plant]`` and ``[sensing]`` (values a type alone does not
    constrain). Changes nothing.
    """
    check_choice("plant.friction", pc.friction, ("urdf", "scaled"))
    check_choice("plant.disturbance", pc.disturbance, ("auto", *sorted(DISTURBANCE_KINDS), "custom"))
    check_choice("plant.engine", pc.engine, ENGINES)
    check_choice("plant.mujoco_integrator", pc.mujoco_integrator, MUJOCO_INTEGRATORS)
    check_choice("plant.torque_speed", pc.torque_speed, ("none", "urdf"))
    for key in ("disturbance_scale", "friction_scale"):
        if not 0 <= getattr(pc, key) <= MAX_FACTOR:
            raise ConfigError(f"plant.{key}", f"must be in [0, {MAX_FACTOR:g}], got {getattr(pc, key):g}")
    require_physical("plant.viscous_friction", pc.viscous_friction, "N m s/rad")
    require_physical("plant.coulomb_friction", pc.coulomb_friction, "N m")
    for key in ("joint_friction_scales", "joint_disturbance_scales"):
        scales = getattr(pc, key)
        if scales is not None and any(not 0 <= f <= MAX_FACTOR for f in scales):
            raise ConfigError(f"plant.{key}", f"each factor must be in [0, {MAX_FACTOR:g}], got {scales}")
    if not 0 <= pc.payload <= MAX_PAYLOAD:
        raise ConfigError("plant.payload", f"must be in [0, {MAX_PAYLOAD:g}] kg, got {pc.payload:g}")
    if not 0 < pc.disturbance_omega_scale <= MAX_FACTOR:
        raise ConfigError(
            "plant.disturbance_omega_scale",
            f"must be in (0, {MAX_FACTOR:g}], got {pc.disturbance_omega_scale:g}",
        )
    if abs(pc.disturbance_phase_shift) > 1e3:
        raise ConfigError(
            "plant.disturbance_phase_shift",
            f"{pc.disturbance_phase_shift:g} rad; give it within +-1000 rad (it acts modulo 2 pi)",
        )
    if not 1 <= pc.stiction < 1e6:
        raise ConfigError(
            "plant.stiction", f"the static / Coulomb friction ratio must be in [1, 1e6), got {pc.stiction}"
        )
    _check_region(pc)
    if isinstance(pc.torque_limits, str):
        if pc.torque_limits not in ("urdf", "none"):
            raise ConfigError(
                "plant.torque_limits",
                f"{pc.torque_limits!r} is not one of urdf, none (or give one limit per joint [N m])",
            )
    else:
        require_positive("plant.torque_limits", pc.torque_limits)
    if pc.torque_speed == "urdf" and pc.torque_limits == "none":
        raise ConfigError(
            "plant.torque_speed",
            "'urdf' cuts the effort limits at speed, and plant.torque_limits = 'none' sets none: "
            "set plant.torque_limits (urdf, or one limit per joint)",
        )
    if not 0.0 <= pc.torque_speed_knee < 1.0:
        raise ConfigError(
            "plant.torque_speed_knee",
            f"{pc.torque_speed_knee:g} is outside [0, 1) (a fraction of the velocity limit)",
        )
    if not 0 < pc.joint_stop_stiffness <= MAX_STOP_STIFFNESS:
        raise ConfigError(
            "plant.joint_stop_stiffness",
            f"must be in (0, {MAX_STOP_STIFFNESS:g}] (the stop's stiffness / the joint's torque scale, "
            f"per rad), got {pc.joint_stop_stiffness:g}",
        )
    if not 0 <= pc.joint_stop_damping <= MAX_PHYSICAL:
        raise ConfigError(
            "plant.joint_stop_damping",
            f"must be in [0, {MAX_PHYSICAL:g}] s/rad, got {pc.joint_stop_damping:g}",
        )
    if pc.armature is not None and (not pc.armature or any(not 0 <= a < 1e6 for a in pc.armature)):
        raise ConfigError(
            "plant.armature",
            f"needs one value for all joints or one per joint, each in "
            f"[0, 1e6) [kg m^2 or kg], got {pc.armature}",
        )
    for path, values in (
        ("sensing.position_noise", se.position_noise),
        ("sensing.velocity_noise", se.velocity_noise),
        ("sensing.encoder_resolution", se.encoder_resolution),
    ):
        if not values or any(v < 0 for v in values):
            raise ConfigError(
                path, f"needs one value for all joints or one per joint, each >= 0, got {values}"
            )
    require_seed("sensing.seed", se.seed)
    if se.delay < 0:
        raise ConfigError("sensing.delay", f"must be >= 0 control periods, got {se.delay}")
    for key in ("viscous_level", "coulomb_level", "disturbance_level"):
        require_non_negative(f"plant.{key}", getattr(pc, key))
    pc.check_declared(1)  # a disturbance's own keys
    if pc.disturbance == "sinusoid" and (pc.disturbance_amplitude is None or pc.disturbance_omega is None):
        raise ConfigError(
            "plant.disturbance_amplitude",
            "disturbance = 'sinusoid' needs disturbance_amplitude (n x K) and disturbance_omega (K)",
        )


def inert_plant_keys(pc: PlantConfig) -> dict[str, str]:
    """The ``[plant]`` keys its own choices leave unread (friction levels of a URDF friction, the
    other disturbances' keys, MuJoCo's integrator on Pinocchio, ...), each with the choice.
    """
    inert: dict[str, str] = {}

    def mark(keys, why):
        for key in keys:
            inert.setdefault(key, why)

    if pc.friction != "scaled":
        mark(["plant.viscous_level", "plant.coulomb_level"], f"plant.friction = {pc.friction!r}")
    if pc.disturbance == "none":
        mark(
            ["plant.disturbance_scale", "plant.joint_disturbance_scales", "plant.disturbance_omega_scale",
             "plant.disturbance_phase_shift", "plant.disturbance_level"],
            "plant.disturbance = 'none'",
        )  # fmt: skip
    if pc.disturbance not in ("scaled", "auto"):
        mark(["plant.disturbance_level"], f"plant.disturbance = {pc.disturbance!r}")
    if pc.disturbance != "sinusoid":
        mark(["plant.disturbance_amplitude", "plant.disturbance_omega", "plant.disturbance_phase"],
             f"plant.disturbance = {pc.disturbance!r}")  # fmt: skip
    if pc.engine != "mujoco":
        mark(["plant.mujoco_integrator"], f"plant.engine = {pc.engine!r}")
    if pc.torque_speed == "none":
        mark(["plant.torque_speed_knee"], "plant.torque_speed = 'none'")
    if not pc.joint_stops:
        mark(["plant.joint_stop_stiffness", "plant.joint_stop_damping"], "plant.joint_stops = false")
    for name, kind in DISTURBANCE_KINDS.items():  # the keys a disturbance declares, under another
        if name != pc.disturbance:
            mark([p.name for p in kind.params], f"plant.disturbance = {pc.disturbance!r}")
    return inert


def _check_region(pc: PlantConfig) -> None:
    """An identified box's plant: its friction and armature are the box's, so no key replaces them."""
    if pc.region is None:
        if pc.region_coordinates is not None:
            raise ConfigError(
                "plant.region_coordinates", "are a point of plant.region's box: give plant.region too"
            )
        return
    if pc.engine != "pinocchio":
        raise ConfigError(
            "plant.engine",
            f"{pc.engine!r}: an identified box's plant (plant.region) runs on 'pinocchio' only",
        )
    if pc.friction != "urdf":
        raise ConfigError(
            "plant.friction",
            f"{pc.friction!r}: with plant.region the plant's friction is the identified box's; "
            "leave it 'urdf'",
        )
    for key in ("viscous_friction", "coulomb_friction", "armature"):
        if getattr(pc, key) is not None:
            raise ConfigError(
                f"plant.{key}", "would replace the identified box's (plant.region): give one or the other"
            )
    if pc.region_coordinates is not None and not all(
        isinstance(z, (int, float)) and abs(z) < 1e6 for z in pc.region_coordinates
    ):
        raise ConfigError("plant.region_coordinates", f"must be finite numbers, got {pc.region_coordinates}")
