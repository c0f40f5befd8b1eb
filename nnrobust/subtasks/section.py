"""The subtasks room's section of an experiment file: ``[subtasks]``, the self-motion criteria of
eq. (4) and their weights. Its builder: :func:`nnrobust.subtasks.build.build_criterion`.
"""

from __future__ import annotations

from dataclasses import dataclass, field


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
