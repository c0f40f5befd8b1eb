"""The learning environment (docs/learning.md): Gymnasium's checker, the observation against its
Python reference, episodes as a sweep's samples, and runs that must equal the bench's own:
a zero residual is the base law's compiled run and a zero torque is a custom law returning
zeros on the hybrid loop, step for step.
"""

import warnings
from pathlib import Path

import numpy as np
import pytest

from nnrobust.core.exceptions import ConfigError, NNRobustError
from nnrobust.run import compiled
from nnrobust.run.experiment import run_experiment
from nnrobust.studies.learning import ObservationLayout, observation

gym = pytest.importorskip("gymnasium")
if not compiled.available():
    pytest.skip(compiled.unavailable_reason(), allow_module_level=True)

from gymnasium.utils.env_checker import check_env  # noqa: E402

from nnrobust.studies.base.plan import draw, experiment  # noqa: E402
from nnrobust.studies.learning.env import ArmEnv, Reward  # noqa: E402
from nnrobust.studies.learning.vector import ArmVectorEnv  # noqa: E402

COUNTER = Path(__file__).parents[2] / "controllers" / "eq9_again.py"
BOX = {"nominal.relative_error": {"uniform": [0.0, 0.3]}, "plant.disturbance_scale": {"uniform": [0.5, 2.0]}}


@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-ellipse"])
@pytest.mark.parametrize("action", ["torque", "residual", "gains"])
def test_gymnasium_checker_passes(preset, action):
    """Gymnasium's checker passes; its only remarks are on the observation's infinite bounds
    (measured speeds and errors have no physical bound the environment could promise)."""
    env = ArmEnv(preset, action=action, duration=0.05)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=True)
    remarks = {str(w.message) for w in caught}
    assert all("infinity" in r for r in remarks), remarks


@pytest.mark.parametrize("preset", ["paper-ellipse", "panda-pose", "ur5-ellipse"])
def test_the_compiled_observation_equals_its_python_reference(preset):
    """At every step of an episode under random actions, SteppedLoop::observe equals
    observation() on the nominal model and path the controller was built with, to 1e-12."""
    env = ArmEnv(preset, action="residual", duration=0.05)
    obs, _ = env.reset(seed=1)
    rng = np.random.default_rng(0)
    setup, loop = env.setup, env.loop
    for _ in range(40):
        q_m, v_m, t = np.asarray(loop.measured_q), np.asarray(loop.measured_v), loop.time
        ref = observation(setup.nominal, setup.trajectory, t, q_m, v_m)
        assert ref.shape == obs.shape == (env.layout.size,)
        np.testing.assert_allclose(obs, ref, rtol=1e-12, atol=1e-12)
        obs, *_ = env.step(rng.uniform(-1, 1, env.episodes.n))


def test_layout_fields_cover_the_vector():
    layout = ObservationLayout(7, 6)
    assert layout.size == 2 * 7 + 3 + 4 * 6
    covered = np.zeros(layout.size, dtype=int)
    for part in layout.slices().values():
        covered[part] += 1
    assert np.all(covered == 1)


def _applied(env, action, steps=None):
    """Applied torques of one episode under a constant action, and its last info."""
    out, info = [], {}
    env.reset(seed=11)
    while True:
        _, _, terminated, truncated, info = env.step(action)
        out.append(np.array(env.loop.applied_torque))
        if terminated or truncated:
            return np.array(out), info


@pytest.mark.parametrize(
    "preset, law",
    [
        ("paper-ellipse", "nn"),
        ("paper-ellipse", "pd"),
        ("paper-ellipse", "slotine-li"),
        ("panda-ellipse", "slotine-li"),
    ],
)
def test_a_zero_residual_is_the_base_law_compiled_run(preset, law):
    """Residual mode with a = 0 is the base law's own run, bit for bit: the same sample's
    experiment run by run_experiment on the compiled loop gives the same torques and metrics
    (the environment's observation hands its task reference to the law's next step: the same
    numbers, the Pinocchio nominal model's data included)."""
    env = ArmEnv(preset, action="residual", controller=law, vary=BOX, duration=0.3)
    tau, info = _applied(env, np.zeros(env.episodes.n))
    spec = env.episodes.spec
    config = experiment(spec, env.episodes.base, draw(spec, 0), law).replace(
        simulation={"duration": 0.3, "backend": "compiled"}
    )
    run = run_experiment(config)
    np.testing.assert_array_equal(tau, run.tau)
    assert info["metrics"]["rms_error"] == run.metrics()["rms_error"]
    assert info["status"] == "completed"


@pytest.mark.parametrize(("law", "keys"), [("no-u0", ("Kp", "Kv")), ("pd", ("pd_Kp", "pd_Kd"))])
@pytest.mark.parametrize("action", [(0.0, 0.0), (-1.0, 1.0), (0.5, 0.25)])
def test_a_constant_gains_action_is_the_base_law_with_its_gains_scaled(law, keys, action):
    """Gains mode with a constant action a is the compiled run of the base law whose experiment
    sets its position gain times G^a_0 and its damping gain times G^a_1 (the PD's null-space
    damping, sized from K_d when unset, held at the law's own)."""
    G = 3.0
    env = ArmEnv("paper-ellipse", action="gains", controller=law, vary=BOX, duration=0.3, gain_range=G)
    assert env.action_space.shape == (2,)
    tau, info = _applied(env, np.array(action))
    spec = env.episodes.spec
    config = experiment(spec, env.episodes.base, draw(spec, 0), law)
    own = config.controller
    scaled = {key: [g * G**a for g in getattr(own, key)] for key, a in zip(keys, action)}
    if law == "pd":
        scaled["pd_null_damping"] = env.setup.controller.null_damping
    config = config.replace(simulation={"duration": 0.3, "backend": "compiled"}, controller=scaled)
    run = run_experiment(config)
    np.testing.assert_allclose(tau, run.tau, rtol=1e-12, atol=1e-12)
    assert info["metrics"]["rms_error"] == pytest.approx(run.metrics()["rms_error"], rel=1e-10)
    if action == (0.0, 0.0):  # exactly the base law's own run
        np.testing.assert_array_equal(tau, run.tau)


def test_gains_mode_refuses_a_law_without_position_and_velocity_gains():
    with pytest.raises(ConfigError, match="'slotine-li' has no position and velocity gains"):
        ArmEnv("paper-ellipse", action="gains", controller="slotine-li", duration=0.1)


def test_a_zero_torque_is_a_custom_law_returning_zeros_on_the_hybrid_loop():
    env = ArmEnv("panda-ellipse", action="torque", duration=0.2)
    tau, info = _applied(env, np.zeros(7))
    assert not tau.any()
    spec = env.episodes.spec
    config = experiment(spec, env.episodes.base, draw(spec, 0), env.episodes.law).replace(
        controller={"kind": "custom", "class": f"{COUNTER}:Counter"},
        simulation={"duration": 0.2, "backend": "hybrid"},
    )
    run = run_experiment(config)
    assert info["metrics"]["rms_error"] == run.metrics()["rms_error"]
    assert info["metrics"]["max_speed_ratio"] == run.metrics()["max_speed_ratio"]


def test_episodes_are_a_sweeps_samples_and_reproducible():
    """Episode k is sample k of the sweep the source and box make; the same seed gives the same
    episodes, another seed other plants."""
    env = ArmEnv("paper-ellipse", vary=BOX, duration=0.02)
    env.reset(seed=4)
    env.reset()
    spec = env.episodes.spec
    expected = experiment(spec, env.episodes.base, draw(spec, 1), env.episodes.law)
    assert env.setup.config.nominal.relative_error == expected.nominal.relative_error
    assert env.setup.config.plant.disturbance_scale == expected.plant.disturbance_scale

    def first_steps(seed):
        e = ArmEnv("paper-ellipse", vary=BOX, duration=0.02)
        obs = [e.reset(seed=seed)[0]]
        obs += [e.step(np.full(3, 0.2))[0] for _ in range(5)]
        return np.array(obs), e.setup.config.plant.disturbance_scale

    a, scale_a = first_steps(4)
    b, scale_b = first_steps(4)
    c, scale_c = first_steps(5)
    np.testing.assert_array_equal(a, b)
    assert scale_a == scale_b != scale_c


def test_an_episode_is_truncated_at_the_experiments_duration():
    env = ArmEnv("paper-ellipse", duration=0.05)
    env.reset(seed=0)
    steps, ended = 0, False
    while not ended:
        _, reward, terminated, truncated, info = env.step(np.zeros(3))
        steps += 1
        ended = terminated or truncated
    assert steps == 50 and truncated and not terminated
    assert reward < 0 and set(info) >= {"episode", "status", "metrics", "warnings"}
    with pytest.raises(NNRobustError, match="reset"):
        env.step(np.zeros(3))


def test_the_reward_follows_its_formula():
    env = ArmEnv("paper-ellipse", duration=0.05, reward=Reward(error=2.0, effort=0.5, limits=3.0))
    obs, _ = env.reset(seed=0)
    obs, reward, *_ = env.step(np.full(3, 0.5))
    s, eps = env.layout.slices(), env.episodes
    e = obs[s["e"]]
    tau = np.array(env.loop.applied_torque)
    q, dq = obs[s["q"]], obs[s["dq"]]
    beyond = (q < eps.lower) | (q > eps.upper) | (np.abs(dq) > eps.speed_limit)
    expected = -(
        2.0 * np.linalg.norm(e) / env._size
        + 0.5 * np.mean((tau / eps.torque_limit) ** 2)
        + 3.0 * beyond.mean()
    )
    assert reward == pytest.approx(expected, rel=1e-12)
    np.testing.assert_allclose(tau, 0.5 * eps.torque_limit)  # a in [-1, 1] scales the effort limits


def test_the_vector_env_steps_each_episode_as_the_single_env_does():
    """Sub-environment j runs episode j; after an episode ends the next step starts episode
    j + N (next-step autoreset) and returns its first observation."""
    vec = ArmVectorEnv("paper-ellipse", 3, vary=BOX, duration=0.02, threads=2)
    obs, info = vec.reset(seed=9)
    assert list(info["episode"]) == [0, 1, 2]
    rng = np.random.default_rng(1)
    actions = rng.uniform(-1, 1, (20, 3, 3))
    singles = []
    for j in range(3):
        env = ArmEnv("paper-ellipse", vary=BOX, duration=0.02)
        env.reset(seed=9)
        for _ in range(j):
            env.reset()
        singles.append([env.step(actions[k, j]) for k in range(20)])
    for k in range(20):
        obs, rewards, terminated, truncated, infos = vec.step(actions[k])
        for j in range(3):
            o, r, te, tr, _ = singles[j][k]
            np.testing.assert_array_equal(obs[j], o)
            assert rewards[j] == r and terminated[j] == te and truncated[j] == tr
    assert truncated.all() and list(infos["episode"]) == [0, 1, 2]
    obs, rewards, *_ = vec.step(actions[0])
    env = ArmEnv("paper-ellipse", vary=BOX, duration=0.02)
    first = env.reset(seed=9)[0]
    for _ in range(3):
        first = env.reset()[0]
    np.testing.assert_array_equal(obs[0], first)  # episode 3 in sub-environment 0
    assert rewards[0] == 0.0


def test_bad_arguments_are_named():
    with pytest.raises(ConfigError, match="action"):
        ArmEnv("paper-ellipse", action="gains?")
    with pytest.raises(ConfigError, match="reward.effort"):
        Reward(effort=-1.0)
    with pytest.raises(ConfigError, match="paper-elipse"):
        ArmEnv("paper-elipse")
    with pytest.raises(ConfigError, match="num_envs"):
        ArmVectorEnv("paper-ellipse", 0)
    with pytest.raises(ConfigError, match="controller: .*Counter.*one of nn"):
        ArmEnv("paper-ellipse", controller=f"{COUNTER}:Counter")


def test_an_experiment_whose_law_has_no_compiled_twin_is_refused_in_one_line(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text(f'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "{COUNTER}:Counter"\n')
    with pytest.raises(ConfigError, match=r"law \(custom\) has no compiled twin.*controller = one of nn"):
        ArmEnv(str(path), duration=0.02)
    ArmEnv(str(path), controller="pd", duration=0.02).reset(seed=0)  # a shipped base law instead


def test_registered_ids_make_the_environment():
    env = gym.make("nnrobust/paper-ellipse-v1", duration=0.02)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (16,)
    vec = gym.make_vec(
        "nnrobust/paper-ellipse-v1", num_envs=2, vectorization_mode="vector_entry_point", duration=0.02
    )
    obs, _ = vec.reset(seed=0)
    assert obs.shape == (2, 16)


def test_es_training_writes_a_policy_that_runs_as_the_environment_scored_it(tmp_path):
    """A tiny CMA-ES training (the path docs/learning.md documents): its ONNX file, run as a
    controller on episode 0's plant, gives the run the environment's rollout of the same weights
    gave (float32 inference against float64: close, not equal)."""
    from nnrobust.studies.learning.es import Network, train

    out = tmp_path / "policy.onnx"
    record = train("paper-ellipse", out, action="residual", controller="no-u0", duration=0.2,
                   population=4, episodes=2, generations=2, hidden=4, threads=2, progress=None)  # fmt: skip
    assert out.is_file() and (tmp_path / "policy.onnx.json").is_file()
    assert record["simulations"] == 2 * 4 * 2 + 2 and len(record["history"]) == 2
    assert record["layout"] == ObservationLayout(3, 2).describe()
    # the exported weights, scored by the environment (numpy) and run as a controller (ONNX)
    import onnx
    from onnx import numpy_helper

    weights = {t.name: numpy_helper.to_array(t).astype(float) for t in onnx.load(str(out)).graph.initializer}
    net = Network(16, 3, 4, weights["mean"], weights["scale"])
    net.theta = np.concatenate([weights[k].ravel() for k in ("W0", "b0", "W1", "b1")])
    env = ArmEnv("paper-ellipse", action="residual", controller="no-u0", duration=0.2)
    obs, _ = env.reset(seed=0)
    tau, ended = [], False
    while not ended:
        obs, _, terminated, truncated, info = env.step(net.act(net.theta[None], obs[None, None])[0, 0])
        tau.append(np.array(env.loop.applied_torque))
        ended = terminated or truncated
    spec = env.episodes.spec
    config = experiment(spec, env.episodes.base, draw(spec, 0), "no-u0").replace(
        controller={"kind": "policy", "params": {"file": str(out), "action": "residual", "base": "no-u0"}},
        simulation={"duration": 0.2},
    )
    run = run_experiment(config)
    np.testing.assert_allclose(run.tau, np.array(tau), rtol=1e-4, atol=1e-4 * float(np.abs(tau).max()))
    assert run.metrics()["rms_error"] == pytest.approx(info["metrics"]["rms_error"], rel=1e-4)
