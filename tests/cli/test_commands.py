"""The command line a user sees, against a stored copy: every command's ``--help`` text (at 80
columns) and the exit code of each help, of a bare ``nnrobust`` and of an unknown command. A
restructuring of the package must leave them byte-identical; a change made on purpose is stored
again with ``python -m tests.cli.test_commands`` (repository root) and reviewed in the diff.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
from pathlib import Path

import pytest

STORED = Path(__file__).parents[1] / "data" / "cli_help"
COMMANDS = ("", "run", "plot", "presets", "robots", "compare", "view", "sweep", "falsify", "export",
            "serve", "drive", "study", "tune", "identify", "identify design", "learn", "bench")  # fmt: skip
"""Every command ("" is the bare ``nnrobust --help``; "identify design" is two words)."""


def _help(command: str) -> tuple[int, str]:
    """(exit code, stdout) of ``nnrobust [command] --help`` at 80 columns."""
    from nnrobust.cli import main

    os.environ["COLUMNS"] = "80"
    out = io.StringIO()
    code = 0
    with contextlib.redirect_stdout(out):
        try:
            code = main([*command.split(), "--help"])
        except SystemExit as end:
            code = int(end.code or 0)
    return code, out.getvalue()


def _codes() -> dict[str, int]:
    """The exit codes of calls that print no help: a bare command, an unknown one, a bad flag."""
    from nnrobust.cli import main

    out: dict[str, int] = {}
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        for name, argv in (("bare", []), ("unknown", ["nope"]), ("bad flag", ["run", "--nope"])):
            try:
                out[name] = main(argv)
            except SystemExit as end:
                out[name] = int(end.code or 0)
    return out


def stored_text() -> dict[str, str]:
    """What is stored for each command and for the exit codes."""
    texts = {}
    for command in COMMANDS:
        code, text = _help(command)
        texts[(command or "nnrobust").replace(" ", "-")] = f"exit {code}\n{text}"
    texts["exit-codes"] = "".join(f"{name}: {code}\n" for name, code in _codes().items())
    return texts


@pytest.mark.parametrize("command", COMMANDS)
def test_every_help_text_is_the_stored_one(command, monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    code, text = _help(command)
    name = (command or "nnrobust").replace(" ", "-")
    assert f"exit {code}\n{text}" == (STORED / f"{name}.txt").read_text(), (
        f"python -m tests.cli.test_commands ({name})"
    )


def test_the_exit_codes_are_the_stored_ones():
    expected = (STORED / "exit-codes.txt").read_text()
    assert "".join(f"{name}: {code}\n" for name, code in _codes().items()) == expected


if __name__ == "__main__":
    STORED.mkdir(parents=True, exist_ok=True)
    for name, text in stored_text().items():
        (STORED / f"{name}.txt").write_text(text)
    print(f"stored {len(COMMANDS) + 1} files in {STORED}", file=sys.stderr)
