"""The command line, ``nnrobust COMMAND``.

One entry per command in the table of :mod:`nnrobust.cli.commands`, its code in the module of
its group:

- :mod:`~nnrobust.cli.runs`: ``run`` (a preset or experiment file into a run folder), ``plot``
  (draw a run folder's figures again), ``compare`` (run folders side by side), ``view`` (a run's
  3-D replay in meshcat);
- :mod:`~nnrobust.cli.catalog`: ``presets``, ``robots`` (what ships), ``bench`` (the benchmarks);
- :mod:`~nnrobust.cli.studies`: ``sweep`` (Monte Carlo over an uncertainty set), ``falsify`` (the
  worst plant of a box), ``tune`` (controllers at one budget), ``study`` (a study file's report);
- :mod:`~nnrobust.cli.robot`: ``export`` (a law as a C library), ``serve`` (a virtual robot over
  UDP);
- :mod:`~nnrobust.cli.identify`: ``identify`` (a robot's model from its log);
- :mod:`~nnrobust.cli.learn`: ``learn`` (a policy trained by PPO or SAC, per seed, with its
  learning curve).

This module stays light (the stop signals are routed before the commands' modules are imported,
so that a Ctrl-C at any instant of the start is a clean exit 130): :func:`main` imports the table.
"""

from __future__ import annotations

import errno
import os
import sys
import warnings

from ..core.exceptions import ExtrasInterrupted, NNRobustError, one_line
from ..core.signals import ignore_stop_signals, install_stop_handlers, signals_as_interrupt


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit code (0 success, 1 failed run, 2 bad input, 130 interrupted)."""
    from .console import error

    try:
        with signals_as_interrupt():  # from the start: Ctrl-C while importing is a clean exit too
            from .commands import build_parser, routed

            parser = build_parser()
            args = parser.parse_args(routed(sys.argv[1:] if argv is None else list(argv)))
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
        error(f"error: {err}")  # one bounded line (NNRobustError.__str__)
        return 2
    except OSError as err:  # a path too long, a full or read-only disk, met where no check named it
        where = f"{err.filename}: " if err.filename else ""
        error(f"error: {one_line(where + (err.strerror or str(err)))}")
        return 1 if err.errno in (errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EROFS) else 2
    except ValueError as err:
        if "null byte" not in str(err):  # a programming error: its traceback is wanted
            raise
        error("error: a path or name contains a NUL character (\\x00)")
        return 2
    except ExtrasInterrupted as err:
        print(f"nnrobust: {err}", file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        print("nnrobust: interrupted", file=sys.stderr)
        return 130


def run() -> None:
    """The console entry point: exit with main's code. Ctrl-C, SIGTERM and SIGHUP interrupt the
    command's work; one that arrives after the work is done is ignored (core/signals.py).
    """
    from .console import repeated_warnings, warning_line

    install_stop_handlers()
    warnings.showwarning = warning_line
    warnings.simplefilter("always", UserWarning)  # every one reaches warning_line, which counts it
    code = main()
    repeated_warnings()
    ignore_stop_signals()  # also through the interpreter's teardown, which resets Python handlers
    sys.exit(code)
