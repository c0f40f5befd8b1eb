"""Checks that only check: the values of a typed configuration that a type alone does not
constrain (ranges, sizes, consistency between keys), each a one-line ConfigError naming the key;
and which keys a configuration leaves inert. Nothing here changes a configuration.
"""

from __future__ import annotations

import math
import os
import re

from ..controllers.registry import controller_kinds
from ..controllers.section import ControllerConfig, is_eq9
from ..exceptions import ConfigError
from ..model.tasks import TASK_KINDS
from ..numeric_limits import MAX_PAYLOAD
from ..plant.disturbance import DISTURBANCE_KINDS
from ..plant.mujoco_engine import ENGINES, MUJOCO_INTEGRATORS
from ..subtasks.registry import default_criteria
from ..trajectories import PATH_KINDS, path_key
from ..trajectories.section import MAX_PATH_EXTENT, MAX_PATH_RATE, TRAJECTORY_KINDS, TrajectoryConfig
from .resolve import GAIN_KEYS, full_gain
from .schema import USER_PARTS, ExperimentConfig, _user_part, nominal_kind


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
    """Check the path's own keys (its declaration's checks, nnrobust/trajectories/)."""
    _check_extents(tc)
    PATH_KINDS[tc.kind].check(tc)


def _non_negative(path: str, value: float) -> None:
    if value < 0:
        raise ConfigError(path, f"must be >= 0, got {value}")


def _positive(path: str, values) -> None:
    seq = values if isinstance(values, list) else [values]
    if any(v <= 0 for v in seq):
        raise ConfigError(path, f"must be positive, got {values}")


MAX_SUBSTEPS = 10_000
MIN_AXIS_NORM = 1e-9
"""Shortest ``trajectory.rotation_axis`` accepted: its direction is its only meaning, and a
vector of 1e-320 has a length that squares to 0 (no direction to normalise to)."""
MAX_STEPS = 1e9
"""Bounds that no sensible experiment reaches; the memory estimate (experiment.check_memory)
refuses most oversized runs long before them."""

NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]{0,99}")
"""An experiment's name: it names the default run folder, out/<name>-<controller>."""


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
    if math.hypot(*tc.rotation_axis) < MIN_AXIS_NORM:
        raise ConfigError(
            "trajectory.rotation_axis",
            f"[{', '.join(f'{v:.6g}' for v in tc.rotation_axis)}] is too short to give a direction "
            f"(length below {MIN_AXIS_NORM:g}); the axis is normalised, so give it at unit scale, "
            "e.g. [1, 0, 0]",
        )
    return 6, "the pose task has m = 6"


def _check_gain_sizes(c: ControllerConfig, m: int, where: str) -> None:
    """Kp, Kv, pd_Kp, pd_Kd: one value for all m task coordinates or m (their ranges are
    declared and checked next).
    """
    for name in GAIN_KEYS:
        values = getattr(c, name)
        if len(values) not in (1, m):
            raise ConfigError(
                f"controller.{name}", f"has {len(values)} entries, {where} (or give one value for all)"
            )


def _check_eq17(c: ControllerConfig, m: int) -> None:
    """Kv^2 > Kp on each task coordinate for the kinds of eq. (9) (gains already in range)."""
    pairs = zip(full_gain(c.Kp, m), full_gain(c.Kv, m))
    for kp, kv in pairs if is_eq9(c.kind) else ():  # pd and custom laws do not use them
        if kv * kv <= kp:
            raise ConfigError(
                "controller.Kv",
                f"Kv^2 = {kv * kv:g} must exceed Kp = {kp:g}: Q = diag(2 Kp^2, 2 Kv^2 - 2 Kp) of "
                "eq. (17) must be positive definite for the Lyapunov function y^T P y to decrease",
            )


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

    from ..controllers.registry import PAPER_KINDS, registered_law

    kind = f"controller.kind = {c.kind!r}"
    if registered_law(c.kind) is not None:  # its own parameters; it may read subtasks and nominal
        mark(["controller.Kp", "controller.Kv", "controller.k"], f"{kind} is not eq. (9)")
    elif not is_eq9(c.kind):
        mark(["controller.Kp", "controller.Kv", "controller.k", "subtasks."], f"{kind} is not eq. (9)")
        mark(["controller.coulomb_smoothing", "nominal.viscous_friction", "nominal.coulomb_friction"], kind)
    own = PAPER_KINDS[c.kind].keys if c.kind in PAPER_KINDS else ()
    for declared in PAPER_KINDS.values():  # the other kinds' own keys, unless this one reads them
        mark([key for key in declared.keys if key not in own], kind)
    for key, why in PAPER_KINDS[c.kind].ignores if c.kind in PAPER_KINDS else ():
        mark([key], why)
    if c.kind == "custom":
        mark(["controller.pinv_threshold", "controller.pinv_max_damping"], kind)
    if is_eq9(c.kind) and c.k == 0:
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
    if pc.torque_speed == "none":
        mark(["plant.torque_speed_knee"], "plant.torque_speed = 'none'")
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
    path_keys = {name: kind.keys for name, kind in PATH_KINDS.items()} | {"custom": ("class", "params")}
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
    from ..controllers.registry import registered_law

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


def _check_declared(config: ExperimentConfig, m: int) -> None:
    """The keys the paper's kinds read against their declarations (range, size, whole number,
    choice; nnrobust/controllers/registry.py: each kind's own, eq. (9)'s and the pseudo-inverse's),
    whichever kind runs; an unset key that the kind sizes itself (``default`` None) is not checked.
    """
    from ..controllers.registry import declared_params

    for p in declared_params():
        section, field = p.name.split(".")
        value = getattr(getattr(config, section), field)
        if not (value is None and p.default is None):
            p.check(value, None, m, p.name)


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

INDEXED = re.compile(r"^([a-z_]+)\.([A-Za-z_]+)\[(\d{1,4})\]$")
"""``section.field[i]``: one entry of a list-valued key (``nominal.factors[2]``)."""

FILLED_LISTS = {
    ("nominal", "factors"): 1.0,
    ("plant", "joint_friction_scales"): 1.0,
    ("plant", "joint_disturbance_scales"): 1.0,
}
"""List keys whose entries not given are known (a factor not given is 1): set entry by entry."""


def validate(config: ExperimentConfig) -> None:
    """Check values that a type alone does not constrain (robot-independent checks). It changes
    nothing: :func:`nnrobust.config.resolve` returns the normalised copy.
    """
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
    for folder in config.robot.mesh_folders or ():
        if not folder.strip() or os.path.abspath(folder) == os.path.abspath(os.sep):
            raise ConfigError(
                "robot.mesh_folders",
                f"{folder!r} is not a folder to read meshes from: name the folders that hold the "
                'URDF\'s meshes (e.g. ["../meshes"]), never the filesystem root',
            )
    choices = {
        "robot.task": (config.robot.task, tuple(TASK_KINDS)),
        "nominal.kind": (config.nominal.kind, ("auto", "closed-form", "urdf")),
        "plant.friction": (config.plant.friction, ("urdf", "scaled")),
        "plant.disturbance": (
            config.plant.disturbance,
            ("auto", *sorted(DISTURBANCE_KINDS), "custom"),
        ),
        "plant.engine": (config.plant.engine, ENGINES),
        "plant.mujoco_integrator": (config.plant.mujoco_integrator, MUJOCO_INTEGRATORS),
        "plant.torque_speed": (config.plant.torque_speed, ("none", "urdf")),
        "controller.kind": (c.kind, controller_kinds()),
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
    _check_gain_sizes(c, m, where)
    _check_declared(config, m)
    _check_eq17(c, m)
    _check_user_classes(config)
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
        from ..plant.loads import parse_loads

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
    _positive("simulation.memory_limit", sim.memory_limit)
    if config.plant.disturbance == "sinusoid" and (
        config.plant.disturbance_amplitude is None or config.plant.disturbance_omega is None
    ):
        raise ConfigError(
            "plant.disturbance_amplitude",
            "disturbance = 'sinusoid' needs disturbance_amplitude (n x K) and disturbance_omega (K)",
        )
