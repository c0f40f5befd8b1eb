"""The subtasks room's section of an experiment file: ``[subtasks]``, the self-motion criteria of
eq. (4) and their weights. Its builder: :func:`nnrobust.subtasks.build.build_criterion`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

from ..core.exceptions import ConfigError
from ..core.key_checks import DeclaredKeys, require_non_negative, require_positive
from .registry import CRITERION_KINDS, default_criteria


@dataclass
class SubtaskConfig(DeclaredKeys):
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
    SECTION: ClassVar[str] = "subtasks"

    @classmethod
    def kind_params(cls):
        """The keys the criteria declare."""
        return (p for kind in CRITERION_KINDS.values() for p in kind.params)


def check_subtasks(sc: SubtaskConfig) -> None:
    """The rules that read only ``[subtasks]``: eq. (4)'s weights sum to C, the obstacles' spheres
    (the criteria's names are checked when the criterion is built). Changes nothing.
    """
    sc.check_declared(3)  # a criterion's own keys (none is sized per task row)
    require_positive("subtasks.C", sc.C)
    require_positive("subtasks.obstacle_influence", sc.obstacle_influence)
    require_non_negative("subtasks.link_radius", sc.link_radius)
    for i, sphere in enumerate(sc.obstacles):
        if len(sphere) != 4 or sphere[3] < 0:
            raise ConfigError(f"subtasks.obstacles[{i}]", f"must be [x, y, z, radius >= 0], got {sphere}")
    if sc.weights is not None and sc.criteria is None:
        raise ConfigError("subtasks.weights", "weigh criteria that are named: set subtasks.criteria too")
    if "obstacles" in (sc.criteria or []) and not sc.obstacles:
        raise ConfigError("subtasks.obstacles", "criterion 'obstacles' needs at least one sphere")
    if sc.weights is not None:
        named = sc.criteria or []
        if len(sc.weights) != len(named):
            raise ConfigError("subtasks.weights", f"{len(sc.weights)} weights for {len(named)} criteria")
        require_positive("subtasks.weights", sc.weights)
        total = sum(sc.weights)
        if not math.isclose(total, sc.C, rel_tol=1e-9):
            raise ConfigError(
                "subtasks.weights",
                f"sum to {total:g} but subtasks.C = {sc.C:g}; eq. (4) needs sum w_i = C "
                "(or leave weights out for C / number of criteria each)",
            )


def inert_subtask_keys(sc: SubtaskConfig, task: str) -> dict[str, str]:
    """The ``[subtasks]`` keys of criteria that are not among the chosen ones (``subtasks.criteria``,
    or the defaults of a ``task`` task: :func:`nnrobust.subtasks.registry.default_criteria`).
    """
    criteria = sc.criteria if sc.criteria is not None else default_criteria(3, task)
    inert: dict[str, str] = {}
    if "obstacles" not in criteria:
        why = "'obstacles' is not in subtasks.criteria"
        inert |= dict.fromkeys(
            ["subtasks.obstacles", "subtasks.obstacle_influence", "subtasks.link_radius"], why
        )
    if "joint_smoothness" not in criteria:
        inert["subtasks.smoothness_coefficients"] = "'joint_smoothness' is not in subtasks.criteria"
    for name, kind in CRITERION_KINDS.items():  # the keys a criterion declares, while it is not chosen
        if name not in criteria:
            inert |= {p.name: f"{name!r} is not in subtasks.criteria" for p in kind.params}
    return inert
