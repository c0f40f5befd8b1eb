"""The one shape of every registry of kinds: the paper's control laws, the registered laws, the
criteria, the paths and the disturbances are each a :class:`Kinds` — a dictionary from the name
an experiment file gives a kind (``controller.kind``, ``subtasks.criteria``, ``trajectory.kind``,
``plant.disturbance``) to its declaration, filled by the modules that define the kinds, in
declaration order. The one discovery rule: a room's package face imports every module of its
kinds' package (:func:`import_modules`), so a kind is known once its room is imported. The C++
twins register under the same names. A leaf module.
"""

from __future__ import annotations

import pkgutil
from importlib import import_module
from typing import Generic, TypeVar

T = TypeVar("T")


class Kinds(dict[str, T], Generic[T]):
    """The kinds of one concept by name (a dict), declared beside their code."""

    def __init__(self, concept: str):
        super().__init__()
        self.concept = concept

    def declare(self, *kinds: T) -> None:
        """Add kinds by their ``name``; a second kind of the same name is refused (the same
        declaration made again, as a module imported twice makes it, is not).
        """
        for kind in kinds:
            name = kind.name  # type: ignore[attr-defined]
            known = self.get(name)
            if known is not None and known is not kind and known != kind:
                raise ValueError(f"a {self.concept} named {name!r} is already declared")
            self[name] = kind


def import_modules(package: str, path) -> None:
    """Import every module of ``package`` (its ``__path__``): each declares its kinds."""
    for module in pkgutil.iter_modules(path):
        import_module(f"{package}.{module.name}")
