"""The console of a command: one progress line redrawn in place, errors on a line of their own,
each warning once (light: imported before the commands' modules).
"""

from __future__ import annotations

import sys

from ..core.exceptions import one_line

BAR_OPEN = [False]
"""Whether a progress line waits on stderr for its end (an error then starts a line of its own)."""


def bar(done: int, total: int, text: str) -> None:
    """One progress line on stderr, redrawn in place."""
    filled = int(30 * done / max(total, 1))
    print(
        f"\r[{'#' * filled}{' ' * (30 - filled)}] {done}/{total} {text}   ",
        end="",
        file=sys.stderr,
        flush=True,
    )
    BAR_OPEN[0] = True


def error(line: str) -> None:
    """``nnrobust: LINE`` on stderr, on a line of its own."""
    start = "\n" if BAR_OPEN[0] else ""
    BAR_OPEN[0] = False
    print(f"{start}nnrobust: {line}", file=sys.stderr)


WARNED: dict[str, int] = {}
"""Each warning line printed in this command, with how many times it was raised."""


def warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one line, ``warning: ...`` (no file name, line number or source line), printed
    once however often it is raised (every draw of a sweep builds the same experiment again); the
    repeats are counted and said when the command ends (:func:`repeated_warnings`).
    """
    if issubclass(category, DeprecationWarning):
        return
    text = one_line(str(message))
    WARNED[text] = WARNED.get(text, 0) + 1
    if WARNED[text] == 1:
        print(f"warning: {text}", file=sys.stderr if file is None else file)


def repeated_warnings() -> None:
    """One line per warning raised more than once: its count, and the start of its text."""
    for text, count in WARNED.items():
        if count > 1:
            print(f"warning (raised {count} times in all): {one_line(text, 120)}", file=sys.stderr)
