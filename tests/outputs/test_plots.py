"""The figures, read back from the matplotlib objects: what each axis shows, its labels, limits
and limit lines (nnrobust/outputs/plots.py)."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from nnrobust.config.presets import load_preset  # noqa: E402
from nnrobust.outputs import plots  # noqa: E402
from nnrobust.run.experiment import run_experiment  # noqa: E402


@pytest.fixture(scope="module")
def panda():
    return run_experiment(load_preset("panda-ellipse").replace(simulation={"duration": 6.3}))  # one lap


@pytest.fixture(scope="module")
def paper():
    return run_experiment(load_preset("paper-ellipse").replace(simulation={"duration": 1.0}))


def _figure(name, result):
    fig = plots.FIGURES[name](result)
    fig.canvas.draw()
    return fig


def test_a_spatial_path_is_shown_in_3d_and_in_its_own_plane(panda):
    """panda-ellipse's path has orthogonal semi-axes |a| = 0.15 m and |b| = 0.112 m: in the
    path's plane the desired path spans 2|a| and 2|b| (it showed as a line in a fixed x-z view)."""
    fig = _figure("path", panda)
    view, plane = fig.axes[:2]
    assert view.name == "3d" and plane.name == "rectilinear"
    assert view.zaxis.label.get_rotation() == 90  # upright, not turned over by the view angle
    assert plane.get_xlabel().startswith("along $u_1$") and plane.get_ylabel().startswith("along $u_2$")
    desired = plane.get_lines()[0]
    x, y = desired.get_xdata(), desired.get_ydata()
    assert np.ptp(x) == pytest.approx(0.30, rel=0.01)
    assert np.ptp(y) == pytest.approx(2 * np.hypot(0.05, 0.10), rel=0.01)
    plt.close(fig)


def test_path_plane_is_the_plane_of_the_path():
    t = np.linspace(0, 2 * np.pi, 200)[:, None]
    a, b = np.array([0.0, 0.15, 0.0]), np.array([0.05, 0.0, 0.10])
    points = np.array([0.45, 0.0, 0.45]) + a * np.cos(t) + b * np.sin(t)
    centre, (u, v) = plots.path_plane(points)
    normal = np.cross(a, b) / np.linalg.norm(np.cross(a, b))
    assert abs(u @ normal) < 1e-12 and abs(v @ normal) < 1e-12 and abs(u @ v) < 1e-12
    np.testing.assert_allclose(centre, [0.45, 0.0, 0.45], atol=1e-3)


def test_snapshots_of_a_spatial_run_lie_in_the_path_plane(panda):
    fig = _figure("snapshots", panda)
    ax = fig.axes[0]
    assert "path's plane" in ax.get_title() and ax.get_xlabel().startswith("along $u_1$")
    assert len(ax.get_lines()) == 8  # the desired path and seven instants
    plt.close(fig)


def test_the_error_axis_starts_near_the_smallest_meaningful_error(paper):
    fig = _figure("errors", paper)
    norm_axis = fig.axes[-1]
    bottom = norm_axis.get_ylim()[0]
    late = paper.position_error()[paper.t >= 0.5] * 1e3  # mm
    assert bottom >= 1e-6 * paper.position_error().max() * 1e3 > 1e-9
    assert bottom <= late.min()  # every settled error is on the axis
    assert norm_axis.get_yscale() == "log" and norm_axis.get_ylabel() == "|position error| [mm]"
    plt.close(fig)


def test_a_pose_run_shows_each_error_in_its_own_unit():
    pose = run_experiment(load_preset("panda-pose").replace(simulation={"duration": 0.5}))
    fig = _figure("errors", pose)
    labels = [ax.get_ylabel() for ax in fig.axes[:4]]
    assert labels == [
        "position error [mm]",
        "|position error| [mm]",
        "orientation error [mrad]",
        "|orientation error| [mrad]",
    ]
    for log_axis in (fig.axes[1], fig.axes[3]):  # plain numbers at 1, 2, 5 x 10^k, not 2x10^0
        shown = [t.get_text() for t in log_axis.get_yticklabels(which="both") if t.get_text()]
        assert shown and all(text.replace(".", "").isdigit() for text in shown), shown
        mantissas = {round(float(text) / 10 ** np.floor(np.log10(float(text))), 6) for text in shown}
        assert mantissas <= {1.0, 2.0, 5.0}
    plt.close(fig)


def test_joint_and_torque_figures_draw_every_limit_and_keep_legends_off_the_data(paper):
    for name, limits in (
        ("joints", (paper.lower_limit, paper.upper_limit)),
        ("torques", (paper.torque_limit,)),
    ):
        fig = _figure(name, paper)
        ax = fig.axes[0]
        lines = [line for line in ax.get_lines() if (line.get_gid() or "").startswith("limit:")]
        expected = sorted(float(v) for bound in limits for v in np.asarray(bound) if np.isfinite(v))
        if name == "torques":
            expected = sorted(expected + [-v for v in expected])
        assert sorted(float(line.get_ydata()[0]) for line in lines) == pytest.approx(expected)
        unit = "rad" if name == "joints" else "N m"
        assert ax.get_ylabel().endswith(f"[{unit}]")
        legend = ax.get_legend().get_window_extent()
        assert legend.x0 >= ax.get_window_extent().x1  # outside, right of the axes
        plt.close(fig)


def test_each_joints_legend_names_its_own_effort_limit_and_says_when_it_is_off_the_axis(panda):
    """Panda: joints 1-4 are limited to 87 N m, 5-7 to 12 N m; a 12 N m line drawn beside joint 4's
    25 N m must not read as joint 4's limit, and a limit beyond the axis is said, not hidden."""
    fig = _figure("torques", panda)
    ax = fig.axes[0]
    top = ax.get_ylim()[1]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(texts) == 7
    for text, limit in zip(texts, panda.torque_limit):
        assert f"±{limit:.3g}" in text
        assert ("off the axis" in text) == (limit > top), (text, top)
    plt.close(fig)


def test_compare_draws_errors_in_mm_with_ticks_that_do_not_touch(panda, paper, tmp_path):
    other = run_experiment(
        load_preset("paper-ellipse").replace(simulation={"duration": 1.0}, controller={"kind": "no-u0"})
    )
    captured = {}
    original = plots.save_figure

    def keep(fig, folder, stem):  # read the figure as drawn, before it is saved and closed
        fig.canvas.draw()
        path = fig.axes[0]
        frame = path.get_window_extent()
        captured["ticks"] = [
            (label.get_text(), label.get_window_extent())
            for label in path.get_xticklabels()
            if label.get_text()
            and frame.x0 - 1 <= label.get_window_extent().x0
            and label.get_window_extent().x1 <= frame.x1 + 1
        ]
        captured["error"] = fig.axes[1]
        return original(fig, folder, stem)

    plots.save_figure = keep
    try:
        plots.plot_comparison({"nn": paper, "no-u0": other}, tmp_path)
    finally:
        plots.save_figure = original
    error = captured["error"]
    assert error.get_ylabel() == "|position error| [mm]"
    drawn = np.concatenate([line.get_ydata() for line in error.get_lines()])
    assert drawn.max() == pytest.approx(1e3 * max(paper.position_error().max(), other.position_error().max()))
    ticks = captured["ticks"]
    assert len(ticks) >= 2
    assert all(a.x1 < b.x0 for (_, a), (_, b) in zip(ticks, ticks[1:])), [text for text, _ in ticks]


def test_prismatic_joints_are_labelled_in_metres_and_newtons(paper):
    import dataclasses

    mixed = dataclasses.replace(paper, prismatic=np.array([False, True, False]))
    for name, label, unit in (
        ("joints", "joint position [rad or m]", "[m]"),
        ("torques", "joint torque or force [N m or N]", "[N]"),
    ):
        fig = _figure(name, mixed)
        ax = fig.axes[0]
        assert ax.get_ylabel() == label
        assert f" {unit}" in [t.get_text() for t in ax.get_legend().get_texts()][1]
        plt.close(fig)


def test_subtask_figure_names_the_criterion_and_its_units(panda, paper):
    fig = _figure("subtask", panda)
    assert fig.axes[0].get_title() == "h(q) = 0.5 manipulability + 0.5 joint_limits"
    assert fig.axes[0].get_ylabel() == "h(q) [m$^3$ + 1]"  # m^3 and a ratio
    assert fig.axes[1].get_ylabel().endswith("[m$^3$]")
    plt.close(fig)
    fig = _figure("subtask", paper)
    assert fig.axes[0].get_title() == "h(q) = 0.5 det(J J^T) - 0.5 (0.5 q1 - q2 + q3)^2, eq. (19)"
    assert fig.axes[0].get_ylabel() == "h(q) [m$^4$ + rad$^2$]"
    assert fig.axes[1].get_ylabel().endswith("[m$^2$]")
    plt.close(fig)
    limits_only = run_experiment(load_preset("panda-pose").replace(simulation={"duration": 0.2}))
    fig = _figure("subtask", limits_only)
    assert fig.axes[0].get_ylabel() == "h(q) [1]" and fig.axes[0].get_title() == "h(q) = joint_limits"
    plt.close(fig)


def test_compare_warns_when_runs_differ_and_draws_each_desired_path(panda, paper, tmp_path):
    other = run_experiment(
        load_preset("panda-ellipse").replace(
            simulation={"duration": 0.5}, trajectory={"omega": 0.5}, controller={"kind": "no-u0"}
        )
    )
    said = plots.comparison_warnings({"a": panda, "b": other})
    assert said == [said[0]] and "desired trajectory" in said[0] and "omega 0.5" in said[0]
    assert any("robot" in s for s in plots.comparison_warnings({"panda": panda, "paper": paper}))
    assert plots.comparison_warnings({"a": panda, "b": panda}) == []
    written = plots.plot_comparison({"a": panda, "b": other}, tmp_path)
    assert [p.suffix for p in written] == [".png", ".svg"]


def _svg_size_pt(path) -> tuple[float, float]:
    import re

    head = path.read_text()[:2000]
    width, height = re.search(r'<svg[^>]*width="([0-9.]+)pt" height="([0-9.]+)pt"', head).groups()
    return float(width), float(height)


@pytest.mark.parametrize("name", ["errors", "joints", "path"])
def test_saved_figures_are_cropped_to_what_they_draw(panda, tmp_path, name):
    """PNG and SVG cover what matplotlib's own tight layout measures (the legends outside the axes
    included) to within a few pixels, with a white margin all round, and both have one size."""
    from PIL import Image

    fig = plots.FIGURES[name](panda)
    tight = fig.get_tightbbox(fig.canvas.get_renderer()).padded(plots.PAD)
    png, svg = plots.save_figure(fig, tmp_path, name)
    image = np.asarray(Image.open(png).convert("RGB"))
    rows, columns = image.shape[:2]
    assert abs(columns - tight.width * plots.DPI) < 12 and abs(rows - tight.height * plots.DPI) < 12
    margin = int(plots.PAD * plots.DPI) - 1
    for border in (image[:margin], image[-margin:], image[:, :margin], image[:, -margin:]):
        assert np.all(border == 255)
    width_pt, height_pt = _svg_size_pt(svg)
    assert width_pt == pytest.approx(columns / plots.DPI * 72, abs=1) and (
        height_pt == pytest.approx(rows / plots.DPI * 72, abs=1)
    )


def test_a_figure_larger_than_its_room_is_cropped_by_its_layout(tmp_path):
    """A legend that runs off the room drawn around the figure: the crop falls back on matplotlib's
    layout and the whole legend is in the picture."""
    from PIL import Image

    fig, ax = plt.subplots(figsize=(4, 2))
    for i in range(40):
        ax.plot([0, 1], [i, i], label=f"line {i}")
    legend = plots.legend_outside(ax)
    tight = fig.get_tightbbox(fig.canvas.get_renderer()).padded(plots.PAD)
    assert legend.get_window_extent().height / fig.dpi > 2 + plots.ROOM[1]  # beyond the room
    png, svg = plots.save_figure(fig, tmp_path, "tall")
    rows = np.asarray(Image.open(png)).shape[0]
    assert rows == pytest.approx(tight.height * plots.DPI, abs=2)
    assert _svg_size_pt(svg)[1] == pytest.approx(tight.height * 72, abs=1)


def test_a_result_shows_its_summary_alone_below_the_outputs_floor():
    config = load_preset("paper-ellipse").replace(
        simulation={"duration": 2.5}, plant={"torque_limits": [3, 3, 1]}
    )
    result = run_experiment(config)
    table = result._repr_html_()
    metrics = result.metrics()
    assert f"{1e3 * metrics['rms_error_after_2s']:.4g} mm" in table and "torque saturation" in table
    assert "<img" not in table
    page = plots.result_html(result)
    assert page.startswith(table) and page.count('<img src="data:image/png;base64,') == 2


SHELL = "from IPython.core.interactiveshell import InteractiveShell; shell = InteractiveShell.instance()"
"""What a Jupyter kernel is: a shell that ``get_ipython()`` returns."""

NOTEBOOK = """
{before}
{after}
from nnrobust.config.presets import load_preset
from nnrobust.run.experiment import run_experiment

result = run_experiment(load_preset("paper-ellipse").replace(simulation={{"duration": 2.5}}))
data, _ = shell.display_formatter.format(result)
print(data["text/html"].count('<img src="data:image/png;base64,'), "RMS error" in data["text/html"])
"""


@pytest.mark.parametrize(
    "before, after",
    [
        (SHELL, ""),  # importing nnrobust.run.experiment imports the package: registered there
        ("import nnrobust", SHELL + "; nnrobust.Result"),  # the shell came later: the first use
    ],
    ids=["shell-first", "shell-after"],
)
def test_a_notebook_shows_a_result_with_its_path_and_error_figures(before, after):
    import subprocess
    import sys

    pytest.importorskip("IPython")
    out = subprocess.run(
        [sys.executable, "-c", NOTEBOOK.format(before=before, after=after)],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert out.stdout.split() == ["2", "True"], out.stderr
