"""The numbers in README.md and docs/ are those the current code produces.

Tables are rendered from docs/data/*.json by docs/render_tables.py; here the rendered tables
must match the documents, and one row of every data file is re-run and must match its data.
"""

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "docs"))

import _common  # noqa: E402
import render_tables  # noqa: E402

DATA_FILES = ["paper_reproduction", "fair_comparison", "nn_options", "subtask", "arm_presets"]
STUDIES = ["paper_robustness", "panda_robustness"]
"""Summaries of the shipped sweeps (their summary.json)."""


@pytest.mark.parametrize("document", render_tables.DOCUMENTS)
def test_tables_are_rendered_from_the_data(document):
    text = (ROOT / document).read_text()
    assert render_tables.render(text) == text, f"run python docs/render_tables.py ({document})"


def test_every_data_file_has_a_table():
    text = "".join((ROOT / d).read_text() for d in render_tables.DOCUMENTS)
    for name, renderer in render_tables.RENDERERS.items():
        assert f"<!-- table: {name} -->" in text, name
    assert {p.stem for p in render_tables.DATA.glob("*.json")} == set(DATA_FILES + STUDIES)


@pytest.mark.parametrize("name", STUDIES)
def test_the_worst_sample_of_a_study_reproduces(name):
    """The worst NN sample of a shipped study, rerun as a normal run, gives the error its summary
    reports (and the summary is of the shipped sweep file as it is now)."""
    from nnrobust.experiment import run_experiment
    from nnrobust.sweep import draw, load_sweep
    from nnrobust.sweep.spec import base_config, experiment

    summary = json.loads((render_tables.DATA / f"{name}.json").read_text())
    spec = load_sweep(name.replace("_", "-"))
    assert summary["sweep"] == spec.name and summary["samples"] == spec.size
    assert set(summary["controllers"]) == set(spec.controllers)
    worst = summary["controllers"]["nn"]["worst"]
    config = experiment(spec, base_config(spec), draw(spec, worst["sample"]), "nn")
    again = run_experiment(config).metrics()
    assert again["rms_error_after_2s"] == pytest.approx(worst["rms_error_after_2s"], rel=1e-9)


def _quickest_row(rows):
    """The first row of the shortest runs (on the 3-link arm where there is a choice)."""
    def cost(row):
        return (row["changes"].get("simulation", {}).get("duration", 20.0), "panda" in row["preset"])

    return min(rows, key=cost)


@pytest.mark.parametrize("name", DATA_FILES)
def test_a_row_of_the_data_reproduces(name):
    rows = json.loads((render_tables.DATA / f"{name}.json").read_text())["rows"]
    row = _quickest_row(rows)
    job = {k: row[k] for k in ("preset", "changes")}
    again = _common.run_row(job)
    for key in ("rms_error_after_2s", "rms_torque", "torque_chatter", "saturated_fraction"):
        assert again[key] == pytest.approx(row[key], rel=1e-9, abs=1e-12), (name, key)
    assert again["warnings"] == row["warnings"]
