import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import ConfigError, NNRobustError
from nnrobust.run.experiment import build
from nnrobust.studies.tune import TuneSpec, arm_scales, run_tune, search_space
from nnrobust.studies.tune.engine import CONSTRAINTS, judge, sweep_of

pytest.importorskip("optuna")
pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def scales():
    return arm_scales(build(load_preset("paper-ellipse-noisy")))


def test_the_spaces_come_from_the_arm_and_share_their_gain_coordinates(scales):
    """Every controller searches the same bandwidth range, capped where the hold and the delay
    cost a radian of phase; the PD's gains carry the task-space inertia, eq. (9)'s do not."""
    T, d = 1e-3, 1  # paper-ellipse-noisy: 1 ms, one period of delay
    assert scales["period"] == T and scales["delay"] == d
    spaces = {c: search_space(c, scales) for c in ("nn", "no-u0", "pd", "sliding-mode")}
    for space in spaces.values():
        w = space.param("bandwidth")
        assert w.high == pytest.approx(1 / ((0.5 + d) * T)) and w.high_reason
        assert w.low == pytest.approx(2 * math.pi / 20.0)
    assert spaces["nn"].param("damping_ratio").low > 0.5  # eq. (17): Kv^2 > Kp
    # one rule for the damping ratio: from 0.2 and widened like any bound, but where the robust
    # term is built on eq. (16)'s P (the NN, the sliding mode), whose eq. (17) needs z > 1/2
    for name, space in spaces.items():
        z = space.param("damping_ratio")
        assert (z.low, bool(z.reason("low"))) == (
            (0.51, True) if name in ("nn", "sliding-mode") else (0.2, False)
        )
    values = {"bandwidth": 100.0, "damping_ratio": 0.8}
    eq9 = search_space("no-u0", scales).overrides({**values, "controller.k": 5.0})
    assert eq9["controller.Kp"] == [1e4] and eq9["controller.Kv"] == [160.0]
    assert eq9["controller.Kv"][0] ** 2 > eq9["controller.Kp"][0]
    pd_ = spaces["pd"].overrides({**values, "controller.pd_null_damping": 1.0})
    lam = scales["task_inertia"]
    assert pd_["controller.pd_Kp"] == [pytest.approx(lam * 1e4)]
    assert pd_["controller.pd_Kd"] == [pytest.approx(2 * 0.8 * lam * 100.0)]
    assert {p.name for p in spaces["nn"].params} >= {"nn.F", "leakage_rate", "nn.eps_min", "controller.k"}
    assert {p.name for p in spaces["sliding-mode"].params} >= {
        "controller.sliding_gain",
        "controller.sliding_boundary",
    }


def test_eq17s_condition_is_checked_only_where_the_robust_term_needs_it():
    """Kv^2 <= Kp (z < 1/2: an underdamped loop) is refused for the NN and the sliding mode, whose
    u_0 is built on eq. (16)'s P, and accepted for eq. (9) without such a term."""
    from nnrobust.run.experiment import build

    gains = {"Kp": [20.0], "Kv": [4.0]}
    for kind in ("no-u0", "computed-torque"):
        build(load_preset("paper-ellipse").replace(controller={"kind": kind, **gains}))
    for kind in ("nn", "sliding-mode"):
        with pytest.raises(ConfigError, match="eq. \\(17\\)"):
            build(load_preset("paper-ellipse").replace(controller={"kind": kind, **gains}))


def test_the_task_inertia_is_that_of_the_arm(scales):
    """lambda is the geometric mean of the eigenvalues of (J M^-1 J^T)^-1 at q(0)."""
    setup = build(load_preset("paper-ellipse-noisy"))
    J, M = setup.robot.task_jacobian(setup.q0), setup.robot.mass(setup.q0)
    eig = np.linalg.eigvalsh(np.linalg.inv(J @ np.linalg.solve(M, J.T)))
    assert scales["task_inertia"] == pytest.approx(np.sqrt(eig.prod()), rel=1e-9)


def test_a_best_setting_on_a_bound_widens_it_unless_the_bound_is_physical(scales):
    space = search_space("nn", scales)
    w, F = space.param("bandwidth"), space.param("nn.F")
    values = {p.name: math.sqrt(p.low * p.high) for p in space.params}
    values.update({"bandwidth": w.high, "nn.F": F.low})
    edges = {(b["param"], b["side"]) for b in space.at_bound(values)}
    assert edges == {("bandwidth", "high"), ("nn.F", "low")}
    wider, moved = space.widened(values)
    assert wider.param("bandwidth").high == w.high  # sampling: physical
    assert wider.param("nn.F").low == pytest.approx(F.low / 10)
    assert moved == [{"param": "nn.F", "side": "low", "old": F.low, "bound": wider.param("nn.F").low}]
    assert space.widened(values, skip=lambda name, side: name == "nn.F")[1] == []
    assert space.widened({p.name: math.sqrt(p.low * p.high) for p in space.params}) == (space, [])


def _drive(controller, objective, until: int) -> None:
    """Run a _Controller's ask/tell/record loop on a synthetic objective of its values."""

    def metrics(values):
        return {
            "status": "completed",
            "rms_error_after_2s": objective(values),
            "rms_torque": 1.0,
            "torque_chatter": 0.0,
            "saturated_fraction": 0.0,
            "runaway": False,
            "max_joint_limit_violation": 0.0,
        }

    while len(controller.rows) < until:  # as run_tune: tell a batch, then record it
        rows = [controller.tell(t, v, phase, [metrics(v)]) for t, v, phase in controller.ask(2)]
        for row in rows:
            controller.record(row)


def test_a_bound_is_widened_until_the_best_is_interior_with_a_worse_probe_beyond_it():
    """An optimum two and a half decades past a non-physical bound: from half the budget on the
    bound moves out a decade at a time, each move probed half a decade beyond the old bound,
    until the best is interior; resuming from the rows asks what the uninterrupted search asks."""
    from nnrobust.studies.tune.search import ControllerSearch as _Controller
    from nnrobust.studies.tune.space import Param, SearchSpace

    space = SearchSpace("toy", (Param("controller.params.x", 1.0, 10.0, "-"),), custom=True)
    spec = TuneSpec("paper-ellipse", ["toy"], 60, validation=0)
    toy = _Controller(spec, "toy", space)
    x = "controller.params.x"
    objective = lambda v: (math.log10(v[x]) - 2.5) ** 2 + 1e-3  # noqa: E731
    _drive(toy, objective, 38)
    resumed = _Controller(spec, "toy", space)
    for row in [dict(r) for r in toy.rows]:
        resumed.record(row)
    _drive(toy, objective, 60)
    _drive(resumed, objective, 60)
    assert [r["search"] for r in resumed.rows] == [r["search"] for r in toy.rows]
    assert toy.widenings and all(w["trial"] >= 30 for w in toy.widenings)  # from half the budget on
    probes = [r for r in toy.rows if r["queued"]]
    assert [r["search"][x] for r in probes] == pytest.approx([w["probe"] for w in toy.widenings])
    assert [w["old"] for w in toy.widenings] == pytest.approx([10.0 ** (k + 1) for k in range(len(probes))])
    best = toy.best()
    assert toy.space.at_bound(best["search"]) == []
    assert 10**2 < best["search"][x] < 10**3 and toy.space.param(x).high == pytest.approx(1e3)
    beyond = [r for r in toy.rows if r["search"][x] > best["search"][x]]
    assert beyond and all(
        r["train"]["rms_error_after_2s"] > best["train"]["rms_error_after_2s"] for r in beyond
    )


def test_the_leakage_is_searched_as_its_rate_between_physical_bounds(scales):
    """sigma enters the adaptation only as F sigma: its bounds are one control period (F sigma T
    = 1) and 1 % over the run (F sigma D = 0.01), never widened, and sigma = rate / F."""
    space = search_space("nn", scales)
    rate = space.param("leakage_rate")
    assert rate.high == pytest.approx(1 / scales["period"]) and rate.high_reason.startswith("sampling")
    assert rate.low == pytest.approx(0.01 / scales["duration"]) and rate.low_reason
    values = {p.name: math.sqrt(p.low * p.high) for p in space.params}
    for end in (rate.low, rate.high):
        assert space.widened({**values, "leakage_rate": end})[0].param("leakage_rate") == rate
    out = space.overrides({**values, "leakage_rate": 2.0, "nn.F": 0.5})
    assert out["nn.sigma"] == pytest.approx(4.0) and "leakage_rate" not in out
    assert space.weakest()["leakage_rate"] == rate.high


def test_the_constraints_judge_a_setting_on_all_its_samples():
    spec = TuneSpec("paper-ellipse", ["pd"], 10, max_rms_torque=5.0, max_saturated=0.01)
    good = {
        "status": "completed",
        "rms_error_after_2s": 1e-3,
        "rms_torque": 4.0,
        "torque_chatter": 0.1,
        "saturated_fraction": 0.0,
        "runaway": False,
        "max_joint_limit_violation": 0.0,
    }
    objectives, constraints, mean = judge(spec, [good, {**good, "rms_torque": 5.5}])
    assert objectives[1] == pytest.approx(4.75) and all(c <= 0 for c in constraints)
    _, constraints, _ = judge(spec, [good, {**good, "rms_torque": 7.0}])
    assert constraints[CONSTRAINTS.index("rms_torque_over_limit")] > 0
    _, constraints, _ = judge(spec, [good, {**good, "max_joint_limit_violation": 0.01}])
    assert constraints[CONSTRAINTS.index("joint_limit_violation")] > 0
    objectives, constraints, _ = judge(spec, [good, {"status": "diverged"}])
    assert all(c > 0 for c in constraints) and objectives[0] >= 1.0


@pytest.mark.parametrize(
    "kwargs, flag",
    [
        ({"budget": 0}, "--budget"),
        ({"budget": 10**9}, "--budget"),
        ({"controllers": ["lqr"]}, "--controllers"),
        ({"controllers": ["pd", "pd"]}, "--controllers"),
        ({"controllers": []}, "--controllers"),
        ({"max_rms_torque": float("nan")}, "--max-rms-torque"),
        ({"max_saturated": 2.0}, "--max-saturated"),
        ({"budget": 3, "train_samples": 4}, "--budget"),
    ],
)
def test_bad_tunings_are_refused_with_the_flag_named(kwargs, flag):
    args = {"target": "paper-ellipse", "controllers": ["pd"], "budget": 10, **kwargs}
    with pytest.raises(ConfigError, match=flag):
        sweep_of(TuneSpec(**args))  # the controllers are resolved against the target


def test_a_sweep_with_a_grid_is_refused_and_its_distributions_are_the_samples(tmp_path):
    grid = tmp_path / "grid.toml"
    grid.write_text(
        'name = "g"\nbase = "paper-ellipse"\ncontrollers = ["pd"]\n[vary]\n'
        '"plant.friction_scale" = [0.5, 2.0]\n'
    )
    with pytest.raises(ConfigError, match="grid"):
        sweep_of(TuneSpec(str(grid), ["pd"], 10))
    drawn = tmp_path / "drawn.toml"
    drawn.write_text(
        'name = "d"\nbase = "paper-ellipse"\ncontrollers = ["pd"]\n[vary]\n'
        '"plant.friction_scale" = {loguniform = [0.5, 2.0]}\n'
    )
    sweep = sweep_of(TuneSpec(str(drawn), ["pd", "nn"], 10, train_samples=2, validation=3))
    assert sweep.samples == 5 and sweep.controllers == ["pd", "nn"]


@pytest.fixture(scope="module")
def short_experiment(tmp_path_factory):
    path = tmp_path_factory.mktemp("tune") / "short.toml"
    config = load_preset("paper-ellipse-noisy").replace(simulation={"duration": 2.5})
    path.write_text(config.to_toml())
    return path


@pytest.fixture(scope="module")
def tuned(scheduler, short_experiment, tmp_path_factory):
    out = tmp_path_factory.mktemp("tune") / "out"
    spec = TuneSpec(
        str(short_experiment),
        ["no-u0", "pd"],
        8,
        train_samples=2,
        validation=2,
        max_rms_torque=10.0,
        max_saturated=0.01,
        seed=3,
    )
    return spec, out, run_tune(spec, out, scheduler=scheduler)


def test_every_controller_gets_the_same_budget_samples_and_constraints(tuned):
    import pandas as pd

    spec, out, summary = tuned
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk == json.loads(json.dumps(summary, default=float))
    assert [s["sample"] for s in summary["train_samples"]] == [0, 1]
    assert [s["sample"] for s in summary["validation_samples"]] == [2, 3]  # never searched on
    seeds = {s["seed"] for s in summary["train_samples"]} | {s["seed"] for s in summary["validation_samples"]}
    assert len(seeds) == 4
    trials = pd.read_parquet(out / "trials")
    for name, entry in summary["controllers"].items():
        assert entry["simulations"] == spec.budget
        assert (trials["controller"] == name).sum() == spec.trials
        best = entry["best"]
        assert best is not None and best["train"]["rms_torque"] <= 10.0
        assert set(best["validation"]) >= {"rms_error_after_2s", "rms_torque", "torque_chatter"}
        assert best["train"]["rms_error_after_2s"] == min(
            json.loads(r)["train"]["rms_error_after_2s"]
            for r, f in zip(trials["row"], trials["feasible"])
            if f and json.loads(r)["controller"] == name
        )
        assert all(p["train"]["rms_torque"] <= 10.0 for p in entry["pareto"])
    assert (out / "pareto.png").stat().st_size > 10_000


def test_a_tuning_is_the_same_on_one_worker_and_on_two(short_experiment, tmp_path):
    """The settings asked each round do not depend on the cluster: one training sample (where
    the batch was the number of workers) gives the same trials and best on 1 and 2 workers."""
    from nnrobust.studies.base.folder import recorded_inputs
    from nnrobust.studies.tune.engine import _read_trials

    spec = TuneSpec(str(short_experiment), ["pd"], 6, train_samples=1, validation=1, seed=1)
    best, asked = [], []
    for workers in (1, 2):
        folder = tmp_path / f"on-{workers}"
        best.append(run_tune(spec, folder, workers=workers)["controllers"]["pd"]["best"]["params"])
        rows = _read_trials(folder, recorded_inputs(folder, "tune").key)
        asked.append([row["params"] for row in sorted(rows, key=lambda row: row["trial"])])
    assert asked[0] == asked[1] and len(asked[0]) == 6
    assert best[0] == best[1]


def test_a_controllers_trials_do_not_depend_on_the_others_running_beside_it(scheduler, tuned, tmp_path):
    """The controllers' rounds run side by side (each is told and asks again while the others'
    simulations run: nnrobust.studies.base.cluster.run_task_groups); each optimiser asks from its own
    rows alone, so no-u0 tuned alone asks, row by row, what it asked beside the PD."""
    from nnrobust.studies.base.folder import recorded_inputs
    from nnrobust.studies.tune.engine import _read_trials

    spec, out, _ = tuned
    alone = replace(spec, controllers=["no-u0"])
    run_tune(alone, tmp_path / "alone", scheduler=scheduler)

    def trials(folder):
        rows = _read_trials(folder, recorded_inputs(folder, "tune").key)
        return [(r["trial"], r["params"], r["train"]) for r in rows if r["controller"] == "no-u0"]

    assert trials(tmp_path / "alone") == trials(out) and len(trials(out)) == spec.trials


def test_reordering_the_controllers_changes_no_laws_tuning(scheduler, tuned, tmp_path):
    """A law's optimiser seed derives from the tuning's seed and the law's name, not its place in
    the list: the PD and no-u0 tuned in the other order ask, row by row, what they asked (with
    seed + index, the PD's sampler seed moved with the order)."""
    from nnrobust.studies.base.folder import recorded_inputs
    from nnrobust.studies.tune.engine import _read_trials

    spec, out, summary = tuned
    reordered = replace(spec, controllers=list(reversed(spec.controllers)))
    again = run_tune(reordered, tmp_path / "reordered", scheduler=scheduler)

    def trials(folder, name):
        rows = _read_trials(folder, recorded_inputs(folder, "tune").key)
        return [(r["trial"], r["params"], r["train"]) for r in rows if r["controller"] == name]

    for name in spec.controllers:
        assert trials(tmp_path / "reordered", name) == trials(out, name), name
        assert again["controllers"][name]["best"] == summary["controllers"][name]["best"]


def test_a_setting_that_breaks_a_constraint_on_the_held_out_draws_says_so():
    """Feasibility is judged on the draws each table column is computed from: a best setting whose
    held-out runs break the torque and saturation limits is marked infeasible on validation, with
    the numbers, beside its training columns (it was a held-out error beside a training torque)."""
    from nnrobust.cli.studies import format_tuning
    from nnrobust.studies.tune.engine import validated

    spec = TuneSpec("paper-ellipse", ["pd"], 4, max_rms_torque=10.0, max_saturated=0.01)
    run = {"status": "completed", "rms_error_after_2s": 1e-4, "torque_chatter": 1.0,
           "max_joint_limit_violation": 0.0, "runaway": False}  # fmt: skip
    train = [{**run, "rms_torque": 8.0, "saturated_fraction": 0.0}]
    held = [{**run, "rms_torque": 13.1, "saturated_fraction": 0.079}, {**run, "rms_torque": 12.0,
            "saturated_fraction": 0.0}]  # fmt: skip
    judged = validated(spec, held)
    assert judged["validation_feasible"] is False and judged["validation"]["rms_torque"] == pytest.approx(
        12.55
    )
    assert validated(spec, train)["validation_feasible"] is True
    best = {"params": {"controller.pd_Kp": [100.0]}, "train": judge(spec, train)[2], **judged, "at_bound": []}
    summary = {"constraints": {"max_rms_torque": 10.0, "max_saturated": 0.01},
               "controllers": {"pd": {"best": best}}}  # fmt: skip
    text = format_tuning(summary)
    assert "training draws" in text and "held-out draws" in text
    assert "infeasible on validation: RMS torque 12.6 N m > 10 N m, saturated 7.9 % > 1 %" in text, text


def test_the_cpp_and_python_twins_tune_to_the_same_setting(scheduler, short_experiment, tmp_path):
    """The task-space PD in C++ (examples/controllers/task_pd.cpp) and its Python twin
    (examples/custom_controller.py), both named TaskPD, tuned apart at one seed and budget: their
    torques agree to 1e-14, so their optimisers ask the same settings and keep the same best."""
    from nnrobust.run.compiled import available

    if not available():
        pytest.skip("the compiled loop is not built: a law in C++ runs there")
    examples = Path(__file__).resolve().parents[3] / "examples"
    best = []
    for file in (examples / "controllers" / "task_pd.cpp", examples / "custom_controller.py"):
        spec = TuneSpec(str(short_experiment), [f"{file}:TaskPD"], 6, train_samples=1, validation=0, seed=2)
        summary = run_tune(spec, tmp_path / file.suffix[1:], scheduler=scheduler)
        best.append(summary["controllers"]["TaskPD"]["best"])
    assert best[0]["params"] == best[1]["params"]
    assert best[0]["train"]["rms_error_after_2s"] == pytest.approx(
        best[1]["train"]["rms_error_after_2s"], rel=1e-9
    )


def test_a_best_setting_reruns_to_its_training_metrics(tuned):
    """The summary's params are the overrides the runs used: rerunning sample 0 gives its row."""
    from nnrobust.config import apply_overrides
    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.base.plan import base_config, draw, experiment

    spec, out, summary = tuned
    sweep = sweep_of(spec)
    best = summary["controllers"]["pd"]["best"]
    runs = []
    for sample in (0, 1):
        sample_config = experiment(sweep, base_config(sweep), draw(sweep, sample), "pd")
        config = apply_overrides(sample_config, best["params"])
        runs.append(run_experiment(config).metrics()["rms_error_after_2s"])
    assert np.mean(runs) == pytest.approx(best["train"]["rms_error_after_2s"], rel=1e-9)


def test_the_same_command_resumes_and_a_different_one_is_refused(scheduler, tuned, short_experiment):
    spec, out, summary = tuned
    again = run_tune(spec, out, scheduler=scheduler)
    assert again["controllers"]["pd"]["best"]["params"] == summary["controllers"]["pd"]["best"]["params"]
    import pandas as pd

    assert len(pd.read_parquet(out / "trials")) == 2 * spec.trials  # nothing ran twice
    other = TuneSpec(str(short_experiment), ["no-u0", "pd"], 10, train_samples=2, validation=2, seed=3)
    with pytest.raises(NNRobustError, match="different tuning"):
        run_tune(other, out, scheduler=scheduler)


def test_tune_refuses_a_folder_it_did_not_write(tmp_path, short_experiment):
    (tmp_path / "notes.md").write_text("mine")
    code = main(
        [
            "tune",
            str(short_experiment),
            "--controllers",
            "pd",
            "--budget",
            "4",
            "--out",
            str(tmp_path),
            "--quiet",
        ]
    )
    assert code == 2 and (tmp_path / "notes.md").read_text() == "mine"
    assert (
        main(["tune", "paper-ellipse", "--controllers", "lqr", "--budget", "4", "--out", str(tmp_path / "x")])
        == 2
    )


def test_a_robust_law_tunes_its_gains_first_then_starts_from_them_with_the_term_at_its_weakest(
    scheduler, short_experiment, tmp_path
):
    """Sliding mode: the first 30 % of its budget run the no-u0 law (u_0 off) over the gains alone;
    the full search then starts from the best gains with K at its low and Phi at its high bound,
    and its best is chosen among runs of the law itself."""
    import pandas as pd

    spec = TuneSpec(str(short_experiment), ["sliding-mode"], 10, validation=0, max_rms_torque=10.0, seed=1)
    summary = run_tune(spec, tmp_path / "out", scheduler=scheduler)
    rows = sorted(
        (json.loads(r) for r in pd.read_parquet(tmp_path / "out" / "trials")["row"]), key=lambda r: r["trial"]
    )
    gains = [r for r in rows if r["phase"] == "gains"]
    assert [r["trial"] for r in gains] == [0, 1, 2] and all(r["law"] == "no-u0" for r in gains)
    assert all(set(r["search"]) == {"bandwidth", "damping_ratio", "controller.k"} for r in gains)
    first = rows[3]
    space = search_space("sliding-mode", arm_scales(build(load_preset("paper-ellipse-noisy"))))
    best_gains = min((r for r in gains if r["feasible"]), key=lambda r: r["train"]["rms_error_after_2s"])
    assert first["law"] == "sliding-mode"
    assert {k: first["search"][k] for k in best_gains["search"]} == best_gains["search"]
    weakest = space.weakest()
    assert first["search"]["controller.sliding_gain"] == pytest.approx(weakest["controller.sliding_gain"])
    assert first["search"]["controller.sliding_boundary"] == pytest.approx(
        weakest["controller.sliding_boundary"]
    )
    entry = summary["controllers"]["sliding-mode"]
    assert "controller.sliding_gain" in entry["best"]["params"] and entry["simulations"] == 10


def test_a_custom_class_is_tuned_in_the_space_it_declares(scheduler, short_experiment, tmp_path):
    """--controllers takes file.py:Class: its declared search_space is searched at the same budget
    and samples as a shipped law, and its best setting reruns to its training metrics."""
    from pathlib import Path

    from nnrobust.config import apply_overrides
    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.base.plan import base_config, draw, experiment

    laws = Path(__file__).parents[2] / "controllers" / "eq9_again.py"
    spec = TuneSpec(str(short_experiment), ["no-u0", f"{laws}:Eq9"], 6, train_samples=2, validation=1, seed=5)
    summary = run_tune(spec, tmp_path / "out", scheduler=scheduler)
    assert set(summary["controllers"]) == {"no-u0", "Eq9"}
    entry = summary["controllers"]["Eq9"]
    assert set(entry["space"]) == {"controller.params.Kp", "controller.params.Kv"}
    assert entry["simulations"] == summary["controllers"]["no-u0"]["simulations"]
    best = entry["best"]
    assert best is not None, entry
    assert set(best["params"]) == {"controller.params.Kp", "controller.params.Kv"}
    sweep = sweep_of(spec)
    runs = [
        run_experiment(
            apply_overrides(experiment(sweep, base_config(sweep), draw(sweep, s), "Eq9"), best["params"])
        ).metrics()["rms_error_after_2s"]
        for s in (0, 1)
    ]
    assert np.mean(runs) == pytest.approx(best["train"]["rms_error_after_2s"], rel=1e-9)


def test_a_registered_law_is_tuned_in_the_space_it_declares(scheduler, short_experiment, tmp_path):
    """slotine-li declares Lambda (up to the sampling limit, never widened), K_D_step (up to the
    law's own limit 1, never widened), the adaptation's gamma and leakage (weakest at gamma's low
    and leakage's high end) and the null-space damping k_n (issue 37: held at 1 it capped
    K_D_step near 0.5, its null-space step K_D_step (1 + k_n) at 1): the tuner
    searches exactly those at the shared budget, runs the law itself with its adaptation at the
    weakest in the gain phase (not no-u0, which takes no such parameters), and its best setting
    reruns to its training metrics."""
    import pandas as pd

    from nnrobust.config import apply_overrides
    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.base.plan import base_config, draw, experiment

    scales = arm_scales(build(load_preset("paper-ellipse-noisy")))
    space = search_space("slotine-li", scales)
    names = ["Lambda", "K_D_step", "gamma", "leakage", "null_damping"]
    assert [p.name for p in space.params] == [f"controller.params.{n}" for n in names]
    assert space.param("controller.params.K_D_step").reason("high").startswith("sampling")
    assert space.param("controller.params.null_damping").reason("low")
    assert space.param("controller.params.Lambda").high == pytest.approx(
        1 / ((0.5 + scales["delay"]) * scales["period"])
    )
    assert space.param("controller.params.Lambda").high_reason.startswith("sampling")
    assert space.weakest() == {"controller.params.gamma": 1e-3, "controller.params.leakage": 10.0}
    spec = TuneSpec(str(short_experiment), ["slotine-li"], 10, train_samples=2, validation=0, seed=2)
    summary = run_tune(spec, tmp_path / "out", scheduler=scheduler)
    rows = [json.loads(r) for r in pd.read_parquet(tmp_path / "out" / "trials")["row"]]
    gains = [r for r in rows if r["phase"] == "gains"]
    assert gains and all(r["law"] == "slotine-li" for r in gains)
    assert all(r["params"]["controller.params.gamma"] == 1e-3 for r in gains)
    assert all(run["status"] == "completed" for r in rows for run in r["runs"]), rows
    best = summary["controllers"]["slotine-li"]["best"]
    assert best is not None and set(best["params"]) == {p.name for p in space.params}
    sweep = sweep_of(spec)
    runs = [
        run_experiment(
            apply_overrides(
                experiment(sweep, base_config(sweep), draw(sweep, s), "slotine-li"), best["params"]
            )
        ).metrics()["rms_error_after_2s"]
        for s in (0, 1)
    ]
    assert np.mean(runs) == pytest.approx(best["train"]["rms_error_after_2s"], rel=1e-9)


def _every_shipped_law():
    from nnrobust.controllers.registry import law_names, paper_kinds

    return (*paper_kinds(), *law_names())


@pytest.mark.parametrize("name", _every_shipped_law())
def test_every_parameter_of_a_shipped_law_is_searched_or_held_with_a_reason(name, scales):
    """Fair by declaration (issue 37, item 4): every key a shipped or registered law reads is a
    search coordinate (or set from one: K_p from the bandwidth, nn.sigma from the leakage rate)
    or is held at the experiment's value for a reason its declaration states; a registered law's
    search bounds lie in its declared range, so widening one never asks what the law refuses."""
    from nnrobust.controllers.registry import SHARED_KEYS, registered_law
    from nnrobust.studies.base.tuned import own_keys, tunable

    assert name in tunable(), f"{name} declares nothing to search"
    space = search_space(name, scales)
    keys, _ = own_keys(name)
    shared = {p.name for s in SHARED_KEYS if s.readers is not None for p in s.params}
    searched, fixed = space.searched_keys(), dict(space.fixed)
    assert searched <= keys, searched - keys
    assert searched | set(fixed) == keys | shared, (keys | shared) - searched - set(fixed)
    assert not searched & set(fixed)
    unstated = [k for k, why in fixed.items() if not why.strip()]
    assert not unstated, f"{name} holds {unstated} without a reason (LawParam.fixed)"
    law = registered_law(name)
    for p in law.params if law else ():
        if p.search is not None:
            low, high = p.search(scales) if callable(p.search) else p.search
            assert p.low <= low < high <= p.high, (p.name, low, high, p.range)
    if name == "policy":  # the learned policy: its file, action and base are the experiment's
        assert {fixed[f"controller.params.{k}"] for k in ("file", "action", "base")} == {
            "chosen by the experiment"
        }
        assert "controller.params.residual_scale" in searched


def test_a_bound_on_the_end_of_a_laws_range_is_physical_and_never_widened(scales):
    """K_D_step's search ends where the law refuses a larger step (1): a best setting there is
    reported on a physical bound, and no widening asks 10 (which the law would refuse)."""
    from dataclasses import replace

    space = search_space("slotine-li", scales)
    step = space.param("controller.params.K_D_step")
    values = {p.name: math.sqrt(p.low * p.high) for p in space.params}
    values[step.name] = step.high
    wider, moved = space.widened(values)
    assert not moved and wider.param(step.name).high == 1.0
    (bound,) = space.at_bound(values)
    assert bound["param"] == step.name and bound["physical"]
    # a declared reason aside, the range alone stops a widening: leakage's 10 moves to 100, 1000, no further
    leak = replace(space.param("controller.params.leakage"), high=1e3)
    assert leak.reason("high") == "the law's range ends at 1000"


def test_a_custom_class_says_which_of_its_parameters_it_does_not_search():
    """A user's class searches its search_space; its other constructor parameters are listed as
    held, the reason being its author's choice."""
    from nnrobust.studies.tune.space import custom_space

    class Law:
        search_space = {"Kp": (1.0, 1e5, "1/s^2")}

        def __init__(self, context, Kp, Kv=4.0, *, law="corrected"):
            pass

    space = custom_space("mine", Law)
    assert dict(space.fixed) == {
        f"controller.params.{k}": "not in Law.search_space: its author's choice" for k in ("Kv", "law")
    }
    assert [p.name for p in space.params] == ["controller.params.Kp"]


def test_the_tuning_prints_what_it_does_not_search_and_why(scales):
    """nnrobust tune's table lists, under each controller, the keys it holds grouped by reason."""
    from nnrobust.cli.studies import format_tuning

    space = search_space("slotine-li", scales)
    text = format_tuning(
        {"controllers": {"slotine-li": {"best": None, "note": "none", "fixed": dict(space.fixed)}}}
    )
    assert "not searched, chosen by the experiment: controller.params.project" in text
    assert "controller.params.criterion_gain" in text and "controller.params.null_damping" not in text


def test_a_moved_tuning_resumes_and_trials_copied_in_or_changed_are_refused(
    scheduler, tuned, short_experiment, tmp_path
):
    """Issue 35, item 1: another tuning's trials copied into the folder were counted (8
    simulations for a budget of 4), and a trial row changed in place became the reported best.
    A copy of the folder elsewhere resumes with nothing run again; a part of another tuning, or a
    part changed after it was written, is refused by name."""
    import shutil

    import pandas as pd

    spec, out, summary = tuned
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    again = run_tune(spec, copy, scheduler=scheduler)
    assert again["controllers"]["pd"]["best"]["params"] == summary["controllers"]["pd"]["best"]["params"]
    parts = sorted((copy / "trials").glob("part-*.parquet"))
    assert [p.name for p in parts] == sorted(p.name for p in (out / "trials").glob("part-*.parquet"))
    run_tune(
        TuneSpec(str(short_experiment), ["pd"], 2, validation=0, seed=9),
        tmp_path / "other",
        scheduler=scheduler,
    )
    foreign = sorted((tmp_path / "other" / "trials").glob("part-*.parquet"))[0]
    shutil.copy(foreign, copy / "trials" / foreign.name)
    with pytest.raises(NNRobustError, match=f"{foreign.name} was computed from other inputs"):
        run_tune(spec, copy, scheduler=scheduler)
    (copy / "trials" / foreign.name).unlink()
    frame = pd.read_parquet(parts[0])
    rows = [json.loads(r) for r in frame["row"]]
    rows[0]["train"]["rms_error_after_2s"] = 1e-9  # the best there is, written in place
    frame["row"] = [json.dumps(r) for r in rows]
    frame.to_parquet(parts[0])
    with pytest.raises(NNRobustError, match=f"{parts[0].name} was changed after it was written"):
        run_tune(spec, copy, scheduler=scheduler)


def test_a_tuning_where_a_law_never_gave_a_result_exits_1(scheduler, short_experiment, tmp_path, capsys):
    """Every run of the law raised (after its first step passed the up-front check): the tuning
    says so and exits 1, as a sweep whose rows ended without a result does; no-u0 beside it is
    tuned as usual."""
    from pathlib import Path

    from nnrobust.cli import main

    law = f"{Path(__file__).parents[2] / 'controllers' / 'eq9_again.py'}:RaisesLate"
    argv = ["tune", str(short_experiment), "--controllers", f"no-u0,{law}", "--budget", "4"]
    assert (
        main([*argv, "--validation", "0", "--scheduler", scheduler, "--out", str(tmp_path / "t"), "--quiet"])
        == 1
    )
    assert "RaisesLate: every run ended without a result" in capsys.readouterr().err
    summary = json.loads((tmp_path / "t" / "summary.json").read_text())
    assert summary["controllers"]["RaisesLate"]["runs_without_result"] == 4
    assert summary["controllers"]["no-u0"]["runs_without_result"] == 0
