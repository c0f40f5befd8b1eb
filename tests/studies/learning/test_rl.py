"""PPO and SAC with Stable-Baselines3 on the vector environment (docs/learning.md#ppo-and-sac):
each trains for a tiny budget, its ONNX file computes what the trained model's deterministic
``predict`` does, and run as a controller it gives the environment's rollout of the same policy;
an untrained residual is its base law, bit for bit."""

import json

import numpy as np
import pytest

from nnrobust.run import compiled
from nnrobust.run.experiment import run_experiment

pytest.importorskip("stable_baselines3")
if not compiled.available():
    pytest.skip(compiled.unavailable_reason(), allow_module_level=True)

from nnrobust.studies.base.plan import draw, experiment  # noqa: E402
from nnrobust.studies.learning import rl  # noqa: E402
from nnrobust.studies.learning.env import ArmEnv  # noqa: E402

ORT = pytest.importorskip("onnxruntime")


def _onnx_actions(path, obs: np.ndarray) -> np.ndarray:
    session = ORT.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    return session.run(None, {"obs": obs.astype(np.float32)})[0]


def _rollout(path, record, episode: int = 0):
    """The environment's episode ``episode`` under the policy file (float32 ONNX), its applied
    torques and info."""
    env = ArmEnv(
        "paper-ellipse", action=record["action"], controller=record["controller"], duration=record["duration"]
    )
    obs, _ = env.reset(seed=record["seed"])
    for _ in range(episode):
        obs, _ = env.reset()
    tau, ended, info = [], False, {}
    while not ended:
        obs, _, terminated, truncated, info = env.step(_onnx_actions(path, obs[None])[0].astype(float))
        tau.append(np.array(env.loop.applied_torque))
        ended = terminated or truncated
    return env, np.array(tau), info


@pytest.mark.parametrize("algorithm", rl.ALGORITHMS)
def test_training_writes_a_policy_that_is_the_model_and_runs_as_the_environment_scored_it(
    algorithm, tmp_path
):
    out = tmp_path / f"{algorithm}.onnx"
    hyper = (
        {"learning_starts": 100, "batch_size": 64}
        if algorithm == "sac"
        else {"n_steps": 64, "batch_size": 128}
    )
    record = rl.train("paper-ellipse", out, algorithm=algorithm, budget=0.3, duration=0.1, num_envs=2,
                      validation_episodes=2, eval_every=0.15, controller="no-u0", hyper=hyper, threads=2,
                      progress=None)  # fmt: skip
    stored = json.loads((tmp_path / f"{algorithm}.onnx.json").read_text())
    assert stored == json.loads(json.dumps(record))
    assert record["algorithm"] == algorithm and record["simulated_seconds"] >= 0.3
    assert [p["simulated_seconds"] for p in record["curve"]][:3] == pytest.approx([0.0, 0.15, 0.3])
    assert record["hyper"]["batch_size"] == hyper["batch_size"] and len(record["experiment_sha256"]) == 64
    assert record["versions"]["stable-baselines3"] != "not installed"
    # the file computes the model's deterministic action after VecNormalize's frozen statistics
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.vec_env import VecNormalize

    model = (PPO if algorithm == "ppo" else SAC).load(str(out) + ".zip", device="cpu")
    venv = VecNormalize.load(str(out) + ".vecnormalize.pkl", rl.sb3_vec_env(_vec(record)))
    venv.training = False
    obs = np.random.default_rng(1).normal(size=(64, 16)) * np.sqrt(venv.obs_rms.var) + venv.obs_rms.mean
    expected, _ = model.predict(venv.normalize_obs(obs.astype(np.float32)), deterministic=True)
    np.testing.assert_allclose(_onnx_actions(out, obs), expected, atol=2e-5)
    # run as a controller on episode 0's plant, it is the environment's rollout of the file
    env, tau, info = _rollout(out, record)
    spec = env.episodes.spec
    config = experiment(spec, env.episodes.base, draw(spec, 0), "no-u0").replace(
        controller={"kind": "policy", "params": {"file": str(out), "action": "residual", "base": "no-u0"}},
        simulation={"duration": record["duration"]},
    )
    run = run_experiment(config)
    np.testing.assert_allclose(run.tau, tau, rtol=1e-4, atol=1e-4 * float(np.abs(tau).max()))


def _vec(record):
    from nnrobust.studies.learning.vector import ArmVectorEnv

    return ArmVectorEnv("paper-ellipse", 2, action=record["action"], controller=record["controller"],
                        duration=record["duration"], verdicts=False, threads=1)  # fmt: skip


@pytest.mark.parametrize("algorithm", rl.ALGORITHMS)
def test_an_untrained_residual_is_its_base_law_bit_for_bit(algorithm, tmp_path):
    from stable_baselines3.common.vec_env import VecNormalize

    from nnrobust.studies.learning.vector import ArmVectorEnv

    vec = ArmVectorEnv(
        "paper-ellipse", 2, action="residual", controller="no-u0", duration=0.1, verdicts=False
    )
    venv = VecNormalize(rl.sb3_vec_env(vec))
    model = rl._make_model(algorithm, venv, rl.DEFAULTS[algorithm], 0, "residual")
    layers, output = rl.policy_layers(model, algorithm)
    path = rl.export_onnx(tmp_path / "zero.onnx", layers, output, np.zeros(16), np.ones(16), 1e-8)
    base = experiment(vec.episodes.spec, vec.episodes.base, draw(vec.episodes.spec, 0), "no-u0")
    base = base.replace(simulation={"duration": 0.1})
    policy = base.replace(
        controller={"kind": "policy", "params": {"file": str(path), "action": "residual", "base": "no-u0"}}
    )
    np.testing.assert_array_equal(run_experiment(policy).tau, run_experiment(base).tau)


def test_bad_arguments_are_named(tmp_path):
    from nnrobust.core.exceptions import ConfigError

    with pytest.raises(ConfigError, match="algorithm"):
        rl.train("paper-ellipse", tmp_path / "x.onnx", algorithm="a2c")
    with pytest.raises(ConfigError, match="budget"):
        rl.train("paper-ellipse", tmp_path / "x.onnx", budget=0)
    with pytest.raises(ConfigError, match="unknown for ppo: buffer_size"):
        rl.train("paper-ellipse", tmp_path / "x.onnx", hyper={"buffer_size": 10})


@pytest.mark.parametrize("output", ["clip", "tanh"])
def test_the_exported_file_is_its_formula(output, tmp_path):
    """clip((obs - mean) / sqrt(var + eps), ±10), the layers, then PPO's clip to [-1, 1] or SAC's
    tanh, against numpy; the observation and the action are large enough that both clips act."""
    rng = np.random.default_rng(3)
    W0, b0, W1 = rng.normal(size=(16, 5)), rng.normal(size=5), 3 * rng.normal(size=(5, 3))
    b1 = np.array([4.0, -4.0, 0.2])
    layers = [("linear", W0, b0), ("relu", None, None), ("linear", W1, b1)]
    mean, var = rng.normal(size=16), rng.uniform(0.5, 2.0, size=16)
    path = rl.export_onnx(tmp_path / "f.onnx", layers, output, mean, var, 1e-8)
    obs = rng.normal(size=(32, 16)) * 30.0
    x = np.clip((obs - mean) / np.sqrt(var + 1e-8), -rl.CLIP_OBS, rl.CLIP_OBS)
    y = np.maximum(x @ W0 + b0, 0.0) @ W1 + b1
    expected = np.clip(y, -1.0, 1.0) if output == "clip" else np.tanh(y)
    assert (np.abs(x) == rl.CLIP_OBS).any() and (np.abs(y) > 1).any()
    np.testing.assert_allclose(_onnx_actions(path, obs), expected, atol=1e-5)


def test_a_residual_on_a_tuned_law_starts_at_that_law_bit_for_bit(tmp_path):
    """tuned=DIR: the base law runs at the tuning's best setting (the row LAW-tuned); an untrained
    residual on it is the tuned law's run, which is not the untuned law's."""
    from stable_baselines3.common.vec_env import VecNormalize

    from nnrobust.studies.learning.vector import ArmVectorEnv

    tuning = tmp_path / "tuning"
    tuning.mkdir()
    best = {"controller.Kp": [400.0, 400.0], "controller.Kv": [40.0, 40.0]}
    (tuning / "summary.json").write_text(json.dumps({"controllers": {"no-u0": {"best": {"params": best}}}}))
    vec = ArmVectorEnv("paper-ellipse", 2, action="residual", controller="no-u0", duration=0.1,
                       verdicts=False, tuned=tuning)  # fmt: skip
    assert vec.episodes.law == "no-u0-tuned" and vec.episodes.kind == "no-u0" and vec.episodes.tuned == best
    model = rl._make_model("ppo", VecNormalize(rl.sb3_vec_env(vec)), rl.DEFAULTS["ppo"], 0, "residual")
    path = rl.export_onnx(
        tmp_path / "zero.onnx", *rl.policy_layers(model, "ppo"), np.zeros(16), np.ones(16), 1e-8
    )
    spec = vec.episodes.spec
    tuned = experiment(spec, vec.episodes.base, draw(spec, 0), "no-u0-tuned").replace(
        simulation={"duration": 0.1}
    )
    assert tuned.controller.Kp == [400.0, 400.0]
    policy = tuned.replace(
        controller={"kind": "policy", "params": {"file": str(path), "action": "residual", "base": "no-u0"}}
    )
    untuned = experiment(spec, vec.episodes.base, draw(spec, 0), "no-u0").replace(
        simulation={"duration": 0.1}
    )
    np.testing.assert_array_equal(run_experiment(policy).tau, run_experiment(tuned).tau)
    assert not np.array_equal(run_experiment(untuned).tau, run_experiment(tuned).tau)


class Stop(Exception):
    """Stands for Ctrl-C in the middle of a training."""


@pytest.mark.parametrize("algorithm", rl.ALGORITHMS)
def test_a_stopped_training_resumes_from_its_last_point(algorithm, tmp_path):
    """Stopped after its second curve point, a training leaves OUT.checkpoint; run again it goes on
    from there (the curve up to that point is the uninterrupted run's, the budget is spent once, the
    record says where it resumed) and the checkpoint is removed. Past the point the two runs differ:
    Stable-Baselines3 keeps no rollout in progress (docs/learning.md#ppo-and-sac)."""
    hyper = (
        {"learning_starts": 20, "batch_size": 32} if algorithm == "sac" else {"n_steps": 32, "batch_size": 64}
    )
    options = dict(algorithm=algorithm, budget=0.4, duration=0.1, num_envs=2, validation_episodes=1,
                   eval_every=0.1, controller="no-u0", hyper=hyper, threads=1)  # fmt: skip
    whole = rl.train("paper-ellipse", tmp_path / "whole.onnx", progress=None, **options)
    assert whole["resumed_at"] is None and not (tmp_path / "whole.onnx.checkpoint").exists()

    def stop_at_the_third_point(text):
        if "0.2 / 0.4 simulated s" in text:
            raise Stop

    out = tmp_path / "stopped.onnx"
    with pytest.raises(Stop):
        rl.train("paper-ellipse", out, progress=stop_at_the_third_point, **options)
    assert (tmp_path / "stopped.onnx.checkpoint" / "state.json").is_file() and not out.exists()
    said = []
    resumed = rl.train("paper-ellipse", out, progress=said.append, **options)
    assert said[0] == f"{algorithm} seed 0: resumed at 0.1 simulated s"
    assert resumed["resumed_at"] == pytest.approx(0.1)
    keys = ("simulated_seconds", "mean_return", "median_rms_torque")  # (0.1 s episodes: no error after 2 s)
    assert [{k: p[k] for k in keys} for p in resumed["curve"][:2]] == [
        {k: p[k] for k in keys} for p in whole["curve"][:2]
    ]
    # the budget spent once (PPO ends on a whole rollout of 2 x 32 steps, from wherever it resumed)
    assert 0.4 <= resumed["simulated_seconds"] < 0.4 + 0.064 + 1e-9
    points = [p["simulated_seconds"] for p in resumed["curve"]]
    assert points[:5] == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4]) and len(points) <= 6
    assert not (tmp_path / "stopped.onnx.checkpoint").exists()
