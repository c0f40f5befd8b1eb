"""The command table: every command of ``nnrobust``, in the order ``nnrobust --help`` lists them,
and the parser built from it. A new command is one :class:`~nnrobust.cli.common.Command` in its
group's module and one line here.
"""

from __future__ import annotations

import argparse

from . import catalog, identify, learn, robot, runs, studies
from .common import Command, many_run_options

COMMANDS: tuple[Command, ...] = (
    runs.RUN,
    runs.PLOT,
    catalog.PRESETS,
    catalog.ROBOTS,
    runs.COMPARE,
    runs.VIEW,
    studies.SWEEP,
    studies.FALSIFY,
    robot.EXPORT,
    robot.SERVE,
    robot.DRIVE,
    studies.STUDY,
    studies.TUNE,
    identify.IDENTIFY,
    identify.IDENTIFY_DESIGN,
    learn.LEARN,
    catalog.BENCH,
)

EXIT_CODES = """exit codes:
  0    success
  1    a run diverged or was interrupted (its partial result is written), or its
       figures could not be written
  2    bad input: one line on stderr names the file, key or value
  130  interrupted (Ctrl-C, SIGTERM, SIGHUP) outside a simulation"""


SUBCOMMANDS = {("identify", "design"): "identify-design"}
"""Two words that name one command: ``nnrobust identify design`` is ``identify-design`` (identify
itself takes its logs as positional arguments, so the design is a command of its own)."""


def routed(argv: list[str]) -> list[str]:
    """``argv`` with a two-word command (:data:`SUBCOMMANDS`) as its one-word name."""
    if len(argv) >= 2 and (argv[0], argv[1]) in SUBCOMMANDS:
        return [SUBCOMMANDS[argv[0], argv[1]], *argv[2:]]
    return argv


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``nnrobust`` command, one subcommand per entry of COMMANDS."""
    from ..core.package_version import package_version

    parser = argparse.ArgumentParser(
        prog="nnrobust",
        description="Robust neural-network control of redundant manipulators: simulate the "
        "paper's experiments or your own, and compare controllers.",
        epilog=EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"nnrobust {package_version()}")
    sub = parser.add_subparsers(dest="command")
    many = many_run_options()
    for command in COMMANDS:
        parents = [many] if command.many_runs else []
        spoken = {one: " ".join(two) for two, one in SUBCOMMANDS.items()}.get(command.name)
        child = sub.add_parser(
            command.name,
            help=command.help,
            description=command.description,
            parents=parents,
            prog=f"nnrobust {spoken or command.name}",
        )
        command.arguments(child)
        child.set_defaults(func=command.run)
    return parser
