"""Search spaces for tuning, derived from the arm: every knob of each controller, log-scaled.

Gains are searched as a closed-loop bandwidth w [rad/s] and a damping ratio z, the same two
coordinates for every controller, so no law gets a wider reach than another:

- eq. (9) laws: K_p = w^2, K_v = 2 z w. Where the robust term is built on eq. (16)'s P (the NN
  compensator, the sliding mode, the RBF network) eq. (17)'s K_v^2 > K_p is z > 1/2, a physical
  bound (0.51); every other law with a damping ratio (no-u0, computed torque, the PD) is searched
  from 0.2 and widened below it like any bound that is not physical;
- the task-space PD: K_p = lambda w^2, K_d = 2 z lambda w, with lambda the task-space inertia
  (J M^-1 J^T)^-1 at q(0) (geometric mean of its eigenvalues) [kg].

w spans from one oscillation per run to the sampling limit w (1/2 + d) T = 1 (period T, delay d
periods: the phase lag of the zero-order hold and the delay reaches a radian there); the
self-motion gain k, a first-order velocity loop, stops at k T = 1. The NN's leakage is searched
as its rate F sigma [1/s] (sigma = rate / F, which reaches every (F, sigma)), from 1 % over the
run (F sigma D = 0.01: less changes nothing the run can show) to one control period (F sigma T =
1: Z then follows |w| phi / sigma, no longer adaptive), so that its bounds are physical as F
moves. The robust terms' levels
scale with the arm's task acceleration a = max_i (tau_i / M_ii) |J|: the largest acceleration
its actuators give the tool [m/s^2]. A bound that is physical (sampling, eq. 17) is never
widened; the others are, when a best setting sits on them.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ...core.search_coordinates import Param, bandwidth_range
from ..base.tuned import own_keys, tunable

EDGE = 0.03
"""A value within this fraction of its log range from a bound is "at the bound"."""


@dataclass(frozen=True)
class SearchSpace:
    """A controller's search coordinates and how they become experiment overrides."""

    controller: str
    params: tuple[Param, ...]
    task_inertia: float = 1.0  # lambda [kg] (the PD's gains)
    custom: bool = False  # a user's class: every coordinate is a controller.params key
    eq9: bool = True  # its gains are eq. (9)'s Kp, Kv (else the PD's pd_Kp, pd_Kd)
    fixed: tuple[tuple[str, str], ...] = ()  # (key, why) of each key of the law not searched
    search_keys: Callable[[dict], dict] | None = None  # its robust term's coordinates -> keys

    def param(self, name: str) -> Param:
        """The coordinate called ``name``."""
        return next(p for p in self.params if p.name == name)

    @property
    def gains(self) -> tuple[Param, ...]:
        """The coordinates of the law without its robust term (eq. 9 with u_0 = 0, or the PD)."""
        return tuple(p for p in self.params if not p.weak)

    @property
    def robust(self) -> tuple[Param, ...]:
        """The robust term's coordinates (none for no-u0, computed torque and the PD)."""
        return tuple(p for p in self.params if p.weak)

    def weakest(self) -> dict[str, float]:
        """The robust term's knobs where it does least (u_0 about 0)."""
        return {p.name: p.low if p.weak == "low" else p.high for p in self.robust}

    def overrides(self, values: dict[str, float]) -> dict:
        """Dotted-key overrides of the experiment for the coordinates' values."""
        out: dict[str, object] = {k: v for k, v in values.items() if "." in k}
        if self.custom:
            return out
        w, z = values["bandwidth"], values["damping_ratio"]
        if not self.eq9:  # the PD's stiffness and damping, scaled by the task inertia
            lam = self.task_inertia
            out.update({"controller.pd_Kp": [lam * w * w], "controller.pd_Kd": [2 * z * lam * w]})
        else:
            out.update({"controller.Kp": [w * w], "controller.Kv": [2 * z * w]})
        if self.search_keys is not None:  # as the robust term's kind declares them
            out.update(self.search_keys(values))
        return out

    def at_bound(self, values: dict[str, float]) -> list[dict]:
        """The coordinates whose value sits on a bound: name, side and why it may be physical."""
        out = []
        for p in self.params:
            pos = p.position(values[p.name])
            if pos < EDGE:
                out.append({"param": p.name, "side": "low", "bound": p.low, "physical": p.reason("low")})
            elif pos > 1 - EDGE:
                out.append({"param": p.name, "side": "high", "bound": p.high, "physical": p.reason("high")})
        return out

    def widened(self, values: dict[str, float], skip=None) -> tuple[SearchSpace, list[dict]]:
        """The space with every non-physical bound that ``values`` sits on moved out a decade,
        and what moved: ``{param, side, old, bound}`` each. ``skip(param, side)`` keeps a bound.
        """
        params, moved = [], []
        for p in self.params:
            pos = p.position(values[p.name])
            side = "low" if pos < EDGE and not p.reason("low") else ""
            side = "high" if pos > 1 - EDGE and not p.reason("high") else side
            if side and not (skip and skip(p.name, side)):
                old = p.low if side == "low" else p.high
                if side == "low":
                    p = replace(p, low=max(p.low / 10, p.range_low))
                else:
                    p = replace(p, high=min(p.high * 10, p.range_high))
                moved.append(
                    {"param": p.name, "side": side, "old": old, "bound": p.low if side == "low" else p.high}
                )
            params.append(p)
        return replace(self, params=tuple(params)), moved

    def to_dict(self) -> dict:
        """JSON-ready description of the space."""
        return {
            p.name: {
                "low": p.low,
                "high": p.high,
                "unit": p.unit,
                "low_reason": p.reason("low"),
                "high_reason": p.reason("high"),
            }
            for p in self.params
        }

    def searched_keys(self) -> frozenset[str]:
        """The configuration keys a setting of this space sets (``controller.Kp`` for the
        bandwidth, ``nn.sigma`` for the leakage rate, ...).
        """
        return frozenset(self.overrides({p.name: math.sqrt(p.low * p.high) for p in self.params}))


def arm_scales(setup) -> dict[str, float]:
    """The arm's scales the spaces derive from (a built experiment's robot, q(0), period)."""
    from ...plant.scaling import torque_scale

    robot, q0, config = setup.robot, setup.q0, setup.config
    sim = config.simulation
    M = robot.mass(q0)
    J = robot.task_jacobian(q0)[: min(robot.m, 3)]
    Lam_inv = J @ np.linalg.solve(M, J.T)
    eig = np.clip(np.linalg.eigvalsh(Lam_inv), 1e-12, None)
    task_inertia = float(np.exp(np.mean(np.log(1.0 / eig))))
    limit = setup.plant.torque_limit
    tau = np.asarray(limit, float) if limit is not None else np.full(robot.nq, np.inf)
    tau = np.where(np.isfinite(tau) & (tau > 0), tau, torque_scale(robot))
    acceleration = float(np.max(tau / np.diag(M)) * np.linalg.norm(J, 2))
    delay = config.sensing.delay
    return {
        "period": sim.control_period,
        "delay": delay,
        "duration": sim.duration,
        "task_inertia": task_inertia,
        "task_acceleration": acceleration,
        "joint_inertia": float(np.mean(np.diag(M))),
    }


def search_space(controller: str, scales: dict[str, float]) -> SearchSpace:
    """The search space of a controller on an arm (see the module docstring)."""
    from ...controllers.registry import paper_kind, registered_law

    if controller not in tunable():
        raise ValueError(
            f"tune: no search space for controller {controller!r}; tunable: {', '.join(tunable())}"
        )
    law = registered_law(controller)
    if law is not None:  # its declared bounds: fixed, or derived from the arm
        params = []
        for p in law.params:
            if p.search is None:
                continue
            low, high = p.search(scales) if callable(p.search) else p.search
            params.append(
                Param(
                    f"controller.params.{p.name}", float(low), float(high), p.unit,
                    low_reason=p.low_reason, high_reason=p.high_reason, weak=p.weak,
                    range_low=max(p.low, 0.0), range_high=p.high,
                )
            )  # fmt: skip
        space = SearchSpace(controller, tuple(params), custom=True)
        return replace(space, fixed=_fixed(controller, space))
    T = scales["period"]
    w_low, w_high = bandwidth_range(scales)
    sampling = f"sampling: w (1/2 + delay) T = 1, {w_high:.4g} rad/s"
    params = [Param("bandwidth", w_low, w_high, "rad/s", high_reason=sampling)]
    kind = paper_kind(controller)
    assert kind is not None  # tunable() lists only the paper's kinds and the registered laws
    if not kind.eq9:  # the PD: its damping ratio, and the null-space damping from the arm
        params.append(Param("damping_ratio", 0.2, 5.0, "-"))
        m = scales["joint_inertia"]
        params.append(Param("controller.pd_null_damping", m * w_low, m * w_high, "N m s/rad"))
    elif kind.lyapunov:  # its u_0 is built on eq. (16)'s P, which needs eq. (17)'s Kv^2 > Kp
        params.append(Param("damping_ratio", 0.51, 5.0, "-", low_reason="eq. (17): K_v^2 > K_p"))
    else:  # eq. (9) without such a term: the PD's rule, searched from 0.2, widened if the best is there
        params.append(Param("damping_ratio", 0.2, 5.0, "-"))
    if kind.eq9:
        params.append(
            Param("controller.k", 0.1, 1.0 / T, "1/s", high_reason=f"sampling: k T <= 1, {1.0 / T:.4g} 1/s")
        )
    if kind.search is not None:  # its robust term's coordinates, as its module declares them
        params += kind.search(scales)
    space = SearchSpace(
        controller, tuple(params), scales["task_inertia"], eq9=kind.eq9, search_keys=kind.search_keys
    )
    return replace(space, fixed=_fixed(controller, space))


def _fixed(controller: str, space: SearchSpace) -> tuple[tuple[str, str], ...]:
    """(key, why) of every key the shipped law ``controller`` reads that ``space`` does not
    search: its own keys (:func:`own_keys`) and the keys every shipped law shares (the
    pseudo-inverse's), each with its declaration's :attr:`~nnrobust.controllers.registry.LawParam.
    fixed_reason` ("" where none is declared: tests/studies/tune/test_engine.py fails on one).
    """
    from ...controllers.registry import SHARED_KEYS, declared_key, registered_law

    keys, _ = own_keys(controller)
    shared = [p.name for s in SHARED_KEYS if s.readers is not None for p in s.params]
    searched = space.searched_keys()
    law = registered_law(controller)
    out = []
    for key in [*sorted(keys), *shared]:
        if key in searched:
            continue
        if law is not None and key.startswith("controller.params."):
            declared = law.param(key.removeprefix("controller.params."))
        else:
            declared = declared_key(key)
        out.append((key, declared.fixed_reason if declared is not None else ""))
    return tuple(out)


def fixed_text(fixed) -> list[str]:
    """The held keys as lines, those of one reason together: ``why: key, key``."""
    by_reason: dict[str, list[str]] = {}
    for key, why in fixed:
        by_reason.setdefault(why or "no reason declared", []).append(key)
    return [f"{why}: {', '.join(keys)}" for why, keys in by_reason.items()]


def custom_space(name: str, cls: type) -> SearchSpace:
    """The search space a custom controller class declares: ``search_space``, a dict of
    constructor parameter -> (low, high) or (low, high, unit), each searched log-uniformly and
    widened like the shipped laws' bounds when a best setting sits on one.
    """
    from ...core.exceptions import ConfigError

    declared = getattr(cls, "search_space", None)
    key = f"--controllers {name}"
    if not isinstance(declared, dict) or not declared:
        raise ConfigError(
            key,
            f"{cls.__name__} declares no search space: give the class a search_space = "
            "{'param': (low, high, 'unit'), ...} of its constructor's parameters "
            "(docs/extending.md)",
        )
    params = []
    for param, bounds in declared.items():
        ok = (
            isinstance(bounds, (tuple, list))
            and len(bounds) in (2, 3)
            and all(isinstance(b, (int, float)) and not isinstance(b, bool) for b in bounds[:2])
            and 0 < bounds[0] < bounds[1] < math.inf
        )
        if not isinstance(param, str) or not param.isidentifier() or not ok:
            raise ConfigError(
                key,
                f"{cls.__name__}.search_space[{param!r}] = {bounds!r}: needs a parameter "
                "name and (low, high[, unit]) with 0 < low < high (searched on a log scale)",
            )
        unit = str(bounds[2]) if len(bounds) == 3 else "-"
        params.append(Param(f"controller.params.{param}", float(bounds[0]), float(bounds[1]), unit))
    fixed = tuple(
        (f"controller.params.{param}", f"not in {cls.__name__}.search_space: its author's choice")
        for param in _constructor_params(cls)
        if param not in declared
    )
    return SearchSpace(name, tuple(params), custom=True, fixed=fixed)


def _constructor_params(cls: type) -> list[str]:
    """The named parameters of ``cls(context, ...)`` after the context."""
    import inspect

    try:
        signature = inspect.signature(cls)
    except (TypeError, ValueError):
        return []
    named = [
        p.name for p in signature.parameters.values() if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
    ]
    return named[1:]  # after the context
