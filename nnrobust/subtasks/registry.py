"""The shipped self-motion criteria, each declared once beside its class: its configuration name
(``subtasks.criteria``), a description, its unit, how an experiment builds it, and the fields its
compiled twin (csrc/subtasks/, registered under the same name) is built from. The config checks,
the docs' list, the figures' units and the compiled spec read these declarations.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..core.kinds import Kinds
from ..core.twins import field_array
from .base import Criterion


@dataclass(frozen=True)
class CriterionKind:
    """A shipped criterion.

    Attributes:
        name: its name in ``subtasks.criteria`` and of its compiled twin.
        cls: its class (how a built criterion is recognised).
        description: one line, with the equation (docs, figure titles).
        unit: its unit for a task of size m (matplotlib text).
        build: ``build(subtasks_section, robot)`` -> the criterion (a ConfigError names the key at
            fault).
        twin_fields: ``twin_fields(criterion)`` -> its numbers by name, as the twin reads them
            (2-D arrays; a number is 1 x 1, a vector k x 1); None: no compiled twin.
        det: whether it reads det(J J^T) (its twin is compiled for planar and position tasks).
        params: the ``[subtasks]`` keys it reads beyond the section's fields, each declared
            (:class:`nnrobust.core.key_checks.LawParam`, named ``subtasks.KEY``): a valid key of any
            experiment, defaulted, range-checked and inert while the criterion is not chosen.
        twin_source: the C++ file of a twin compiled apart (a criterion declared outside
            nnrobust, docs/extending.md#a-twin-in-c); None: the twin is shipped.

    """

    name: str
    cls: type
    description: str
    unit: Callable[[int], str]
    build: Callable[[Any, Any], Criterion]
    twin_fields: Callable[[Any], dict[str, Any]] | None = None
    det: bool = False
    params: tuple[Any, ...] = ()
    twin_source: str | Path | None = None

    def twin_values(self, criterion: Criterion) -> dict[str, np.ndarray]:
        """The twin's fields as 2-D float arrays (what LoopSpec.criterion_params carries)."""
        assert self.twin_fields is not None, self.name
        return {key: field_array(value) for key, value in self.twin_fields(criterion).items()}


CRITERION_KINDS: Kinds[CriterionKind] = Kinds("criterion")
"""The shipped criteria by name, in the order their modules declare them."""

declare = CRITERION_KINDS.declare
"""Register criteria (at the end of the module that defines their classes)."""


def kind_of(criterion: Criterion) -> CriterionKind | None:
    """The declaration of a built criterion (by its class), or None for a user's."""
    return next((k for k in CRITERION_KINDS.values() if type(criterion) is k.cls), None)


def criterion_unit(name: str, m: int) -> str:
    """The unit of the criterion ``name`` for a task of size m ("mixed" for a user's)."""
    kind = CRITERION_KINDS.get(name)
    return kind.unit(m) if kind is not None else "mixed"


def default_criteria(n: int, task: str) -> list[str]:
    """``subtasks.criteria`` when it is not given: the paper's eq. (19) on a three-joint planar
    arm, else manipulability and joint-limit avoidance (joint limits alone on a pose task, where
    the manipulability of a 6 x n Jacobian mixes metres and radians).
    """
    if n == 3 and task == "planar":
        return ["paper"]
    return ["joint_limits"] if task == "pose" else ["manipulability", "joint_limits"]
