"""The shipped position paths, each declared once beside its class: its name in
``trajectory.kind``, what it is, the keys it reads, their checks, and how an experiment builds
it. The configuration's choices and checks, the keys a configuration leaves inert, the builder
and docs/robots.md's table read these declarations. A path's compiled twin is declared on its
class, ``twin`` and ``twin_fields``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..core.kinds import Kinds
from .base import Trajectory


@dataclass(frozen=True)
class PathKind:
    """A shipped position path.

    Attributes:
        name: its name in ``trajectory.kind``.
        description: x_d(t) in one line (docs, errors).
        keys: the ``[trajectory]`` keys it reads; the first places the path (errors about the
            path's size name it).
        keys_doc: the keys with their meaning, one line (docs).
        check: ``check(trajectory_config)``: its keys' values (a ConfigError names the key).
        dimension: ``dimension(trajectory_config)``: entries of a path point (2 or 3 are valid).
        build: ``build(trajectory_section, robot, q_seed)`` -> the path (``q_seed``:
            ``simulation.q_seed``, where a path that starts where the arm is reads the start).
        params: the ``[trajectory]`` keys it reads beyond the section's fields, each declared
            (:class:`nnrobust.core.key_checks.LawParam`, named ``trajectory.KEY``; list them in
            ``keys`` too): defaulted, range-checked, inert under another path.

    """

    name: str
    description: str
    keys: tuple[str, ...]
    keys_doc: str
    check: Callable[[Any], None]
    dimension: Callable[[Any], int]
    build: Callable[[Any, Any, Any], Trajectory]
    params: tuple[Any, ...] = ()


PATH_KINDS: Kinds[PathKind] = Kinds("path")
"""The shipped paths by name, in the order their modules declare them."""

declare = PATH_KINDS.declare
"""Register paths (in the module that defines their class)."""


def path_key(trajectory) -> str:
    """The key of a ``[trajectory]`` section that places the path: center, goal, waypoints (or
    class, for a user's).
    """
    kind = PATH_KINDS.get(trajectory.kind)
    return kind.keys[0] if kind is not None else "class" if trajectory.kind == "custom" else "center"
