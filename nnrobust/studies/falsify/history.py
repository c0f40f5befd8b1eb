"""One point of the box: its run on a worker (:func:`evaluate`) and its margins (:func:`judged`);
and the history of points simulated so far, Parquet parts in DIR/history/.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from ...core.exceptions import NNRobustError
from ...run.properties import Property
from .spec import HISTORY

FLOOR = -1e6
"""The objective of a run that did not complete (margin -inf): below every finite margin."""


def _objective(margins: dict[str, float]) -> float:
    least = min(margins.values())
    return max(least, FLOOR) if math.isfinite(least) else FLOOR


def evaluate(sweep, base: dict, controller: str, values: dict, properties: list[Property]) -> dict:
    """One run at one point of the box (on a worker): its margins and the metrics they read;
    ``base``: the base's own values (:func:`nnrobust.studies.base.plan.base_values`).
    """
    import time

    from ...run.experiment import run_experiment
    from ..base.plan import Sample, experiment, sample_seed

    start = time.perf_counter()  # task_seconds: build, run and metrics, as a sweep's rows carry
    sample = Sample(-1, values, sample_seed(sweep.seed, 0))
    try:
        metrics = run_experiment(experiment(sweep, base, sample, controller)).metrics()
    except NNRobustError as err:
        metrics = {"status": "refused", "message": str(err)[:300]}
    except BaseException as err:  # a defect, or user code raising SystemExit or BaseException
        metrics = {"status": "error", "message": f"{type(err).__name__}: {err}"[:300]}
    return {**judged(metrics, properties), "task_seconds": time.perf_counter() - start}


def judged(metrics: dict, properties: list[Property]) -> dict:
    """A run's margins under ``properties`` and the metrics they read."""
    keep = {p.metric for p in properties} | {"status", "message", "rms_error_after_2s", "rms_torque"}
    margins = {p.text: p.margin(metrics) for p in properties}
    return {
        "metrics": {k: metrics.get(k) for k in sorted(keep)},
        "margins": margins,
        "objective": _objective(margins),
    }


HISTORY_IDS = ("controller", "search", "index")
"""The columns of the history that name a row."""


def _history(folder: Path, key: str | None) -> dict[tuple[str, str, int], dict]:
    """The rows simulated so far, by (controller, search, index); each part checked against
    ``key`` (the search's inputs; None: those the folder's marker records) and no row twice.
    """
    from ..base.folder import read_parts, recorded_inputs

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

    from ..base.folder import write_part

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
