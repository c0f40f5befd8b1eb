"""How an experiment builds its plant from its own sections, ``[plant]`` and ``[sensing]``
(:mod:`.section`): the true robot (armature, payload), friction, disturbance (its declaration,
nnrobust/plant/disturbance.py), actuator limits, joint stops, sensors, delay, loads, and MuJoCo as
the engine when asked. What the builders take beyond their sections is chosen by the composition
root (:func:`nnrobust.run.experiment.build`): the control period, the duration and the disturbance
``auto`` resolves to.
"""

from __future__ import annotations

import functools
import warnings
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from ..core.arrays import joint_vector, padded, per_joint
from ..core.exceptions import ConfigError
from ..model import PinocchioModel
from ..model.ik import finite_limits
from ..model.region import read_region
from ..model.regressor import with_inertial_vector
from .custom import build_disturbance as build_custom_disturbance
from .disturbance import DISTURBANCE_KINDS, Disturbance, ScaledDisturbance, SinusoidalDisturbance
from .friction import Friction
from .limits import JointStops
from .loads import ExternalLoads, parse_loads
from .mujoco_engine import build_mujoco_plant
from .plant import Plant
from .scaling import limits_or_inf, scaled_friction, torque_scale, usable
from .section import PlantConfig, SensingConfig
from .sensing import Sensor


def build_torque_limits(pc: PlantConfig, robot: PinocchioModel) -> np.ndarray | None:
    """Effort limit per joint [N m or N] (inf where the URDF has none), or None (ideal actuators)."""
    limits = pc.torque_limits
    if limits == "none":
        return None
    if limits == "urdf":
        zero = [name for name, e in zip(robot.joint_names, robot.effort_limits) if e == 0]
        if zero:  # a limit of 0 would hold the joint still; URDFs write it for "none": said, not silent
            several = len(zero) > 1
            joints = f"joint{'s' if several else ''} {', '.join(map(repr, zero))}"
            warnings.warn(
                f"plant.torque_limits = 'urdf': {joints} of {robot.name} {'give' if several else 'gives'} "
                '<limit effort="0">, read as no effort limit (as a joint without one); give '
                f"plant.torque_limits to limit {'them' if several else 'it'}",
                stacklevel=2,
            )
        return limits_or_inf(robot.effort_limits)
    return joint_vector("plant.torque_limits", limits, robot.nq)


def build_speed_limits(pc: PlantConfig, robot: PinocchioModel) -> np.ndarray | None:
    """The velocity limits the torque-speed envelope falls to zero at (``plant.torque_speed =
    "urdf"``): the URDF's, inf where it has none [rad/s or m/s]; None without an envelope.
    """
    if pc.torque_speed == "none":
        return None
    speed = robot.velocity_limits
    if not np.any(usable(speed)):
        raise ConfigError(
            "plant.torque_speed",
            f"'urdf' needs the URDF's velocity limits, and {robot.name} gives none (<limit velocity>): "
            "set plant.torque_speed = 'none' or add them to the URDF",
        )
    return limits_or_inf(speed)


def build_stops(
    pc: PlantConfig, robot: PinocchioModel, tau_ref: Callable[[], np.ndarray] | None = None
) -> JointStops | None:
    """Hard stops at the URDF's position limits, stiffness relative to each joint's torque scale
    (``tau_ref()``, default :func:`torque_scale`).
    """
    if not pc.joint_stops:
        return None
    lower, upper = finite_limits(robot.lower_limits), finite_limits(robot.upper_limits)
    scale = torque_scale(robot) if tau_ref is None else tau_ref()
    return JointStops(lower, upper, pc.joint_stop_stiffness * scale, pc.joint_stop_damping)


def build_sensor(se: SensingConfig, n: int) -> Sensor:
    """Noise and quantisation of the measurements, one value for all joints or one per joint."""
    return Sensor(
        per_joint("sensing.position_noise", se.position_noise, n),
        per_joint("sensing.velocity_noise", se.velocity_noise, n),
        per_joint("sensing.encoder_resolution", se.encoder_resolution, n),
        se.seed,
    )


def build_plant(
    pc: PlantConfig,
    se: SensingConfig,
    robot: PinocchioModel,
    *,
    disturbance_kind: str,
    period: float,
    duration: float,
) -> Plant:
    """True model, friction (URDF or scaled to the robot, unless given), disturbance, actuator
    limits, joint stops, sensors and delay. ``disturbance_kind`` is ``plant.disturbance`` with
    ``auto`` resolved; ``period`` and ``duration`` place the loads of ``[[plant.loads]]`` on the
    control instants.
    """
    n = robot.nq
    tau_ref = functools.cache(lambda: torque_scale(robot))  # once (with its warning), if asked for
    identified = identified_plant(pc, robot)
    if identified is not None:
        base = identified[1]
    elif pc.friction == "scaled":
        base = scaled_friction(robot, pc.viscous_level, pc.coulomb_level, tau_ref())
    else:
        base = Friction(robot.viscous_friction, robot.coulomb_friction)
    scale = pc.friction_scale * _joint_scales("plant.joint_friction_scales", pc.joint_friction_scales, n)
    coulomb = scale * joint_vector("plant.coulomb_friction", pc.coulomb_friction, n, base.coulomb)
    friction = Friction(
        scale * joint_vector("plant.viscous_friction", pc.viscous_friction, n, base.viscous),
        coulomb,
        static=pc.stiction * coulomb,
    )
    disturbance: Disturbance
    if disturbance_kind == "custom":
        disturbance = build_custom_disturbance(pc.disturbance_class or "", pc.disturbance_params, robot)
    else:
        disturbance = DISTURBANCE_KINDS[disturbance_kind].build(pc, robot, tau_ref)
    rows = pc.disturbance_scale * _joint_scales(
        "plant.joint_disturbance_scales", pc.joint_disturbance_scales, n
    )
    if not isinstance(disturbance, SinusoidalDisturbance):
        for key, value, default in (
            ("disturbance_omega_scale", pc.disturbance_omega_scale, 1.0),
            ("disturbance_phase_shift", pc.disturbance_phase_shift, 0.0),
        ):
            if value != default:
                raise ConfigError(f"plant.{key}", "acts on sinusoids; a custom disturbance has none")
        if np.any(rows != 1.0):
            disturbance = ScaledDisturbance(disturbance, rows)
    elif np.any(rows != 1.0) or pc.disturbance_omega_scale != 1.0 or pc.disturbance_phase_shift != 0.0:
        disturbance = SinusoidalDisturbance(
            disturbance.amplitude * rows[:, None],
            disturbance.omega * pc.disturbance_omega_scale,
            disturbance.phase + pc.disturbance_phase_shift,
        )
    true = true_model(pc, robot if identified is None else identified[0])
    loads = parse_loads(pc.loads, period, n, duration)
    return Plant(
        true,
        friction,
        disturbance,
        build_torque_limits(pc, robot),
        build_stops(pc, robot, tau_ref),
        build_sensor(se, n),
        se.delay,
        loads=loads,
        payload_inertias=payload_inertias(true, loads),
        speed_limit=build_speed_limits(pc, robot),
        torque_speed_knee=pc.torque_speed_knee if pc.torque_speed != "none" else -1.0,
    )


def payload_inertias(true: PinocchioModel, loads: ExternalLoads) -> tuple[pin.Inertia, ...]:
    """The inertia of the joint that carries the task frame after each payload change of
    ``[[plant.loads]]`` (the sphere of ``plant.payload`` with that mass, added to the joint's own),
    and last its inertia before any change.
    """
    if not loads.payloads:
        return ()
    joint = true.model.frames[true.frame_id].parentJoint
    before = pin.Inertia(true.model.inertias[joint])
    after = [before + payload(true.model, true.task_frame, c.mass)[1] for c in loads.payloads]
    return (*after, before)


def _joint_scales(path: str, scales: list[float] | None, n: int) -> np.ndarray:
    """One factor per joint, the entries not given 1; more entries than joints are refused."""
    if scales is None:
        return np.ones(n)
    return np.array(padded(path, scales, n, f"has {len(scales)} entries; the robot has {n} joints"))


PAYLOAD_RADIUS = 0.02
"""[m] ``plant.payload`` is a solid sphere of this radius on the task frame's origin."""


def payload(model: pin.Model, task_frame: str, mass: float) -> tuple[int, pin.Inertia]:
    """``plant.payload``: the joint that carries it (the task frame's parent) and its inertia in
    that joint's frame, a solid sphere of PAYLOAD_RADIUS centred on the task frame's origin.
    """
    frame = model.frames[model.getFrameId(task_frame)]
    sphere = np.eye(3) * 0.4 * mass * PAYLOAD_RADIUS**2
    return frame.parentJoint, pin.Inertia(mass, frame.placement.translation, sphere)


def identified_plant(pc: PlantConfig, robot: PinocchioModel) -> tuple[PinocchioModel, Friction] | None:
    """The robot at the point ``plant.region_coordinates`` of the identified box ``plant.region``
    (its bodies and armature) and its friction, or None without a region
    (:mod:`nnrobust.model.region`).
    """
    if pc.region is None:
        return None
    region = read_region(pc.region)
    names = tuple(robot.model.names[1:])
    if names != region.joints:
        raise ConfigError(
            "plant.region",
            f"the box's joints {list(region.joints)} are not the robot's {list(names)}: identify it on the "
            "same robot (robot.source, locked_joints, chain)",
        )
    z = np.zeros(region.dimension)
    given = pc.region_coordinates or []
    if len(given) > region.dimension:
        raise ConfigError(
            "plant.region_coordinates",
            f"has {len(given)} entries; the box has {region.dimension} coordinates",
        )
    z[: len(given)] = given
    phi = region.parameters(z)
    model = with_inertial_vector(robot.model, phi)
    armature = region.armature(phi)
    if armature is not None:
        model.armature = armature
    problems = region.plant_problems(phi, model)
    if problems:
        raise ConfigError(
            "plant.region_coordinates",
            f"this point of the box is no plant: {'; '.join(problems)} (the box's coordinates "
            f"{np.round(z, 3).tolist()})",
        )
    true = PinocchioModel(model, robot.task_frame, robot.task, robot.name)
    true.urdf_text = robot.urdf_text
    return true, Friction(region.friction(phi, "viscous"), region.friction(phi, "coulomb"))


def true_model(pc: PlantConfig, robot: PinocchioModel) -> PinocchioModel:
    """The true robot's dynamics: the robot with ``plant.armature`` on the diagonal of M and
    ``plant.payload`` carried by the task frame's joint (a copy, also when a payload change of
    ``[[plant.loads]]`` will alter it; the nominal model knows neither).
    """
    changes = any(entry.get("kind") == "payload" for entry in pc.loads or ())
    if pc.armature is None and pc.payload == 0.0 and not changes:
        return robot
    model = pin.Model(robot.model)
    if pc.armature is not None:
        model.armature = joint_vector("plant.armature", pc.armature, robot.nq)
    if pc.payload > 0.0:
        joint, inertia = payload(model, robot.task_frame, pc.payload)
        model.inertias[joint] = model.inertias[joint] + inertia
    true = PinocchioModel(model, robot.task_frame, robot.task, robot.name)
    true.urdf_text = robot.urdf_text
    return true


def build_engine(pc: PlantConfig, plant: Plant, period: float, substeps: int) -> None:
    """Give the plant MuJoCo as its engine (``plant.engine = "mujoco"``), built and audited, its
    step the control ``period`` over ``substeps``.
    """
    if pc.engine != "mujoco":
        return

    true = plant.model
    assert isinstance(true, PinocchioModel)  # build_plant's true_model
    assert plant.loads is not None  # Plant sets an empty one
    if plant.loads.wrenches or plant.loads.payloads:
        kind = "wrench" if plant.loads.wrenches else "payload"
        raise ConfigError(
            "plant.loads",
            f"a {kind!r} load has no MuJoCo twin yet: use plant.engine = 'pinocchio' (step and impulse "
            "loads run on both engines)",
        )
    load = None
    if pc.payload > 0.0:  # on the body of the task frame's joint, where Pinocchio's true model has it
        joint, inertia = payload(true.model, true.task_frame, pc.payload)
        load = (true.model.names[joint], inertia)
    plant.engine = build_mujoco_plant(
        true,
        plant,
        period,
        substeps,
        pc.mujoco_integrator,
        true.model.armature,
        pc.stiction,
        load,
    )
