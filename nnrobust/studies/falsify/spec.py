"""What a search searches: the box of a sweep file's ranges (:class:`Box`), the sweep as searched
(its seeded model error made searchable) and the options (:class:`FalsifySpec`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...core.exceptions import ConfigError

MAX_SCALE = 8.0
"""The largest scale of the box the robustness margin tries (``--margin``)."""


MARKER = "falsify.toml"
HISTORY = "history"
MAX_BUDGET = 100_000


@dataclass(frozen=True)
class Box:
    """The searched coordinates: dotted keys, their bounds, and which are searched on a log scale."""

    keys: tuple[str, ...]
    low: np.ndarray
    high: np.ndarray
    log: np.ndarray

    def values(self, u: np.ndarray) -> dict[str, float]:
        """The plant at u in [0, 1]^d (geometric interpolation on the log-scaled keys)."""
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        out = {}
        for key, lo, hi, log, x in zip(self.keys, self.low, self.high, self.log, u):
            out[key] = float(lo * (hi / lo) ** x if log else lo + x * (hi - lo))
        return out

    def scaled(self, s: float) -> Box:
        """The box scaled by s about its centre: each range's half-width times s (on the log scale
        for loguniform keys); s = 0 is the centre alone, s = 1 the box itself.
        """
        log = self.log
        ratio = np.divide(self.high, self.low, out=np.ones_like(self.low), where=log)  # log keys: low > 0
        centre = np.where(log, np.sqrt(np.abs(self.low * self.high)), 0.5 * (self.low + self.high))
        half = np.where(log, np.sqrt(ratio), 0.5 * (self.high - self.low))
        low = np.where(log, centre / half**s, centre - s * half)
        low = np.where(~log & (self.low >= 0), np.maximum(low, 0.0), low)  # non-negative stays so
        high = np.where(log, centre * half**s, centre + s * half)
        return Box(self.keys, low, high, log)

    def largest_scale(self) -> float:
        """The largest s for which :meth:`scaled` keeps every positive linear range at least 10 %
        of its centre away from zero (a factor or a scale must not reach 0), at most MAX_SCALE.
        """
        positive = ~self.log & (self.low > 0)
        centre, half = 0.5 * (self.low + self.high), 0.5 * (self.high - self.low)
        limits = 0.9 * centre[positive & (half > 0)] / half[positive & (half > 0)]
        return float(min(MAX_SCALE, *limits)) if limits.size else MAX_SCALE


def searchable(sweep, base) -> tuple[Any, str]:
    """The sweep with its seeded model error made searchable, and a line saying so ("" if none).

    ``nominal.relative_error`` in [lo, r] draws each parameter of the controller's model off by
    its own factor in [1 - r, 1 + r] along a direction chosen by the seed, which no search can
    move along. The models it can draw are the box of those factors, so falsify searches
    ``nominal.factors[i]`` over [1 - r, 1 + r] instead, with ``relative_error`` set to 0 (the
    centre-of-mass error, ``com_error``, stays seeded).
    """
    import copy

    from ...config import nominal_kind
    from ...model.nominal import nominal_factor_count

    spec = sweep.vary.get("nominal.relative_error")
    if spec is None:
        return sweep, ""
    if any(k.startswith("nominal.factors") for k in sweep.vary):
        raise ConfigError(
            "vary.nominal.relative_error",
            "falsify searches it as nominal.factors, which the sweep varies too: vary one of the two",
        )
    values = spec if isinstance(spec, list) else next(iter(spec.values()))
    if isinstance(spec, dict) and next(iter(spec)) not in ("uniform", "loguniform"):
        raise ConfigError("vary.nominal.relative_error", f"falsify searches ranges, not {next(iter(spec))}")
    top = float(max(values))
    if not 0 < top < 1:
        raise ConfigError("vary.nominal.relative_error", f"needs a largest value in (0, 1), got {top}")
    count = nominal_factor_count(nominal_kind(base), base.robot)
    out = copy.deepcopy(sweep)
    del out.vary["nominal.relative_error"]
    for i in range(count):
        out.vary[f"nominal.factors[{i}]"] = {"uniform": [1.0 - top, 1.0 + top]}
    out.set["nominal.relative_error"] = 0.0
    note = (
        f"nominal.relative_error up to {top:g} is searched as the {count} factors it draws "
        f"(nominal.factors[0..{count - 1}] each in [{1 - top:g}, {1 + top:g}], relative_error 0)"
    )
    return out, note


def _searched_sweep(spec: FalsifySpec):
    """(the sweep as searched, its base's own values with its [set], what :func:`searchable`
    says): the target's sweep with the controllers (tuned where asked), its seeded model error
    made searchable (its [set] then holds ``nominal.relative_error = 0``, which the values take).
    """
    from ..base.plan import base_config, base_values, load_sweep
    from ..base.tuned import check_tuned, check_tuned_values, with_controllers

    target = load_sweep(spec.target)
    check_tuned(spec.tuned or {}, target.vary, entries=target.entries)  # the law's own keys, none varied
    sweep = with_controllers(target, spec.controllers, spec.tuned)
    check_tuned_values(sweep, spec.tuned or {})
    searched, note = searchable(sweep, base_config(sweep))
    if searched is not sweep:
        base_config(searched)  # its [set] (relative_error 0) checked on the base
    return searched, base_values(searched), note


def box_of(spec) -> Box:
    """The box of a sweep's ``[vary]`` ranges; grids and other distributions are refused."""
    keys, low, high, log = [], [], [], []
    for key, value in spec.vary.items():
        if isinstance(value, list):  # a grid of numbers: the range it spans
            numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
            if not numbers or min(value) == max(value):
                raise ConfigError(
                    f"vary.{key}",
                    "falsify searches ranges: a grid of two or more numbers is searched over the range it "
                    "spans; make this one a uniform or loguniform range, or set it in [set]",
                )
            value = {"uniform": [min(value), max(value)]}
        ((kind, params),) = value.items()
        if kind not in ("uniform", "loguniform"):
            raise ConfigError(
                f"vary.{key}",
                f"falsify searches uniform and loguniform ranges, not {kind}: "
                "give its range, or set it in [set]",
            )
        keys.append(key)
        low.append(float(params[0]))
        high.append(float(params[1]))
        log.append(kind == "loguniform")
    if not keys:
        raise ConfigError(
            "vary",
            "the sweep file varies nothing: falsify needs a box of uniform or loguniform ranges to search",
        )
    return Box(tuple(keys), np.array(low), np.array(high), np.array(log))


@dataclass
class FalsifySpec:
    """What to search: the sweep (box and base), the controllers, the properties, the budget."""

    target: str
    controllers: list[str]
    require: list[str]
    budget: int
    seed: int = 0
    margin: bool = False
    tuned: dict | None = None  # law -> the dotted-key settings it runs at (tune.engine.tuned_settings)

    @property
    def margin_budget(self) -> int:
        """Simulations per controller and scale of the margin's search (a quarter of the budget)."""
        return max(4, self.budget // 4)

    def __post_init__(self):
        if (
            isinstance(self.budget, bool)
            or not isinstance(self.budget, int)
            or not 4 <= self.budget <= MAX_BUDGET
        ):
            raise ConfigError("--budget", f"must be an integer in [4, {MAX_BUDGET}], got {self.budget!r}")
        if not 0 <= self.seed < 2**31:
            raise ConfigError("--seed", f"must be an integer in [0, 2^31), got {self.seed}")
        if not self.require:
            raise ConfigError(
                "--require", "falsify needs at least one property to falsify, e.g. 'rms_error_after_2s<=0.05'"
            )

    def to_toml(self) -> str:
        """The resolved search (DIR/falsify.toml): a different one is refused in the same folder."""
        from ...config import dump_toml

        return dump_toml(
            {
                "target": self.target,
                "controllers": self.controllers,
                "require": self.require,
                "budget": self.budget,
                "seed": self.seed,
                **({"margin": True} if self.margin else {}),
                **({"tuned": self.tuned} if self.tuned else {}),
            }
        )
