import json
from pathlib import Path

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.config import EQ9_KINDS, KEY_ALIASES, ExperimentConfig, from_dict, load_config
from nnrobust.config.presets import load_preset, preset_names
from nnrobust.core.exceptions import ConfigError, RunFolderExists
from nnrobust.outputs.run_folder import RunFolderError, write_run
from nnrobust.run.experiment import build, run_experiment
from nnrobust.run.results import Result

DATA = Path(__file__).resolve().parents[2] / "docs" / "data"


@pytest.fixture(scope="module")
def paper_runs():
    """Cases (a) and (b), 20 s, NN controller and the no-u0 baseline."""
    runs = {}
    for preset in ("paper-line", "paper-ellipse"):
        for kind in ("nn", "no-u0"):
            config = load_preset(preset).replace(controller={"kind": kind})
            runs[preset, kind] = run_experiment(config).metrics()
    return runs


@pytest.mark.parametrize("preset", ["paper-line", "paper-ellipse"])
def test_nn_controller_beats_baseline_tenfold(paper_runs, preset):
    """Acceptance: RMS task error over t >= 2 s at least 10x smaller with the NN compensator."""
    nn, base = paper_runs[preset, "nn"], paper_runs[preset, "no-u0"]
    assert nn["status"] == base["status"] == "completed"
    assert np.isfinite(base["rms_error_after_2s"])
    assert nn["rms_error_after_2s"] * 10 <= base["rms_error_after_2s"]
    assert np.isfinite(nn["rms_torque"]) and nn["rms_torque"] > 0
    # and both are what the README publishes (docs/data/paper_reproduction.json), within 2 %: a
    # weaker compensator that still beats a 360 mm baseline tenfold fails here
    case = {"paper-line": "case (a) line", "paper-ellipse": "case (b) ellipse"}[preset]
    published = {
        r["variant"]: r
        for r in json.loads((DATA / "paper_reproduction.json").read_text())["rows"]
        if r["case"] == case
    }
    assert nn["rms_error_after_2s"] == pytest.approx(
        published["NN, defaults"]["rms_error_after_2s"], rel=0.02
    )
    assert base["rms_error_after_2s"] == pytest.approx(
        published["no-u0 baseline"]["rms_error_after_2s"], rel=0.02
    )


def test_every_preset_validates():
    """All shipped presets load and round-trip through TOML."""
    assert {"paper-line", "paper-ellipse", "paper-ellipse-vertical"} <= set(preset_names())
    for name in preset_names():
        config = load_preset(name)
        assert from_dict(__import__("tomllib").loads(config.to_toml())) == config


@pytest.mark.parametrize("name", preset_names())
def test_checking_a_configuration_changes_nothing_and_integration_step_is_substeps(name):
    """validate only checks: every preset, and one given as an integration step, is the same
    after it; the step is read where the run needs it, so that a run with integration_step = T/3
    is the run with substeps = 3, bit for bit."""
    from nnrobust.config import apply_overrides, validate

    config = load_preset(name)
    stepped = apply_overrides(config, {"simulation.integration_step": config.simulation.control_period / 3})
    for c in (config, stepped):
        before = c.to_toml()
        validate(c)
        assert c.to_toml() == before
    assert stepped.simulation.substeps is None and stepped.simulation.requested_substeps == 3
    if name == "paper-ellipse":
        short = {"simulation.duration": 0.05}
        by_step = run_experiment(apply_overrides(stepped, short))
        by_count = run_experiment(apply_overrides(config, {**short, "simulation.substeps": 3}))
        T = config.simulation.control_period
        assert by_step.plant_step == by_count.plant_step == pytest.approx(T / 3)
        assert np.array_equal(by_step.q, by_count.q)


@pytest.mark.parametrize(
    ("task", "changes", "m"),
    [("planar", {}, 2), ("pose", {"robot": {"source": "panda", "task_frame": "panda_hand_tcp"}}, 6)],
)
def test_validate_leaves_its_input_and_resolve_returns_the_full_copy(task, changes, m):
    """A gain given once for every task coordinate passes validate unchanged; resolve returns a
    copy with it written out m times (the input untouched), and resolving again changes nothing.
    Eq. (17)'s Kv^2 > Kp is checked on every coordinate of the broadcast gains."""
    import copy

    from nnrobust.config import resolve, task_rows, validate

    config = ExperimentConfig()
    config.robot.task = task
    for section, values in changes.items():
        for key, value in values.items():
            setattr(getattr(config, section), key, value)
    if task == "pose":
        config.trajectory.center = [0.45, 0.0, 0.45]
        config.trajectory.axis_a, config.trajectory.axis_b = [0.1, 0.0, 0.0], [0.0, 0.1, 0.0]
    before = copy.deepcopy(config)
    validate(config)
    assert config == before and config.controller.Kp == [10.0]
    full = resolve(config)
    assert config == before
    assert task_rows(config) == m
    c = full.controller
    assert (c.Kp, c.Kv, c.pd_Kp, c.pd_Kd) == ([10.0] * m, [4.0] * m, [400.0] * m, [40.0] * m)
    assert resolve(full) == full
    with pytest.raises(ConfigError, match="controller.Kv.*Kv\\^2 = 9 must exceed Kp = 10"):
        from_dict({"controller": {"Kp": [10.0], "Kv": [4.0, 3.0]}})
    for kv in (-1.0, -4.0):  # out of range is said before eq. (17), whatever the size
        with pytest.raises(ConfigError, match=f"controller.Kv: {kv:g} is outside"):
            from_dict({"controller": {"Kv": [kv]}})


def test_config_errors_name_the_key(tmp_path):
    """Unknown keys suggest the closest one; Kv^2 <= Kp is refused with the reason."""
    with pytest.raises(ConfigError, match="did you mean 'duration'"):
        from_dict({"simulation": {"duraton": 3.0}})
    with pytest.raises(ConfigError, match="controller.Kv.*positive definite"):
        from_dict({"controller": {"Kp": [10.0, 10.0], "Kv": [3.0, 3.0]}})
    with pytest.raises(ConfigError, match="expected a number"):
        from_dict({"nn": {"F": "fast"}})
    bad = tmp_path / "bad.toml"
    bad.write_text("[simulation\nduration = 1")
    with pytest.raises(ConfigError, match="bad.toml: invalid TOML"):
        load_config(bad)


def _short(config: ExperimentConfig, kind: str = "nn") -> ExperimentConfig:
    return config.replace(controller={"kind": kind}, simulation={"duration": 0.3})


def test_run_folder_contents_and_reload(tmp_path):
    """A run folder holds config.toml, result.npz (per-period arrays), metrics.json, plots and
    animation.html."""
    result = run_experiment(_short(load_preset("paper-ellipse")))
    folder = write_run(tmp_path / "run", result)
    names = {p.name for p in folder.iterdir()}
    assert names == {"config.toml", "result.npz", "metrics.json", "plots", "animation.html", ".nnrobust-run"}
    marker = json.loads((folder / ".nnrobust-run").read_text())
    assert (marker["status"], marker["extras"]) == ("completed", "complete")
    with np.load(folder / "result.npz") as data:
        for key in ("t", "q", "dq", "tau", "x", "x_d"):
            assert data[key].shape[0] == 300
    metrics = json.loads((folder / "metrics.json").read_text())
    for key in ("rms_error", "rms_error_after_2s", "max_error", "rms_torque"):
        assert key in metrics
    assert (folder / "plots" / "path.png").stat().st_size > 1000
    again = Result.load(folder)
    np.testing.assert_array_equal(again.q, result.q)
    # the written configuration repeats the run exactly
    repeat = run_experiment(load_config(folder / "config.toml"))
    np.testing.assert_array_equal(repeat.tau, result.tau)


def test_write_is_atomic_and_never_clobbers(tmp_path, monkeypatch):
    """An existing run is kept unless overwrite; a failed write leaves the old run intact."""
    result = run_experiment(_short(load_preset("paper-line"), "no-u0"))
    folder = write_run(tmp_path / "run", result, plots=False)
    before = (folder / "metrics.json").read_text()
    with pytest.raises(RunFolderExists):
        write_run(folder, result, plots=False)

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(Result, "save_npz", broken)
    with pytest.raises(RunFolderError, match="disk full.*the previous run there is unchanged"):
        write_run(folder, result, overwrite=True, plots=False)
    assert (folder / "metrics.json").read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ["run"]  # no partial folder left behind


def test_cli_run_compare_and_errors(tmp_path, capsys):
    """nnrobust run / compare / presets work; bad input gives exit code 2 and one message."""
    out_nn, out_pd = tmp_path / "nn", tmp_path / "pd"
    assert main(["run", "paper-ellipse", "--duration", "0.3", "--out", str(out_nn), "--quiet"]) == 0
    assert (
        main(
            [
                "run",
                "paper-ellipse",
                "--controller",
                "pd",
                "--duration",
                "0.3",
                "--out",
                str(out_pd),
                "--quiet",
                "--no-plots",
            ]
        )
        == 0
    )
    assert main(["compare", str(out_nn), str(out_pd), "--out", str(tmp_path / "cmp")]) == 0
    table = capsys.readouterr().out
    assert "nn" in table and "pd" in table and (tmp_path / "cmp" / "comparison.png").exists()
    assert main(["presets"]) == 0
    assert "paper-line" in capsys.readouterr().out
    assert main(["run", "no-such-preset"]) == 2
    assert main(["run", "paper-ellipse", "--duration", "0.3", "--out", str(out_nn)]) == 2
    assert "exists" in capsys.readouterr().err


def test_vertical_plane_preset_compensates_gravity():
    """In the vertical plane the NN controller still tracks (gravity is in the nominal model)."""
    config = load_preset("paper-ellipse-vertical").replace(simulation={"duration": 3.0})
    metrics = run_experiment(config).metrics()
    assert metrics["status"] == "completed"
    assert metrics["rms_error_after_2s"] < 0.01


def test_paper_nominal_is_the_closed_form_with_p_hat():
    """Erratum 3: the paper's nominal model is the closed form with p-hat = (0.4, 0.1, 0.1), which
    no URDF with the paper's lengths realises (point masses give p2 / p3 = l1 / l2)."""
    from nnrobust.model import ThreeLinkPlanarModel

    setup = build(load_preset("paper-ellipse").replace(simulation={"duration": 1.0}))
    nominal = setup.nominal
    assert isinstance(nominal, ThreeLinkPlanarModel)
    assert tuple(nominal.params.p) == (0.4, 0.1, 0.1)
    l1, l2 = nominal.params.lengths[:2]
    assert abs(nominal.params.p[1] / nominal.params.p[2] - l1 / l2) > 0.1


def test_initial_state_starts_on_the_path():
    """Erratum 7: q(0) by inverse kinematics of x_d(0), q'(0) = J+ x_d'(0): zero task error and
    zero task velocity error at t = 0."""
    setup = build(load_preset("paper-line").replace(simulation={"duration": 1.0}))
    xd, dxd, _ = setup.trajectory(0.0)
    np.testing.assert_allclose(setup.robot.task_position(setup.q0), xd, atol=1e-9)
    np.testing.assert_allclose(setup.robot.task_jacobian(setup.q0) @ setup.v0, dxd, atol=1e-9)


def test_nominal_friction_holds_the_viscous_estimate_only():
    """Erratum 10: N-hat has f-hat_d = (4, 1, 0.2) and no Coulomb term unless asked for."""
    controller = build(load_preset("paper-ellipse").replace(simulation={"duration": 1.0})).controller
    np.testing.assert_array_equal(controller.nominal_friction.viscous, [4.0, 1.0, 0.2])
    np.testing.assert_array_equal(controller.nominal_friction.coulomb, [0.0, 0.0, 0.0])


@pytest.mark.parametrize("n", [100_001, 10_001, 5_901, 20_001, 3_001, 4_499])
def test_plots_draw_the_envelope_of_long_series(n):
    """A long series is drawn as its per-bucket minimum and maximum over the whole run: every
    bucket of an independent cut (np.array_split, sizes differing by one) has its peaks drawn,
    no two drawn samples are more than two buckets apart, and short series are drawn whole.
    Lengths that are not multiples of the bucket count are the ones that matter (a 10 s run at
    1 kHz has 10 001 samples)."""
    from nnrobust.outputs.plots import MAX_BUCKETS, envelope

    t = np.linspace(0.0, 10.0, n)
    rng = np.random.default_rng(n)
    y = np.sin(7 * t) + rng.normal(0, 0.1, n) + (np.arange(n) % 997 == 0) * 5.0  # isolated spikes
    t2, y2 = envelope(t, y)
    assert len(y2) <= 2 * MAX_BUCKETS + 2
    assert np.all(np.diff(t2) > 0) and t2[0] == t[0] and t2[-1] == t[-1]
    drawn = set(np.searchsorted(t, t2))
    for bucket in np.array_split(np.arange(n), MAX_BUCKETS):
        assert bucket[np.argmin(y[bucket])] in drawn and bucket[np.argmax(y[bucket])] in drawn
    width = -(-n // MAX_BUCKETS)
    assert np.diff(sorted(drawn)).max() <= 2 * width
    spikes = np.flatnonzero(y > 2)
    assert set(t[spikes]) <= set(t2)  # every spike is drawn
    short = np.arange(100.0)
    assert envelope(short, short)[1] is short


def test_a_reachable_path_is_checked_once_per_process_and_a_changed_one_again(monkeypatch):
    """The workspace check's inverse kinematics runs once for a sweep's shared arm and path; a
    path that leaves the workspace is still refused, however many reachable ones came before."""
    import nnrobust.run.experiment as ex
    from nnrobust.core.exceptions import ConfigError

    calls = []
    real = ex.solve_ik
    monkeypatch.setattr(ex, "solve_ik", lambda *a, **k: calls.append(1) or real(*a, **k))
    monkeypatch.setattr(ex, "_REACHABLE", set())
    config = load_preset("paper-ellipse").replace(simulation={"duration": 2.0})
    ex.build(config)
    first = len(calls)
    ex.build(config.replace(plant={"disturbance_scale": 1.5}))  # another plant, the same arm and path
    assert first > ex.WORKSPACE_SAMPLES - 1 and len(calls) - first < ex.WORKSPACE_SAMPLES
    for _ in range(2):
        with pytest.raises(ConfigError, match="leaves the workspace"):
            ex.build(config.replace(trajectory={"axis_b": [0.0, 0.8]}))


INERT_CASES = [
    ("paper-ellipse", {}),
    ("paper-ellipse", {"controller": {"kind": "pd"}}),
    ("paper-ellipse", {"controller": {"kind": "computed-torque"}}),
    ("paper-ellipse", {"controller": {"kind": "sliding-mode"}, "plant": {"disturbance": "none"}}),
    ("panda-ellipse", {"simulation": {"adaptive_step": False}, "plant": {"joint_stops": False}}),
    ("paper-ellipse", {"controller": {"kind": "slotine-li"}}),
    ("panda-ellipse", {"controller": {"kind": "rbf-nn"}}),
]


@pytest.mark.parametrize(("preset", "changes"), INERT_CASES)
def test_every_key_called_inert_changes_nothing(preset, changes):
    """config.inert_keys: each numeric key it names, changed, leaves the run bit for bit the same
    (what `run --set` warns about), and a key it does not name is not claimed inert."""
    from nnrobust.config import inert_keys

    sections = {**changes, "simulation": {**changes.get("simulation", {}), "duration": 0.05}}
    config = load_preset(preset).replace(**sections)
    reference = run_experiment(config).q
    inert = inert_keys(config)
    representative = {"nn.": "nn.F", "subtasks.": "subtasks.C", "nominal.": "nominal.relative_error"}
    checked = 0
    for key in inert:
        key = representative.get(key, key)
        section, name = key.split(".")
        value = getattr(getattr(config, section), KEY_ALIASES.get(name, name))
        if value is None and name == "pd_null_damping":
            value = 1.0
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue  # lists, strings and unset lists: numbers only here
        new = 0.2 if name == "relative_error" else value * 1.5 + 0.1
        changed = config.replace(**{section: {name: new}})
        if section == "subtasks" and name == "C":
            changed = config.replace(subtasks={"C": new, "weights": None})
        np.testing.assert_array_equal(run_experiment(changed).q, reference, err_msg=f"{key} = {new}")
        checked += 1
    assert checked >= 3
    assert "controller.Kp" not in inert or config.controller.kind not in EQ9_KINDS


def test_run_warns_about_a_set_key_that_changes_nothing(tmp_path):
    with pytest.warns(UserWarning, match=r"--set controller.Kp changes nothing here: controller.kind = 'pd'"):
        args = ["run", "paper-ellipse", "--controller", "pd", "--set", "controller.Kp=[20.0]"]
        code = main(
            [*args, "--duration", "0.05", "--no-plots", "--no-animation", "--out", str(tmp_path / "r")]
        )
    assert code == 0


def _readme_panda() -> str:
    """The README's my-panda.toml (its first TOML block)."""
    import re

    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    return re.findall(r"```toml\n(.*?)```", readme, flags=re.S)[0]


def _preset_text(name: str) -> str:
    from nnrobust.config.presets import preset_path

    return preset_path(name).read_text()


SET_CASES = {  # an experiment file, a --set, and the same change made by editing the file
    "README panda, one-value gains, pose task": (
        _readme_panda,
        "robot.task=pose",
        ('task = "position"', 'task = "pose"'),
    ),
    "planar file, one gain for both coordinates": (
        lambda: _preset_text("paper-ellipse"),
        "controller.Kp=[12.0]",
        ("Kp = [10.0, 10.0]", "Kp = [12.0]"),
    ),
    "a law's parameter (controller.params.NAME)": (
        lambda: 'base = "panda-ellipse"\n[controller]\nkind = "slotine-li"\nparams = {gamma = 3.0}\n',
        "controller.params.leakage=0.2",
        ("{gamma = 3.0}", "{gamma = 3.0, leakage = 0.2}"),
    ),
    "one entry of a list (nominal.factors[4])": (
        lambda: _preset_text("paper-ellipse"),
        "nominal.factors[4]=1.3",
        ("[nominal]\n", "[nominal]\nfactors = [1.0, 1.0, 1.0, 1.0, 1.3]\n"),
    ),
}


@pytest.mark.parametrize("case", SET_CASES)
def test_a_set_gives_the_configuration_of_the_edited_file(case, tmp_path):
    """`run FILE --set KEY=VALUE` is FILE edited so: the override is set in the file's own values,
    before a gain given once is written out m times (it was set in the resolved copy, where the
    README's Kp = [25.0] had become 3 entries, and robot.task=pose was refused for them)."""
    from nnrobust.cli.common import load_target as _load_target
    from nnrobust.config import parse_override

    text, override, (old, new) = SET_CASES[case]
    given, edited = tmp_path / "given.toml", tmp_path / "edited.toml"
    given.write_text(text())
    assert old in given.read_text()
    edited.write_text(given.read_text().replace(old, new, 1))
    overridden = _load_target(str(given), dict([parse_override(override)]))
    assert overridden == load_config(edited)
    assert overridden.to_toml() == load_config(edited).to_toml()


def test_the_readmes_panda_runs_with_a_pose_task_set(tmp_path, capsys):
    """The command of issue 34: `nnrobust run my-panda.toml --set robot.task=pose` runs (it said
    `controller.Kp: has 3 entries`), and its config.toml is the file edited to a pose task with
    six gains of 25."""
    experiment = tmp_path / "my-panda.toml"
    experiment.write_text(_readme_panda())
    out = tmp_path / "out"
    words = ["run", str(experiment), "--set", "robot.task=pose", "--set", "simulation.duration=0.05"]
    assert main([*words, "--out", str(out), "--quiet", "--no-plots", "--no-animation"]) == 0, (
        capsys.readouterr().err
    )
    ran = load_config(out / "config.toml")
    assert ran.robot.task == "pose" and ran.controller.Kp == [25.0] * 6 and ran.controller.Kv == [10.0] * 6
    edited = tmp_path / "edited.toml"
    edited.write_text(
        experiment.read_text()
        .replace('task = "position"', 'task = "pose"')
        .replace("duration = 8.0", "duration = 0.05")
    )
    assert ran == load_config(edited)
