"""The paper's figures for a run (Figs. 1-6) and comparison figures, as PNG and SVG."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402

from ..run.results import Result  # noqa: E402
from ..subtasks.manipulability import MANIPULABILITY_UNITS  # noqa: E402

FORMATS = ("png", "svg")

MAX_BUCKETS = 1500
"""Time series longer than 2 x this are drawn as their min-max envelope over this many buckets:
the same picture at figure resolution (every peak kept), at a fraction of the drawing and SVG
cost. result.npz keeps every sample."""


def envelope(t: np.ndarray, y: np.ndarray, buckets: int = MAX_BUCKETS) -> tuple[np.ndarray, np.ndarray]:
    """The samples of y that a plot needs: per bucket of consecutive samples its minimum and its
    maximum (in time order), plus the first and the last sample.

    The n samples are cut into ``buckets`` buckets whose sizes differ by at most one (as
    ``np.array_split`` cuts them), so the end of a run is drawn as finely as its start.
    """
    n = y.size
    if n <= 2 * buckets:
        return t, y
    size, longer = divmod(n, buckets)  # the first ``longer`` buckets hold size + 1 samples
    keep = [np.array([0, n - 1])]
    for start, count, length in ((0, longer, size + 1), (longer * (size + 1), buckets - longer, size)):
        if count:
            blocks = y[start : start + count * length].reshape(count, length)
            offsets = start + np.arange(count) * length
            keep += [blocks.argmin(axis=1) + offsets, blocks.argmax(axis=1) + offsets]
    index = np.unique(np.concatenate(keep))
    return t[index], y[index]


MAX_PATH_POINTS = 4000
"""Points of a drawn path at most (every k-th sample: a path of the arm is smooth)."""


def _path(x: np.ndarray) -> np.ndarray:
    """Every k-th sample of a path, and its last one: at most about :data:`MAX_PATH_POINTS`."""
    every = max(1, -(-len(x) // MAX_PATH_POINTS))
    index = np.arange(0, len(x), every)
    if len(x) and index[-1] != len(x) - 1:
        index = np.append(index, len(x) - 1)
    return x[index]


def _series(draw, t: np.ndarray, y: np.ndarray, *args, **kwargs):
    """``draw(t, y, ...)`` (ax.plot, ax.semilogy) on the envelope of a long series."""
    return draw(*envelope(t, y), *args, **kwargs)


DPI = 120
"""Resolution of the PNG figures [dots per inch]."""

PAD = 0.1
"""White margin around what a figure draws [in]."""

ROOM = (0.6, 0.6, 3.0, 0.6)
"""Room drawn around a figure before it is cropped [in]: left, bottom, right (where the legends
sit, outside the axes), top."""


def save_figure(fig, folder: Path, name: str) -> list[Path]:
    """The figure in every format of :data:`FORMATS`, cropped to what it draws plus :data:`PAD`.

    The crop is found on the raster: the figure is drawn once at :data:`DPI` with :data:`ROOM`
    around it, and the box of its non-background pixels is both the PNG (cut from that drawing)
    and the page of the other formats. Only where the drawing reaches an edge of its room (a
    legend taller than the figure) is the crop measured by matplotlib's layout instead, which
    costs a layout of every text.
    """
    from matplotlib.transforms import Bbox

    width, height = fig.get_size_inches()
    left, bottom, right, top = ROOM
    room = Bbox.from_extents(-left, -bottom, width + right, height + top)
    raster = _draw_raster(fig, room)
    ink = None if raster is None else _ink_box(raster)
    if ink is not None:
        (r0, r1), (c0, c1) = ink  # pixel rows from the top, columns from the left
        crop = Bbox.from_extents(
            room.x0 + c0 / DPI, room.y1 - r1 / DPI, room.x0 + c1 / DPI, room.y1 - r0 / DPI
        )
    else:
        crop = fig.get_tightbbox(fig.canvas.get_renderer()).padded(PAD)
    paths = []
    for fmt in FORMATS:
        path = folder / f"{name}.{fmt}"
        if fmt == "png" and ink is not None and raster is not None:
            from PIL import Image

            Image.fromarray(raster[r0:r1, c0:c1, :3]).save(path, dpi=(DPI, DPI))
        else:
            fig.savefig(path, dpi=DPI, bbox_inches=crop)
        paths.append(path)
    plt.close(fig)
    return paths


def _draw_raster(fig, room) -> np.ndarray | None:
    """The figure drawn over ``room`` [in] at :data:`DPI`: rows x columns x RGBA (None if the
    buffer's size is not the room's).
    """
    import io

    buffer = io.BytesIO()
    fig.savefig(buffer, format="rgba", dpi=DPI, bbox_inches=room)
    data = np.frombuffer(buffer.getbuffer(), dtype=np.uint8)
    for columns in {int(room.width * DPI), round(room.width * DPI)}:
        for rows in {int(room.height * DPI), round(room.height * DPI)}:
            if rows * columns * 4 == data.size:
                return data.reshape(rows, columns, 4)
    return None


def _ink_box(raster: np.ndarray) -> tuple[tuple[int, int], tuple[int, int]] | None:
    """((first row, end row), (first column, end column)) of what differs from the background
    (the corner pixel), grown by :data:`PAD`; None when nothing is drawn or the drawing reaches
    an edge (it may go on beyond it).
    """
    ink = np.any(raster != raster[0, 0], axis=2)
    rows, columns = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    if (
        rows.size == 0
        or rows[0] == 0
        or columns[0] == 0
        or rows[-1] == ink.shape[0] - 1
        or (columns[-1] == ink.shape[1] - 1)
    ):
        return None
    pad = int(round(PAD * DPI))
    return (
        (max(rows[0] - pad, 0), min(rows[-1] + 1 + pad, ink.shape[0])),
        (max(columns[0] - pad, 0), min(columns[-1] + 1 + pad, ink.shape[1])),
    )


AXES = ("x", "y", "z")


def legend_outside(ax, **kwargs):
    """The legend to the right of the axes, off the data."""
    return ax.legend(
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        borderaxespad=0.0,
        fontsize=kwargs.pop("fontsize", 8),
        **kwargs,
    )


def _position_size(result: Result) -> int:
    return min(result.x.shape[1], 3)


def path_plane(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(centre, 2 x 3 in-plane directions) of the plane that best fits a 3-D path (its two
    principal directions), each direction signed so that its largest component is positive.
    """
    points = np.asarray(points, dtype=float)
    centre = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centre, full_matrices=False)
    axes = vt[:2].copy()
    for row in axes:
        if row[np.argmax(np.abs(row))] < 0:
            row *= -1
    return centre, axes


def _direction_label(name: str, axis: np.ndarray) -> str:
    return f"{name} = ({axis[0]:+.2f}, {axis[1]:+.2f}, {axis[2]:+.2f}) [m]"


@dataclass(frozen=True)
class DrawingPlane:
    """Where points are drawn in 2-D: the x-y plane of a planar task, or a spatial path's own
    plane (:func:`path_plane`).
    """

    centre: np.ndarray
    axes: np.ndarray  # 2 x d, d = 2 (x-y) or 3 (a spatial path's plane)

    @classmethod
    def of(cls, result: Result) -> DrawingPlane:
        """The plane a run is drawn in."""
        if _position_size(result) == 2:
            return cls(np.zeros(2), np.eye(2))
        return cls(*path_plane(result.x_d[:, :3]))

    @property
    def spatial(self) -> bool:
        """Whether this is a spatial path's plane (not the x-y plane)."""
        return self.centre.size == 3

    def project(self, points: np.ndarray) -> np.ndarray:
        """In-plane coordinates of points (... x 2 or 3, extra entries ignored), ... x 2 [m]."""
        d = self.centre.size
        return (np.asarray(points, dtype=float)[..., :d] - self.centre) @ self.axes.T

    def label(self, ax) -> None:
        """Name the in-plane directions on ``ax``'s axes."""
        if self.spatial:
            ax.set_xlabel(_direction_label("along $u_1$", self.axes[0]))
            ax.set_ylabel(_direction_label("along $u_2$", self.axes[1]))
        else:
            ax.set_xlabel("x [m]")
            ax.set_ylabel("y [m]")


def plot_path_in_plane(
    result: Result, ax, label: str = "actual", legend: bool = True, plane: DrawingPlane | None = None
) -> None:
    """Desired vs actual end-effector path (Figs. 1, 4) in the x-y plane of a planar task, else
    projected on the desired path's own plane (:func:`path_plane`).
    """
    plane = plane or DrawingPlane.of(result)
    for data, style, name in (
        (result.x_d, dict(ls="--", color="k", lw=1.5), "desired $x_d$"),
        (result.x, dict(lw=1.0, color="C0"), label),
    ):
        ax.plot(*plane.project(_path(data)).T, label=name, **style)
    ax.plot(*plane.project(result.x[0]), "o", ms=4, color="C0", label="start")
    plane.label(ax)
    ax.set_aspect("equal", adjustable="datalim")
    if legend:
        legend_outside(ax)


def _path_figure(result: Result):
    if _position_size(result) == 2:
        fig, ax = plt.subplots(figsize=(5, 4.5))
        plot_path_in_plane(result, ax)
        fig.suptitle("End-effector path")
        return fig
    fig = plt.figure(figsize=(12, 5))  # a 3-D view, and the path's own plane
    view = fig.add_subplot(1, 2, 1, projection="3d")
    view.plot(*_path(result.x_d[:, :3]).T, "k--", lw=1.2)
    view.plot(*_path(result.x[:, :3]).T, lw=1.0, color="C0")
    view.plot(*result.x[:1, :3].T, "o", ms=4, color="C0")
    shown = [result.x_d[:, :3]]
    if result.chain is not None:  # the arm at t = 0, for scale and place
        view.plot(*result.chain[0].T, "-o", color="0.55", lw=2, ms=3)
        shown.append(result.chain[0])
    points = np.vstack(shown)
    lows, highs = points.min(axis=0), points.max(axis=0)
    half = max(float(np.max(highs - lows)) / 2, 1e-3) * 1.05
    for setter, mid in zip((view.set_xlim, view.set_ylim, view.set_zlim), (lows + highs) / 2):
        setter(mid - half, mid + half)  # equal scales on the three axes
    plane = DrawingPlane.of(result)
    normal = np.cross(*plane.axes)
    normal *= np.sign(normal[2]) if normal[2] else 1.0
    view.view_init(
        elev=float(np.degrees(np.arcsin(np.clip(normal[2], -1, 1)))) * 0.6 + 15,
        azim=float(np.degrees(np.arctan2(normal[1], normal[0]))) + 25,
    )  # the path face-on, tilted
    view.set_xlabel("x [m]")
    view.set_ylabel("y [m]")
    view.zaxis.set_rotate_label(False)  # mplot3d would turn it upside down at some view angles
    view.set_zlabel("z [m]", rotation=90)
    view.set_title("3-D view (grey: the arm at t = 0)", fontsize=10)
    in_plane = fig.add_subplot(1, 2, 2)
    fig.subplots_adjust(wspace=0.35)
    plot_path_in_plane(result, in_plane, plane=plane)
    in_plane.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(6))  # not crowded beside the 3-D view
    in_plane.set_title("in the path's plane", fontsize=10)
    fig.suptitle("End-effector path")
    return fig


def _plain_label(value: float, _position=None, mantissas=(1,)) -> str:
    """``value`` as a plain number (0.2, 5, 40) when its leading digit is one of ``mantissas``."""
    if value <= 0:
        return ""
    leading = round(value / 10 ** np.floor(np.log10(value)))
    return f"{value:g}" if leading in mantissas else ""


def readable_log_ticks(ax) -> None:
    """On a log y axis that spans less than three decades: plain-number labels at 1, 2 and 5
    times the powers of ten (0.2, 0.5, 1, 2, 5, 10), not 2x10^-1.
    """
    low, high = ax.get_ylim()
    if low > 0 and high / low < 1e3:
        ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(_plain_label))
        ax.yaxis.set_minor_formatter(
            matplotlib.ticker.FuncFormatter(lambda value, position: _plain_label(value, position, (2, 5)))
        )


def log_floor(*series: np.ndarray) -> float:
    """The bottom of a log axis for error norms: half the smallest error of the run's second half
    (what the controller settles to), and no more than 6 decades under the largest error, so that
    the exact zero at a start on the path does not stretch the axis to 1e-12.
    """
    values = np.concatenate([np.asarray(s, dtype=float) for s in series])
    values = values[np.isfinite(values) & (values > 0)]
    if values.size == 0:
        return 1e-12
    late = np.concatenate([np.asarray(s, dtype=float)[len(s) // 2 :] for s in series])
    late = late[np.isfinite(late) & (late > 0)]
    floor = 0.5 * float(np.min(late)) if late.size else float(np.min(values))
    return max(floor, float(np.max(values)) * 1e-6)


def _errors_figure(result: Result):
    """The error's components and its norm (log axis), in mm, and for a pose task the same for the
    orientation in mrad: one unit per axis.
    """
    t, npos, pose = result.t, _position_size(result), result.e.shape[1] == 6
    parts: list[tuple[str, str, np.ndarray, np.ndarray, tuple[str, ...]]] = [
        ("position", "mm", result.e[:, :npos], result.position_error(), AXES)
    ]
    orientation = result.orientation_error()
    if pose and orientation is not None:
        parts.append(
            ("orientation", "mrad", result.e[:, 3:6], orientation, tuple(f"\\theta {a}" for a in AXES))
        )
    fig, axes = plt.subplots(2 * len(parts), 1, figsize=(7, 3.6 * len(parts) + 1.6), sharex=True)
    fig.subplots_adjust(hspace=0.3)
    for k, (what, unit, components, norm, names) in enumerate(parts):
        top, bottom = axes[2 * k], axes[2 * k + 1]
        for i in range(components.shape[1]):
            _series(top.plot, t, components[:, i] * 1e3, lw=0.8, label=f"$e_{{{names[i]}}}$")
        top.set_ylabel(f"{what} error [{unit}]")
        legend_outside(top)
        floor = log_floor(norm * 1e3)
        _series(bottom.semilogy, t, np.maximum(norm * 1e3, floor), lw=0.8)
        bottom.set_ylim(bottom=floor)
        readable_log_ticks(bottom)
        bottom.set_ylabel(f"|{what} error| [{unit}]")
    axes[-1].set_xlabel("t [s]")
    fig.suptitle("Task-space tracking error")
    return fig


def _unit(result: Result, revolute: str, prismatic: str) -> list[str]:
    """Per joint, the unit of its position (or force): ``prismatic`` for a prismatic joint."""
    kinds = result.prismatic if result.prismatic is not None else np.zeros(result.q.shape[1], dtype=bool)
    return [prismatic if p else revolute for p in kinds]


def _joint_series_figure(result: Result, name: str):
    """Joint positions or applied torques against time, with their limits dotted; prismatic
    joints in m and N.
    """
    t = result.t
    joint_labels = result.joint_names or [f"q{i + 1}" for i in range(result.q.shape[1])]
    if name == "joints":
        data, lw, units = result.q, 0.9, _unit(result, "rad", "m")
        title = "Joint positions (dotted: position limits)"
        limits = (result.lower_limit, result.upper_limit)
    else:
        data, lw, units = result.tau, 0.6, _unit(result, "N m", "N")
        title = "Applied joint torques (dotted: effort limits; faint: commanded where it differs)"
        limits = (None if result.torque_limit is None else -result.torque_limit, result.torque_limit)
    quantity = (
        "joint position"
        if name == "joints"
        else ("joint torque" if set(units) == {"N m"} else "joint torque or force")
    )
    ylabel = f"{quantity} [{' or '.join(sorted(set(units), key=units.index))}]"
    fig, ax = plt.subplots(figsize=(7, 3.5))
    top = None
    if name == "torques" and result.tau_cmd is not None and result.torque_limit is not None:
        # the applied range, and the limits that are near it; commands beyond them are clipped
        peak = float(np.nanmax(np.abs(data))) if data.size else 1.0
        near = result.torque_limit[result.torque_limit <= 3 * peak]
        top = 1.15 * max(peak, float(near.max()) if near.size else 0.0, 1e-9)
    for i, joint in enumerate(joint_labels):
        label = joint if len(set(units)) == 1 else f"{joint} [{units[i]}]"
        bounds = [b[i] for b in limits if b is not None and np.isfinite(b[i]) and abs(b[i]) < 1e6]
        if bounds:  # each joint's legend entry names its own limits, drawn or off the axis
            shown = [b for b in bounds if top is None or abs(b) <= top]
            label += f" ({_limit_text(bounds)}{'' if len(shown) == len(bounds) else ', off the axis'})"
        (line,) = _series(ax.plot, t, data[:, i], lw=lw, label=label)
        commanded = result.tau_cmd if name == "torques" else None
        if commanded is not None and np.any(commanded[:, i] != data[:, i]):
            _series(ax.plot, t, commanded[:, i], lw=0.4, alpha=0.35, color=line.get_color())
        for bound in bounds:
            ax.axhline(bound, ls=":", lw=0.8, color=line.get_color(), gid=f"limit:{joint}")
    if top is not None:
        ax.set_ylim(-top, top)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    legend_outside(ax)
    ax.set_title(title, fontsize=10)
    return fig


def _limit_text(bounds: list[float]) -> str:
    """'±87' for symmetric limits, else '-2.9 to 2.9'."""
    if len(bounds) == 2 and bounds[0] == -bounds[1]:
        return f"±{abs(bounds[1]):.3g}"
    return " to ".join(f"{b:.3g}" for b in sorted(bounds))


def _subtask_figure(result: Result):
    t = result.t
    fig, axes = plt.subplots(2, 1, figsize=(7, 4.5), sharex=True)
    _series(axes[0].plot, t, result.signals["h"], lw=0.9)
    name, unit = result.info.criterion_label if result.info else ("h(q)", "?")
    axes[0].set_ylabel(f"h(q) [{unit}]")
    axes[0].set_title(name, fontsize=9)
    _series(axes[1].plot, t, result.signals["manipulability"], lw=0.9)
    unit = MANIPULABILITY_UNITS.get(result.e.shape[1], "")
    axes[1].set_ylabel(f"$\\sqrt{{\\det JJ^T}}$ [{unit}]")
    axes[1].set_xlabel("t [s]")
    fig.suptitle("Subtask criterion and manipulability")
    return fig


def _snapshots_figure(result: Result):
    """Stick figures at seven instants (Figs. 3, 6), in the x-y plane of a planar task, else in
    the desired path's plane.
    """
    if result.chain is None:
        return None
    t = result.t
    fig, ax = plt.subplots(figsize=(5.5, 5))
    plane = DrawingPlane.of(result)
    where = "projected on the path's plane" if plane.spatial else "x-y projection"
    ax.plot(*plane.project(result.x_d).T, "k--", lw=1, label="desired path")
    instants = np.linspace(0, t.size - 1, 7).astype(int)
    colors = plt.cm.viridis(np.linspace(0, 0.9, instants.size))
    for k, color in zip(instants, colors):
        ax.plot(*plane.project(result.chain[k]).T, "-o", color=color, ms=3, lw=2, label=f"t = {t[k]:.1f} s")
    ax.set_aspect("equal", adjustable="datalim")
    plane.label(ax)
    legend_outside(ax, fontsize=7)
    ax.set_title(f"Arm at several instants ({where})", fontsize=10)
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


PAPER_SIGNALS = ("h", "manipulability", "rho_hat", "eps", "z_norm", "damping")
"""Signals of the paper's laws: drawn in the subtask and nn figures, or summarised in the metrics
(``damping``: singular_fraction and singular_episodes; ``z_norm``: final_rho_hat's weights).
Every other signal (a registered or user law's ``signal_names``) is drawn by :func:`_signals_figure`."""

MAX_SIGNAL_PANELS = 8
"""At most this many signals in the signals figure (the rest are named in its title)."""


def _signals_figure(result: Result):
    """The controller's other recorded signals (a shipped law's or a user's ``signal_names``),
    one panel each; None where there are none.
    """
    names = [k for k in result.signals if k not in PAPER_SIGNALS]
    if not names:
        return None
    shown = names[:MAX_SIGNAL_PANELS]
    fig, axes = plt.subplots(len(shown), 1, figsize=(7, 1.2 + 1.3 * len(shown)), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], shown):
        _series(ax.plot, result.t, np.asarray(result.signals[name], dtype=float), lw=0.9)
        ax.set_ylabel(name, fontsize=8)
    axes[-1, 0].set_xlabel("t [s]")
    rest = f" ({len(names) - len(shown)} more in result.npz: {', '.join(names[len(shown) :])})"
    fig.suptitle("Controller signals" + (rest if len(names) > len(shown) else ""), fontsize=10)
    return fig


FIGURES = {
    "path": _path_figure,
    "errors": _errors_figure,
    "joints": lambda result: _joint_series_figure(result, "joints"),
    "torques": lambda result: _joint_series_figure(result, "torques"),
    "subtask": _subtask_figure,
    "snapshots": _snapshots_figure,
    "nn": _nn_figure,
    "signals": _signals_figure,
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
            written += save_figure(fig, folder, name)
    return written


def result_html(result: Result) -> str:
    """A run in a notebook: its summary table (``Result._repr_html_``) and its path and error
    figures inline, as PNG. The front door registers this as IPython's HTML formatter of
    :class:`~nnrobust.run.results.Result`.
    """
    import base64
    import io

    images = []
    for name in ("path", "errors"):
        fig = FIGURES[name](result)
        if fig is None:
            continue
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=80, bbox_inches="tight")
        plt.close(fig)
        images.append(
            f'<img src="data:image/png;base64,{base64.b64encode(buffer.getvalue()).decode()}" '
            f'alt="{name}" style="max-width:48%">'
        )
    return f"{result._repr_html_()}<div>{''.join(images)}</div>"


def comparison_warnings(results: dict[str, Result]) -> list[str]:
    """What makes runs hard to compare: a different robot, task or desired trajectory."""
    infos = {label: r.info for label, r in results.items() if r.info is not None}
    said = []
    for what, get in (
        ("robot", lambda i: i.robot),
        ("task", lambda i: i.task),
        ("desired trajectory", lambda i: i.trajectory),
    ):
        values = {label: get(i) for label, i in infos.items()}
        if len({repr(v) for v in values.values()}) > 1:
            shown = "; ".join(f"{label}: {_short(v)}" for label, v in values.items())
            said.append(f"the runs differ in their {what} ({shown})")
    return said


def _short(value) -> str:
    if isinstance(value, tuple):
        value = value[0]
    if isinstance(value, dict) and "axis_a" in value:  # a trajectory's settings
        return f"centre {value['center']}, axes {value['axis_a']} {value['axis_b']}, omega {value['omega']:g}"
    return str(value)[:80]


def plot_comparison(results: dict[str, Result], folder: str | Path) -> list[Path]:
    """Overlay several runs: each run's desired (dashed) and actual path, in the x-y plane of a
    planar task or in the first run's path plane, the error norms and the torque norms.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    plane = DrawingPlane.of(next(iter(results.values())))
    for i, (name, res) in enumerate(results.items()):
        color = f"C{i % 10}"
        for data, style in ((res.x_d, {"ls": "--", "lw": 1.2}), (res.x, {"lw": 0.9})):
            axes[0].plot(
                *plane.project(_path(data)).T, color=color, label=name if data is res.x else None, **style
            )
        _series(axes[1].semilogy, res.t, np.maximum(1e3 * res.position_error(), 1e-9), lw=0.8, color=color)
        _series(axes[2].plot, res.t, np.linalg.norm(res.tau, axis=1), lw=0.5, color=color)
    axes[1].set_ylim(bottom=log_floor(*(1e3 * r.position_error() for r in results.values())))
    readable_log_ticks(axes[1])
    axes[0].set_aspect("equal", adjustable="datalim")
    for axis in (axes[0].xaxis, axes[0].yaxis):  # a narrow panel: few ticks, so that labels do not touch
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
    plane.label(axes[0])
    axes[0].set_title(
        "paths (dashed: desired)" + (" in the first run's path plane" if plane.spatial else ""), fontsize=9
    )
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylabel("|position error| [mm]")
    axes[2].set_xlabel("t [s]")
    axes[2].set_ylabel("$\\|\\tau\\|$ [N m]")
    legend_outside(axes[2], handles=axes[0].get_lines()[1::2], labels=list(results))
    return save_figure(fig, folder, "comparison")
