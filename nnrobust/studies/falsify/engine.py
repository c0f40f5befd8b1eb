"""Running a search: the folder prepared (or resumed) on the search's inputs, every controller's
search and random baseline on the cluster, then the summary, the CSV and the plot.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from ...core.exceptions import NNRobustError
from ...core.search_coordinates import controller_seed
from ...core.signals import signals_as_interrupt
from .history import _history
from .search import _Driver, _Margins, _Search
from .spec import HISTORY, MARKER, FalsifySpec, _searched_sweep, box_of
from .summary import WORST, _summary, _write_csv, certify_box, plot_convergence


def search_inputs(spec: FalsifySpec, sweep):
    """What the search's rows are computed from (:func:`nnrobust.studies.base.plan.study_inputs`): the
    box and the base as searched, the controllers with their tuned settings, and the options.
    """
    from ..base.plan import study_inputs

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
    ``overwrite``, which replaces only what a search wrote (:mod:`nnrobust.studies.base.folder`).
    """
    from ..base.folder import prepare

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
    ship_files: bool | None = None,
) -> dict:
    """Search each controller's worst plant and its random baseline; returns the summary (also
    DIR/summary.json, DIR/falsification.csv and DIR/convergence.png). The folder is locked for
    the search. ``claim`` = (epsilon, beta): the random baseline's runs, independent draws of the
    box, certify P(a property fails) <= epsilon with confidence 1 - beta (:func:`certify_box`).
    ``ship_files``: send the files the runs read with the tasks
    (:func:`nnrobust.studies.base.cluster.ships_files`; default: on a ``scheduler`` of the user's).
    """
    from ...core.folders import held
    from ...run.properties import check_claim
    from ..base.cluster import check_local_workers, ships_files

    check_claim(*claim)
    check_local_workers(workers, scheduler)  # before the folder is made
    ship = ships_files(ship_files, scheduler)
    with held(Path(folder)):
        return _run_falsify(spec, Path(folder), workers, scheduler, overwrite, progress, claim, ship)


def _run_falsify(
    spec: FalsifySpec,
    folder: Path,
    workers,
    scheduler,
    overwrite: bool,
    progress,
    claim: tuple[float, float],
    ship: bool = False,
) -> dict:
    from ...run.properties import run_properties
    from ..base.cluster import cluster_client as _client
    from ..base.cluster import require_engine as _require_engine
    from ..base.cluster import shipped_files
    from ..base.plan import Sample, check_controllers, experiment, rerun_command, sample_seed

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
            spec.seed + controller_seed(name) + (1 if kind == "random" else 0),
            kind == "random",
        )
        for name in sweep.controllers
        for kind in ("falsifier", "random")
    }
    rows: dict[tuple[str, str], list[dict]] = {key: [] for key in searches}
    total = len(searches) * spec.budget
    started = time.monotonic()
    with signals_as_interrupt(), _client(workers, scheduler) as client:
        if progress:  # before any work: what the folder already holds of this search
            progress(sum((c, s) in searches and i < spec.budget for c, s, i in done), total)
        files = shipped_files(client, inputs, ship)
        drive = _Driver(client, folder, done, sweep, base, properties, progress, inputs.key, files)
        margins = _Margins(spec, sweep, box, rows) if spec.margin else None
        drive(searches, dict.fromkeys(searches, box), rows, total, then=margins)
    seconds = time.monotonic() - started
    summary = _summary(spec, sweep, box, properties, rows, seconds, rerun_command, Sample, sample_seed)
    if expanded:
        summary["searched_as"] = expanded
    for name in sweep.controllers:
        summary["controllers"][name]["certificate"] = certify_box(
            sweep, box, properties, rows[(name, "random")], *claim
        )
    if margins is not None:
        summary["margin"] = margins.result()
    from ...run.results import write_json_atomic

    write_json_atomic(folder / "summary.json", summary)
    _write_csv(folder, summary)
    plot_convergence({k: v for k, v in rows.items() if k[1] in ("falsifier", "random")}, folder)
    from .summary import FalsifySummary

    return FalsifySummary(summary)
