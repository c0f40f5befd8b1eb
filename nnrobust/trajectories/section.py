"""The trajectories room's section of an experiment file: ``[trajectory]``, with its keys, types,
defaults and choices. Its builder: :func:`nnrobust.trajectories.build.build_trajectory`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

from ..core.exceptions import ConfigError
from ..core.key_checks import DeclaredKeys, check_choice
from .registry import PATH_KINDS, path_key


@dataclass
class TrajectoryConfig(DeclaredKeys):
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
    SECTION: ClassVar[str] = "trajectory"

    @classmethod
    def kind_params(cls):
        """The keys the paths declare."""
        return (p for kind in PATH_KINDS.values() for p in kind.params)

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


MIN_AXIS_NORM = 1e-9
"""Shortest ``trajectory.rotation_axis`` accepted: its direction is its only meaning, and a
vector of 1e-320 has a length that squares to 0 (no direction to normalise to)."""


def check_trajectory(tc: TrajectoryConfig) -> None:
    """The rules that read only ``[trajectory]``: its kind, and a shipped path's keys (their
    extents, then the path's declared checks) with 2 or 3 entries per point. Changes nothing.
    """
    check_choice("trajectory.kind", tc.kind, (*PATH_KINDS, "custom"))  # as declared now
    if tc.kind == "custom":
        return
    _check_extents(tc)
    PATH_KINDS[tc.kind].check(tc)
    if tc.dimension not in (2, 3):
        raise ConfigError(
            f"trajectory.{path_key(tc)}",
            f"path points have 2 (x, y) or 3 (x, y, z) entries, got {tc.dimension}",
        )
    tc.check_declared(tc.dimension)


def check_orientation(tc: TrajectoryConfig) -> None:
    """The rules of a pose task's orientation keys (``orientation_rpy``, ``rotation_axis``)."""
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


def inert_trajectory_keys(tc: TrajectoryConfig) -> dict[str, str]:
    """The ``[trajectory]`` keys of the paths (and of a user's class) other than the chosen one."""
    path_keys = {name: kind.keys for name, kind in PATH_KINDS.items()} | {"custom": ("class", "params")}
    why = f"trajectory.kind = {tc.kind!r}"
    return {f"trajectory.{k}": why for other, keys in path_keys.items() if other != tc.kind for k in keys}
