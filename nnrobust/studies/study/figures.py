"""The study report's figures, drawn from the stages' own folders as SVG inside report.html (and
the error CDF as files in figures/): per case, the certification draws' error distribution with
the requirement's line, each tuned law's search (best-so-far against simulations, every seed),
each trained policy's learning curves (beside the tuned laws' training), the falsification's
(least margin found against simulations, search and random baseline), and the kept settings'
time responses (error and torque against time on the median and the worst certification draw).
Long series are drawn as min-max envelopes and text stays text, so a figure is a few tens of kB;
a figure's SVG is the same bytes from the same numbers.
"""

from __future__ import annotations

import base64
import io
import re
from pathlib import Path

import numpy as np

from ...core.drawing import drawn_alone
from ...core.folders import own_folder

RESPONSE_BUCKETS = 60
"""Buckets of a time response's min-max envelope (every peak kept at figure resolution)."""


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def svg_markup(fig, salt: str) -> str:
    """The figure as SVG markup to inline in HTML: text as text, ids salted by ``salt`` (two
    figures of one page never share an id; the same figure is the same bytes), no XML prologue.
    """
    import matplotlib

    small: dict = {"svg.fonttype": "none", "svg.hashsalt": salt, "font.sans-serif": ["DejaVu Sans"]}
    with matplotlib.rc_context(small):  # one font named: each text's style is one name, not eleven
        buffer = io.StringIO()
        fig.savefig(buffer, format="svg")
    text = buffer.getvalue()
    text = re.sub(r"<\?xml[^>]*\?>\s*", "", text)
    text = re.sub(r"<!DOCTYPE[^>]*>\s*", "", text)
    return re.sub(r"<metadata>.*?</metadata>\s*", "", text, flags=re.S)


def requirement_line(require: list[str], metric: str = "rms_error_after_2s") -> float | None:
    """The bound ``require`` puts on ``metric`` from above (``metric<=v`` or ``<v``), or None."""
    for text in require:
        found = re.fullmatch(rf"\s*{metric}\s*<=?\s*(\S+)\s*", text)
        if found:
            return float(found.group(1))
    return None


@drawn_alone
def error_cdf(name: str, folder: Path, require: list[str]) -> tuple[str, str]:
    """The certification draws' error CDF per controller, with the requirement's bound as a
    vertical line: saved as PNG, SVG and PDF in ``figures/``; returned as (inline SVG, base64 PNG).
    """
    import pandas as pd

    plt = _pyplot()
    frame = pd.read_parquet(folder / "cases" / name / "certify" / "results")
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for label, rows in frame.groupby("controller", sort=False):
        done = rows[rows["status"] == "completed"]
        e = np.sort(1e3 * done["rms_error_after_2s"].to_numpy(dtype=float))
        e = e[np.isfinite(e)]
        if e.size:
            ax.step(e, np.arange(1, e.size + 1) / len(rows), where="post", label=str(label))
    bound = requirement_line(require)
    if bound is not None:
        ax.axvline(1e3 * bound, color="k", ls="--", lw=1, label=f"required: <= {1e3 * bound:g} mm")
    ax.set_xscale("log")
    ax.set_xlabel("RMS task error, t >= 2 s [mm]")
    ax.set_ylabel("fraction of draws")
    ax.set_title(f"{name}: certification draws")
    ax.grid(True, which="both", alpha=0.3)
    if ax.get_legend_handles_labels()[0]:  # no completed draw: no line, no legend
        ax.legend(fontsize=8)
    fig.tight_layout()
    out = own_folder(folder / "figures")
    for ext in ("png", "svg", "pdf"):  # drawn beside, renamed into place: never through a link
        tmp = out / f".{name}-error-cdf.partial.{ext}"
        fig.savefig(tmp, dpi=120)
        tmp.replace(out / f"{name}-error-cdf.{ext}")
    markup = svg_markup(fig, f"{name}-cdf")
    plt.close(fig)
    return markup, base64.b64encode((out / f"{name}-error-cdf.png").read_bytes()).decode()


def _plain(ax) -> None:
    """Small tick labels, the major grid only and no minor ticks: what a small panel needs, at a
    fraction of the SVG a log axis' minor ticks and grid lines cost.
    """
    from matplotlib.ticker import LogLocator, MaxNLocator, NullLocator

    ax.tick_params(labelsize=7)
    ax.xaxis.set_major_locator(MaxNLocator(4))
    ax.yaxis.set_major_locator(LogLocator(numticks=4) if ax.get_yscale() == "log" else MaxNLocator(4))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.yaxis.set_minor_locator(NullLocator())
    ax.grid(True, alpha=0.3)


def _inline(fig, plt, title: str, salt: str) -> str:
    """A report figure finished (its title, its layout) as inline SVG markup, then closed."""
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    markup = svg_markup(fig, salt)
    plt.close(fig)
    return markup


def _grid(count: int, plt, height: float = 1.9):
    columns = min(count, 3)
    rows = -(-count // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(3.4 * columns, height * rows + 0.6), squeeze=False)
    for ax in axes.flat[count:]:
        ax.set_visible(False)
    return fig, list(axes.flat[:count])


@drawn_alone
def tuning_curves(name: str, curves: dict[str, dict[int, list]], half: int) -> str | None:
    """Each tuned law's search: the least training error of a feasible setting so far against
    the simulations run, one line per optimiser seed, the half budget marked (where the
    convergence check compares). ``curves``: law -> seed -> [[simulations, error or None], ...].
    """
    laws = {c: seeds for c, seeds in curves.items() if any(seeds.values())}
    if not laws:
        return None
    plt = _pyplot()
    fig, axes = _grid(len(laws), plt)
    for ax, (law, seeds) in zip(axes, laws.items()):
        for seed, curve in sorted(seeds.items()):
            points = [(s, 1e3 * e) for s, e in curve if e is not None]
            if points:
                ax.step(*zip(*points), where="post", lw=1.2, label=f"seed {seed}")
        ax.axvline(half, color="0.6", ls=":", lw=1)
        ax.set_yscale("log")
        ax.set_title(law, fontsize=9)
        _plain(ax)
    axes[0].set_ylabel("best training e [mm]", fontsize=8)
    axes[0].legend(fontsize=7)
    fig.supxlabel("simulations (dotted: half the budget)", fontsize=8)
    return _inline(fig, plt, f"{name}: tuning, best feasible setting so far", f"{name}-tuning")


@drawn_alone
def learning_curves(name: str, trained: dict[str, dict], budgets: dict[str, float]) -> str | None:
    """Each trained policy's learning curve: the median RMS error after 2 s of its validation
    episodes against the simulated seconds of training, one line per seed, with each tuned law's
    training (its tunings' simulations times the run's duration, every seed) marked on the same
    axis. ``trained``: policy -> the report's ``trained`` entry; ``budgets``: tuned law -> seconds.
    """
    laws = {c: t for c, t in trained.items() if t and t.get("curves")}
    if not laws:
        return None
    plt = _pyplot()
    fig, axes = _grid(len(laws), plt, height=2.3)
    for ax, (law, entry) in zip(axes, laws.items()):
        for seed, curve in sorted(entry["curves"].items(), key=lambda item: int(item[0])):
            points = [(p["simulated_seconds"], 1e3 * p["median_rms_error_after_2s"]) for p in curve
                      if np.isfinite(p["median_rms_error_after_2s"])]  # fmt: skip
            if points:
                ax.plot(*zip(*points), marker="o", ms=2.5, lw=1.2, label=f"seed {seed}")
        for i, (tuned, seconds) in enumerate(sorted(budgets.items())):
            ax.axvline(seconds, color=f"C{(i + 3) % 10}", ls=":", lw=1, label=f"{tuned}'s tuning")
        ax.set_yscale("log")
        ax.set_title(f"{law} ({entry['algorithm'].upper()})", fontsize=9)
        _plain(ax)
    axes[0].set_ylabel("validation median e [mm]", fontsize=8)
    axes[0].legend(fontsize=6)
    fig.supxlabel("simulated seconds of training (dotted: the tuned laws' own training)", fontsize=8)
    return _inline(fig, plt, f"{name}: learning curves, every seed", f"{name}-learning")


@drawn_alone
def falsification_curves(name: str, records: dict[str, dict]) -> str | None:
    """Each law's falsification: the least margin found so far against the simulations run, by
    the search and by the random baseline at the same budget (below 0: a property is violated).
    ``records``: law -> the falsification stage's record of it.
    """
    laws = {c: r for c, r in records.items() if r.get("curve")}
    if not laws:
        return None
    plt = _pyplot()
    fig, axes = _grid(len(laws), plt)
    for ax, (law, record) in zip(axes, laws.items()):
        for label, curve, style in (
            ("search", record.get("curve") or [], "-"),
            ("random", (record.get("random_baseline") or {}).get("curve") or [], "--"),
        ):
            values = np.array([np.nan if v is None else v for v in curve], dtype=float)
            values[np.isinf(values)] = np.nan  # a run that did not complete: no finite margin
            if values.size:
                ax.step(np.arange(1, values.size + 1), values, style, where="post", lw=1.2, label=label)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_title(law, fontsize=9)
        _plain(ax)
    axes[0].set_ylabel("least margin found", fontsize=8)
    axes[0].legend(fontsize=7)
    fig.supxlabel("simulations", fontsize=8)
    title = f"{name}: falsification, worst plant so far (below 0: violated)"
    return _inline(fig, plt, title, f"{name}-falsification")


@drawn_alone
def time_responses(name: str, responses: dict[str, dict]) -> str | None:
    """Each kept law's error norm and torque norm against time on its median and its worst
    certification draw (min-max envelopes). ``responses``: law -> {"median": {...}, "worst": {...}},
    each as :func:`response_of` gives it.
    """
    laws = {c: r for c, r in responses.items() if r}
    if not laws:
        return None
    plt = _pyplot()
    fig, axes = plt.subplots(len(laws), 2, figsize=(8.4, 1.55 * len(laws) + 0.7), squeeze=False)
    for row, (law, draws) in zip(axes, laws.items()):
        for which, style in (("median", "-"), ("worst", "--")):
            run = draws.get(which)
            if not run or "reason" in run:  # the run raised: no response to draw
                continue
            label = f"{which} draw (sample {run['sample']})"
            row[0].plot(run["t_error"], 1e3 * np.asarray(run["error"]), style, lw=0.9, label=label)
            row[1].plot(run["t_torque"], run["torque"], style, lw=0.9, label=label)
        row[0].set_yscale("log")
        row[0].set_ylabel(law, fontsize=8)
        for ax in row:
            _plain(ax)
    axes[0][0].set_title("task error |e| [mm]", fontsize=9)
    axes[0][1].set_title("torque |tau| [N m]", fontsize=9)
    axes[0][1].legend(fontsize=7)
    axes[-1][0].set_xlabel("t [s]", fontsize=8)
    axes[-1][1].set_xlabel("t [s]", fontsize=8)
    return _inline(fig, plt, f"{name}: time responses of the kept settings", f"{name}-responses")


def response_of(result, sample: int) -> dict:
    """A run's error norm [m] and torque norm [N m] against time, each as its min-max envelope
    (its own sample times: the two keep different samples).
    """
    from ...outputs.plots import envelope

    error = result.position_error()
    torque = np.linalg.norm(np.asarray(result.tau, dtype=float), axis=1)
    t_e, e = envelope(result.t, error, RESPONSE_BUCKETS)
    t_tau, tau = envelope(result.t, torque, RESPONSE_BUCKETS)
    return {"sample": int(sample), "t_error": t_e.tolist(), "error": e.tolist(), "t_torque": t_tau.tolist(),
            "torque": tau.tolist()}  # fmt: skip
