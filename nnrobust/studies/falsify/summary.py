"""What a search found: the summary (DIR/summary.json), the random baseline's certificate, the
ARCH-COMP CSV, the convergence plot, and the worst plants rerun as run folders (``--keep-worst``).
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from ...core.drawing import drawn_alone
from ...run.properties import Property
from ..base.display import html_cell, table
from .history import _history
from .spec import Box, FalsifySpec, _searched_sweep


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
                # the search's convergence: the least margin found after each simulation
                "curve": [float(v) for v in np.minimum.accumulate([r["objective"] for r in history])],
                "worst": {
                    "values": worst["values"],
                    "metrics": worst["metrics"],
                    "margins": worst["margins"],
                    "margin": least,
                    "command": rerun_command(sweep, sample, name),
                },
            }
        search, random = entry["falsifier"], entry["random"]
        out["controllers"][name] = {
            **search,
            # the box is falsified by any of its plants that violates a property, whichever of the
            # two searches found it; ``worst`` stays the search's, the baseline's is beside it
            "falsified": search["falsified"] or random["falsified"],
            "falsified_by": [k for k, e in (("search", search), ("random", random)) if e["falsified"]],
            "random_baseline": random,
        }
    return out


def replayed_worst(entry: dict) -> tuple[dict, str]:
    """(the worst plant that replays a controller's verdict, who found it): the search's worst,
    or the random baseline's where only the baseline found a violation (``falsified_by``).
    """
    if entry.get("falsified_by") == ["random"]:
        return entry["random_baseline"]["worst"], "random"
    return entry.get("worst") or {}, "search"


def certify_box(
    sweep, box: Box, properties: list[Property], history: list[dict], epsilon: float, beta: float
):
    """What the random baseline's runs prove: its points are independent uniform draws of the box
    (log-uniform on loguniform keys, a grid's range uniformly), so its N runs with k failures give
    each property's one-sided Clopper-Pearson bound on P(fail) over that distribution, and Wilks'
    bound on its metric (:func:`nnrobust.run.properties.certify_runs`). The falsifier's own points
    were chosen by a search and never count.
    """
    import hashlib

    from ...run.properties import certify_runs

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
    from ...outputs.run_folder import write_run
    from ...run.experiment import run_experiment
    from ..base.plan import Sample, experiment, sample_seed

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
    import csv
    import io

    from ...core.table_text import csv_cell
    from ...run.results import write_text_atomic

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["system", "property", "falsified", "simulations", "time", "robustness"])
    for name, entry in summary["controllers"].items():
        for prop, margin in entry["worst"]["margins"].items():
            row = (name, prop, margin < 0, entry["simulations"], f"{summary['seconds']:.1f}", f"{margin:.6g}")
            writer.writerow([csv_cell(v) for v in row])
    write_text_atomic(folder / "falsification.csv", buffer.getvalue())


@drawn_alone
def plot_convergence(rows: dict, folder: Path) -> None:
    """DIR/convergence.png and .svg: the least margin found against simulations, per controller,
    for the falsifier and its random baseline.
    """
    from ...outputs.plots import legend_outside, plt, save_figure

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
    save_figure(fig, folder, "convergence")


class FalsifySummary(dict):
    """A falsification's summary.json: per controller the verdict, the least margin and the worst
    plant's command.
    """

    def _repr_html_(self) -> str:
        from ..falsify.summary import replayed_worst

        rows = []
        for name, e in self["controllers"].items():
            worst, found_by = replayed_worst(e)
            verdict = "FALSIFIED" if e.get("falsified") else "not falsified"
            if found_by == "random":
                verdict = "FALSIFIED by random search only"
            rows.append(
                [
                    html.escape(name),
                    verdict,
                    html_cell(e.get("simulations")),
                    html_cell(worst.get("margin")),
                    html_cell(((e.get("random_baseline") or {}).get("worst") or {}).get("margin")),
                    f"<code>{html.escape(str(worst.get('command', '')))}</code>",
                ]
            )
        head = ["controller", "verdict", "simulations", "least margin", "random search", "worst plant"]
        props = ", ".join(html.escape(p) for p in self.get("properties", []))
        return f"<h4>falsification of {props}</h4>" + table(head, rows)
