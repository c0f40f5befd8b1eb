"""One controller's search (:class:`ControllerSearch`): its space, its history, what to ask
next, and how one setting's runs are judged (:func:`judge`).
"""

from __future__ import annotations

import math
from collections import Counter
from typing import TYPE_CHECKING

import numpy as np

from ...core.search_coordinates import controller_seed
from .space import SearchSpace
from .spec import CONSTRAINTS, FAILED, GAIN_SHARE, MAX_WIDENINGS, OBJECTIVES, WIDEN_FROM, TuneSpec

if TYPE_CHECKING:
    import optuna


def judge(spec: TuneSpec, runs: list[dict]) -> tuple[tuple[float, ...], list[float], dict]:
    """(objectives, constraints <= 0 when met, the mean metrics) of one setting's runs."""
    completed = all(r.get("status") == "completed" for r in runs)
    finite = all(r.get(k) is not None and math.isfinite(float(r[k])) for r in runs for k in OBJECTIVES)
    if not completed or not finite:
        return FAILED, [1.0] * len(CONSTRAINTS), {"status": "failed"}
    numbers = {k: float(np.mean([r[k] for r in runs])) for k in OBJECTIVES}
    saturated = float(max(r["saturated_fraction"] for r in runs))
    violation = float(max(r["max_joint_limit_violation"] for r in runs))
    runaway = bool(any(r["runaway"] for r in runs))
    mean = {
        **numbers,
        "saturated_fraction": saturated,
        "max_joint_limit_violation": violation,
        "runaway": runaway,
        "status": "completed",
    }
    torque = numbers["rms_torque"] - spec.max_rms_torque if math.isfinite(spec.max_rms_torque) else -1.0
    constraints = [torque, saturated - spec.max_saturated, 1.0 if runaway else -1.0, violation, -1.0]
    return tuple(numbers[k] for k in OBJECTIVES), constraints, mean


class ControllerSearch:
    """One controller's search: its space, its history, what to ask next.

    A law with a robust term (NN, sliding mode) is eq. (9) with u_0 added, and with u_0 off it is
    the no-u0 law. Such a controller spends the first GAIN_SHARE of its own budget on its gains
    with u_0 = 0 (phase ``gains``), then searches every knob (phase ``all``) from its best gains
    with the robust term at its weakest: a random robust term at high gains chatters past the
    torque limit, and a search started there learns to avoid the only gains where the law can
    win. Its best setting is chosen among the phase ``all`` runs, which use the law itself. A
    registered law with an adaptive or robust term (its ``weak`` parameters) runs itself in the
    gain phase, with those parameters at their weakest.
    """

    def __init__(self, spec: TuneSpec, name: str, space: SearchSpace):
        self.spec, self.name, self.space = spec, name, space
        self.gain_trials = int(GAIN_SHARE * spec.trials) if space.robust else 0
        self.rows: list[dict] = []
        self.widenings: list[dict] = []  # {param, side, old, bound, trial, probe}, in order
        self.queue: list[dict] = []  # settings to try before the sampler's own: starts, probes
        # from the law's name, not its place in the list: a law tunes the same beside any others
        self.sampler_seed = (spec.seed + controller_seed(name)) % 2**31

    @property
    def phase(self) -> str:
        """``gains`` while the gain phase's share of the budget runs (u_0 = 0), then ``all``."""
        return "gains" if len(self.rows) < self.gain_trials else "all"

    def law(self, phase: str) -> str:
        """The controller kind the runs of a phase use."""
        return "no-u0" if phase == "gains" and not self.space.custom else self.name

    def overrides(self, values: dict, phase: str) -> dict:
        """The experiment overrides of a setting's runs in a phase."""
        if phase == "gains" and self.space.custom:  # the law itself, its robust term at its weakest
            values = {**values, **self.space.weakest()}
        return self.space.overrides(values)

    def _distributions(self, phase: str):
        import optuna

        params = self.space.gains if phase == "gains" else self.space.params
        return {p.name: optuna.distributions.FloatDistribution(p.low, p.high, log=True) for p in params}

    def _study(self):
        import warnings

        import optuna

        optuna.logging.set_verbosity(optuna.logging.WARNING)
        warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
        phase = self.phase
        sampler = optuna.samplers.TPESampler(
            seed=self.sampler_seed + 7919 * len(self.rows),
            multivariate=True,
            constant_liar=True,
            n_startup_trials=min(10, max(2, self.spec.trials // 5)),
        )
        study = optuna.create_study(direction="minimize", sampler=sampler)
        history = [r for r in self.rows if r["phase"] == phase]
        for row in history:
            study.add_trial(
                optuna.trial.create_trial(
                    params=row["search"],
                    distributions=self._distributions(phase),
                    value=row["objectives"][0],
                    constraints=dict(zip(CONSTRAINTS, row["constraints"])),
                )
            )
        return study

    @property
    def remaining(self) -> int:
        """Settings of the budget not yet tried."""
        return self.spec.trials - len(self.rows)

    def best(self, phase: str = "all", trials: int | None = None) -> dict | None:
        """The feasible setting of a phase with the least training error (among the first
        ``trials`` settings tried, or all).
        """
        rows = self.rows if trials is None else self.rows[:trials]
        feasible = [r for r in rows if r["feasible"] and r["phase"] == phase]
        return min(feasible, key=lambda r: r["train"]["rms_error_after_2s"]) if feasible else None

    def curve(self) -> list[list[float | None]]:
        """The search's convergence: [simulations run, the least training error of a feasible
        setting of the law itself so far (phase ``all``; None before one)] after each setting.
        """
        out: list[list[float | None]] = []
        least = math.inf
        for i, row in enumerate(self.rows):
            if row["feasible"] and row["phase"] == "all":
                least = min(least, row["train"]["rms_error_after_2s"])
            out.append([(i + 1) * self.spec.train_samples, least if math.isfinite(least) else None])
        return out

    def starts(self) -> list[dict]:
        """The gain settings the full search starts from: the best of the gain phase, and the best
        with a tenth and a quarter of the torque limit to spare (a robust term adds torque, and
        the best gains often sit on the limit).
        """
        feasible = sorted(
            (r for r in self.rows if r["feasible"] and r["phase"] == "gains"),
            key=lambda r: r["train"]["rms_error_after_2s"],
        )
        limit = self.spec.max_rms_torque
        out: list[dict] = []
        for share in (1.0, 0.9, 0.75):
            pick = next(
                (
                    r
                    for r in feasible
                    if not math.isfinite(limit) or r["train"]["rms_torque"] <= share * limit
                ),
                None,
            )
            if pick is not None and pick not in out:
                out.append(pick)
        return out

    def tell(self, trial, values: dict, phase: str, results: list[dict]) -> dict:
        """Judge a setting's runs, tell the study, and return its trials-table row."""
        objectives, constraints, mean = judge(self.spec, results)
        for key, value in zip(CONSTRAINTS, constraints):
            trial.set_constraint(key, value)
        trial.study.tell(trial, objectives[0])
        return {
            "controller": self.name,
            "phase": phase,
            "law": self.law(phase),
            "search": values,
            "params": self.overrides(values, phase),
            "objectives": list(objectives),
            "constraints": constraints,
            "feasible": all(v <= 0 for v in constraints),
            "queued": values in self.queue,
            "train": mean,
            "runs": results,
        }

    def record(self, row: dict) -> None:
        """Add a finished trial; from WIDEN_FROM of the budget on, widen the space where the best
        sits on a bound that is not physical, and queue a probe past it (module docstring).
        Replaying the rows in order repeats every widening and probe, so a resumed tuning asks
        what an uninterrupted one would.
        """
        before = self.phase
        row["trial"] = len(self.rows)
        self.rows.append(row)
        if row.get("queued"):
            self.queue = [p for p in self.queue if p != row["search"]]
        if before == "gains" and self.phase == "all":
            self.queue += [{**g["search"], **self.space.weakest()} for g in self.starts()]
        if len(self.rows) < max(1, int(WIDEN_FROM * self.spec.trials)) or self.phase != "all":
            return
        best = self.best()
        if best is None:
            return
        moved = Counter((w["param"], w["side"]) for w in self.widenings)
        wider, widenings = self.space.widened(
            best["search"], skip=lambda p, side: moved[p, side] >= MAX_WIDENINGS
        )
        if not widenings:
            return
        self.space = wider
        probe = dict(best["search"])
        for w in widenings:
            old = w["old"]
            probe[w["param"]] = old / math.sqrt(10) if w["side"] == "low" else old * math.sqrt(10)
            self.widenings.append({**w, "trial": len(self.rows), "probe": probe[w["param"]]})
        self.queue.append(probe)

    def ask(self, count: int) -> list[tuple[optuna.trial.Trial, dict, str]]:
        """Up to ``count`` new settings of the current phase: (Optuna trial, values, phase),
        queued settings first. The study is rebuilt from the rows, seeded by their number, so
        what is asked depends on the rows alone: a resumed tuning asks what an uninterrupted one
        would.
        """
        study = self._study()
        phase = self.phase
        left = (self.gain_trials - len(self.rows)) if phase == "gains" else self.remaining
        out = []
        pending = list(self.queue)
        for _ in range(min(count, left)):
            if pending:
                study.enqueue_trial(pending.pop(0))
            trial = study.ask(self._distributions(phase))
            out.append((trial, dict(trial.params), phase))
        return out
