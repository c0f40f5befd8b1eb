"""The data files behind README.md's and docs/' tables: rendered, current, and rerun."""

import json
from pathlib import Path

import pytest

from tests.docs_numbers.common import (
    DATA_FILES,
    OTHERS,
    ROOT,
    STUDIES,
    TIMINGS,
    _common,
    _docs_data_commands,
    _quickest_row,
    _read,
    _rerun,
    _rerun_validation,
    render_tables,
)


@pytest.mark.parametrize("document", render_tables.DOCUMENTS)
def test_tables_are_rendered_from_the_data(document):
    text = (ROOT / document).read_text()
    assert render_tables.render(text) == text, f"run python docs/render_tables.py ({document})"


def test_every_published_study_report_was_computed_from_todays_files():
    """Each study report in docs/data records the SHA-256 of every file it was computed from (the
    study file, experiment files, custom laws, another study's report it takes settings from):
    each path in the project must hold those bytes today, else the report is stale (run
    ``make docs-data``). Paths are relative to the project (the folder the study ran from)."""
    from nnrobust.studies.base.folder import file_sha256

    reports = [p for p in sorted(render_tables.DATA.glob("*.json")) if "inputs" in json.loads(p.read_text())]
    assert len(reports) >= 9  # the eight studies of make docs-data and the example study
    for report in reports:
        for path, digest in json.loads(report.read_text())["inputs"].items():
            assert not Path(path).is_absolute(), (report.name, path)
            if (ROOT / path).is_file():
                assert file_sha256(ROOT / path) == digest, f"{report.name}: {path} changed since"


def test_every_data_file_has_a_table():
    text = "".join((ROOT / d).read_text() for d in render_tables.DOCUMENTS)
    for name, renderer in render_tables.RENDERERS.items():
        assert f"<!-- table: {name} -->" in text, name
    assert {p.stem for p in render_tables.DATA.glob("*.json")} == set(DATA_FILES + STUDIES + OTHERS + TIMINGS)


@pytest.mark.parametrize(
    "name, case", [("paper_robustness", "half-disturbance"), ("panda_robustness", "preset-disturbance")]
)
def test_a_case_of_a_robustness_study_reproduces(name, case):
    """The NN's certification draws of one case of a shipped robustness study, rebuilt from the
    study file as its certify stage draws them (the case's own disturbance scale) and rerun: their
    median and worst RMS errors are the report's (and the report is of the study file as it is)."""
    from statistics import median

    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.base.plan import base_config, draw, experiment
    from nnrobust.studies.study import load_study
    from nnrobust.studies.study.stages import CERTIFY_SEED, sweep_of

    spec = load_study(ROOT / "benchmarks" / "studies" / f"{name.replace('_', '-')}.toml")
    report = _read(name)
    assert list(report["cases"]) == [c.name for c in spec.cases]
    assert report["budgets"]["certify"] == spec.budgets["certify"]
    (study_case,) = [c for c in spec.cases if c.name == case]
    n = spec.budgets["certify"]
    sweep = sweep_of(spec, study_case, ["nn"], {}, n, spec.seed + CERTIFY_SEED)
    base = base_config(sweep)
    errors = [
        run_experiment(experiment(sweep, base, draw(sweep, i), "nn")).metrics()["rms_error_after_2s"]
        for i in range(n)
    ]
    published = report["cases"][case]["controllers"]["nn"]["statistics"]["rms_error_after_2s"]
    assert median(errors) == pytest.approx(published["median"], rel=1e-9)
    assert max(errors) == pytest.approx(published["max"], rel=1e-9)


@pytest.mark.parametrize("name", DATA_FILES)
def test_a_row_of_the_data_reproduces(name):
    rows = _read(name)["rows"]
    row = _quickest_row(rows)
    job = {k: row[k] for k in ("preset", "changes")}
    again = _common.run_row(job)
    for key in ("rms_error_after_2s", "rms_torque", "torque_chatter", "saturated_fraction"):
        assert again[key] == pytest.approx(row[key], rel=1e-9, abs=1e-12), (name, key)
    assert again["warnings"] == row["warnings"]


def test_a_run_of_the_friction_compensation_data_reproduces():
    runs = _read("friction_compensation")["runs"]
    run = runs[0]
    again = _rerun(run)
    for key in ("rms_error_after_2s", "rms_torque", "torque_chatter"):
        assert again[key] == pytest.approx(run[key], rel=1e-9), key


def test_a_run_of_the_plant_convergence_data_reproduces():
    """The default-step run of paper-ellipse with the NN, and the table's claim that it converged."""
    data = _read("plant_convergence")
    run = next(
        r
        for r in data["runs"]
        if r["preset"] == "paper-ellipse" and r["controller"] == "nn" and r["run"] == "default"
    )
    again = _rerun(run)
    for key in ("rms_error_after_2s", "rms_torque", "torque_chatter", "friction_events"):
        assert again[key] == pytest.approx(run[key], rel=1e-9), key
    row = next(r for r in data["rows"] if r["preset"] == "paper-ellipse" and r["controller"] == "nn")
    assert row["converged"] and not row["chaotic"]


def test_the_default_row_of_the_adaptive_step_data_reproduces():
    """The falling arm at the default max_step_rotation: the same energy drift and cut periods."""
    import adaptive_step

    data = _read("adaptive_step")
    row = next(r for r in data["rows"] if r["max_step_rotation"] == 0.02)
    again = adaptive_step.row(0.02, data["duration"])
    assert again["energy_drift"] == pytest.approx(row["energy_drift"], rel=1e-6)
    assert again["refined_periods"] == row["refined_periods"]


@pytest.mark.parametrize(
    "study, case, controller",
    [
        ("tuned-paper", "paper-ellipse", "pd"),  # ideal sensing: every draw is the training plant
        ("tuned-paper", "paper-ellipse-noisy", "rbf-nn"),  # noisy: held-out draws
        ("tuned-paper", "paper-ellipse-noisy", "slotine-li"),
        ("tuned-paper", "paper-line-noisy", "taskpd-cpp"),  # the law in C++ that is not shipped
        ("tuned-panda", "panda-ellipse-noisy", "nn"),
    ],
)
def test_a_kept_setting_of_the_tuned_studies_reproduces_its_validation_error(study, case, controller):
    """The headline table's numbers are the seeds' validation medians: one kept setting of each
    kind, rerun on its validation draws, gives its median."""
    again, published = _rerun_validation(study, case, controller)
    assert again == pytest.approx(published, rel=1e-6)


def test_make_docs_data_runs_the_tuned_studies_the_tables_name():
    """The comparison's tables name the studies' commands; make docs-data runs each and copies
    its report.json to the data file the tables read."""
    import shlex

    loops = [" ".join(c) for c in _docs_data_commands() if c[:3] == ["for", "study", "in"]]
    for study in render_tables.TUNED_STUDIES:
        assert f"benchmarks/studies/{study}.toml" in render_tables.TUNED_COMMAND
        assert any(
            f" {study}" in line
            and "nnrobust study benchmarks/studies/$$study.toml --out out/$$study --workers 2" in line
            for line in loops
        ), study
    text = (ROOT / "Makefile").read_text()
    # each report is published as soon as its study ends (the next study's `tuned = ` reads it),
    # with this checkout's path taken out of its commands
    assert 'sed "s|$(CURDIR)/||g" $(OUT)/$$study/report.json > $(DATA)/$$(echo $$study | tr - _).json' in text
    assert shlex.split(render_tables.TUNED_COMMAND.split(" and ")[0])[:2] == ["nnrobust", "study"]


def test_a_row_of_the_engine_gap_reproduces():
    """paper-ellipse with the NN on both engines reruns to docs/data/engine_gap.json's figures."""
    pytest.importorskip("mujoco")
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import run_experiment

    data = _read("engine_gap")
    row = next(r for r in data["presets"] if r["preset"] == "paper-ellipse" and r["controller"] == "nn")
    for engine in ("pinocchio", "mujoco"):
        config = load_preset("paper-ellipse").replace(controller={"kind": "nn"}, plant={"engine": engine})
        again = run_experiment(config).metrics()
        for key in ("rms_error_after_2s", "rms_torque", "torque_chatter", "saturated_fraction"):
            assert again[key] == pytest.approx(row[engine][key], rel=1e-9, abs=1e-12), (engine, key)
        assert again["warnings"] == row[engine]["warnings"]


def test_the_interval_coverage_reruns():
    """One row of benchmarks/interval_coverage.py's data (N = 11, skewed differences), recomputed
    with its seed: the same shares of covering intervals, and the order-statistic one at its exact
    coverage within sampling error (3 standard errors)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "interval_coverage", ROOT / "benchmarks" / "interval_coverage.py"
    )
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    data = _read("interval_coverage")
    row = next(r for r in data["rows"] if (r["n"], r["distribution"]) == (11, "skewed"))
    k = list(bench.DISTRIBUTIONS).index("skewed")
    again = bench.coverage(11, bench.DISTRIBUTIONS["skewed"], data["trials"], seed=1000 * 11 + k)
    assert again == {"order": row["order"], "bootstrap": row["bootstrap"]}
    for r in data["rows"]:
        se = (r["exact"] * (1 - r["exact"]) / data["trials"]) ** 0.5
        assert abs(r["order"] - r["exact"]) <= 3 * se + 1e-12, r
