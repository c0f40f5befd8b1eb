"""Training a policy without a deep-learning framework: CMA-ES over a small network, on the vector
environment, exported to ONNX (docs/learning.md#training).

The network is a = tanh(W₂ tanh(W₁ (obs − μ) / σ + b₁) + b₂) (or a = tanh(W (obs − μ) / σ + b)
with no hidden layer), μ and σ the observation's mean and spread over the base law's own
episodes (a zero action), fixed before training. CMA-ES (the ``cma`` package) searches the weights:
each generation evaluates every candidate on the same ``episodes`` plants (common random numbers:
episodes k … k + episodes − 1 of the environment's sweep, new ones each generation), all of them
stepped together in one vector environment; a candidate's fitness is its mean return. The budget
is counted in simulations (one episode is one simulation of the environment's duration), the unit
the tuner's budgets use.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...core.exceptions import ConfigError
from ...run.results import write_json_atomic


@dataclass
class Network:
    """The policy network's shapes, normalisation and weights (a flat vector ``theta``)."""

    d: int
    n: int
    hidden: int
    mean: np.ndarray
    scale: np.ndarray
    theta: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def size(self) -> int:
        """Entries of theta: (d + 1) h + (h + 1) n, or (d + 1) n without a hidden layer."""
        h, d, n = self.hidden, self.d, self.n
        return (d + 1) * h + (h + 1) * n if h else (d + 1) * n

    def layers(self, theta: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """[(W, b), ...] of a weight vector (obs @ W + b at each layer)."""
        sizes = [self.d, self.hidden, self.n] if self.hidden else [self.d, self.n]
        out, at = [], 0
        for a, b in zip(sizes[:-1], sizes[1:]):
            W = theta[at : at + a * b].reshape(a, b)
            at += a * b
            out.append((W, theta[at : at + b]))
            at += b
        return out

    def act(self, thetas: np.ndarray, obs: np.ndarray) -> np.ndarray:
        """Actions of P candidates (thetas: P x size) on their observations (P x E x d) -> P x E x n."""
        x = (obs - self.mean) / self.scale
        for i in range(2 if self.hidden else 1):
            Ws, bs = [], []
            for theta in thetas:
                W, b = self.layers(theta)[i]
                Ws.append(W)
                bs.append(b)
            x = np.tanh(np.einsum("ped,pdh->peh", x, np.array(Ws)) + np.array(bs)[:, None, :])
        return x

    def export(self, path: str | Path) -> Path:
        """The network with ``theta`` as an ONNX file: input ``obs`` [batch, d] float32, output
        ``action`` [batch, n] (docs/learning.md#policy-files).
        """
        from onnx import helper, numpy_helper

        f = np.float32
        tensors = [numpy_helper.from_array(self.mean.astype(f), "mean"),
                   numpy_helper.from_array(self.scale.astype(f), "scale")]  # fmt: skip
        nodes = [helper.make_node("Sub", ["obs", "mean"], ["centred"]),
                 helper.make_node("Div", ["centred", "scale"], ["x0"])]  # fmt: skip
        layers = self.layers(self.theta)
        for i, (W, b) in enumerate(layers):
            tensors += [
                numpy_helper.from_array(W.astype(f), f"W{i}"),
                numpy_helper.from_array(b.astype(f), f"b{i}"),
            ]
            last = "action" if i == len(layers) - 1 else f"x{i + 1}"
            nodes += [helper.make_node("MatMul", [f"x{i}", f"W{i}"], [f"h{i}"]),
                      helper.make_node("Add", [f"h{i}", f"b{i}"], [f"z{i}"]),
                      helper.make_node("Tanh", [f"z{i}"], [last])]  # fmt: skip
        return write_policy(path, "nnrobust-es-policy", nodes, tensors, self.d, self.n)


def write_policy(path: str | Path, name: str, nodes: list, tensors: list, d: int, n: int) -> Path:
    """A policy file (docs/learning.md#policy-files) of ``nodes`` and ``tensors``: input ``obs``
    [batch, d] float32, output ``action`` [batch, n]; checked, and written atomically.
    """
    import onnx
    from onnx import TensorProto, helper

    graph = helper.make_graph(
        nodes,
        name,
        [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", d])],
        [helper.make_tensor_value_info("action", TensorProto.FLOAT, ["batch", n])],
        tensors,
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.checker.check_model(model)
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    onnx.save(model, str(tmp))
    tmp.replace(path)
    return path


def observation_statistics(vec, episodes: int) -> tuple[np.ndarray, np.ndarray]:
    """μ and σ of the observation over the base law's episodes (a zero action), σ at least 1e-3
    of the largest spread and 1e-6 (a constant entry, such as a planar path's x_d'' on a line).
    """
    obs, _ = vec.reset(seed=vec.episodes.spec.seed)
    seen = [obs]
    zeros = np.zeros((vec.num_envs, vec.episodes.action_size))
    while True:
        obs, _, terminated, truncated, _ = vec.step(zeros)
        if (terminated | truncated).any():
            break
        seen.append(obs)
    stacked = np.concatenate(seen)
    mean, spread = stacked.mean(axis=0), stacked.std(axis=0)
    return mean, np.maximum(spread, max(1e-3 * float(spread.max()), 1e-6))


def train(
    experiment: str | Path,
    out: str | Path,
    *,
    action: str = "residual",
    controller: str | None = None,
    vary: dict | None = None,
    duration: float = 2.0,
    hidden: int = 16,
    population: int = 12,
    episodes: int = 4,
    generations: int = 40,
    sigma: float = 0.1,
    seed: int = 0,
    residual_scale: float = 0.1,
    gain_range: float = 4.0,
    threads: int | None = None,
    progress=print,
) -> dict:
    """Train a policy by CMA-ES on ``experiment``'s vector environment and write ``out``
    (the ONNX file) and ``out`` + ``.json`` (the training record: settings, budget, returns).

    The budget is ``generations x population x episodes`` simulations of ``duration`` seconds,
    plus ``episodes`` for the observation statistics. Returns the record.
    """
    import cma

    from .vector import ArmVectorEnv

    for name, value, low in (("population", population, 2), ("episodes", episodes, 1),
                             ("generations", generations, 1), ("hidden", hidden, 0)):  # fmt: skip
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise ConfigError(name, f"expected an integer >= {low}, got {value!r}")
    start = time.perf_counter()
    settings: dict[str, Any] = {
        "action": action,
        "vary": vary,
        "controller": controller,
        "duration": duration,
        "residual_scale": residual_scale,
        "gain_range": gain_range,
        "verdicts": False,
        "threads": threads,
    }
    vec = ArmVectorEnv(experiment, population * episodes, seed=seed, **settings)
    stats = ArmVectorEnv(experiment, episodes, seed=seed + 1, **settings)  # mu and sigma: other plants
    n, d = vec.episodes.action_size, vec.episodes.layout.size
    mean, scale = observation_statistics(stats, episodes)
    net = Network(d, n, hidden, mean, scale)
    es = cma.CMAEvolutionStrategy(
        np.zeros(net.size), sigma, {"popsize": population, "seed": seed + 1, "verbose": -9}
    )
    history = []
    for generation in range(generations):
        thetas = np.array(es.ask())
        # every candidate on the same plants: episodes generation * episodes + (0 ... episodes - 1)
        returns = rollout(vec, net, thetas, episodes, seed, generation)
        es.tell(list(thetas), list(-returns.mean(axis=1)))
        best = float(returns.mean(axis=1).max())
        history.append(
            {"generation": generation, "best": best, "median": float(np.median(returns.mean(axis=1)))}
        )
        if progress:
            progress(f"generation {generation + 1}/{generations}: best mean return {best:.4g}")
    net.theta = np.asarray(es.result.xfavorite, dtype=float)
    path = net.export(out)
    simulations = generations * population * episodes + episodes
    record = {
        "experiment": str(experiment),
        "action": action,
        "controller": vec.episodes.kind,
        "residual_scale": residual_scale,
        "gain_range": gain_range,
        "vary": vary or {},
        "duration": duration,
        "training_duration": duration,  # the episodes' horizon: a study scoring past it warns
        "reward_window": [0.0, duration],  # the reward counts every step of an episode
        "hidden": hidden,
        "population": population,
        "episodes": episodes,
        "generations": generations,
        "sigma": sigma,
        "seed": seed,
        "simulations": simulations,
        "simulated_seconds": simulations * duration,
        "wall_seconds": time.perf_counter() - start,
        "layout": vec.episodes.layout.describe(),
        "history": history,
    }
    write_json_atomic(Path(str(path) + ".json"), record)
    return record


def rollout(vec, net: Network, thetas: np.ndarray, episodes: int, seed: int, generation: int) -> np.ndarray:
    """Returns (P x episodes) of P candidates, each on the same ``episodes`` plants of this
    generation, all stepped together (candidate p runs in sub-environments p E ... p E + E - 1).
    """
    P = thetas.shape[0]
    # sub-environment p E + k runs episode k of this generation's plants, for every candidate p
    plants = generation * episodes + np.tile(np.arange(episodes), P)
    obs, _ = vec.reset(seed=seed, options={"episodes": plants.tolist()})
    total = np.zeros(P * episodes)
    alive = np.ones(P * episodes, dtype=bool)
    while alive.any():
        a = net.act(thetas, obs.reshape(P, episodes, -1)).reshape(P * episodes, -1)
        obs, reward, terminated, truncated, _ = vec.step(a)
        total += np.where(alive, reward, 0.0)
        alive &= ~(terminated | truncated)
        if math.isnan(total.sum()):
            total = np.nan_to_num(total, nan=-1e9)
    return total.reshape(P, episodes)
