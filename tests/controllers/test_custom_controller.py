"""A controller of one's own (docs/extending.md): built from the experiment file as
``Class(context, **params)``, checked against the contract, recorded, and re-run exactly.

The reference is the built-in no-u0 law: ``tests/controllers/eq9_again.py`` writes eq. (9)
again from the context alone, and the two runs must agree.
"""

import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import nnrobust
from nnrobust.cli import main
from nnrobust.config import load_config
from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import ConfigError, ControllerError
from nnrobust.run import compiled
from nnrobust.run.experiment import build, run_experiment

LAWS = Path(__file__).parents[1] / "controllers" / "eq9_again.py"


def _experiment(folder: Path, cls: str, params: str = "", extra: str = "", duration: float = 0.5) -> Path:
    """An experiment file beside a copy of the controller file, starting from a preset."""
    shutil.copy(LAWS, folder / "laws.py")
    path = folder / "experiment.toml"
    path.write_text(
        f'base = "paper-ellipse"\nname = "mine"\n\n[controller]\nkind = "custom"\n'
        f'class = "laws.py:{cls}"\n{params}\n[simulation]\nduration = {duration}\n{extra}'
    )
    return path


def test_the_context_is_enough_to_write_eq9_again(tmp_path):
    """The contract's context carries everything eq. (9) needs: an independent re-implementation
    tracks the built-in no-u0 law to 1e-9 rad over 0.5 s of the paper's case (b)."""
    config = load_config(_experiment(tmp_path, "Eq9", "[controller.params]\nKp = 10.0\nKv = 4.0\n"))
    mine = run_experiment(config)
    builtin = run_experiment(
        load_preset("paper-ellipse").replace(simulation={"duration": 0.5}, controller={"kind": "no-u0"})
    )
    assert mine.status == builtin.status == "completed"
    assert mine.backend == ("hybrid" if compiled.available() else "python")
    np.testing.assert_allclose(mine.q, builtin.q, atol=1e-9, rtol=0)
    assert np.all(mine.signals["pinv_damping_free"] == 1.0)


def test_the_context_holds_the_nominal_model_never_the_true_one(tmp_path):
    setup = build(load_config(_experiment(tmp_path, "Eq9", "[controller.params]\nKp = 10.0\nKv = 4.0\n")))
    ctx = setup.controller.ctx
    assert ctx.nominal is setup.nominal and ctx.nominal is not setup.plant.model
    assert ctx.nominal.pinocchio_model is None  # the closed-form arm of the paper
    q = setup.q0
    assert not np.allclose(ctx.nominal.mass(q), setup.plant.model.mass(q))  # case (b) has model error
    assert ctx.period == setup.config.simulation.control_period and (ctx.n, ctx.m) == (3, 2)
    np.testing.assert_array_equal(ctx.torque_limits, setup.plant.torque_limit)
    np.testing.assert_array_equal(ctx.q0, setup.q0)
    panda = build(
        load_preset("panda-ellipse").replace(
            simulation={"duration": 0.1}, controller={"kind": "custom", "class": f"{LAWS}:Counter"}
        )
    )
    assert panda.controller.n == 7
    import pinocchio as pin

    assert isinstance(
        build(load_preset("panda-ellipse").replace(simulation={"duration": 0.1})).nominal.pinocchio_model,
        pin.Model,
    )


UNPERTURBED = {"kind": "urdf", "relative_error": 0.0, "com_error": 0.0, "p": None, "beta": None}


@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-ellipse"])
@pytest.mark.parametrize("backend", ["python", "hybrid"])
def test_a_law_cannot_reach_the_plant_or_the_record_through_its_context(preset, backend):
    """A law that scales its (unperturbed URDF) nominal model's inertias in place, or writes into
    its trajectory's and criterion's arrays, changes neither the true plant nor the recorded x_d,
    e and h: every run applying zero torque is the same, bit for bit."""
    if backend == "hybrid" and not compiled.available():
        pytest.skip(compiled.unavailable_reason())
    base = load_preset(preset).replace(nominal=UNPERTURBED, simulation={"duration": 0.3, "backend": backend})
    runs = {
        cls: run_experiment(base.replace(controller={"kind": "custom", "class": f"{LAWS}:{cls}"}))
        for cls in ("Counter", "AdaptsItsModel", "MovesTheReference")
    }
    reference = runs.pop("Counter")
    for cls, run in runs.items():
        for name in ("q", "dq", "x", "x_d", "e"):
            np.testing.assert_array_equal(
                getattr(run, name), getattr(reference, name), err_msg=f"{cls} {name}"
            )
        np.testing.assert_array_equal(run.signals["h"], reference.signals["h"], err_msg=cls)
    setup = build(base.replace(controller={"kind": "custom", "class": f"{LAWS}:Counter"}))
    assert setup.nominal.pinocchio_model is not setup.plant.model.pinocchio_model
    assert setup.controller_context.trajectory is not setup.trajectory


def test_a_run_records_its_class_and_reruns_bit_for_bit_from_elsewhere(tmp_path, monkeypatch):
    experiment = _experiment(tmp_path, "Counter")
    run = tmp_path / "run"
    assert main(["run", str(experiment), "--out", str(run), "--quiet", "--no-plots", "--no-animation"]) == 0
    text = (run / "config.toml").read_text()
    assert f'class = "{(tmp_path / "laws.py").resolve()}:Counter"' in text
    assert "# controller sha256: " in text
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    quiet = ["--quiet", "--no-plots", "--no-animation"]
    assert main(["run", str(run / "config.toml"), "--out", "again", *quiet]) == 0
    first, again = np.load(run / "result.npz"), np.load(elsewhere / "again" / "result.npz")
    for key in first.files:
        if first[key].dtype.kind == "f":
            np.testing.assert_array_equal(first[key], again[key], err_msg=key)
    elapsed = first["signal_elapsed"]  # z, as the law reports it: advanced by one period per step
    np.testing.assert_allclose(elapsed, first["t"], rtol=0, atol=1e-12)
    with open(tmp_path / "laws.py", "a") as fh:
        fh.write("\n# edited\n")
    with pytest.warns(UserWarning, match="controller file .* has changed"):
        load_config(run / "config.toml")


def test_run_takes_a_class_on_the_command_line_with_its_params(tmp_path, monkeypatch):
    shutil.copy(LAWS, tmp_path / "laws.py")
    monkeypatch.chdir(tmp_path)
    assert (
        main(
            [
                "run",
                "paper-ellipse",
                "--controller",
                "laws.py:Eq9",
                "--set",
                "controller.params.Kp=10.0",
                "--set",
                "controller.params.Kv=4.0",
                "--duration",
                "0.2",
                "--quiet",
                "--no-plots",
                "--no-animation",
            ]
        )
        == 0
    )
    config = load_config(tmp_path / "out" / "paper-ellipse-Eq9" / "config.toml")
    assert config.controller.params == {"Kp": 10.0, "Kv": 4.0}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        back = config.replace(controller={"kind": "nn", "class": None, "params": None})
    assert back.controller.class_ is None


@pytest.mark.parametrize(
    "cls, params, key, words",
    [
        ("Nope", "", "controller.class", "has no 'Nope'"),
        ("Eq", "", "controller.class", "did you mean 'Eq9'"),
        ("NotAController", "", "controller.class", "not a subclass of nnrobust.Controller"),
        ("Abstract", "", "controller.class", "does not implement compute"),
        ("Eq9", "[controller.params]\nKp = 1.0\nKvv = 2.0\n", "controller.params.Kvv", "did you mean 'Kv'"),
        ("Eq9", "[controller.params]\nKp = 1.0\n", "controller.params", "Eq9 needs Kv"),
        (
            "NeedsGain",
            "[controller.params]\ngain = -1.0\n",
            "controller.params",
            "ValueError: gain must be >= 0, got -1.0 (laws.py, line",
        ),
    ],
)
def test_a_bad_class_or_bad_params_is_one_error_naming_the_key(tmp_path, cls, params, key, words):
    config = load_config(_experiment(tmp_path, cls, params).parent / "experiment.toml")
    with pytest.raises(ConfigError) as err:
        build(config)
    assert err.value.key == key and words in str(err.value), str(err.value)


@pytest.mark.parametrize(
    "cls, words",
    [
        (
            "Undeclared",
            "returned signal 'surprise', which is not in its signal_names ('elapsed',); declare it",
        ),
        ("WrongShape", "returned a torque of shape (4,) at t = 0 s; the arm has 3 joints"),
        (
            "Raises",
            "Raises.compute raised at t = 0.011 s: IndexError: list index out of range (laws.py, line",
        ),
    ],
)
def test_a_controller_that_breaks_the_contract_while_running_is_named(tmp_path, cls, words):
    config = load_config(_experiment(tmp_path, cls))
    with pytest.raises(ControllerError) as err:
        run_experiment(config)
    assert words in str(err.value), str(err.value)


@pytest.mark.parametrize("backend", ["python", "hybrid"])
@pytest.mark.parametrize(
    "breach, words",
    [
        ("ints", None),
        ("strided", None),
        ("scalar", "LateBreach.compute returned a torque of shape () at t = 0.051 s; the arm has 3 joints"),
        ("size", "LateBreach.compute returned a torque of shape (2,) at t = 0.051 s; the arm has 3 joints"),
        ("tuple", "LateBreach.compute must return a ControlOutput, got tuple at t = 0.051 s"),
        ("words", "LateBreach.compute returned a torque that is not numbers at t = 0.051 s: ['a', 'a', 'a']"),
        ("signal", "LateBreach.compute returned signal 'elapsed' = 'soon' at t = 0.051 s; a signal is one"),
        ("state", "LateBreach.compute returned a state of shape (3,) at t = 0.051 s; initial_state() has 1"),
    ],
)
def test_the_contract_is_checked_at_every_step_on_both_loops(tmp_path, backend, breach, words):
    """A wrong output after the first step is named (the class, what it returned, when) on both
    loops that run user code; a list of ints and a strided view are valid torques on both, and
    give the run of a float array."""
    if backend == "hybrid" and not compiled.available():
        pytest.skip("the compiled extension is not built")
    params = f'[controller.params]\nbreach = "{breach}"\n'
    config = load_config(_experiment(tmp_path, "LateBreach", params, f'backend = "{backend}"\n', 0.1))
    if words is None:
        result = run_experiment(config)
        assert result.status == "completed"
        reference = run_experiment(
            load_config(_experiment(tmp_path, "Counter", "", f'backend = "{backend}"\n', 0.1))
        )
        np.testing.assert_array_equal(result.q, reference.q)
        return
    with pytest.raises(ControllerError) as err:
        run_experiment(config)
    assert words in str(err.value), str(err.value)


@pytest.mark.parametrize("backend", ["python", "hybrid"])
def test_a_non_finite_torque_from_a_finite_state_is_the_laws_not_the_gains(tmp_path, backend):
    if backend == "hybrid" and not compiled.available():
        pytest.skip("the compiled extension is not built")
    params = '[controller.params]\nbreach = "nan"\n'
    result = run_experiment(
        load_config(_experiment(tmp_path, "LateBreach", params, f'backend = "{backend}"\n', 0.1))
    )
    assert result.status == "diverged"
    assert "cause: LateBreach.compute returned a non-finite torque [nan, nan, nan] from a finite state" in (
        result.message
    ), result.message
    assert "unstable for these gains" not in result.message


@pytest.mark.parametrize("backend", ["python", "hybrid"])
def test_a_law_that_ends_the_process_is_a_named_error_not_a_silent_success(tmp_path, backend):
    """sys.exit(0) inside compute made `nnrobust run` exit 0 with no message and no run folder:
    it is a ControllerError on both loops that run user code, and the command fails saying so."""
    import subprocess
    import sys

    config = load_config(_experiment(tmp_path, "Exits", extra=f'backend = "{backend}"\n'))
    with pytest.raises(
        ControllerError, match=r"Exits.compute raised at t = 0.011 s: SystemExit: 0 \(laws.py"
    ):
        run_experiment(config)
    if backend == "python":
        done = subprocess.run(
            [sys.executable, "-m", "nnrobust.cli", "run", str(tmp_path / "experiment.toml"), "--out",
             str(tmp_path / "run"), "--no-plots", "--no-animation"],
            capture_output=True, text=True, timeout=300,
        )  # fmt: skip
        assert done.returncode != 0 and "a control law may not end the process" in done.stderr, done.stderr


def test_class_and_params_belong_to_custom_and_custom_needs_a_class():
    config = load_preset("paper-ellipse")
    with pytest.raises(ConfigError, match="controller.class: is read only with kind = 'custom'"):
        config.replace(controller={"class": "laws.py:Eq9"})
    with pytest.raises(ConfigError, match="controller.class: kind = 'custom' needs the class"):
        config.replace(controller={"kind": "custom"})
    with pytest.raises(ConfigError, match='is not "file.py:Class"'):
        config.replace(controller={"kind": "custom", "class": "laws.py"})
    with pytest.raises(ConfigError, match="controller.params.2x: .* not a valid Python identifier"):
        config.replace(controller={"kind": "custom", "class": "a.py:B", "params": {"2x": 1}})
    with pytest.raises(ConfigError, match="no module 'no_such_package_here'"):
        build(config.replace(controller={"kind": "custom", "class": "no_such_package_here:Law"}))


def test_the_pd_and_custom_laws_are_not_held_to_eq17(tmp_path):
    """Kv^2 > Kp constrains the gains of the laws whose u_0 is built on eq. (16)'s P only; the PD
    baseline, custom laws and eq. (9) without a robust term do not need it."""
    config = load_preset("paper-ellipse")
    assert config.replace(controller={"kind": "pd", "Kp": [100.0]}).controller.Kp == [100.0, 100.0]
    assert config.replace(controller={"kind": "no-u0", "Kp": [100.0]}).controller.Kp == [100.0, 100.0]
    with pytest.raises(ConfigError, match="Kv\\^2 = 16 must exceed Kp = 100"):
        config.replace(controller={"kind": "nn", "Kp": [100.0]})


def test_an_experiment_file_starts_from_a_preset_or_another_file(tmp_path):
    (tmp_path / "a.toml").write_text('base = "panda-ellipse"\nname = "a"\n[simulation]\nduration = 1.5\n')
    (tmp_path / "b.toml").write_text('base = "a.toml"\n[controller]\nkind = "pd"\n')
    b = load_config(tmp_path / "b.toml")
    panda = load_preset("panda-ellipse")
    assert (b.name, b.simulation.duration, b.controller.kind) == ("a", 1.5, "pd")
    assert b.robot == panda.robot and b.trajectory == panda.trajectory
    assert b.simulation.control_period == panda.simulation.control_period
    (tmp_path / "c.toml").write_text('base = "c.toml"\n')
    with pytest.raises(ConfigError, match="more than 8 deep"):
        load_config(tmp_path / "c.toml")
    (tmp_path / "d.toml").write_text('base = "nope"\n')
    with pytest.raises(ConfigError, match="d.toml: base: unknown preset 'nope'"):
        load_config(tmp_path / "d.toml")


def test_the_front_door_exposes_the_workflow():
    for name in (
        "load_robot",
        "load_preset",
        "ExperimentConfig",
        "build",
        "run_experiment",
        "Result",
        "write_run",
        "plot_run",
        "run_sweep",
        "run_tune",
        "Controller",
        "ControlOutput",
        "ControllerContext",
    ):
        assert name in nnrobust.__all__ and getattr(nnrobust, name) is not None


needs_extension = pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())


@needs_extension
@pytest.mark.parametrize("preset", ["paper-ellipse-noisy", "panda-ellipse"])
def test_the_hybrid_loop_is_the_python_loop_with_a_compiled_plant(preset):
    """The compiled plant calling the Python controller once per period: the same run as the
    Python loop to 1e-9 (sensor noise, delay, stick-slip friction, stops and a Pinocchio or
    closed-form nominal model included), the controller's signals and state recorded, and auto
    picks it for a custom controller."""
    base = load_preset(preset).replace(simulation={"duration": 2.5})
    c = base.controller
    config = base.replace(
        controller={"kind": "custom", "class": f"{LAWS}:Eq9", "params": {"Kp": c.Kp, "Kv": c.Kv}}
    )
    hybrid = run_experiment(config)
    python = run_experiment(config.replace(simulation={"backend": "python"}))
    assert (hybrid.backend, python.backend) == ("hybrid", "python")
    assert hybrid.metrics()["backend"] == "hybrid"
    np.testing.assert_allclose(hybrid.q, python.q, atol=1e-9, rtol=0)
    np.testing.assert_allclose(hybrid.tau, python.tau, atol=1e-9, rtol=0)
    np.testing.assert_array_equal(hybrid.signals["pinv_damping_free"], python.signals["pinv_damping_free"])
    np.testing.assert_allclose(hybrid.signals["h"], python.signals["h"], atol=1e-9)
    counting = config.replace(controller={"class": f"{LAWS}:Counter", "params": None})
    z = run_experiment(counting).signals["elapsed"]
    np.testing.assert_allclose(z, np.arange(z.size) * 1e-3, atol=1e-12)


@needs_extension
@pytest.mark.parametrize(
    "cls, words",
    [
        ("Undeclared", "returned signal 'surprise', which is not in its signal_names"),
        ("WrongShape", "returned a torque of shape (4,) at t = 0 s; the arm has 3 joints"),
        (
            "Raises",
            "Raises.compute raised at t = 0.011 s: IndexError: list index out of range (laws.py, line",
        ),
    ],
)
def test_the_hybrid_loop_names_a_broken_contract_as_the_python_loop_does(tmp_path, cls, words):
    config = load_config(_experiment(tmp_path, cls, extra='backend = "hybrid"\n'))
    with pytest.raises(ControllerError) as err:
        run_experiment(config)
    assert words in str(err.value), str(err.value)


@needs_extension
def test_a_signal_inside_the_hybrid_loop_keeps_the_steps_so_far(tmp_path):
    """Ctrl-C while the Python controller runs: the run stops, marked interrupted, with its steps."""
    import signal

    from nnrobust.core.signals import signals_as_interrupt

    config = load_config(_experiment(tmp_path, "Counter", extra='backend = "hybrid"\n', duration=5.0))
    setup = build(config)
    calls = [0]
    compute = setup.controller.compute

    def interrupting(t, q, v, z, period=0.0):
        calls[0] += 1
        if calls[0] == 700:
            signal.raise_signal(signal.SIGINT)
        return compute(t, q, v, z, period)

    setup.controller.compute = interrupting
    with signals_as_interrupt():
        result = run_experiment(config, setup=setup)
    assert result.status == "interrupted" and 600 <= result.t.size <= 800
    assert np.isfinite(result.q).all()


def test_a_setup_runs_twice_identically_on_the_python_loop():
    """Every random draw comes from the seed at the start of a run: the noisy preset's Setup,
    simulated twice, gives the same run (the sensor used to carry its RNG state over)."""
    config = load_preset("paper-ellipse-noisy").replace(simulation={"duration": 0.5, "backend": "python"})
    setup = build(config)
    first, second = run_experiment(config, setup=setup), run_experiment(config, setup=setup)
    np.testing.assert_array_equal(first.q, second.q)
