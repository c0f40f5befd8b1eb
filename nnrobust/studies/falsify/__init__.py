"""Searching for the worst admissible plant: ``nnrobust falsify`` (docs/falsification.md).

The uncertainty set is the sweep file's ``[vary]`` box: each ``uniform`` or ``loguniform`` key is
a coordinate (searched on the log scale for ``loguniform``); a grid of numbers is searched over
the range it spans, which contains every grid point. A point of the box is one plant; the
controller's run on it gives each property (``--require``) a signed margin
(:mod:`nnrobust.run.properties`), and the search minimises the least of them: a negative margin
falsifies the property. Every point runs with the same seed, so a point is one plant, the
objective is deterministic, and the printed command reruns it bit for bit.

The search, per controller, at one budget of simulations on a Dask cluster:

1. a scrambled Sobol sequence over the box (a quarter of the budget, a power of two);
2. CMA-ES (the ``cma`` package) from the best point found, in batches the size of the worker
   pool, restarted with a doubled population (IPOP) when it converges, until the budget is spent;
   a box of one coordinate, which CMA-ES does not search, gets a zooming grid instead
   (:meth:`.search._Search._ask_line`);
3. as the reported baseline, the same budget of uniform random points.

The history is written as Parquet parts as it grows; running the same command into the same
folder reuses every point already simulated (the search is deterministic given its seed), so
Ctrl-C keeps what was found and a rerun resumes.
"""

from .engine import prepare_folder, run_falsify, search_inputs
from .history import FLOOR, HISTORY_IDS, evaluate, judged
from .search import LINE_START, LINE_TOLERANCE, MARGIN_STEPS, MARGIN_TOLERANCE
from .spec import HISTORY, MARKER, MAX_BUDGET, MAX_SCALE, Box, FalsifySpec, box_of, searchable
from .summary import WORST, certify_box, keep_worst, plot_convergence

__all__ = [
    "Box",
    "FLOOR",
    "FalsifySpec",
    "HISTORY",
    "HISTORY_IDS",
    "LINE_START",
    "LINE_TOLERANCE",
    "MARGIN_STEPS",
    "MARGIN_TOLERANCE",
    "MARKER",
    "MAX_BUDGET",
    "MAX_SCALE",
    "WORST",
    "box_of",
    "certify_box",
    "evaluate",
    "judged",
    "keep_worst",
    "plot_convergence",
    "prepare_folder",
    "run_falsify",
    "search_inputs",
    "searchable",
]
