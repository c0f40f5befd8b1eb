"""A study's train stage: a policy entry with a ``train`` table is trained (PPO, each seed, on the
kept setting of the law the study tunes as its base), its seeds validated on the study's own
validation draws beside the tuned law's, the best feasible one kept and certified like every row;
a rerun trains nothing."""

import json

import pytest

pytest.importorskip("distributed")
pytest.importorskip("optuna")
pytest.importorskip("stable_baselines3")

from nnrobust.cli import main  # noqa: E402
from nnrobust.studies.study.case_run import TRAIN_SEED  # noqa: E402

TRAIN = (
    "{algorithm = 'ppo', budget = 0.2, seeds = 2, num_envs = 2, curve_points = 2, curve_episodes = 1, "
    "hyper = {n_steps = 32, batch_size = 64}}"
)
STUDY = (
    """
name = "trained"
cases = ["paper-ellipse-noisy"]
controllers = [
    "pd",
    {name = "ppo-residual", kind = "policy", params = {action = "residual", base = "pd"}, train = TRAIN},
]
""".replace("TRAIN", TRAIN)
    + """require = ["rms_error_after_2s<=0.002"]
seed = 5
[set]
"simulation.duration" = 2.2
[vary]
"plant.disturbance_scale" = {uniform = [0.5, 2.0]}
[budgets]
tune = 4
seeds = 1
train_samples = 1
validation = 2
epsilon = 0.5
beta = 0.2
falsify = 4
second_engine = true
"""
)


@pytest.fixture(scope="module")
def study(tmp_path_factory, scheduler):
    here = tmp_path_factory.mktemp("trained")
    (here / "study.toml").write_text(STUDY)
    out = here / "out"
    argv = ["study", str(here / "study.toml"), "--out", str(out), "--scheduler", scheduler, "--quiet"]
    assert main(argv) == 0
    return here, out, json.loads((out / "report.json").read_text()), argv


def test_each_seed_learns_on_the_kept_setting_and_the_best_on_validation_is_kept(study):
    here, out, report, _ = study
    case = report["cases"]["paper-ellipse-noisy"]
    assert case["stages"]["train"] == "finished"
    pd, policy = case["controllers"]["pd"], case["controllers"]["ppo-residual"]
    folder = out / "cases" / "paper-ellipse-noisy"
    records = [
        json.loads((folder / "train" / f"ppo-residual-seed{s}" / "policy.onnx.json").read_text())
        for s in (0, 1)
    ]
    for s, record in enumerate(records):
        assert record["algorithm"] == "ppo" and record["budget_seconds"] == 0.2
        assert record["seed"] == 5 + TRAIN_SEED + s  # apart from every draw the selection ranks on
        assert (
            record["tuned"]["settings"] == pd["tuned"]["settings"]
        )  # the residual's base: pd's kept setting
    # every seed was validated on the validation draws the tuned law's seeds were, the least
    # median among the feasible ones kept
    seeds = policy["tuned"]["seeds"]
    assert sorted(e["seed"] for e in seeds) == [0, 1]
    feasible = [e for e in seeds if e["feasible"]]
    assert policy["tuned"]["kept_seed"] == min(feasible, key=lambda e: (e["median_error"], e["seed"]))["seed"]
    validation = {row["sample"]: row for row in _rows(folder / "validate")}
    trained = {row["sample"]: row for row in _rows(folder / "validate-train")}
    assert sorted(validation) == sorted(trained) == [0, 1]
    for sample in (0, 1):  # the same plants: the box's draw of each sample
        assert validation[sample]["plant.disturbance_scale"] == trained[sample]["plant.disturbance_scale"]
    # certified like every row, at the kept seed's file with its base at pd's kept setting
    kept = policy["tuned"]["kept_seed"]
    entry = policy["entry"]
    assert entry["params"]["file"].endswith(f"train/ppo-residual-seed{kept}/policy.onnx")
    assert entry["set"] == pd["entry"]["set"]
    assert policy["certificates"] and policy["certificates"][0]["N"] == 3
    assert isinstance(policy["worst"]["falsified"], bool) and policy["worst"]["simulations"] >= 4
    if case["stages"]["engine"] == "finished":  # MuJoCo installed: the same draws on its plant
        assert policy["engines"]["mujoco"]["rows"] == 3
    assert policy["training"]["simulated_seconds"] == pytest.approx(
        sum(r["simulated_seconds"] for r in records)
    )
    assert "PPO, 2 seeds" in policy["training"]["by"]
    convergence = policy["tuned"]["convergence"]
    assert convergence["unit"] == "simulated seconds" and isinstance(convergence["converged"], bool)
    assert (folder / "train" / "ppo-residual" / "curves.csv").is_file()


def test_the_report_draws_the_learning_curves_beside_the_tuned_budgets(study):
    _, out, report, _ = study
    case = report["cases"]["paper-ellipse-noisy"]
    pd = case["controllers"]["pd"]
    assert pd["training"]["simulated_seconds"] == pytest.approx(4 * 2.2)  # 4 simulations of 2.2 s
    html = (out / "report.html").read_text()
    assert "Learning: validation error against simulated seconds of training" in html
    start = html.index("Learning: validation error")
    figure = html[start : html.index("</svg>", start)]
    assert "pd" in figure and "tuning" in figure and "seed 1" in figure


def test_a_rerun_trains_nothing_and_writes_the_same_report(study):
    here, out, report, argv = study
    folder = out / "cases" / "paper-ellipse-noisy" / "train"
    stamps = {p: p.stat().st_mtime_ns for p in folder.rglob("policy.onnx*")}
    assert main(argv) == 0
    assert {p: p.stat().st_mtime_ns for p in folder.rglob("policy.onnx*")} == stamps
    again = json.loads((out / "report.json").read_text())
    policy, before = (
        again["cases"]["paper-ellipse-noisy"]["controllers"]["ppo-residual"],
        report["cases"]["paper-ellipse-noisy"]["controllers"]["ppo-residual"],
    )
    assert policy["tuned"] == before["tuned"] and policy["statistics"] == before["statistics"]


def _rows(folder):
    from nnrobust.studies.sweep import read_results

    return read_results(folder).to_dict("records")


def test_learn_marks_a_studys_tuned_budgets_from_its_report(study):
    """``nnrobust learn --tuned REPORT.json#CASE`` marks each tuned law's own training on its
    curves: the report's seconds for the tuned law, none for the trained policy."""
    from nnrobust.studies.learning.rl import tuned_budgets

    _, out, _, _ = study
    assert tuned_budgets(f"{out / 'report.json'}#paper-ellipse-noisy") == pytest.approx({"pd": 4 * 2.2})
    assert tuned_budgets(out / "cases" / "paper-ellipse-noisy" / "kept.json") == {}


def test_export_of_a_trained_policy_says_why_it_has_no_twin(study, tmp_path, capsys):
    _, out, _, _ = study
    code = main(["export", "paper-ellipse-noisy", "--tuned", f"{out / 'report.json'}#paper-ellipse-noisy",
                 "--controller", "ppo-residual", "--out", str(tmp_path / "x"), "--no-build"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "a learned policy (controller.kind = 'policy') is an ONNX network" in err, err
    assert "export its base law (pd)" in err


def test_a_changed_entry_is_named_by_the_key_that_changed():
    """A study refused over its folder names the entry's key that changed (its train budget),
    not the whole controllers list."""
    from nnrobust.studies.study.engine import _changed

    assert _changed(STUDY, STUDY.replace("budget = 0.2", "budget = 0.3")) == (
        "controllers.ppo-residual.train.budget 0.2 -> 0.3"
    )
    assert _changed(STUDY, STUDY.replace('    "pd",\n', "")).startswith("controllers (their order) ")
