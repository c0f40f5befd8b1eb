"""A Gymnasium environment for any experiment: the honest plant, one control period a step.

Each episode is one run of the experiment on the compiled loop (``SteppedLoop``,
csrc/closed_loop.cpp): the same plant, sensors, delay, effort limits and verdicts as
``nnrobust run``. Episode k is sample k of a sweep (:func:`nnrobust.studies.base.plan.draw`): its
``[vary]`` box (domain randomisation) and its seeds for the nominal model's error and the sensor
noise, so an episode is reproducible and is the same plant a sweep row with that sample runs.
docs/learning.md documents the observation, the actions, the reward and the info dict.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from ...controllers.laws.policy import ACTIONS
from ...controllers.observation import ObservationLayout
from ...core.exceptions import ConfigError, NNRobustError

try:
    import gymnasium as gym
except ImportError as err:  # pragma: no cover - the extra is missing
    raise NNRobustError("the learning environment needs Gymnasium: pip install 'nnrobust[learning]'") from err

ACTION_MODES = {name: mode for mode, name in enumerate(ACTIONS)}
"""The policy law's action modes by their number on the compiled loop (csrc/learning.hpp's
ActionMode). What an action is: ``torque``, the command itself, a ⊙ τ_max; ``residual``, added to the base
law's command (eq. 9 with or without u_0, the PD, any compiled law), scale · a ⊙ τ_max; ``gains``,
two entries: the base law's position and velocity gains (K_p, K_v of eq. 9; K_p, K_d of the PD)
times G^a_0 and G^a_1 over the period, G = ``gain_range``."""

ENV_VERSION = 1
"""Version of the environment's interface (observation, actions, reward, info): registered ids
end in ``-v1``."""


def checked_actions(actions, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``actions`` as a float array of exactly ``shape`` with every entry finite, else one line
    naming ``what``: a NaN would become a NaN reward, and a scalar is not one number per joint.
    """
    try:
        array = np.asarray(actions, dtype=float)
    except (TypeError, ValueError) as err:
        raise ConfigError(what, f"expected numbers of shape {shape}, got {type(actions).__name__}") from err
    if array.shape != shape:
        raise ConfigError(what, f"expected shape {shape}, got {array.shape} ({str(actions)[:60]})")
    if not np.isfinite(array).all():
        where = np.argwhere(~np.isfinite(array))[0]
        raise ConfigError(
            what, f"entry {tuple(int(i) for i in where)} is {array[tuple(where)]}: actions are finite"
        )
    return array


@dataclass(frozen=True)
class Reward:
    """The reward per control period (docs/learning.md#reward), all weights ≥ 0.

    r_k = - error · |e_p| / L - effort · mean_i (τ_i / τ_max,i)² - limits · (joints beyond a
    position or speed limit) / n, and - runaway once when the run diverges (the episode then
    terminates).

    |e_p| is the position part of the measured task error [m] (the observation's ``e``), L the
    path's size (its bounding-box diagonal, at least 5 cm, as the ``tracking lost`` verdict), τ
    the torque applied over the period and τ_max the effort limits. The limits are the URDF's;
    a joint beyond a position limit is at its stop.
    """

    error: float = 1.0
    effort: float = 0.01
    limits: float = 0.1
    runaway: float = 100.0

    def __post_init__(self):
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not 0 <= value < math.inf:
                raise ConfigError(f"reward.{f.name}", f"expected a finite weight >= 0, got {value!r}")


def _source_spec(experiment, vary: dict | None, seed: int, controller: str | None, tuned=None):
    """(SweepSpec, the base law's row name, its tuned settings) of an environment's source: a
    sweep file (its base, [set] and [vary]), or a preset / experiment file with an optional
    ``vary`` box; with ``tuned`` (a tuning's DIR or summary.json, a study's REPORT.json#CASE, as
    ``--tuned`` reads them), the base law runs at its tuned setting (the row ``LAW-tuned``).
    """
    from ...config.presets import preset_names
    from ...controllers.registry import shipped_laws
    from ..base.plan import load_sweep, parse_sweep

    text = str(experiment)
    if controller is not None and controller not in shipped_laws():
        raise ConfigError(
            "controller",
            f"{controller!r}: the base law supplies the observation's model and the residual's torque on "
            f"the compiled loop, so it is one of {', '.join(shipped_laws())}",
        )
    is_sweep = text.endswith(".toml") and Path(text).is_file() and _is_sweep_file(Path(text))
    if is_sweep:
        if vary:
            raise ConfigError(
                "vary", f"{text} is a sweep file: its [vary] box is the episodes' uncertainty set"
            )
        spec = load_sweep(text)
        spec.seed = seed
    else:
        if not (text in preset_names() or (text.endswith(".toml") and Path(text).is_file())):
            raise ConfigError(
                "experiment",
                f"{text!r} is neither a preset, an experiment file nor a sweep file; presets: "
                f"{', '.join(preset_names())}",
            )
        from ...config import load_config

        kind = load_config(Path(text) if text.endswith(".toml") else _preset(text)).controller.kind
        if controller is None and kind not in shipped_laws():
            raise ConfigError(
                "controller",
                f"{text}'s law ({kind}) has no compiled twin, and the base law supplies the observation's "
                f"model and the residual's torque on the compiled loop: give controller = one of "
                f"{', '.join(shipped_laws())}",
            )
        spec = parse_sweep(
            {
                "name": "env",
                "base": str(Path(text).resolve()) if text.endswith(".toml") else text,
                "controllers": [controller or kind],
                "seed": seed,
                "vary": dict(vary or {}),
            },
            "experiment",
        )
    law = controller or spec.controllers[0]
    if law not in spec.controllers:
        raise ConfigError(
            "controller", f"{law!r} is not one of the sweep's controllers: {', '.join(spec.controllers)}"
        )
    settings: dict = {}
    if tuned is not None:
        from ..base.tuned import tuned_settings, with_controllers

        settings = tuned_settings(tuned, [law], varied=list(spec.vary), entries=spec.entries).get(law, {})
        if settings:
            spec = with_controllers(spec, [law], {law: settings})
            law = spec.controllers[0]  # LAW-tuned: its entry sets the tuned keys
    return spec, law, settings


def _preset(name: str) -> Path:
    from ...config.presets import preset_path

    return preset_path(name)


def _is_sweep_file(path: Path) -> bool:
    import tomllib

    try:
        return "controllers" in tomllib.loads(path.read_text(encoding="utf-8"))  # a sweep lists its laws
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False  # load_config names what is wrong with it


class Episodes:
    """The episodes of an environment: episode k is sample k of the source's sweep, built and
    loaded on the compiled loop. Shared by :class:`ArmEnv` and the vector environment.
    """

    def __init__(
        self,
        experiment,
        *,
        action: str,
        vary,
        seed: int,
        controller,
        residual_scale,
        duration,
        gain_range,
        tuned=None,
    ):
        """See :class:`ArmEnv` for the arguments."""
        from ...run import compiled

        if not compiled.available():
            raise NNRobustError(
                f"the learning environment runs on the compiled loop: {compiled.unavailable_reason()}"
            )
        if action not in ACTION_MODES:
            raise ConfigError("action", f"{action!r} is not one of {', '.join(ACTION_MODES)}")
        if isinstance(residual_scale, bool) or not (
            isinstance(residual_scale, int | float) and residual_scale > 0
        ):
            raise ConfigError("residual_scale", f"expected a number > 0, got {residual_scale!r}")
        from ...controllers.laws.policy import LAW as POLICY

        # the range a policy law accepts: a policy trained here runs as controller.kind = "policy"
        (declared,) = (p for p in POLICY.params if p.name == "gain_range")
        gain_range = declared.check(gain_range, None, 1, "gain_range")
        if duration is not None and (
            isinstance(duration, bool) or not isinstance(duration, int | float) or not 0 < duration < math.inf
        ):
            raise ConfigError("duration", f"expected a duration > 0 [s], got {duration!r}")
        from ..base.plan import base_values

        self.spec, self.law, self.tuned = _source_spec(experiment, vary, seed, controller, tuned)
        # the base law's kind: a policy file's controller.params.base (the row may be LAW-tuned)
        self.kind = self.spec.entries.get(self.law, {}).get("kind", self.law)
        self.base = base_values(self.spec)
        own = self.base.get("controller", {})
        if isinstance(own, dict) and own.get("kind") != self.kind:  # another law than the file's
            for key in ("class", "params"):  # the file's law's own settings: not the base law's
                own.pop(key, None)
        self.action, self.mode = action, ACTION_MODES[action]
        self.residual_scale, self.duration = float(residual_scale), duration
        self.gain_range = float(gain_range)
        self.setup, self.loop, self.loop_spec = None, None, None
        first = self.build(0)  # the shapes, limits and period every episode shares
        robot = first.robot
        self.n, self.m = robot.nq, robot.m
        self.layout = ObservationLayout(self.n, self.m)
        limit = first.plant.torque_limit
        if limit is None or not np.all(np.isfinite(limit)):
            raise ConfigError(
                "plant.torque_limit",
                "the actions are scaled by the effort limits: every joint needs one (set plant.torque_limit "
                "or give the URDF's <limit effort=...>)",
            )
        self.torque_limit = np.asarray(limit, dtype=float)
        from ...controllers.laws.policy import action_scale, no_gains

        if action == "gains" and not first.controller.scale_gains(1.0, 1.0):
            raise ConfigError("controller", no_gains(self.kind))
        self.action_scale = action_scale(action, self.torque_limit, self.residual_scale, self.gain_range)
        self.action_size = self.action_scale.size
        self.speed_limit = np.asarray(robot.velocity_limits, dtype=float)
        self.lower, self.upper = (
            np.asarray(a, dtype=float) for a in (robot.lower_limits, robot.upper_limits)
        )
        self.period = first.config.simulation.control_period
        self.horizon = first.config.simulation.duration  # an episode's length [s]
        self.cache = 64  # built episodes kept: candidates of a training generation share plants
        self._built: dict = {(self.spec.seed, 0): first}

    def build(self, episode: int):
        """The built experiment of ``episode`` (sample ``episode`` of the sweep, or of its grid)."""
        from ...run.experiment import build
        from ..base.plan import draw, experiment

        spec = self.spec
        index = episode % spec.size if spec.grid_keys else episode
        sample = draw(spec, index)
        config = experiment(spec, self.base, sample, self.law)
        if self.duration is not None:
            config.simulation.duration = float(self.duration)
        return build(config)

    def start(self, episode: int):
        """A new episode's (setup, loop, spec, path size): the compiled loop at t = 0."""
        from ...run import compiled
        from ...run.verdicts import path_size

        key = (self.spec.seed, episode)
        setup = self._built.get(key)
        if setup is None or setup.plant.engine is not None:  # a MuJoCo plant steps its own data
            setup = self.build(episode)
            self._built[key] = setup
            while len(self._built) > self.cache:  # the oldest first
                self._built.pop(next(iter(self._built)))
        sim = setup.config.simulation
        try:
            loop, spec = compiled.stepped_loop(setup, sim.duration)
        except NNRobustError as err:
            raise NNRobustError(
                f"the learning environment's base law {self.law!r} needs a compiled twin "
                f"(a shipped or registered law): {err}"
            ) from err
        steps = int(round(sim.duration / sim.control_period))
        size = path_size(setup.trajectory.position(np.arange(steps) * sim.control_period))
        return setup, loop, spec, size

    def reward_spec(self, weights: Reward):
        """The compiled loop's RewardSpec: the weights, the limits and the action's scale."""
        from ...run import compiled

        spec = compiled._module().RewardSpec()
        spec.error, spec.effort, spec.limits = weights.error, weights.effort, weights.limits
        spec.torque_limit, spec.speed_limit = self.torque_limit, self.speed_limit
        spec.lower, spec.upper = self.lower, self.upper
        spec.action_scale, spec.mode = self.action_scale, self.mode
        return spec

    def info(self, setup, spec, loop, episode: int, wall: float) -> dict:
        """The info of an episode's last step: its sample, status and verdicts (the run's metrics
        and warnings, as ``nnrobust run`` reports them).
        """
        from ...run import compiled
        from ...run.experiment import result_of

        result = result_of(setup, compiled.stepped_trace(setup, spec, loop), wall, "compiled")
        metrics = result.metrics()
        return {
            "episode": episode,
            "status": metrics["status"],
            "metrics": metrics,
            "warnings": metrics["warnings"],
        }


class ArmEnv(gym.Env):
    """One experiment as a Gymnasium environment (docs/learning.md).

    Args:
        experiment: a preset name, an experiment file, or a sweep file (its base, [set] and
            [vary] box, and its controllers: ``controller`` picks the base law, default the first).
        action: ``"torque"`` (the command is a ⊙ τ_max) or ``"residual"`` (scale · a ⊙ τ_max added
            to the base law's command); a ∈ [-1, 1]^n.
        vary: for a preset or an experiment file, a sweep's [vary] table: each reset draws the
            episode's plant from it (``{"nominal.mass_scale": {"uniform": [0.8, 1.2]}}``).
        seed: the sweep seed of the episodes until ``reset(seed=...)`` sets another.
        controller: the base law's kind (``nn``, ``no-u0``, ``pd``, ``slotine-li``, ...; default
            the experiment's); it supplies the nominal model and path the observation uses.
        residual_scale: the residual's bound as a fraction of the effort limits.
        gain_range: G: in ``gains`` mode the action a ∈ [-1, 1]^2 multiplies the base law's
            position and velocity gains by G^a_0 and G^a_1.
        duration: the episode's length [s] (default the experiment's simulation.duration).
        reward: the reward's weights.
        verdicts: compute the run's metrics and warnings at the end of each episode (info).
        tuned: the base law at its tuned setting: a tuning's folder or summary.json, or a
            study's ``REPORT.json#CASE`` (as ``--tuned`` reads them).

    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        experiment: str | Path = "paper-ellipse",
        *,
        action: str = "torque",
        vary: dict | None = None,
        seed: int = 0,
        controller: str | None = None,
        residual_scale: float = 0.1,
        duration: float | None = None,
        reward: Reward | None = None,
        verdicts: bool = True,
        gain_range: float = 4.0,
        tuned: str | Path | None = None,
    ):
        self.episodes = Episodes(
            experiment,
            action=action,
            vary=vary,
            seed=seed,
            controller=controller,
            residual_scale=residual_scale,
            duration=duration,
            gain_range=gain_range,
            tuned=tuned,
        )
        self.weights = reward if reward is not None else Reward()
        self.verdicts = verdicts
        n, size = self.episodes.n, self.episodes.layout.size
        self.action_space = gym.spaces.Box(-1.0, 1.0, (self.episodes.action_size,), dtype=np.float32)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (size,), dtype=np.float64)
        self.episode = -1
        self.setup = self.loop = self.loop_spec = None
        self._started = 0.0
        from ...run import compiled

        # one row of the vector environment's arrays, stepped by the same compiled function
        self._pool = compiled._module().StepPool(1)
        self._reward = self.episodes.reward_spec(self.weights)
        self._size = np.ones(1)
        self._obs = np.zeros((1, size))
        self._action = np.zeros((1, self.episodes.action_size))
        self._applied = np.zeros((1, n))
        self._rewards = np.zeros(1)
        self._running = np.zeros(1, dtype=bool)

    @property
    def layout(self) -> ObservationLayout:
        """The observation's fields (docs/learning.md#observation)."""
        return self.episodes.layout

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start the next episode (sample ``episode`` of the sweep); ``seed`` restarts the
        count at episode 0 of the sweep with that seed.
        """
        super().reset(seed=seed)
        if seed is not None:
            self.episodes.spec.seed = int(seed)
            self.episode = -1
        self.episode += 1
        self.setup, loop, self.loop_spec, self._size[0] = self.episodes.start(self.episode)
        self.loop = loop
        self._obs[0] = loop.observe()
        self._started = time.perf_counter()
        return self._obs[0].copy(), {"episode": self.episode}

    def step(self, action):
        """One control period; see docs/learning.md for the reward and the info."""
        loop = self.loop
        if loop is None or not loop.running:
            raise NNRobustError("ArmEnv.step: call reset() first (the episode has ended)")
        from ...run import compiled

        self._action[0] = checked_actions(action, (self.episodes.action_size,), "ArmEnv.step: action")
        compiled._module().step_loops(
            self._pool,
            [loop],
            self._reward,
            self._action,
            self._size,
            self._obs,
            self._applied,
            self._rewards,
            self._running,
        )
        diverged = loop.status == "diverged"
        reward = float(self._rewards[0]) - (self.weights.runaway if diverged else 0.0)
        ended = not self._running[0]
        info: dict = {"episode": self.episode}
        if ended and self.verdicts:
            wall = time.perf_counter() - self._started
            info = self.episodes.info(self.setup, self.loop_spec, loop, self.episode, wall)
        return self._obs[0].copy(), reward, diverged, bool(ended and not diverged), info
