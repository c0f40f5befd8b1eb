"""``python -m nnrobust`` and the ``nnrobust`` command: the stop signals are routed through
nnrobust.core.signals before the command line's modules are imported, so that a Ctrl-C, SIGTERM or
SIGHUP at any instant of the start ends the command with its one line and exit code 130.
"""

from nnrobust.core.signals import install_stop_handlers


def run() -> None:
    """The console entry point (nnrobust.cli.run, its imports after the stop handlers)."""
    install_stop_handlers()
    from nnrobust.cli import run as command_line

    command_line()


if __name__ == "__main__":
    run()
