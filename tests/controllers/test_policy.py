"""A learned policy as a controller (controller.kind = "policy", docs/learning.md): ONNX files
built from the documented layout alone run through ``run``; the compiled path equals the Python
reference; a zero policy is exactly the run of a law returning zeros, or of its base law; bad
files and bad outputs are one line naming the file.
"""

from pathlib import Path

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.config import load_config
from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import ConfigError, ControllerError
from nnrobust.run import compiled
from nnrobust.run.experiment import build, run_experiment
from nnrobust.studies.learning import ObservationLayout

pytest.importorskip("onnxruntime")
pytest.importorskip("onnx")

from tests.policies import linear_policy, nan_policy, unknown_operator_policy  # noqa: E402

COUNTER = Path(__file__).parents[1] / "controllers" / "eq9_again.py"
PAPER = ObservationLayout(3, 2)
needs_compiled = pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())


def _config(preset, file, duration=0.2, backend="auto", **params):
    return load_preset(preset).replace(
        controller={"kind": "policy", "params": {"file": str(file), **params}},
        simulation={"duration": duration, "backend": backend},
    )


def _weights(layout: ObservationLayout, seed=0, scale=0.3):
    rng = np.random.default_rng(seed)
    s = layout.slices()
    W = np.zeros((layout.size, layout.n))
    W[s["e"].start : s["e"].start + 2, :] = rng.normal(0, scale, (2, layout.n))  # a little feedback on e
    return W


@needs_compiled
def test_a_zero_torque_policy_is_a_custom_law_returning_zeros(tmp_path):
    file = linear_policy(tmp_path / "zero.onnx", 3 * 2 + 2 + 4 * 2, 3)
    mine = run_experiment(_config("paper-ellipse", file))
    zeros = run_experiment(
        load_preset("paper-ellipse").replace(
            controller={"kind": "custom", "class": f"{COUNTER}:Counter"},
            simulation={"duration": 0.2, "backend": "hybrid"},
        )
    )
    assert mine.backend == "hybrid"
    np.testing.assert_array_equal(mine.q, zeros.q)
    np.testing.assert_array_equal(mine.tau, zeros.tau)
    assert np.all(np.isfinite(mine.signals["inference_time"]))


@needs_compiled
@pytest.mark.parametrize("base", ["nn", "pd"])
def test_a_zero_residual_policy_is_its_base_laws_compiled_run(tmp_path, base):
    file = linear_policy(tmp_path / "zero.onnx", PAPER.size, 3)
    mine = run_experiment(_config("paper-ellipse", file, action="residual", base=base))
    theirs = run_experiment(
        load_preset("paper-ellipse").replace(controller={"kind": base}, simulation={"duration": 0.2})
    )
    assert theirs.backend == "compiled"
    np.testing.assert_array_equal(mine.tau, theirs.tau)
    for name in theirs.signals:
        np.testing.assert_array_equal(mine.signals[name], theirs.signals[name])


@needs_compiled
@pytest.mark.parametrize(
    ("preset", "layout", "action"),
    [
        ("paper-ellipse", PAPER, "residual"),
        ("panda-ellipse", ObservationLayout(7, 3), "torque"),
        ("paper-ellipse", PAPER, "gains"),
    ],
)
def test_the_compiled_policy_run_equals_the_python_reference(tmp_path, preset, layout, action):
    """The same policy (feedback on e) through the compiled path and the Python loop's PolicyLaw:
    one implementation of the observation, the action and the base law."""
    n = 2 if action == "gains" else layout.n
    W = _weights(layout, scale=30.0 if action == "gains" else 0.3)[:, :n]
    file = linear_policy(tmp_path / "p.onnx", layout.size, n, W, dtype=np.float64)
    fast = run_experiment(_config(preset, file, duration=0.3, action=action, residual_scale=0.2))
    slow = run_experiment(
        _config(preset, file, duration=0.3, backend="python", action=action, residual_scale=0.2)
    )
    assert (fast.backend, slow.backend) == ("hybrid", "python")
    assert np.abs(fast.tau).max() > 0
    np.testing.assert_allclose(fast.q, slow.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.tau, slow.tau, rtol=1e-7, atol=1e-7)


def test_a_gains_policy_needs_a_base_law_with_gains_and_two_outputs(tmp_path):
    two = linear_policy(tmp_path / "two.onnx", PAPER.size, 2)
    with pytest.raises(ConfigError, match="params.base: 'slotine-li' has no position and velocity gains"):
        build(_config("paper-ellipse", two, action="gains", base="slotine-li"))
    three = linear_policy(tmp_path / "three.onnx", PAPER.size, 3)
    with pytest.raises(ConfigError, match=r"three.onnx: its output 'action' .* the action is \[2\]"):
        build(_config("paper-ellipse", three, action="gains", base="pd"))


def test_files_that_cannot_be_a_policy_are_refused_naming_the_file(tmp_path):
    cases = {
        "missing.onnx": None,
        "garbage.onnx": lambda p: p.write_bytes(b"\x00not a model\xff" * 10),
        "small.onnx": lambda p: linear_policy(p, PAPER.size - 1, 3),
        "wide.onnx": lambda p: linear_policy(p, PAPER.size, 4),
        "dream.onnx": lambda p: unknown_operator_policy(p, PAPER.size, 3),
    }
    said = {}
    for name, make in cases.items():
        path = tmp_path / name
        if make:
            make(path)
        with pytest.raises(ConfigError) as err:
            build(_config("paper-ellipse", path))
        said[name] = str(err.value)
        assert "controller.params.file" in said[name] and name in said[name]
    assert "is not a file" in said["missing.onnx"]
    assert "not an ONNX model" in said["garbage.onnx"] and "not an ONNX model" in said["dream.onnx"]
    assert f"[batch, {PAPER.size}]" in said["small.onnx"] and "[batch, 3]" in said["wide.onnx"]
    with pytest.raises(ConfigError, match="controller.params.file: missing"):
        build(load_preset("paper-ellipse").replace(controller={"kind": "policy"}))


@pytest.mark.parametrize("backend", ["auto", "python"])
def test_a_policy_returning_nan_is_a_named_error(tmp_path, backend):
    if backend == "auto" and not compiled.available():
        pytest.skip(compiled.unavailable_reason())
    file = nan_policy(tmp_path / "nan.onnx", PAPER.size, 3)
    with pytest.raises(ControllerError, match=r"nan.onnx returned a non-finite action at t = 0 s"):
        run_experiment(_config("paper-ellipse", file, backend=backend))


@needs_compiled
def test_a_policy_run_records_its_file_and_reruns_from_its_folder(tmp_path, capsys):
    """An experiment file naming the policy by a relative path runs from anywhere; the run's
    config.toml records the file's SHA-256 and reruns to the same numbers."""
    import hashlib

    folder = tmp_path / "study"
    folder.mkdir()
    linear_policy(folder / "policy.onnx", PAPER.size, 3, _weights(PAPER), dtype=np.float64)
    (folder / "mine.toml").write_text(
        'base = "paper-ellipse"\n[controller]\nkind = "policy"\n'
        '[controller.params]\nfile = "policy.onnx"\naction = "residual"\nbase = "nn"\n'
        "[simulation]\nduration = 0.3\n"
    )
    out = tmp_path / "run"
    assert main(["run", str(folder / "mine.toml"), "--out", str(out), "--no-plots"]) == 0
    text = (out / "config.toml").read_text()
    digest = hashlib.sha256((folder / "policy.onnx").read_bytes()).hexdigest()
    assert f"# policy sha256: {digest}" in text
    again = run_experiment(load_config(out / "config.toml"))
    first = run_experiment(load_config(folder / "mine.toml"))
    np.testing.assert_array_equal(again.tau, first.tau)


@needs_compiled
def test_a_policy_entry_runs_in_a_sweep_on_the_same_plants(scheduler, tmp_path):
    """A sweep file names a policy by a path relative to itself; a zero residual on eq. (9) gives,
    sample for sample (common random numbers), exactly eq. (9)'s own rows; the file's SHA-256
    is among the sweep's inputs."""
    pytest.importorskip("distributed")
    from nnrobust.studies.sweep import load_sweep, read_results, run_sweep

    linear_policy(tmp_path / "zero.onnx", PAPER.size, 3)
    (tmp_path / "sweep.toml").write_text(
        'name = "learned"\nbase = "paper-ellipse"\nsamples = 3\nseed = 5\n'
        'controllers = ["no-u0", {name = "zero-residual", kind = "policy", '
        'params = {file = "zero.onnx", action = "residual", base = "no-u0"}}]\n'
        '[set]\n"simulation.duration" = 0.3\n'
        '[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
    )
    spec = load_sweep(tmp_path / "sweep.toml")
    run_sweep(spec, tmp_path / "out", scheduler=scheduler)
    frame = read_results(tmp_path / "out").sort_values(["controller", "sample"])
    mine = frame[frame["controller"] == "zero-residual"]
    theirs = frame[frame["controller"] == "no-u0"]
    assert list(mine["status"]) == ["completed"] * 3
    np.testing.assert_array_equal(mine["rms_error"].to_numpy(), theirs["rms_error"].to_numpy())
    import hashlib

    digest = hashlib.sha256((tmp_path / "zero.onnx").read_bytes()).hexdigest()
    recorded = (tmp_path / "out" / "sweep.toml").read_text()
    assert f"# the policy file of controller zero-residual: {tmp_path / 'zero.onnx'} {digest}" in recorded


@needs_compiled
def test_an_inference_longer_than_the_period_is_a_verdict(tmp_path, monkeypatch):
    """Each step's inference time is recorded; a step that took longer than the period is
    counted and warned about (the run itself goes on: the simulation waits)."""
    from nnrobust.controllers.laws import policy

    file = linear_policy(tmp_path / "zero.onnx", PAPER.size, 3)
    calls = {"n": 0}
    real = policy.OnnxPolicy.on_buffer  # the hybrid loop's call

    def slow_every_tenth(self, obs):  # the measured time of every tenth call: 2 periods
        call = real(self, obs)

        def timed(t):
            a = call(t)
            calls["n"] += 1
            self.seconds = 2e-3 if calls["n"] % 10 == 0 else 1e-6
            return a

        return timed

    monkeypatch.setattr(policy.OnnxPolicy, "on_buffer", slow_every_tenth)
    metrics = run_experiment(_config("paper-ellipse", file, duration=0.2)).metrics()
    assert metrics["inference_over_period"] == pytest.approx(0.1)
    assert metrics["max_inference_time"] == 2e-3
    assert any(w.startswith("deadline missed") and "10 % of the steps" in w for w in metrics["warnings"])


@needs_compiled
def test_tune_searches_a_residual_policys_scale(scheduler, tmp_path):
    """``nnrobust tune`` on an experiment whose law is a policy searches residual_scale in its
    declared bounds and holds the file, the action and the base law, saying why."""
    pytest.importorskip("optuna")
    import json

    linear_policy(tmp_path / "p.onnx", PAPER.size, 3, _weights(PAPER), dtype=np.float64)
    (tmp_path / "exp.toml").write_text(
        'base = "paper-ellipse"\n[controller]\nkind = "policy"\n[controller.params]\nfile = "p.onnx"\n'
        'action = "residual"\nbase = "no-u0"\n[simulation]\nduration = 2.5\n'
    )
    out = tmp_path / "out"
    argv = [
        "tune",
        str(tmp_path / "exp.toml"),
        "--controllers",
        "policy",
        "--budget",
        "4",
        "--scheduler",
        scheduler,
    ]
    assert main([*argv, "--out", str(out)]) == 0
    best = json.loads((out / "summary.json").read_text())["controllers"]["policy"]["best"]
    assert set(best["params"]) == {"controller.params.residual_scale"}
    assert 0.01 <= best["params"]["controller.params.residual_scale"] <= 1.0


def test_a_policy_scored_past_the_horizon_it_was_trained_on_is_said_to_be(tmp_path):
    """The record beside a policy file gives its episodes' length: a sweep or study of longer runs,
    scored from t = 2 s, warns (the shipped CMA-ES policies were trained on 2 s episodes and scored
    on t >= 2 s of 4 s runs); runs within it, or a file without a record, do not."""
    import json

    from nnrobust.controllers.laws.policy import horizon_warning, trained_horizon

    policy = tmp_path / "p.onnx"
    policy.write_bytes(b"")
    assert trained_horizon(policy) is None and horizon_warning("p", policy, 4.0, 2.0) == ""
    (tmp_path / "p.onnx.json").write_text(json.dumps({"duration": 2.0}))
    said = horizon_warning("learned", policy, 4.0, 2.0)
    assert said == (
        "the policy learned (p.onnx) was trained on 2 s episodes; runs of 4 s, scored only past it, take "
        "it outside its training horizon"
    )
    (tmp_path / "p.onnx.json").write_text(json.dumps({"duration": 2.0, "training_duration": 4.0}))
    assert horizon_warning("learned", policy, 4.0, 2.0) == ""


def test_a_policy_whose_lengths_are_symbolic_runs_where_they_match(tmp_path):
    """An ONNX file whose input and output lengths are named dimensions (["batch", "obs"]) is taken
    when a trial run on the arm's observation gives its action (it was refused for its symbolic
    length), and refused in one line when it does not take that observation."""
    fits = linear_policy(tmp_path / "fits.onnx", PAPER.size, 3, symbolic=True)
    result = run_experiment(_config("paper-ellipse", fits, backend="python"))
    assert result.status == "completed"
    wrong = linear_policy(tmp_path / "wrong.onnx", PAPER.size + 1, 3, symbolic=True)
    with pytest.raises(ConfigError, match=f"does not take this arm's observation of {PAPER.size} entries"):
        build(_config("paper-ellipse", wrong))


def test_the_base_laws_a_policy_takes_are_the_registrys():
    """controller.params.base accepts every shipped law but a policy (and the designed
    excitation's law, which reads a file of its own too), read from the registry when a value is
    checked (a law registered after the policy module is one too), and names them."""
    from nnrobust.controllers.registry import registered_law, shipped_laws

    (base,) = [p for p in registered_law("policy").params if p.name == "base"]
    assert base.allowed == tuple(n for n in shipped_laws() if n not in ("policy", "joint-fourier"))
    assert {"nn", "pd", "slotine-li", "rbf-nn"} <= set(base.allowed)
    with pytest.raises(ConfigError, match="expected one of 'nn', .*'slotine-li', got 'policy'"):
        base.check("policy", 3, 2, "controller.params.base")
