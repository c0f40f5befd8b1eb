"""The paper's figures for a run (Figs. 1-6) and comparison figures, as PNG and SVG."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .results import Result  # noqa: E402

FORMATS = ("png", "svg")

MAX_BUCKETS = 1500
"""Time series longer than 2 x this are drawn as their min-max envelope over this many buckets:
the same picture at figure resolution (every peak kept), at a fraction of the drawing and SVG
cost. result.npz keeps every sample."""


def envelope(t: np.ndarray, y: np.ndarray, buckets: int = MAX_BUCKETS) -> tuple[np.ndarray, np.ndarray]:
    """The samples of y that a plot needs: per bucket of consecutive samples its minimum and its
    maximum (in time order), plus the last sample.
    """
    n = y.size
    if n <= 2 * buckets:
        return t, y
    size = n // buckets
    blocks = y[: size * buckets].reshape(buckets, size)
    offsets = np.arange(buckets) * size
    tail = y[size * buckets:]  # fewer than ``buckets`` samples: one more bucket
    keep = np.concatenate([blocks.argmin(axis=1) + offsets, blocks.argmax(axis=1) + offsets,
                           size * buckets + np.array([tail.argmin(), tail.argmax()]) if tail.size else [],
                           [n - 1]]).astype(int)
    keep = np.unique(keep)
    return t[keep], y[keep]


MAX_PATH_POINTS = 4000
"""Points of a drawn path at most (every k-th sample: a path of the arm is smooth)."""


def _path_stride(x: np.ndarray) -> int:
    return max(1, -(-len(x) // MAX_PATH_POINTS))


def _series(draw, t: np.ndarray, y: np.ndarray, *args, **kwargs):
    """``draw(t, y, ...)`` (ax.plot, ax.semilogy) on the envelope of a long series."""
    return draw(*envelope(t, y), *args, **kwargs)


def _save(fig, folder: Path, name: str) -> list[Path]:
    """The figure in every format of :data:`FORMATS`, cropped to what it draws (the crop is
    measured once: ``bbox_inches="tight"`` would lay the figure out twice per format).
    """
    paths = []
    crop = fig.get_tightbbox(fig.canvas.get_renderer()).padded(0.1)
    for fmt in FORMATS:
        path = folder / f"{name}.{fmt}"
        fig.savefig(path, dpi=120, bbox_inches=crop)
        paths.append(path)
    plt.close(fig)
    return paths


AXES = ("x", "y", "z")


def legend_outside(ax, **kwargs):
    """The legend to the right of the axes, off the data."""
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                     fontsize=kwargs.pop("fontsize", 8), **kwargs)


def _position_size(result: Result) -> int:
    return min(result.x.shape[1], 3)


def plot_path(result: Result, ax=None, label: str = "actual", axes: tuple[int, int] = (0, 1),
              legend: bool = True) -> None:
    """Desired vs actual end-effector path projected on two world axes (Figs. 1, 4)."""
    i, j = axes
    every = _path_stride(result.x)
    ax.plot(result.x_d[::every, i], result.x_d[::every, j], "k--", lw=1.5, label="desired $x_d$")
    ax.plot(result.x[::every, i], result.x[::every, j], lw=1.0, label=label)
    ax.plot(result.x[0, i], result.x[0, j], "o", ms=4, color="C0")
    ax.set_xlabel(f"{AXES[i]} [m]")
    ax.set_ylabel(f"{AXES[j]} [m]")
    ax.set_aspect("equal", adjustable="datalim")
    if legend:
        legend_outside(ax)


def _path_figure(result: Result):
    if _position_size(result) == 2:
        fig, ax = plt.subplots(figsize=(5, 4.5))
        plot_path(result, ax)
    else:  # top and side views of a spatial path
        fig, (top, side) = plt.subplots(1, 2, figsize=(10, 4.5))
        plot_path(result, top, axes=(0, 1), legend=False)
        plot_path(result, side, axes=(0, 2))
        top.set_title("top view")
        side.set_title("side view")
    fig.suptitle("End-effector path")
    return fig


def _errors_figure(result: Result):
    t, npos, pose = result.t, _position_size(result), result.e.shape[1] == 6
    fig, axes = plt.subplots(3 if pose else 2, 1, figsize=(7, 7 if pose else 5), sharex=True)
    for i in range(npos):
        _series(axes[0].plot, t, result.e[:, i] * 1e3, lw=0.8, label=f"$e_{AXES[i]}$")
    axes[0].set_ylabel("position error [mm]")
    legend_outside(axes[0])
    if pose:
        for i in range(3):
            _series(axes[1].plot, t, result.e[:, 3 + i] * 1e3, lw=0.8, label=f"$e_{{\\theta {AXES[i]}}}$")
        axes[1].set_ylabel("orientation error [mrad]")
        legend_outside(axes[1])
    _series(axes[-1].semilogy, t, np.maximum(result.position_error(), 1e-12), lw=0.8, label="position [m]")
    if pose:
        _series(axes[-1].semilogy, t, np.maximum(result.orientation_error(), 1e-12), lw=0.8,
                label="orientation [rad]")
        legend_outside(axes[-1])
    axes[-1].set_ylabel("error norm [m]" if not pose else "error norm [m, rad]")
    axes[-1].set_xlabel("t [s]")
    fig.suptitle("Task-space tracking error")
    return fig


def _joint_series_figure(result: Result, name: str):
    """Joint angles or applied torques against time, with their limits dotted."""
    t = result.t
    joint_labels = result.joint_names or [f"q{i + 1}" for i in range(result.q.shape[1])]
    if name == "joints":
        data, ylabel, title, lw = result.q, "joint angle [rad]", "Joint angles (dotted: position limits)", 0.9
        limits = (result.lower_limit, result.upper_limit)
    else:
        data, ylabel, lw = result.tau, "torque [N m]", 0.6
        title = "Applied joint torques (dotted: effort limits; faint: commanded where it differs)"
        limits = (None if result.torque_limit is None else -result.torque_limit, result.torque_limit)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for i, joint in enumerate(joint_labels):
        line, = _series(ax.plot, t, data[:, i], lw=lw, label=joint)
        commanded = result.tau_cmd if name == "torques" else None
        if commanded is not None and np.any(commanded[:, i] != data[:, i]):
            _series(ax.plot, t, commanded[:, i], lw=0.4, alpha=0.35, color=line.get_color())
        for bound in limits:
            if bound is not None and np.isfinite(bound[i]) and abs(bound[i]) < 1e6:
                ax.axhline(bound[i], ls=":", lw=0.8, color=line.get_color())
    if name == "torques" and result.tau_cmd is not None and result.torque_limit is not None:
        # the applied range, and the limits that are near it; commands beyond them are clipped
        peak = float(np.nanmax(np.abs(data))) if data.size else 1.0
        near = result.torque_limit[result.torque_limit <= 3 * peak]
        top = 1.15 * max(peak, float(near.max()) if near.size else 0.0, 1e-9)
        ax.set_ylim(-top, top)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    ax.set_title(title, fontsize=10)
    return fig


def _subtask_figure(result: Result):
    t = result.t
    fig, axes = plt.subplots(2, 1, figsize=(7, 4.5), sharex=True)
    _series(axes[0].plot, t, result.signals["h"], lw=0.9)
    axes[0].set_ylabel("h(q)")
    _series(axes[1].plot, t, result.signals["manipulability"], lw=0.9)
    axes[1].set_ylabel("$\\sqrt{\\det JJ^T}$ [m$^m$]")
    axes[1].set_xlabel("t [s]")
    fig.suptitle("Subtask criterion and manipulability")
    return fig


def _snapshots_figure(result: Result):
    if result.chain is None:
        return None
    t = result.t
    fig, ax = plt.subplots(figsize=(5.5, 5))
    ax.plot(result.x_d[:, 0], result.x_d[:, 1], "k--", lw=1, label="desired path")
    instants = np.linspace(0, t.size - 1, 7).astype(int)
    colors = plt.cm.viridis(np.linspace(0, 0.9, instants.size))
    for k, color in zip(instants, colors):
        pts = result.chain[k]
        ax.plot(pts[:, 0], pts[:, 1], "-o", color=color, ms=3, lw=2, label=f"t = {t[k]:.1f} s")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    legend_outside(ax, fontsize=7)
    ax.set_title("Arm at several instants (x-y projection)")
    return fig


def _nn_figure(result: Result):
    if "rho_hat" not in result.signals:
        return None
    t = result.t
    fig, axes = plt.subplots(2, 1, figsize=(7, 4.5), sharex=True)
    _series(axes[0].plot, t, result.signals["rho_hat"], lw=0.9)
    axes[0].set_ylabel("$\\hat\\rho$ [m/s$^2$]")
    _series(axes[1].semilogy, t, np.maximum(result.signals["eps"], 1e-16), lw=0.9)
    axes[1].set_ylabel("$\\varepsilon$")
    axes[1].set_xlabel("t [s]")
    fig.suptitle("NN bound estimate and boundary layer")
    return fig


FIGURES = {
    "path": _path_figure,
    "errors": _errors_figure,
    "joints": lambda result: _joint_series_figure(result, "joints"),
    "torques": lambda result: _joint_series_figure(result, "torques"),
    "subtask": _subtask_figure,
    "snapshots": _snapshots_figure,
    "nn": _nn_figure,
}
"""The figures of a run, by file name; a figure function returns None when the run lacks its data."""


def plot_run(result: Result, folder: str | Path, names=None) -> list[Path]:
    """Write the figure set of one run (or the figures ``names`` of :data:`FIGURES`) into
    ``folder``; returns the files written.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name in FIGURES if names is None else names:
        fig = FIGURES[name](result)
        if fig is not None:
            written += _save(fig, folder, name)
    return written


def plot_comparison(results: dict[str, Result], folder: str | Path) -> list[Path]:
    """Overlay several runs: paths, error norms and torque norms."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    first = next(iter(results.values()))
    axes[0].plot(first.x_d[:, 0], first.x_d[:, 1], "k--", lw=1.5, label="desired")
    for name, res in results.items():
        axes[0].plot(res.x[:, 0], res.x[:, 1], lw=0.9, label=name)
        _series(axes[1].semilogy, res.t, np.maximum(res.position_error(), 1e-12), lw=0.8, label=name)
        _series(axes[2].plot, res.t, np.linalg.norm(res.tau, axis=1), lw=0.5, label=name)
    axes[0].set_aspect("equal", adjustable="datalim")
    axes[0].set_xlabel("x [m]")
    axes[0].set_ylabel("y [m]")
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylabel("position error [m]")
    axes[2].set_xlabel("t [s]")
    axes[2].set_ylabel("$\\|\\tau\\|$ [N m]")
    handles, labels = axes[0].get_legend_handles_labels()  # one legend: the colours are the same
    legend_outside(axes[2], handles=handles, labels=labels)
    written = _save(fig, folder, "comparison")
    return written
