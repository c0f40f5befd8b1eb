"""Checks that only check: the values of a typed configuration that a type alone does not
constrain (ranges, sizes, consistency between keys), each a one-line ConfigError naming the key;
and which keys a configuration leaves inert. Each room checks its own sections (``check_model``,
``check_plant``, ``check_subtasks``, ``check_trajectory``, ``check_controller``, in the room's
``section`` module); here are the rules that read two sections, and ``[simulation]``'s. Nothing
here changes a configuration.
"""

from __future__ import annotations

import re

from ..controllers.registry import registered_law
from ..controllers.section import check_controller, inert_controller_keys
from ..core.exceptions import ConfigError
from ..core.key_checks import check_choice, require_positive
from ..core.numeric_limits import MAX_FACTOR, MAX_PAYLOAD, MAX_PHYSICAL, MAX_STOP_STIFFNESS
from ..model.section import check_model, inert_model_keys
from ..model.tasks import TASK_KINDS
from ..plant.loads import parse_loads
from ..plant.section import check_plant, inert_plant_keys
from ..subtasks.section import check_subtasks, inert_subtask_keys
from ..trajectories import path_key
from ..trajectories.section import MAX_PATH_EXTENT, check_orientation, check_trajectory, inert_trajectory_keys
from .schema import USER_PARTS, ExperimentConfig, _user_part

__all__ = [  # the limits the rooms' rules use, re-exported with the configuration's own
    "MAX_FACTOR",
    "MAX_PAYLOAD",
    "MAX_PHYSICAL",
    "MAX_STOP_STIFFNESS",
]


MAX_SUBSTEPS = 10_000
MAX_STEPS = 1e9
"""Bounds that no sensible experiment reaches; the memory estimate (experiment.check_memory)
refuses most oversized runs long before them."""

NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]{0,99}")
"""An experiment's name: it names the default run folder, out/<name>-<controller>."""


CLASS_PATTERN = re.compile(r"(?P<where>[^:]+):(?P<name>[A-Za-z_][A-Za-z0-9_]*)")
"""A user's class (``controller.class``, ``trajectory.class``, ...): ``file.py:Class`` or
``package.module:Class``."""


def inert_keys(config: ExperimentConfig) -> dict[str, str]:
    """Keys (``section.key``, or ``section.`` for a whole section) that this configuration does
    not read, each with the choice that makes it so: a key set here changes nothing. Each room
    says which of its keys its own choices leave unread; here are the rules across sections.
    """
    pc, sim, task = config.plant, config.simulation, config.robot.task
    inert: dict[str, str] = {}

    def mark(keys, why):
        for key in keys:
            inert.setdefault(key, why)

    def take(room: dict[str, str]):
        for key, why in room.items():
            inert.setdefault(key, why)

    take(inert_controller_keys(config.controller, config.nn))
    take(inert_model_keys(config.robot, config.nominal))
    take(inert_plant_keys(pc))
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
    take(inert_trajectory_keys(config.trajectory))
    if task != "pose":
        mark(
            [f"trajectory.{k}" for k in ("orientation_rpy", "rotation_axis", "rotation_amplitude",
                                         "rotation_omega", "rotation_phase")],
            f"robot.task = {task!r}",
        )  # fmt: skip
    take(inert_subtask_keys(config.subtasks, task))
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


MIN_STEP_ROTATION = 1e-6
"""Smallest ``simulation.max_step_rotation`` [rad or m]: below it every fast period is cut to the
most steps a period may take, and a run crawls (1e-300 ran 46x slower than real time)."""
INDEXED = re.compile(r"^([a-z_]+)\.([A-Za-z_]+)\[(\d{1,4})\]$")
"""``section.field[i]``: one entry of a list-valued key (``nominal.factors[2]``)."""

FILLED_LISTS = {
    ("nominal", "factors"): 1.0,
    ("plant", "joint_friction_scales"): 1.0,
    ("plant", "joint_disturbance_scales"): 1.0,
    ("plant", "region_coordinates"): 0.0,
}
"""List keys whose entries not given are known (a factor not given is 1, a box's coordinate 0):
set entry by entry."""


def validate(config: ExperimentConfig) -> None:
    """Check values that a type alone does not constrain (robot-independent checks): each room's
    own rules on its sections (:func:`check_model`, :func:`check_plant`, :func:`check_subtasks`,
    :func:`check_trajectory`, :func:`check_controller`), then the rules that read two sections
    and ``[simulation]``'s. It changes nothing: :func:`nnrobust.config.resolve` returns the
    normalised copy.
    """
    sim, tc, task = config.simulation, config.trajectory, config.robot.task
    if not NAME_PATTERN.fullmatch(config.name) or ".." in config.name:
        raise ConfigError(
            "name",
            f"{config.name!r} is not a valid name: 1 to 100 letters, digits, '.', '_', "
            "'+' or '-', starting with a letter or digit, without '..' (it names the run "
            "folder out/<name>-<controller>)",
        )
    check_model(config.robot, config.nominal)
    check_plant(config.plant, config.sensing)
    check_subtasks(config.subtasks)
    check_trajectory(tc)
    check_choice("simulation.integrator", sim.integrator, ("rk4", "solve_ivp"))
    check_choice("simulation.backend", sim.backend, ("auto", "compiled", "hybrid", "python"))
    if tc.kind == "custom":
        if task == "pose":
            raise ConfigError(
                "trajectory.kind",
                "a custom trajectory is for planar and position tasks; a pose task takes the "
                "shipped paths with their orientation (ellipse, point_to_point, waypoints)",
            )
        m, where = TASK_KINDS[task], f"the {task} task has m = {TASK_KINDS[task]}"
    elif task != "pose":
        m, where = tc.dimension, f"the task has m = {tc.dimension} (trajectory.{path_key(tc)})"
    else:
        if tc.dimension != 3:
            raise ConfigError(
                f"trajectory.{path_key(tc)}", f"a pose task needs a 3-D path, got {tc.dimension} entries"
            )
        check_orientation(tc)
        m, where = 6, "the pose task has m = 6"
    check_controller(config.controller, config.nn, m, where)
    _check_user_classes(config)
    pc, se = config.plant, config.sensing
    if pc.engine == "mujoco" and sim.integrator != "rk4":
        raise ConfigError(
            "simulation.integrator",
            f"{sim.integrator!r} integrates the pinocchio engine; "
            "MuJoCo has its own (plant.mujoco_integrator)",
        )
    if se.delay > 0 and sim.control_period > 0 and se.delay * sim.control_period >= sim.duration > 0:
        raise ConfigError(
            "sensing.delay",
            f"{se.delay} control periods is the whole run ({sim.duration:g} s) or more: no command "
            "computed from a measurement would reach the actuators",
        )
    require_positive("simulation.duration", sim.duration)
    require_positive("simulation.control_period", sim.control_period)
    if sim.substeps is not None:
        require_positive("simulation.substeps", sim.substeps)
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
        require_positive("simulation.integration_step", sim.integration_step)
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
    if pc.loads:
        parse_loads(pc.loads, sim.control_period)
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
    require_positive("simulation.memory_limit", sim.memory_limit)
