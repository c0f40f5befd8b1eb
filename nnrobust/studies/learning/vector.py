"""The vector environment: N episodes stepped together on the compiled loop's C++ threads.

One ``step`` advances every running episode by one control period on a persistent pool of C++
threads with the GIL released (``step_loops``, csrc/bindings.cpp); the observations, applied
torques and rewards come back as arrays. Sub-environment j runs episodes j, j + N, j + 2N, ...
of the source's sweep, so the batch covers the uncertainty set without repeating a plant. An
episode that ends is restarted at the next ``step`` (Gymnasium's next-step autoreset: that
step's action for it is ignored and it returns the new episode's first observation).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from ...core.exceptions import ConfigError, NNRobustError
from .env import Episodes, Reward, checked_actions, gym


class ArmVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` episodes of one experiment on the compiled loop's threads (docs/learning.md).

    Takes :class:`~nnrobust.studies.learning.env.ArmEnv`'s arguments, and ``num_envs`` and ``threads``
    (C++ threads stepping the episodes; default one per core).
    """

    metadata = {"autoreset_mode": gym.vector.AutoresetMode.NEXT_STEP}

    def __init__(
        self,
        experiment: str | Path = "paper-ellipse",
        num_envs: int = 8,
        *,
        action: str = "torque",
        vary: dict | None = None,
        seed: int = 0,
        controller: str | None = None,
        residual_scale: float = 0.1,
        duration: float | None = None,
        reward: Reward | None = None,
        verdicts: bool = True,
        threads: int | None = None,
        gain_range: float = 4.0,
        tuned: str | Path | None = None,
    ):
        from ...run import compiled

        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or not 1 <= num_envs <= 4096:
            raise ConfigError("num_envs", f"expected an integer in [1, 4096], got {num_envs!r}")
        threads = (os.cpu_count() or 1) if threads is None else threads
        if isinstance(threads, bool) or not isinstance(threads, int) or not 1 <= threads <= 256:
            raise ConfigError("threads", f"expected an integer in [1, 256], got {threads!r}")
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
        self.num_envs = num_envs
        n, size = self.episodes.n, self.episodes.layout.size
        self.single_action_space = gym.spaces.Box(-1.0, 1.0, (self.episodes.action_size,), dtype=np.float32)
        self.single_observation_space = gym.spaces.Box(-np.inf, np.inf, (size,), dtype=np.float64)
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, num_envs)
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space, num_envs)
        self._pool = compiled._module().StepPool(threads)
        self._step_loops = compiled._module().step_loops
        self._reward = self.episodes.reward_spec(self.weights)
        self._rewards = np.zeros(num_envs)
        self._loops: list = [None] * num_envs
        self._runs: list = [None] * num_envs  # (setup, loop, spec, path size, episode, start time)
        self._obs = np.zeros((num_envs, size))
        self._applied = np.zeros((num_envs, n))
        self._running = np.zeros(num_envs, dtype=bool)
        self._ended = np.zeros(num_envs, dtype=bool)
        self._sizes = np.ones(num_envs)
        self._every = np.arange(num_envs)
        self._count = 0  # episodes started since the last seeded reset

    @property
    def layout(self):
        """The observation's fields (docs/learning.md#observation)."""
        return self.episodes.layout

    def _start(self, j: int, episode: int | None = None) -> None:
        """Sub-environment j's next episode (or ``episode``)."""
        if episode is None:
            episode = self._count
            self._count += 1
        setup, loop, spec, size = self.episodes.start(episode)
        self._runs[j] = (setup, loop, spec, episode, time.perf_counter())
        self._loops[j] = loop
        self._obs[j] = loop.observe()
        self._sizes[j] = size
        self._running[j], self._ended[j] = True, False

    def restart(self, j: int) -> np.ndarray:
        """Start sub-environment j's next episode now and return its first observation: a
        same-step reset, for trainers that expect one (Stable-Baselines3's VecEnv;
        nnrobust.studies.learning.rl). Call it after the step that ended j's episode.
        """
        self._start(j)
        return self._obs[j].copy()

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start a new episode in every sub-environment; ``seed`` restarts at episode 0 of the
        sweep with that seed (sub-environment j then runs episode j). ``options={"episodes":
        [k_0, ..., k_N-1]}`` starts sub-environment j at episode k_j instead (several may share
        one: a training generation's candidates on the same plants); later episodes continue
        after the largest.
        """
        super().reset(seed=seed)
        if seed is not None:
            self.episodes.spec.seed = int(seed)
            self._count = 0
        chosen = (options or {}).get("episodes")
        if chosen is not None:
            chosen = [int(k) for k in chosen]
            if len(chosen) != self.num_envs or min(chosen) < 0:
                raise ConfigError(
                    "options.episodes", f"expected {self.num_envs} episode numbers >= 0, got {len(chosen)}"
                )
            self._count = max(self._count, max(chosen) + 1)
        for j in range(self.num_envs):
            self._start(j, None if chosen is None else chosen[j])
        episodes = np.array([run[3] for run in self._runs])
        return self._obs.copy(), {"episode": episodes, "_episode": np.ones(self.num_envs, dtype=bool)}

    def step(self, actions):
        """One control period of every running episode; an episode that ended at the previous
        step restarts now (next-step autoreset).
        """
        N = self.num_envs
        if self._runs[0] is None:
            raise NNRobustError("ArmVectorEnv.step: call reset() first")
        shape = (N, self.episodes.action_size)
        actions = np.ascontiguousarray(checked_actions(actions, shape, "ArmVectorEnv.step: actions"))
        terminated = np.zeros(N, dtype=bool)
        truncated = np.zeros(N, dtype=bool)
        infos: dict = {}
        restart = np.flatnonzero(self._ended) if self._ended.any() else ()
        for j in restart:
            self._start(int(j))
        step = self._step_loops
        if len(restart) == 0:  # every episode runs on: the arrays are stepped in place
            index = self._every
            step(self._pool, self._loops, self._reward, actions, self._sizes, self._obs,
                 self._applied, self._rewards, self._running)  # fmt: skip
            rewards, running = self._rewards.copy(), self._running
        else:  # the restarted ones return their first observation and a zero reward
            index = np.flatnonzero(~np.isin(np.arange(N), restart))
            rewards = np.zeros(N)
            obs, applied = self._obs[index], self._applied[index]
            done, running = np.zeros(index.size), np.zeros(index.size, dtype=bool)
            step(self._pool, [self._loops[j] for j in index], self._reward,
                 np.ascontiguousarray(actions[index]), np.ascontiguousarray(self._sizes[index]), obs,
                 applied, done, running)  # fmt: skip
            self._obs[index], self._applied[index], rewards[index] = obs, applied, done
        for j in () if running.all() else index[~running]:
            setup, loop, spec, episode, started = self._runs[j]
            diverged = loop.status == "diverged"
            terminated[j], truncated[j] = diverged, not diverged
            if diverged:
                rewards[j] -= self.weights.runaway
            self._ended[j] = True
            if self.verdicts:
                info = self.episodes.info(setup, spec, loop, episode, time.perf_counter() - started)
                infos = self._add_info(infos, info, int(j))
        return self._obs.copy(), rewards, terminated, truncated, infos
