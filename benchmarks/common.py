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


def run_rows(jobs: list[dict], workers: int | None = None, echo=None) -> list[dict]:
    """Every job's row, in order, on ``workers`` processes (default: the machine's cores)."""
    workers = workers or os.cpu_count() or 1
    rows = []
    if workers == 1:
        for job in jobs:
            rows.append(run_row(job))
            if echo:
                echo(rows[-1])
        return rows
    with ProcessPoolExecutor(workers) as pool:
        for row in pool.map(run_row, jobs):
            rows.append(row)
            if echo:
                echo(row)
    return rows
