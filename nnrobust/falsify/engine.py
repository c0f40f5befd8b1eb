"""Searching for the worst admissible plant: ``nnrobust falsify`` (docs/falsification.md).

The uncertainty set is the sweep file's ``[vary]`` box: each ``uniform`` or ``loguniform`` key is
a coordinate (searched on the log scale for ``loguniform``); a grid of numbers is searched over
the range it spans, which contains every grid point. A point of the box is one plant; the
controller's run on it gives each property (``--require``) a signed margin
(:mod:`nnrobust.properties`), and the search minimises the least of them: a negative margin
falsifies the property. Every point runs with the same seed, so a point is one plant, the
objective is deterministic, and the printed command reruns it bit for bit.

The search, per controller, at one budget of simulations on a Dask cluster:

1. a scrambled Sobol sequence over the box (a quarter of the budget, a power of two);
2. CMA-ES (the ``cma`` package) from the best point found, in batches the size of the worker
   pool, restarted with a doubled population (IPOP) when it converges, until the budget is spent;
   a box of one coordinate, which CMA-ES does not search, gets a zooming grid instead
   (:meth:`_Search._ask_line`);
3. as the reported baseline, the same budget of uniform random points.

The history is written as Parquet parts as it grows; running the same command into the same
folder reuses every point already simulated (the search is deterministic given its seed), so
Ctrl-C keeps what was found and a rerun resumes.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import ConfigError, NNRobustError
from ..properties import Property
from ..signals import signals_as_interrupt

MAX_SCALE = 8.0
"""The largest scale of the box the robustness margin tries (``--margin``)."""
MARGIN_STEPS = 7
"""Scales the margin's search tries after the box itself (doubling, then bisection)."""
MARGIN_TOLERANCE = 0.1
"""The margin's bisection stops when its bracket is narrower than this fraction of its top."""
MARKER = "falsify.toml"
HISTORY = "history"
MAX_BUDGET = 100_000
FLOOR = -1e6
"""The objective of a run that did not complete (margin -inf): below every finite margin."""


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

    from ..model.nominal import nominal_factor_count

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
    count = nominal_factor_count(base)
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
    from ..sweep.spec import base_config, base_values, load_sweep
    from ..tune.engine import _with_controllers, check_tuned, check_tuned_values

    target = load_sweep(spec.target)
    check_tuned(spec.tuned or {}, target.vary, entries=target.entries)  # the law's own keys, none varied
    sweep = _with_controllers(target, spec.controllers, spec.tuned)
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
        from ..config import dump_toml

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


def _objective(margins: dict[str, float]) -> float:
    least = min(margins.values())
    return max(least, FLOOR) if math.isfinite(least) else FLOOR


def evaluate(sweep, base: dict, controller: str, values: dict, properties: list[Property]) -> dict:
    """One run at one point of the box (on a worker): its margins and the metrics they read;
    ``base``: the base's own values (:func:`nnrobust.sweep.spec.base_values`).
    """
    from ..experiment import run_experiment
    from ..sweep.spec import Sample, experiment, sample_seed

    sample = Sample(-1, values, sample_seed(sweep.seed, 0))
    try:
        metrics = run_experiment(experiment(sweep, base, sample, controller)).metrics()
    except NNRobustError as err:
        metrics = {"status": "refused", "message": str(err)[:300]}
    except BaseException as err:  # a defect, or user code raising SystemExit or BaseException
        metrics = {"status": "error", "message": f"{type(err).__name__}: {err}"[:300]}
    return judged(metrics, properties)


def judged(metrics: dict, properties: list[Property]) -> dict:
    """A run's margins under ``properties`` and the metrics they read."""
    keep = {p.metric for p in properties} | {"status", "message", "rms_error_after_2s", "rms_torque"}
    margins = {p.text: p.margin(metrics) for p in properties}
    return {
        "metrics": {k: metrics.get(k) for k in sorted(keep)},
        "margins": margins,
        "objective": _objective(margins),
    }


LINE_START = 0.3
"""Half-width of a one-coordinate search's first grid, in the unit box (CMA-ES's sigma_0)."""

LINE_TOLERANCE = 1e-9
"""Half-width in the unit box below which a one-coordinate search has converged and restarts."""


class _Search:
    """One controller's search (Sobol, then CMA-ES with IPOP restarts; a zooming grid in a box
    of one coordinate) or its random baseline, asking batches and told the results;
    deterministic given the seed, so a resumed search asks the same points again and takes their
    results from the history.
    """

    def __init__(self, dims: int, budget: int, seed: int, random: bool):
        self.dims, self.budget, self.seed, self.random = dims, budget, seed, random
        self.asked = 0
        self.best: tuple[float, np.ndarray] | None = None
        self.rng = np.random.default_rng(seed)
        self.es: Any = None  # a cma.CMAEvolutionStrategy once the Sobol start is spent
        self._pending: list[np.ndarray] = []
        self.popsize = max(4 + int(3 * math.log(dims)), 4)
        self.restarts = 0
        self.line: tuple[float, np.ndarray, float] | None = None  # one coordinate: (f, centre, half-width)
        if random:
            self.start: list[np.ndarray] = []
        else:
            from scipy.stats import qmc

            m = max(1, int(math.log2(max(2, budget // 4))))
            self.start = list(qmc.Sobol(dims, scramble=True, seed=seed).random_base2(m))

    @property
    def remaining(self) -> int:
        return self.budget - self.asked

    def ask(self, count: int) -> list[tuple[str, np.ndarray]]:
        """Points (phase, u) to simulate next: up to ``count`` random or Sobol points, or CMA-ES's
        whole population (it learns only from a whole one); never past the budget.
        """
        if self.random:
            points = [("random", self.rng.random(self.dims)) for _ in range(min(count, self.remaining))]
        elif self.start:
            points = [
                ("sobol", self.start.pop(0)) for _ in range(min(count, len(self.start), self.remaining))
            ]
        elif self.dims == 1:
            points = [("line", u) for u in self._ask_line()]
        else:
            points = [("cma", u) for u in self._ask_cma()]
        self.asked += len(points)
        return points

    def _ask_line(self) -> list[np.ndarray]:
        """One coordinate (CMA-ES needs two; cma 3 refuses one, cma 4 fails in ``tell``): a grid
        of the population's size over [c - w, c + w] within [0, 1], about the best point c of
        this start; each batch zooms to the grid's spacing about the new best (its neighbours
        bracket a minimum), nearest points first. Converged (w < LINE_TOLERANCE): restarted from
        a random point with a doubled population, as IPOP restarts CMA-ES.
        """
        if self.line is None or self.line[2] < LINE_TOLERANCE:
            if self.line is not None:
                self.restarts += 1
                self.popsize *= 2
            if self.best is not None and self.restarts == 0:
                self.line = (self.best[0], self.best[1], LINE_START)
            else:
                self.line = (math.inf, self.rng.random(1), LINE_START)
        _, centre, width = self.line
        low, high = max(0.0, float(centre[0]) - width), min(1.0, float(centre[0]) + width)
        grid = np.linspace(low, high, self.popsize)
        grid = grid[np.argsort(np.abs(grid - centre[0]), kind="stable")]  # a budget cut keeps the nearest
        self._pending = [np.array([x]) for x in grid][: self.remaining]
        return self._pending

    def _ask_cma(self) -> list[np.ndarray]:
        import cma

        if self.es is None or self.es.stop():
            if self.es is not None:  # converged: restart with a doubled population (IPOP)
                self.restarts += 1
                self.popsize *= 2
            x0 = self.best[1] if self.best is not None and self.restarts == 0 else self.rng.random(self.dims)
            self.es = cma.CMAEvolutionStrategy(
                list(x0),
                0.3,
                {
                    "bounds": [0, 1],
                    "popsize": self.popsize,
                    "verbose": -9,
                    "seed": self.seed + 1 + self.restarts,
                },
            )
        self._pending = [np.clip(np.asarray(x), 0, 1) for x in self.es.ask()][: self.remaining]
        return self._pending

    def tell(self, points: list[tuple[str, np.ndarray]], objectives: list[float]) -> None:
        """Results of the last batch, in its order."""
        for (_, u), f in zip(points, objectives):
            if self.best is None or f < self.best[0]:
                self.best = (f, np.asarray(u))
        line_points = [(f, u) for (phase, u), f in zip(points, objectives) if phase == "line"]
        if line_points and self.line is not None:
            f, u = min([(self.line[0], self.line[1]), *line_points], key=lambda p: p[0])
            grid = [float(p[0]) for _, p in line_points]
            self.line = (f, np.asarray(u), (max(grid) - min(grid)) / max(len(grid) - 1, 1))
        cma_points = [(u, f) for (phase, u), f in zip(points, objectives) if phase == "cma"]
        if cma_points and self.es is not None:
            us, fs = zip(*cma_points)
            if len(us) == self.es.popsize:
                self.es.tell(list(us), list(fs))
            else:  # the budget cut the population short: the search ends here
                self.es = None


class _Driver:
    """Runs searches on the cluster in batches the size of the worker pool, taking the points
    already simulated from the history (a resumed search asks the same points again) and
    appending the new ones to it.
    """

    def __init__(self, client, folder: Path, done: dict, sweep, base: dict, properties, progress, key: str):
        self.client, self.folder, self.done, self.key = client, folder, done, key
        self.properties, self.progress = properties, progress
        self.workers = max(len(client.scheduler_info().get("workers", {})), 1)
        from ..sweep.engine import shared

        self.sweep, self.base = shared(client, sweep), shared(client, base)  # sent to each worker once
        self.finished = 0  # simulations of the calls before (the progress bar counts on)

    def _simulate(self, tasks: list[tuple]) -> list[dict]:
        """Each (function, *arguments) task's result; one that ends its worker, run again alone,
        is a run with status ``crashed`` (:func:`nnrobust.sweep.engine.run_tasks`).
        """
        from ..sweep.engine import CRASHED, run_tasks

        crashed = {"status": CRASHED}
        return run_tasks(self.client, tasks, lambda why: judged({**crashed, "message": why}, self.properties))

    def __call__(self, searches: dict, boxes: dict, rows: dict, total: int, stop_at_violation=False):
        """Run every search to the end of its budget (or to its first violation); ``total``: the
        simulations this call plans, for the progress bar.
        """
        planned = self.finished + total
        while any(s.remaining > 0 for s in searches.values()):
            asked = {
                key: search.ask(self.workers) for key, search in searches.items() if search.remaining > 0
            }
            tasks: dict[tuple, tuple] = {}
            for key, points in asked.items():
                for offset, (_, u) in enumerate(points):
                    index = len(rows[key]) + offset
                    cached = self.done.get((*key, index))
                    if cached is None or not np.allclose(cached["u"], u, atol=1e-12):
                        tasks[(key, index)] = (
                            evaluate,
                            self.sweep,
                            self.base,
                            key[0],
                            boxes[key].values(u),
                            self.properties,
                        )
            results = dict(zip(tasks, self._simulate(list(tasks.values()))))
            new = []
            for key, points in asked.items():
                for phase, u in points:
                    index = len(rows[key])
                    if (key, index) in results:
                        row = {
                            "controller": key[0],
                            "search": key[1],
                            "index": index,
                            "phase": phase,
                            "u": [float(x) for x in u],
                            "values": boxes[key].values(u),
                            **results[(key, index)],
                        }
                        new.append(row)
                    else:
                        row = self.done[(*key, index)]
                    rows[key].append(row)
                searches[key].tell(points, [r["objective"] for r in rows[key][-len(points) :]])
                if stop_at_violation and any(r["objective"] < 0 for r in rows[key]):
                    searches[key].budget = searches[key].asked  # a violation is all the margin needs
            if new:
                _write_history(self.folder, new, self.key)
            if self.progress:
                self.progress(self.finished + sum(len(rows[key]) for key in searches), planned)
        self.finished += sum(len(rows[key]) for key in searches)


@dataclass
class _Bracket:
    """One controller's margin search: the largest scale without a violation found (``low``), the
    least with one (``high``), the scale to search next, and what each scale gave.
    """

    cap: float
    low: float | None = None
    high: float | None = None
    next: float | None = None
    plant: dict | None = None
    steps: list[dict] = field(default_factory=list)

    def record(self, scale: float, history: list[dict]) -> None:
        """The search at ``scale`` ended: narrow the bracket and choose the next scale (doubling
        until a violation, the centre once one is found, then bisection to MARGIN_TOLERANCE).
        """
        worst = min(history, key=lambda r: r["objective"])
        violated = worst["objective"] < 0
        self.steps.append(
            {
                "scale": scale,
                "falsified": violated,
                "simulations": len(history),
                "least_margin": worst["objective"],
            }
        )
        if violated:
            self.high, self.plant = scale, worst
        else:
            self.low = scale
        if self.high is None:  # not violated yet: double, up to the cap
            self.next = None if scale >= self.cap else min(2 * scale, self.cap)
        elif self.low is None:  # violated: does the centre of the box (the nominal plant) hold?
            self.next = None if scale == 0.0 else 0.0
        elif self.high - self.low <= MARGIN_TOLERANCE * self.high:
            self.next = None
        else:
            self.next = 0.5 * (self.low + self.high)


def _margins(spec: FalsifySpec, sweep, box: Box, rows: dict, drive: _Driver) -> dict:
    """The robustness margin of each controller: the box scaled by s about its centre, s searched
    by doubling from the box itself (s = 1, the main search) up to :meth:`Box.largest_scale`,
    then by bisection, each scale searched at ``spec.margin_budget`` simulations and stopped at
    its first violation. Where the box itself is violated, the centre (s = 0) is tried first.
    """
    from ..sweep.spec import Sample, rerun_command, sample_seed

    brackets = {name: _Bracket(box.largest_scale()) for name in sweep.controllers}
    for name, bracket in brackets.items():
        bracket.record(1.0, rows[(name, "falsifier")])
    for step in range(MARGIN_STEPS):
        active = [(name, b.next) for name, b in brackets.items() if b.next is not None]
        if not active:
            break
        searches, boxes = {}, {}
        for i, (name, scale) in enumerate(active):
            key = (name, f"margin {scale:.6g}")
            budget = 1 if scale == 0.0 else spec.margin_budget
            searches[key] = _Search(len(box.keys), budget, spec.seed + 104729 * (step + 1) + 7919 * i, False)
            boxes[key] = box.scaled(scale)
            rows[key] = []
        drive(searches, boxes, rows, sum(s.budget for s in searches.values()), stop_at_violation=True)
        for (name, scale), key in zip(active, searches):
            brackets[name].record(scale, rows[key])
    out = {}
    for name, b in brackets.items():
        plant = None
        if b.plant is not None:
            command = rerun_command(sweep, Sample(-1, b.plant["values"], sample_seed(sweep.seed, 0)), name)
            plant = {"values": b.plant["values"], "margins": b.plant["margins"], "command": command}
        out[name] = {
            "holds_up_to": b.low if b.low is not None else 0.0,
            "violated_at": b.high,
            "largest_scale": b.cap,
            "simulations": sum(x["simulations"] for x in b.steps[1:]),
            "steps": b.steps,
            "violating_plant": plant,
        }
    return out


HISTORY_IDS = ("controller", "search", "index")
"""The columns of the history that name a row."""


def _history(folder: Path, key: str | None) -> dict[tuple[str, str, int], dict]:
    """The rows simulated so far, by (controller, search, index); each part checked against
    ``key`` (the search's inputs; None: those the folder's marker records) and no row twice.
    """
    from ..study_folder import read_parts, recorded_inputs

    if key is None:
        recorded = recorded_inputs(folder, "falsify")
        key = recorded.key if recorded is not None else None
    tables = read_parts(folder / HISTORY, [*HISTORY_IDS, "row"], key, HISTORY_IDS)
    rows = [json.loads(r) for t in tables for r in t.column("row").to_pylist()]
    return {(r["controller"], r["search"], r["index"]): r for r in rows}


def _write_history(folder: Path, rows: list[dict], key: str) -> None:
    """One Parquet part of history rows, tied to the search's inputs (``key``)."""
    import pandas as pd
    import pyarrow as pa

    from ..study_folder import write_part

    flat = [
        {
            "controller": r["controller"],
            "search": r["search"],
            "index": r["index"],
            "phase": r["phase"],
            "objective": r["objective"],
            **{f"value.{k}": v for k, v in r["values"].items()},
            "row": json.dumps(r),
        }
        for r in rows
    ]
    write_part(folder / HISTORY, pa.Table.from_pandas(pd.DataFrame(flat), preserve_index=False), key)


def search_inputs(spec: FalsifySpec, sweep):
    """What the search's rows are computed from (:func:`nnrobust.sweep.spec.study_inputs`): the
    box and the base as searched, the controllers with their tuned settings, and the options.
    """
    from ..sweep.spec import study_inputs

    options = {
        "--require": json.dumps(spec.require),
        "--budget": str(spec.budget),
        "--seed": str(spec.seed),
        "--margin": str(spec.margin),
    }
    return study_inputs(sweep, options)


def prepare_folder(spec: FalsifySpec, folder: Path, overwrite: bool, inputs) -> None:
    """Create DIR or accept it for resuming the same search on the same ``inputs``
    (:func:`search_inputs`); one of other inputs is refused, naming what changed, unless
    ``overwrite``, which replaces only what a search wrote (:mod:`nnrobust.study_folder`).
    """
    from ..study_folder import prepare

    outputs = (
        HISTORY,
        MARKER,
        "summary.json",
        "falsification.csv",
        "convergence.png",
        "convergence.svg",
        WORST,
    )
    prepare(folder, "falsify", spec.to_toml(), outputs, overwrite, "search", HISTORY, MARKER, inputs)


def run_falsify(
    spec: FalsifySpec,
    folder: str | Path,
    workers: int | None = None,
    scheduler: str | None = None,
    overwrite: bool = False,
    progress=None,
    claim: tuple[float, float] = (0.05, 0.05),
) -> dict:
    """Search each controller's worst plant and its random baseline; returns the summary (also
    DIR/summary.json, DIR/falsification.csv and DIR/convergence.png). The folder is locked for
    the search. ``claim`` = (epsilon, beta): the random baseline's runs, independent draws of the
    box, certify P(a property fails) <= epsilon with confidence 1 - beta (:func:`certify_box`).
    """
    from ..properties import check_claim
    from ..study_folder import held

    check_claim(*claim)
    with held(Path(folder)):
        return _run_falsify(spec, Path(folder), workers, scheduler, overwrite, progress, claim)


def _run_falsify(
    spec: FalsifySpec, folder: Path, workers, scheduler, overwrite: bool, progress, claim: tuple[float, float]
) -> dict:
    from ..properties import run_properties
    from ..sweep.engine import _client, _require_engine, check_controllers
    from ..sweep.spec import Sample, experiment, rerun_command, sample_seed

    _require_engine()
    try:
        import cma  # noqa: F401
    except ImportError as err:
        raise NNRobustError(
            f"falsify needs the cma package ({err}); pip install 'nnrobust[falsify]'"
        ) from err
    properties = run_properties(spec.require)
    sweep, base, expanded = _searched_sweep(spec)
    box = box_of(sweep)
    for name in sweep.controllers:  # every controller's experiment validated before anything runs
        for corner in (np.zeros(len(box.keys)), np.ones(len(box.keys))):
            experiment(sweep, base, Sample(-1, box.values(corner), sample_seed(sweep.seed, 0)), name)
    check_controllers(sweep, base, box.values(np.full(len(box.keys), 0.5)))  # each built, its first step run
    folder = Path(folder)
    inputs = search_inputs(spec, sweep)
    prepare_folder(spec, folder, overwrite, inputs)
    done = _history(folder, inputs.key)
    searches = {
        (name, kind): _Search(
            len(box.keys),
            spec.budget,
            spec.seed + 7919 * i + (1 if kind == "random" else 0),
            kind == "random",
        )
        for i, name in enumerate(sweep.controllers)
        for kind in ("falsifier", "random")
    }
    rows: dict[tuple[str, str], list[dict]] = {key: [] for key in searches}
    total = len(searches) * spec.budget
    started = time.monotonic()
    with signals_as_interrupt(), _client(workers, scheduler) as client:
        if progress:  # before any work: what the folder already holds of this search
            progress(sum((c, s) in searches and i < spec.budget for c, s, i in done), total)
        drive = _Driver(client, folder, done, sweep, base, properties, progress, inputs.key)
        drive(searches, dict.fromkeys(searches, box), rows, total)
        margins = _margins(spec, sweep, box, rows, drive) if spec.margin else None
    seconds = time.monotonic() - started
    summary = _summary(spec, sweep, box, properties, rows, seconds, rerun_command, Sample, sample_seed)
    if expanded:
        summary["searched_as"] = expanded
    for name in sweep.controllers:
        summary["controllers"][name]["certificate"] = certify_box(
            sweep, box, properties, rows[(name, "random")], *claim
        )
    if margins is not None:
        summary["margin"] = margins
    from ..results import write_json_atomic

    write_json_atomic(folder / "summary.json", summary)
    _write_csv(folder, summary)
    plot_convergence({k: v for k, v in rows.items() if k[1] in ("falsifier", "random")}, folder)
    from ..display import FalsifySummary

    return FalsifySummary(summary)


def _summary(spec, sweep, box, properties, rows, seconds, rerun_command, Sample, sample_seed) -> dict:
    out = {
        "target": spec.target,
        "budget": spec.budget,
        "seed": spec.seed,
        "properties": [p.text for p in properties],
        "box": {
            k: {"low": float(lo), "high": float(hi), "log": bool(g)}
            for k, lo, hi, g in zip(box.keys, box.low, box.high, box.log)
        },
        "seconds": seconds,
        "controllers": {},
    }
    for name in sweep.controllers:
        entry = {}
        for kind in ("falsifier", "random"):
            history = rows[(name, kind)]
            worst = min(history, key=lambda r: r["objective"])
            least = min(worst["margins"].values())
            sample = Sample(-1, worst["values"], sample_seed(sweep.seed, 0))
            entry[kind] = {
                "falsified": bool(least < 0 or any(not p.holds({**worst["metrics"]}) for p in properties)),
                "simulations": len(history),
                "first_violation": next((i + 1 for i, r in enumerate(history) if r["objective"] < 0), None),
                "worst": {
                    "values": worst["values"],
                    "metrics": worst["metrics"],
                    "margins": worst["margins"],
                    "margin": least,
                    "command": rerun_command(sweep, sample, name),
                },
            }
        out["controllers"][name] = {**entry.pop("falsifier"), "random_baseline": entry["random"]}
    return out


def certify_box(
    sweep, box: Box, properties: list[Property], history: list[dict], epsilon: float, beta: float
):
    """What the random baseline's runs prove: its points are independent uniform draws of the box
    (log-uniform on loguniform keys, a grid's range uniformly), so its N runs with k failures give
    each property's one-sided Clopper-Pearson bound on P(fail) over that distribution, and Wilks'
    bound on its metric (:func:`nnrobust.properties.certify_runs`). The falsifier's own points
    were chosen by a search and never count.
    """
    import hashlib

    from ..properties import certify_runs

    described = repr(
        [(k, float(lo), float(hi), bool(g)) for k, lo, hi, g in zip(box.keys, box.low, box.high, box.log)]
    ) + repr((sorted(sweep.set.items()), sweep.seed))
    distribution = hashlib.sha256(described.encode()).hexdigest()
    certificates, bounds = certify_runs([r["metrics"] for r in history], properties, epsilon, beta)
    for entry in certificates:
        entry["distribution"] = distribution
        entry["method"] = (
            "one-sided Clopper-Pearson (exact binomial) bound on P(fail) from the random baseline's "
            "runs: independent uniform draws of the box (log-uniform on loguniform keys), each run at "
            "the sweep's first sample seed; the falsifier's points never count"
        )
    return {"certificates": certificates, "quantile_bounds": bounds}


WORST = "worst"
"""Sub-folder of the worst plants' run folders (``--keep-worst``)."""


def keep_worst(spec: FalsifySpec, summary: dict, folder: str | Path, count: int = 1) -> list[Path]:
    """The ``count`` worst plants the search found for each controller, rerun on this machine as
    full run folders (arrays, metrics, plots, animation): DIR/worst/CONTROLLER for the worst (the
    run its printed command makes), DIR/worst/CONTROLLER-2, -3, ... for the next distinct ones,
    from the search's history in order of their least margin.
    """
    from ..experiment import run_experiment
    from ..run_folder import write_run
    from ..sweep.spec import Sample, experiment, sample_seed

    sweep, base, _ = _searched_sweep(spec)
    history = _history(Path(folder), None) if count > 1 else {}
    written = []
    for name, entry in summary["controllers"].items():
        plants = [entry["worst"]["values"]]
        ranked = sorted(
            (r for (c, search, _), r in history.items() if c == name and search == "falsifier"),
            key=lambda r: r["objective"],
        )
        for row in ranked:
            if len(plants) >= count:
                break
            if row["values"] not in plants:
                plants.append(row["values"])
        for rank, values in enumerate(plants, start=1):
            config = experiment(sweep, base, Sample(-1, values, sample_seed(sweep.seed, 0)), name)
            target = Path(folder) / WORST / (name if rank == 1 else f"{name}-{rank}")
            written.append(write_run(target, run_experiment(config), overwrite=True))
    return written


def _write_csv(folder: Path, summary: dict) -> None:
    """DIR/falsification.csv in the ARCH-COMP falsification format: one row per controller and
    property (system, property, falsified, simulations, time, robustness).
    """
    lines = ["system,property,falsified,simulations,time,robustness"]
    for name, entry in summary["controllers"].items():
        for prop, margin in entry["worst"]["margins"].items():
            lines.append(
                f'{name},"{prop}",{"yes" if margin < 0 else "no"},{entry["simulations"]},'
                f"{summary['seconds']:.1f},{margin:.6g}"
            )
    tmp = folder / ".falsification.csv.partial"
    tmp.write_text("\n".join(lines) + "\n")
    os.replace(tmp, folder / "falsification.csv")


def plot_convergence(rows: dict, folder: Path) -> None:
    """DIR/convergence.png and .svg: the least margin found against simulations, per controller,
    for the falsifier and its random baseline.
    """
    from ..plots import _save, legend_outside, plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for i, (name, kind) in enumerate(sorted(rows)):
        objective = np.minimum.accumulate([r["objective"] for r in rows[(name, kind)]])
        ax.plot(
            np.arange(1, objective.size + 1),
            objective,
            color=f"C{sorted({n for n, _ in rows}).index(name)}",
            ls="-" if kind == "falsifier" else ":",
            label=f"{name} ({kind})",
        )
    ax.axhline(0.0, color="k", lw=0.8)
    ax.set_xlabel("simulations")
    ax.set_ylabel("least margin found (< 0: falsified)")
    ax.set_yscale("symlog", linthresh=0.01)
    legend_outside(ax)
    _save(fig, folder, "convergence")
