"""What a study's report shows beside its tables, taken from the stages' folders: each tuned law's
search curve per seed, the certification draws on which a kept law failed its requirement (which
property, by how much, and the command that replays the draw), and the kept laws' time responses
on their median and worst certification draws (rerun here, kept in ``cases/C/responses/``,
recomputed only when the experiment they ran changes).
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

from ...core.exceptions import NNRobustError

FAILING_SHOWN = 10
"""The most failing draws a report lists per law and case (the count says how many there were)."""


def tuning_curves(tunings: dict) -> dict[str, dict[int, list]]:
    """Each law's search curve per optimiser seed ([simulations, best feasible training error]),
    from each seed's tuning summary.
    """
    out: dict[str, dict[int, list]] = {}
    for seed, summary in tunings.items():
        for law, entry in summary["controllers"].items():
            out.setdefault(law, {})[int(seed)] = entry.get("curve") or []
    return out


def failing_draws(sweep, rows, properties) -> dict[str, dict]:
    """Per controller of a certification sweep: how many of its draws failed the requirement, and
    the first :data:`FAILING_SHOWN` of them: the sample, its drawn values, the status, each failed
    property with its margin, and the command that replays the draw as a normal run.
    """
    from ..base.plan import draw, rerun_command

    out: dict[str, dict] = {}
    for label, group in rows.groupby("controller", sort=False):
        failing = []
        for record in group.sort_values("sample").to_dict("records"):
            failed = {p.text: p.margin(record) for p in properties if not p.holds(record)}
            if failed:
                failing.append((record, failed))
        shown = []
        for record, failed in failing[:FAILING_SHOWN]:
            sample = draw(sweep, int(record["sample"]))
            shown.append(
                {
                    "sample": int(record["sample"]),
                    "values": sample.values,
                    "status": str(record["status"]),
                    "message": str(record.get("message") or "")[:300],
                    "failed": {k: (v if math.isfinite(v) else None) for k, v in failed.items()},
                    "command": rerun_command(sweep, sample, str(label)),
                }
            )
        out[str(label)] = {"draws": int(len(group)), "failing": len(failing), "shown": shown}
    return out


def responses(sweep, rows, labels: list[str], folder: Path) -> dict[str, dict]:
    """Per controller: its run on the median and on the worst certification draw (by RMS error
    after 2 s; a run that did not complete is the worst) as time-response envelopes
    (:func:`nnrobust.studies.study.figures.response_of`), each stored with the SHA-256 of the experiment
    it ran in ``folder/LABEL.json`` and read back while that experiment is unchanged.
    """
    import numpy as np

    from ...core.folders import own_folder
    from ...run.experiment import run_experiment
    from ...run.results import write_json_atomic
    from ..base.plan import base_config, draw, experiment
    from .figures import RESPONSE_BUCKETS, response_of

    base = base_config(sweep)
    out: dict[str, dict] = {}
    for label in labels:
        group = rows[rows["controller"] == label]
        if not len(group):
            continue
        errors = np.where(
            group["status"] == "completed", group["rms_error_after_2s"].to_numpy(dtype=float), np.inf
        )
        errors = np.where(np.isnan(errors), np.inf, errors)
        order = np.argsort(errors, kind="stable")
        picks = {"median": int(group["sample"].iloc[order[(len(order) - 1) // 2]]),
                 "worst": int(group["sample"].iloc[order[-1]])}  # fmt: skip
        configs = {k: experiment(sweep, base, draw(sweep, s), label) for k, s in picks.items()}
        drawn = f"{RESPONSE_BUCKETS} buckets" + "".join(c.to_toml() for c in configs.values())
        key = hashlib.sha256(drawn.encode()).hexdigest()
        stored = own_folder(folder) / f"{label}.json"
        if stored.is_file():
            data = json.loads(stored.read_text())
            if data.get("experiment_sha256") == key:
                out[label] = data["responses"]
                continue
        runs = {}
        for k, config in configs.items():
            try:
                runs[k] = response_of(run_experiment(config), picks[k])
            except NNRobustError as err:  # a law that raises on this draw: its figure says why
                runs[k] = {"sample": picks[k], "reason": str(err)[:300]}
        write_json_atomic(stored, {"experiment_sha256": key, "responses": runs})
        out[label] = runs
    return out


def failures(rows) -> dict:
    """Per controller: each status other than completed, how many runs ended so and the first
    one's message (why a law lost its certificate, in its own words).
    """
    out: dict = {}
    for label, group in rows.groupby("controller", sort=False):
        failed = group[group["status"] != "completed"].sort_values("sample")
        out[str(label)] = {
            str(status): {"runs": int(len(g)), "first_message": str(g["message"].iloc[0])[:300]}
            for status, g in failed.groupby("status")
        }
    return out


def step_cost(sweep, rows) -> dict:
    """Per controller: the median of its runs' loop time (``wall_seconds``) over the control steps
    of a run [us per step], the backend it ran on and the runs it is read from.
    """
    import numpy as np

    from ..base.plan import base_config

    sim = base_config(sweep).simulation
    steps = sim.duration / sim.control_period
    out = {}
    for label, group in rows.groupby("controller", sort=False):
        done = group[group["status"] == "completed"]
        seconds = done["wall_seconds"].to_numpy(dtype=float)
        seconds = seconds[np.isfinite(seconds)]
        out[str(label)] = {
            "step_cost_us": float(1e6 * np.median(seconds) / steps) if seconds.size else None,
            "backend": str(done["backend"].mode().iloc[0]) if len(done) else None,
            "runs": int(seconds.size),
        }
    return out


REALTIME_REPEATS = 3
"""Passes of the timed step through the recorded run (the realtime stage)."""


def realtime(sweep, labels: list[str], folder: Path) -> dict:
    """Per controller (its entry ``label`` of the certification sweep): its law exported at its
    setting on the sweep's first draw into ``folder/LABEL/law`` and stepped out of Python through
    that run's measured states (nnrobust.outputs.export.time_steps): the step's p50, p99 and max [us],
    heap allocations per step, the control period and p99 over it (the share of the period the law
    takes); or why it has no export (a Python law, a learned policy, no C compiler). Stored in
    ``folder/LABEL/timing.json`` with the SHA-256 of the experiment it timed: a rerun reads it.
    """
    import hashlib

    from ...outputs.export import export_law, recorded_steps, time_steps
    from ...run.results import write_json_atomic
    from ..base.plan import base_config, draw, experiment

    base, first = base_config(sweep), draw(sweep, 0)
    out = {}
    for label in labels:
        config = experiment(sweep, base, first, label)
        key = hashlib.sha256(config.to_toml().encode()).hexdigest()
        stored = folder / label / "timing.json"
        if stored.is_file():
            data = json.loads(stored.read_text())
            if data.get("experiment_sha256") == key:
                out[label] = data["timing"]
                continue
        try:
            export_law(config, folder / label / "law", overwrite=True)
        except NNRobustError as err:
            timing: dict = {"exported": False, "reason": str(err)}
        else:
            inputs, _ = recorded_steps(config)
            try:  # a step that fails out of Python (one that keeps memory it allocated) says why
                timed = time_steps(folder / label / "law", inputs, REALTIME_REPEATS) or {}
            except NNRobustError as err:
                timed = {"reason": str(err)}
            period_us = 1e6 * config.simulation.control_period
            timing = {"exported": True, **timed, "period_us": period_us}
            if "p99_us" in timed:
                timing["p99_share"] = timed["p99_us"] / period_us
        write_json_atomic(stored, {"experiment_sha256": key, "timing": timing})
        out[label] = timing
    return out
