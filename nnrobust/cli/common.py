"""What the commands share: the metrics table, the targets and choices of the flags, the progress
line, the one-line errors and warnings, and the command table's entry.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..core.exceptions import NNRobustError, one_line


@dataclass(frozen=True)
class Command:
    """One entry of the command table (:data:`nnrobust.cli.commands.COMMANDS`): its name, its one
    line in ``nnrobust --help``, its description in ``nnrobust NAME --help``, the function that
    adds its arguments, the function that runs it (returns the exit code), and whether it takes
    the options of the commands that run many simulations (:func:`many_run_options`).
    """

    name: str
    help: str
    arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]
    description: str | None = None
    many_runs: bool = False


def say_unless_quiet(quiet: bool):
    """The function a command's progress lines go through: to stderr, or nowhere with --quiet."""
    return (lambda text: None) if quiet else (lambda text: print(text, file=sys.stderr))


def no_arguments(parser: argparse.ArgumentParser) -> None:
    """A command without arguments of its own."""


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


def load_target(target: str, overrides: dict | None = None):
    """A preset or an experiment file, with ``overrides`` (dotted keys) set in its own values
    (:func:`nnrobust.config.load_config`): as if the file had been edited so.
    """
    from ..config import load_config
    from ..config.presets import preset_names, preset_path, presets_hint

    path = Path(target)
    if path.suffix == ".toml" or path.exists():
        return load_config(path, overrides)
    if target in preset_names():
        return load_config(preset_path(target), overrides)
    raise NNRobustError(f"{target!r} is neither a TOML file nor a preset; {presets_hint(target)}")


def controller_choice(text: str) -> str:
    """--controller: a built-in kind, or a custom class (``file.py:Class``, ``package.module:Class``)."""
    from ..config import CLASS_PATTERN, shipped_laws

    if text in shipped_laws() or CLASS_PATTERN.fullmatch(text):
        return text
    raise argparse.ArgumentTypeError(
        f"{text!r} is not one of {', '.join(shipped_laws())} nor a class as "
        "file.py:Class or package.module:Class"
    )


MAX_KEEP_WORST = 100
"""Most run folders --keep-worst writes per controller (each holds a whole run and its animation)."""


def keep_count(text: str) -> int:
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
    from ..config import shipped_laws
    from ..plugins.user_code import class_file

    if choice in shipped_laws():
        return {"kind": choice, "class": None, "params": None}
    path, name = class_file(choice), choice.rpartition(":")[2]
    return {"kind": "custom", "class": f"{path.resolve()}:{name}" if path is not None else choice}


def resumable(work, kept):
    """work()'s result, or None after Ctrl-C with one line saying what was kept (``kept``, or
    what ``kept()`` says then) and how to resume.
    """
    try:
        return work()
    except KeyboardInterrupt:
        said = kept() if callable(kept) else kept
        print(f"\nnnrobust: {said}; run the same command again to resume", file=sys.stderr)
        return None


def viewer_options(parser) -> None:
    """The meshcat viewer's --host and --port (run --view, view)."""
    parser.add_argument(
        "--host",
        default="127.0.0.1",
        help="address the viewer listens on (default 127.0.0.1: this machine only)",
    )
    parser.add_argument("--port", type=int, help="viewer web port (default: first free from 7000)")


def many_run_options() -> argparse.ArgumentParser:
    """The parent parser of the commands that run many simulations on dask.distributed (sweep,
    falsify, study, tune): the options they share, declared once (shown under their own heading).
    """
    parent = argparse.ArgumentParser(add_help=False)
    options = parent.add_argument_group("cluster and console")
    options.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    options.add_argument("--scheduler", help="address of an existing dask scheduler, e.g. tcp://host:8786")
    options.add_argument("--quiet", action="store_true", help="print nothing but errors")
    return parent
