"""The experiment schema: its typed sections (the keys of an experiment file, their types and
defaults), the names a key may take, and what a configuration implies (its default criteria, its
nominal model, its controller's label). Reading and writing TOML is :mod:`.toml_io`; checking
values is :mod:`.checks`.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import typing
from dataclasses import dataclass, field

from ..controllers.registry import PAPER_KINDS, declared_default, paper_kinds
from ..simulation import MAX_STEP_ROTATION
from ..trajectories import PATH_KINDS


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
            robot's Pinocchio model, perfect unless perturbed by the fields below) or ``auto``
            (the default: closed-form on the paper's arm, urdf on any other; :func:`nominal_kind`).
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
        viscous_friction: F_d-hat [N m s/rad] (default 0).
        coulomb_friction: Coulomb friction in N-hat [N m] (default 0: Coulomb friction unmodelled).

    """

    kind: str = "auto"
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


@dataclass
class TrajectoryConfig:
    """The desired path x_d(t) [m], of one of three kinds, or a user's class.

    - ``ellipse`` (eq. 18): x_d(t) = center + axis_a cos(omega t + phase) + axis_b sin(omega t +
      phase); a zero axis_b gives the paper's line;
    - ``point_to_point``: from ``start`` to ``goal`` along a straight line in ``move_time``
      seconds, with the quintic time law (at rest at both ends), then held;
    - ``waypoints``: a cubic spline through ``waypoints`` at ``waypoint_times``, at rest at both
      ends, then held;
    - ``custom``: ``Class(robot, **params)`` of ``class`` (``"file.py:Class"`` or
      ``"package.module:Class"``), a :class:`nnrobust.Trajectory` (planar and position tasks;
      docs/extending.md).

    For a ``pose`` task the orientation is R_d(t) = exp(theta(t) u) R_0 with
    theta(t) = rotation_amplitude sin(rotation_omega t + rotation_phase) (held at R_0 when the
    amplitude is 0).

    Attributes:
        kind: ``ellipse``, ``point_to_point``, ``waypoints`` or ``custom``.
        class_: for ``custom``, the trajectory's class (TOML key ``class``).
        params: for ``custom``, the keyword arguments of its constructor (TOML table).
        center, axis_a, axis_b: the ellipse's centre and semi-axes (2 or 3 entries) [m].
        omega: angular frequency along the ellipse [rad/s].
        phase: phase at t = 0 [rad].
        start: where a point-to-point move starts (default: where the task frame is at
            ``simulation.q_seed``) [m].
        goal: where it ends [m].
        move_time: how long it takes [s].
        waypoints: the points a spline passes through, 2 or 3 entries each [m].
        waypoint_times: when it passes through each, strictly increasing from 0 [s].
        orientation_rpy: R_0 as roll, pitch, yaw [rad] (pose; default: the task frame's
            orientation at the position-only inverse-kinematics solution from q_seed).
        rotation_axis: u, world axes (pose).
        rotation_amplitude: rocking amplitude [rad] (pose).
        rotation_omega: rocking angular frequency [rad/s] (pose).
        rotation_phase: rocking phase at t = 0 [rad] (pose).

    """

    kind: str = "ellipse"
    center: list[float] = field(default_factory=lambda: [0.30, 0.40])
    axis_a: list[float] = field(default_factory=lambda: [0.20, 0.0])
    axis_b: list[float] = field(default_factory=lambda: [0.0, 0.10])
    omega: float = 1.0
    phase: float = 0.0
    start: list[float] | None = None
    goal: list[float] | None = None
    move_time: float = 2.0
    waypoints: list[list[float]] | None = None
    waypoint_times: list[float] | None = None
    orientation_rpy: list[float] | None = None
    rotation_axis: list[float] = field(default_factory=lambda: [0.0, 0.0, 1.0])
    rotation_amplitude: float = 0.0
    rotation_omega: float = 1.0
    rotation_phase: float = 0.0
    class_: str | None = None
    params: dict | None = None

    @property
    def dimension(self) -> int:
        """Entries of a path point: 2 (planar) or 3."""
        kind = PATH_KINDS.get(self.kind)
        return kind.dimension(self) if kind is not None else len(self.center)


TRAJECTORY_KINDS = (*PATH_KINDS, "custom")
"""The choices of ``trajectory.kind``: the shipped paths (their declarations) and a user's class."""

MAX_PATH_EXTENT = 1e3
"""Largest coordinate of a path point or axis [m] (an arm's workspace is metres)."""

MAX_PATH_RATE = 1e4
"""Largest angular frequency of a path or of its rocking [rad/s]."""


@dataclass
class ControllerConfig:
    """Which control law and its gains.

    Attributes:
        kind: ``nn`` (eq. 9 with the NN compensator), ``no-u0`` (eq. 9 with u_0 = 0),
            ``computed-torque`` (eq. 9 with u_0 = 0 and the true model and friction as nominal:
            what perfect model knowledge buys), ``sliding-mode`` (eq. 9 with a fixed-gain
            boundary-layer sliding-mode u_0) or ``pd``.
        Kp, Kv, k, coulomb_smoothing: eq. (9)'s gains [1/s^2, 1/s] (m entries or one for all;
            Kv^2 > Kp is required by eq. (17)), self-motion gain [1/s] and F-hat's sign smoothing
            [rad/s], as nnrobust/controllers/task_space.py declares them.
        pinv_threshold, pinv_max_damping: the damped pseudo-inverse's [m/rad], as
            nnrobust/controllers/pseudoinverse.py declares them.
        pd_Kp, pd_Kd, pd_null_damping: the PD baseline's, as ``pd`` declares them
            (nnrobust/controllers/task_space.py).
        sliding_gain, sliding_boundary: the sliding-mode u_0's, as ``sliding-mode`` declares them
            (nnrobust/controllers/sliding_mode.py). docs/controller.md's key reference lists every
            declared key with its unit, default and valid values.
        class_: for ``kind = "custom"``, the controller class (TOML key ``class``):
            ``"file.py:Class"`` (a path relative to the experiment file) or ``"package.module:Class"``,
            a subclass of :class:`nnrobust.Controller` (docs/extending.md).
        params: for ``kind = "custom"``, the keyword arguments of the class's constructor (TOML
            table ``[controller.params]``).

    """

    kind: str = "nn"
    Kp: list[float] = field(default_factory=lambda: declared_default("controller.Kp"))
    Kv: list[float] = field(default_factory=lambda: declared_default("controller.Kv"))
    k: float = declared_default("controller.k")
    pinv_threshold: float = declared_default("controller.pinv_threshold")
    pinv_max_damping: float = declared_default("controller.pinv_max_damping")
    pd_Kp: list[float] = field(default_factory=lambda: declared_default("controller.pd_Kp"))
    pd_Kd: list[float] = field(default_factory=lambda: declared_default("controller.pd_Kd"))
    pd_null_damping: float | None = declared_default("controller.pd_null_damping")
    coulomb_smoothing: float = declared_default("controller.coulomb_smoothing")
    sliding_gain: float = declared_default("controller.sliding_gain")
    sliding_boundary: float = declared_default("controller.sliding_boundary")
    class_: str | None = None
    params: dict | None = None


CONTROLLER_KINDS = paper_kinds()
"""The paper's kinds, the built-in values of ``controller.kind`` set by flat keys, as their modules
declare them (:class:`nnrobust.controllers.registry.PaperKind`), when nnrobust was imported; the
registered laws (:func:`controller_kinds`) take ``[controller.params]``, and ``custom`` names a
user's class (``controller.class``)."""


EQ9_KINDS = tuple(name for name, kind in PAPER_KINDS.items() if kind.eq9)
"""The kinds that are the task-space law of eq. (9), whose Kp and Kv eq. (17) constrains (when
nnrobust was imported; :func:`is_eq9` asks the declarations)."""


def is_eq9(kind: str) -> bool:
    """Whether ``controller.kind`` is one of the paper's kinds that is eq. (9)'s law."""
    declared = PAPER_KINDS.get(kind)
    return declared is not None and declared.eq9


KEY_ALIASES = {"class": "class_"}
"""TOML keys that are Python keywords, and the field each is stored in."""


@dataclass
class NNConfig:
    """The NN robust compensator, eqs. (15)-(17): its keys, their units, defaults and ranges as
    the ``nn`` kind declares them (nnrobust/controllers/nn_compensator.py; docs/controller.md's
    key reference).
    """

    law: str = declared_default("nn.law")
    F: float = declared_default("nn.F")
    gamma: float = declared_default("nn.gamma")
    eps0: float = declared_default("nn.eps0")
    eps_min: float = declared_default("nn.eps_min")
    sigma: float = declared_default("nn.sigma")
    basis_input: str = declared_default("nn.basis_input")
    centers: int = declared_default("nn.centers")
    width: float = declared_default("nn.width")
    bias: bool = declared_default("nn.bias")
    velocity_range: float = declared_default("nn.velocity_range")
    error_range: list[float] = field(default_factory=lambda: declared_default("nn.error_range"))


@dataclass
class SubtaskConfig:
    """Self-motion criteria h_i with weights w_i that sum to C, eq. (4).

    Attributes:
        criteria: names (``paper``, ``half_det_manipulability``, ``manipulability``,
            ``joint_limits``, ``joint_centering``, ``joint_smoothness``, ``obstacles``; see
            docs/controller.md), or ``custom`` (``Class(robot, **criterion_params)`` of
            ``criterion_class``, a :class:`nnrobust.Criterion`; docs/extending.md); empty for
            pure null-space damping; not given: the paper's on a three-joint planar arm, else
            manipulability and joint_limits (:func:`default_criteria`).
        weights: w_i, positive and summing to C (default: C / number of criteria each).
        C: the constant of eq. (4).
        smoothness_coefficients: c of ``joint_smoothness`` (default the paper's (0.5, -1, 1)).
        obstacles: spheres [x, y, z, radius] [m] for ``obstacles``.
        obstacle_influence: distance d_0 within which an obstacle repels a link [m].
        link_radius: thickness of the links for ``obstacles`` [m].
        criterion_class: for ``custom``, the criterion's class (``"file.py:Class"`` or
            ``"package.module:Class"``).
        criterion_params: for ``custom``, the keyword arguments of its constructor.

    """

    criteria: list[str] | None = None
    weights: list[float] | None = None
    C: float = 1.0
    smoothness_coefficients: list[float] | None = None
    obstacles: list[list[float]] = field(default_factory=list)
    obstacle_influence: float = 0.1
    link_radius: float = 0.0
    criterion_class: str | None = None
    criterion_params: dict | None = None


@dataclass
class SimulationConfig:
    """Time, integration and initial state.

    Attributes:
        duration: simulated time [s].
        control_period: zero-order-hold period T [s].
        substeps: integration steps per control period; unset, the fewest that keep the plant
            stable, after the joint stops are sized to the step (experiment.plant_step; one
            step where nothing needs more, said in a warning where something does).
        integration_step: the RK4 step [s]; when given it sets substeps = control_period /
            integration_step, which must be a whole number (a step never spans two periods).
        integrator: ``rk4`` or ``solve_ivp``.
        max_step_rotation: the most the fastest joint may turn in one RK4 step [rad or m], at its
            speed at the start of a control period; a faster period is cut into more steps (both
            loops; docs/plant.md#speed-adaptive-step). MuJoCo (plant.engine) keeps its own
            fixed step.
        adaptive_step: whether max_step_rotation applies (false: T / substeps throughout).
        backend: ``auto`` (the compiled loop when every component of the experiment has a
            compiled twin; the hybrid loop for a custom controller; else the Python loop),
            ``compiled``, ``hybrid`` (the compiled plant calling the Python controller once per
            control period) or ``python`` (docs/compiled.md).
        q_seed: inverse-kinematics seed for q(0) [rad] (default: mid-range of the joint limits).
        initial_task_offset: x(0) - x_d(0), m entries [m] (pose: position [m], then a rotation
            vector [rad] applied in world axes); default zero: start on the path.
        memory_limit: the most memory the run may take [GB], its recorded arrays and its
            Pinocchio models (which grow as n^3); a run estimated above it, or above what the
            machine has available, is refused before it starts (docs/bad-inputs.md).

    """

    duration: float = 20.0
    control_period: float = 1e-3
    substeps: int | None = None
    integration_step: float | None = None
    integrator: str = "rk4"
    max_step_rotation: float = MAX_STEP_ROTATION
    adaptive_step: bool = True
    backend: str = "auto"
    q_seed: list[float] | None = None
    initial_task_offset: list[float] | None = None
    memory_limit: float = 2.0

    @property
    def requested_substeps(self) -> int | None:
        """Plant steps per control period as given: ``substeps``, or ``control_period /
        integration_step`` (a whole number, :func:`validate`), or None (chosen by the run).
        """
        if self.substeps is not None:
            return self.substeps
        if self.integration_step is not None:
            return int(round(self.control_period / self.integration_step))
        return None


@dataclass
class ExperimentConfig:
    """A complete, reproducible experiment."""

    name: str = "experiment"
    description: str = ""
    robot: RobotConfig = field(default_factory=RobotConfig)
    nominal: NominalConfig = field(default_factory=NominalConfig)
    plant: PlantConfig = field(default_factory=PlantConfig)
    sensing: SensingConfig = field(default_factory=SensingConfig)
    trajectory: TrajectoryConfig = field(default_factory=TrajectoryConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    nn: NNConfig = field(default_factory=NNConfig)
    subtasks: SubtaskConfig = field(default_factory=SubtaskConfig)
    simulation: SimulationConfig = field(default_factory=SimulationConfig)

    def to_dict(self) -> dict:
        """Nested plain dict (None values dropped), with the TOML spelling of every key.

        Field by field rather than ``dataclasses.asdict`` (a third of a sweep sample's checks).
        """
        spelled = {v: k for k, v in KEY_ALIASES.items()}
        out: dict = {}
        for name in _field_names(type(self)):
            value = getattr(self, name)
            if dataclasses.is_dataclass(value):
                out[name] = {
                    spelled.get(k, k): _drop_none(copy.deepcopy(v)) if isinstance(v, (list, dict)) else v
                    for k in _field_names(type(value))
                    if (v := getattr(value, k)) is not None
                }
            elif value is not None:
                out[name] = value
        return out

    def to_toml(self) -> str:
        """TOML text that :func:`load_config` reads back to an equal configuration."""
        from .toml_io import dump_toml

        return dump_toml(self.to_dict())

    def replace(self, **sections) -> ExperimentConfig:
        """A copy with some fields changed: ``replace(controller={"kind": "pd"})``."""
        data = self.to_dict()
        for key, value in sections.items():
            if isinstance(value, dict):
                data.setdefault(key, {}).update(value)
            else:
                data[key] = value
        from .toml_io import from_dict

        return from_dict(data)


# ---- helpers of the sections' own methods -------------------------------------------------


def _drop_none(obj):
    if isinstance(obj, dict):
        return {k: _drop_none(v) for k, v in obj.items() if v is not None}
    return obj


USER_PARTS = {
    "controller": ("controller", "class", "params", "kind"),
    "trajectory": ("trajectory", "class", "params", "kind"),
    "disturbance": ("plant", "disturbance_class", "disturbance_params", "disturbance"),
    "criterion": ("subtasks", "criterion_class", "criterion_params", "criteria"),
}
"""The parts an experiment may take from a user's class: part -> (section, TOML key of the class,
of its params, and of the choice that names it: ``"custom"``, or ``"custom"`` in a list)."""


def _user_part(config: ExperimentConfig, part: str) -> tuple[str | None, dict | None, bool, object]:
    """(class, params, chosen, the choice's value) of one of :data:`USER_PARTS` in a configuration."""
    section, class_key, params_key, choice = USER_PARTS[part]
    table = getattr(config, section)
    now = getattr(table, choice)
    if choice == "criteria":
        now = now or []
    chosen = "custom" in now if isinstance(now, list) else now == "custom"
    return getattr(table, KEY_ALIASES.get(class_key, class_key)), getattr(table, params_key), chosen, now


def controller_label(config: ExperimentConfig) -> str:
    """The controller as runs and folders name it: its kind, or a custom law's class name."""
    if config.controller.kind == "custom" and config.controller.class_:
        return config.controller.class_.rpartition(":")[2]
    return config.controller.kind


def step_rotation_limit(config: ExperimentConfig) -> float:
    """simulation.max_step_rotation where the speed-adaptive step applies (RK4 on Pinocchio's
    plant with simulation.adaptive_step), else inf: the step stays T / substeps.
    """
    sim = config.simulation
    adaptive = sim.adaptive_step and sim.integrator == "rk4" and config.plant.engine != "mujoco"
    return sim.max_step_rotation if adaptive else math.inf


def nominal_kind(config: ExperimentConfig) -> str:
    """``nominal.kind`` resolved: ``auto`` is the closed form on the paper's arm
    (``three_link_planar``, planar task), the URDF model on every other arm.
    """
    kind = config.nominal.kind
    if kind == "auto":
        paper = config.robot.source == "three_link_planar" and config.robot.task == "planar"
        return "closed-form" if paper else "urdf"
    return kind


def task_rows(config: ExperimentConfig) -> int:
    """m, the task coordinates a configuration implies: 6 on a pose task, else the entries of its
    path's points (a custom trajectory: the task's, 2 planar or 3 position).
    """
    from ..model.tasks import TASK_KINDS

    if config.robot.task == "pose":
        return 6
    if config.trajectory.kind == "custom":
        return TASK_KINDS.get(config.robot.task, 2)
    return config.trajectory.dimension


_FIELD_NAMES: dict[typing.Any, list[str]] = {}


def _field_names(cls: typing.Any) -> list[str]:
    """A config dataclass's field names, listed once per class."""
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = [f.name for f in dataclasses.fields(cls)]
    return names
