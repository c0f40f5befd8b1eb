"""The law out of Python and the plant in real time: export, serve."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from ..core.exceptions import NNRobustError
from .common import (
    Command,
    controller_change,
    load_target,
)


def _served_target(args, verb: str):
    """The experiment of ``export`` and ``serve``: a preset, an experiment file or a run folder's
    config.toml, with --controller, the --tuned setting and --set (which wins over --tuned), each
    --set that changes nothing warned about as ``run`` does.
    """
    from ..config import inert_reason, parse_override

    target = Path(args.target)
    if target.is_dir():
        if not (target / "config.toml").is_file():
            raise NNRobustError(f"{target}: not a run folder (config.toml is missing)")
        target = target / "config.toml"
    overrides = dict(parse_override(item) for item in args.set or ())
    changes = {}
    certified = None
    if getattr(args, "tuned", None) and getattr(args, "controller", None):
        from ..studies.base.tuned import kept_entry

        certified = kept_entry(args.tuned, args.controller)  # a study's law by the name it gave it
    if certified is not None:  # exactly what its certification ran: kind or class, params, set
        changes = _entry_changes(certified)
    elif getattr(args, "controller", None):
        changes = {f"controller.{k}": v for k, v in controller_change(args.controller).items()}
    config = load_target(str(target), {**changes, **overrides})
    if getattr(args, "tuned", None) and certified is None:  # the tuning's best setting, under --set
        from ..studies.base.tuned import tuned_settings, tuned_target

        kind = config.controller.kind
        settings = tuned_settings(args.tuned, [kind]).get(kind, {})
        tuned_on = tuned_target(args.tuned)
        if tuned_on and tuned_on not in (config.name, args.target, Path(args.target).stem):
            warnings.warn(
                f"--tuned: that tuning was of {tuned_on}, not {config.name}: its setting is {verb} as "
                "it is, on another experiment",
                stacklevel=2,
            )
        config = load_target(str(target), {**changes, **settings, **overrides})
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
    from ..outputs.export import export_law

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
    from ..outputs.serve import serve

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


def export_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust export``."""
    parser.add_argument("target", help="preset name, experiment file (TOML) or run folder")
    parser.add_argument("--out", required=True, help="folder to write (include/, lib/, example/, ...)")
    parser.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="set one key of the experiment (dotted, TOML value); repeatable",
    )
    parser.add_argument(
        "--controller",
        help="the controller to export: a kind, e.g. slotine-li, or a law in C++ as FILE.cpp:CLASS "
        "(a FILE.py:CLASS has no twin)",
    )
    parser.add_argument(
        "--tuned",
        metavar="DIR|FILE[#CASE]",
        help="export the controller at its best setting in this tuning (nnrobust tune's folder or "
        "summary.json, or a study's kept settings of a case), as sweep and falsify take it",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace an earlier export in --out")
    parser.add_argument(
        "--no-build", action="store_true", help="write the sources without compiling libnnrobust_law"
    )
    parser.add_argument("--quiet", action="store_true", help="print nothing but errors")


EXPORT = Command(
    "export",
    help="export a controller as a C library (no Python at run time)",
    description="Write the compiled twin of an experiment's controller (a preset, an experiment "
    "file or a run folder's config.toml) as a shared library with a C header and a CMake "
    "package: nnrobust_law_create(), nnrobust_law_step(law, t, q, v, tau), "
    "nnrobust_law_destroy() (docs/export.md).",
    arguments=export_arguments,
    run=cmd_export,
)


def cmd_drive(args) -> int:
    """Drive a served robot with an experiment's law, in Python."""
    from ..outputs.serve.client import drive
    from ..run.experiment import build

    config = _served_target(args, "driven")
    if not 0 < args.wait <= 86400:
        raise NNRobustError(f"--wait must be in (0, 86400] s, got {args.wait:g}")
    done = drive(build(config), args.port, args.host, args.wait)
    if not args.quiet:
        step = f"; the law's step {done['step_us']:.1f} us (median)" if done["step_us"] is not None else ""
        print(
            f"drove {done['periods']} periods of the robot at {args.host}:{args.port} with {config.name}'s "
            f"{config.controller.kind} law{step}",
            file=sys.stderr,
        )
    return 0


def drive_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust drive``."""
    parser.add_argument("target", help="preset name, experiment file (TOML) or run folder whose law drives")
    parser.add_argument("--port", type=int, required=True, help="the served robot's UDP port")
    parser.add_argument("--host", default="127.0.0.1", help="the served robot's address (default 127.0.0.1)")
    parser.add_argument(
        "--controller", help="the law: a built-in kind, a registered law or a custom class (FILE.py:Class)"
    )
    parser.add_argument(
        "--tuned",
        help="a tuning's folder or summary.json, or a study's REPORT.json#CASE: its setting of the law",
    )
    parser.add_argument(
        "--wait", type=float, default=60.0, help="seconds to wait for any datagram of the robot (default 60)"
    )
    parser.add_argument(
        "--set", action="append", metavar="KEY=VALUE", help="set one key of the experiment; repeatable"
    )
    parser.add_argument("--quiet", action="store_true", help="print nothing but errors")


DRIVE = Command(
    "drive",
    help="a controller in Python for a served robot: the experiment's law over UDP",
    description="Answer a virtual robot's (nnrobust serve) measured states with the torques of "
    "the experiment's law computed here in Python, period by period, until the robot's run "
    "ends: any law, also one without a C++ twin (an ONNX policy, a custom Python class), drives "
    "a served robot as an exported law's bin/drive does (docs/serve.md).",
    arguments=drive_arguments,
    run=cmd_drive,
)


def serve_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust serve``."""
    parser.add_argument("target", help="preset name, experiment file (TOML) or run folder")
    parser.add_argument("--out", required=True, help="run folder to write (with timing.json)")
    parser.add_argument(
        "--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)"
    )
    parser.add_argument("--port", type=int, default=0, help="UDP port (default: a free one, printed)")
    parser.add_argument(
        "--watchdog",
        type=int,
        default=20,
        help="periods without a command before the robot stops (default 20)",
    )
    parser.add_argument(
        "--wait", type=float, default=60.0, help="seconds to wait for the controller (default 60)"
    )
    parser.add_argument(
        "--rt", action="store_true", help="run the robot's thread under SCHED_FIFO where allowed"
    )
    parser.add_argument(
        "--lockstep",
        action="store_true",
        help="no wall clock: each period waits for its command (--wait seconds at most); checks a "
        "controller's logic apart from its timing",
    )
    parser.add_argument(
        "--set", action="append", metavar="KEY=VALUE", help="set one key of the experiment; repeatable"
    )
    parser.add_argument(
        "--no-compare", action="store_true", help="skip the simulated run timing.json compares with"
    )
    parser.add_argument("--no-plots", action="store_true", help="skip the figures and the animation")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing run folder")
    parser.add_argument("--quiet", action="store_true", help="print nothing but errors")


SERVE = Command(
    "serve",
    help="a virtual robot: the experiment's plant in real time over UDP",
    description="Run the experiment's plant (a preset, an experiment file or a run folder's "
    "config.toml) paced by the wall clock at its control period, serving the measured state "
    "and taking torque commands over UDP from a controller in another process, e.g. an "
    "exported law's bin/drive (docs/serve.md). A late, missing or malformed command is not "
    "applied (the last one is held, the reason logged); after --watchdog periods without one "
    "the robot stops. Writes a run folder plus timing.json (misses, latency, the simulated run "
    "beside the served one).",
    arguments=serve_arguments,
    run=cmd_serve,
)
