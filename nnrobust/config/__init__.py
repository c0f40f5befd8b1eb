"""Experiment configuration, in four rooms: :mod:`.schema` (the typed sections and what a
configuration implies), :mod:`.toml_io` (experiment files in and out, with overrides and
provenance), :mod:`.checks` (checks that only check) and :mod:`.resolve` (the normalised copy
of a checked configuration). Everything is importable from here.
"""

from ..controllers.registry import controller_kinds, shipped_laws  # the rooms' own rules, re-exported
from ..controllers.section import CONTROLLER_KINDS, EQ9_KINDS, ControllerConfig, NNConfig, is_eq9
from ..core.numeric_limits import MAX_CENTERS, MAX_GAIN, MAX_PINV, RANGE_LIMITS
from ..model.section import NominalConfig, RobotConfig
from ..plant.section import PlantConfig, SensingConfig
from ..subtasks.registry import default_criteria
from ..subtasks.section import SubtaskConfig
from ..trajectories.piecewise import MAX_WAYPOINTS, MIN_MOVE_TIME  # the paths' own limits
from ..trajectories.registry import path_key
from ..trajectories.section import MAX_PATH_EXTENT, MAX_PATH_RATE, TRAJECTORY_KINDS, TrajectoryConfig
from .checks import (
    CLASS_PATTERN,
    FILLED_LISTS,
    INDEXED,
    MAX_FACTOR,
    MAX_PAYLOAD,
    MAX_PHYSICAL,
    MAX_STEPS,
    MAX_STOP_STIFFNESS,
    MAX_SUBSTEPS,
    MIN_STEP_ROTATION,
    NAME_PATTERN,
    inert_keys,
    inert_reason,
    validate,
)
from .resolve import resolve
from .schema import (
    KEY_ALIASES,
    USER_PARTS,
    ExperimentConfig,
    SimulationConfig,
    controller_label,
    disturbance_kind,
    nominal_kind,
    step_rotation_limit,
    task_rows,
)
from .toml_io import (
    MAX_BASE_DEPTH,
    MAX_TOML_BYTES,
    RECORDED_DIGEST,
    _suggest,
    apply_overrides,
    check_dotted_key,
    dump_toml,
    from_dict,
    load_config,
    parse_override,
    parse_toml,
    provenance_header,
    read_text_file,
    user_classes,
    user_files,
)

__all__ = [
    "CLASS_PATTERN",
    "CONTROLLER_KINDS",
    "ControllerConfig",
    "EQ9_KINDS",
    "ExperimentConfig",
    "FILLED_LISTS",
    "INDEXED",
    "KEY_ALIASES",
    "MAX_BASE_DEPTH",
    "MAX_CENTERS",
    "MAX_FACTOR",
    "MAX_GAIN",
    "MAX_PATH_EXTENT",
    "MAX_PATH_RATE",
    "MAX_PAYLOAD",
    "MAX_PHYSICAL",
    "MAX_PINV",
    "MAX_STEPS",
    "MAX_STOP_STIFFNESS",
    "MAX_SUBSTEPS",
    "MAX_TOML_BYTES",
    "MAX_WAYPOINTS",
    "MIN_MOVE_TIME",
    "MIN_STEP_ROTATION",
    "NAME_PATTERN",
    "NNConfig",
    "NominalConfig",
    "PlantConfig",
    "RANGE_LIMITS",
    "RECORDED_DIGEST",
    "RobotConfig",
    "SensingConfig",
    "SimulationConfig",
    "SubtaskConfig",
    "TRAJECTORY_KINDS",
    "TrajectoryConfig",
    "USER_PARTS",
    "_suggest",
    "apply_overrides",
    "check_dotted_key",
    "controller_kinds",
    "controller_label",
    "disturbance_kind",
    "default_criteria",
    "dump_toml",
    "from_dict",
    "inert_keys",
    "inert_reason",
    "is_eq9",
    "load_config",
    "nominal_kind",
    "parse_override",
    "parse_toml",
    "path_key",
    "provenance_header",
    "read_text_file",
    "resolve",
    "shipped_laws",
    "step_rotation_limit",
    "task_rows",
    "user_classes",
    "user_files",
    "validate",
]
