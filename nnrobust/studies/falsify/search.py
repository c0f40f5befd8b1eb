"""The search: per controller, a Sobol start then CMA-ES with IPOP restarts (a zooming grid in a
box of one coordinate), or the random baseline (:class:`_Search`); the batches run on the cluster
(:class:`_Driver`); and the robustness margin's doubling and bisection on the box's scale
(:class:`_Margins`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...core.search_coordinates import controller_seed
from .history import _write_history, evaluate, judged
from .spec import Box, FalsifySpec

MARGIN_STEPS = 7
"""Scales the margin's search tries after the box itself (doubling, then bisection)."""
MARGIN_TOLERANCE = 0.1
"""The margin's bisection stops when its bracket is narrower than this fraction of its top."""


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

    def __init__(self, dims: int, budget: int, seed: int, random: bool, stop_at_violation: bool = False):
        self.dims, self.budget, self.seed, self.random = dims, budget, seed, random
        self.stop_at_violation = stop_at_violation  # a margin's search: its first violation ends it
        self.asked = 0
        self.best: tuple[float, np.ndarray] | None = None
        self.rng = np.random.default_rng(seed)
        # CMA-ES's own normal draws (cma's ``randn`` option): cma would otherwise sample from
        # NumPy's global generator, which every search of the run shares, so a controller's points
        # would depend on the other controllers searched beside it
        self.normal = np.random.default_rng([seed, 1])
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
                    "randn": lambda lam, n: self.normal.standard_normal((lam, n)),
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
    """Runs searches on the cluster, each on its own: as soon as a batch of a search has
    finished, the search is told its results and its next batch is submitted while the other
    searches' simulations run (:func:`nnrobust.studies.base.cluster.run_task_groups`). Points already
    simulated are taken from the history (a resumed search asks the same points again); new ones
    are appended to it. Each search draws from generators of its own (its Sobol start, its random
    points, CMA-ES's normal draws) and asks batches whose points do not depend on their size, so
    a controller's points depend neither on the other controllers of the run nor on the timing of
    their simulations, nor on the number of workers.
    """

    def __init__(
        self, client, folder: Path, done: dict, sweep, base: dict, properties, progress, key: str, files=None
    ):
        self.client, self.folder, self.done, self.key = client, folder, done, key
        self.files = (
            files  # the files sent with the tasks (nnrobust.studies.base.cluster.shipped_files), or None
        )
        self.properties, self.progress = properties, progress
        self.workers = max(len(client.scheduler_info().get("workers", {})), 1)
        from ..base.cluster import shared

        self.sweep, self.base = shared(client, sweep), shared(client, base)  # sent to each worker once
        self.new: list[dict] = []  # history rows not yet written

    def __call__(self, searches: dict, boxes: dict, rows: dict, total: int, then=None) -> None:
        """Run every search to the end of its budget (one with ``stop_at_violation``: to its first
        violation). ``then(key)``, called as the search ``key`` ends, returns the search to run
        next in its place, (key, search, box), or None (the margin's scales, :class:`_Margins`).
        ``total``: the simulations planned, for the progress bar (grown by each search ``then``
        starts).
        """
        from ..base.cluster import CRASHED, run_task_groups

        planned = [total]
        current = {key: key for key in searches}  # a lane of the cluster -> the search it runs
        asked: dict[tuple, tuple[list, list[int]]] = {}  # lane -> (points, those simulated)

        def batch(lane: tuple) -> list[tuple] | None:
            """The lane's next batch of tasks; points the history holds are told at once."""
            while True:
                key = current[lane]
                if searches[key].remaining <= 0:
                    following = then(key) if then else None
                    if following is None:
                        return None
                    key, search, box = following
                    searches[key], boxes[key], rows[key], current[lane] = search, box, [], key
                    planned[0] += search.budget
                    continue
                points = searches[key].ask(self.workers)
                first = len(rows[key])
                simulated = [i for i, (_, u) in enumerate(points) if not self._cached(key, first + i, u)]
                if simulated:
                    asked[lane] = (points, simulated)
                    box = boxes[key]
                    return [
                        (evaluate, self.sweep, self.base, key[0], box.values(points[i][1]), self.properties)
                        for i in simulated
                    ]
                self._tell(key, searches[key], boxes[key], rows, points, {})

        def told(lane: tuple, results: list[dict]) -> list[tuple] | None:
            points, simulated = asked.pop(lane)
            key = current[lane]
            self._tell(key, searches[key], boxes[key], rows, points, dict(zip(simulated, results)))
            if len(self.new) >= len(current) * self.workers:  # about one batch of every search a part
                self._flush()
            if self.progress:
                self.progress(sum(len(rows[k]) for k in searches), planned[0])
            return batch(lane)

        crashed = {"status": CRASHED}
        try:
            run_task_groups(
                self.client,
                {lane: batch(lane) for lane in list(current)},
                lambda why: judged({**crashed, "message": why}, self.properties),
                told,
                self.files,
            )
        finally:
            self._flush()  # what finished is kept, also when interrupted
        if self.progress:
            self.progress(sum(len(rows[k]) for k in searches), planned[0])

    def _cached(self, key: tuple, index: int, u: np.ndarray) -> bool:
        cached = self.done.get((*key, index))
        return cached is not None and np.allclose(cached["u"], u, atol=1e-12)

    def _tell(self, key: tuple, search: _Search, box: Box, rows: dict, points: list, results: dict) -> None:
        """Record a batch (``results``: the simulated points' results by their place in the
        batch; the others from the history) and tell the search.
        """
        for i, (phase, u) in enumerate(points):
            index = len(rows[key])
            if i in results:
                row = {
                    "controller": key[0],
                    "search": key[1],
                    "index": index,
                    "phase": phase,
                    "u": [float(x) for x in u],
                    "values": box.values(u),
                    **results[i],
                }
                self.new.append(row)
            else:
                row = self.done[(*key, index)]
            rows[key].append(row)
        search.tell(points, [r["objective"] for r in rows[key][-len(points) :]])
        if search.stop_at_violation and any(r["objective"] < 0 for r in rows[key]):
            search.budget = search.asked  # a violation is all the margin needs

    def _flush(self) -> None:
        if self.new:
            _write_history(self.folder, self.new, self.key)
            self.new = []


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


class _Margins:
    """The robustness margin of each controller, searched as its searches end (the driver's
    ``then``): the box scaled by s about its centre, s searched by doubling from the box itself
    (s = 1: the main search and the random baseline, violated if either found a violation) up to
    :meth:`Box.largest_scale`, then by bisection, each scale searched at ``spec.margin_budget``
    simulations and stopped at its first violation. Where the box itself is violated, the centre
    (s = 0) is tried first. A controller's scales follow its own searches alone, so they do not
    depend on the other controllers of the run.
    """

    def __init__(self, spec: FalsifySpec, sweep, box: Box, rows: dict):
        self.spec, self.sweep, self.box, self.rows = spec, sweep, box, rows
        self.brackets = {name: _Bracket(box.largest_scale()) for name in sweep.controllers}
        self.ended: set[tuple] = set()

    def __call__(self, key: tuple) -> tuple[tuple, _Search, Box] | None:
        """The search ``key`` ended: the controller's next scale to search, or None."""
        name, kind = key
        bracket = self.brackets[name]
        self.ended.add(key)
        if kind in ("falsifier", "random"):
            if not {(name, "falsifier"), (name, "random")} <= self.ended:
                return None
            bracket.record(1.0, self.rows[(name, "falsifier")] + self.rows[(name, "random")])
        else:
            assert bracket.next is not None  # the scale this search was started for
            bracket.record(bracket.next, self.rows[key])
        step = len(bracket.steps) - 1  # the scales searched so far beyond the box itself
        scale = bracket.next
        if scale is None or step >= MARGIN_STEPS:
            bracket.next = None
            return None
        budget = 1 if scale == 0.0 else self.spec.margin_budget
        seed = self.spec.seed + 104729 * (step + 1) + controller_seed(name)
        search = _Search(len(self.box.keys), budget, seed, False, stop_at_violation=True)
        return (name, f"margin {scale:.6g}"), search, self.box.scaled(scale)

    def result(self) -> dict:
        """Each controller's margin: the scales it holds up to and is violated at, the
        simulations beyond the box, every scale's search and the violating plant's command.
        """
        from ..base.plan import Sample, rerun_command, sample_seed

        out = {}
        for name, b in self.brackets.items():
            plant = None
            if b.plant is not None:
                sample = Sample(-1, b.plant["values"], sample_seed(self.sweep.seed, 0))
                command = rerun_command(self.sweep, sample, name)
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
