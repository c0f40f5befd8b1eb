"""Tables a reviewer opens: no CSV cell a spreadsheet evaluates, no LaTeX text TeX reads as a
command, whatever the names in them (a case file's stem, a controller's name, a property)."""

import csv
import io
import re

from hypothesis import given
from hypothesis import strategies as st

from nnrobust.core.table_text import FORMULA_STARTS, TEX_ESCAPES, csv_cell, tex_text

HOSTILE = ["=cmd|' -C calc'!A0", "+1+2", "-3+4", "@SUM(1+1)", "\t=1", "\r=1", "=1+1", "-inf"]

ESCAPE = re.compile("|".join(re.escape(e) for e in sorted(TEX_ESCAPES.values(), key=len, reverse=True)))


def _read_back(cell) -> str:
    buffer = io.StringIO()
    csv.writer(buffer).writerow([cell])
    return next(csv.reader(io.StringIO(buffer.getvalue())))[0]


def _evaluated(text: str) -> bool:
    """Whether a spreadsheet would read the cell as a formula (OWASP's rule: what it starts with),
    a plain number (-3.5) being a number."""
    return text.startswith(FORMULA_STARTS) and not re.fullmatch(
        r"[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?", text
    )


def test_the_issues_cells_are_quoted():
    for text in HOSTILE:
        cell = _read_back(csv_cell(text))
        assert not _evaluated(cell), cell
        assert cell.startswith("'") or text.startswith("\r") and cell == " =1", cell  # \r: a space
    assert csv_cell(-3.5) == -3.5 and _read_back(csv_cell("-3.5")) == "-3.5"  # numbers stay numbers
    assert csv_cell(float("-inf")) == "'-inf" and csv_cell(None) == "" and csv_cell(True) == "yes"


@given(st.text())
def test_no_csv_cell_is_a_formula_whatever_the_text(text):
    cell = _read_back(csv_cell(text))
    assert not _evaluated(cell)
    assert "\n" not in cell and "\r" not in cell.lstrip("'")


@given(st.text())
def test_no_tex_special_character_survives_whatever_the_text(text):
    out = tex_text(text)
    bare = ESCAPE.sub("", out)
    assert not set(bare) & set(TEX_ESCAPES), (text, out)
    assert all(ord(c) >= 32 for c in out)  # no control character (TeX's ^^ notation cannot form)
    # each escape stands for its character, in order: the text is recovered
    back = {v: k for k, v in TEX_ESCAPES.items()}
    assert ESCAPE.sub(lambda m: back[m.group(0)], out) == "".join(
        c for c in text if ord(c) >= 32 and c != "\x7f"
    )


def test_the_issues_tex_name_is_no_command():
    out = tex_text("^^5cinput{^^2fetc^^2fpasswd}")
    assert "^" not in ESCAPE.sub("", out) and "\\input" not in out
    assert tex_text("$x$ ~ {a} & b # c % d _ e \\ f") == (
        r"\$x\$ \textasciitilde{} \{a\} \& b \# c \% d \_ e \textbackslash{} f"
    )


def _report(case: str, controller: str) -> dict:
    entry = {
        "statistics": {"rms_error_after_2s": {"median": 0.001, "p95": 0.002}, "success_rate": 1.0},
        "certificates": [{"property": "rms_error_after_2s<=0.005", "N": 3, "k": 0, "p_upper": 0.05}],
        "tuned": None,
        "worst": None,
        "engines": {},
        "step_cost_us": 5.0,
        "realtime": None,
    }
    return {"cases": {case: {"controllers": {controller: entry}}}}


def test_a_studys_tables_quote_every_name(tmp_path):
    """write_tables with names no study file would pass today (the study's rules refuse them):
    the CSV has no formula cell and the LaTeX no unescaped special character."""
    from nnrobust.studies.study.tables import write_tables

    csv_path, tex_path = write_tables(_report("=cmd|' -C calc'!A0", "@SUM(1+1)"), tmp_path)
    rows = list(csv.reader(csv_path.open()))
    assert rows[1][:2] == ["'=cmd|' -C calc'!A0", "'@SUM(1+1)"]
    assert not any(_evaluated(c) for row in rows for c in row)
    (tmp_path / "b").mkdir()
    tex_path2 = write_tables(_report("^^5cinput{^^2fetc^^2fpasswd}", "x$y"), tmp_path / "b")[1]
    body = tex_path2.read_text().splitlines()[4]  # the one row of the first table
    assert "\\input" not in body and "^^" not in body and r"x\$y" in body
