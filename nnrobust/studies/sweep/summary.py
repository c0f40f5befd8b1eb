"""What a sweep found: per-controller statistics (DIR/summary.json) and the worst samples."""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np

from ...core.drawing import drawn_alone
from ...run.results import write_json_atomic
from ..base.display import html_cell, table
from ..base.plan import SweepSpec, draw, rerun_command

STATISTICS = ("rms_error_after_2s", "rms_torque", "torque_chatter")


def _stats(values: np.ndarray) -> dict:
    values = values[np.isfinite(values)]
    if not values.size:
        return {"median": None, "p95": None, "max": None}
    return {
        "median": float(np.median(values)),
        "p95": float(np.percentile(values, 95)),
        "max": float(values.max()),
    }


def _equal(cell, value) -> bool:
    """A results cell equals a grid value (list cells come back from Parquet as arrays)."""
    return (np.asarray(cell).tolist() if isinstance(value, list) else cell) == value


def warning_kinds(warnings) -> dict[str, int]:
    """How many rows carry each kind of warning (a warning's words before its colon)."""
    counts: dict[str, int] = {}
    for row in warnings:
        for kind in {str(w).split(":", 1)[0] for w in row}:
            counts[kind] = counts.get(kind, 0) + 1
    return dict(sorted(counts.items()))


def summarize(spec: SweepSpec, frame) -> dict:
    """Per controller: rows, how many of each status, success rate (completed runs), the median,
    95th percentile and maximum of the RMS error (t >= 2 s) and RMS torque over completed runs, the same error
    statistics at each value of every grid key (``by_grid``), the mean saturated fraction, how
    many rows carry warnings and how many each kind of warning (``warnings_by_kind``: the words
    before its colon), and the worst sample with its rerun command; and ``paired``, every pair of
    controllers compared sample by sample (:func:`nnrobust.studies.base.paired.compare`).
    """
    out: dict = {"sweep": spec.name, "samples": spec.size, "controllers": {}}
    for controller in spec.controllers:
        rows = frame[frame["controller"] == controller]
        completed = rows[rows["status"] == "completed"]
        entry: dict[str, object] = {
            "rows": int(len(rows)),
            "statuses": {str(k): int(v) for k, v in rows["status"].value_counts().sort_index().items()},
            "success_rate": float(len(completed) / len(rows)) if len(rows) else None,
            "saturated_fraction_mean": (
                float(completed["saturated_fraction"].mean()) if len(completed) else None
            ),
            "rows_with_warnings": int(sum(len(w) > 0 for w in rows["warnings"])),
            "warnings_by_kind": warning_kinds(rows["warnings"]),
        }
        for key in STATISTICS:
            entry[key] = _stats(completed[key].to_numpy(dtype=float))
        entry["by_grid"] = {
            key: {
                str(value): _stats(
                    completed[completed[key].map(lambda v, w=value: _equal(v, w))][
                        "rms_error_after_2s"
                    ].to_numpy(dtype=float)
                )
                for value in spec.vary[key]
            }
            for key in spec.grid_keys
        }
        ranked = completed[np.isfinite(completed["rms_error_after_2s"].to_numpy(dtype=float))]
        if len(ranked):
            worst = ranked.loc[ranked["rms_error_after_2s"].idxmax()]
            sample = draw(spec, int(worst["sample"]))
            entry["worst"] = {
                "sample": int(worst["sample"]),
                "rms_error_after_2s": float(worst["rms_error_after_2s"]),
                "values": sample.values,
                "command": rerun_command(spec, sample, controller),
            }
        out["controllers"][controller] = entry
    out["warnings"] = policy_warnings(spec)
    if len(spec.controllers) > 1:  # every pair on the same samples (nnrobust.studies.base.paired)
        from ..base.paired import all_pairs

        out["paired"] = all_pairs(frame, list(spec.controllers))
    return SweepSummary(out)


def policy_warnings(spec: SweepSpec) -> list[str]:
    """A warning per learned policy the sweep scores outside the horizon its record says it was
    trained on (nnrobust.controllers.laws.policy.horizon_warning).
    """
    from ...controllers.laws.policy import horizon_warning
    from ...run.results import SETTLED_AFTER
    from ..base.plan import base_config

    duration = base_config(spec).simulation.duration
    out = []
    for name in spec.controllers:
        entry = spec.entries.get(name, {})
        file = (entry.get("params") or {}).get("file")
        if entry.get("kind") == "policy" and isinstance(file, str):
            said = horizon_warning(name, file, duration, SETTLED_AFTER)
            if said:
                out.append(said)
    return out


def write_summary(folder: str | Path, summary: dict) -> Path:
    """DIR/summary.json, atomically."""
    return write_json_atomic(Path(folder) / "summary.json", summary)


def format_summary(summary: dict) -> str:
    """The closing table: one line per controller (errors in mm, torques in N m)."""
    head = (
        f"{'controller':16s} {'rows':>6s} {'ok %':>6s} {'median e [mm]':>14s} {'p95 e [mm]':>11s} "
        f"{'max e [mm]':>11s} {'median tau':>11s} {'p95 tau':>9s} {'sat %':>6s}"
    )
    lines = [head, "-" * len(head)]

    def mm(v):
        return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{1e3 * v:.3g}"

    def nm(v):
        return "-" if v is None else f"{v:.3g}"

    for controller, e in summary["controllers"].items():
        ok = "-" if e["success_rate"] is None else f"{100 * e['success_rate']:.0f}"
        sat = "-" if e["saturated_fraction_mean"] is None else f"{100 * e['saturated_fraction_mean']:.2f}"
        err, tau = e["rms_error_after_2s"], e["rms_torque"]
        lines.append(
            f"{controller:16s} {e['rows']:6d} {ok:>6s} {mm(err['median']):>14s} "
            f"{mm(err['p95']):>11s} {mm(err['max']):>11s} {nm(tau['median']):>11s} "
            f"{nm(tau['p95']):>9s} {sat:>6s}"
        )
    if summary.get("paired"):
        from ..base.paired import format_pair

        lines.append("paired on the same samples, RMS error after 2 s (A - B; 95 % interval; sign test):")
        lines += [f"  {format_pair(entry)}" for entry in summary["paired"]]
    return "\n".join(lines)


@drawn_alone
def plot_sweep(spec: SweepSpec, frame, folder: str | Path) -> list[Path]:
    """DIR/plots: the error CDF per controller, the error against each varied key and the Pareto
    picture of error against torque (completed runs; errors in mm over t >= 2 s).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd

    out = Path(folder) / "plots"
    out.mkdir(parents=True, exist_ok=True)
    done = frame[frame["status"] == "completed"]
    written = []

    def log_scale(ax, axis: str, values, empty: str = "no completed run lasted past 2 s") -> None:
        """A log axis where the data has a positive value to show; else linear, and said."""
        values = np.asarray(values, dtype=float)
        if np.any(np.isfinite(values) & (values > 0)):
            getattr(ax, f"set_{axis}scale")("log")
        else:
            ax.text(0.5, 0.5, empty, transform=ax.transAxes, ha="center", va="center", color="0.4")

    def legend(ax) -> None:
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)

    def save(fig, name):
        path = out / f"{name}.png"
        fig.tight_layout()
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)

    fig, ax = plt.subplots(figsize=(6, 4))
    for controller in spec.controllers:
        errors = np.sort(done[done["controller"] == controller]["rms_error_after_2s"].to_numpy(dtype=float))
        errors = errors[np.isfinite(errors)]
        if errors.size:
            ax.step(1e3 * errors, np.arange(1, errors.size + 1) / errors.size, where="post", label=controller)
    ax.set_xlabel("RMS task error, t >= 2 s [mm]")
    log_scale(ax, "x", done["rms_error_after_2s"])
    ax.set_ylabel("fraction of samples")
    ax.set_title(f"{spec.name}: error distribution ({spec.size} samples)")
    ax.grid(True, which="both", alpha=0.3)
    legend(ax)
    save(fig, "error_cdf")

    for key in spec.vary:
        fig, ax = plt.subplots(figsize=(6, 4))
        for controller in spec.controllers:
            rows = done[done["controller"] == controller]
            values = rows[key]
            labels = None
            if not pd.api.types.is_numeric_dtype(values):  # lists, strings, mixed: plot against their index
                labels = sorted({str(v) for v in done[key]})
                values = [labels.index(str(v)) for v in values]
            error = 1e3 * rows["rms_error_after_2s"].to_numpy(dtype=float)
            shown = np.isfinite(error)
            if shown.any():
                ax.scatter(
                    np.asarray(values, dtype=float)[shown], error[shown], s=10, alpha=0.6, label=controller
                )
            if labels is not None:
                ax.set_xticks(range(len(labels)), [label[:20] for label in labels], fontsize=7)
        log_scale(ax, "y", done["rms_error_after_2s"])
        ax.set_xlabel(key)
        ax.set_ylabel("RMS task error, t >= 2 s [mm]")
        ax.grid(True, which="both", alpha=0.3)
        legend(ax)
        save(fig, f"error_vs_{key.replace('.', '_')}")

    fig, ax = plt.subplots(figsize=(6, 4))
    torque = done["rms_torque"].to_numpy(dtype=float)
    error = done["rms_error_after_2s"].to_numpy(dtype=float)
    both = np.isfinite(torque) & (torque > 0) & np.isfinite(error) & (error > 0)
    for controller in spec.controllers:
        mine = both & (done["controller"] == controller).to_numpy()
        if mine.any():
            ax.scatter(torque[mine], 1e3 * error[mine], s=10, alpha=0.6, label=controller)
    log_scale(ax, "x", torque[both], "no completed run lasted past 2 s")
    log_scale(ax, "y", error[both])
    ax.set_xlabel("RMS torque [N m]")
    ax.set_ylabel("RMS task error, t >= 2 s [mm]")
    ax.set_title("error against torque, every sample")
    ax.grid(True, which="both", alpha=0.3)
    legend(ax)
    save(fig, "pareto")
    return written


def keep_worst(spec: SweepSpec, frame, folder: str | Path, count: int) -> list[Path]:
    """Full run folders (arrays, metrics, plots, animation) of the ``count`` worst completed
    samples of each controller, in DIR/worst/CONTROLLER-sample-ID, rerun on this machine.
    """
    from ...outputs.run_folder import write_run
    from ...run.experiment import run_experiment
    from ..base.plan import base_config, experiment

    base = base_config(spec)
    written = []
    done = frame[(frame["status"] == "completed") & np.isfinite(frame["rms_error_after_2s"].astype(float))]
    for controller in spec.controllers:
        rows = done[done["controller"] == controller].nlargest(count, "rms_error_after_2s")
        for sample_id in rows["sample"]:
            config = experiment(spec, base, draw(spec, int(sample_id)), controller)
            target = Path(folder) / "worst" / f"{controller}-sample-{int(sample_id)}"
            written.append(write_run(target, run_experiment(config), overwrite=True))
    return written


class SweepSummary(dict):
    """A sweep's summary.json: per controller its rows, success rate and error statistics, and the
    paired comparisons.
    """

    def _repr_html_(self) -> str:
        rows = []
        for name, e in self["controllers"].items():
            err = e.get("rms_error_after_2s") or {}
            rows.append(
                [
                    html.escape(name),
                    html_cell(e.get("rows")),
                    html_cell(e.get("success_rate"), 100, 3),
                    html_cell(err.get("median"), 1e3),
                    html_cell(err.get("p95"), 1e3),
                    html_cell(err.get("max"), 1e3),
                ]
            )
        out = f"<h4>sweep {html.escape(str(self.get('sweep')))}: {self.get('samples')} samples</h4>"
        out += table(["controller", "rows", "completed %", "median e [mm]", "p95 e [mm]", "max e [mm]"], rows)
        if self.get("paired"):
            from ..base.paired import format_pair

            out += (
                "<ul>" + "".join(f"<li>{html.escape(format_pair(p))}</li>" for p in self["paired"]) + "</ul>"
            )
        return out
