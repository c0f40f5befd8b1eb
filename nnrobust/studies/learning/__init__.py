"""Learned controllers on the bench (docs/learning.md): the observation every learned controller
sees, a Gymnasium environment for any experiment, its vector form on the compiled loop's
threads, and the trainers (:func:`train`). The environment needs the ``learning`` extra
(Gymnasium); PPO and SAC the ``rl`` extra (Stable-Baselines3, PyTorch).
"""

from __future__ import annotations

from pathlib import Path

from ...controllers.observation import OBSERVATION_VERSION, ObservationLayout, observation
from ...core.exceptions import ConfigError

__all__ = ["OBSERVATION_VERSION", "ObservationLayout", "TRAINERS", "observation", "train"]

TRAINERS = ("cmaes", "ppo", "sac")
"""The algorithms :func:`train` knows: CMA-ES (no framework, ``es.py``), and Stable-Baselines3's
PPO and SAC (``rl.py``)."""


def train(experiment: str | Path, out: str | Path, *, algorithm: str = "ppo", **options) -> dict:
    """Train a policy on ``experiment`` and write ``out`` (the ONNX policy file) and its record
    (``out`` + ``.json``): ``algorithm="cmaes"`` is :func:`nnrobust.studies.learning.es.train`
    (its budget in generations), ``"ppo"`` and ``"sac"`` are
    :func:`nnrobust.studies.learning.rl.train` (its budget in simulated seconds). ``options``
    are that function's keyword arguments. Returns the record.
    """
    if algorithm == "cmaes":
        from .es import train as train_es

        return train_es(experiment, out, **options)
    if algorithm in ("ppo", "sac"):
        from .rl import train as train_rl

        return train_rl(experiment, out, algorithm=algorithm, **options)
    raise ConfigError("algorithm", f"expected one of {', '.join(TRAINERS)}, got {algorithm!r}")


def _register() -> None:
    """Gymnasium ids for the presets: ``nnrobust/<preset>-v1`` (keyword arguments of
    :class:`~nnrobust.studies.learning.env.ArmEnv` pass through ``gymnasium.make``; ``gymnasium.make_vec``
    with ``vectorization_mode="vector_entry_point"`` gives the vector environment).
    """
    try:
        import gymnasium
    except ImportError:  # the learning extra is not installed: no ids
        return
    from ...config.presets import preset_names

    for name in preset_names():
        env_id = f"nnrobust/{name}-v1"
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id,
                entry_point="nnrobust.studies.learning.env:ArmEnv",
                vector_entry_point="nnrobust.studies.learning.vector:ArmVectorEnv",
                kwargs={"experiment": name},
                # tests/studies/learning/test_env.py runs Gymnasium's checker itself
                disable_env_checker=True,
            )


_register()
