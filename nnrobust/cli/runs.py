"""One run and its folder: run, plot, compare, view."""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

from ..core.exceptions import ConfigError, NNRobustError, one_line
from ..outputs.run_folder import (
    Drawing,
    RunFolderError,
    check_out_folder,
    check_parent,
    load_run,
    locked,
    redraw_run,
    write_run,
)
from .common import (
    Command,
    controller_change,
    controller_choice,
    format_table,
    load_target,
    viewer_options,
)
from .console import (
    warning_line,
)


def _live_view(args, config, setup):
    """Start the viewer, draw the arm and the desired path; returns (viewer, callback)."""
    import numpy as np

    from ..outputs.viewer import RunScene, start_viewer
    from ..outputs.viewer.scene import world_points
    from ..run.run_info import RunInfo

    viewer = start_viewer(args.host, args.port)
    scene = RunScene(viewer.vis, RunInfo.from_config(config))
    chain = setup.robot.chain_points(setup.q0)
    tip_z = chain[-1, 2]
    times = np.linspace(0.0, config.simulation.duration, 400)
    desired = world_points(setup.trajectory.position(times), tip_z)
    scene.draw_paths(desired)
    scene.frame_camera(np.vstack([desired, chain]))
    print(f"live view: {viewer.web_url}", file=sys.stderr)

    def show(t, q):
        scene.show(q, world_points(setup.trajectory(t)[0][:3], tip_z)[0])

    return viewer, show


def cmd_run(args) -> int:
    """Run a preset or an experiment file and write its run folder."""
    from ..config import parse_override

    changes: dict = {}  # the flags' keys and --set's, set in the file's values before it resolves
    if args.controller:
        changes.update({f"controller.{k}": v for k, v in controller_change(args.controller).items()})
    if args.duration is not None:
        changes["simulation.duration"] = args.duration
    if args.backend:
        changes["simulation.backend"] = args.backend
    if args.view:  # the live view follows the run step by step: the Python loop
        if args.backend and args.backend != "python":
            raise ConfigError(
                "--backend", f"--view follows the run on the Python loop; drop --backend {args.backend}"
            )
        changes["simulation.backend"] = "python"
    overrides = dict(parse_override(item) for item in args.set or ())
    for flag, given, keys in (
        ("--controller", args.controller, ("controller.kind", "controller.class")),
        ("--duration", args.duration is not None, ("simulation.duration",)),
        ("--backend", args.backend or args.view, ("simulation.backend",)),
    ):
        both = [key for key in keys if key in overrides]
        if given and both:
            raise ConfigError(both[0], f"given twice, by {flag} and by --set; give it once")
    config = load_target(args.target, {**changes, **overrides})
    if overrides:
        from ..config import inert_reason

        for key in overrides:
            reason = inert_reason(config, key)
            if reason:
                warnings.warn(f"--set {key} changes nothing here: {reason}", stacklevel=2)
    from ..config import controller_label

    out = check_out_folder(args.out or f"out/{config.name}-{controller_label(config)}", args.overwrite)
    with locked(out):
        return _run_into(args, config, out)


def _run_into(args, config, out: Path) -> int:
    """Simulate and write the run folder (``out`` is checked and locked)."""
    from ..config import controller_label

    if not args.quiet:
        print(
            f"running {config.name} with controller {controller_label(config)!r} "
            f"for {config.simulation.duration:g} s ...",
            file=sys.stderr,
        )
    # the figures' process is forked now, so that it imports matplotlib while the run simulates
    with Drawing(plots=not args.no_plots, animation=not args.no_animation) as drawing:
        return _simulate_and_write(args, config, out, drawing)


def _simulate_and_write(args, config, out: Path, drawing: Drawing) -> int:
    from ..core.progress import ProgressBar
    from ..run.experiment import build, run_experiment

    setup = build(config)
    bar = None if args.quiet else ProgressBar(config.simulation.duration)
    viewer = show = None
    if args.view:
        viewer, show = _live_view(args, config, setup)

    def progress(t, q):
        if bar is not None:
            bar(t, q)
        if show is not None:
            show(t, q)

    try:
        result = run_experiment(config, progress, setup)
        if bar is not None:
            bar.finish(float(result.t[-1]) if result.t.size else 0.0)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            written = write_run(out, result, overwrite=args.overwrite, drawing=drawing)
        for warning in caught:  # where the folder went, when not where asked (said even with --quiet)
            warning_line(warning.message, warning.category, warning.filename, warning.lineno)
        metrics = result.metrics()
        if not args.quiet:  # "print nothing but errors": the verdicts stay in metrics.json
            for verdict in metrics["warnings"]:
                print(f"warning: {verdict}", file=sys.stderr)
            print(format_table([(str(written), metrics)]))
            print(
                f"simulated {metrics['simulated_seconds']:.2f} s in {metrics['wall_seconds']:.2f} s "
                f"wall; results in {written}/",
                file=sys.stderr,
            )
        if viewer is not None:
            from ..outputs.viewer import draw_run

            draw_run(viewer.vis, result)
            _serve_until_interrupted(viewer)
    finally:
        if viewer is not None:
            viewer.close()
    if result.status != "completed":
        print(f"run {result.status}: {one_line(result.message)}", file=sys.stderr)
        return 1
    return 0


def _serve_until_interrupted(viewer, seconds: float | None = None) -> None:
    import time
    from urllib.parse import urlsplit

    host = urlsplit(viewer.web_url).hostname
    print(f"viewer at {viewer.web_url} (listening on {host} only); Ctrl-C to stop", file=sys.stderr)
    end = None if seconds is None else time.monotonic() + seconds
    try:
        while end is None or time.monotonic() < end:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass


def cmd_plot(args) -> int:
    """Draw the figures and animation of run folders again (run_folder.redraw_run)."""
    code = 0
    for folder in args.runs:
        extras = redraw_run(folder, plots=not args.no_plots, animation=not args.no_animation)
        if extras != "complete":  # the reason was said as a warning
            code = 1
        else:
            print(f"drew {Path(folder)}/", file=sys.stderr)
    return code


def cmd_view(args) -> int:
    """Replay a run folder in the meshcat viewer."""
    from ..outputs.viewer import draw_run, start_viewer

    folder = Path(args.run)
    if not (folder / "config.toml").is_file():
        raise NNRobustError(f"{folder}: not a run folder (config.toml is missing)")
    result = load_run(folder)
    with start_viewer(args.host, args.port) as viewer:
        draw_run(viewer.vis, result)
        if args.open:
            import webbrowser

            webbrowser.open(viewer.web_url, new=2)
        _serve_until_interrupted(viewer, args.seconds)
    return 0


def run_labels(folders: list[str]) -> list[str]:
    """A label per run folder: its name, or as many trailing path parts as make it unique
    (x/run and y/run are x/run and y/run, never both "run").
    """
    if len({Path(f).resolve() for f in folders}) != len(folders):
        raise NNRobustError("the same run folder is given twice")
    parts = [Path(f).resolve().parts for f in folders]
    depth = 1
    while True:
        labels = ["/".join(p[-depth:]) for p in parts]
        if len(set(labels)) == len(labels):
            return labels
        depth += 1


def check_figure_folder(folder: str) -> None:
    """Refuse, before any work, a folder for figures that cannot be made or written."""
    path = Path(folder)
    if path.exists() and not path.is_dir():
        raise RunFolderError(f"{folder} exists and is not a folder; choose another --out")
    check_parent(path)


def cmd_compare(args) -> int:
    """Table of metrics and overlaid plots for several run folders."""
    if args.out:
        check_figure_folder(args.out)
    rows, results = [], {}
    for label, folder in zip(run_labels(args.runs), args.runs):
        result = load_run(folder)  # checks that metrics.json holds a table
        rows.append((label, json.loads((Path(folder) / "metrics.json").read_text())))
        results[label] = result
    print(format_table(rows))
    from ..outputs.plots import comparison_warnings, plot_comparison
    from ..outputs.run_deltas import delta_table, verdict_changes
    from ..run.properties import run_properties

    properties = run_properties(args.require or [])
    if len(rows) > 1:
        print(f"\nchanges from {one_line(rows[0][0], 60)}:")
        print(delta_table(rows))
        changed = verdict_changes(rows, properties)
        print(
            "\nverdicts that change:"
            if changed
            else "\nno verdict changes"
            + (f" ({', '.join(p.text for p in properties)} and the warnings)" if properties else "")
        )
        for line in changed:  # names and values from received folders: no control characters
            print(f"  {one_line(line)}")

    for warning in comparison_warnings(results):
        print(f"warning: {one_line(warning)}", file=sys.stderr)
    if args.out:
        written = plot_comparison(results, args.out)
        print(f"comparison plot: {written[0]}", file=sys.stderr)
    return 0


def run_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust run``."""
    from ..config import shipped_laws
    from ..controllers.registry import LAWS, law_names

    parser.add_argument("target", help="preset name (see 'nnrobust presets') or path to a .toml file")
    parser.add_argument("--out", help="run folder (default out/NAME-CONTROLLER)")
    parser.add_argument(
        "--controller",
        type=controller_choice,
        metavar="{" + ",".join(shipped_laws()) + ",FILE.py:CLASS}",
        help="override the controller: nn (eq. 9 + NN compensator), no-u0 "
        "(eq. 9 without u_0), computed-torque (eq. 9 with the true model and friction), "
        "sliding-mode (eq. 9 + fixed-gain boundary-layer sliding mode), pd (task-space "
        "PD + gravity compensation), "
        + "".join(f"{name} ({LAWS[name].summary.split(',')[0]}), " for name in law_names())
        + "or your own class as file.py:Class or package.module:Class "
        "(parameters of these last from --set controller.params.NAME=VALUE; docs/controller.md, "
        "docs/extending.md)",
    )
    parser.add_argument("--duration", type=float, help="override the simulated time [s]")
    parser.add_argument(
        "--backend",
        choices=("auto", "compiled", "hybrid", "python"),
        help="simulation loop: compiled (C++), hybrid (the compiled plant calling a Python "
        "controller once per period), python (the reference) or auto (compiled when the "
        "experiment has a compiled twin, hybrid for a custom controller; the default)",
    )
    parser.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="set one key of the experiment (dotted, TOML value), e.g. --set nn.sigma=0.5 "
        "--set 'controller.Kp=[100.0]'; repeatable, checked like an experiment file",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an existing run folder")
    parser.add_argument("--no-plots", action="store_true", help="skip the figures")
    parser.add_argument(
        "--no-animation",
        action="store_true",
        help="skip animation.html (the 3-D replay; a few MB for meshed robots)",
    )
    parser.add_argument(
        "--quiet", action="store_true", help="print nothing but errors (no progress bar, no summary table)"
    )
    parser.add_argument(
        "--view",
        action="store_true",
        help="watch the arm live in meshcat while it runs, then replay the run until Ctrl-C",
    )
    viewer_options(parser)


RUN = Command(
    "run",
    help="run a preset or an experiment file (TOML)",
    description="Simulate a preset or a TOML experiment file and write a run "
    "folder: config.toml, result.npz, metrics.json, plots/, animation.html.",
    arguments=run_arguments,
    run=cmd_run,
)


def plot_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust plot``."""
    parser.add_argument("runs", nargs="+", help="run folders written by 'nnrobust run'")
    parser.add_argument("--no-plots", action="store_true", help="leave plots/ as it is")
    parser.add_argument("--no-animation", action="store_true", help="leave animation.html as it is")


PLOT = Command(
    "plot",
    help="draw the figures and animation of run folders again",
    description="Draw plots/ and animation.html of run folders from their "
    "result.npz, as 'nnrobust run' draws them: after a drawing that was "
    "interrupted or skipped (--no-plots, --no-animation), or to redraw after an "
    "upgrade. The arrays and metrics are not touched.",
    arguments=plot_arguments,
    run=cmd_plot,
)


def compare_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust compare``."""
    parser.add_argument("runs", nargs="+", help="run folders written by 'nnrobust run'")
    parser.add_argument("--out", help="folder for the comparison figure (PNG and SVG)")
    parser.add_argument(
        "--require",
        action="append",
        metavar="EXPR",
        help="a property each run is checked against, METRIC OP VALUE (e.g. "
        "'rms_error_after_2s<=0.05'); repeatable; shown where runs disagree",
    )


COMPARE = Command(
    "compare",
    help="compare run folders: metrics table and plots",
    description="Print the metrics of several run folders side by side "
    "(labelled by folder name, or by as much of the path as tells them "
    "apart), each metric's change from the first run, and the verdicts "
    "(status, warnings, --require properties) that differ; with --out, draw "
    "their paths, errors and torques in one figure. The same experiment run "
    "with --set plant.engine=mujoco gives the sim-to-sim gap (docs/engines.md).",
    arguments=compare_arguments,
    run=cmd_compare,
)


def view_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust view``."""
    parser.add_argument("run", help="run folder written by 'nnrobust run'")
    parser.add_argument("--open", action="store_true", help="open the page in the default browser")
    parser.add_argument("--seconds", type=float, help="stop after this many seconds (default: Ctrl-C)")
    viewer_options(parser)


VIEW = Command(
    "view",
    help="replay a run folder in the meshcat viewer (browser)",
    description="Serve the run's 3-D replay (arm from the URDF, desired path, "
    "end-effector trace) with meshcat and print the address to open. The "
    "run folder's animation.html is the same replay as a file.",
    arguments=view_arguments,
    run=cmd_view,
)
