"""nnrobust study: one study file through tune (two seeds), validation, certification and
falsification into one report, with a custom law no one here wrote beside the shipped nn and pd;
its tuned settings are exactly those its sweep and falsification ran, a rerun computes nothing,
every replay command recomputes its stage, and a case without randomness says it was validated
on the training plant."""

import json
import shlex
import shutil
from pathlib import Path

import pytest

pytest.importorskip("distributed")
pytest.importorskip("optuna")
pytest.importorskip("cma")

from nnrobust.cli import main  # noqa: E402
from nnrobust.studies.study import load_study, run_study  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"

CUT = {"tune": 8, "seeds": 2, "train_samples": 2, "validation": 2, "epsilon": 0.5, "beta": 0.2,
       "falsify": 4, "margin": "false"}  # fmt: skip
"""examples/study.toml's budgets, cut down for the suite."""


def _cut(text: str) -> str:
    import re

    text = re.sub(r'"simulation.duration" = [0-9.]+', '"simulation.duration" = 2.5', text)
    text = re.sub(r'"plant.friction_scale" = .*\n', "", text)
    for key, value in CUT.items():
        text = re.sub(rf"^{key} = .*$", f"{key} = {value}", text, flags=re.M)
    # a handful of settings cannot meet the torque constraints: the cut study's stages run without
    return re.sub(r"^max_(rms_torque|saturated) = .*\n", "", text, flags=re.M)


STUDY = (
    "".join(
        line
        for line in _cut((EXAMPLES / "study.toml").read_text()).splitlines(True)
        if "train = {" not in line
    )
    .replace("custom_controller.py:TaskPD", "laws.py:TaskPD")
    .replace('file = "policies/', f'file = "{EXAMPLES}/policies/')
)
STUDY_CORE = "".join(line for line in STUDY.splitlines(keepends=True) if "learned-" not in line)
"""The study without its learned rows (the tests of one stage's behaviour). Both leave out the
example's PPO rows, which train for an hour (tests/studies/study/test_train.py trains)."""


def _parts(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("part-*.parquet"))


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    here = tmp_path_factory.mktemp("study")
    shutil.copy(EXAMPLES / "custom_controller.py", here / "laws.py")
    (here / "study.toml").write_text(STUDY)
    out = here / "out"
    assert main(["study", str(here / "study.toml"), "--out", str(out), "--workers", "2", "--quiet"]) == 0
    return here, out, json.loads((out / "report.json").read_text())


def test_the_report_holds_every_stage_for_every_controller(study):
    here, out, report = study
    assert report["schema"] == "nnrobust-study-report/1"
    case = report["cases"]["paper-ellipse-noisy"]
    stages = ("tune", "validate", "certify", "falsify", "realtime", "engine")
    train = {
        "train": "skipped: no policy to train (no entry with a train table)"
    }  # tests/studies/study/test_train.py
    assert case["stages"] == {s: "finished" for s in stages} | train
    assert case["held_out"] and case["validated_on"].startswith("fresh draws")
    import os

    umask = os.umask(0)
    os.umask(umask)
    for stage_file in ("case.toml", "validate.toml", "certify.toml"):  # the umask's mode, as every output
        mode = (out / "cases" / "paper-ellipse-noisy" / stage_file).stat().st_mode & 0o777
        assert mode == 0o666 & ~umask, (stage_file, oct(mode))
    learned = {"learned-residual", "learned-torque"}  # trained offline: tune = false
    assert set(case["controllers"]) == {"nn", "pd", "taskpd"} | learned
    for name, entry in case["controllers"].items():
        if name in learned:
            assert entry["fixed"] and entry["tuned"] is None and entry["backend"] == "hybrid"
        else:
            seeds = entry["tuned"]["seeds"]  # a seed whose tuning found no feasible setting has none
            assert {s["seed"] for s in seeds} <= {0, 1} and seeds, name
            feasible = [s for s in seeds if s["feasible"]]  # judged on the validation draws
            assert entry["tuned"]["kept_seed"] == min(feasible, key=lambda s: s["median_error"])["seed"]
            assert entry["validation"]["feasible"] and isinstance(
                entry["tuned"]["convergence"]["converged"], bool
            )
        assert entry["certificates"] and entry["certificates"][0]["N"] == 3  # ceil(ln(1/0.2) / ln(1/0.5)) = 3
        assert "command" in entry["worst"] and isinstance(entry["worst"]["falsified"], bool)
        assert entry["engines"]["mujoco"]["rows"] == 3 and entry["engines"]["mujoco"]["certificates"]
        assert entry["step_cost_us"] > 0 and entry["backend"] in ("compiled", "hybrid", "python")
        # out of Python: the shipped laws export and are timed; Python code and policies say why not
        timing = entry["realtime"]
        if name in ("nn", "pd"):
            assert timing["exported"] and timing["allocations_per_step"] == 0, timing
            assert 0 < timing["p50_us"] <= timing["p99_us"] <= timing["max_us"]
            assert timing["p99_share"] == pytest.approx(timing["p99_us"] / 1000.0)
            assert (
                out / "cases" / "paper-ellipse-noisy" / "realtime" / f"{name}-tuned" / "law" / "bin"
            ).is_dir()
        else:
            assert not timing["exported"] and "cannot be exported" in timing["reason"], timing
    names = ["nn", "pd", "taskpd", "learned-residual", "learned-torque"]
    assert [(p["a"], p["b"]) for p in case["paired"]] == [
        (a, b) for i, a in enumerate(names) for b in names[i + 1 :]
    ]
    assert str(here / "study.toml") in report["inputs"]
    assert any(p.endswith("laws.py") for p in report["inputs"])
    # beneath the folder the study ran from (the suite's: the project), a path is relative to it
    policies = EXAMPLES / "policies"
    if policies.is_relative_to(Path.cwd()):
        policies = policies.relative_to(Path.cwd())
    assert {p for p in report["inputs"] if p.endswith(".onnx")} == {
        str(policies / "residual.onnx"),
        str(policies / "torque.onnx"),
    }
    assert (out / "tables" / "summary.csv").read_text().count("paper-ellipse-noisy") == 5
    assert (out / "tables" / "summary.tex").read_text().count("paper-ellipse-noisy") == 10  # two tables
    assert "\\toprule" in (out / "tables" / "summary.tex").read_text()
    for ext in ("png", "svg", "pdf"):
        assert (out / "figures" / f"paper-ellipse-noisy-error-cdf.{ext}").stat().st_size > 1000
    page = (out / "report.html").read_text()
    assert page.count("<svg") >= 4 and "<img" not in page  # the figures inline, as SVG
    assert "http://" not in page.replace("http://www.w3.org/", "") and "https://" not in page


def test_the_stage_table_is_what_the_engine_ran_and_the_spec_budgets(study):
    """The stage table (nnrobust.studies.study.stages.STAGES) names every [budgets] key of the
    spec, every stage folder a case holds, and the report's stages in its order."""
    from nnrobust.studies.study.spec import BUDGET_KEYS
    from nnrobust.studies.study.stages import STAGE_FOLDERS, STAGES

    _, out, report = study
    assert set().union(*(stage.budgets for stage in STAGES)) == set(BUDGET_KEYS)
    reported = [stage.name for stage in STAGES if stage.reported]
    for name, case in report["cases"].items():
        assert list(case["stages"]) == reported, name
        folders = {p.name for p in (out / "cases" / name).iterdir() if p.is_dir()}
        assert {f for f in folders if not f.startswith("tune-seed")} <= set(STAGE_FOLDERS), name


def test_the_custom_laws_tuned_settings_are_the_ones_every_stage_ran(study):
    _, out, report = study
    here = out / "cases" / "paper-ellipse-noisy"
    kept = report["cases"]["paper-ellipse-noisy"]["controllers"]["taskpd"]["tuned"]["settings"]
    seed = report["cases"]["paper-ellipse-noisy"]["controllers"]["taskpd"]["tuned"]["kept_seed"]
    tuned = json.loads((here / f"tune-seed{seed}" / "summary.json").read_text())
    assert tuned["controllers"]["taskpd"]["best"]["params"] == kept
    params = {k.removeprefix("controller.params."): v for k, v in kept.items()}
    from nnrobust.config import parse_toml

    certify = parse_toml((here / "certify.toml").read_text(), "certify.toml")
    entry = next(c for c in certify["controllers"] if isinstance(c, dict) and c["name"] == "taskpd-tuned")
    assert entry["params"] == params
    falsify = parse_toml((here / "falsify" / "falsify.toml").read_text(), "falsify.toml")
    assert falsify["tuned"]["taskpd"] == kept
    worst = shlex.split(report["cases"]["paper-ellipse-noisy"]["controllers"]["taskpd"]["worst"]["command"])
    for key, value in params.items():
        assert f"controller.params.{key}={value!r}" in worst
    # the worst plant's command reruns to the metrics the report quotes
    rerun = out.parent / "rerun"
    assert main([*worst[1:], "--out", str(rerun), "--quiet", "--no-plots", "--no-animation"]) == 0
    quoted = report["cases"]["paper-ellipse-noisy"]["controllers"]["taskpd"]["worst"]["metrics"]
    again = json.loads((rerun / "metrics.json").read_text())
    assert again["rms_error_after_2s"] == quoted["rms_error_after_2s"]


def test_a_study_runs_the_settings_another_studys_report_kept(scheduler, study, tmp_path, capsys):
    """``tuned = "REPORT.json#CASE"``: each law at the kept setting of another study's case, as
    NAME-tuned and untuned (the custom law too; a law that study ran untuned keeps its own name),
    through certification and falsification; the report names the source file's SHA-256. A case
    the report does not hold, or a law it did not tune, is one line naming ``tuned``. When the
    source report changes, the resume is refused and the stages' input files stay as they were."""
    import re

    from nnrobust.config import parse_toml
    from nnrobust.studies.base.folder import file_sha256

    _, first, report = study
    source = report["cases"]["paper-ellipse-noisy"]["controllers"]
    src = tmp_path / "source.json"
    shutil.copy(first / "report.json", src)
    shutil.copy(EXAMPLES / "custom_controller.py", tmp_path / "laws.py")
    text = re.sub(
        r"controllers = \[.*?\n\]\n",
        f'controllers = ["nn", {{name = "taskpd", class = "laws.py:TaskPD"}}]\n'
        f'tuned = "{src}#paper-ellipse-noisy"\n',
        STUDY_CORE.replace('name = "example"', 'name = "again"'),
        flags=re.S,
    )
    (tmp_path / "study.toml").write_text(text)
    spec = load_study(tmp_path / "study.toml")
    assert spec.controllers == ["nn-tuned", "taskpd-tuned"] and spec.fixed == spec.controllers
    assert json.loads((first / "report.json").read_text())["tuned_from"] is None
    out = tmp_path / "out"
    assert (
        main(["study", str(tmp_path / "study.toml"), "--out", str(out), "--scheduler", scheduler, "--quiet"])
        == 0
    )
    again = json.loads((out / "report.json").read_text())
    assert again["tuned_from"] == f"{src}#paper-ellipse-noisy"
    assert again["cases"]["paper-ellipse-noisy"]["stages"]["tune"].startswith(
        "skipped: every law runs at the kept"
    )
    assert again["inputs"][str(src)] == file_sha256(src)
    here = out / "cases" / "paper-ellipse-noisy"
    certify = {c["name"]: c for c in parse_toml((here / "certify.toml").read_text(), "c")["controllers"]}
    taskpd = source["taskpd"]["tuned"]["settings"]
    assert certify["taskpd-tuned"]["params"] == {
        k.removeprefix("controller.params."): v for k, v in taskpd.items()
    }
    assert certify["nn-tuned"]["set"] == source["nn"]["tuned"]["settings"]
    assert not list(here.glob("tune-seed*"))  # nothing tuned again
    falsified = json.loads((here / "falsify" / "summary.json").read_text())
    assert set(falsified["controllers"]) == {"nn-tuned", "taskpd-tuned"}
    for change, message in [
        (
            (f"{src}#paper-ellipse-noisy", str(first)),
            "is a study's folder: name its report",
        ),
        (("#paper-ellipse-noisy", "#paper-line"), "name one of its cases"),
        (('["nn", {name', '["no-u0", {name'), "has no best setting for 'no-u0'"),
    ]:
        (tmp_path / "bad.toml").write_text(text.replace(*change))
        assert main(["study", str(tmp_path / "bad.toml"), "--out", str(tmp_path / "bad")]) == 2
        err = capsys.readouterr().err
        assert "bad.toml: tuned: " in err and message in err and err.count("\n") == 1, err
    # the source's kept setting changes: refused, and the stages' files still name the old one
    stage_files = {name: (here / name).read_text() for name in ("case.toml", "validate.toml", "certify.toml")}
    changed = json.loads(src.read_text())
    settings = changed["cases"]["paper-ellipse-noisy"]["controllers"]["nn"]["tuned"]["settings"]
    settings["controller.k"] *= 2
    src.write_text(json.dumps(changed))
    assert (
        main(["study", str(tmp_path / "study.toml"), "--out", str(out), "--scheduler", scheduler, "--quiet"])
        == 2
    )
    assert "holds a different" in capsys.readouterr().err
    assert {name: (here / name).read_text() for name in stage_files} == stage_files


def test_a_rerun_computes_nothing_and_each_replay_command_recomputes_its_stage(scheduler, study, capsys):
    here, out, report = study
    before = _parts(out)
    assert (
        main(["study", str(here / "study.toml"), "--out", str(out), "--scheduler", scheduler, "--quiet"]) == 0
    )
    assert _parts(out) == before
    assert json.loads((out / "report.json").read_text())["cases"] == report["cases"]
    said: list[str] = []
    run_study(load_study(here / "study.toml"), out, scheduler=scheduler, say=said.append)
    assert said[-1].startswith("nothing computed: every stage's") and _parts(out) == before
    commands = report["cases"]["paper-ellipse-noisy"]["commands"]
    assert set(commands) == {"tune seed 0", "tune seed 1", "validate", "certify", "falsify", "engine"}
    for name in ("validate", "certify", "falsify", "engine", "tune seed 1"):
        words = shlex.split(commands[name])  # a replay of a finished stage runs nothing
        assert main([*words[1:], "--scheduler", scheduler, "--quiet"]) == 0, name
    assert _parts(out) == before  # the stage folders took every command as their own: nothing new


def test_a_case_without_randomness_says_it_was_validated_on_the_training_plant(scheduler, tmp_path):
    (tmp_path / "study.toml").write_text(
        STUDY_CORE.replace('cases = ["paper-ellipse-noisy"]', 'cases = ["paper-ellipse"]')
        .replace('"plant.disturbance_scale" = {uniform = [0.5, 2.0]}', "")
        .replace('    {name = "taskpd", class = "laws.py:TaskPD"},\n', "")
        .replace("seeds = 2", "seeds = 1")
        .replace("train_samples = 1", "train_samples = 2")
    )
    said: list[str] = []
    report = run_study(
        load_study(tmp_path / "study.toml"), tmp_path / "out", scheduler=scheduler, say=said.append
    )
    case = report["cases"]["paper-ellipse"]
    assert not case["held_out"]
    assert case["validated_on"].startswith("the training plant")
    assert case["stages"]["falsify"].startswith("skipped")
    # every draw is the same plant: the budget buys settings, one run each, not repeats
    assert any("every draw is the same plant" in line for line in said)
    tuning = json.loads(
        (tmp_path / "out" / "cases" / "paper-ellipse" / "tune-seed0" / "summary.json").read_text()
    )
    assert len(tuning["train_samples"]) == 1 and tuning["trials"] == tuning["budget"]
    # and the report's command for that tuning is the one it ran: rerun into its folder, nothing to do
    words = shlex.split(case["commands"]["tune seed 0"])
    assert "--train-samples" in words and words[words.index("--train-samples") + 1] == "1"
    parts = _parts(tmp_path / "out")
    assert main([*words[1:], "--scheduler", scheduler, "--quiet"]) == 0
    assert _parts(tmp_path / "out") == parts


@pytest.mark.parametrize(
    "case, vary, differ",
    [
        ("paper-ellipse", {}, False),  # no box, ideal sensing, the closed-form nominal model
        ("paper-ellipse-noisy", {}, True),  # sensor noise drawn from each draw's seed
        ("panda-ellipse", {}, True),  # the nominal model's error drawn from each draw's seed
        ("paper-ellipse", {"plant.friction_scale": {"uniform": [0.5, 2.0]}}, True),  # a box
    ],
)
def test_draws_differ_exactly_where_a_case_has_randomness(case, vary, differ):
    from nnrobust.studies.base.plan import SweepSpec
    from nnrobust.studies.study.stages import draws_differ

    sweep = SweepSpec(name="s", base=case, controllers=["pd"], samples=1, seed=0, vary=vary)
    assert draws_differ(sweep) is differ


def test_a_shipped_law_runs_untuned_under_its_own_name(tmp_path):
    """{name = "nn", tune = false} is the kind itself at its own settings (its rows, settings and
    falsification named nn, as the published falsification studies need); {name = "pd", tune =
    true} is plain "pd", tuned; a name that is no kind is refused naming the valid ones."""
    from nnrobust.core.exceptions import ConfigError

    text = (
        'name = "s"\ncases = ["paper-ellipse"]\nrequire = ["rms_error_after_2s<=0.05"]\n'
        'controllers = [{name = "nn", tune = false}, {name = "pd", tune = true}, "no-u0"]\n'
    )
    (tmp_path / "s.toml").write_text(text)
    spec = load_study(tmp_path / "s.toml")
    assert spec.controllers == ["nn", "pd", "no-u0"] and spec.fixed == ["nn"] and spec.entries == {}
    assert spec.case_sweep(spec.cases[0]).controllers == ["nn", "pd", "no-u0"]
    (tmp_path / "s.toml").write_text(text.replace('name = "nn"', 'name = "nnx"'))
    with pytest.raises(ConfigError, match="'nnx' is not one of nn, "):
        load_study(tmp_path / "s.toml")


def test_cases_of_one_experiment_with_overrides_of_their_own(scheduler, tmp_path):
    """Case tables {name, base, set}: the paper's arm at half and twice the disturbance are two
    cases, each certified on its own ``certify`` draws at its own scale (and the larger
    disturbance gives the larger error); ``falsify = 0`` skips the search and says so."""
    text = (
        'name = "levels"\nrequire = ["rms_error_after_2s<=0.05"]\n'
        'cases = [{name = "low", base = "paper-ellipse", set = {"plant.disturbance_scale" = 0.5}},\n'
        '         {name = "high", base = "paper-ellipse", set = {"plant.disturbance_scale" = 2.0}}]\n'
        'controllers = [{name = "nn", tune = false}]\n'
        '[set]\n"simulation.duration" = 2.5\n'
        '[vary]\n"plant.friction_scale" = {loguniform = [0.5, 2.0]}\n'
        "[budgets]\nvalidation = 2\nepsilon = 0.5\nbeta = 0.2\ncertify = 5\nfalsify = 0\n"
    )
    (tmp_path / "s.toml").write_text(text)
    spec = load_study(tmp_path / "s.toml")
    assert [c.name for c in spec.cases] == ["low", "high"]
    report = run_study(spec, tmp_path / "out", scheduler=scheduler)
    import pandas as pd

    from nnrobust.config import parse_toml

    medians = {}
    for name, scale in (("low", 0.5), ("high", 2.0)):
        case = report["cases"][name]
        assert case["set"] == {"plant.disturbance_scale": scale}
        assert case["stages"]["falsify"] == "skipped: falsify = 0"
        here = tmp_path / "out" / "cases" / name
        assert parse_toml((here / "certify.toml").read_text(), "c")["set"]["plant.disturbance_scale"] == scale
        rows = pd.read_parquet(here / "certify" / "results")
        assert len(rows) == 5 and rows["plant.friction_scale"].nunique() == 5
        assert case["controllers"]["nn"]["certificates"][0]["N"] == 5
        medians[name] = rows["rms_error_after_2s"].median()
    assert medians["high"] > medians["low"]


@pytest.mark.parametrize(
    "change, message",
    [
        (("[budgets]", "[budget]"), "budget: unknown key; did you mean 'budgets'?"),
        (("tune = 8", "tunes = 8"), "budgets.tunes: unknown key; did you mean 'tune'?"),
        (("seeds = 2", "seeds = 0"), "budgets.seeds: expected an integer in [1, 20], got 0"),
        (("{uniform = [0.5, 2.0]}", "[0.5, 2.0]"), "a study's uncertainty set is distributions"),
        (("<=0.002", "<=0.002 mm"), "require"),
        (
            ("{uniform = [0.5, 2.0]}", "{normal = [1.0, 0.2]}"),
            "falsify searches uniform and loguniform ranges, not normal",
        ),
        (
            ('cases = ["paper-ellipse-noisy"]', 'cases = [{name = "a", bas = "paper-ellipse-noisy"}]'),
            "cases[0].bas: unknown key; did you mean 'base'?",
        ),
        (
            (
                'cases = ["paper-ellipse-noisy"]',
                'cases = [{name = "a", base = "paper-ellipse-noisy", '
                'set = {"plant.disturbance_scale" = 1.0}}]',
            ),
            "cases.a.set: sets 'plant.disturbance_scale', which [vary] draws",
        ),  # fmt: skip
        (("falsify = 4", "falsify = 2"), "budgets.falsify: expected 0 (no search) or at least 4, got 2"),
        (
            (
                'cases = ["paper-ellipse-noisy"]',
                'cases = [{name = "a", base = "paper-ellipse-noisy", set = {"controller.pd_Kp" = [1000.0]}}]',
            ),
            "case a: set.controller.pd_Kp: is a key of pd, which the study tunes",
        ),  # fmt: skip
        (
            ('"simulation.duration" = 2.5', '"simulation.duration" = 1.5'),
            "simulation.duration: 1.5 s: a study selects, certifies and reports by the RMS error after 2 s",
        ),
        (
            ('"simulation.duration" = 2.5', '"simulation.duration" = 2.5\n"plant.payload" = -1.0'),
            "case paper-ellipse-noisy: set: plant.payload",
        ),
        (("beta = 0.2", "beta = 0.2\ncertify = 2"), "budgets.certify: 2 draws cannot prove P(fail) <= 0.5"),
        (("laws.py:TaskPD", "laws.py:TaskPDD"), "has no 'TaskPDD'; did you mean 'TaskPD'?"),
        (
            ('class = "laws.py:TaskPD"', 'class = "laws.py:TaskPD", tuen = false'),
            "tuen: unknown key; did you mean 'tune'?",
        ),
    ],
)
def test_a_bad_study_is_one_line_naming_the_key_before_any_stage(change, message, tmp_path, capsys):
    shutil.copy(EXAMPLES / "custom_controller.py", tmp_path / "laws.py")
    (tmp_path / "study.toml").write_text(STUDY.replace(*change))
    assert main(["study", str(tmp_path / "study.toml"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
    assert not (tmp_path / "out").exists()


def test_a_controller_that_cannot_run_is_refused_before_any_stage(tmp_path, capsys):
    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", tmp_path / "laws.py")
    (tmp_path / "study.toml").write_text(STUDY.replace("laws.py:TaskPD", "laws.py:WrongShape"))
    assert main(["study", str(tmp_path / "study.toml"), "--out", str(tmp_path / "out")]) == 2
    assert "returned a torque of shape (4,)" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_the_report_opens_in_a_browser_without_a_console_error(study, tmp_path):
    from tests.outputs.test_viewer import _chromium, console_errors

    browser = _chromium()
    if browser is None:
        pytest.skip("Chromium is not installed (make test installs Debian's chromium where it can)")
    _, out, _ = study
    assert console_errors(browser, out / "report.html", tmp_path) == []


def test_validation_and_certification_draws_are_ones_the_earlier_stages_never_saw(study):
    """Held out means held out: the tunings' training draws, the validation draws (which select
    the seed) and the certification draws are three disjoint sets of plants."""
    from nnrobust.studies.sweep import read_results

    _, out, _ = study
    here = out / "cases" / "paper-ellipse-noisy"
    key = "plant.disturbance_scale"
    training = {
        s[key]
        for seed in (0, 1)
        for s in json.loads((here / f"tune-seed{seed}" / "summary.json").read_text())["train_samples"]
    }
    validation = set(read_results(here / "validate")[key])
    certification = set(read_results(here / "certify")[key])
    assert training and validation and certification
    assert not training & validation and not training & certification and not validation & certification


def test_every_summary_displays_as_html_in_a_notebook(study):
    """load_summary reads a sweep's, a tuning's, a falsification's and a study's folder; each is the
    summary's own dict and renders as one HTML table naming every controller (Jupyter calls
    _repr_html_)."""
    from html.parser import HTMLParser

    import nnrobust

    _, out, report = study
    here = out / "cases" / "paper-ellipse-noisy"

    def kept(c: str) -> int:
        return report["cases"]["paper-ellipse-noisy"]["controllers"][c]["tuned"]["kept_seed"]

    shown = {
        "SweepSummary": (here / "validate", [f"{c}-seed{kept(c)}" for c in ("nn", "pd", "taskpd")]),
        "TuneSummary": (here / "tune-seed0", ["nn", "pd", "taskpd"]),
        "FalsifySummary": (here / "falsify", ["nn-tuned", "pd-tuned", "taskpd-tuned", "falsified"]),
        "StudyReport": (out, ["nn", "pd", "taskpd", "validated on fresh draws"]),
    }
    for kind, (folder, names) in shown.items():
        summary = nnrobust.load_summary(folder)
        assert type(summary).__name__ == kind
        assert summary == json.loads(
            (folder / ("report.json" if kind == "StudyReport" else "summary.json")).read_text()
        )
        page = summary._repr_html_()
        HTMLParser().feed(page)
        assert page.count("<table>") == 1 and page.count("</table>") == 1, kind
        for name in names:
            assert name in page, (kind, name)
    with pytest.raises(
        nnrobust.NNRobustError, match="holds no finished sweep, tuning, falsification or study"
    ):
        nnrobust.load_summary(here)


def test_a_law_that_fails_says_why_in_the_report_and_the_report_is_standard_json(scheduler, tmp_path, capsys):
    """A tuned law whose every run raises is not silently dropped: the report, its page and the
    command say why (its exception, located). A law run untuned that fails keeps its rows' first
    message. report.json holds no Infinity (a margin of -inf is null beside the status)."""
    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", tmp_path / "laws.py")
    text = STUDY_CORE.replace(
        '{name = "taskpd", class = "laws.py:TaskPD"}',
        '{name = "late", class = "laws.py:RaisesLate", tune = false}, '
        '{name = "latet", class = "laws.py:RaisesLate"}',
    ).replace('    "nn",\n', "")
    (tmp_path / "study.toml").write_text(text)
    out = tmp_path / "out"
    assert main(["study", str(tmp_path / "study.toml"), "--out", str(out), "--scheduler", scheduler]) == 0
    said = capsys.readouterr()
    raw = (out / "report.json").read_text()
    report = json.loads(raw, parse_constant=lambda c: pytest.fail(f"report.json holds {c}"))
    case = report["cases"]["paper-ellipse-noisy"]
    assert (
        "RaisesLate.compute raised at t = 1.001 s: RuntimeError: boom after 1 s" in case["not_kept"]["latet"]
    )
    assert "latet" in said.out and "not kept: seed 0: no setting met the constraints" in said.out
    failed = case["controllers"]["late"]["failures"]
    assert (
        failed["refused"]["runs"] == 3
        and "RuntimeError: boom after 1 s" in failed["refused"]["first_message"]
    )
    assert case["controllers"]["late"]["worst"]["margin"] is None  # -inf: the runs did not complete
    page = (out / "report.html").read_text()
    assert "latet: not kept." in page and "boom after 1 s" in page


def test_a_law_without_a_search_space_is_refused_naming_the_way_out(tmp_path, capsys):
    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", tmp_path / "laws.py")
    (tmp_path / "study.toml").write_text(STUDY.replace("laws.py:TaskPD", "laws.py:Counter"))
    assert main(["study", str(tmp_path / "study.toml"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "controllers.taskpd: Counter declares no search space" in err and "tune = false" in err, err


def test_a_changed_study_is_refused_naming_what_changed(study, tmp_path, capsys):
    here, out, _ = study
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    (tmp_path / "study.toml").write_text(
        (here / "study.toml").read_text().replace("validation = 2", "validation = 3")
    )
    shutil.copy(here / "laws.py", tmp_path / "laws.py")
    assert main(["study", str(tmp_path / "study.toml"), "--out", str(copy), "--quiet"]) == 2
    assert "changed since its rows were computed: budgets.validation 2 -> 3" in capsys.readouterr().err


def test_stages_side_by_side_give_their_results_in_order_and_stop_together_on_an_error():
    """side_by_side: each stage's result in the stages' order; when one fails, the others are
    asked to stop at their next check (an engine's check_interrupt) and the first error is raised
    once all have ended; the request is lifted afterwards (the next run is not stopped)."""
    import threading

    from nnrobust.core.signals import check_interrupt
    from nnrobust.studies.study.stages import side_by_side

    assert side_by_side([lambda: 1, lambda: 2, lambda: 3]) == [1, 2, 3]
    stopped = threading.Event()
    failing = threading.Event()

    def long_stage():
        failing.wait(10)
        try:
            for _ in range(1000):  # 100 s unless stopped
                check_interrupt()
                threading.Event().wait(0.1)
        except KeyboardInterrupt:
            stopped.set()
            raise
        return "never stopped"

    def failing_stage():
        failing.set()
        raise ValueError("this stage's inputs are bad")

    with pytest.raises(ValueError, match="inputs are bad"):
        side_by_side([long_stage, failing_stage])
    assert stopped.is_set()
    check_interrupt()  # lifted


def test_an_interrupt_in_one_stage_stops_the_others_and_the_study_resumes(study, tmp_path, monkeypatch):
    """A stop while certify, falsify and the MuJoCo draws run side by side (here: the
    falsification interrupted as it starts) ends every stage, each keeping what it computed; run
    again, the study finishes with the numbers of a study never interrupted."""
    import nnrobust.studies.falsify
    from nnrobust.studies.study.engine import STAGE_FOLDERS

    here, out, report = study
    spec = load_study(here / "study.toml")
    # the finished study's tunings and validation, the stages from certify on to compute again
    shutil.copytree(out, tmp_path / "out", ignore=shutil.ignore_patterns("report.*", "tables", "figures"))
    for case in (tmp_path / "out" / "cases").iterdir():
        for stage in set(STAGE_FOLDERS) - {"validate"}:
            shutil.rmtree(case / stage, ignore_errors=True)

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    with monkeypatch.context() as patch:
        patch.setattr(nnrobust.studies.falsify, "run_falsify", interrupted)
        with pytest.raises(KeyboardInterrupt):
            run_study(spec, tmp_path / "out", workers=2)
    assert not (tmp_path / "out" / "report.json").exists()
    assert not list((tmp_path / "out" / "cases").glob("*/falsify/history/*"))
    again = run_study(spec, tmp_path / "out", workers=2)
    for name, case in report["cases"].items():
        for c, entry in case["controllers"].items():
            resumed = again["cases"][name]["controllers"][c]
            assert resumed["statistics"] == entry["statistics"], c
            drop = ("command",)  # it names the law's file, in this test's folder
            assert {k: v for k, v in resumed["worst"].items() if k not in drop} == {
                k: v for k, v in entry["worst"].items() if k not in drop
            }, c


def _validation_frame(rows: dict):
    """Validation rows: label -> [(error [m], RMS torque [N m], saturated share), ...] per draw."""
    import pandas as pd

    records = []
    for label, draws in rows.items():
        for sample, (error, torque, saturated) in enumerate(draws):
            records.append(
                {"controller": label, "sample": sample, "status": "completed", "rms_error_after_2s": error,
                 "rms_torque": torque, "torque_chatter": 1.0, "saturated_fraction": saturated,
                 "runaway": False, "max_joint_limit_violation": 0.0}
            )  # fmt: skip
    return pd.DataFrame(records)


def _spec_with(tmp_path, budgets: str = "", top: str = ""):
    (tmp_path / "s.toml").write_text(
        'name = "s"\ncases = ["paper-ellipse"]\ncontrollers = ["pd"]\n'
        f'require = ["rms_error_after_2s<=0.005"]\n{top}[vary]\n'
        f'"plant.friction_scale" = {{uniform = [0.5, 2.0]}}\n[budgets]\n{budgets}'
    )
    return load_study(tmp_path / "s.toml")


def test_the_kept_seed_is_the_least_error_among_the_seeds_feasible_on_validation(tmp_path):
    """Seed 0 has the least validation median but breaks the torque limit on the validation draws:
    seed 1 is kept. With every seed infeasible the law is not kept, and the reason gives the
    numbers (it kept the least median, feasible or not)."""
    from nnrobust.studies.study.selection import select_kept as _select

    spec = _spec_with(tmp_path, "max_rms_torque = 10.0\nmax_saturated = 0.01\n")
    setting_of = {"pd-seed0": ("pd", 0, {"k": 1}, []), "pd-seed1": ("pd", 1, {"k": 2}, [])}
    frame = _validation_frame(
        {"pd-seed0": [(1e-4, 13.1, 0.0), (1e-4, 12.0, 0.0)], "pd-seed1": [(2e-4, 8.0, 0.0), (3e-4, 9.0, 0.0)]}
    )
    kept, per_seed, infeasible = _select(spec, frame, setting_of)
    assert kept["pd"]["seed"] == 1 and not infeasible
    assert [s["feasible"] for s in per_seed["pd"]] == [False, True]
    assert per_seed["pd"][0]["why_infeasible"] == "RMS torque 12.6 N m > 10 N m"
    frame = _validation_frame({"pd-seed0": [(1e-4, 13.1, 0.0)], "pd-seed1": [(2e-4, 8.0, 0.079)]})
    kept, _, infeasible = _select(spec, frame, setting_of)
    assert kept == {} and infeasible["pd"] == (
        "infeasible on validation: seed 0: RMS torque 13.1 N m > 10 N m; seed 1: saturated 7.9 % > 1 %"
    )


def test_a_tuning_has_converged_when_doubling_its_budget_moves_the_kept_median_less_than_the_tolerance(
    tmp_path,
):
    """m(B/2) against m(B): the least validation median of the feasible seeds' best settings at half
    the budget and at the whole of it; converged when |m(B/2) / m(B) - 1| <= budgets.tolerance."""
    from nnrobust.studies.study.selection import convergence as _convergence

    spec = _spec_with(tmp_path, "tune = 40\ntolerance = 0.1\n")
    labels, halves = ["pd-seed0", "pd-seed1"], {"pd-seed0": "pd-seed0-half", "pd-seed1": "pd-seed1"}
    rows = {
        "pd-seed0": [(1.0e-4, 1.0, 0.0)],
        "pd-seed1": [(1.2e-4, 1.0, 0.0)],
        "pd-seed0-half": [(1.5e-4, 1.0, 0.0)],
    }
    record = _convergence(spec, _validation_frame(rows), labels, halves)
    assert record["kept_median"] == 1.0e-4 and record["kept_median_half"] == 1.2e-4  # seed 1 held its best
    assert record["change"] == pytest.approx(0.2) and record["converged"] is False
    assert record["budget"] == 40 and record["half_budget"] == 20
    rows["pd-seed1"] = [(1.05e-4, 1.0, 0.0)]
    assert _convergence(spec, _validation_frame(rows), labels, halves)["converged"] is True


def test_the_certificate_is_over_the_designs_whole_requirement(tmp_path):
    """A study certifies its require, its tuning constraints, no stop hit, no runaway and the path
    kept, together ("all of") and one by one; a run that completed but broke the torque limit
    fails it (it counted as a pass). A study file may waive one part, and says so."""
    from nnrobust.run.properties import certify_runs, run_properties

    spec = _spec_with(tmp_path, "max_rms_torque = 10.0\nmax_saturated = 0.01\n")
    assert spec.certified_properties() == [
        "rms_error_after_2s<=0.005", "rms_torque<=10", "saturated_fraction<=0.01",
        "max_joint_limit_violation<=0", "runaway==false", "tracking_error_ratio<=0.1",
    ]  # fmt: skip
    ok = {"status": "completed", "rms_error_after_2s": 1e-3, "rms_torque": 5.0, "saturated_fraction": 0.0,
          "max_joint_limit_violation": 0.0, "runaway": False, "tracking_error_ratio": 0.01}  # fmt: skip
    records = [ok, {**ok, "rms_torque": 12.0}, {**ok, "max_joint_limit_violation": 0.02}]
    certificates, _ = certify_runs(records, run_properties(spec.certified_properties()), 0.1, 0.05)
    whole = certificates[0]
    assert whole["property"].startswith("all of: rms_error_after_2s<=0.005, rms_torque<=10")
    assert (whole["N"], whole["k"]) == (3, 2)
    assert {c["property"]: c["k"] for c in certificates[1:]}["rms_torque<=10"] == 1
    waived = _spec_with(tmp_path, "max_rms_torque = 10.0\n", top='waive = ["stops"]\n')
    assert "max_joint_limit_violation<=0" not in waived.certified_properties()
    from nnrobust.studies.study.report import study_warnings

    assert any("waived by the study file: no joint stop hit" in w for w in study_warnings(waived))
    assert any("no torque or saturation constraint" in w for w in study_warnings(_spec_with(tmp_path)))


def test_reordering_a_studys_controllers_changes_no_result(scheduler, tmp_path):
    """Every stage of a law is seeded by the study's seed and the law's name: the same study with its
    controllers listed the other way round writes the same report but for the order (the step
    costs, wall-clock readings, and the study file's own digest aside)."""
    study = (
        'name = "order"\ncases = ["paper-ellipse"]\ncontrollers = [{order}]\n'
        'require = ["rms_error_after_2s<=0.002"]\n[set]\n"simulation.duration" = 2.5\n'
        '[vary]\n"plant.disturbance_scale" = {{uniform = [0.5, 2.0]}}\n'
        "[budgets]\ntune = 8\nseeds = 1\ntrain_samples = 1\nvalidation = 2\nepsilon = 0.5\nbeta = 0.2\n"
        "falsify = 4\n"
    )
    reports = []
    for order in ('"no-u0", "pd"', '"pd", "no-u0"'):
        folder = tmp_path / order.replace('"', "").replace(", ", "-")
        folder.mkdir()
        (folder / "study.toml").write_text(study.format(order=order))
        run_study(load_study(folder / "study.toml"), folder / "out", scheduler=scheduler)
        reports.append(json.loads((folder / "out" / "report.json").read_text()))

    def comparable(report: dict) -> dict:
        case = report["cases"]["paper-ellipse"]
        controllers = {}
        for name, entry in case["controllers"].items():
            entry = {k: v for k, v in entry.items() if k not in ("step_cost_us", "backend", "realtime")}
            controllers[name] = json.loads(json.dumps(entry).replace(str(tmp_path), "<tmp>"))
        paired = sorted((tuple(sorted((p["a"], p["b"]))), p.get("ratio")) for p in case["paired"])
        return {"controllers": controllers, "paired": paired, "not_kept": case["not_kept"]}

    first, second = (comparable(r) for r in reports)
    assert first["controllers"]["pd"]["tuned"]["settings"]  # tuned, and tuned alike (no-u0 too, or
    for name in first["controllers"]:  # not kept for the same reason in both)
        a = (
            json.dumps(first["controllers"][name], sort_keys=True)
            .replace("no-u0-pd", "X")
            .replace("pd-no-u0", "X")
        )
        b = (
            json.dumps(second["controllers"][name], sort_keys=True)
            .replace("no-u0-pd", "X")
            .replace("pd-no-u0", "X")
        )
        assert a == b, name
    assert first["paired"] == second["paired"] and first["not_kept"] == second["not_kept"]


def test_a_tuned_law_in_cpp_needs_no_params_of_its_own(tmp_path):
    """A study's tuned C++ entry without params is checked at the centre of the space it declares,
    as the tuner first builds it (a C++ law has no Python defaults: built at its entry's own
    params it was refused for a missing Kp)."""
    import shutil

    from nnrobust.run.compiled import available
    from nnrobust.studies.study.engine import _check_controllers

    if not available():
        pytest.skip("the compiled loop is not built: a law in C++ runs there")
    shutil.copy(EXAMPLES / "controllers" / "task_pd.cpp", tmp_path / "task_pd.cpp")
    (tmp_path / "s.toml").write_text(
        'name = "cpp"\ncases = ["paper-ellipse-noisy"]\n'
        'controllers = ["pd", {name = "taskpd-cpp", class = "task_pd.cpp:TaskPD"}]\n'
        'require = ["rms_error_after_2s<=0.002"]\n[set]\n"simulation.duration" = 2.5\n'
        '[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n[budgets]\ntune = 4\nfalsify = 0\n'
    )
    _check_controllers(load_study(tmp_path / "s.toml"))


def test_a_policy_per_arm_is_one_law_in_a_study_of_two_arms(scheduler, tmp_path):
    """Two entries named learned, each listing its case (cases = [...]), each with the policy file
    of its arm (observations of 16 and 29 entries): one law of the study, run on each arm with its
    own file (a policy file is bound to one observation size; it was refused on the other arm)."""
    pytest.importorskip("onnxruntime")
    from nnrobust.studies.learning import ObservationLayout
    from tests.policies import linear_policy

    linear_policy(tmp_path / "paper.onnx", ObservationLayout(3, 2).size, 3)
    linear_policy(tmp_path / "panda.onnx", ObservationLayout(7, 3).size, 7)
    entry = (
        '{{name = "learned", kind = "policy", tune = false, cases = ["{case}"], '
        'params = {{file = "{file}", action = "residual", base = "pd"}}}}'
    )
    paper, panda = (entry.format(case=f"{arm}-ellipse", file=f"{arm}.onnx") for arm in ("paper", "panda"))
    (tmp_path / "study.toml").write_text(
        'name = "arms"\ncases = ["paper-ellipse", "panda-ellipse"]\n'
        f'controllers = [{{name = "pd", tune = false}}, {paper}, {panda}]\n'
        'require = ["rms_error_after_2s<=0.01"]\n[set]\n"simulation.duration" = 2.2\n'
        '[vary]\n"plant.friction_scale" = {uniform = [0.5, 2.0]}\n'
        "[budgets]\nvalidation = 2\ncertify = 3\nepsilon = 0.5\nbeta = 0.2\nfalsify = 0\n"
    )
    spec = load_study(tmp_path / "study.toml")
    assert spec.controllers == ["pd", "learned"]
    files = {c.name: spec.for_case(c).entries["learned"]["params"]["file"] for c in spec.cases}
    assert files == {
        "paper-ellipse": str(tmp_path / "paper.onnx"),
        "panda-ellipse": str(tmp_path / "panda.onnx"),
    }
    report = run_study(spec, tmp_path / "out", scheduler=scheduler)
    for case, file in files.items():
        entry = report["cases"][case]["controllers"]["learned"]
        assert entry["entry"]["params"]["file"].endswith(Path(file).name)
        assert entry["statistics"]["rows"] == 3 and entry["statistics"]["success_rate"] == 1.0
    (tmp_path / "twice.toml").write_text(
        (tmp_path / "study.toml")
        .read_text()
        .replace('cases = ["panda-ellipse"]', 'cases = ["paper-ellipse"]')
    )
    from nnrobust.core.exceptions import ConfigError

    with pytest.raises(ConfigError, match="'learned' has two entries for the case 'paper-ellipse'"):
        load_study(tmp_path / "twice.toml")


def test_the_reports_seed_spread_and_median_rank_only_the_seeds_feasible_on_validation(tmp_path):
    """Three seeds, the least median (0.1 mm) infeasible: the report's spread and median are over
    the two feasible seeds (0.2 and 0.4 mm), and it names the seed left out."""
    from nnrobust.studies.study.report import _controller_entry

    spec = _spec_with(tmp_path, "max_rms_torque = 10.0\n")
    seeds = [
        {"seed": 0, "median_error": 1e-4, "feasible": False, "why_infeasible": "RMS torque 13.1 N m"},
        {"seed": 1, "median_error": 4e-4, "feasible": True, "why_infeasible": ""},
        {"seed": 2, "median_error": 2e-4, "feasible": True, "why_infeasible": ""},
    ]
    kept = {"seed": 2, "settings": {}, "at_bound": [], "median_error": 2e-4, "rows": 2, "completed": 2,
            "feasible": True}  # fmt: skip
    case = {"certify": {"controllers": {}}, "kept": {"pd": kept}, "per_seed": {"pd": seeds}, "stages": {}}
    tuned = _controller_entry(spec, case, "pd")["tuned"]
    assert tuned["seed_spread"] == [2e-4, 4e-4]
    assert tuned["seed_median"] == pytest.approx(3e-4, rel=1e-12)
    assert tuned["infeasible_seeds"] == [0]
