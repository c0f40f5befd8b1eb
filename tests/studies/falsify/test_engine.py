"""nnrobust falsify: the box of a sweep's ranges, the search at one budget with its random
baseline, a worst plant that reruns bit for bit, and a search that resumes."""

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("cma")
pytest.importorskip("distributed")

from nnrobust.cli import main  # noqa: E402
from nnrobust.core.exceptions import ConfigError  # noqa: E402
from nnrobust.studies.falsify import FalsifySpec, box_of, run_falsify  # noqa: E402
from nnrobust.studies.sweep import parse_sweep  # noqa: E402

SWEEP = """name = "fz"
base = "paper-ellipse"
controllers = ["nn"]
seed = 4
[set]
"simulation.duration" = 3.0
[vary]
"plant.disturbance_scale" = {uniform = [0.0, 4.0]}
"plant.friction_scale" = {loguniform = [0.5, 2.0]}
"""


def test_the_box_is_the_sweeps_ranges():
    spec = parse_sweep(
        {
            "name": "b",
            "base": "paper-ellipse",
            "controllers": ["nn"],
            "vary": {
                "plant.disturbance_scale": {"uniform": [0.0, 4.0]},
                "plant.friction_scale": {"loguniform": [0.5, 2.0]},
            },
        }
    )
    box = box_of(spec)
    assert box.values(np.array([0.5, 0.5])) == pytest.approx(
        {"plant.disturbance_scale": 2.0, "plant.friction_scale": 1.0}
    )  # log midpoint
    assert box.values(np.array([1.0, 0.0])) == pytest.approx(
        {"plant.disturbance_scale": 4.0, "plant.friction_scale": 0.5}
    )
    grid = box_of(
        parse_sweep(
            {
                "name": "b",
                "base": "paper-ellipse",
                "controllers": ["nn"],
                "vary": {"plant.disturbance_scale": [0.5, 1.0, 2.0]},
            }
        )
    )
    assert (grid.low.tolist(), grid.high.tolist()) == ([0.5], [2.0])  # the range the grid spans
    for vary, words in (
        ({"controller.k": ["a", "b"]}, "falsify searches ranges"),
        ({"nn.sigma": {"normal": [0.1, 0.02]}}, "not normal"),
        ({}, "varies nothing"),
    ):
        with pytest.raises(ConfigError, match=words):
            box_of(parse_sweep({"name": "b", "base": "paper-ellipse", "controllers": ["nn"], "vary": vary}))


@pytest.mark.parametrize(
    "kwargs, flag",
    [
        ({"budget": 0}, "--budget"),
        ({"budget": 10**9}, "--budget"),
        ({"require": []}, "--require"),
        ({"seed": -1}, "--seed"),
    ],
)
def test_bad_searches_are_refused_with_the_flag_named(kwargs, flag):
    args = {"target": "x.toml", "controllers": ["nn"], "require": ["rms_error<=1"], "budget": 10, **kwargs}
    with pytest.raises(ConfigError, match=flag):
        FalsifySpec(**args)


def test_a_search_finds_the_worst_plant_reruns_it_and_resumes(scheduler, tmp_path, capsys):
    """The error grows with the disturbance: the worst plant found is near the top of its range;
    every controller and its random baseline spend the budget exactly; the printed command
    reproduces the worst plant's metrics bit for bit; the same command again simulates nothing."""
    sweep = tmp_path / "fz.toml"
    sweep.write_text(SWEEP)
    spec = FalsifySpec(str(sweep), ["nn"], ["rms_error<=0.02"], 16, seed=1)
    out = tmp_path / "out"
    summary = run_falsify(spec, out, scheduler=scheduler)
    entry = summary["controllers"]["nn"]
    assert entry["simulations"] == entry["random_baseline"]["simulations"] == 16
    worst = entry["worst"]
    assert worst["values"]["plant.disturbance_scale"] > 3.0
    assert worst["values"]["plant.friction_scale"] < 1.0
    assert entry["falsified"] == (worst["margin"] < 0)
    assert worst["margin"] == pytest.approx((0.02 - worst["metrics"]["rms_error"]) / 0.02, rel=1e-12)
    check_certificate(entry["certificate"], out, "rms_error", 0.02)
    import shlex

    words = shlex.split(worst["command"])
    quiet = ["--quiet", "--no-plots", "--no-animation"]
    assert main([*words[1:], "--out", str(tmp_path / "again"), *quiet]) == 0
    again = json.loads((tmp_path / "again" / "metrics.json").read_text())
    assert again["rms_error"] == worst["metrics"]["rms_error"]
    csv = (out / "falsification.csv").read_text().splitlines()
    assert csv[0] == "system,property,falsified,simulations,time,robustness" and len(csv) == 2
    assert (out / "convergence.png").is_file()
    parts = sorted((out / "history").glob("part-*.parquet"))
    resumed = run_falsify(spec, out, scheduler=scheduler)
    assert sorted((out / "history").glob("part-*.parquet")) == parts  # nothing simulated again
    assert resumed["controllers"]["nn"]["worst"] == worst
    from nnrobust.studies.falsify import keep_worst

    kept = keep_worst(spec, summary, out, 2)  # --keep-worst 2: the two worst plants as run folders
    assert kept == [out / "worst" / "nn", out / "worst" / "nn-2"]
    assert (out / "worst" / "nn" / "animation.html").is_file()
    kept_metrics = [json.loads((k / "metrics.json").read_text()) for k in kept]
    assert kept_metrics[0]["rms_error"] == worst["metrics"]["rms_error"]
    import pandas as pd

    history = pd.read_parquet(out / "history")
    rows = [json.loads(r) for r in history["row"]]
    errors = sorted((r["metrics"]["rms_error"] for r in rows if r["search"] == "falsifier"), reverse=True)
    second = next(e for e in errors if e < worst["metrics"]["rms_error"])  # the next distinct plant
    assert kept_metrics[1]["rms_error"] == pytest.approx(second, rel=1e-12)
    other = FalsifySpec(str(sweep), ["nn"], ["rms_error<=0.03"], 16, seed=1)
    with pytest.raises(Exception, match="holds a different search"):
        run_falsify(other, out, scheduler=scheduler)
    # the search's own outputs replaced, worst/ too
    run_falsify(other, out, scheduler=scheduler, overwrite=True)
    assert not (out / "worst").exists()


def check_certificate(certified: dict, out, metric: str, limit: float) -> None:
    """The random baseline's certificate: N its runs, k those over the limit (read back from the
    history), p_upper scipy's Beta quantile, and no Wilks bound from 16 runs (the 95 % quantile
    with 95 % confidence needs 59)."""
    import pandas as pd
    from scipy.stats import beta

    rows = [json.loads(r) for r in pd.read_parquet(out / "history")["row"]]
    errors = [r["metrics"][metric] for r in rows if r["search"] == "random"]
    k = sum(e > limit for e in errors)
    (cert,) = certified["certificates"]
    assert (cert["N"], cert["k"], cert["epsilon"], cert["beta"]) == (len(errors), k, 0.05, 0.05)
    expected = 1.0 if k == len(errors) else beta.ppf(0.95, k + 1, len(errors) - k)
    assert cert["p_upper"] == pytest.approx(expected, rel=1e-12)
    assert cert["holds"] == (expected <= 0.05)
    assert "random baseline" in cert["method"] and len(cert["distribution"]) == 64
    (bound,) = certified["quantile_bounds"]
    assert bound["bound"] is None and bound["N"] == len(errors)


def test_a_claim_no_sample_can_make_is_one_line_error(tmp_path, capsys):
    sweep = tmp_path / "fz.toml"
    sweep.write_text(SWEEP)
    words = ["falsify", str(sweep), "--controllers", "nn", "--require", "rms_error<=0.02", "--budget", "8"]
    assert main([*words, "--epsilon", "1.5", "--out", str(tmp_path / "out")]) == 2
    assert (
        capsys.readouterr().err.strip()
        == "nnrobust: error: --epsilon: must be a probability in (0, 1), got 1.5"
    )
    assert not (tmp_path / "out").exists()


def test_a_seeded_relative_error_is_searched_as_the_factors_it_draws():
    """nominal.relative_error draws each model parameter off by its own seeded factor in
    [1 - r, 1 + r]: falsify searches those factors instead (6 on the closed-form arm, a mass and an
    inertia per body on the Panda), with relative_error 0, and the plant of a point is the model
    those factors give; both keys varied at once is refused."""
    from nnrobust.run.experiment import build
    from nnrobust.studies.base.plan import Sample, base_config, experiment
    from nnrobust.studies.falsify import searchable
    from nnrobust.studies.sweep import load_sweep

    study = load_sweep("paper-robustness")
    sweep, note = searchable(study, base_config(study))
    factors = [k for k in sweep.vary if k.startswith("nominal.factors")]
    assert (
        factors == [f"nominal.factors[{i}]" for i in range(6)] and "nominal.relative_error" not in sweep.vary
    )
    assert all(sweep.vary[k] == {"uniform": [0.7, 1.3]} for k in factors)
    assert sweep.set["nominal.relative_error"] == 0.0 and "6 factors" in note
    assert study.vary["nominal.relative_error"] == {"uniform": [0.0, 0.3]}  # the study itself untouched
    values = {k: 1.0 + 0.1 * i for i, k in enumerate(factors)} | {"plant.disturbance_scale": 1.0}
    config = experiment(sweep, base_config(sweep), Sample(-1, values, 7), "nn")
    nominal = build(config.replace(simulation={"duration": 0.01})).nominal
    true = build(config.replace(nominal={"factors": None}, simulation={"duration": 0.01})).nominal
    assert np.allclose(nominal.params.beta, np.multiply(true.params.beta, [1.0, 1.1, 1.2]), rtol=1e-12)
    assert np.allclose(nominal.params.p, np.multiply(true.params.p, [1.3, 1.4, 1.5]), rtol=1e-12)
    panda = parse_sweep(
        {
            "name": "p",
            "base": "panda-ellipse",
            "controllers": ["nn"],
            "vary": {"nominal.relative_error": {"uniform": [0.0, 0.2]}},
        }
    )
    expanded, _ = searchable(panda, base_config(panda))
    assert len(box_of(expanded).keys) == 14  # the Panda's 7 bodies: masses, then inertias
    both = parse_sweep(
        {
            "name": "b",
            "base": "paper-ellipse",
            "controllers": ["nn"],
            "vary": {
                "nominal.relative_error": {"uniform": [0, 0.3]},
                "nominal.factors[0]": {"uniform": [0.9, 1.1]},
            },
        }
    )
    with pytest.raises(ConfigError, match="vary one of the two"):
        searchable(both, base_config(both))


def test_the_searched_factors_replace_the_bases_seeded_model_error(tmp_path):
    """A base with a seeded model error (panda-ellipse: relative_error = 0.2) whose box varies it:
    each point runs with relative_error 0, as the printed command sets it, the searched factors
    alone drawing the model (the base's 0.2 was drawn on top of them: [set] took no part)."""
    from nnrobust.studies.base.plan import Sample, experiment, rerun_command
    from nnrobust.studies.falsify.spec import _searched_sweep

    path = tmp_path / "p.toml"
    path.write_text(
        'name = "p"\nbase = "panda-ellipse"\ncontrollers = ["nn"]\n'
        '[vary]\n"nominal.relative_error" = {uniform = [0.0, 0.2]}\n'
    )
    sweep, base, _ = _searched_sweep(FalsifySpec(str(path), ["nn"], ["rms_error<=0.05"], 4))
    values = dict.fromkeys(box_of(sweep).keys, 1.1)
    config = experiment(sweep, base, Sample(-1, values, 1), "nn")
    assert config.nominal.relative_error == 0.0 and config.nominal.factors[0] == 1.1
    assert "nominal.relative_error=0.0" in rerun_command(sweep, Sample(-1, values, 1), "nn")


def test_per_joint_plant_keys_are_coordinates_of_the_box():
    """One joint's friction scale and the disturbance's frequency, searched as box coordinates:
    each point builds the plant it names."""
    from nnrobust.run.experiment import build
    from nnrobust.studies.base.plan import Sample, base_config, experiment

    spec = parse_sweep(
        {
            "name": "b",
            "base": "paper-ellipse",
            "controllers": ["nn"],
            "vary": {
                "plant.joint_friction_scales[1]": {"loguniform": [0.5, 2.0]},
                "plant.disturbance_omega_scale": {"uniform": [0.5, 1.5]},
            },
        }
    )
    box = box_of(spec)
    values = box.values(np.array([1.0, 0.0]))
    plant = build(experiment(spec, base_config(spec), Sample(-1, values, 1), "nn")).plant
    nominal = build(base_config(spec)).plant
    np.testing.assert_allclose(plant.friction.viscous, nominal.friction.viscous * [1.0, 2.0, 1.0])
    np.testing.assert_allclose(plant.disturbance.omega, 0.5 * nominal.disturbance.omega)


def test_the_box_scales_about_its_centre():
    spec = parse_sweep(
        {
            "name": "b",
            "base": "paper-ellipse",
            "controllers": ["nn"],
            "vary": {
                "plant.disturbance_scale": {"uniform": [0.5, 1.5]},
                "plant.friction_scale": {"loguniform": [0.5, 2.0]},
                "nominal.relative_error": {"uniform": [0.0, 0.3]},
            },
        }
    )
    box = box_of(spec)
    double = box.scaled(2.0)
    assert double.low.tolist() == pytest.approx([0.0, 0.25, 0.0])  # relative_error stays >= 0
    assert double.high.tolist() == pytest.approx([2.0, 4.0, 0.45])
    centre = box.scaled(0.0)
    assert centre.low.tolist() == pytest.approx(centre.high.tolist()) and centre.low[1] == pytest.approx(1.0)
    assert box.scaled(1.0).low.tolist() == pytest.approx(box.low.tolist())
    assert box.largest_scale() == pytest.approx(0.9 * 1.0 / 0.5)  # disturbance_scale keeps 10 % of 1


def test_the_margin_brackets_the_scale_where_a_monotone_property_breaks(scheduler, tmp_path, capsys):
    """One coordinate, the disturbance scale in [0.5, 1.5] (centre 1), the task-space PD (whose
    error grows with the disturbance) and a bound on the error met exactly at 1.7, i.e. at s* =
    1.4 times the box: the margin's bracket holds s*, is narrower than 10 % of its top, and its
    violating plant reruns past the bound."""
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import run_experiment

    base = load_preset("paper-ellipse").replace(simulation={"duration": 3.0}, controller={"kind": "pd"})
    errors = [
        run_experiment(base.replace(plant={"disturbance_scale": d})).metrics()["rms_error_after_2s"]
        for d in (1.5, 1.7, 1.9)
    ]
    assert errors[0] < errors[1] < errors[2]  # monotone where it matters
    sweep = tmp_path / "m.toml"
    sweep.write_text(
        'name = "m"\nbase = "paper-ellipse"\ncontrollers = ["pd"]\nseed = 4\n[set]\n'
        '"simulation.duration" = 3.0\n[vary]\n'
        '"plant.disturbance_scale" = {uniform = [0.5, 1.5]}\n'
    )
    spec = FalsifySpec(str(sweep), ["pd"], [f"rms_error_after_2s<={errors[1]!r}"], 64, seed=2, margin=True)
    summary = run_falsify(spec, tmp_path / "out", scheduler=scheduler)
    margin = summary["margin"]["pd"]
    assert not summary["controllers"]["pd"]["falsified"]  # the box itself holds
    assert margin["holds_up_to"] <= 1.4 + 1e-9 <= margin["violated_at"]
    assert margin["violated_at"] - margin["holds_up_to"] <= 0.1 * margin["violated_at"]
    plant = margin["violating_plant"]
    assert plant["values"]["plant.disturbance_scale"] >= 1.7
    assert margin["steps"][0]["scale"] == 1.0 and len(margin["steps"]) <= 8
    import shlex

    words = shlex.split(plant["command"])
    quiet = ["--quiet", "--no-plots", "--no-animation"]
    assert main([*words[1:], "--out", str(tmp_path / "again"), *quiet]) == 0
    assert json.loads((tmp_path / "again" / "metrics.json").read_text())["rms_error_after_2s"] > errors[1]


def test_tuned_settings_are_falsified_as_named_entries(scheduler, tmp_path, capsys):
    """--tuned DIR runs each law at its best setting in a tuning's summary, as NAME-tuned: the
    worst plant's command carries the settings and reruns to its metrics; a law the tuning did
    not tune, or a folder that is not a tuning, is refused naming --tuned."""
    import shlex

    sweep = tmp_path / "fz.toml"
    sweep.write_text(SWEEP)
    tuning = tmp_path / "tuning"
    tuning.mkdir()
    settings = {"controller.pd_Kp": [2000.0], "controller.pd_Kd": [90.0], "controller.pd_null_damping": 0.7}
    summary = {"controllers": {"pd": {"best": {"params": settings}}, "nn": {"best": None}}}
    (tuning / "summary.json").write_text(json.dumps(summary))
    out = tmp_path / "out"
    base = ["falsify", str(sweep), "--require", "rms_error<=0.02", "--budget", "4", "--quiet"]
    on = ["--scheduler", scheduler]
    assert main([*base, *on, "--controllers", "pd", "--tuned", str(tuning), "--out", str(out)]) == 0
    found = json.loads((out / "summary.json").read_text())
    assert list(found["controllers"]) == ["pd-tuned"]
    words = shlex.split(found["controllers"]["pd-tuned"]["worst"]["command"])
    assert "controller.pd_Kp=[2000.0]" in words and "controller.pd_null_damping=0.7" in words
    assert (
        main([*words[1:], "--out", str(tmp_path / "again"), "--quiet", "--no-plots", "--no-animation"]) == 0
    )
    again = json.loads((tmp_path / "again" / "metrics.json").read_text())
    assert again["rms_error"] == found["controllers"]["pd-tuned"]["worst"]["metrics"]["rms_error"]
    capsys.readouterr()
    assert main([*base, "--controllers", "nn", "--tuned", str(tuning), "--out", str(tmp_path / "x")]) == 2
    assert "--tuned" in capsys.readouterr().err
    assert main([*base, "--controllers", "pd", "--tuned", str(tmp_path), "--out", str(tmp_path / "y")]) == 2


def test_a_case_of_a_study_report_gives_its_kept_settings(tmp_path):
    """--tuned REPORT#CASE reads one case of a study's report.json (the shipped
    docs/data/tuned_panda.json): each tuned controller's kept setting, as the study's own
    cases/CASE/kept.json gives it, and nothing for a law the study ran untuned; no case, a wrong
    one, or a case on a plain tuning is refused naming --tuned and the cases there are."""
    from nnrobust.studies.base.tuned import tuned_settings, tuned_target

    data = Path(__file__).parents[3] / "docs" / "data" / "tuned_panda.json"
    report = json.loads(data.read_text())
    case = report["cases"]["panda-ellipse-noisy"]["controllers"]
    found = tuned_settings(f"{data}#panda-ellipse-noisy", ["nn", "rbf-nn"])
    assert found == {n: case[n]["tuned"]["settings"] for n in ("nn", "rbf-nn")}
    assert found["nn"] != tuned_settings(f"{data}#panda-ellipse", ["nn"])["nn"]
    assert tuned_target(f"{data}#panda-ellipse-noisy") == "panda-ellipse-noisy"
    # the same settings as a study folder's kept.json of that case
    kept = {n: {"best": {"params": case[n]["tuned"]["settings"]}} for n in ("nn", "rbf-nn")}
    (tmp_path / "kept.json").write_text(json.dumps({"controllers": kept}))
    assert tuned_settings(tmp_path / "kept.json", ["nn", "rbf-nn"]) == found
    untuned = {**report, "cases": {"c": {"controllers": {"nn": {"tuned": None}}}}}
    (tmp_path / "untuned.json").write_text(json.dumps(untuned))
    assert tuned_settings(f"{tmp_path / 'untuned.json'}#c", ["nn"]) == {}
    for selector, words in (("", "name one of its cases"), ("#panda", "not 'panda'")):
        with pytest.raises(ConfigError, match=f"--tuned: .*{words}"):
            tuned_settings(f"{data}{selector}", ["nn"])
    plain = tmp_path / "summary.json"
    plain.write_text(json.dumps({"controllers": {"nn": {"best": {"params": {}}}}}))
    with pytest.raises(ConfigError, match="not a study's report: drop #x"):
        tuned_settings(f"{plain}#x", ["nn"])


def test_the_header_counts_what_the_folder_held_before_the_search(scheduler, tmp_path, capsys):
    """The first line says how many simulations the folder already held, before any is run: 0 in an
    empty folder (it said "4 of 8", counting the first batch it had just run), all of them when
    the same command runs again, and what is left of a history that lost a part."""
    sweep = tmp_path / "fz.toml"
    sweep.write_text(SWEEP.replace("= 3.0", "= 0.5"))
    out = tmp_path / "out"
    words = ["falsify", str(sweep), "--controllers", "nn", "--require", "rms_error<=0.02"]
    words += ["--budget", "4", "--scheduler", scheduler, "--out", str(out)]

    def header() -> str:
        assert main(words) == 0
        lines = [line for line in capsys.readouterr().err.splitlines() if "already done" in line]
        assert len(lines) == 1, lines
        return lines[0].rpartition("; ")[2]

    assert header() == "0 of 8 already done"
    assert header() == "8 of 8 already done"
    parts = sorted((out / "history").glob("part-*.parquet"))
    import pandas as pd

    kept = len(pd.read_parquet(out / "history")) - len(pd.read_parquet(parts[0]))
    parts[0].unlink()
    assert header() == f"{kept} of 8 already done"


def test_one_coordinate_is_searched_by_a_zooming_grid_without_cma(monkeypatch):
    """CMA-ES does not search one coordinate (cma 3 refuses it; cma 4 failed in ``tell``: "not
    yet initialized (dimension needed)"): after the Sobol start, a grid zooms on the minimum of a
    toy objective, restarts once converged, spends the budget exactly and never builds CMA-ES."""
    import cma

    from nnrobust.studies.falsify.search import _Search

    def refused(*args, **kwargs):
        raise ValueError("Optimization in 1-D is not supported (code was never tested)")

    monkeypatch.setattr(cma, "CMAEvolutionStrategy", refused)
    search, asked = _Search(1, 300, seed=3, random=False), []
    while search.remaining > 0:
        points = search.ask(4)
        asked += [phase for phase, _ in points]
        search.tell(points, [float((u[0] - 0.371) ** 2) for _, u in points])
    assert len(asked) == 300 and set(asked) == {"sobol", "line"} and search.restarts >= 1
    assert abs(search.best[1][0] - 0.371) < 1e-6


def test_a_box_of_one_coordinate_is_falsified_at_a_tiny_budget(scheduler, tmp_path, capsys):
    """The disturbance scale alone, budget 8: the search runs to its end (it crashed in CMA-ES),
    the worst plant at the top of the range, the falsifier and its baseline 8 simulations each."""
    sweep = tmp_path / "one.toml"
    sweep.write_text(
        'name = "one"\nbase = "paper-ellipse"\ncontrollers = ["no-u0"]\nseed = 4\n'
        '[set]\n"simulation.duration" = 0.5\n[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
    )
    spec = FalsifySpec(str(sweep), ["no-u0"], ["rms_error<=0.05"], 8, seed=1)
    entry = run_falsify(spec, tmp_path / "out", scheduler=scheduler)["controllers"]["no-u0"]
    assert entry["simulations"] == entry["random_baseline"]["simulations"] == 8
    assert entry["worst"]["values"]["plant.disturbance_scale"] > 1.9


def test_a_controller_that_cannot_run_is_refused_and_a_refused_run_keeps_its_message(tmp_path):
    """Issue 35, item 4: a controller whose first step returns a torque of the wrong shape is one
    line before any simulation (it was "FALSIFIED in 4 simulations; least margin -inf", with a
    certificate from k = N); a run refused later (a law that raises at t = 0.011 s) is a row whose
    metrics keep the refusal's message (they kept its status alone)."""
    import shutil

    from nnrobust.run.properties import run_properties
    from nnrobust.studies.falsify import evaluate
    from nnrobust.studies.falsify.spec import _searched_sweep

    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", tmp_path / "laws.py")
    sweep = tmp_path / "laws.toml"
    sweep.write_text(
        'name = "laws"\nbase = "paper-ellipse"\ncontrollers = [{name = "shape", class = '
        '"laws.py:WrongShape"}, {name = "late", class = "laws.py:Raises"}]\n[set]\n'
        '"simulation.duration" = 0.2\n[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
    )
    spec = FalsifySpec(str(sweep), ["shape"], ["rms_error<=0.05"], 4)
    with pytest.raises(
        ConfigError, match=r"controllers: shape: cannot run: WrongShape.compute returned a torque"
    ):
        run_falsify(spec, tmp_path / "out", workers=1)
    assert not (tmp_path / "out").exists()
    searched, base, _ = _searched_sweep(FalsifySpec(str(sweep), ["late"], ["rms_error<=0.05"], 4))
    row = evaluate(
        searched, base, "late", {"plant.disturbance_scale": 1.0}, run_properties(["rms_error<=0.05"])
    )
    assert row["metrics"]["status"] == "refused" and row["objective"] < 0
    assert "Raises.compute raised at t = 0.011 s: IndexError" in row["metrics"]["message"]


@pytest.mark.parametrize(
    "settings, words",
    [
        (
            {"pd": {"controller.pd_Kp": [2000.0], "plant.disturbance_scale": 0.0}},
            "sets 'plant.disturbance_scale' for pd, which is not a key pd reads itself",
        ),
        ({"no-u0": {"controller.kind": "pd"}}, "sets 'controller.kind' for no-u0, which is not a key"),
        ({"nn": {"controller.pd_Kp": [2000.0]}}, "sets 'controller.pd_Kp' for nn, which is not a key"),
        (
            {"pd": {"controller.pd_null_damping": 0.7}},
            "sets 'controller.pd_null_damping' for pd, which the box",
        ),
    ],
)
def test_tuned_settings_set_only_the_laws_own_keys_and_none_the_box_varies(settings, words, tmp_path, capsys):
    """Issue 35, item 3: --tuned applied every key of the summary after the box's values, so
    "plant.disturbance_scale": 0.0 ran every point undisturbed while the summary claimed the box,
    and {"controller.kind": "pd"} ran the PD as no-u0-tuned. A tuned setting may set only keys its
    law declares, and none the box varies: one line naming the key and the file, nothing run."""
    sweep = tmp_path / "fz.toml"
    sweep.write_text(SWEEP + '"controller.pd_null_damping" = {uniform = [0.5, 1.0]}\n')
    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"controllers": {n: {"best": {"params": p}} for n, p in settings.items()}}))
    (name,) = settings
    words_ = ["falsify", str(sweep), "--controllers", name, "--require", "rms_error<=0.02", "--budget", "4"]
    assert main([*words_, "--tuned", str(summary), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--tuned: {summary} {words}" in err[0], err
    assert not (tmp_path / "out").exists()
    with pytest.raises(ConfigError, match=f"--tuned: --tuned {words}"):  # the API checks them too
        run_falsify(FalsifySpec(str(sweep), [name], ["rms_error<=0.02"], 4, tuned=settings), tmp_path / "out")


def test_a_search_resumes_only_on_the_inputs_it_was_computed_from(scheduler, tmp_path, capsys):
    """Issue 35, item 1, as the issue ran it: the box's range edited after a search, then the same
    command: it said "16 of 16 already done" and reported a worst plant outside the new box. Now
    an edited box, class file or base experiment is one line naming what changed; the same
    content resumes, from a moved folder too, with nothing simulated again."""
    import shutil

    study = tmp_path / "study"
    study.mkdir()
    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", study / "laws.py")
    (study / "base.toml").write_text('base = "paper-ellipse"\n[simulation]\nduration = 0.3\n')
    (study / "box.toml").write_text(
        'name = "box"\nbase = "base.toml"\ncontrollers = [{name = "eq9", class = "laws.py:Eq9", '
        'params = {Kp = 10.0, Kv = 4.0}}]\n[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
    )

    def search(where) -> tuple[int, list[str]]:
        capsys.readouterr()
        words = ["falsify", str(where / "box.toml"), "--controllers", "eq9", "--require", "rms_error<=0.05"]
        code = main([*words, "--budget", "4", "--scheduler", scheduler, "--out", str(where / "f")])
        return code, capsys.readouterr().err.strip().splitlines()

    assert search(study)[0] == 0
    for name, old, new, words in (
        (
            "box.toml",
            "[0.5, 2.0]",
            "[5.0, 6.0]",
            "[vary] plant.disturbance_scale was {{uniform = [0.5, 2.0]}}, now {{uniform = [5.0, 6.0]}}",
        ),
        (
            "laws.py",
            "import numpy",
            "# edited\nimport numpy",
            "the class file of controller eq9, {}, has changed",
        ),
        ("base.toml", "duration = 0.3", "duration = 0.31", "the base experiment, {}, has changed"),
    ):
        text = (study / name).read_text()
        (study / name).write_text(text.replace(old, new, 1))
        code, err = search(study)
        expected = f"{study / 'f'} holds a different search: {words.format((study / name).resolve())}"
        assert code == 2 and len(err) == 1 and expected in err[0] and "pass --overwrite" in err[0], err
        (study / name).write_text(text)
    parts = sorted(p.name for p in (study / "f" / "history").glob("part-*.parquet"))
    shutil.move(study, tmp_path / "moved")
    code, err = search(tmp_path / "moved")
    assert code == 0 and any(line.endswith("8 of 8 already done") for line in err), err
    assert sorted(p.name for p in (tmp_path / "moved" / "f" / "history").glob("part-*.parquet")) == parts


def test_a_custom_laws_tuned_settings_are_falsified_as_a_shipped_laws(scheduler, tmp_path, monkeypatch):
    """--tuned takes a class given as file.py:Class (found in the summary under its class name):
    it runs as CLASS-tuned at exactly the tuned params, which its worst plant's command carries."""
    import shlex
    import shutil

    shutil.copy(Path(__file__).parents[2] / "controllers" / "eq9_again.py", tmp_path / "laws.py")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "fz.toml").write_text(SWEEP)
    tuning = tmp_path / "tuning"
    tuning.mkdir()
    settings = {"controller.params.Kp": 400.0, "controller.params.Kv": 40.0}
    (tuning / "summary.json").write_text(json.dumps({"controllers": {"Eq9": {"best": {"params": settings}}}}))
    argv = ["falsify", "fz.toml", "--require", "rms_error<=0.02", "--budget", "4", "--quiet"]
    on = ["--scheduler", scheduler]
    assert main([*argv, *on, "--controllers", "laws.py:Eq9", "--tuned", "tuning", "--out", "out"]) == 0
    found = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert list(found["controllers"]) == ["Eq9-tuned"]
    words = shlex.split(found["controllers"]["Eq9-tuned"]["worst"]["command"])
    assert "controller.params.Kp=400.0" in words and "controller.params.Kv=40.0" in words


def test_a_bad_tuned_value_is_blamed_on_the_tuned_setting_not_a_sample(tmp_path, capsys):
    (tmp_path / "fz.toml").write_text(SWEEP)
    tuning = tmp_path / "tuning"
    tuning.mkdir()
    (tuning / "summary.json").write_text(
        json.dumps({"controllers": {"pd": {"best": {"params": {"controller.pd_Kp": "x"}}}}})
    )
    argv = ["falsify", str(tmp_path / "fz.toml"), "--require", "rms_error<=0.02", "--budget", "4"]
    assert main([*argv, "--controllers", "pd", "--tuned", str(tuning), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--tuned: the tuned setting of pd: controller.pd_Kp: expected a list, got str 'x'" in err, err
    assert "sample" not in err


def test_a_search_is_the_same_on_one_worker_and_on_two(tmp_path):
    """The points asked do not depend on the cluster: the search, its random baseline and the
    margin's bracket give the same summary on 1 and 2 workers (the time aside)."""
    sweep = tmp_path / "w.toml"
    sweep.write_text(SWEEP.replace('"simulation.duration" = 3.0', '"simulation.duration" = 0.4'))
    spec = FalsifySpec(str(sweep), ["nn"], ["max_error<=0.002"], 12, seed=1, margin=True)
    one, two = (run_falsify(spec, tmp_path / f"on-{w}", workers=w) for w in (1, 2))
    for summary in (one, two):
        summary.pop("seconds")
    assert json.dumps(one, sort_keys=True, default=float) == json.dumps(two, sort_keys=True, default=float)
    assert one["margin"]["nn"]["steps"] and one["controllers"]["nn"]["simulations"] == 12


def test_a_plant_only_the_random_baseline_found_falsifies_the_box(tmp_path):
    """The random baseline's points are plants of the box: a violation only it found falsifies
    (falsified, falsified_by ["random"]), and the margin's scale 1 counts it, so the margin is
    bracketed below the box instead of above it. Synthetic histories: the search holds
    everywhere, the baseline's third plant violates, and every scaled search holds."""
    from nnrobust.run.properties import run_properties
    from nnrobust.studies.base.plan import Sample, rerun_command, sample_seed
    from nnrobust.studies.falsify.search import _Margins
    from nnrobust.studies.falsify.spec import _searched_sweep
    from nnrobust.studies.falsify.summary import _summary, replayed_worst

    sweep_file = tmp_path / "fz.toml"
    sweep_file.write_text(SWEEP)
    spec = FalsifySpec(str(sweep_file), ["pd"], ["rms_error<=0.02"], 4, margin=True)
    sweep, _, _ = _searched_sweep(spec)
    box = box_of(sweep)

    def row(objective):
        values = dict(zip(box.keys, box.values(np.full(len(box.keys), 0.5))))
        margins = {"rms_error<=0.02": objective}
        return {"values": values, "metrics": {"rms_error": 0.02 * (1 - objective)}, "margins": margins,
                "objective": objective}  # fmt: skip

    rows = {("pd", "falsifier"): [row(0.5)] * 4, ("pd", "random"): [row(0.4), row(0.3), row(-0.2), row(0.1)]}
    summary = _summary(
        spec, sweep, box, run_properties(spec.require), rows, 1.0, rerun_command, Sample, sample_seed
    )
    entry = summary["controllers"]["pd"]
    assert entry["falsified"] and entry["falsified_by"] == ["random"] and entry["first_violation"] is None
    assert entry["random_baseline"]["first_violation"] == 3
    # the plant the CLI, the notebook display and a study's report replay: the baseline's
    assert replayed_worst(entry) == (entry["random_baseline"]["worst"], "random")

    margins = _Margins(spec, sweep, box, rows)
    assert margins(("pd", "falsifier")) is None  # the scales wait for the baseline too
    following = margins(("pd", "random"))
    while following is not None:  # every scaled search holds
        key, search, _ = following
        assert search.stop_at_violation and key[1].startswith("margin ")
        rows[key] = [row(0.5)]
        following = margins(key)
    margin = margins.result()["pd"]
    assert margin["steps"][0] == {"scale": 1.0, "falsified": True, "simulations": 8, "least_margin": -0.2}
    assert margin["violated_at"] == 1.0 and margin["holds_up_to"] < 1.0


def test_a_controllers_search_does_not_depend_on_the_others_in_its_run(scheduler, tmp_path):
    """The PD searched alone and beside the NN (same box, budget, seed, property): its worst
    plant, its whole history of points and its margin are the same. (CMA-ES sampled from NumPy's
    global generator, shared by the searches running in step, and the margins were seeded by
    their place among the controllers still searching: the PD's worst plant moved when the NN
    joined.)"""
    import pandas as pd

    box = tmp_path / "box.toml"
    box.write_text(
        SWEEP.replace('"simulation.duration" = 3.0', '"simulation.duration" = 2.5')
        + '"nominal.factors[0]" = {uniform = [0.7, 1.3]}\n'
    )
    found = {}
    for controllers in (["pd"], ["nn", "pd"]):
        out = tmp_path / "-".join(controllers)
        spec = FalsifySpec(str(box), controllers, ["rms_error_after_2s<=0.004"], 24, seed=1, margin=True)
        summary = run_falsify(spec, out, scheduler=scheduler)
        history = pd.read_parquet(out / "history")
        points = history[history["controller"] == "pd"].sort_values(["search", "index"])
        found[len(controllers)] = (summary["controllers"]["pd"], summary["margin"]["pd"], points)
    (alone, margin_alone, points_alone), (beside, margin_beside, points_beside) = found[1], found[2]
    assert alone["worst"]["values"] == beside["worst"]["values"]
    assert alone["random_baseline"]["worst"]["values"] == beside["random_baseline"]["worst"]["values"]
    assert margin_alone == margin_beside and len(margin_alone["steps"]) > 1
    columns = ["search", "index", *(c for c in points_alone.columns if c.startswith("value."))]
    assert points_alone[columns].to_numpy().tolist() == points_beside[columns].to_numpy().tolist()
