"""Experiment configuration: typed sections, validation with clear messages, TOML round trip."""

from __future__ import annotations

import copy
import dataclasses
import difflib
import functools
import math
import os
import re
import tomllib
import types
import typing
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from .controllers.nn_compensator import DEFAULTS as NN_DEFAULTS
from .exceptions import ConfigError
from .model.tasks import TASK_KINDS
from .plant.mujoco_engine import ENGINES, MUJOCO_INTEGRATORS
from .simulation import MAX_STEP_ROTATION


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

    """

    source: str = "three_link_planar"
    task_frame: str | None = None
    task: str = "planar"
    gravity: list[float] | None = None
    locked_joints: list[str] | None = None
    chain: list[str] | None = None


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
        if self.kind == "point_to_point" and self.goal is not None:
            return len(self.goal)
        if self.kind == "waypoints" and self.waypoints:
            return len(self.waypoints[0])
        return len(self.center)


TRAJECTORY_KINDS = ("ellipse", "point_to_point", "waypoints", "custom")

MAX_WAYPOINTS = 10_000


MAX_PATH_EXTENT = 1e3
"""Largest coordinate of a path point or axis [m] (an arm's workspace is metres)."""

MAX_PATH_RATE = 1e4
"""Largest angular frequency of a path or of its rocking [rad/s]."""

MIN_MOVE_TIME = 1e-3
"""Shortest point-to-point move or waypoint interval [s]: a quintic over less than a millisecond
asks for more than any actuator gives, and below about 1e-60 s its coefficients overflow."""


def _check_extents(tc: TrajectoryConfig) -> None:
    """Path points and axes within :data:`MAX_PATH_EXTENT`, rates within :data:`MAX_PATH_RATE`."""
    vectors = {
        "center": tc.center,
        "axis_a": tc.axis_a,
        "axis_b": tc.axis_b,
        "start": tc.start,
        "goal": tc.goal,
    }
    for name, values in vectors.items():
        if values is not None and any(abs(v) > MAX_PATH_EXTENT for v in values):
            raise ConfigError(f"trajectory.{name}", f"{values} has a coordinate beyond {MAX_PATH_EXTENT:g} m")
    for i, point in enumerate(tc.waypoints or []):
        if any(abs(v) > MAX_PATH_EXTENT for v in point):
            raise ConfigError(
                f"trajectory.waypoints[{i}]", f"{point} has a coordinate beyond {MAX_PATH_EXTENT:g} m"
            )
    for name in ("omega", "rotation_omega"):
        if abs(getattr(tc, name)) > MAX_PATH_RATE:
            raise ConfigError(
                f"trajectory.{name}", f"{getattr(tc, name):g} rad/s is beyond {MAX_PATH_RATE:g} rad/s"
            )
    if abs(tc.rotation_amplitude) > math.pi:
        raise ConfigError(
            "trajectory.rotation_amplitude",
            f"{tc.rotation_amplitude:g} rad is more than half a turn; at most pi",
        )


def _check_path(tc: TrajectoryConfig) -> None:
    """Check the path's own keys."""
    _check_extents(tc)
    if tc.kind == "ellipse":
        m_path = len(tc.center)
        for path, values in (("trajectory.axis_a", tc.axis_a), ("trajectory.axis_b", tc.axis_b)):
            if len(values) != m_path:
                raise ConfigError(path, f"has {len(values)} entries, trajectory.center has {m_path}")
        return
    if tc.kind == "point_to_point":
        if tc.goal is None:
            raise ConfigError(
                "trajectory.goal", "a point_to_point move needs its goal, e.g. goal = [0.5, 0.1, 0.4]"
            )
        if tc.start is not None and len(tc.start) != len(tc.goal):
            raise ConfigError(
                "trajectory.start", f"has {len(tc.start)} entries, trajectory.goal has {len(tc.goal)}"
            )
        if not tc.move_time >= MIN_MOVE_TIME:
            raise ConfigError(
                "trajectory.move_time", f"must be at least {MIN_MOVE_TIME:g} s, got {tc.move_time}"
            )
        return
    points, times = tc.waypoints, tc.waypoint_times
    if not points or len(points) < 2:
        raise ConfigError(
            "trajectory.waypoints",
            "a waypoint path needs at least 2 points, e.g. waypoints = [[0.4, 0.0, 0.5], [0.4, 0.2, 0.5]]",
        )
    if len(points) > MAX_WAYPOINTS:
        raise ConfigError("trajectory.waypoints", f"{len(points)} points; at most {MAX_WAYPOINTS}")
    sizes = {len(p) for p in points}
    if len(sizes) != 1:
        raise ConfigError(
            "trajectory.waypoints", f"every point needs as many entries; got sizes {sorted(sizes)}"
        )
    if times is None or len(times) != len(points):
        raise ConfigError(
            "trajectory.waypoint_times",
            f"needs one time per waypoint ({len(points)}), got {None if times is None else len(times)}",
        )
    if times[0] < 0 or any(b - a < MIN_MOVE_TIME for a, b in zip(times, times[1:])):
        raise ConfigError(
            "trajectory.waypoint_times",
            f"must start at 0 or later and increase by at least "
            f"{MIN_MOVE_TIME:g} s from one point to the next, got {times}",
        )


@dataclass
class ControllerConfig:
    """Which control law and its gains.

    Attributes:
        kind: ``nn`` (eq. 9 with the NN compensator), ``no-u0`` (eq. 9 with u_0 = 0),
            ``computed-torque`` (eq. 9 with u_0 = 0 and the true model and friction as nominal:
            what perfect model knowledge buys), ``sliding-mode`` (eq. 9 with a fixed-gain
            boundary-layer sliding-mode u_0) or ``pd``.
        Kp, Kv: diagonals of the task gains [1/s^2, 1/s], m entries or one for all;
            Kv^2 > Kp is required by eq. (17).
        k: self-motion gain of eq. (3) [1/s].
        pinv_threshold: smallest singular value of J below which J+ is damped [m/rad].
        pinv_max_damping: damping at a singularity [m/rad].
        pd_Kp, pd_Kd: task stiffness [N/m] and damping [N s/m] of the PD baseline (m entries or
            one for all; N m/rad and N m s/rad for the orientation rows of a pose).
        pd_null_damping: null-space joint damping D of the PD baseline [N m s/rad]; unset (the
            default): sized from the arm at q(0), so that the self-motion decays at the task
            damping's rate and at most at half the sampling rate
            (:func:`nnrobust.controllers.task_space.sized_null_damping`).
        coulomb_smoothing: v_s [rad/s]: the controller compensates Coulomb friction with
            sat(q' / v_s) instead of sgn(q') (0, the default: the exact sgn of the sampled
            velocity; see docs/plant.md for what that does near zero speed).
        sliding_gain: K of the sliding-mode u_0 [m/s^2].
        sliding_boundary: boundary-layer width Phi of the sliding-mode u_0 [m/s^2].
        class_: for ``kind = "custom"``, the controller class (TOML key ``class``):
            ``"file.py:Class"`` (a path relative to the experiment file) or ``"package.module:Class"``,
            a subclass of :class:`nnrobust.Controller` (docs/extending.md).
        params: for ``kind = "custom"``, the keyword arguments of the class's constructor (TOML
            table ``[controller.params]``).

    """

    kind: str = "nn"
    Kp: list[float] = field(default_factory=lambda: [10.0])
    Kv: list[float] = field(default_factory=lambda: [4.0])
    k: float = 10.0
    pinv_threshold: float = 0.02
    pinv_max_damping: float = 0.02
    pd_Kp: list[float] = field(default_factory=lambda: [400.0])
    pd_Kd: list[float] = field(default_factory=lambda: [40.0])
    pd_null_damping: float | None = None
    coulomb_smoothing: float = 0.0
    sliding_gain: float = 20.0
    sliding_boundary: float = 0.5
    class_: str | None = None
    params: dict | None = None


CONTROLLER_KINDS = ("nn", "no-u0", "computed-torque", "sliding-mode", "pd")
"""The built-in values of ``controller.kind`` set by flat keys; the registered laws
(:func:`controller_kinds`) take ``[controller.params]``, and ``custom`` names a user's class
(``controller.class``)."""


def shipped_laws() -> tuple[str, ...]:
    """The laws nnrobust ships: the built-in kinds and the registered laws
    (nnrobust/controllers/laws/).
    """
    from .controllers.registry import law_names

    return (*CONTROLLER_KINDS, *law_names())


def controller_kinds() -> tuple[str, ...]:
    """Every valid ``controller.kind``: the shipped laws and ``custom``."""
    return (*shipped_laws(), "custom")


EQ9_KINDS = ("nn", "no-u0", "computed-torque", "sliding-mode")
"""The kinds that are the task-space law of eq. (9), whose Kp and Kv eq. (17) constrains."""

KEY_ALIASES = {"class": "class_"}
"""TOML keys that are Python keywords, and the field each is stored in."""


@dataclass
class NNConfig:
    """The NN robust compensator, eqs. (15)-(17) (docs/controller.md).

    Attributes:
        law: ``corrected`` (u_0 = -rho^2 w / (rho |w| + eps)) or ``printed`` (-rho w / (...)).
        F: adaptation gain.
        gamma: decay rate of eps [1/s].
        eps0: eps(0) > 0.
        eps_min: eps floor (0 = the paper's vanishing boundary layer).
        sigma: sigma-modification leakage (0 = the paper's law; the default keeps a sampled
            controller bounded, docs/controller.md).
        basis_input: ``joint`` (s = [q, q']) or ``error`` (s = [e, e']).
        centers: Gaussian centres per input coordinate.
        width: Gaussian width as a multiple of the centre spacing.
        bias: include a constant unit.
        velocity_range: q' centres span [-velocity_range, velocity_range] [rad/s]; q centres
            span the joint limits.
        error_range: e and e' centres span [-error_range[0], error_range[0]] [m] and
            [-error_range[1], error_range[1]] [m/s].

    """

    law: str = "corrected"
    F: float = NN_DEFAULTS["F"]
    gamma: float = NN_DEFAULTS["gamma"]
    eps0: float = NN_DEFAULTS["eps0"]
    eps_min: float = NN_DEFAULTS["eps_min"]
    sigma: float = NN_DEFAULTS["sigma"]
    basis_input: str = "joint"
    centers: int = 5
    width: float = 1.0
    bias: bool = True
    velocity_range: float = 3.0
    error_range: list[float] = field(default_factory=lambda: [0.05, 0.5])


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
        return dump_toml(self.to_dict())

    def replace(self, **sections) -> ExperimentConfig:
        """A copy with some fields changed: ``replace(controller={"kind": "pd"})``."""
        data = self.to_dict()
        for key, value in sections.items():
            if isinstance(value, dict):
                data.setdefault(key, {}).update(value)
            else:
                data[key] = value
        return from_dict(data)


# ---- validation --------------------------------------------------------------------------


def _drop_none(obj):
    if isinstance(obj, dict):
        return {k: _drop_none(v) for k, v in obj.items() if v is not None}
    return obj


def _suggest(key: str, valid: list[str], prefix: str = "") -> str:
    """'unknown key; did you mean X?' and the valid keys (``prefix`` + each name; the names alone
    are compared, so that a shared prefix does not make every key look close).
    """
    close = [prefix + c for c in difflib.get_close_matches(key, valid, n=1)]
    valid = [prefix + v for v in valid]
    hint = f"; did you mean {close[0]!r}?" if close else "."
    return f"unknown key{hint} Valid keys: {', '.join(valid)}"


_TYPE_WORDS = {str: "string", float: "number", int: "integer", bool: "boolean"}


def _check_type(path: str, value, annotation):
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1:
            return _check_type(path, value, inner[0])
        for alternative in inner:  # e.g. str | list[float]: the first that takes the value
            if (typing.get_origin(alternative) or alternative) is type(value):
                return _check_type(path, value, alternative)
        kinds = " or ".join(
            "a list" if typing.get_origin(a) is list else f"a {_TYPE_WORDS[a]}" for a in inner
        )
        raise ConfigError(path, f"expected {kinds}, got {type(value).__name__} {value!r}")
    if origin is list:
        if not isinstance(value, list):
            raise ConfigError(path, f"expected a list, got {type(value).__name__} {value!r}")
        return [_check_type(f"{path}[{i}]", v, args[0]) for i, v in enumerate(value)]
    if annotation is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(path, f"expected a number, got {type(value).__name__} {value!r}")
        if isinstance(value, int) and abs(value) >= 2**63:
            raise ConfigError(
                path,
                f"expected a finite number of sensible size, got an integer of {len(str(abs(value)))} digits",
            )
        if not math.isfinite(value):
            raise ConfigError(path, f"expected a finite number, got {value!r}")
        return float(value)
    if annotation is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(path, f"expected an integer, got {type(value).__name__} {value!r}")
        if abs(value) >= 2**63:
            raise ConfigError(
                path, f"expected an integer in (-2^63, 2^63), got one of {len(str(abs(value)))} digits"
            )
        return value
    if annotation is bool:
        if not isinstance(value, bool):
            raise ConfigError(path, f"expected true or false, got {value!r}")
        return value
    if annotation is dict:  # free keyword arguments (controller.params): names checked, values kept
        if not isinstance(value, dict):
            raise ConfigError(path, f"expected a table, got {type(value).__name__} {value!r}")
        for key in value:
            if not key.isidentifier():
                raise ConfigError(
                    f"{path}.{key}", "is not a valid Python identifier (a keyword argument name)"
                )
        return dict(value)
    if annotation is str:
        if not isinstance(value, str):
            raise ConfigError(path, f"expected a string, got {type(value).__name__} {value!r}")
        return value
    raise TypeError(f"unsupported annotation {annotation!r} at {path}")  # pragma: no cover


@functools.cache
def _type_hints(cls) -> dict:
    """The annotations of a config dataclass, resolved once (every sample of a sweep parses one)."""
    return typing.get_type_hints(cls)


def _section_from_dict(cls, data: dict, path: str):
    if not isinstance(data, dict):
        raise ConfigError(path, f"expected a table, got {type(data).__name__}")
    hints = _type_hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    values = {}
    shown = [next((a for a, f in KEY_ALIASES.items() if f == n), n) for n in names]
    for key, value in data.items():
        full = f"{path}.{key}" if path else key
        key = KEY_ALIASES.get(key, key)
        if key not in names:
            raise ConfigError(full, _suggest(key, shown))
        annotation = hints[key]
        if dataclasses.is_dataclass(annotation):
            values[key] = _section_from_dict(annotation, value, full)
        else:
            values[key] = _check_type(full, value, annotation)
    return cls(**values)


def from_dict(data: dict) -> ExperimentConfig:
    """Build and validate a configuration from nested dicts (as read from TOML)."""
    config = _section_from_dict(ExperimentConfig, data, "")
    validate(config)
    return config


MAX_TOML_BYTES = 1_000_000
"""Largest experiment or sweep file read (an experiment file is a few kB)."""


def read_text_file(path: str | Path, limit: int = MAX_TOML_BYTES, what: str = "file") -> str:
    """The text of a regular file of at most ``limit`` bytes; a device, FIFO, folder, larger or
    non-UTF-8 file is one clear error (never an endless read or a hang).
    """
    path = Path(path)
    try:
        if path.exists() and not path.is_file():
            raise ConfigError(str(path), f"not a regular file; give a TOML {what}")
        with open(path, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as err:
        raise ConfigError(str(path), f"cannot read the file: {err.strerror or err}") from err
    if len(data) > limit:
        article = "an" if what[0] in "aeiou" else "a"
        raise ConfigError(str(path), f"larger than {limit // 1000} kB, the most read for {article} {what}")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ConfigError(str(path), "not a UTF-8 text file") from err


def parse_toml(text: str, where: str) -> dict:
    """tomllib.loads with one-line errors (also for tables nested too deep to parse)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(where, f"invalid TOML: {err}") from err
    except RecursionError as err:
        raise ConfigError(where, "invalid TOML: nested too deeply") from err


def load_config(path: str | Path) -> ExperimentConfig:
    """Read and validate a TOML experiment file. A relative URDF path in ``robot.source`` is read
    from the file's folder; a run folder's config.toml that recorded its URDF's SHA-256
    (:func:`provenance_header`) warns when that URDF has changed since.
    """
    path = Path(path)
    text = read_text_file(path, what="experiment file")
    data = _file_data(path, text)
    try:
        config = from_dict(data)
    except ConfigError as err:
        raise ConfigError(f"{path}: {err.key}", str(err).split(": ", 1)[1]) from err
    from .model.loading import urdf_digest

    checks = [("robot's URDF", RECORDED_DIGEST, config.robot.source, urdf_digest)]
    for part, source in user_files(config).items():
        pattern = re.compile(rf"^# {part} sha256: ([0-9a-f]{{64}})$", re.MULTILINE)
        checks.append((f"{part} file", pattern, source, _file_digest))
    for what, pattern, source, digest in checks:
        recorded = pattern.search(text)
        if not recorded or not source:
            continue
        try:
            now = digest(source)
        except OSError:
            now = ""
        if now and now != recorded.group(1):
            warnings.warn(
                f"{path}: the {what} ({source}) has changed since this run was written "
                f"(SHA-256 {recorded.group(1)[:12]}... then, {now[:12]}... now)",
                stacklevel=2,
            )
    return config


RECORDED_DIGEST = re.compile(r"^# urdf sha256: ([0-9a-f]{64})$", re.MULTILINE)

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


MAX_BASE_DEPTH = 8
"""Experiment files that start from one another (``base = "file.toml"``), at most this deep."""


def _file_data(path: Path, text: str, depth: int = 0) -> dict:
    """An experiment file's table with its relative paths (robot.source, the classes of
    :data:`USER_PARTS`) made
    absolute from the file's folder, merged over its ``base`` (a preset name or an experiment
    file): the file's keys win, section by section.
    """
    data = parse_toml(text, str(path))
    folder = path.resolve().parent
    robot = data.get("robot")
    if (
        isinstance(robot, dict)
        and isinstance(robot.get("source"), str)
        and _is_relative_urdf_path(robot["source"])
    ):
        resolved = (folder / robot["source"]).resolve()
        if not resolved.is_file():
            raise ConfigError(
                f"{path}: robot.source",
                f"{robot['source']!r} is not a file in {folder} (a "
                "relative path in an experiment file is read from the file's folder)",
            )
        robot["source"] = str(resolved)
    from .user_code import class_file

    for section, key, _, _ in USER_PARTS.values():
        table = data.get(section)
        if isinstance(table, dict) and isinstance(table.get(key), str):
            where, name = class_file(table[key]), table[key].rpartition(":")[2]
            if where is not None and not where.is_absolute():
                table[key] = f"{(folder / where).resolve()}:{name}"
    if "base" not in data:
        return data
    base = data.pop("base")
    if not isinstance(base, str):
        raise ConfigError(f"{path}: base", f"expected a preset name or an experiment file, got {base!r}")
    if depth >= MAX_BASE_DEPTH:
        raise ConfigError(
            f"{path}: base",
            f"experiment files start from one another more than {MAX_BASE_DEPTH} deep (a cycle?)",
        )
    if base.endswith(".toml"):
        base_path = (folder / base).resolve()
        if not base_path.is_file():
            raise ConfigError(f"{path}: base", f"{base!r} is not a file in {folder}")
    else:
        from .presets import preset_path

        try:
            base_path = preset_path(base)
        except ConfigError as err:
            raise ConfigError(f"{path}: base", str(err).split(": ", 1)[1]) from err
    merged = _file_data(base_path, read_text_file(base_path, what="experiment file"), depth + 1)
    for key, value in data.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return merged


def user_classes(config: ExperimentConfig) -> dict[str, str]:
    """The user classes the experiment uses: part (controller, trajectory, disturbance,
    criterion) -> its ``"file.py:Class"`` or ``"package.module:Class"``.
    """
    parts = {part: _user_part(config, part) for part in USER_PARTS}
    return {part: spec for part, (spec, _, chosen, _) in parts.items() if chosen and spec}


def user_files(config: ExperimentConfig) -> dict[str, str]:
    """The files of the user classes the experiment uses (part -> path; module paths left out)."""
    from .user_code import class_file

    paths = {part: class_file(spec) for part, spec in user_classes(config).items()}
    return {part: str(path) for part, path in paths.items() if path is not None}


def _file_digest(source: str) -> str:
    from .user_code import file_digest

    return file_digest(source)


def controller_label(config: ExperimentConfig) -> str:
    """The controller as runs and folders name it: its kind, or a custom law's class name."""
    if config.controller.kind == "custom" and config.controller.class_:
        return config.controller.class_.rpartition(":")[2]
    return config.controller.kind


def _is_relative_urdf_path(source: str) -> bool:
    """Whether robot.source names a URDF file by a relative path (not a robot name, not URDF text)."""
    if source.lstrip().startswith("<") or Path(source).is_absolute():
        return False
    return source.lower().endswith(".urdf") or "/" in source or os.sep in source


@functools.cache
def _package_version(package: str) -> str:
    """An installed package's version, or "?" (read once per process)."""
    from importlib import metadata

    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "?"


def provenance_header(config: ExperimentConfig) -> str:
    """Comment lines for a run's config.toml: the versions that ran it and the SHA-256 of the
    robot's URDF and of every user class's file, so that a run can be repeated, and checked,
    from anywhere.
    """
    from . import __version__
    from .model.loading import urdf_digest

    lines = [
        f"# written by nnrobust {__version__} (pin {_package_version('pin')}, example-robot-data "
        f"{_package_version('example-robot-data')})"
    ]
    digest = urdf_digest(config.robot.source)
    if digest:
        lines.append(f"# urdf sha256: {digest}")
    for part, source in user_files(config).items():
        if Path(source).is_file():
            lines.append(f"# {part} sha256: {_file_digest(source)}")
    return "\n".join(lines) + "\n"


def _non_negative(path: str, value: float) -> None:
    if value < 0:
        raise ConfigError(path, f"must be >= 0, got {value}")


def _positive(path: str, values) -> None:
    seq = values if isinstance(values, list) else [values]
    if any(v <= 0 for v in seq):
        raise ConfigError(path, f"must be positive, got {values}")


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


def default_criteria(n: int, task: str) -> list[str]:
    """``subtasks.criteria`` when it is not given: the paper's eq. (19) on a three-joint planar
    arm, else manipulability and joint-limit avoidance (joint limits alone on a pose task, where
    the manipulability of a 6 x n Jacobian mixes metres and radians).
    """
    if n == 3 and task == "planar":
        return ["paper"]
    return ["joint_limits"] if task == "pose" else ["manipulability", "joint_limits"]


MAX_SUBSTEPS = 10_000
MAX_STEPS = 1e9
MAX_CENTERS = 1000
"""Bounds that no sensible experiment reaches; the memory estimate (experiment.check_memory)
refuses most oversized runs long before them."""

NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]{0,99}")
"""An experiment's name: it names the default run folder, out/<name>-<controller>."""


def path_key(tc: TrajectoryConfig) -> str:
    """The key that places the path: center, goal, waypoints (or class, for a user's)."""
    keys = {"ellipse": "center", "point_to_point": "goal", "waypoints": "waypoints", "custom": "class"}
    return keys.get(tc.kind, "center")


CLASS_PATTERN = re.compile(r"(?P<where>[^:]+):(?P<name>[A-Za-z_][A-Za-z0-9_]*)")
"""A user's class (``controller.class``, ``trajectory.class``, ...): ``file.py:Class`` or
``package.module:Class``."""


def _check_trajectory(config: ExperimentConfig) -> tuple[int, str]:
    """A shipped path's keys against the task: (m, where m comes from, for messages)."""
    tc = config.trajectory
    _check_path(tc)
    m_path = tc.dimension
    if m_path not in (2, 3):
        raise ConfigError(
            f"trajectory.{path_key(tc)}", f"path points have 2 (x, y) or 3 (x, y, z) entries, got {m_path}"
        )
    if config.robot.task != "pose":
        return m_path, f"the task has m = {m_path} (trajectory.{path_key(tc)})"
    if m_path != 3:
        raise ConfigError(f"trajectory.{path_key(tc)}", f"a pose task needs a 3-D path, got {m_path} entries")
    for path, values in (
        ("trajectory.orientation_rpy", tc.orientation_rpy),
        ("trajectory.rotation_axis", tc.rotation_axis),
    ):
        if values is not None and len(values) != 3:
            raise ConfigError(path, f"needs 3 entries, got {len(values)}")
    if not any(tc.rotation_axis):
        raise ConfigError("trajectory.rotation_axis", "must be a non-zero vector")
    return 6, "the pose task has m = 6"


def _check_gains(c: ControllerConfig, m: int, where: str) -> None:
    """Kp, Kv, pd_Kp, pd_Kd: one value for all m task coordinates (repeated here) or m, positive."""
    for name in ("Kp", "Kv", "pd_Kp", "pd_Kd"):
        values = getattr(c, name)
        if len(values) == 1:  # one value for every task coordinate
            setattr(c, name, values * m)
        elif len(values) != m:
            raise ConfigError(
                f"controller.{name}", f"has {len(values)} entries, {where} (or give one value for all)"
            )
    for path, values in (
        ("controller.Kp", c.Kp),
        ("controller.Kv", c.Kv),
        ("controller.pd_Kp", c.pd_Kp),
        ("controller.pd_Kd", c.pd_Kd),
    ):
        _positive(path, values)


def inert_keys(config: ExperimentConfig) -> dict[str, str]:
    """Keys (``section.key``, or ``section.`` for a whole section) that this configuration does
    not read, each with the choice that makes it so: a key set here changes nothing.
    """
    c, tc, pc, sc, sim = (
        config.controller,
        config.trajectory,
        config.plant,
        config.subtasks,
        config.simulation,
    )
    inert: dict[str, str] = {}

    def mark(keys, why):
        for key in keys:
            inert.setdefault(key, why)

    from .controllers.registry import registered_law

    kind = f"controller.kind = {c.kind!r}"
    if registered_law(c.kind) is not None:  # its own parameters; it may read subtasks and nominal
        mark(["controller.Kp", "controller.Kv", "controller.k"], f"{kind} is not eq. (9)")
    elif c.kind not in EQ9_KINDS:
        mark(["controller.Kp", "controller.Kv", "controller.k", "subtasks."], f"{kind} is not eq. (9)")
        mark(["controller.coulomb_smoothing", "nominal.viscous_friction", "nominal.coulomb_friction"], kind)
    if c.kind != "nn":
        mark(["nn."], kind)
    if c.kind != "sliding-mode":
        mark(["controller.sliding_gain", "controller.sliding_boundary"], kind)
    if c.kind != "pd":
        mark(["controller.pd_Kp", "controller.pd_Kd", "controller.pd_null_damping"], kind)
    if c.kind == "computed-torque":
        mark(["nominal."], "computed torque uses the true model")
    if c.kind == "custom":
        mark(["controller.pinv_threshold", "controller.pinv_max_damping"], kind)
    if c.kind in EQ9_KINDS and c.k == 0:
        mark(["subtasks."], "controller.k = 0 (no self-motion)")
    if nominal_kind(config) == "urdf":
        mark(["nominal.beta", "nominal.p"], "nominal.kind = 'urdf' (beta and p are the closed form's)")
    if c.kind == "nn" and config.nn.basis_input == "joint":
        mark(["nn.error_range"], "nn.basis_input = 'joint'")
    if c.kind == "nn" and config.nn.basis_input == "error":
        mark(["nn.velocity_range"], "nn.basis_input = 'error'")
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
    if not pc.joint_stops:
        mark(["plant.joint_stop_stiffness", "plant.joint_stop_damping"], "plant.joint_stops = false")
    fixed = (
        "simulation.adaptive_step = false" if not sim.adaptive_step
        else "simulation.integrator = 'solve_ivp'" if sim.integrator == "solve_ivp"
        else "plant.engine = 'mujoco'" if pc.engine == "mujoco"
        else ""
    )  # fmt: skip
    if fixed:
        mark(["simulation.max_step_rotation"], fixed)
    if sim.integrator == "solve_ivp":
        mark(["simulation.substeps", "simulation.integration_step"], "simulation.integrator = 'solve_ivp'")
    path_keys = {
        "ellipse": ["center", "axis_a", "axis_b", "omega", "phase"],
        "point_to_point": ["start", "goal", "move_time"],
        "waypoints": ["waypoints", "waypoint_times"],
        "custom": ["class", "params"],
    }
    for other, keys in path_keys.items():
        if other != tc.kind:
            mark([f"trajectory.{k}" for k in keys], f"trajectory.kind = {tc.kind!r}")
    if config.robot.task != "pose":
        mark(
            [f"trajectory.{k}" for k in ("orientation_rpy", "rotation_axis", "rotation_amplitude",
                                         "rotation_omega", "rotation_phase")],
            f"robot.task = {config.robot.task!r}",
        )  # fmt: skip
    criteria = sc.criteria if sc.criteria is not None else default_criteria(3, config.robot.task)
    if "obstacles" not in criteria:
        mark(["subtasks.obstacles", "subtasks.obstacle_influence", "subtasks.link_radius"],
             "'obstacles' is not in subtasks.criteria")  # fmt: skip
    if "joint_smoothness" not in criteria:
        mark(["subtasks.smoothness_coefficients"], "'joint_smoothness' is not in subtasks.criteria")
    return inert


def inert_reason(config: ExperimentConfig, key: str) -> str:
    """Why setting ``key`` (``section.key`` or ``section.key[i]``) changes nothing here, or ""."""
    base = key.split("[", 1)[0]
    inert = inert_keys(config)
    if base in inert:
        return inert[base]
    section = base.split(".", 1)[0] + "."
    return inert.get(section, "")


def _check_user_classes(config: ExperimentConfig) -> None:
    """A class and its params belong to the choice that names a user's class (e.g.
    ``controller.kind = "custom"``), which needs the class.
    """
    from .controllers.registry import registered_law

    for part, (section, class_name, params_name, choice) in USER_PARTS.items():
        spec, params, custom, now = _user_part(config, part)
        class_key, params_key = f"{section}.{class_name}", f"{section}.{params_name}"
        law = registered_law(str(now)) if part == "controller" else None
        if law is not None:  # a registered law: its declared params, no class
            if spec is not None:
                raise ConfigError(
                    class_key, f"is read only with kind = 'custom' (kind is {now!r}, a shipped law)"
                )
            law.resolve(params, None, TASK_KINDS[config.robot.task])
            continue
        wanted = "criteria = [..., 'custom']" if choice == "criteria" else f"{choice} = 'custom'"
        if not custom:
            for key, value in ((class_key, spec), (params_key, params)):
                if value is not None:
                    raise ConfigError(key, f"is read only with {wanted} ({choice} is {now!r})")
            continue
        if spec is None:
            raise ConfigError(
                class_key,
                f'{wanted} needs the class: "my_code.py:MyClass" (a file relative to the experiment '
                'file) or "package.module:MyClass"',
            )
        if not CLASS_PATTERN.fullmatch(spec):
            raise ConfigError(class_key, f'{spec!r} is not "file.py:Class" nor "package.module:Class"')


MAX_GAIN = 1e12
"""Largest gain or adaptation rate accepted: beyond it a 1 ms sampled loop is numerically
meaningless, and the two loops' rounding would tell different stories."""

RANGE_LIMITS = (1e-9, 1e9)
"""Accepted span of the NN basis ranges (velocity_range, error_range): a Gaussian of width 1e-300
underflows to 0/0 in one loop and not the other."""


def _within_range(config: ExperimentConfig) -> None:
    """Values both loops compute the same way: gains up to :data:`MAX_GAIN`, basis ranges within
    :data:`RANGE_LIMITS`; beyond, a refusal rather than two different runs.
    """
    c, nn = config.controller, config.nn
    for key, values in (
        ("controller.Kp", c.Kp),
        ("controller.Kv", c.Kv),
        ("controller.pd_Kp", c.pd_Kp),
        ("controller.pd_Kd", c.pd_Kd),
        ("controller.k", [c.k]),
        ("controller.pd_null_damping", [c.pd_null_damping or 0.0]),
        ("controller.sliding_gain", [c.sliding_gain]),
        ("controller.sliding_boundary", [c.sliding_boundary]),
        ("nn.F", [nn.F]),
        ("nn.gamma", [nn.gamma]),
        ("nn.sigma", [nn.sigma]),
        ("nn.eps0", [nn.eps0]),
    ):
        if any(abs(v) > MAX_GAIN for v in values):
            shown = values if len(values) > 1 else values[0]
            raise ConfigError(
                key,
                f"{shown} is beyond {MAX_GAIN:g}; no sampled loop at a realistic period uses such a value",
            )
    low, high = RANGE_LIMITS
    for key, values in (("nn.error_range", nn.error_range), ("nn.velocity_range", [nn.velocity_range])):
        if any(not low <= v <= high for v in values):
            shown = values if len(values) > 1 else values[0]
            raise ConfigError(key, f"{shown} is outside [{low:g}, {high:g}]")


MAX_PAYLOAD = 1000.0
"""Largest ``plant.payload`` [kg]."""
MAX_FACTOR = 100.0
"""Largest factor on a nominal inertial parameter (``nominal.factors``) or on the plant's friction
or disturbance (``plant.friction_scale``, ...)."""
MIN_STEP_ROTATION = 1e-6
"""Smallest ``simulation.max_step_rotation`` [rad or m]: below it every fast period is cut to the
most steps a period may take, and a run crawls (1e-300 ran 46x slower than real time)."""
MAX_PHYSICAL = 1e6
"""Largest friction coefficient, stop damping or closed-form parameter accepted: beyond it the
plant is so stiff that no plant step resolves it (a 1e10 friction scale asked for 1.7e8 RK4 steps
per period)."""
MAX_STOP_STIFFNESS = 1e6
"""Largest ``plant.joint_stop_stiffness`` [1/rad] (the default is 100)."""
MAX_PINV = 1e3
"""Largest ``controller.pinv_threshold`` and ``pinv_max_damping`` [m/rad]: a task Jacobian's
singular values are metres per radian."""

INDEXED = re.compile(r"^([a-z_]+)\.([A-Za-z_]+)\[(\d{1,4})\]$")
"""``section.field[i]``: one entry of a list-valued key (``nominal.factors[2]``)."""

FILLED_LISTS = {
    ("nominal", "factors"): 1.0,
    ("plant", "joint_friction_scales"): 1.0,
    ("plant", "joint_disturbance_scales"): 1.0,
}
"""List keys whose entries not given are known (a factor not given is 1): set entry by entry."""


def validate(config: ExperimentConfig) -> None:
    """Check values that a type alone does not constrain (robot-independent checks)."""
    c, nn, sim = config.controller, config.nn, config.simulation
    if not NAME_PATTERN.fullmatch(config.name) or ".." in config.name:
        raise ConfigError(
            "name",
            f"{config.name!r} is not a valid name: 1 to 100 letters, digits, '.', '_', "
            "'+' or '-', starting with a letter or digit, without '..' (it names the run "
            "folder out/<name>-<controller>)",
        )
    gravity = config.robot.gravity
    if gravity is not None and (len(gravity) != 3 or math.hypot(*gravity) > 1e3):
        raise ConfigError(
            "robot.gravity", f"needs 3 entries (x, y, z) [m/s^2] of at most 1000 m/s^2 in all, got {gravity}"
        )
    if config.robot.chain is not None and len(config.robot.chain) != 2:
        raise ConfigError("robot.chain", f"needs 2 frame names, [base, tip], got {config.robot.chain}")
    choices = {
        "robot.task": (config.robot.task, tuple(TASK_KINDS)),
        "nominal.kind": (config.nominal.kind, ("auto", "closed-form", "urdf")),
        "plant.friction": (config.plant.friction, ("urdf", "scaled")),
        "plant.disturbance": (
            config.plant.disturbance,
            ("auto", "paper", "none", "scaled", "sinusoid", "custom"),
        ),
        "plant.engine": (config.plant.engine, ENGINES),
        "plant.mujoco_integrator": (config.plant.mujoco_integrator, MUJOCO_INTEGRATORS),
        "controller.kind": (c.kind, controller_kinds()),
        "nn.law": (nn.law, ("corrected", "printed")),
        "nn.basis_input": (nn.basis_input, ("joint", "error")),
        "simulation.integrator": (sim.integrator, ("rk4", "solve_ivp")),
        "simulation.backend": (sim.backend, ("auto", "compiled", "hybrid", "python")),
        "trajectory.kind": (config.trajectory.kind, TRAJECTORY_KINDS),
    }
    for path, (value, valid) in choices.items():
        if value not in valid:
            raise ConfigError(path, f"{value!r} is not one of {', '.join(valid)}")
    tc = config.trajectory
    if tc.kind == "custom":
        if config.robot.task == "pose":
            raise ConfigError(
                "trajectory.kind",
                "a custom trajectory is for planar and position tasks; a pose task takes the "
                "shipped paths with their orientation (ellipse, point_to_point, waypoints)",
            )
        m, where = (
            TASK_KINDS[config.robot.task],
            f"the {config.robot.task} task has m = {TASK_KINDS[config.robot.task]}",
        )
    else:
        m, where = _check_trajectory(config)
    _check_gains(c, m, where)
    _check_user_classes(config)
    for kp, kv in zip(c.Kp, c.Kv) if c.kind in EQ9_KINDS else ():  # pd and custom laws do not use them
        if kv * kv <= kp:
            raise ConfigError(
                "controller.Kv",
                f"Kv^2 = {kv * kv:g} must exceed Kp = {kp:g}: Q = diag(2 Kp^2, 2 Kv^2 - 2 Kp) of "
                "eq. (17) must be positive definite for the Lyapunov function y^T P y to decrease",
            )
    _non_negative("controller.k", c.k)
    if c.pd_null_damping is not None:
        _non_negative("controller.pd_null_damping", c.pd_null_damping)
    for key in ("pinv_threshold", "pinv_max_damping"):
        if not 0 < getattr(c, key) <= MAX_PINV:
            raise ConfigError(
                f"controller.{key}", f"must be in (0, {MAX_PINV:g}] m/rad, got {getattr(c, key):g}"
            )
    _positive("nn.F", nn.F)
    _positive("nn.eps0", nn.eps0)
    _positive("nn.centers", nn.centers)
    low, high = RANGE_LIMITS
    if not low <= nn.width <= high:  # 1e-308 makes the basis 0/0: the two loops would disagree
        raise ConfigError("nn.width", f"{nn.width:g} is outside [{low:g}, {high:g}]")
    _positive("nn.velocity_range", nn.velocity_range)
    _positive("nn.error_range", nn.error_range)
    _within_range(config)
    for key, number in (("nn.gamma", nn.gamma), ("nn.eps_min", nn.eps_min), ("nn.sigma", nn.sigma)):
        _non_negative(key, number)
    if nn.eps_min > nn.eps0:
        raise ConfigError("nn.eps_min", f"the floor {nn.eps_min} must not exceed nn.eps0 = {nn.eps0}")
    nc, pc = config.nominal, config.plant
    _positive("nominal.mass_scale", nc.mass_scale)
    _positive("nominal.inertia_scale", nc.inertia_scale)
    if not 0 <= nc.relative_error < 1:
        raise ConfigError(
            "nominal.relative_error", f"must be in [0, 1) so masses stay positive, got {nc.relative_error}"
        )
    if nc.com_error < 0:
        raise ConfigError("nominal.com_error", f"must be >= 0 [m], got {nc.com_error}")
    if nc.factors is not None and any(not 0 < f <= MAX_FACTOR for f in nc.factors):
        raise ConfigError("nominal.factors", f"each factor must be in (0, {MAX_FACTOR:g}], got {nc.factors}")
    if nominal_kind(config) == "closed-form" and (nc.mass_scale, nc.inertia_scale, nc.com_error) != (1, 1, 0):
        raise ConfigError(
            "nominal.kind",
            "mass_scale, inertia_scale and com_error perturb the URDF "
            "model: set kind = 'urdf' (closed-form takes beta, p and relative_error)",
        )
    for key in ("disturbance_scale", "friction_scale"):
        if not 0 <= getattr(pc, key) <= MAX_FACTOR:
            raise ConfigError(f"plant.{key}", f"must be in [0, {MAX_FACTOR:g}], got {getattr(pc, key):g}")
    for section, key, values, unit in (
        ("plant", "viscous_friction", pc.viscous_friction, "N m s/rad"),
        ("plant", "coulomb_friction", pc.coulomb_friction, "N m"),
        ("nominal", "viscous_friction", nc.viscous_friction, "N m s/rad"),
        ("nominal", "coulomb_friction", nc.coulomb_friction, "N m"),
        ("nominal", "beta", nc.beta, "kg m^2"),
        ("nominal", "p", nc.p, "kg m^2"),
    ):
        if values is not None and any(not 0 <= v <= MAX_PHYSICAL for v in values):
            raise ConfigError(
                f"{section}.{key}", f"each entry must be in [0, {MAX_PHYSICAL:g}] {unit}, got {values}"
            )
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
    if isinstance(pc.torque_limits, str):
        if pc.torque_limits not in ("urdf", "none"):
            raise ConfigError(
                "plant.torque_limits",
                f"{pc.torque_limits!r} is not one of urdf, none (or give one limit per joint [N m])",
            )
    else:
        _positive("plant.torque_limits", pc.torque_limits)
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
    if pc.engine == "mujoco" and sim.integrator != "rk4":
        raise ConfigError(
            "simulation.integrator",
            f"{sim.integrator!r} integrates the pinocchio engine; "
            "MuJoCo has its own (plant.mujoco_integrator)",
        )
    se = config.sensing
    for path, values in (
        ("sensing.position_noise", se.position_noise),
        ("sensing.velocity_noise", se.velocity_noise),
        ("sensing.encoder_resolution", se.encoder_resolution),
    ):
        if not values or any(v < 0 for v in values):
            raise ConfigError(
                path, f"needs one value for all joints or one per joint, each >= 0, got {values}"
            )
    for path, seed in (("sensing.seed", se.seed), ("nominal.seed", config.nominal.seed)):
        if not 0 <= seed < 2**63:
            raise ConfigError(path, f"must be an integer in [0, 2^63), got {seed}")
    if se.delay < 0:
        raise ConfigError("sensing.delay", f"must be >= 0 control periods, got {se.delay}")
    if se.delay > 0 and sim.control_period > 0 and se.delay * sim.control_period >= sim.duration > 0:
        raise ConfigError(
            "sensing.delay",
            f"{se.delay} control periods is the whole run ({sim.duration:g} s) or more: no command "
            "computed from a measurement would reach the actuators",
        )
    _non_negative("controller.coulomb_smoothing", c.coulomb_smoothing)
    _positive("controller.sliding_gain", c.sliding_gain)
    _positive("controller.sliding_boundary", c.sliding_boundary)
    for key, number in (
        ("plant.viscous_level", pc.viscous_level),
        ("plant.coulomb_level", pc.coulomb_level),
        ("plant.disturbance_level", pc.disturbance_level),
    ):
        _non_negative(key, number)
    _positive("subtasks.C", config.subtasks.C)
    _positive("subtasks.obstacle_influence", config.subtasks.obstacle_influence)
    _non_negative("subtasks.link_radius", config.subtasks.link_radius)
    for i, sphere in enumerate(config.subtasks.obstacles):
        if len(sphere) != 4 or sphere[3] < 0:
            raise ConfigError(f"subtasks.obstacles[{i}]", f"must be [x, y, z, radius >= 0], got {sphere}")
    if config.subtasks.weights is not None and config.subtasks.criteria is None:
        raise ConfigError("subtasks.weights", "weigh criteria that are named: set subtasks.criteria too")
    if "obstacles" in (config.subtasks.criteria or []) and not config.subtasks.obstacles:
        raise ConfigError("subtasks.obstacles", "criterion 'obstacles' needs at least one sphere")
    if config.subtasks.weights is not None:
        named = config.subtasks.criteria or []
        if len(config.subtasks.weights) != len(named):
            raise ConfigError(
                "subtasks.weights", f"{len(config.subtasks.weights)} weights for {len(named)} criteria"
            )
        _positive("subtasks.weights", config.subtasks.weights)
        total = sum(config.subtasks.weights)
        if not math.isclose(total, config.subtasks.C, rel_tol=1e-9):
            raise ConfigError(
                "subtasks.weights",
                f"sum to {total:g} but subtasks.C = {config.subtasks.C:g}; eq. (4) needs sum w_i = C "
                "(or leave weights out for C / number of criteria each)",
            )
    _positive("simulation.duration", sim.duration)
    _positive("simulation.control_period", sim.control_period)
    if sim.substeps is not None:
        _positive("simulation.substeps", sim.substeps)
    if sim.max_step_rotation < MIN_STEP_ROTATION:
        raise ConfigError(
            "simulation.max_step_rotation",
            f"must be at least {MIN_STEP_ROTATION:g} rad (or m), got "
            f"{sim.max_step_rotation:g}; to keep the plant step fixed, set "
            "simulation.adaptive_step = false",
        )
    offset = sim.initial_task_offset
    if offset is not None and any(abs(v) > MAX_PATH_EXTENT for v in offset):
        raise ConfigError(
            "simulation.initial_task_offset", f"{offset} has an entry beyond {MAX_PATH_EXTENT:g} m (or rad)"
        )
    if sim.integration_step is not None:
        _positive("simulation.integration_step", sim.integration_step)
        ratio = sim.control_period / sim.integration_step
        if ratio < 1 - 1e-9:
            raise ConfigError(
                "simulation.integration_step",
                f"{sim.integration_step:g} s is longer than the control period {sim.control_period:g} s; "
                "the torque changes every control period, so a step may not span two",
            )
        if abs(ratio - round(ratio)) > 1e-6 * ratio:
            raise ConfigError(
                "simulation.integration_step",
                f"the control period {sim.control_period:g} s is not a whole number of steps of "
                f"{sim.integration_step:g} s (ratio {ratio:.6g})",
            )
        if sim.substeps is not None and sim.substeps != int(round(ratio)):
            raise ConfigError(
                "simulation.substeps",
                f"{sim.substeps} disagrees with simulation.integration_step = {sim.integration_step:g} s "
                f"({int(round(ratio))} steps per control period); give one of the two",
            )
    if config.plant.loads:
        from .plant.loads import parse_loads

        parse_loads(config.plant.loads, config.simulation.control_period)
    if sim.duration < sim.control_period:
        raise ConfigError("simulation.duration", "is shorter than one control period")
    substeps = sim.requested_substeps
    if substeps is not None and substeps > MAX_SUBSTEPS:
        raise ConfigError(
            "simulation.substeps" if sim.substeps is not None else "simulation.integration_step",
            f"{substeps} integration steps per control period; at "
            f"most {MAX_SUBSTEPS} (a shorter control_period does the same job)",
        )
    steps = sim.duration / sim.control_period
    if steps > MAX_STEPS:
        raise ConfigError(
            "simulation.duration",
            f"{sim.duration:g} s at a control period of "
            f"{sim.control_period:g} s is {steps:.3g} steps; at most {MAX_STEPS:.0e}",
        )
    if nn.centers > MAX_CENTERS:
        raise ConfigError("nn.centers", f"{nn.centers} centres per input; at most {MAX_CENTERS}")
    _positive("simulation.memory_limit", sim.memory_limit)
    if config.plant.disturbance == "sinusoid" and (
        config.plant.disturbance_amplitude is None or config.plant.disturbance_omega is None
    ):
        raise ConfigError(
            "plant.disturbance_amplitude",
            "disturbance = 'sinusoid' needs disturbance_amplitude (n x K) and disturbance_omega (K)",
        )


# ---- TOML output -------------------------------------------------------------------------


_TOML_ESCAPES = {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\t": "\\t", "\r": "\\r"}


_TOML_ESCAPED = re.compile(r'[\\"\x00-\x1f\x7f]')


def _toml_string(value: str) -> str:
    """A TOML basic string: quotes, backslashes and every control character escaped."""

    def escape(match: re.Match) -> str:
        c = match.group()
        return _TOML_ESCAPES.get(c) or f"\\u{ord(c):04x}"

    return '"' + _TOML_ESCAPED.sub(escape, value) + '"'


def _toml_key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else _toml_string(key)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):  # an inline table (controller.params)
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")


def dump_toml(data: dict) -> str:
    """TOML text of a dict whose values are scalars, lists or one level of sub-tables."""
    lines = [f"{k} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for key, table in data.items():
        if isinstance(table, dict):
            lines += ["", f"[{key}]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


# ---- dotted overrides (``run --set``, sweep files) ------------------------------------------


_FIELD_NAMES: dict[typing.Any, list[str]] = {}


def _field_names(cls: typing.Any) -> list[str]:
    """A config dataclass's field names, listed once per class."""
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = [f.name for f in dataclasses.fields(cls)]
    return names


def check_dotted_key(key: str) -> None:
    """Refuse a dotted key that names no field of the experiment schema (``section.field``, or a
    top-level ``name`` / ``description``, or ``section.field[i]`` of a list field), with a
    suggestion.
    """
    indexed = INDEXED.match(key)
    if indexed:
        section, field_name, _ = indexed.groups()
        check_dotted_key(f"{section}.{field_name}")
        annotation = _type_hints(_type_hints(ExperimentConfig)[section])[field_name]
        if "list" not in str(annotation):
            raise ConfigError(key, f"{section}.{field_name} is not a list; index only list keys")
        return
    parts = key.split(".")
    top = _field_names(ExperimentConfig)
    hints = _type_hints(ExperimentConfig)
    if len(parts) == 1:
        if parts[0] not in top or dataclasses.is_dataclass(hints.get(parts[0])):
            raise ConfigError(
                key, "not a key of the experiment schema; use section.field, e.g. simulation.duration"
            )
        return
    section, field_name = parts[0], ".".join(parts[1:])
    if section not in top or not dataclasses.is_dataclass(hints[section]):
        raise ConfigError(key, _suggest(section, [t for t in top if dataclasses.is_dataclass(hints[t])]))
    names = [next((a for a, f in KEY_ALIASES.items() if f == n), n) for n in _field_names(hints[section])]
    if len(parts) == 3 and section == "controller" and parts[1] == "params":  # one keyword argument
        if not parts[2].isidentifier():
            raise ConfigError(key, f"{parts[2]!r} is not a valid Python identifier (a keyword argument name)")
        return
    if len(parts) != 2 or field_name not in names:
        raise ConfigError(key, _suggest(field_name, names, prefix=f"{section}."))


def apply_overrides(config: ExperimentConfig, overrides: dict) -> ExperimentConfig:
    """A copy of ``config`` with dotted keys set (``{"simulation.duration": 20.0}``), validated like
    an experiment file.
    """
    data = config.to_dict()
    for key, value in overrides.items():
        check_dotted_key(key)
        parts = key.split(".")
        indexed = INDEXED.match(key)
        if indexed:
            section, field_name, index = indexed.groups()
            _set_entry(data.setdefault(section, {}), section, field_name, int(index), value)
        elif len(parts) == 1:
            data[parts[0]] = value
        elif len(parts) == 3:  # controller.params.NAME
            section = data.setdefault(parts[0], {})
            section[parts[1]] = {**(section.get(parts[1]) or {}), parts[2]: value}
        else:
            data.setdefault(parts[0], {})[parts[1]] = value
    return from_dict(data)


def _set_entry(table: dict, section: str, field_name: str, index: int, value) -> None:
    """``section.field[index] = value`` in a section's table: a list key given in full, or one
    whose missing entries are known (:data:`FILLED_LISTS`).
    """
    current = table.get(field_name)
    fill = FILLED_LISTS.get((section, field_name))
    if current is None and fill is None:
        raise ConfigError(
            f"{section}.{field_name}[{index}]",
            f"{section}.{field_name} is not set: give the whole list first (in [set]), then vary its entries",
        )
    entries = list(current) if current is not None else []
    if index >= len(entries):
        if fill is None:
            raise ConfigError(
                f"{section}.{field_name}[{index}]", f"{section}.{field_name} has {len(entries)} entries"
            )
        entries += [fill] * (index + 1 - len(entries))
    entries[index] = value
    table[field_name] = entries


def parse_override(text: str) -> tuple[str, object]:
    """``key=value`` with a TOML value (``simulation.duration=20``, ``nn.sigma=0.5``,
    ``controller.Kp=[100.0]``); a value that is not TOML is taken as a string.
    """
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ConfigError("--set", f"{text!r} is not key=value (e.g. simulation.duration=20)")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    except RecursionError as err:
        raise ConfigError(f"--set {key}", "the value is nested too deeply") from err
    check_dotted_key(key)
    return key, value
