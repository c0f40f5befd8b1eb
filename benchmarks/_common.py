"""Shared by the benchmark scripts: run a list of experiment variants on worker processes and
turn each run into one row of metrics (the scripts import it from their own folder)."""

from __future__ import annotations

import os
import signal
import sys
from concurrent.futures import ProcessPoolExecutor

from nnrobust.config.presets import load_preset
from nnrobust.run.experiment import run_experiment

ROW_METRICS = (
    "status",
    "rms_error_after_2s",
    "max_error",
    "rms_torque",
    "max_torque_cmd",
    "torque_chatter",
    "saturated_fraction",
    "rms_torque_ratio",
    "max_speed_ratio",
    "tracking_error_ratio",
    "max_joint_limit_violation",
    "final_rho_hat",
    "rms_error_early",
    "rms_error_last_fifth",
    "runaway",
    "h_start",
    "h_end",
    "warnings",
    "rms_orientation_error_after_2s",
)
"""The metrics each benchmark row keeps."""


def worst_config(command: str):
    """The experiment of a printed rerun command (``nnrobust run PRESET|FILE.toml --controller C
    --set K=V ...``, as a falsification or a sweep prints a plant's)."""
    import shlex

    from nnrobust.config import apply_overrides, load_config, parse_override

    words = shlex.split(command)
    if words[:2] != ["nnrobust", "run"]:
        raise ValueError(f"not a rerun command (nnrobust run ...): {command[:80]!r}")
    sets = dict(parse_override(words[i + 1]) for i, w in enumerate(words) if w == "--set")
    controller = words[words.index("--controller") + 1]
    base = load_config(words[2]) if words[2].endswith(".toml") else load_preset(words[2])
    return apply_overrides(base.replace(controller={"kind": controller}), sets)


def run_row(job: dict) -> dict:
    """One run: ``job`` = {"preset": name, "changes": {section: {key: value}}, **labels}."""
    config = load_preset(job["preset"]).replace(**job["changes"])
    metrics = run_experiment(config).metrics()
    return {**job, **{k: metrics.get(k) for k in ROW_METRICS}}  # orientation: pose tasks only


PROBE = 1e-6
"""Relative change of the plant's disturbance (or friction, without one) in the probe runs."""

CHAOS = 0.01
"""A row whose probes move a metric by more than this fraction is chaotic: a spread, not a number."""

PROBED_METRICS = ("rms_error_after_2s", "rms_torque", "torque_chatter", "saturated_fraction")


def run_probed_row(job: dict) -> dict:
    """run_row, plus the same run with the plant's disturbance (or friction, if it has no
    disturbance) scaled by 1 +- PROBE: each metric's ``_min`` and ``_max`` over the three, and
    ``chaotic`` when one moves by more than CHAOS. The row's own values are the unprobed run's
    (what a rerun of its job gives)."""
    row = run_row(job)
    config = load_preset(job["preset"]).replace(**job["changes"])
    key = "disturbance_scale" if config.plant.disturbance != "none" else "friction_scale"
    scale = getattr(config.plant, key)
    probes = [row]
    for sign in (1, -1):
        changes = {
            **job["changes"],
            "plant": {**job["changes"].get("plant", {}), key: scale * (1 + sign * PROBE)},
        }
        probes.append(run_row({**job, "changes": changes}))
    row["chaotic"] = False
    for name in PROBED_METRICS:
        values = [p[name] for p in probes if p[name] is not None]
        if not values:
            continue
        row[f"{name}_min"], row[f"{name}_max"] = min(values), max(values)
        scale_ = max(abs(row[name]), 1e-12)
        if name != "saturated_fraction" and (max(values) - min(values)) > CHAOS * scale_:
            row["chaotic"] = True
    return row


def _end_with_parent() -> None:
    """Pool initializer: on Linux the kernel sends this worker SIGTERM when the script that started
    it dies, however it dies (``nnrobust bench`` also stops the script's whole process group)."""
    if sys.platform.startswith("linux"):
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


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
    with ProcessPoolExecutor(workers, initializer=_end_with_parent) as pool:
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


def report(
    args, jobs: list[dict], columns: list[tuple[str, int, object]], runner=run_probed_row, **extra
) -> list[dict]:
    """Run the jobs (each with its chaos probes), print one line per row as it arrives
    (``columns``: header, width, and a function of the row giving the cell text), and write
    {**extra, "rows": rows} to --json."""
    from nnrobust.run.results import write_json_atomic

    print(" ".join(f"{h:>{w}s}" if i else f"{h:{w}s}" for i, (h, w, _) in enumerate(columns)))

    def echo(row):
        print(
            " ".join(
                f"{cell(row):>{w}s}" if i else f"{cell(row):{w}s}" for i, (_, w, cell) in enumerate(columns)
            ),
            flush=True,
        )

    rows = run_rows(jobs, args.workers, echo, runner)
    if args.json:
        write_json_atomic(args.json, {**extra, "rows": rows})
    return rows


def mm(key: str):
    """Cell: a length metric in mm."""
    return lambda r: "-" if r.get(key) is None else f"{1e3 * r[key]:.3f}"


def number(key: str, fmt: str = ".2f", scale: float = 1.0):
    """Cell: a metric with a format."""
    return lambda r: "-" if r.get(key) is None else f"{scale * r[key]:{fmt}}"
