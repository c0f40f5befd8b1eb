"""The experiment schema: the composition of the rooms' sections (each room declares its own: the
keys of an experiment file, their types and defaults) with ``[simulation]``, and what a
configuration implies across sections (its nominal model, its controller's label, m). Reading
and writing TOML is :mod:`.toml_io`; checking values is :mod:`.checks`.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import typing
from dataclasses import dataclass, field

from ..controllers.section import ControllerConfig, NNConfig
from ..core.numeric_limits import MAX_STEP_ROTATION
from ..model.section import NominalConfig, RobotConfig, resolved_nominal_kind
from ..model.tasks import TASK_KINDS
from ..plant.section import PlantConfig, SensingConfig
from ..subtasks.section import SubtaskConfig
from ..trajectories.section import TrajectoryConfig

KEY_ALIASES = {"class": "class_"}
"""TOML keys that are Python keywords, and the field each is stored in."""


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
                out[name].update(copy.deepcopy(getattr(value, "extra", None) or {}))  # kinds' keys
            elif value is not None:
                out[name] = value
        return out

    def to_toml(self) -> str:
        """TOML text that :func:`load_config` reads back to an equal configuration."""
        from .toml_io import dump_toml  # here: toml_io imports this module

        return dump_toml(self.to_dict())

    def replace(self, **sections) -> ExperimentConfig:
        """A copy with some fields changed: ``replace(controller={"kind": "pd"})``."""
        data = self.to_dict()
        for key, value in sections.items():
            if isinstance(value, dict):
                data.setdefault(key, {}).update(value)
            else:
                data[key] = value
        from .toml_io import from_dict  # here: toml_io imports this module

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
    """``nominal.kind`` resolved (:func:`nnrobust.model.section.resolved_nominal_kind`)."""
    return resolved_nominal_kind(config.nominal, config.robot)


def disturbance_kind(config: ExperimentConfig) -> str:
    """``plant.disturbance`` resolved: ``auto`` is the paper's tau_d on the paper's arm
    (``three_link_planar``), the arm-scaled harmonics on every other arm.
    """
    kind = config.plant.disturbance
    if kind == "auto":
        return "paper" if config.robot.source == "three_link_planar" else "scaled"
    return kind


def task_rows(config: ExperimentConfig) -> int:
    """m, the task coordinates a configuration implies: 6 on a pose task, else the entries of its
    path's points (a custom trajectory: the task's, 2 planar or 3 position).
    """
    if config.robot.task == "pose":
        return 6
    if config.trajectory.kind == "custom":
        return TASK_KINDS.get(config.robot.task, 2)
    return config.trajectory.dimension


_FIELD_NAMES: dict[typing.Any, list[str]] = {}


def _field_names(cls: typing.Any) -> list[str]:
    """A config dataclass's field names (its keys; ``extra`` holds the kinds' declared keys),
    listed once per class.
    """
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = [f.name for f in dataclasses.fields(cls) if f.name != "extra"]
    return names
