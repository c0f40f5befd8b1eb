r"""Text that goes into a table a reviewer opens: a CSV cell a spreadsheet never evaluates, and
LaTeX text in which no character is a command.

Names in tables come from a user's files (a case's experiment file, a controller's entry), so
whatever they hold is quoted here, not trusted: a spreadsheet evaluates a cell that starts with
``=``, ``+``, ``-``, ``@``, a tab or a carriage return (OWASP's "CSV injection"); TeX reads ``\``,
``{``, ``}``, ``$``, ``&``, ``#``, ``^``, ``_``, ``~`` and ``%`` as commands, and ``^^5c`` as a
backslash.
"""

from __future__ import annotations

import math
import re

FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r", "\uff1d", "\uff0b", "\uff0d", "\uff20")
"""What makes a spreadsheet evaluate a cell (with the full-width forms some spreadsheets read)."""

_NUMBER = re.compile(r"[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?")

TEX_ESCAPES = {
    "\\": r"\textbackslash{}",
    "{": r"\{",
    "}": r"\}",
    "$": r"\$",
    "&": r"\&",
    "#": r"\#",
    "^": r"\textasciicircum{}",
    "_": r"\_",
    "~": r"\textasciitilde{}",
    "%": r"\%",
}
"""Every character TeX treats specially in text, and what stands for it."""


def csv_cell(value) -> str | int | float:
    """A CSV cell: finite numbers as numbers, and text (``-inf`` too) that a spreadsheet would
    evaluate as a formula quoted with a leading apostrophe (``'=1+1``), control characters made
    spaces so that a cell is one line.
    """
    if value is None:
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, float)) and math.isfinite(value):
        return value
    text = "".join(" " if ord(c) < 32 and c != "\t" else c for c in str(value))
    if text.startswith(FORMULA_STARTS) and not _NUMBER.fullmatch(text):
        return "'" + text
    return text


def tex_text(text: str) -> str:
    """``text`` as LaTeX text: each special character its escape (one pass, so an escape is never
    escaped again), control characters dropped (``^^`` sequences cannot form: ``^`` is escaped).
    """
    return "".join(TEX_ESCAPES.get(c, c) for c in str(text) if ord(c) >= 32 and c != "\x7f")
