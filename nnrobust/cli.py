"""Command line: ``nnrobust run | plot | sweep | presets | robots | compare | view | bench``."""

from __future__ import annotations

from .signals import ignore_stop_signals, install_stop_handlers, signals_as_interrupt  # light

if __name__ == "__main__":  # python -m nnrobust.cli: a stop signal during the imports is noted
    install_stop_handlers()

import argparse  # noqa: E402 (the stop handlers first)
import errno
import json
import os
import sys
import warnings
from pathlib import Path

from .exceptions import ConfigError, NNRobustError, one_line
from .run_folder import (
    Drawing,
    ExtrasInterrupted,
    RunFolderError,
    check_out_folder,
    check_parent,
    load_run,
    locked,
    redraw_run,
    write_run,
)

TABLE_COLUMNS = (
    ("run", None),
    ("status", None),
    ("rms_error", 1e3),
    ("rms_error_after_2s", 1e3),
    ("max_error", 1e3),
    ("rms_torque", 1.0),
    ("torque_chatter", 1.0),
    ("saturated_fraction", 100.0),
    ("final_rho_hat", 1.0),
)
HEADERS = (
    "run",
    "status",
    "rms e [mm]",
    "rms e t>=2s [mm]",
    "max e [mm]",
    "rms |tau| [N m]",
    "chatter [N m]",
    "saturated [%]",
    "rho-hat end",
)


ORIENTATION_COLUMN = ("rms_orientation_error_after_2s", 1e3)
ORIENTATION_HEADER = "rms rot t>=2s [mrad]"


def format_table(rows: list[tuple[str, dict]]) -> str:
    """A plain-text table of run metrics (position errors in mm; orientation in mrad for poses)."""
    columns, headers = list(TABLE_COLUMNS), list(HEADERS)
    if any(ORIENTATION_COLUMN[0] in metrics for _, metrics in rows):
        columns.insert(4, ORIENTATION_COLUMN)
        headers.insert(4, ORIENTATION_HEADER)
    if any(metrics.get("plant_engine", "pinocchio") != "pinocchio" for _, metrics in rows):
        columns.insert(2, ("plant_engine", None))
        headers.insert(2, "engine")
    cells = [headers]
    for name, metrics in rows:
        row = []
        for key, scale in columns:
            if key == "run":
                row.append(one_line(name, 60))
            elif scale is None:  # text from a received folder: one line, no control characters
                row.append(one_line(str(metrics.get(key, "pinocchio" if key == "plant_engine" else "")), 60))
            else:
                value = metrics.get(key)
                number = isinstance(value, (int, float)) and not isinstance(value, bool)
                row.append(
                    "-" if value is None else f"{value * scale:.4g}" if number else one_line(str(value), 20)
                )
        cells.append(row)
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = [
        "  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))) for r in cells
    ]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _load_target(target: str, overrides: dict | None = None):
    """A preset or an experiment file, with ``overrides`` (dotted keys) set in its own values
    (:func:`nnrobust.config.load_config`): as if the file had been edited so.
    """
    from .config import load_config
    from .presets import preset_names, preset_path, presets_hint

    path = Path(target)
    if path.suffix == ".toml" or path.exists():
        return load_config(path, overrides)
    if target in preset_names():
        return load_config(preset_path(target), overrides)
    raise NNRobustError(f"{target!r} is neither a TOML file nor a preset; {presets_hint(target)}")


def _live_view(args, config, setup):
    """Start the viewer, draw the arm and the desired path; returns (viewer, callback)."""
    import numpy as np

    from .run_info import RunInfo
    from .viewer import RunScene, start_viewer
    from .viewer.scene import world_points

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


def _controller_choice(text: str) -> str:
    """--controller: a built-in kind, or a custom class (``file.py:Class``, ``package.module:Class``)."""
    from .config import CLASS_PATTERN, shipped_laws

    if text in shipped_laws() or CLASS_PATTERN.fullmatch(text):
        return text
    raise argparse.ArgumentTypeError(
        f"{text!r} is not one of {', '.join(shipped_laws())} nor a class as "
        "file.py:Class or package.module:Class"
    )


MAX_KEEP_WORST = 100
"""Most run folders --keep-worst writes per controller (each holds a whole run and its animation)."""


def _keep_count(text: str) -> int:
    """--keep-worst K: an integer in [0, MAX_KEEP_WORST]."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value <= MAX_KEEP_WORST:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer in [0, {MAX_KEEP_WORST}]")
    return value


def controller_change(choice: str) -> dict:
    """The controller section's change for --controller: a kind, or a custom class (a file path
    from the working folder).
    """
    from .config import shipped_laws
    from .user_code import class_file

    if choice in shipped_laws():
        return {"kind": choice, "class": None, "params": None}
    path, name = class_file(choice), choice.rpartition(":")[2]
    return {"kind": "custom", "class": f"{path.resolve()}:{name}" if path is not None else choice}


def cmd_run(args) -> int:
    """Run a preset or an experiment file and write its run folder."""
    from .config import parse_override

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
    config = _load_target(args.target, {**changes, **overrides})
    if overrides:
        from .config import inert_reason

        for key in overrides:
            reason = inert_reason(config, key)
            if reason:
                warnings.warn(f"--set {key} changes nothing here: {reason}", stacklevel=2)
    from .config import controller_label

    out = check_out_folder(args.out or f"out/{config.name}-{controller_label(config)}", args.overwrite)
    with locked(out):
        return _run_into(args, config, out)


def _run_into(args, config, out: Path) -> int:
    """Simulate and write the run folder (``out`` is checked and locked)."""
    from .config import controller_label

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
    from .experiment import build, run_experiment
    from .progress import ProgressBar

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
            _warning_line(warning.message, warning.category, warning.filename, warning.lineno)
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
            from .viewer import draw_run

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


def _served_target(args, verb: str):
    """The experiment of ``export`` and ``serve``: a preset, an experiment file or a run folder's
    config.toml, with --controller, the --tuned setting and --set (which wins over --tuned), each
    --set that changes nothing warned about as ``run`` does.
    """
    from .config import inert_reason, parse_override

    target = Path(args.target)
    if target.is_dir():
        if not (target / "config.toml").is_file():
            raise NNRobustError(f"{target}: not a run folder (config.toml is missing)")
        target = target / "config.toml"
    overrides = dict(parse_override(item) for item in args.set or ())
    changes = {}
    certified = None
    if getattr(args, "tuned", None) and getattr(args, "controller", None):
        from .tune.engine import kept_entry

        certified = kept_entry(args.tuned, args.controller)  # a study's law by the name it gave it
    if certified is not None:  # exactly what its certification ran: kind or class, params, set
        changes = _entry_changes(certified)
    elif getattr(args, "controller", None):
        changes = {f"controller.{k}": v for k, v in controller_change(args.controller).items()}
    config = _load_target(str(target), {**changes, **overrides})
    if getattr(args, "tuned", None) and certified is None:  # the tuning's best setting, under --set
        from .tune.engine import tuned_settings, tuned_target

        kind = config.controller.kind
        settings = tuned_settings(args.tuned, [kind]).get(kind, {})
        tuned_on = tuned_target(args.tuned)
        if tuned_on and tuned_on not in (config.name, args.target, Path(args.target).stem):
            warnings.warn(
                f"--tuned: that tuning was of {tuned_on}, not {config.name}: its setting is {verb} as "
                "it is, on another experiment",
                stacklevel=2,
            )
        config = _load_target(str(target), {**changes, **settings, **overrides})
    for key in overrides:
        reason = inert_reason(config, key)
        if reason:
            warnings.warn(f"--set {key} changes nothing here: {reason}", stacklevel=2)
    return config


def _entry_changes(entry: dict) -> dict:
    """The dotted-key changes that run a sweep's or a study's controllers entry: its kind or class
    (a class file as the working folder finds it), its params and its own settings.
    """
    if "class" in entry:
        changes = {f"controller.{k}": v for k, v in controller_change(entry["class"]).items()}
    else:
        changes = {"controller.kind": entry.get("kind"), "controller.class": None}
    changes["controller.params"] = dict(entry["params"]) if entry.get("params") else None
    return {**changes, **(entry.get("set") or {})}


def cmd_export(args) -> int:
    """Export the controller of a preset, experiment file or run folder as a C library."""
    from .export import export_law

    config = _served_target(args, "exported")
    info = export_law(config, args.out, overwrite=args.overwrite, build=not args.no_build)
    if not args.quiet:
        built = (
            "lib/libnnrobust_law.so, bin/drive, bin/replay" if info["built"] else "sources only (--no-build)"
        )
        print(
            f"exported {info['controller']} of {info['experiment']} ({info['joints']} joints, law "
            f"{info['law']}, step period {info['period']:g} s) to {args.out}/: {built}; docs/export.md "
            "shows how to call it",
            file=sys.stderr,
        )
    return 0


def cmd_serve(args) -> int:
    """Serve an experiment's plant in real time to a controller in another process."""
    from .serve import serve

    config = _served_target(args, "served")

    def ready(port: int) -> None:
        if not args.quiet:
            print(
                f"virtual robot of {config.name} listening on {args.host}:{port} (UDP, docs/serve.md); "
                f"start its controller, e.g. nnrobust export ... --out LAW && LAW/bin/drive {port}",
                file=sys.stderr,
                flush=True,
            )

    record = serve(
        config,
        args.out,
        host=args.host,
        port=args.port,
        watchdog=args.watchdog,
        wait_seconds=args.wait,
        realtime=args.rt,
        lockstep=args.lockstep,
        overwrite=args.overwrite,
        compare=not args.no_compare,
        plots=not args.no_plots,
        on_ready=ready,
    )
    if not args.quiet:
        latency = record["round_trip_latency_us"]
        said = "; ".join(f"{count} {reason}" for reason, count in record["rejected"].items()) or "none"
        rate, misses = 1 / record["period_s"], record["deadline_misses"]
        print(
            f"{record['periods']} periods at {rate:g} Hz: {misses} deadline misses; round trip p50 "
            f"{latency['p50'] or 0:.0f} us, p99 {latency['p99'] or 0:.0f} us, max {latency['max'] or 0:.0f} "
            f"us; rejected: {said}",
            file=sys.stderr,
        )
        if record["stopped"]:
            print(f"the robot stopped: {record['stopped']}", file=sys.stderr)
        if record.get("tracking_ratio") is not None:
            served, simulated = record["served"], record["simulated"]
            print(
                f"tracking (rms error after 2 s) {served['rms_error_after_2s'] * 1e3:.4g} mm served, "
                f"{simulated['rms_error_after_2s'] * 1e3:.4g} mm simulated "
                f"(ratio {record['tracking_ratio']:.4f}); results in {record['folder']}/",
                file=sys.stderr,
            )
    return 0 if record["served"]["status"] == "completed" and not record["stopped"] else 1


def cmd_view(args) -> int:
    """Replay a run folder in the meshcat viewer."""
    from .viewer import draw_run, start_viewer

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


_BAR_OPEN = [False]
"""Whether a progress line waits on stderr for its end (an error then starts a line of its own)."""


def _bar(done: int, total: int, text: str) -> None:
    """One progress line on stderr, redrawn in place."""
    filled = int(30 * done / max(total, 1))
    print(
        f"\r[{'#' * filled}{' ' * (30 - filled)}] {done}/{total} {text}   ",
        end="",
        file=sys.stderr,
        flush=True,
    )
    _BAR_OPEN[0] = True


def _error(line: str) -> None:
    """``nnrobust: LINE`` on stderr, on a line of its own."""
    start = "\n" if _BAR_OPEN[0] else ""
    _BAR_OPEN[0] = False
    print(f"{start}nnrobust: {line}", file=sys.stderr)


def _resumable(work, kept):
    """work()'s result, or None after Ctrl-C with one line saying what was kept (``kept``, or
    what ``kept()`` says then) and how to resume.
    """
    try:
        return work()
    except KeyboardInterrupt:
        said = kept() if callable(kept) else kept
        print(f"\nnnrobust: {said}; run the same command again to resume", file=sys.stderr)
        return None


def cmd_sweep(args) -> int:
    """Run or resume a robustness sweep on dask.distributed."""
    import time

    from .sweep import load_sweep, read_results, run_sweep
    from .sweep.summary import format_summary, keep_worst, plot_sweep, summarize, write_summary

    spec = load_sweep(args.sweep)
    if args.tuned:  # each controller at its best setting of a tuning, as NAME-tuned
        from .tune.engine import _with_controllers, check_tuned_values, tuned_settings

        tuned = tuned_settings(args.tuned, spec.controllers, spec.vary, spec.entries)
        spec = _with_controllers(spec, spec.controllers, tuned)
        check_tuned_values(spec, tuned)
    out = Path(args.out)
    properties, claim = _sweep_claim(args, spec)

    def progress(done, total):
        if args.quiet:
            return
        if not started:  # the sweep validated and its cluster is up
            started.append(time.monotonic())
            where = args.scheduler or f"a local cluster of {args.workers or 'one worker per core'}"
            print(
                f"sweep {spec.name}: {spec.size} samples x {len(spec.controllers)} controllers on "
                f"{where}; {done} of {total} rows already done",
                file=sys.stderr,
            )
        if len(started) == 1:
            started.append(done)  # rows already there when the sweep started
        elapsed = time.monotonic() - started[0]
        rate = (done - started[1]) / elapsed if elapsed > 0 else 0.0
        eta = f"{(total - done) / rate:.0f} s" if rate > 0 else "?"
        _bar(done, total, f"rows, {rate:.2f}/s, ETA {eta}")

    started: list[float] = []
    checking_since = time.monotonic()
    checking_shown: list[bool] = []

    def checking(done, total):  # 10^6 rows take minutes to validate: said after a second
        if args.quiet:
            return
        elapsed = time.monotonic() - checking_since
        if not checking_shown and (elapsed < 1.0 or done == total):  # quick: nothing to show
            return
        if not checking_shown:
            checking_shown.append(True)
            print(
                f"sweep {spec.name}: checking the experiments of {total} rows before any of them runs",
                file=sys.stderr,
            )
        eta = f"{elapsed * (total - done) / done:.0f} s" if done else "?"
        _bar(done, total, f"rows checked, ETA {eta}")
        if done == total:
            print(file=sys.stderr)

    stop = None
    if args.stop_early:
        from .exceptions import ConfigError
        from .properties import refuted_groups

        if not claim:
            raise ConfigError(
                "--stop-early", "stops once a claim is refuted: give --require, --epsilon and --beta"
            )
        stop = lambda records: refuted_groups(spec, records, properties, *claim)  # noqa: E731
    counts = _resumable(
        lambda: run_sweep(
            spec, out, args.workers, args.scheduler, args.overwrite, progress, stop=stop, checking=checking
        ),
        lambda: (
            f"sweep interrupted; the rows written so far are in {out}/results"
            if (out / "results").is_dir()
            else "sweep interrupted before any row was written"
        ),
    )
    if counts is None:
        return 130
    if started:
        print(file=sys.stderr)
    frame = read_results(out)
    summary = summarize(spec, frame)
    certified = {}
    if properties and claim:
        from .properties import certify

        certified = certify(spec, frame, properties, *claim, stopped_early=bool(counts.get("stopped")))
        for controller, entry in certified.items():
            summary["controllers"][controller].update(entry)
    write_summary(out, summary)
    plot_sweep(spec, frame, out)
    if args.keep_worst:
        kept = keep_worst(spec, frame, out, args.keep_worst)
        if not args.quiet:
            print(f"run folders of the worst samples: {', '.join(str(p) for p in kept)}", file=sys.stderr)
    if not args.quiet:
        print(format_summary(summary))
        if certified:
            from .properties import format_certificates

            print("\n".join(format_certificates(certified)))
        for controller, entry in summary["controllers"].items():
            if "worst" in entry:
                print(f"worst {controller}: sample {entry['worst']['sample']}: {entry['worst']['command']}")
        stopped = f", {counts['stopped']} not run (claim already refuted)" if counts.get("stopped") else ""
        print(
            f"{counts['computed']} rows computed, {counts['skipped']} already there{stopped}; results in "
            f"{out}/results (pandas.read_parquet), summary in {out}/summary.json",
            file=sys.stderr,
        )
    return _broken_rows(frame)


def _broken_rows(frame) -> int:
    """1 (and a line on stderr) when a row ended with status ``crashed`` (its worker died) or
    ``error`` (a defect): such a sweep is not a result to cite; 0 otherwise.
    """
    broken = frame[frame["status"].isin(["crashed", "error"])]
    if not len(broken):
        return 0
    first = broken.iloc[0]
    print(
        f"nnrobust: {len(broken)} rows ended without a result ({', '.join(sorted(set(broken['status'])))}); "
        f"first: sample {first['sample']}, {first['controller']}: {one_line(str(first['message']))}",
        file=sys.stderr,
    )
    return 1


def _sweep_claim(args, spec) -> tuple[list, tuple[float, float] | None]:
    """(the properties of --require, (epsilon, beta) or None), the sweep's size checked against
    the claim before anything runs.
    """
    from .exceptions import ConfigError
    from .properties import check_claim, confidence_text, run_properties, samples_needed

    properties = run_properties(args.require)
    if (args.epsilon is None) != (args.beta is None):
        raise ConfigError("--epsilon", "give --epsilon and --beta together (the claim and its confidence)")
    if args.epsilon is None:
        if properties:
            raise ConfigError(
                "--require",
                "needs --epsilon and --beta: the claim P(fail) <= EPSILON with "
                "confidence 1 - BETA that the sweep certifies",
            )
        return properties, None
    if not properties:
        raise ConfigError("--epsilon", "certifies the properties of --require; give at least one")
    check_claim(args.epsilon, args.beta, args.failures)
    needed = samples_needed(args.epsilon, args.beta, args.failures)
    if spec.samples < needed and not args.allow_small:
        cell = " per grid point" if spec.grid_keys else ""
        raise ConfigError(
            "samples",
            f"P(fail) <= {args.epsilon:g} with confidence {confidence_text(args.beta)} needs "
            f"N >= {needed} samples{cell} with at most {args.failures} failures; the sweep "
            f"draws {spec.samples}: raise samples, or --allow-small to report the bound anyway",
        )
    return properties, (args.epsilon, args.beta)


def _simulations_bar(quiet: bool, first_line):
    """(progress(done, total), started): a bar of simulations, after one line ``first_line(done,
    total)`` says what runs; ``started`` holds the start time once it has.
    """
    import time

    started: list[float] = []

    def progress(done, total):
        if quiet:
            return
        if not started:
            started.append(time.monotonic())
            print(first_line(done, total), file=sys.stderr)
        _bar(done, total, f"simulations, {time.monotonic() - started[0]:.0f} s")

    return progress, started


def cmd_study(args) -> int:
    """Run (or resume) a study: tune, validate, certify and falsify every case, then the report."""
    import time

    from .study import load_study, run_study
    from .study.tables import console_line, table_rows

    spec = load_study(args.study)
    start = time.monotonic()

    def say(line: str) -> None:
        if not args.quiet:
            print(f"\rstudy {spec.name} [{time.monotonic() - start:.0f} s] {line}".ljust(60), file=sys.stderr)
            _BAR_OPEN[0] = False

    def progress(done: int, total: int) -> None:
        if not args.quiet:
            _bar(done, total, f"of the stages now running, {time.monotonic() - start:.0f} s in all")

    report = _resumable(
        lambda: run_study(spec, args.out, args.workers, args.scheduler, args.overwrite, say, progress),
        f"study interrupted; each stage keeps what it computed under {args.out}/cases",
    )
    if report is None:
        return 130
    if not args.quiet:
        print(file=sys.stderr)
        for row in table_rows(report):
            print(console_line(row))
        for name, case in report["cases"].items():
            for controller, reason in case["not_kept"].items():
                print(f"{name:24s} {controller:18s} not kept: {reason}")
        for warning in report.get("warnings", []):
            print(f"warning: {warning}", file=sys.stderr)
        print(f"report in {args.out}/report.html and {args.out}/report.json", file=sys.stderr)
    return 0


def cmd_falsify(args) -> int:
    """Search each controller's worst plant in the sweep file's box, at one budget."""
    from .falsify import FalsifySpec, run_falsify
    from .falsify.summary import replayed_worst

    controllers = [c.strip() for c in args.controllers.split(",") if c.strip()]
    tuned = None
    if args.tuned:
        from .sweep import load_sweep
        from .tune.engine import tuned_settings

        box = load_sweep(args.sweep)
        tuned = tuned_settings(args.tuned, controllers, box.vary, box.entries)
    spec = FalsifySpec(args.sweep, controllers, args.require, args.budget, args.seed, args.margin, tuned)
    progress, started = _simulations_bar(
        args.quiet,
        lambda done, total: (
            f"falsify {args.sweep}: {', '.join(spec.controllers)}, {spec.budget} simulations each and as "
            f"many for random search; {done} of {total} already done"
        ),
    )

    out = Path(args.out)
    summary = _resumable(
        lambda: run_falsify(
            spec, out, args.workers, args.scheduler, args.overwrite, progress, (args.epsilon, args.beta)
        ),
        f"search interrupted; the plants simulated so far are in {out}/history",
    )
    if summary is None:
        return 130
    if started:
        print(file=sys.stderr)
    if not args.quiet:
        for name, entry in summary["controllers"].items():
            baseline = entry["random_baseline"]
            worst, found_by = replayed_worst(entry)
            verdict = "FALSIFIED" if entry["falsified"] else "not falsified"
            if found_by == "random":
                verdict = "FALSIFIED by random search only (the search found none)"
            status = worst["metrics"].get("status", "completed")
            ended = (
                f" (the run ended {status}: {one_line(str(worst['metrics'].get('message', '')))})"
                if status != "completed"
                else ""
            )
            print(
                f"{name}: {verdict} in {entry['simulations']} simulations; least margin "
                f"{worst['margin']:.4g}{ended} (random search: {baseline['worst']['margin']:.4g}); "
                f"worst plant: {worst['command']}"
            )
        if summary.get("searched_as"):
            print(f"searched: {summary['searched_as']}")
        for name, margin in summary.get("margin", {}).items():
            print(format_margin(name, margin))
        from .properties import format_certificates

        certified = {name: entry["certificate"] for name, entry in summary["controllers"].items()}
        print("from the random baseline (independent draws of the box):")
        print("\n".join(f"  {line}" for line in format_certificates(certified)))
        print(
            f"summary in {out}/summary.json, history in {out}/history, {out}/falsification.csv",
            file=sys.stderr,
        )
    if args.keep_worst:
        from .falsify import keep_worst

        for folder in keep_worst(spec, summary, out, args.keep_worst):
            if not args.quiet:
                print(f"worst plant kept: {folder}/ (nnrobust view {folder})", file=sys.stderr)
    return 0


def format_margin(name: str, margin: dict) -> str:
    """One controller's robustness margin in a line: the largest scale of the box searched without
    a violation, and the scale and plant that violated.
    """
    plant, low, high = margin["violating_plant"], margin["holds_up_to"], margin["violated_at"]
    if high == 0.0:
        return f"{name}: margin 0 (the nominal plant, the centre of the box, fails: {plant['command']})"
    held = f"no violation found up to {low:.3g} x the box with {margin['simulations']} simulations"
    if high is None:
        return f"{name}: margin >= {low:.3g} ({held}, the largest scale tried)"
    return f"{name}: margin {low:.3g} ({held}; violated at {high:.3g} x by {plant['command']})"


def format_tuning(summary: dict) -> str:
    """Each controller's best setting under the constraints: errors on the training and the
    held-out samples, torque, chatter, the bounds it sits on, and the keys it does not search
    with why.
    """
    from .tune.engine import infeasible_text
    from .tune.space import fixed_text

    lines = [
        f"{'':14s} {'training draws':^29s}   {'held-out draws':^29s}",
        f"{'controller':14s} {'e [mm]':>10s} {'tau [N m]':>9s} {'chatter':>8s}   {'e [mm]':>10s} "
        f"{'tau [N m]':>9s} {'feasible':>8s}  setting",
    ]
    for name, entry in summary["controllers"].items():
        best = entry["best"]
        fixed = [f"{'':14s} not searched, {line}" for line in fixed_text(entry.get("fixed", {}).items())]
        if best is None:
            lines += [f"{name:14s} {entry['note']}", *fixed]
            continue
        held = best["validation"]
        feasible = best.get("validation_feasible")
        settings = ", ".join(
            f"{k} = {v[0] if isinstance(v, list) else v:.4g}" for k, v in best["params"].items()
        )

        def number(value, scale=1.0, width=10, digits=4):
            return f"{'-' if value is None else f'{scale * value:.{digits}g}':>{width}s}"

        train = best["train"]
        lines.append(
            f"{name:14s} {number(train['rms_error_after_2s'], 1e3)} "
            f"{number(train['rms_torque'], width=9)} {number(train['torque_chatter'], width=8)}"
            f"   {number(held.get('rms_error_after_2s'), 1e3)} {number(held.get('rms_torque'), width=9)} "
            f"{'-' if feasible is None else 'yes' if feasible else 'NO':>8s}  {settings}"
        )
        if feasible is False:
            why = infeasible_text(summary["constraints"], held, best["validation_constraints"])
            lines.append(f"{'':14s} infeasible on validation: {why}")
        for b in best["at_bound"]:
            lines.append(
                f"{'':14s} at the {b['side']} bound of {b['param']} ({b['bound']:.4g})"
                + (f": {b['physical']}" if b["physical"] else "")
            )
        lines += fixed
    return "\n".join(lines)


def cmd_tune(args) -> int:
    """Tune every controller by one optimiser at one budget; validate on held-out samples."""
    import math

    from .config import parse_override
    from .tune import TuneSpec, run_tune

    spec = TuneSpec(
        args.target,
        [c.strip() for c in args.controllers.split(",") if c.strip()],
        args.budget,
        args.train_samples,
        args.validation,
        math.inf if args.max_rms_torque is None else args.max_rms_torque,
        1.0 if args.max_saturated is None else args.max_saturated,
        args.seed,
        dict(parse_override(item) for item in args.set or ()),
    )
    progress, started = _simulations_bar(
        args.quiet,
        lambda done, total: (
            f"tune {args.target}: {', '.join(spec.controllers)}, {spec.budget} simulations each "
            f"({spec.trials} settings x {spec.train_samples} samples); {done} of {total} already done"
        ),
    )

    out = Path(args.out)
    summary = _resumable(
        lambda: run_tune(spec, out, args.workers, args.scheduler, args.overwrite, progress),
        f"tuning interrupted; the settings tried so far are in {out}/trials",
    )
    if summary is None:
        return 130
    if started:
        print(file=sys.stderr)
    if not args.quiet:
        print(format_tuning(summary))
        print(
            f"summary in {out}/summary.json, settings in {out}/trials (pandas.read_parquet), Pareto fronts "
            f"in {out}/pareto.png",
            file=sys.stderr,
        )
    never = [
        name
        for name, entry in summary["controllers"].items()
        if entry["simulations"] and entry.get("runs_without_result") == entry["simulations"]
    ]
    if never:  # as a sweep whose rows ended without a result: the command did not do its work
        first = summary["controllers"][never[0]].get("note", "").partition("(first: ")[2].removesuffix(")")
        print(
            one_line(
                f"nnrobust: {', '.join(never)}: every run ended without a result (refused, raised or "
                f"crashed{'; first: ' + first if first else ''}): see {out}/summary.json"
            ),
            file=sys.stderr,
        )
        return 1
    return 0


def cmd_bench(args) -> int:
    """Run the benchmark scripts of benchmarks/ and write their JSON into a folder."""
    import subprocess

    root = Path(__file__).resolve().parent.parent / "benchmarks"
    if not root.is_dir():
        raise NNRobustError(f"{root} not found: 'bench' runs from a source checkout of nnrobust")
    available = sorted(p.stem for p in root.glob("*.py") if not p.stem.startswith("_"))  # _: helpers
    names = args.names or available
    unknown = [n for n in names if n not in available]
    if unknown:
        raise NNRobustError(f"unknown benchmarks {unknown}; available: {', '.join(available)}")
    out = _bench_folder(Path(args.out), names)
    code = 0
    for name in names:
        print(f"== {name}", flush=True)
        # its own process group: a stop signal here ends the script and every worker it started
        command = [sys.executable, str(root / f"{name}.py"), "--json", str(out / f"{name}.json")]
        child = subprocess.Popen(command, start_new_session=True)
        try:
            code = code or child.wait()
        except KeyboardInterrupt:
            _stop_group(child)
            raise
    return 1 if code else 0


def _bench_folder(out: Path, names: list[str]) -> Path:
    """The --out folder of ``bench``, checked (and made) before any benchmark runs: each one
    writes ``<name>.json`` into it, after minutes of work that a file in its place would lose.
    """
    if out.exists() and not out.is_dir():
        raise NNRobustError(
            f"--out {out}: exists and is not a folder; bench writes one <name>.json per benchmark "
            "into a folder (e.g. --out out/bench)"
        )
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise NNRobustError(f"--out {out}: cannot make the folder ({err.strerror or err})") from err
    if not os.access(out, os.W_OK | os.X_OK):
        raise NNRobustError(f"--out {out}: the folder is not writable")
    taken = [f"{name}.json" for name in names if (out / f"{name}.json").is_dir()]
    if taken:
        raise NNRobustError(f"--out {out}: {', '.join(taken)} is a folder; the benchmark writes a file there")
    return out


def _stop_group(child, grace: float = 10.0) -> None:
    """SIGTERM to a child's process group (the child and every process it started), SIGKILL to
    what is left of it after ``grace`` seconds: no orphan workers.
    """
    import signal
    import subprocess

    try:
        os.killpg(child.pid, signal.SIGTERM)
    except ProcessLookupError:
        return
    try:
        child.wait(grace)
    except subprocess.TimeoutExpired:
        pass
    try:
        os.killpg(child.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    child.wait()


def cmd_presets(args) -> int:
    """List the shipped presets."""
    from .presets import load_preset, preset_names

    for name in preset_names():
        print(f"{name:28s} {load_preset(name).description}")
    return 0


def cmd_robots(args) -> int:
    """List the arms known to work (or, with --all, every example-robot-data robot): joint
    count, default chain and task frame.
    """
    from .model import ARMS, load_robot
    from .model.example_robots import example_robot, is_example_robot, robot_names

    names = robot_names() if args.all else list(ARMS)
    print(f"{'name':26s} {'n':>3s}  {'default chain':44s} {'task frame':28s} note")
    failed = 0
    for name in names:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the note column says what a warning would
            try:
                robot = load_robot(name)
            except NNRobustError as err:
                failed += 1
                print(f"{name:26s} {'-':>3s}  {'refused: ' + str(err)}")
                continue
        joints = robot.joint_names
        chain = joints[0] if len(joints) == 1 else f"{joints[0]} .. {joints[-1]}"
        note = ARMS.get(name, {}).get("description", "")
        if is_example_robot(name) and example_robot(name).floating_base:
            note = "floating base fixed to the world"
        print(f"{name:26s} {robot.nq:3d}  {chain:44s} {robot.task_frame:28s} {note}".rstrip())
    if args.all:
        print(f"\n{len(names) - failed} of {len(names)} load.")
    else:
        print(
            "\nAlso: planar<N> for N up to 300 (generated chain), any example-robot-data name "
            "(nnrobust robots --all), a URDF file."
        )
    return 1 if failed and not args.all else 0


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
    from .plots import comparison_warnings, plot_comparison
    from .properties import run_properties
    from .run_deltas import delta_table, verdict_changes

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


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``nnrobust`` command."""
    from . import __version__
    from .config import shipped_laws
    from .controllers.registry import LAWS, law_names
    from .sweep.spec import shipped_sweeps

    parser = argparse.ArgumentParser(
        prog="nnrobust",
        description="Robust neural-network control of redundant manipulators: simulate the "
        "paper's experiments or your own, and compare controllers.",
        epilog=EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"nnrobust {__version__}")
    sub = parser.add_subparsers(dest="command")

    run = sub.add_parser(
        "run",
        help="run a preset or an experiment file (TOML)",
        description="Simulate a preset or a TOML experiment file and write a run "
        "folder: config.toml, result.npz, metrics.json, plots/, animation.html.",
    )
    run.add_argument("target", help="preset name (see 'nnrobust presets') or path to a .toml file")
    run.add_argument("--out", help="run folder (default out/NAME-CONTROLLER)")
    run.add_argument(
        "--controller",
        type=_controller_choice,
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
    run.add_argument("--duration", type=float, help="override the simulated time [s]")
    run.add_argument(
        "--backend",
        choices=("auto", "compiled", "hybrid", "python"),
        help="simulation loop: compiled (C++), hybrid (the compiled plant calling a Python "
        "controller once per period), python (the reference) or auto (compiled when the "
        "experiment has a compiled twin, hybrid for a custom controller; the default)",
    )
    run.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="set one key of the experiment (dotted, TOML value), e.g. --set nn.sigma=0.5 "
        "--set 'controller.Kp=[100.0]'; repeatable, checked like an experiment file",
    )
    run.add_argument("--overwrite", action="store_true", help="replace an existing run folder")
    run.add_argument("--no-plots", action="store_true", help="skip the figures")
    run.add_argument(
        "--no-animation",
        action="store_true",
        help="skip animation.html (the 3-D replay; a few MB for meshed robots)",
    )
    run.add_argument(
        "--quiet", action="store_true", help="print nothing but errors (no progress bar, no summary table)"
    )
    run.add_argument(
        "--view",
        action="store_true",
        help="watch the arm live in meshcat while it runs, then replay the run until Ctrl-C",
    )
    _viewer_options(run)
    run.set_defaults(func=cmd_run)

    plot = sub.add_parser(
        "plot",
        help="draw the figures and animation of run folders again",
        description="Draw plots/ and animation.html of run folders from their "
        "result.npz, as 'nnrobust run' draws them: after a drawing that was "
        "interrupted or skipped (--no-plots, --no-animation), or to redraw after an "
        "upgrade. The arrays and metrics are not touched.",
    )
    plot.add_argument("runs", nargs="+", help="run folders written by 'nnrobust run'")
    plot.add_argument("--no-plots", action="store_true", help="leave plots/ as it is")
    plot.add_argument("--no-animation", action="store_true", help="leave animation.html as it is")
    plot.set_defaults(func=cmd_plot)

    presets = sub.add_parser("presets", help="list the shipped presets")
    presets.set_defaults(func=cmd_presets)

    robots = sub.add_parser(
        "robots",
        help="list the arms known to work (n, chain, task frame)",
        description="Load every arm nnrobust knows (the paper's arm, a generated "
        "planar chain and example-robot-data arms) and print its joint count, "
        "default chain and task frame. With --all: every robot example-robot-data "
        "ships, loaded or refused with the reason (docs/robots.md).",
    )
    robots.add_argument(
        "--all", action="store_true", help="every example-robot-data robot, not only the arms known to work"
    )
    robots.set_defaults(func=cmd_robots)

    compare = sub.add_parser(
        "compare",
        help="compare run folders: metrics table and plots",
        description="Print the metrics of several run folders side by side "
        "(labelled by folder name, or by as much of the path as tells them "
        "apart), each metric's change from the first run, and the verdicts "
        "(status, warnings, --require properties) that differ; with --out, draw "
        "their paths, errors and torques in one figure. The same experiment run "
        "with --set plant.engine=mujoco gives the sim-to-sim gap (docs/engines.md).",
    )
    compare.add_argument("runs", nargs="+", help="run folders written by 'nnrobust run'")
    compare.add_argument("--out", help="folder for the comparison figure (PNG and SVG)")
    compare.add_argument(
        "--require",
        action="append",
        metavar="EXPR",
        help="a property each run is checked against, METRIC OP VALUE (e.g. "
        "'rms_error_after_2s<=0.05'); repeatable; shown where runs disagree",
    )
    compare.set_defaults(func=cmd_compare)

    view = sub.add_parser(
        "view",
        help="replay a run folder in the meshcat viewer (browser)",
        description="Serve the run's 3-D replay (arm from the URDF, desired path, "
        "end-effector trace) with meshcat and print the address to open. The "
        "run folder's animation.html is the same replay as a file.",
    )
    view.add_argument("run", help="run folder written by 'nnrobust run'")
    view.add_argument("--open", action="store_true", help="open the page in the default browser")
    view.add_argument("--seconds", type=float, help="stop after this many seconds (default: Ctrl-C)")
    _viewer_options(view)
    view.set_defaults(func=cmd_view)

    many = _many_run_options()
    sweep = sub.add_parser(
        "sweep",
        parents=[many],
        help="run a robustness sweep (Monte Carlo over the uncertainty set)",
        description="Run one experiment over many samples of model error, friction, "
        "disturbance, gains or seeds with several controllers, on dask.distributed: "
        "a local cluster on 127.0.0.1 by default, or an existing scheduler. Re-running "
        "the same command into the same folder computes only the missing rows "
        "(docs/robustness.md).",
    )
    sweep.add_argument(
        "sweep", help=f"sweep file (TOML), or a shipped sweep file by name: {', '.join(shipped_sweeps())}"
    )
    sweep.add_argument("--out", required=True, help="sweep folder (results/, sweep.toml, summary.json)")
    sweep.add_argument(
        "--overwrite", action="store_true", help="replace the results of a different sweep in --out"
    )
    sweep.add_argument(
        "--keep-worst",
        type=_keep_count,
        default=0,
        metavar="K",
        help="write full run folders (with animation) of the K worst samples of each "
        "controller into DIR/worst/",
    )
    sweep.add_argument(
        "--tuned",
        metavar="DIR",
        help="run each controller at its best setting in this tuning (nnrobust tune's DIR or its "
        "summary.json, a study's cases/CASE/kept.json, or REPORT.json#CASE of a study's report), as "
        "NAME-tuned; every law takes them: shipped, registered, custom entries",
    )
    sweep.add_argument(
        "--require",
        action="append",
        metavar="EXPR",
        default=[],
        help="a property every run should have, METRIC OP VALUE (repeatable), e.g. "
        "'rms_error_after_2s<=0.05', 'runaway==false'; with --epsilon and --beta, "
        "summary.json gets a certificate per controller (docs/robustness.md)",
    )
    sweep.add_argument("--epsilon", type=float, help="claim P(a property fails) <= EPSILON ...")
    sweep.add_argument("--beta", type=float, help="... with confidence 1 - BETA (one-sided Clopper-Pearson)")
    sweep.add_argument(
        "--failures",
        type=int,
        default=0,
        metavar="K",
        help="plan the sample size for up to K failures (default 0)",
    )
    sweep.add_argument(
        "--allow-small",
        action="store_true",
        help="run a sweep too small to prove the claim, and report its bound anyway",
    )
    sweep.add_argument(
        "--stop-early",
        action="store_true",
        help="sequential stopping: stop a controller's rows (per grid cell) once its claim is "
        "refuted whatever the rest give; a claim is proved only by all its rows",
    )
    sweep.set_defaults(func=cmd_sweep)

    falsify = sub.add_parser(
        "falsify",
        parents=[many],
        help="search the worst plant of an uncertainty box",
        description="Search the sweep file's [vary] box (uniform and loguniform ranges) "
        "for the plant on which each controller most violates the --require properties: "
        "a Sobol start, then CMA-ES with restarts, at one budget of simulations per "
        "controller on dask.distributed, with uniform random search at the same budget "
        "as the baseline. Re-running the same command into the same folder resumes "
        "(docs/falsification.md).",
    )
    falsify.add_argument(
        "sweep", help="sweep file (TOML) or shipped sweep file by name whose [vary] ranges are the box"
    )
    falsify.add_argument(
        "--controllers",
        required=True,
        help="comma-separated controller kinds, custom "
        "classes as file.py:Class, or the sweep file's custom entries",
    )
    falsify.add_argument(
        "--require",
        action="append",
        required=True,
        metavar="EXPR",
        help="a property to falsify, METRIC OP VALUE (repeatable), e.g. 'rms_error_after_2s<=0.05'",
    )
    falsify.add_argument(
        "--budget",
        type=int,
        required=True,
        help="simulations per controller (and as many for its random baseline)",
    )
    falsify.add_argument("--seed", type=int, default=0, help="seed of the search (default 0)")
    falsify.add_argument(
        "--tuned",
        metavar="DIR",
        help="run each listed law at its best setting in this tuning (nnrobust tune's DIR or its "
        "summary.json, a study's cases/CASE/kept.json, or one case of a study's report as "
        "REPORT.json#CASE, e.g. 'docs/data/tuned_panda.json#panda-ellipse-noisy'), as NAME-tuned; "
        "every law takes them: shipped, registered, file.py:Class, a sweep file's entries",
    )
    falsify.add_argument(
        "--out",
        required=True,
        help="folder (falsify.toml, history/, summary.json, falsification.csv, convergence.png)",
    )
    falsify.add_argument("--overwrite", action="store_true", help="replace a different search in --out")
    falsify.add_argument(
        "--keep-worst",
        type=_keep_count,
        nargs="?",
        const=1,
        default=0,
        metavar="K",
        help="rerun each controller's K worst distinct plants (1 without K) into "
        "OUT/worst/CONTROLLER, CONTROLLER-2, ... as full run folders (arrays, metrics, plots, "
        "animation)",
    )
    falsify.add_argument(
        "--margin",
        action="store_true",
        help="also find each controller's robustness margin: the largest scale s of the box "
        "about its centre with no violation found, by doubling then bisection on s, each "
        "scale searched at a quarter of the budget (docs/falsification.md)",
    )
    falsify.add_argument(
        "--epsilon",
        type=float,
        default=0.05,
        help="the random baseline's runs, independent draws of the box, certify P(a property fails) "
        "<= EPSILON (default 0.05) ...",
    )
    falsify.add_argument(
        "--beta",
        type=float,
        default=0.05,
        help="... with confidence 1 - BETA (default 0.05; one-sided Clopper-Pearson)",
    )
    falsify.set_defaults(func=cmd_falsify)

    export = sub.add_parser(
        "export",
        help="export a controller as a C library (no Python at run time)",
        description="Write the compiled twin of an experiment's controller (a preset, an experiment "
        "file or a run folder's config.toml) as a shared library with a C header and a CMake "
        "package: nnrobust_law_create(), nnrobust_law_step(law, t, q, v, tau), "
        "nnrobust_law_destroy() (docs/export.md).",
    )
    export.add_argument("target", help="preset name, experiment file (TOML) or run folder")
    export.add_argument("--out", required=True, help="folder to write (include/, lib/, example/, ...)")
    export.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="set one key of the experiment (dotted, TOML value); repeatable",
    )
    export.add_argument(
        "--controller",
        help="the controller to export: a kind, e.g. slotine-li, or a law in C++ as FILE.cpp:CLASS "
        "(a FILE.py:CLASS has no twin)",
    )
    export.add_argument(
        "--tuned",
        metavar="DIR|FILE[#CASE]",
        help="export the controller at its best setting in this tuning (nnrobust tune's folder or "
        "summary.json, or a study's kept settings of a case), as sweep and falsify take it",
    )
    export.add_argument("--overwrite", action="store_true", help="replace an earlier export in --out")
    export.add_argument(
        "--no-build", action="store_true", help="write the sources without compiling libnnrobust_law"
    )
    export.add_argument("--quiet", action="store_true", help="print nothing but errors")
    export.set_defaults(func=cmd_export)

    serve = sub.add_parser(
        "serve",
        help="a virtual robot: the experiment's plant in real time over UDP",
        description="Run the experiment's plant (a preset, an experiment file or a run folder's "
        "config.toml) paced by the wall clock at its control period, serving the measured state "
        "and taking torque commands over UDP from a controller in another process, e.g. an "
        "exported law's bin/drive (docs/serve.md). A late, missing or malformed command is not "
        "applied (the last one is held, the reason logged); after --watchdog periods without one "
        "the robot stops. Writes a run folder plus timing.json (misses, latency, the simulated run "
        "beside the served one).",
    )
    serve.add_argument("target", help="preset name, experiment file (TOML) or run folder")
    serve.add_argument("--out", required=True, help="run folder to write (with timing.json)")
    serve.add_argument(
        "--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)"
    )
    serve.add_argument("--port", type=int, default=0, help="UDP port (default: a free one, printed)")
    serve.add_argument(
        "--watchdog",
        type=int,
        default=20,
        help="periods without a command before the robot stops (default 20)",
    )
    serve.add_argument(
        "--wait", type=float, default=60.0, help="seconds to wait for the controller (default 60)"
    )
    serve.add_argument(
        "--rt", action="store_true", help="run the robot's thread under SCHED_FIFO where allowed"
    )
    serve.add_argument(
        "--lockstep",
        action="store_true",
        help="no wall clock: each period waits for its command (--wait seconds at most); checks a "
        "controller's logic apart from its timing",
    )
    serve.add_argument(
        "--set", action="append", metavar="KEY=VALUE", help="set one key of the experiment; repeatable"
    )
    serve.add_argument(
        "--no-compare", action="store_true", help="skip the simulated run timing.json compares with"
    )
    serve.add_argument("--no-plots", action="store_true", help="skip the figures and the animation")
    serve.add_argument("--overwrite", action="store_true", help="replace an existing run folder")
    serve.add_argument("--quiet", action="store_true", help="print nothing but errors")
    serve.set_defaults(func=cmd_serve)

    study = sub.add_parser(
        "study",
        parents=[many],
        help="one study file -> one report: tune, validate, certify, falsify",
        description="Run a study file's cases and controllers through every stage: tune (each "
        "optimiser seed), validate every seed's setting on fresh draws and keep the best, certify "
        "the kept settings on draws the selection never saw (with paired comparisons), falsify "
        "them, and where the study asks, export and time them out of Python (realtime) and run the "
        "certification draws on MuJoCo (second_engine); each "
        "stage is the sweep, tune, falsify or export command's own engine and folder, and stages "
        "that do not need each other's results (the seeds' tunings; certify, falsify and MuJoCo) "
        "run side by side. Writes DIR/report.html, report.json, tables/ and figures/. Re-running "
        "the same command resumes (docs/study.md).",
    )
    study.add_argument("study", help="study file (TOML)")
    study.add_argument("--out", required=True, help="study folder (cases/, report.json, report.html)")
    study.add_argument(
        "--overwrite", action="store_true", help="replace what a different study wrote in --out"
    )
    study.set_defaults(func=cmd_study)

    tune = sub.add_parser(
        "tune",
        parents=[many],
        help="tune controllers at an equal budget of simulations",
        description="Tune each controller with the same optimiser (Optuna's TPE, "
        "minimising the RMS error after 2 s under the constraints; torque and chatter are "
        "recorded for the Pareto fronts) over a search space derived from the arm, at the "
        "same budget of simulations, on the same samples, under the same constraints; "
        "then check each best setting on held-out samples. Re-running the same command "
        "into the same folder resumes (docs/tuning.md).",
    )
    tune.add_argument(
        "target",
        help="a preset, an experiment file, or a sweep file whose [vary] "
        "distributions are the uncertainty the settings are tuned over",
    )
    tune.add_argument(
        "--controllers",
        required=True,
        help="comma-separated controller kinds, e.g. "
        "nn,no-u0,pd,sliding-mode; a custom class as file.py:Class (it declares its "
        "search_space); or the names of a sweep file's custom entries",
    )
    tune.add_argument("--budget", type=int, required=True, help="simulations per controller (training)")
    tune.add_argument(
        "--out", required=True, help="tuning folder (tune.toml, trials/, summary.json, pareto.png)"
    )
    tune.add_argument("--max-rms-torque", type=float, metavar="X", help="constraint: RMS torque <= X [N m]")
    tune.add_argument(
        "--max-saturated",
        type=float,
        metavar="F",
        help="constraint: at most this fraction of steps saturated (0 to 1)",
    )
    tune.add_argument(
        "--train-samples",
        type=int,
        default=1,
        metavar="S",
        help="samples (noise seeds, uncertainty draws) each setting runs on (default 1)",
    )
    tune.add_argument(
        "--validation",
        type=int,
        default=4,
        metavar="K",
        help="held-out samples each best setting is checked on (default 4)",
    )
    tune.add_argument("--seed", type=int, default=0, help="seed of the optimiser and the samples")
    tune.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="set one key of the target's experiment for every run (dotted, TOML value; as a sweep "
        "file's [set]); repeatable",
    )
    tune.add_argument("--overwrite", action="store_true", help="replace a different tuning in --out")
    tune.set_defaults(func=cmd_tune)

    bench = sub.add_parser(
        "bench",
        help="run the benchmarks (source checkout)",
        description="Run the scripts in benchmarks/ (all, or those named) and "
        "write each one's JSON into --out; docs/benchmarks.md explains them.",
    )
    bench.add_argument("names", nargs="*", help="benchmark names, e.g. step_scaling (default: all)")
    bench.add_argument("--out", default="out/bench", help="folder for the JSON files")
    bench.set_defaults(func=cmd_bench)
    return parser


def _many_run_options() -> argparse.ArgumentParser:
    """The parent parser of the commands that run many simulations on dask.distributed (sweep,
    falsify, study, tune): the options they share, declared once (shown under their own heading).
    """
    parent = argparse.ArgumentParser(add_help=False)
    options = parent.add_argument_group("cluster and console")
    options.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    options.add_argument("--scheduler", help="address of an existing dask scheduler, e.g. tcp://host:8786")
    options.add_argument("--quiet", action="store_true", help="print nothing but errors")
    return parent


def _viewer_options(parser) -> None:
    parser.add_argument(
        "--host",
        default="127.0.0.1",
        help="address the viewer listens on (default 127.0.0.1: this machine only)",
    )
    parser.add_argument("--port", type=int, help="viewer web port (default: first free from 7000)")


EXIT_CODES = """exit codes:
  0    success
  1    a run diverged or was interrupted (its partial result is written), or its
       figures could not be written
  2    bad input: one line on stderr names the file, key or value
  130  interrupted (Ctrl-C, SIGTERM, SIGHUP) outside a simulation"""


_WARNED: dict[str, int] = {}
"""Each warning line printed in this command, with how many times it was raised."""


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one line, ``warning: ...`` (no file name, line number or source line), printed
    once however often it is raised (every draw of a sweep builds the same experiment again); the
    repeats are counted and said when the command ends (:func:`_repeated_warnings`).
    """
    if issubclass(category, DeprecationWarning):
        return
    text = one_line(str(message))
    _WARNED[text] = _WARNED.get(text, 0) + 1
    if _WARNED[text] == 1:
        print(f"warning: {text}", file=sys.stderr if file is None else file)


def _repeated_warnings() -> None:
    """One line per warning raised more than once: its count, and the start of its text."""
    for text, count in _WARNED.items():
        if count > 1:
            print(f"warning (raised {count} times in all): {one_line(text, 120)}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code (0 success, 1 failed run, 2 bad input, 130 interrupted)."""
    try:
        with signals_as_interrupt():  # from the start: Ctrl-C while importing is a clean exit too
            parser = build_parser()
            args = parser.parse_args(argv)
            if getattr(args, "quiet", False):  # "print nothing but errors": no warning lines either
                warnings.simplefilter("ignore")
            if args.command is None:  # bare `nnrobust`: the help
                parser.print_help()
                return 0
            return args.func(args)
    except BrokenPipeError:  # `nnrobust presets | head -1`: the reader left; say nothing
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except NNRobustError as err:
        _error(f"error: {err}")  # one bounded line (NNRobustError.__str__)
        return 2
    except OSError as err:  # a path too long, a full or read-only disk, met where no check named it
        where = f"{err.filename}: " if err.filename else ""
        _error(f"error: {one_line(where + (err.strerror or str(err)))}")
        return 1 if err.errno in (errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EROFS) else 2
    except ValueError as err:
        if "null byte" not in str(err):  # a programming error: its traceback is wanted
            raise
        _error("error: a path or name contains a NUL character (\\x00)")
        return 2
    except ExtrasInterrupted as err:
        print(f"nnrobust: {err}", file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        print("nnrobust: interrupted", file=sys.stderr)
        return 130


def run() -> None:
    """The console entry point: exit with main's code. Ctrl-C, SIGTERM and SIGHUP interrupt the
    command's work; one that arrives after the work is done is ignored (signals.py).
    """
    install_stop_handlers()
    warnings.showwarning = _warning_line
    warnings.simplefilter("always", UserWarning)  # every one reaches _warning_line, which counts it
    code = main()
    _repeated_warnings()
    ignore_stop_signals()  # also through the interpreter's teardown, which resets Python handlers
    sys.exit(code)


if __name__ == "__main__":
    run()
