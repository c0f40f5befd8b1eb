"""Learned controllers on the bench (docs/learning.md): the observation every learned controller
sees, a Gymnasium environment for any experiment, and its vector form on the compiled loop's
threads. The environment needs the ``learning`` extra (Gymnasium).
"""

from ...controllers.observation import OBSERVATION_VERSION, ObservationLayout, observation

__all__ = ["OBSERVATION_VERSION", "ObservationLayout", "observation"]


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
