"""Training with the field's standard library: Stable-Baselines3's PPO and SAC on the vector
environment, exported to the policy-file layout (docs/learning.md#ppo-and-sac).

The environment is :class:`~nnrobust.studies.learning.vector.ArmVectorEnv` seen through
:class:`Sb3VecEnv` (Stable-Baselines3's ``VecEnv``, with its same-step reset), its observation
normalised by ``VecNormalize`` (running mean and variance, clipped at ±``CLIP_OBS``; the reward
scaled by its running return's spread). The budget is simulated seconds of training (each
environment step is one control period of one episode), the unit every study budget is stated
in. The learning curve is measured every ``eval_every`` simulated seconds on fixed validation
episodes drawn with another seed (plants the training never sees): the mean return and the median
``rms_error_after_2s`` of the deterministic policy. The ONNX file computes what
``model.predict(obs, deterministic=True)`` does after ``VecNormalize`` (the statistics frozen at
the end of training): PPO's Gaussian mean clipped to [-1, 1], SAC's squashed mean. With
``action="residual"`` (or ``"gains"``) the last layer starts at zero, so the untrained policy is
its base law exactly.

Stable-Baselines3 and PyTorch are the ``rl`` extra (``pip install 'nnrobust[rl]'``).
"""

from __future__ import annotations

import csv
import hashlib
import importlib.metadata
import io
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from ...core.exceptions import ConfigError, NNRobustError
from ...run.results import write_json_atomic

CURVE_COLUMNS = ("seed", "simulated_seconds", "wall_seconds", "mean_return", "median_rms_error_after_2s",
                 "median_rms_torque")  # fmt: skip
"""The columns of curves.csv: one row per seed and point of its learning curve."""

SAME_RUN = ("experiment_sha256", "algorithm", "budget_seconds", "action", "controller", "duration", "hyper")
"""A seed's stored record is reused when these (and the tuned setting) match the training asked
for (:func:`stored_training`)."""

ACTIVATIONS = ("tanh", "relu")
"""The networks' activation functions (``hyper["activation"]``)."""

ALGORITHMS = ("ppo", "sac")
"""The Stable-Baselines3 algorithms :func:`train` runs."""

CLIP_OBS = 10.0
"""VecNormalize's clip of the normalised observation (its default)."""

VALIDATION_SEED_OFFSET = 1_000_003
"""The validation episodes are the sweep's with seed ``seed + VALIDATION_SEED_OFFSET``."""

DEFAULTS: dict[str, dict[str, Any]] = {
    "ppo": {"n_steps": 256, "batch_size": 256, "n_epochs": 10, "learning_rate": 3e-4, "gamma": 0.99,
            "gae_lambda": 0.95, "clip_range": 0.2, "ent_coef": 0.0, "net_arch": [64, 64],
            "activation": "tanh", "log_std_init": -1.0},
    "sac": {"buffer_size": 200_000, "batch_size": 256, "learning_rate": 3e-4, "gamma": 0.99, "tau": 0.005,
            "learning_starts": 1000, "train_freq": 1, "gradient_steps": 1, "net_arch": [64, 64],
            "activation": "relu"},
}  # fmt: skip
"""Each algorithm's hyper-parameters unless ``hyper`` says otherwise (the record holds them all)."""


def _sb3():
    try:
        import stable_baselines3
        import torch
    except ImportError as err:
        raise NNRobustError(
            f"training with PPO or SAC needs Stable-Baselines3 and PyTorch ({err}): "
            "pip install 'nnrobust[rl]'"
        ) from None
    return stable_baselines3, torch


def _vec_env_base():
    from stable_baselines3.common.vec_env import VecEnv

    return VecEnv


def sb3_vec_env(vec):
    """``vec`` (an ArmVectorEnv) as Stable-Baselines3's VecEnv (:class:`Sb3VecEnv`)."""
    VecEnv = _vec_env_base()

    class Sb3VecEnv(VecEnv):
        """An ArmVectorEnv as Stable-Baselines3's VecEnv: an episode that ends restarts in the same
        step (its last observation in ``info["terminal_observation"]``, a time limit marked
        ``TimeLimit.truncated``), observations as float32.
        """

        def __init__(self, vec):
            import gymnasium as gym

            self.vec = vec
            low, high = vec.single_action_space.low, vec.single_action_space.high
            space = gym.spaces.Box(-np.inf, np.inf, vec.single_observation_space.shape, dtype=np.float32)
            super().__init__(vec.num_envs, space, gym.spaces.Box(low, high, dtype=np.float32))
            self._actions = np.zeros(vec.action_space.shape)
            self._next_seed: int | None = None

        def seed(self, seed=None):
            self._next_seed = seed
            return [seed] * self.num_envs

        def reset(self):
            obs, _ = self.vec.reset(seed=self._next_seed)
            self._next_seed = None
            return obs.astype(np.float32)

        def step_async(self, actions):
            self._actions = np.asarray(actions, dtype=float)

        def step_wait(self):
            obs, reward, terminated, truncated, _ = self.vec.step(self._actions)
            done = terminated | truncated
            infos: list[dict] = [{} for _ in range(self.num_envs)]
            for j in np.flatnonzero(done):
                infos[j]["terminal_observation"] = obs[j].astype(np.float32)
                infos[j]["TimeLimit.truncated"] = bool(truncated[j] and not terminated[j])
                obs[j] = self.vec.restart(int(j))
            return obs.astype(np.float32), reward.astype(np.float32), done, infos

        def close(self):
            pass

        def get_attr(self, attr_name, indices=None):
            return [getattr(self.vec, attr_name)] * len(self._indices(indices))

        def set_attr(self, attr_name, value, indices=None):
            setattr(self.vec, attr_name, value)

        def env_method(self, method_name, *args, indices=None, **kwargs):
            return [getattr(self.vec, method_name)(*args, **kwargs)] * len(self._indices(indices))

        def env_is_wrapped(self, wrapper_class, indices=None):
            return [False] * len(self._indices(indices))

        def _indices(self, indices):
            if indices is None:
                return range(self.num_envs)
            return [indices] if isinstance(indices, int) else indices

    return Sb3VecEnv(vec)


def experiment_sha256(experiment) -> str:
    """SHA-256 of the experiment's file (a preset's shipped file), as the record's input hash."""
    from .env import _preset

    path = Path(experiment)
    if not path.is_file():
        path = _preset(str(experiment))
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _versions() -> dict[str, str]:
    out = {}
    for name in ("nnrobust", "stable-baselines3", "torch", "gymnasium", "numpy", "onnx"):
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def _layers(sequential) -> list[tuple[str, np.ndarray | None, np.ndarray | None]]:
    """(kind, W, b) of a torch Sequential of Linear and activation layers, in order."""
    import torch.nn as nn

    out: list[tuple[str, np.ndarray | None, np.ndarray | None]] = []
    for module in sequential if isinstance(sequential, nn.Sequential) else [sequential]:
        if isinstance(module, nn.Linear):
            out.append(("linear", module.weight.detach().cpu().numpy().T, module.bias.detach().cpu().numpy()))
        elif isinstance(module, nn.Tanh):
            out.append(("tanh", None, None))
        elif isinstance(module, nn.ReLU):
            out.append(("relu", None, None))
        else:
            raise NNRobustError(f"exporting the policy: no ONNX form for the layer {type(module).__name__}")
    return out


def policy_layers(model, algorithm: str) -> tuple[list, str]:
    """The deterministic actor of a trained model as layers (:func:`_layers`), and its output
    map: ``clip`` (PPO: the Gaussian's mean, clipped to the action box as ``predict`` does) or
    ``tanh`` (SAC: the squashed mean).
    """
    policy = model.policy
    if algorithm == "ppo":
        return _layers(policy.mlp_extractor.policy_net) + _layers(policy.action_net), "clip"
    return _layers(policy.actor.latent_pi) + _layers(policy.actor.mu), "tanh"


def export_onnx(
    path: str | Path, layers: list, output: str, mean: np.ndarray, var: np.ndarray, eps: float
) -> Path:
    """The policy file (docs/learning.md#policy-files): input ``obs`` [batch, d] float32,
    normalised as VecNormalize does (``clip((obs - mean) / sqrt(var + eps), ±CLIP_OBS)``), the
    layers, then ``output``; output ``action`` [batch, n]. Written atomically.
    """
    from onnx import helper, numpy_helper

    from .es import write_policy

    f = np.float32
    d = int(mean.size)
    tensors = [
        numpy_helper.from_array(mean.astype(f), "mean"),
        numpy_helper.from_array(np.sqrt(var + eps).astype(f), "scale"),
        numpy_helper.from_array(np.array(-CLIP_OBS, dtype=f), "clip_low"),
        numpy_helper.from_array(np.array(CLIP_OBS, dtype=f), "clip_high"),
        numpy_helper.from_array(np.array(-1.0, dtype=f), "action_low"),
        numpy_helper.from_array(np.array(1.0, dtype=f), "action_high"),
    ]
    nodes = [
        helper.make_node("Sub", ["obs", "mean"], ["centred"]),
        helper.make_node("Div", ["centred", "scale"], ["scaled"]),
        helper.make_node("Clip", ["scaled", "clip_low", "clip_high"], ["x0"]),
    ]
    x, n = "x0", 0
    for i, (kind, W, b) in enumerate(layers):
        if kind == "linear":
            tensors += [
                numpy_helper.from_array(W.astype(f), f"W{i}"),
                numpy_helper.from_array(b.astype(f), f"b{i}"),
            ]
            nodes += [
                helper.make_node("MatMul", [x, f"W{i}"], [f"m{i}"]),
                helper.make_node("Add", [f"m{i}", f"b{i}"], [f"y{i}"]),
            ]
            n = W.shape[1]
        else:
            nodes.append(helper.make_node("Tanh" if kind == "tanh" else "Relu", [x], [f"y{i}"]))
        x = f"y{i}"
    if output == "clip":
        nodes.append(helper.make_node("Clip", [x, "action_low", "action_high"], ["action"]))
    else:
        nodes.append(helper.make_node("Tanh", [x], ["action"]))
    return write_policy(path, "nnrobust-sb3-policy", nodes, tensors, d, n)


def validate(model, normalize, vec, seed: int) -> dict:
    """The deterministic policy on ``vec``'s episodes 0 … N − 1 of ``seed`` (one each): the mean
    return and the median, over the episodes, of ``rms_error_after_2s`` (NaN where a run is too
    short to have it) and of ``rms_torque``.
    """
    keys = ("rms_error_after_2s", "rms_torque")
    obs, _ = vec.reset(seed=seed)
    total, alive = np.zeros(vec.num_envs), np.ones(vec.num_envs, dtype=bool)
    seen = {key: np.full(vec.num_envs, np.nan) for key in keys}
    while alive.any():
        action, _ = model.predict(normalize.normalize_obs(obs.astype(np.float32)), deterministic=True)
        obs, reward, terminated, truncated, info = vec.step(action)
        total += np.where(alive, reward, 0.0)
        metrics = info.get("metrics", {})  # batched: metrics[key][j], with the mask metrics["_" + key]
        for j in np.flatnonzero(alive & (terminated | truncated)):
            for key in keys:
                if key in metrics and metrics["_" + key][j] and metrics[key][j] is not None:
                    seen[key][j] = float(metrics[key][j])
        alive &= ~(terminated | truncated)

    def median(key):
        values = seen[key][np.isfinite(seen[key])]
        return float(np.median(values)) if values.size else math.nan

    return {
        "mean_return": float(total.mean()),
        "median_rms_error_after_2s": median("rms_error_after_2s"),
        "median_rms_torque": median("rms_torque"),
    }


def _make_model(algorithm: str, venv, hyper: dict, seed: int, action: str):
    sb3, torch = _sb3()
    activation = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[hyper["activation"]]  # ACTIVATIONS
    kwargs = {k: v for k, v in hyper.items() if k not in ("net_arch", "activation", "log_std_init")}
    policy_kwargs: dict[str, Any] = {"net_arch": list(hyper["net_arch"]), "activation_fn": activation}
    if algorithm == "ppo":
        policy_kwargs["log_std_init"] = hyper["log_std_init"]
        model = sb3.PPO(
            "MlpPolicy", venv, policy_kwargs=policy_kwargs, seed=seed, device="cpu", verbose=0, **kwargs
        )
        last = model.policy.action_net
    else:
        model = sb3.SAC(
            "MlpPolicy", venv, policy_kwargs=policy_kwargs, seed=seed, device="cpu", verbose=0, **kwargs
        )
        last = model.policy.actor.mu
    if action in ("residual", "gains"):  # the untrained policy is its base law, exactly
        with torch.no_grad():
            last.weight.zero_()
            last.bias.zero_()
    return model


def hyper_settings(algorithm: str, hyper: dict | None) -> dict:
    """Every hyper-parameter of ``algorithm``: its defaults (:data:`DEFAULTS`) with ``hyper`` over
    them; an unknown name or activation is refused.
    """
    unknown = sorted(set(hyper or {}) - set(DEFAULTS[algorithm]))
    if unknown:
        raise ConfigError(
            "hyper",
            f"unknown for {algorithm}: {', '.join(unknown)} (known: {', '.join(DEFAULTS[algorithm])})",
        )
    settings = {**DEFAULTS[algorithm], **(hyper or {})}
    if settings["activation"] not in ACTIVATIONS:
        raise ConfigError(
            "hyper.activation", f"expected one of {', '.join(ACTIVATIONS)}, got {settings['activation']!r}"
        )
    return settings


def _check_rollout(algorithm: str, steps: int, settings: dict, num_envs: int, period: float, budget: float):
    """PPO trains on whole rollouts (n_steps x environments): a budget below one is refused, not
    rounded up to it.
    """
    if algorithm == "ppo" and steps < settings["n_steps"] * num_envs:
        rollout = settings["n_steps"] * num_envs * period
        raise ConfigError(
            "budget",
            f"{budget:g} simulated s is less than one PPO rollout ({settings['n_steps']} steps x {num_envs} "
            f"environments x the {period:g} s period = {rollout:g} s), and PPO trains on whole rollouts: "
            f"give a budget of at least {rollout:g} s, or fewer n_steps or environments",
        )


def _start(checkpoint, algorithm: str, vec, settings: dict, seed: int, action: str):
    """(model, normalised env, curve so far, resumed): a stopped training's checkpoint, else a new
    model on ``vec`` (an ArmVectorEnv).
    """
    from stable_baselines3.common.vec_env import VecNormalize

    resumed = checkpoint.load(algorithm, sb3_vec_env(vec))
    if resumed is not None:
        return (*resumed, True)
    venv = VecNormalize(
        sb3_vec_env(vec), norm_obs=True, norm_reward=True, clip_obs=CLIP_OBS, gamma=settings["gamma"]
    )
    venv.seed(seed)
    return _make_model(algorithm, venv, settings, seed, action), venv, [], False


def train(
    experiment: str | Path,
    out: str | Path,
    *,
    algorithm: str = "ppo",
    budget: float = 60.0,
    action: str = "residual",
    controller: str | None = None,
    vary: dict | None = None,
    duration: float | None = None,
    seed: int = 0,
    num_envs: int = 8,
    validation_episodes: int = 8,
    eval_every: float | None = None,
    hyper: dict | None = None,
    residual_scale: float = 0.1,
    gain_range: float = 4.0,
    tuned: str | Path | None = None,
    threads: int | None = None,
    progress=print,
) -> dict:
    """Train a policy with Stable-Baselines3's ``algorithm`` (``"ppo"`` or ``"sac"``) for
    ``budget`` simulated seconds on ``experiment``'s vector environment; write ``out`` (the ONNX
    file), ``out`` + ``.json`` (the record: algorithm, hyper-parameters, seed, budget, wall time,
    versions, the experiment's SHA-256, the learning curve) and ``out`` + ``.zip`` (the model,
    Stable-Baselines3's format) with ``out`` + ``.vecnormalize.pkl``. Returns the record.

    The episodes are ``duration`` seconds long (default: the experiment's ``simulation.duration``,
    the horizon a run is scored on). ``eval_every`` (simulated seconds of training, default a tenth
    of the budget) spaces the learning curve's points. ``tuned`` (a tuning's folder or
    summary.json, a study's ``REPORT.json#CASE``) runs the base law at its tuned setting: a
    residual then learns on top of the best model-based law the tuning found.
    """
    sb3, torch = _sb3()
    from stable_baselines3.common.callbacks import BaseCallback

    from .vector import ArmVectorEnv

    if algorithm not in ALGORITHMS:
        raise ConfigError(
            "algorithm", f"expected one of {', '.join(ALGORITHMS)} (or 'cmaes'), got {algorithm!r}"
        )
    if isinstance(budget, bool) or not isinstance(budget, (int, float)) or not budget > 0:
        raise ConfigError("budget", f"expected simulated seconds > 0, got {budget!r}")
    settings = hyper_settings(algorithm, hyper)
    started = time.perf_counter()
    torch.set_num_threads(1)  # the environment's C++ threads use the cores
    common: dict[str, Any] = {"action": action, "vary": vary, "controller": controller, "duration": duration,
                              "residual_scale": residual_scale, "gain_range": gain_range, "threads": threads,
                              "tuned": tuned}  # fmt: skip
    vec = ArmVectorEnv(experiment, num_envs, seed=seed, verdicts=False, **common)
    checking = ArmVectorEnv(experiment, validation_episodes, seed=seed, verdicts=True, **common)
    period, horizon = vec.episodes.period, vec.episodes.horizon
    steps = int(math.ceil(budget / period))
    _check_rollout(algorithm, steps, settings, num_envs, period, budget)
    every = max(1, int(round((eval_every if eval_every is not None else budget / 10) / period)))
    validation_seed = seed + VALIDATION_SEED_OFFSET
    path = Path(out)
    sha = experiment_sha256(experiment)  # the checkpoint's and the record's
    same = {"experiment_sha256": sha, "algorithm": algorithm, "hyper": settings,
            "seed": seed, "budget": budget, "every": every, **common, "num_envs": num_envs,
            "tuned": str(tuned) if tuned is not None else None,
            "validation_episodes": validation_episodes}  # fmt: skip
    checkpoint = Checkpoint(path, same)  # what a stopped training of the same resumes from
    model, venv, curve, resumed = _start(checkpoint, algorithm, vec, settings, seed, action)
    if resumed:
        started -= curve[-1]["wall_seconds"]  # the wall time already spent, before the interruption
        if progress:
            progress(f"{algorithm} seed {seed}: resumed at {model.num_timesteps * period:.4g} simulated s")

    def point(simulated_steps: int) -> None:
        venv.training = False
        score = validate(model, venv, checking, validation_seed)
        venv.training = True
        curve.append(
            {
                "simulated_seconds": simulated_steps * period,
                "wall_seconds": time.perf_counter() - started,
                **score,
            }
        )
        if progress:
            error = score["median_rms_error_after_2s"]
            shown = "-" if math.isnan(error) else f"{1e3 * error:.3g} mm"
            progress(f"{algorithm} seed {seed}: {simulated_steps * period:.4g} / {budget:.4g} simulated s, "
                     f"validation return {score['mean_return']:.4g}, median error {shown}")  # fmt: skip

    class Curve(BaseCallback):
        def __init__(self, done: int):
            super().__init__()
            self.next = (done // every + 1) * every

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next:
                point(self.num_timesteps)
                checkpoint.save(model, venv, curve)  # where a stopped training resumes
                self.next += every
            return True

    done = model.num_timesteps
    if not curve:
        point(0)
    model.learn(
        total_timesteps=max(steps - done, 0),
        callback=Curve(done),
        reset_num_timesteps=done == 0,
        progress_bar=False,
    )
    if not curve or curve[-1]["simulated_seconds"] < model.num_timesteps * period:
        point(model.num_timesteps)
    layers, output = policy_layers(model, algorithm)
    rms: Any = venv.obs_rms  # one RunningMeanStd: the observation is one array
    path = export_onnx(path, layers, output, rms.mean, rms.var, venv.epsilon)
    model.save(str(path) + ".zip")
    venv.save(str(path) + ".vecnormalize.pkl")
    record = {
        "experiment": str(experiment),
        "experiment_sha256": sha,
        "algorithm": algorithm,
        "hyper": settings,
        "action": action,
        "controller": vec.episodes.kind,
        "tuned": {"file": str(tuned), "settings": vec.episodes.tuned} if tuned is not None else None,
        "residual_scale": residual_scale,
        "gain_range": gain_range,
        "vary": vary or {},
        "duration": horizon,
        "training_duration": horizon,  # the episodes' horizon: a study scoring past it warns
        "reward_window": [0.0, horizon],
        "seed": seed,
        "num_envs": num_envs,
        "budget_seconds": budget,
        "simulated_seconds": model.num_timesteps * period,
        "simulations": model.num_timesteps * period / horizon,
        "wall_seconds": time.perf_counter() - started,
        "validation": {"seed": validation_seed, "episodes": validation_episodes},
        "resumed_at": done * period if resumed else None,  # simulated s: an interrupted training
        "versions": _versions(),
        "layout": vec.episodes.layout.describe(),
        "curve": curve,
    }
    write_json_atomic(Path(str(path) + ".json"), record)
    checkpoint.remove()
    return record


class Checkpoint:
    """Where a training stopped (Ctrl-C, a killed process) resumes: at each point of the learning
    curve, ``OUT.checkpoint/`` holds the model, its normalisation, SAC's replay buffer and the
    curve so far, with what the training is (``same``); a training of the same ``same`` starts
    from it, another starts afresh. Removed when the training ends.

    A resumed training is not the uninterrupted one continued bit for bit: Stable-Baselines3 does
    not save a rollout in progress, the environments' episodes in flight or the random generators'
    states, so it goes on from the last point with fresh episodes. Its curve up to that point is
    the uninterrupted run's, and its record says where it resumed (``resumed_at``).
    """

    def __init__(self, out: Path, same: dict):
        self.folder = Path(str(out) + ".checkpoint")
        self.same = json.loads(json.dumps(same, default=str))

    def save(self, model, venv, curve: list[dict]) -> None:
        """The training as it is now, replacing the last checkpoint (written apart, then renamed)."""
        import shutil

        fresh = self.folder.with_name(self.folder.name + ".new")
        shutil.rmtree(fresh, ignore_errors=True)
        fresh.mkdir(parents=True)
        model.save(str(fresh / "model.zip"))
        venv.save(str(fresh / "vecnormalize.pkl"))
        if hasattr(model, "save_replay_buffer"):
            model.save_replay_buffer(str(fresh / "replay.pkl"))
        write_json_atomic(fresh / "state.json", {"same": self.same, "curve": curve})
        old = self.folder.with_name(self.folder.name + ".old")
        shutil.rmtree(old, ignore_errors=True)
        if self.folder.exists():
            self.folder.rename(old)
        fresh.rename(self.folder)
        shutil.rmtree(old, ignore_errors=True)

    def load(self, algorithm: str, sb3_env):
        """(model, normalised env, curve) of a checkpoint of this training, or None."""
        state_file = self.folder / "state.json"
        try:
            state = json.loads(state_file.read_text())
        except (OSError, ValueError):
            return None
        if state.get("same") != self.same or not state.get("curve"):
            return None
        sb3, _ = _sb3()
        from stable_baselines3.common.vec_env import VecNormalize

        venv = VecNormalize.load(str(self.folder / "vecnormalize.pkl"), sb3_env)
        venv.training = True
        model = getattr(sb3, algorithm.upper()).load(str(self.folder / "model.zip"), env=venv, device="cpu")
        if (self.folder / "replay.pkl").is_file():
            model.load_replay_buffer(str(self.folder / "replay.pkl"))
        return model, venv, state["curve"]

    def remove(self) -> None:
        """The checkpoint of a finished training, gone."""
        import shutil

        shutil.rmtree(self.folder, ignore_errors=True)


def stored_training(path: Path, wanted: dict, where: str = "--out") -> dict | None:
    """The record of the training stored at ``path`` (a policy file and its ``.json`` record)
    when it is the training ``wanted`` describes (:data:`SAME_RUN`; ``tuned_file``, and
    ``tuned_settings`` where given, the base law's tuned setting); None when nothing is stored
    there. Another training there is refused, naming ``where``.
    """
    record = Path(str(path) + ".json")
    if not record.is_file():
        return None
    stored = json.loads(record.read_text())
    differs = [k for k in SAME_RUN if k in wanted and stored.get(k) != wanted[k]]
    tuned = stored.get("tuned") or {}
    if tuned.get("file") != wanted.get("tuned_file") or (
        "tuned_settings" in wanted and tuned.get("settings") != wanted["tuned_settings"]
    ):
        differs.append("tuned setting")
    if differs:
        raise ConfigError(
            where,
            f"{path.parent} holds another training (its {', '.join(differs)} differ): choose another "
            "folder" + (" or give --overwrite" if where != "--out" else ""),
        )
    return stored if path.is_file() else None


def tuned_budgets(tuned: str | Path | None) -> dict[str, float]:
    """The simulated seconds each tuned law of a study's case trained for (its report's
    ``training``: the tunings' simulations times the run's duration, every seed), from
    ``REPORT.json#CASE``; {} for any other source (a tuning's folder does not say its duration).
    """
    from ..base.tuned import study_report

    report, case = study_report(tuned) if tuned is not None else (None, "")
    if report is None:
        return {}
    laws = ((report.get("cases") or {}).get(case) or {}).get("controllers") or {}
    out = {}
    for law, entry in laws.items():
        seconds = ((entry or {}).get("training") or {}).get("simulated_seconds")
        if (
            (entry or {}).get("tuned")
            and not (entry or {}).get("trained")
            and isinstance(seconds, int | float)
        ):
            out[law] = float(seconds)
    return out


def write_curves(
    out: Path, records: list[dict], marks: dict[str, float] | None = None, seed_offset: int = 0
) -> None:
    """``out``/curves.csv (one row per seed and point) and curves.png (the validation error and
    return against simulated seconds, one line per seed; ``marks``, each tuned law's own training
    in simulated seconds, drawn on the same axis). A seed is shown as its record's seed less
    ``seed_offset`` (a study's seeds 0, 1, ... of its training seeds).
    """
    from ...outputs.plots import plt, save_figure
    from ...run.results import write_text_atomic

    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(CURVE_COLUMNS)
    for record in records:
        for point in record["curve"]:
            writer.writerow([record["seed"], *(point[k] for k in CURVE_COLUMNS[1:])])
    write_text_atomic(out / "curves.csv", text.getvalue())
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.4, 5.6), sharex=True)
    for record in records:
        x = [p["simulated_seconds"] for p in record["curve"]]
        top.plot(
            x,
            [1e3 * p["median_rms_error_after_2s"] for p in record["curve"]],
            marker="o",
            label=f"seed {record['seed'] - seed_offset}",
        )
        bottom.plot(x, [p["mean_return"] for p in record["curve"]], marker="o")
    for i, (law, seconds) in enumerate(sorted((marks or {}).items())):
        for ax in (top, bottom):
            ax.axvline(
                seconds,
                color=f"C{(i + 3) % 10}",
                ls=":",
                lw=1,
                label=f"{law}'s tuning" if ax is top else None,
            )
    top.set_ylabel("validation median\nRMS error, t >= 2 s [mm]")
    bottom.set_ylabel("validation mean return")
    bottom.set_xlabel("simulated seconds of training")
    top.legend(fontsize="small")
    first = records[0]
    on = "" if first["action"] == "torque" else f" on {first['controller']}"  # a torque policy has no base
    top.set_title(f"{first['algorithm'].upper()}, {first['action']}{on}")
    save_figure(fig, out, "curves")
    plt.close(fig)
