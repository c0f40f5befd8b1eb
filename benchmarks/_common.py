"""Shared by the benchmark scripts: run a list of experiment variants on worker processes and
turn each run into one row of metrics (the scripts import it from their own folder)."""

from __future__ import annotations

import os
from concurrent.futures import ProcessPoolExecutor

from nnrobust.experiment import run_experiment
from nnrobust.presets import load_preset

ROW_METRICS = ("status", "rms_error_after_2s", "max_error", "rms_torque", "max_torque_cmd",
               "torque_chatter", "saturated_fraction", "max_joint_limit_violation", "final_rho_hat",
               "rms_error_early", "rms_error_last_fifth", "runaway", "h_start", "h_end", "warnings",
               "rms_orientation_error_after_2s")
"""The metrics each benchmark row keeps."""


def run_row(job: dict) -> dict:
    """One run: ``job`` = {"preset": name, "changes": {section: {key: value}}, **labels}."""
    config = load_preset(job["preset"]).replace(**job["changes"])
    metrics = run_experiment(config).metrics()
    return {**job, **{k: metrics.get(k) for k in ROW_METRICS}}  # orientation: pose tasks only


def run_rows(jobs: list[dict], workers: int | None = None, echo=None, runner=run_row) -> list[dict]:
    """Every job's row, in order, on ``workers`` processes (default: the machine's cores);
    ``runner`` turns a job into its row (a module-level function, so workers can import it)."""
    workers = workers or os.cpu_count() or 1
    rows = []
    if workers == 1:
        for job in jobs:
            rows.append(runner(job))
            if echo:
                echo(rows[-1])
        return rows
    with ProcessPoolExecutor(workers) as pool:
        for row in pool.map(runner, jobs):
            rows.append(row)
            if echo:
                echo(row)
    return rows


def parser(doc: str):
    """The command line every grid benchmark shares: --json and --workers."""
    import argparse

    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("--json", help="write the rows as JSON to this file")
    p.add_argument("--workers", type=int, help="worker processes (default: one per core)")
    return p


def report(args, jobs: list[dict], columns: list[tuple[str, int, object]], **extra) -> list[dict]:
    """Run the jobs, print one line per row as it arrives (``columns``: header, width, and a
    function of the row giving the cell text), and write {**extra, "rows": rows} to --json."""
    from nnrobust.results import write_json_atomic

    print(" ".join(f"{h:>{w}s}" if i else f"{h:{w}s}" for i, (h, w, _) in enumerate(columns)))

    def echo(row):
        print(" ".join(f"{cell(row):>{w}s}" if i else f"{cell(row):{w}s}"
                       for i, (_, w, cell) in enumerate(columns)), flush=True)

    rows = run_rows(jobs, args.workers, echo)
    if args.json:
        write_json_atomic(args.json, {**extra, "rows": rows})
    return rows


def mm(key: str):
    """Cell: a length metric in mm."""
    return lambda r: "-" if r.get(key) is None else f"{1e3 * r[key]:.3f}"


def number(key: str, fmt: str = ".2f", scale: float = 1.0):
    """Cell: a metric with a format."""
    return lambda r: "-" if r.get(key) is None else f"{scale * r[key]:{fmt}}"
