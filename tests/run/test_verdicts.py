"""Verdicts that mean what they say: saturation of the applied torque, per-joint torque metrics,
joint speed limits and the torque-speed envelope, lost tracking, a degraded subtask, and the
figure of a law's own signals (docs/plant.md#verdicts-in-metricsjson)."""

import numpy as np
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.plant.limits import available_torque
from nnrobust.run import verdicts
from nnrobust.run.experiment import build, run_experiment
from nnrobust.run.results import Result
from tests.run.test_compiled import needs_extension

LIMIT = np.array([60.0, 40.0, 20.0])


def _result(tau_cmd, tau=None, dq=None, x_d=None, e=None, h=None, t=None, **kwargs) -> Result:
    """A hand-made run of N samples at 1 ms (q = 0) with the given arrays."""
    tau_cmd = np.asarray(tau_cmd, dtype=float)
    N, n = tau_cmd.shape
    t = np.arange(N) * 1e-3 if t is None else t
    x_d = np.zeros((N, 2)) if x_d is None else x_d
    e = np.zeros_like(x_d) if e is None else e
    signals = {"h": np.zeros(N) if h is None else h, "manipulability": np.ones(N)}
    signals.update(kwargs.pop("signals", {}))
    return Result(
        t,
        np.zeros((N, n)),
        np.zeros((N, n)) if dq is None else dq,
        np.clip(tau_cmd, -LIMIT, LIMIT) if tau is None else tau,
        x_d + e,
        x_d,
        e,
        signals,
        tau_cmd=tau_cmd,
        torque_limit=LIMIT,
        joint_names=["a", "b", "c"],
        **kwargs,
    )


def test_a_law_that_clips_its_own_command_is_counted_saturated():
    """A law that returns its torque already clipped at the limit gives applied = command = limit:
    the actuator gives all it has, and the step is saturated (it was 0 % when only commands beyond
    the limit counted)."""
    clipped = np.tile([60.0, -10.0, 5.0], (100, 1))
    clipped[50:, 0] = 30.0  # half the run within the limits
    m = _result(clipped).metrics()
    assert m["saturated_fraction"] == pytest.approx(0.5)
    assert m["max_torque_ratio"] == pytest.approx(1.0)
    assert m["max_applied_torque_ratio"] == pytest.approx(1.0)
    assert any(w.startswith("torque saturation:") for w in m["warnings"])
    below = _result(np.tile([59.9, -10.0, 5.0], (100, 1))).metrics()
    assert below["saturated_fraction"] == 0.0


def test_torque_metrics_are_per_joint_and_relative_to_the_limits():
    """rms_torque_ratio is the most loaded joint's RMS torque over its limit; the per-joint
    maxima and RMS are listed; the norm rms_torque is what its formula says."""
    rng = np.random.default_rng(0)
    tau = rng.uniform(-1.0, 1.0, (400, 3)) * [30.0, 35.0, 4.0]
    m = _result(tau).metrics()
    rms = np.sqrt(np.mean(tau**2, axis=0))
    assert m["rms_torque_per_joint"] == pytest.approx(rms.tolist())
    assert m["max_torque_per_joint"] == pytest.approx(np.abs(tau).max(axis=0).tolist())
    assert m["rms_torque_ratio"] == pytest.approx(np.max(rms / LIMIT))
    assert m["rms_torque_ratio"] == pytest.approx(rms[1] / 40.0)  # joint b, not the largest RMS
    assert m["rms_torque"] == pytest.approx(np.sqrt(np.mean(np.sum(tau**2, axis=1))))
    assert m["max_applied_torque_ratio"] == pytest.approx(np.max(np.abs(tau) / LIMIT))


def test_a_joint_over_its_velocity_limit_is_a_verdict_naming_it():
    """Steps with some joint over its velocity limit, the peak ratio and the joint; a warning
    names it (the speed was recorded and never judged before)."""
    dq = np.zeros((200, 3))
    dq[:, 2] = np.linspace(0.0, 46.0 * np.pi, 200)  # joint c: up to 46x a limit of pi rad/s
    dq[:, 0] = 1.0
    r = _result(np.zeros((200, 3)), dq=dq, velocity_limit=np.array([2.0, np.inf, np.pi]))
    m = r.metrics()
    assert m["max_speed_ratio"] == pytest.approx(46.0)
    assert m["speed_limit_joint"] == 2
    assert m["speed_limit_fraction"] == pytest.approx(np.mean(dq[:, 2] > np.pi))
    (warning,) = [w for w in m["warnings"] if w.startswith("joint speed:")]
    assert "'c'" in warning and "46x" in warning
    within = _result(
        np.zeros((200, 3)), dq=dq / 50.0, velocity_limit=np.array([2.0, np.inf, np.pi])
    ).metrics()
    assert within["speed_limit_fraction"] == 0.0 and not any("joint speed" in w for w in within["warnings"])
    assert m["joints_over_speed_limit"] == 1 and "1 joint over a limit" in warning
    unknown = _result(np.zeros((5, 3)), dq=dq[:5]).metrics()  # no limits known: no verdict, not 0
    assert unknown["max_speed_ratio"] is None and unknown["speed_limit_fraction"] is None


def test_tracking_lost_is_judged_against_the_path_size():
    """RMS error after 2 s over TRACKING_LOST of the bounding-box diagonal of x_d fires 'tracking
    lost'; the same error on a path ten times larger does not."""
    t = np.arange(0.0, 4.0, 1e-3)
    ellipse = np.column_stack([0.3 + 0.2 * np.cos(t * 2), 0.4 + 0.1 * np.sin(t * 2)])
    size = np.hypot(0.4, 0.2)
    error = np.zeros_like(ellipse)
    error[:, 0] = 0.2 * size  # 89 mm on a 447 mm path
    m = _result(np.zeros((t.size, 3)), t=t, x_d=ellipse, e=error).metrics()
    assert m["path_size"] == pytest.approx(size, rel=1e-3)
    assert m["tracking_error_ratio"] == pytest.approx(0.2, rel=1e-3)
    assert any(w.startswith("tracking lost:") for w in m["warnings"])
    big = _result(np.zeros((t.size, 3)), t=t, x_d=10 * ellipse, e=error).metrics()
    assert not any(w.startswith("tracking lost:") for w in big["warnings"])
    assert verdicts.path_size(np.zeros((10, 2))) == verdicts.PATH_SIZE_FLOOR  # a set point


def test_the_subtask_verdict_compares_h_at_the_same_point_of_the_path():
    """h that follows the path periodically does not degrade, though h at the end differs from
    h(0) (the old verdict fired on it); the same h drifting down by 20 % over the run does."""
    t = np.arange(0.0, 20.0, 1e-3)
    x_d = np.column_stack([0.3 + 0.2 * np.cos(t), 0.4 + 0.1 * np.sin(t)])
    periodic = -0.5 + 0.1 * np.cos(t)
    zeros = np.zeros((t.size, 3))
    m = _result(zeros, t=t, x_d=x_d, h=periodic).metrics()
    assert periodic[-1] < periodic[0] - verdicts.SUBTASK_LOSS * 0.5  # what fired the old verdict
    assert not m["subtask_degraded"]
    assert m["h_start_time"] == pytest.approx(20.0 - 1e-3 - 2 * 2 * np.pi, abs=0.02)  # two laps back
    drifting = periodic - 0.1 * t / 20.0
    m = _result(zeros, t=t, x_d=x_d, h=drifting).metrics()
    assert m["subtask_degraded"] and any(w.startswith("subtask degraded:") for w in m["warnings"])
    line = np.column_stack([np.linspace(0, 1, t.size), np.zeros(t.size)])  # never comes back
    m = _result(zeros, t=t, x_d=line, h=drifting).metrics()
    assert not m["subtask_degraded"] and np.isnan(m["h_start_time"])  # no verdict, not a late instant
    short = t < 5.0  # less than one lap after 2 s: nothing to compare
    m = _result(zeros[short], t=t[short], x_d=x_d[short], h=drifting[short]).metrics()
    assert np.isnan(m["h_start_time"]) and not m["subtask_degraded"]
    arrive = np.column_stack([np.minimum(t, 6.0) / 6.0, np.zeros(t.size)])  # point to point, then a hold
    m = _result(zeros, t=t, x_d=arrive, h=drifting).metrics()
    assert m["h_start_time"] == pytest.approx(6.0, abs=0.05) and m["subtask_degraded"]  # the arrival


def test_the_envelope_is_the_motor_line_above_its_knee():
    """Full effort below knee x the velocity limit, falling linearly to zero at the limit while
    driving; full effort braking; knee < 0 or an inf limit leave the effort alone."""
    limit, speed = np.full(5, 10.0), np.full(5, 2.0)
    v = np.array([0.5, 1.5, 1.5, 2.5, -1.5])
    tau = np.array([1.0, 1.0, -1.0, 1.0, -1.0])
    got = available_torque(limit, tau, v, speed, 0.5)
    np.testing.assert_allclose(got, [10.0, 5.0, 10.0, 0.0, 5.0])
    np.testing.assert_allclose(available_torque(limit, tau, v, speed, 0.0), [7.5, 2.5, 10.0, 0.0, 2.5])
    np.testing.assert_allclose(available_torque(limit, tau, v, speed, -1.0), limit)
    np.testing.assert_allclose(available_torque(limit, tau, v, np.full(5, np.inf), 0.5), limit)
    unlimited = available_torque(np.full(5, np.inf), tau, v, speed, 0.0)  # inf x 0 is not NaN
    assert np.all(unlimited == np.inf)


@pytest.fixture(scope="module")
def envelope_runs():
    """The Panda's ellipse with effort limits it nearly needs and the URDF's torque-speed envelope
    from zero speed (knee 0), on the compiled and the Python loop, and without the envelope."""
    config = load_preset("panda-ellipse").replace(
        simulation={"duration": 1.5},
        plant={"torque_speed": "urdf", "torque_speed_knee": 0.0, "torque_limits": [27.0] * 4 + [5.5] * 3},
    )
    runs = {b: run_experiment(config.replace(simulation={"backend": b})) for b in ("compiled", "python")}
    runs["none"] = run_experiment(config.replace(plant={"torque_speed": "none"}))
    return runs


@needs_extension
def test_the_envelope_cuts_the_driving_torque_on_both_loops(envelope_runs):
    """Applied torques never exceed the envelope at the recorded speeds; it cut some commands
    (so the run differs from the one without it); the compiled plant is its Python twin."""
    run = envelope_runs["python"]
    limit = run.torque_limit
    setup = build(load_preset("panda-ellipse"))
    speed = np.asarray(setup.robot.velocity_limits)
    available = available_torque(limit, run.tau_cmd, run.dq, speed, 0.0)
    assert np.all(np.abs(run.tau) <= available + 1e-12)
    cut = np.abs(run.tau) < np.minimum(np.abs(run.tau_cmd), limit) - 1e-12  # below what saturation leaves
    plain = envelope_runs["none"]
    assert cut.any(axis=1).mean() > 0.05 and not np.any(np.abs(plain.tau) < np.abs(plain.tau_cmd))
    assert run.metrics()["saturated_fraction"] >= np.mean(cut.any(axis=1))
    assert plain.metrics()["saturated_fraction"] == 0.0
    other = envelope_runs["compiled"]
    assert other.backend == "compiled"
    np.testing.assert_allclose(other.tau, run.tau, atol=1e-8)
    np.testing.assert_allclose(other.q, run.q, atol=1e-9)


def test_the_envelope_needs_effort_limits_and_is_refused_by_name():
    """plant.torque_speed names what is wrong: an unknown choice, no effort limits to cut."""
    from nnrobust.core.exceptions import ConfigError

    config = load_preset("paper-ellipse")
    with pytest.raises(ConfigError, match=r"plant.torque_speed: 'urdff' is not one of none, urdf"):
        build(config.replace(plant={"torque_speed": "urdff"}))
    with pytest.raises(ConfigError, match=r"plant.torque_speed: 'urdf' cuts the effort limits"):
        build(config.replace(plant={"torque_speed": "urdf", "torque_limits": "none"}))
    with pytest.raises(ConfigError, match=r"plant.torque_speed_knee: 1 is outside \[0, 1\)"):
        build(config.replace(plant={"torque_speed": "urdf", "torque_speed_knee": 1.0}))


def test_a_laws_own_signals_are_drawn():
    """A law's declared signals get the signals figure, one panel each; the paper's kinds (whose
    signals have figures or metrics of their own) get none."""
    from nnrobust.outputs import plots

    t = np.arange(50) * 1e-3
    own = _result(np.zeros((50, 3)), signals={"gain": np.sin(t), "s_norm": t, "rho_hat": t, "eps": t})
    fig = plots.FIGURES["signals"](own)
    assert [ax.get_ylabel() for ax in fig.axes] == ["gain", "s_norm"]
    assert plots.FIGURES["signals"](_result(np.zeros((50, 3)), signals={"damping": t, "z_norm": t})) is None


def test_the_pandas_null_space_outruns_a_velocity_limit_under_three_times_the_disturbance():
    """docs/robustness.md: panda-ellipse at three times its disturbance tracks the ellipse to under
    a millimetre while panda_joint7 moves at 2.4 times its 2.61 rad/s limit and 6 joints are over
    theirs in 49 % of the steps (panda_joint7 alone in 23 %)."""
    result = run_experiment(load_preset("panda-ellipse").replace(plant={"disturbance_scale": 3.0}))
    m = result.metrics()
    assert result.joint_names[m["speed_limit_joint"]] == "panda_joint7"
    assert result.velocity_limit[m["speed_limit_joint"]] == pytest.approx(2.61)
    assert round(m["max_speed_ratio"], 1) == 2.4 and round(100 * m["speed_limit_fraction"]) == 49
    assert m["joints_over_speed_limit"] == 6
    own = np.abs(result.dq[:, 6]) > result.velocity_limit[6]
    assert round(100 * np.mean(own)) == 23
    assert round(1e3 * m["rms_error_after_2s"], 2) == 0.86
    assert any(w.startswith("joint speed: joint 'panda_joint7'") for w in m["warnings"])


def test_no_subtask_verdict_on_a_run_that_lost_the_path():
    """h compared 'at the same point of the path' means nothing when the arm is far from it: a
    drifting h with tracking lost is not a degraded subtask (it flipped from engine to engine)."""
    t = np.arange(0.0, 20.0, 1e-3)
    x_d = np.column_stack([0.3 + 0.2 * np.cos(t), 0.4 + 0.1 * np.sin(t)])
    drifting = -0.5 + 0.1 * np.cos(t) - 0.1 * t / 20.0
    zeros = np.zeros((t.size, 3))
    lost = np.full_like(x_d, 0.2)  # 283 mm from the path
    m = _result(zeros, t=t, x_d=x_d, e=lost, h=drifting).metrics()
    assert any(w.startswith("tracking lost:") for w in m["warnings"]) and not m["subtask_degraded"]
    assert m["h_end"] < m["h_start"]  # the values are still reported
