"""How any kind declares a key of an experiment file, and the one-line checks every room's rules
are written with (a leaf module).

- :class:`LawParam`: one key a kind declares (a law's ``[controller.params]`` entry, a paper
  kind's flat key, a path's, criterion's or disturbance's key): unit, default, range, size,
  choices and the tuner's search coordinate; the configuration checks, the inert-key rules, the
  tuner and the docs' tables read it.
- :class:`DeclaredKeys`: a section whose kinds may declare keys beyond its dataclass fields; their
  values live in the section's ``extra`` table and read as attributes, defaulted by the
  declaration.
- a value among its choices, a positive or non-negative number, a physical coefficient, a seed:
  each raises a :class:`~nnrobust.core.exceptions.ConfigError` naming the key.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from .exceptions import ConfigError
from .numeric_limits import MAX_PHYSICAL


def check_choice(path: str, value: object, valid: Sequence[str]) -> None:
    """``value`` is one of ``valid``."""
    if value not in valid:
        raise ConfigError(path, f"{value!r} is not one of {', '.join(valid)}")


def require_positive(path: str, values) -> None:
    """A number, or every entry of a list, > 0."""
    seq = values if isinstance(values, list) else [values]
    if any(v <= 0 for v in seq):
        raise ConfigError(path, f"must be positive, got {values}")


def require_non_negative(path: str, value: float) -> None:
    """A number >= 0."""
    if value < 0:
        raise ConfigError(path, f"must be >= 0, got {value}")


def require_physical(path: str, values: list[float] | None, unit: str) -> None:
    """Each entry of a coefficient list (friction, inertial parameter) in [0, MAX_PHYSICAL]."""
    if values is not None and any(not 0 <= v <= MAX_PHYSICAL for v in values):
        raise ConfigError(path, f"each entry must be in [0, {MAX_PHYSICAL:g}] {unit}, got {values}")


def require_seed(path: str, seed: int) -> None:
    """A seed of numpy's generators: an integer in [0, 2^63)."""
    if not 0 <= seed < 2**63:
        raise ConfigError(path, f"must be an integer in [0, 2^63), got {seed}")


CHOSEN = "chosen by the experiment"
"""Why a text, file or true/false parameter is never searched: it picks a structure, not a level."""


@dataclass(frozen=True)
class LawParam:
    """One parameter of a registered law (a key of ``[controller.params]``).

    Attributes:
        name: the keyword argument of the law's constructor.
        default: its value when the experiment leaves it out (None: the law sizes it, as ``doc``
            says).
        unit: its unit ("-" for none).
        doc: one line on what it is.
        low, high: the range of every entry (numbers), closed unless ``low_open``.
        size: ``"1"`` (a number), ``"2"`` (two numbers), ``"m"`` (one or one per task
            coordinate) or ``"n"`` (one or one per joint).
        integer: the number must be whole.
        choices: the accepted strings, for a text parameter; or a function returning them, read
            when a value is checked (a list another registry holds, complete only once it is).
        search: (low, high) of the tuner's log-uniform search, or a function of the arm's scales
            (:func:`nnrobust.studies.tune.arm_scales`) returning them; None: not searched.
        low_reason, high_reason: why a search bound is physical (the tuner never widens it), or "".
            A search bound at the end of the range is physical by that alone: the tuner never
            widens a bound past the parameter's range.
        fixed: why the tuner does not search it (it runs at the experiment's value), for a
            parameter without ``search``; "" for a searched one. A text, file or true/false
            parameter needs none: it is chosen by the experiment (:attr:`fixed_reason`).
        weak: for a knob of a robust or adaptive term, the end (``low`` or ``high``) at which the
            term does least (the tuner's check that the term earns its place); "" for gains.
        low_open: the range excludes ``low`` (a positive gain: (0, high]).
        path: a text naming a file (read from the experiment file's folder when relative, its
            SHA-256 recorded with the run).

    """

    name: str
    default: float | str | bool | tuple[float, ...] | None
    unit: str
    doc: str
    low: float = -math.inf
    high: float = math.inf
    size: str = "1"
    choices: tuple[str, ...] | Callable[[], tuple[str, ...]] = ()
    integer: bool = False
    search: tuple[float, float] | Callable[[dict], tuple[float, float]] | None = None
    low_reason: str = ""
    high_reason: str = ""
    fixed: str = ""
    weak: str = ""
    low_open: bool = False
    path: bool = False

    @property
    def fixed_reason(self) -> str:
        """Why the tuner holds it at the experiment's value: ``fixed``, or :data:`CHOSEN` for a
        text, file or true/false parameter (a structure, not a level to search); "" for a
        searched parameter, and for a number that declares no reason (tests/studies/tune/test_engine.py
        fails on one).
        """
        if self.search is not None:
            return ""
        if self.fixed:
            return self.fixed
        return CHOSEN if self.path or self.choices or isinstance(self.default, bool) else ""

    @property
    def allowed(self) -> tuple[str, ...]:
        """The accepted strings of a text parameter (``choices``, called when it is a function)."""
        return tuple(self.choices()) if callable(self.choices) else self.choices

    @property
    def config_default(self) -> Any:
        """The default as a configuration holds it (a list for a vector)."""
        return list(self.default) if isinstance(self.default, tuple) else self.default

    @property
    def range(self) -> str:
        """The accepted range as text: ``[0, 1e+12]``, ``(0, 1e+12]``."""
        return f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}]"

    def check(self, value, n: int | None, m: int, key: str):
        """The value checked and normalised (a float, a vector of its size, a bool or a string)."""
        if self.path:
            if not isinstance(value, str) or not value.strip():
                raise ConfigError(key, f"expected the path of a file, got {value!r}")
            return value
        if self.choices:
            allowed = self.allowed
            if value not in allowed:
                raise ConfigError(key, f"expected one of {', '.join(map(repr, allowed))}, got {value!r}")
            return value
        if isinstance(self.default, bool):
            if not isinstance(value, bool):
                raise ConfigError(key, f"expected true or false, got {value!r}")
            return value
        size = {"1": 1, "2": 2, "n": n, "m": m}[self.size]  # n is None before the robot is loaded
        entries = value if isinstance(value, list) and self.size != "1" else [value]
        if not entries or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in entries):
            wanted = "a number" if self.size == "1" else f"a number or a list of {size or self.size}"
            raise ConfigError(key, f"expected {wanted} [{self.unit}], got {value!r}")
        arr = np.asarray(entries, dtype=float)
        if self.integer and (arr != np.round(arr)).any():
            raise ConfigError(key, f"expected a whole number, got {value!r}")
        if self.size == "2" and arr.size != 2:
            raise ConfigError(key, f"needs 2 entries, got {arr.size}")
        if size is not None and arr.size not in (1, size):
            raise ConfigError(key, f"needs 1 or {size} entries ({self.size} = {size}), got {arr.size}")
        below = (arr <= self.low) if self.low_open else (arr < self.low)
        bad = ~np.isfinite(arr) | below | (arr > self.high)
        if bad.any():
            first = float(arr[np.flatnonzero(bad)[0]])
            shown = str(int(first)) if self.integer and np.isfinite(first) else f"{first:g}"
            unit = "" if self.unit == "-" else f" {self.unit}"
            raise ConfigError(key, f"{shown} is outside {self.range}{unit}")
        if self.size == "1":
            return float(arr[0])
        return np.full(size or 1, arr[0]) if arr.size == 1 else arr


@dataclass
class DeclaredKeys:
    """A section (``[SECTION]``) whose kinds may declare keys beyond its fields
    (:meth:`kind_params`): a value given in the file is kept in ``extra`` (written back flat by
    ``ExperimentConfig.to_dict``); read as an attribute, it is the value given or the
    declaration's default.
    """

    extra: dict = field(default_factory=dict, kw_only=True)
    """The values given of the keys the section's kinds declare beyond its fields."""

    SECTION: ClassVar[str] = ""

    @classmethod
    def kind_params(cls) -> Iterable[LawParam]:
        """Every key the section's kinds declare (their ``params``)."""
        return ()

    @classmethod
    def declared_keys(cls) -> dict[str, LawParam]:
        """The keys the kinds declare that are not fields, by their name in the section."""
        fields = {f.name for f in dataclasses.fields(cls)}
        out: dict[str, LawParam] = {}
        for p in cls.kind_params():
            where, _, name = p.name.partition(".")
            if where == cls.SECTION and name not in fields:
                out.setdefault(name, p)
        return out

    def __getattr__(self, name: str) -> Any:  # only for a name that is not a field or attribute
        if name.startswith("__") or name == "extra":
            raise AttributeError(name)
        extra = self.__dict__.get("extra") or {}
        if name in extra:
            return extra[name]
        param = type(self).declared_keys().get(name)
        if param is None:
            raise AttributeError(f"{type(self).__name__} has no key {name!r}")
        return param.config_default

    def check_declared(self, m: int) -> None:
        """Every declared key's value (given or default) against its declaration (``m``: the
        task's rows, for a key of one entry per row); an unset key the kind sizes itself (default
        None) is not checked.
        """
        for name, param in type(self).declared_keys().items():
            value = getattr(self, name)
            if not (value is None and param.default is None):
                param.check(value, None, m, param.name)
