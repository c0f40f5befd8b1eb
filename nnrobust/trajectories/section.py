"""The trajectories room's section of an experiment file: ``[trajectory]``, with its keys, types,
defaults and choices. Its builder: :func:`nnrobust.trajectories.build.build_trajectory`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .registry import PATH_KINDS


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
