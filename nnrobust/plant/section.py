"""The plant room's sections of an experiment file: ``[plant]`` (friction, disturbance, actuators,
stops, loads, engine) and ``[sensing]`` (noise, quantisation, delay), with their keys, types and
defaults. Their builder: :func:`nnrobust.plant.build.build_plant`.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class PlantConfig:
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
    engine: str = "pinocchio"
    mujoco_integrator: str = "rk4"


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
