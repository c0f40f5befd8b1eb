"""Hard conditions during a run: divergence and Ctrl-C leave the partial result on disk, marked;
near-singular episodes are recorded."""

import json

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.config.presets import load_preset
from nnrobust.run.experiment import run_experiment
from nnrobust.run.results import Result, singular_episodes


def _experiment(tmp_path, **sections):
    path = tmp_path / "experiment.toml"
    path.write_text(load_preset("paper-ellipse").replace(**sections).to_toml())
    return path


def test_divergence_stops_the_run_and_keeps_the_partial_result(tmp_path, capsys):
    """Kv T = 2 at the 1 ms zero-order hold is unstable without actuator limits: the run stops and
    says which joint ran away, how fast (rad/s), when, and the likely cause."""
    experiment = _experiment(
        tmp_path,
        controller={"Kp": [1e6], "Kv": [2e3]},
        plant={"torque_limits": "none"},
        simulation={"duration": 2.0},
    )
    out = tmp_path / "run"
    assert main(["run", str(experiment), "--out", str(out), "--quiet", "--no-animation"]) == 1
    err = capsys.readouterr().err
    assert "run diverged: joint 'joint" in err and "rad/s" in err
    assert "likely cause: the commanded torque grew without bound" in err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "diverged" and "at t = 0.0" in metrics["message"]
    result = Result.load(out)
    assert 10 < result.t.size < 2000 and np.all(np.isfinite(result.q))
    assert (out / "plots" / "errors.png").exists()


def test_saturation_keeps_the_same_gains_bounded_and_says_so(tmp_path, capsys):
    """The same unstable gains with the URDF's effort limits: the run completes, and its
    warnings say the command saturated (peak ratio far above 1)."""
    experiment = _experiment(tmp_path, controller={"Kp": [1e6], "Kv": [2e3]}, simulation={"duration": 0.5})
    out = tmp_path / "run"
    assert main(["run", str(experiment), "--out", str(out), "--no-animation", "--no-plots"]) == 0
    assert "warning: torque saturation" in capsys.readouterr().err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["saturated_fraction"] > 0.5 and metrics["max_torque_ratio"] > 10
    assert any(w.startswith("torque saturation") for w in metrics["warnings"])


def test_ctrl_c_keeps_the_partial_result_marked_interrupted(tmp_path, monkeypatch, capsys):
    import nnrobust.core.progress

    def interrupt_at_half_a_second(self, t, q=None):
        if t >= 0.5:
            raise KeyboardInterrupt

    monkeypatch.setattr(nnrobust.core.progress.ProgressBar, "__call__", interrupt_at_half_a_second)
    experiment = _experiment(tmp_path, simulation={"duration": 5.0, "backend": "python"})
    out = tmp_path / "run"
    assert main(["run", str(experiment), "--out", str(out), "--no-plots", "--no-animation"]) == 1
    assert "run interrupted: interrupted at t = 0.5" in capsys.readouterr().err
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["status"] == "interrupted"
    assert Result.load(out).t[-1] < 0.5


def test_a_signal_stops_a_compiled_run_and_keeps_its_result():
    """The compiled loop polls for signals every 256 steps: a signal whose handler raises
    KeyboardInterrupt (as Python's SIGINT handler does) 0.2 s into a 300 s run stops it, and the
    partial run comes back marked interrupted. A kernel timer delivers the signal, so the test does
    not depend on a thread being scheduled in time."""
    import signal

    from nnrobust.run import compiled
    from nnrobust.run.experiment import build

    if not compiled.available():
        pytest.skip(compiled.unavailable_reason())
    config = load_preset("paper-ellipse").replace(simulation={"duration": 300.0, "backend": "compiled"})
    setup = build(config)

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, interrupt)
    signal.setitimer(signal.ITIMER_REAL, 0.2)
    try:
        result = run_experiment(config, setup=setup)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    assert result.status == "interrupted" and result.backend == "compiled"
    assert result.message.startswith("interrupted at t = ")
    assert 0 < result.t[-1] < 300.0 and np.all(np.isfinite(result.q))


def test_near_singular_episodes_are_recorded():
    """With the damping threshold at sigma_min = 0.36 m the ellipse crosses it: episodes listed."""
    config = load_preset("paper-ellipse").replace(
        controller={"pinv_threshold": 0.36, "pinv_max_damping": 0.05}, simulation={"duration": 6.0}
    )
    metrics = run_experiment(config).metrics()
    episodes = metrics["singular_episodes"]
    assert episodes["count"] >= 1 and 0 < metrics["singular_fraction"] < 1
    for start, end in episodes["intervals"]:
        assert 0 <= start <= end <= 6.0


def test_singular_episode_intervals():
    t = np.arange(10) * 0.1
    damped = np.array([0, 1, 1, 0, 0, 1, 0, 0, 1, 1], dtype=bool)
    assert singular_episodes(t, damped) == {"count": 3, "intervals": [[0.1, 0.2], [0.5, 0.5], [0.8, 0.9]]}
    assert singular_episodes(t, np.zeros(10, dtype=bool)) == {"count": 0, "intervals": []}


def _fake_trace(q, n):
    from types import SimpleNamespace

    return SimpleNamespace(q=np.array([q]), dq=np.zeros((1, n)), tau_cmd=np.zeros((1, n)))


def test_divergence_cause_names_an_exploding_criterion_gradient():
    """k dh/dq above 1e3 on some joint at the last state: the message says so and names the joint."""
    from nnrobust.run.experiment import build, likely_cause

    config = load_preset("paper-ellipse").replace(
        controller={"k": 1e4}, subtasks={"criteria": ["joint_limits"]}, simulation={"duration": 1.0}
    )
    setup = build(config)
    q = setup.q0.copy()
    q[1] = 2.79  # joint2 next to its +2.8 rad limit: the barrier's steepest part
    message = likely_cause(setup, _fake_trace(q, 3))
    assert "exploding criterion gradient" in message and "'joint2'" in message


def test_divergence_cause_names_an_implausible_effort_limit(tmp_path):
    """An effort limit of 50 kN m on the paper's arm: named in a warning, and the likely cause."""
    from nnrobust.model import paper_arm_urdf
    from nnrobust.run.experiment import build, likely_cause

    urdf = tmp_path / "arm.urdf"
    urdf.write_text(paper_arm_urdf().read_text().replace('effort="60"', 'effort="50000"'))
    config = load_preset("paper-ellipse").replace(
        robot={"source": str(urdf)},
        plant={"friction": "scaled", "disturbance": "scaled", "joint_stops": False},
        nominal={"kind": "urdf"},
        simulation={"duration": 1.0},
    )
    with pytest.warns(UserWarning, match=r"effort limits of joints 'joint1' \(50000\)"):
        setup = build(config)  # the scaled friction and disturbance do not take it at face value
    message = likely_cause(setup, _fake_trace(setup.q0, 3))
    assert "implausible effort limit (5e+04 on joint 'joint1'" in message


@pytest.mark.parametrize("backend", ["python", "compiled"])
def test_a_run_that_diverges_as_a_huge_load_starts_blames_the_load_not_the_gains(backend):
    """A 1e9 N m s impulse at 0.1 s makes any law diverge: the divergence names that load and its
    size (it blamed "the closed loop is unstable for these gains"); a load that started long
    before a divergence is not blamed."""
    from nnrobust.run import compiled
    from nnrobust.run.experiment import _load_just_before

    if backend == "compiled" and not compiled.available():
        pytest.skip(compiled.unavailable_reason())
    impulse = {"kind": "impulse", "time": 0.1, "impulse": [1e9, 0.0, 0.0]}
    config = load_preset("paper-ellipse").replace(
        plant={"loads": [impulse]}, simulation={"duration": 0.3, "backend": backend}
    )
    result = run_experiment(config)
    assert result.status == "diverged"
    assert (
        "likely cause: plant.loads[0], the impulse of [1e+09, 0, 0] N m s at t = 0.1 s: the run "
        "diverged 1 control period after it started" in result.message
    ), result.message
    assert "gains" not in result.message
    step = {"kind": "step", "time": 0.01, "torque": [0.0, 0.1, 0.0]}
    early = config.replace(plant={"loads": [step]})
    assert _load_just_before(early, 0.5) == ""
    assert _load_just_before(early, 0.015).startswith("plant.loads[0], the step of [0, 0.1, 0] N m")
