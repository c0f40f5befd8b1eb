"""External loads that switch on and off during a run (``[[plant.loads]]``, docs/plant.md).

Beside the bounded disturbance tau_d(t) of eq. (7), a run may meet

- a **torque step** on the joints, u applied from time t_0 on;
- a **torque impulse** on the joints, p [N m s] spread over a short pulse of duration d
  (u = p / d on [t_0, t_0 + d), so that the joints receive the angular impulse p);
- a **wrench at the task frame**, w = (f, m) in world axes at the frame's origin, applied on
  [t_0, t_0 + d): it acts on the joints as J(q)^T w, with J the frame's 6 x n Jacobian in world
  axes (eq. (7)'s tau_d gains -J^T w);
- a **payload change**: from t_0 the task frame carries a solid sphere of the given mass (the
  model of ``plant.payload``), so the true M(q), V_m and G change; the controller's nominal
  model does not.

Loads switch at control instants and are held over each period (the simulation asks
:meth:`ExternalLoads.at` at t_k), so the plant's right-hand side is smooth inside a period and the
integrator's order holds. Positive joint torques and wrenches push the arm (they add to the
actuators' torque).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from ..core.exceptions import ConfigError
from ..core.numeric_limits import MAX_PAYLOAD, finite_number

LOAD_KINDS = ("step", "impulse", "wrench", "payload")
"""The values of a ``[[plant.loads]]`` entry's ``kind``."""


@dataclass(frozen=True)
class TorquePulse:
    """u [N m] on the joints over [start, end) [s] (end inf: a step)."""

    start: float
    end: float
    torque: np.ndarray


@dataclass(frozen=True)
class ToolWrench:
    """w = (force [N], moment [N m]) in world axes at the task frame over [start, end) [s]."""

    start: float
    end: float
    wrench: np.ndarray


@dataclass(frozen=True)
class PayloadChange:
    """From ``start`` [s] on, the task frame carries ``mass`` [kg] (on top of ``plant.payload``)."""

    start: float
    mass: float


@dataclass(frozen=True)
class HeldLoads:
    """The loads acting over one control period: joint torque [N m], tool wrench (None: none)."""

    torque: np.ndarray
    wrench: np.ndarray | None


@dataclass(frozen=True)
class ExternalLoads:
    """The ``[[plant.loads]]`` of a run, by kind, for an arm of ``n`` joints (payload changes
    sorted by start; each replaces the one before).
    """

    n: int
    pulses: tuple[TorquePulse, ...] = ()
    wrenches: tuple[ToolWrench, ...] = ()
    payloads: tuple[PayloadChange, ...] = ()
    _none: HeldLoads = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "_none", HeldLoads(np.zeros(self.n), None))

    twin_fields = (
        "pulse_start", "pulse_end", "pulse_torque", "wrench_start", "wrench_end", "wrench", "payload_start"
    )  # fmt: skip
    """What its compiled twin reads (csrc/plant/loads.hpp)."""

    def __bool__(self) -> bool:
        return bool(self.pulses or self.wrenches or self.payloads)

    @property
    def pulse_start(self) -> np.ndarray:
        """Each torque step's or impulse's start [s]."""
        return np.array([p.start for p in self.pulses], dtype=float)

    @property
    def pulse_end(self) -> np.ndarray:
        """Each torque step's or impulse's end [s] (inf: a step)."""
        return np.array([p.end for p in self.pulses], dtype=float)

    @property
    def pulse_torque(self) -> np.ndarray:
        """The pulses' joint torques, one column each: n x P [N m]."""
        return np.array([p.torque for p in self.pulses], dtype=float).T.reshape(self.n, -1)

    @property
    def wrench_start(self) -> np.ndarray:
        """Each tool wrench's start [s]."""
        return np.array([w.start for w in self.wrenches], dtype=float)

    @property
    def wrench_end(self) -> np.ndarray:
        """Each tool wrench's end [s]."""
        return np.array([w.end for w in self.wrenches], dtype=float)

    @property
    def wrench(self) -> np.ndarray:
        """The tool wrenches, one column each: 6 x W [N, N m]."""
        return np.array([w.wrench for w in self.wrenches], dtype=float).T.reshape(6, -1)

    @property
    def payload_start(self) -> np.ndarray:
        """Each payload change's time [s] (sorted)."""
        return np.array([c.start for c in self.payloads], dtype=float)

    def at(self, t: float) -> HeldLoads:
        """The loads held over the control period that starts at t [s]."""
        if not self:
            return self._none
        torque = np.zeros(self.n)
        for p in self.pulses:
            if p.start <= t < p.end:
                torque = torque + p.torque
        wrench = None
        for w in self.wrenches:
            if w.start <= t < w.end:
                wrench = w.wrench if wrench is None else wrench + w.wrench
        return HeldLoads(torque, wrench)


LOAD_KEYS = {
    "step": ("torque",),
    "impulse": ("impulse",),
    "wrench": ("force", "moment"),
    "payload": ("mass",),
}
"""The keys of each kind beside ``kind``, ``time`` and ``duration`` (payload: no duration)."""

LOAD_UNITS = {"torque": "N m", "impulse": "N m s", "force": "N", "moment": "N m", "mass": "kg"}
"""The unit of each of those keys."""

_TOLERANCE = 1e-9
"""Relative tolerance of "a whole number of control periods"."""


MAX_PERIODS = 1e12
"""The most control periods a load's time or duration may span (a run has at most about 10^9 steps)."""


def _periods(path: str, value, period: float, positive: bool) -> float:
    """A time [s] that is a whole number of control periods (loads switch at control instants)."""
    if not (isinstance(value, (int, float)) and finite_number(value)):
        raise ConfigError(path, f"expected a finite number of seconds, got {value!r}")
    count = value / period
    if not abs(count) <= MAX_PERIODS:
        raise ConfigError(path, f"{value:g} s is more than {MAX_PERIODS:.0e} control periods ({period:g} s)")
    if (value <= 0 if positive else value < 0) or abs(count - round(count)) > _TOLERANCE * max(1.0, count):
        lower, upper = np.floor(count) * period, np.ceil(count) * period
        sign = "> 0" if positive else ">= 0"
        raise ConfigError(
            path,
            f"{value:g} s is not a whole number ({sign}) of control periods ({period:g} s): loads "
            f"switch at control instants; give e.g. {max(lower, period if positive else 0.0):g} "
            f"or {max(upper, period):g}",
        )
    return round(count) * period


def _vector(path: str, value, size: int | None, unit: str, per_joint: bool) -> np.ndarray:
    if not isinstance(value, list) or not all(
        isinstance(v, (int, float)) and finite_number(v) for v in value
    ):
        raise ConfigError(path, f"expected a list of finite numbers [{unit}], got {value!r}")
    if size is not None and len(value) != size:
        each = " (one per joint)" if per_joint else ""
        raise ConfigError(path, f"has {len(value)} entries; give {size}{each} [{unit}]")
    return np.asarray(value, dtype=float)


def parse_loads(
    entries: list[dict] | None, period: float, n: int | None = None, duration: float | None = None
) -> ExternalLoads:
    """``[[plant.loads]]`` read and checked: every refusal names the entry and key.

    ``n``: the number of joints (None: the joint vectors' lengths are not checked yet; the
    configuration is checked before the robot is loaded). ``duration``: the run's [s]; a load
    starting at or after its end never acts, and a warning says so.
    """
    pulses, wrenches, payloads = [], [], []
    for i, entry in enumerate(entries or ()):
        where = f"plant.loads[{i}]"
        kind = entry.get("kind")
        if kind not in LOAD_KINDS:
            raise ConfigError(f"{where}.kind", f"{kind!r} is not one of {', '.join(LOAD_KINDS)}")
        valid = ("kind", "time", *(() if kind == "payload" else ("duration",)), *LOAD_KEYS[kind])
        for key in entry:
            if key not in valid:
                raise ConfigError(
                    f"{where}.{key}", f"is not a key of a {kind!r} load; its keys: {', '.join(valid)}"
                )
        if "time" not in entry:
            raise ConfigError(f"{where}.time", f"a {kind!r} load needs the time it starts [s]")
        start = _periods(f"{where}.time", entry["time"], period, positive=False)
        if duration is not None and start >= duration:  # a shortened run of a file with loads: said
            warnings.warn(
                f"{where}.time: {start:g} s is not before the run ends (simulation.duration = "
                f"{duration:g} s): the load never acts",
                stacklevel=2,
            )
        default = period if kind == "impulse" else np.inf
        lasts = (  # the load's own duration, not the run's
            default
            if "duration" not in entry
            else _periods(f"{where}.duration", entry["duration"], period, True)
        )
        end = start + lasts
        if kind in ("step", "impulse"):
            key = LOAD_KEYS[kind][0]
            if key not in entry:
                raise ConfigError(f"{where}.{key}", f"a {kind!r} load needs one value per joint")
            value = _vector(f"{where}.{key}", entry[key], n, LOAD_UNITS[key], per_joint=True)
            pulses.append(TorquePulse(start, end, value if kind == "step" else value / lasts))
        elif kind == "wrench":
            if "force" not in entry and "moment" not in entry:
                raise ConfigError(
                    f"{where}.force", "a 'wrench' load needs force [N] and/or moment [N m] (3 each)"
                )
            force, moment = (
                _vector(f"{where}.{key}", entry.get(key, [0.0] * 3), 3, LOAD_UNITS[key], per_joint=False)
                for key in LOAD_KEYS["wrench"]
            )
            wrenches.append(ToolWrench(start, end, np.concatenate([force, moment])))
        else:
            mass = entry.get("mass")
            if isinstance(mass, bool) or not isinstance(mass, (int, float)) or not 0 <= mass <= MAX_PAYLOAD:
                raise ConfigError(
                    f"{where}.mass",
                    f"the payload carried from then on, in [0, {MAX_PAYLOAD:g}] kg; got {mass!r}",
                )
            payloads.append(PayloadChange(start, float(mass)))
    payloads.sort(key=lambda c: c.start)
    starts = [c.start for c in payloads]
    if len(set(starts)) != len(starts):
        raise ConfigError("plant.loads", "two payload changes at the same time; give one")
    return ExternalLoads(n or 0, tuple(pulses), tuple(wrenches), tuple(payloads))
