"""The registries of control laws declared beside their code (docs/extending.md).

The paper's law and its baselines (``nn``, ``no-u0``, ``computed-torque``, ``sliding-mode``,
``pd``) are :class:`PaperKind` declarations in the modules that hold their code: each says what its
robust term and nominal model are, whether it is eq. (9), the configuration keys it alone reads,
its builder and its robust term's search coordinates. ``controller.kind``'s built-in choices, the
keys a configuration leaves inert, the controller builder, the tuner's search spaces and
docs/controller.md's table of them derive from those declarations. Their numbers are the flat keys
of ``[controller]`` and ``[nn]`` (nnrobust/config/schema.py), as the paper's experiment files
have them.

A registered law is a :class:`nnrobust.Controller` built as ``Class(context, **params)`` from an
experiment's ``controller.kind = NAME`` and ``[controller.params]``. Its module declares, once,
with :func:`register_law`: its name, its parameters (unit, default, range, size, search bounds),
its class and its compiled twin; every module of nnrobust/controllers/laws/ is imported to find
them. The configuration checks, ``nnrobust run --help``, the tuner's search space, the docs' key
reference (docs/controller.md, written by docs/render_tables.py) and the compiled loop's spec
are derived from that declaration, so adding a law touches its Python file, its C++ twin
(csrc/controllers/laws/) and its tests.
"""

from __future__ import annotations

import difflib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core.exceptions import ConfigError, NNRobustError
from ..core.key_checks import CHOSEN, LawParam
from ..core.kinds import Kinds
from ..core.twins import twin_values
from ..plugins.user_code import located

__all__ = ["CHOSEN", "LawParam"]  # the one way any kind declares a key, in the leaf key_checks


@dataclass(frozen=True)
class Law:
    """A control law as the registry knows it.

    Attributes:
        name: the value of ``controller.kind``.
        cls: the :class:`nnrobust.Controller` subclass, built as ``cls(context, **params)``.
        summary: one line for the CLI help and the docs.
        params: its parameters, in the constructor's order.
        twin: the name its compiled twin registers under in csrc/controllers/laws/ (None: Python only).
        twin_fields: the attributes of a built controller the twin reads (each a number, a
            vector or a matrix), by name: the one list of what crosses to C++.
        twin_source: the C++ file of a twin compiled apart (a law registered outside nnrobust,
            docs/extending.md#a-twin-in-c); None: the twin is shipped.

    """

    name: str
    cls: type
    summary: str
    params: tuple[LawParam, ...]
    twin: str | None = None
    twin_fields: tuple[str, ...] = field(default=())
    twin_source: str | Path | None = None

    def param(self, name: str) -> LawParam | None:
        """The declared parameter of this name, or None."""
        return next((p for p in self.params if p.name == name), None)

    def resolve(self, params: dict | None, n: int | None, m: int) -> dict:
        """Every parameter's value: the given ones checked, the others at their defaults (n None:
        the sizes of per-joint parameters are checked when the robot is built).
        """
        given = dict(params or {})
        unknown = [k for k in given if self.param(k) is None]
        if unknown:
            names = [p.name for p in self.params]
            close = difflib.get_close_matches(unknown[0], names, n=1)
            raise ConfigError(
                f"controller.params.{unknown[0]}",
                f"{self.name} has no parameter {unknown[0]!r}"
                + (f"; did you mean {close[0]!r}?" if close else ".")
                + f" Its parameters: {', '.join(names)}",
            )
        out = {}
        for p in self.params:
            if p.name in given:
                out[p.name] = p.check(given[p.name], n, m, f"controller.params.{p.name}")
            else:
                out[p.name] = p.default
        return out

    def build(self, context, params: dict | None):
        """``cls(context, **params)`` with every parameter checked and defaulted; an error of the
        constructor names ``controller.params``.
        """
        resolved = self.resolve(params, context.n, context.m)
        try:
            return self.cls(context, **resolved)
        except NNRobustError:
            raise
        except Exception as err:
            raise ConfigError(
                "controller.params", f"{self.cls.__name__}(context, **params) raised {located(err)}"
            ) from err

    def twin_values(self, controller) -> dict[str, np.ndarray]:
        """The twin's fields of a built controller, each as a 2-D float array (a number 1 x 1,
        a vector k x 1): what the compiled law reads by name (csrc/controllers/laws/law.hpp).
        """
        return twin_values(controller, self.twin_fields)


@dataclass(frozen=True)
class KindParts:
    """What a :class:`PaperKind` is built from: the ``[controller]`` and ``[nn]`` sections
    (:mod:`nnrobust.controllers.section`), the robot, the controller's nominal model, the
    trajectory, the weighted criterion (or None), the true robot's friction (computed torque's
    F-hat) and the :class:`~nnrobust.controllers.ControllerContext`.
    """

    controller: Any
    nn: Any
    robot: Any
    nominal: Any
    trajectory: Any
    criterion: Any
    true_friction: Any
    context: Any


@dataclass(frozen=True)
class PaperKind:
    """One of the paper's law and its baselines, declared beside its code.

    Attributes:
        name: the value of ``controller.kind``.
        u0: its robust term u_0, one line for the docs.
        nominal: the nominal model and friction it uses, one line for the docs.
        build: ``build(parts: KindParts) -> Controller``.
        eq9: whether it is eq. (9)'s task-space law (it reads ``controller.Kp``, ``Kv``, ``k``,
            the subtasks and the nominal friction).
        lyapunov: whether its robust term is built on eq. (16)'s P (w = B^T P y), which needs
            eq. (17)'s Q positive definite: Kv^2 > Kp is then checked, and the tuner's damping
            ratio stops at 0.51 (a physical bound). eq. (9) without such a term needs only Kv > 0.
        keys: its own configuration keys, beyond eq. (9)'s (``section.key``, or ``section.`` for
            a whole section): inert under a kind that does not declare them too.
        ignores: (key, why) of keys that it leaves inert although eq. (9) reads them.
        search: ``search(scales) -> [search_coordinates.Param, ...]``, its robust term's search coordinates
            beside the gains (None: the gains alone).
        search_keys: ``search_keys(values) -> {key: value}``: the configuration keys its search
            coordinates that are not keys themselves set (a rate that is a product of two keys,
            a key held to another), from every coordinate's value (None: its coordinates are keys).
        params: its own keys' declarations (a :class:`LawParam` named by the key,
            ``section.field``): the configuration's defaults, its checks and docs/controller.md's
            key reference read them.

    """

    name: str
    u0: str
    nominal: str
    build: Callable[[KindParts], Any]
    eq9: bool = True
    lyapunov: bool = False
    keys: tuple[str, ...] = ()
    ignores: tuple[tuple[str, str], ...] = ()
    search: Callable[[dict], list] | None = None
    search_keys: Callable[[dict], dict] | None = None
    params: tuple[LawParam, ...] = ()


@dataclass(frozen=True)
class SharedKeys:
    """Keys that several of the paper's kinds read, declared beside the code that reads them
    (eq. (9)'s gains in task_space.py, the pseudo-inverse's in pseudoinverse.py).

    Attributes:
        owner: what reads them, for the docs ("eq. (9)").
        params: their declarations (a :class:`LawParam` named by the key, ``section.field``).
        readers: which laws read them, for the docs; None: the kinds of eq. (9), as declared.

    """

    owner: str
    params: tuple[LawParam, ...]
    readers: str | None = None

    def reader_names(self) -> str:
        """``readers``, or the declared kinds of eq. (9)."""
        if self.readers is not None:
            return self.readers
        return ", ".join(name for name in paper_kinds() if PAPER_KINDS[name].eq9)


SHARED_KEYS: list[SharedKeys] = []
"""The shared keys' declarations, filled when nnrobust.controllers is imported."""


def declare_shared(keys: SharedKeys) -> SharedKeys:
    """Add a declaration of shared keys (its module calls this once, at import)."""
    if keys not in SHARED_KEYS:
        SHARED_KEYS.append(keys)
    return keys


def declared_params() -> list[LawParam]:
    """Every key the paper's kinds declare: the shared ones, then each kind's own."""
    paper_kinds()
    return [p for shared in SHARED_KEYS for p in shared.params] + [
        p for kind in PAPER_KINDS.values() for p in kind.params
    ]


PAPER_KINDS: Kinds[PaperKind] = Kinds("controller kind")
"""The paper's kinds by name, in declaration order (filled when nnrobust.controllers is imported)."""


def declare_kind(kind: PaperKind) -> PaperKind:
    """Add one of the paper's kinds (its module calls this once, at import)."""
    PAPER_KINDS.declare(kind)
    return kind


def paper_kinds() -> tuple[str, ...]:
    """The names of the paper's kinds (``nn``, ``no-u0``, ...), in declaration order."""
    from . import (
        task_space,  # noqa: F401  (their declarations)
    )

    return tuple(PAPER_KINDS)


def shipped_laws() -> tuple[str, ...]:
    """The laws nnrobust ships: the paper's kinds and the registered laws
    (nnrobust/controllers/laws/), as declared now.
    """
    return (*paper_kinds(), *law_names())


def controller_kinds() -> tuple[str, ...]:
    """Every valid ``controller.kind``: the shipped laws and ``custom``."""
    return (*shipped_laws(), "custom")


def declared_key(key: str) -> LawParam:
    """The declaration of one of the keys the paper's kinds read (``section.field``)."""
    for p in declared_params():
        if p.name == key:
            return p
    raise KeyError(f"no kind declares the key {key!r}")


def declared_default(key: str) -> Any:
    """The declared default of one of the keys the paper's kinds read, as the configuration holds
    it (a list for a vector).
    """
    return declared_key(key).config_default


def paper_kind(name: str) -> PaperKind | None:
    """The declaration of the paper's kind ``name``, or None."""
    paper_kinds()
    return PAPER_KINDS.get(name)


LAWS: Kinds[Law] = Kinds("control law")
"""The registered laws by name, filled as their modules are imported (:func:`registered_law`
imports every module of nnrobust/controllers/laws/ once)."""


def register_law(law: Law) -> Law:
    """Add a law to the registry (its module calls this once, at import)."""
    LAWS.declare(law)
    return law


def registered_law(name: str) -> Law | None:
    """The registered law named ``name`` (``controller.kind``), or None (the laws' package,
    imported with the room, has declared every law: nnrobust.core.kinds).
    """
    from . import laws  # noqa: F401  (imported with nnrobust.controllers: a no-op here)

    return LAWS.get(name)


def law_names() -> tuple[str, ...]:
    """The names of the registered laws, in registration order."""
    registered_law("")
    return tuple(LAWS)
