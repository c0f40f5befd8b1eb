"""The log's preparation on signals whose derivatives are known: the filter's bias is the one
stated (amplitude_gain), stale samples and jittered stamps leave the states right."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from nnrobust.studies.identify.logs import JointLog
from nnrobust.studies.identify.signals import EDGE_PERIODS, FilterChoice, amplitude_gain, prepare, quantum


def _sine_log(frequency, t, stale=()):
    w = 2 * np.pi * frequency
    q = np.sin(w * t)[:, None]
    dq = w * np.cos(w * t)[:, None]
    tau = np.cos(w * t)[:, None]
    q, dq, tau = q.copy(), dq.copy(), tau.copy()
    for k in sorted(stale):  # in order: a run of stale samples repeats the last fresh one
        q[k], dq[k], tau[k] = q[k - 1], dq[k - 1], tau[k - 1]
    return JointLog("sine", t, q, dq, tau)


@pytest.mark.parametrize("frequency", [0.5, 2.5, 5.0, 10.0])
def test_the_acceleration_bias_is_the_stated_gain(frequency):
    """q'' of a sinusoid comes out scaled by |H(f)|^2 sinc(w dt) (the filter and one central
    difference of the filtered q'), to 1e-3 of its amplitude: the stated bias is the bias."""
    choice = FilterChoice(cutoff=10.0)
    t = np.arange(20000) / 1000.0
    states = prepare(_sine_log(frequency, t), choice)
    w = 2 * np.pi * frequency
    truth = -(w**2) * np.sin(w * states.t)
    gain = amplitude_gain(frequency, choice, states.dt, 1)
    assert np.max(np.abs(states.ddq[:, 0] - gain * truth)) < 1e-3 * w**2
    if frequency <= choice.cutoff / 2:
        assert abs(gain - 1) < 0.005  # the docstring's claim
    else:
        assert abs(gain - 1) > 0.005  # where it stops holding: at and near the cut-off


def test_stale_samples_and_jittered_stamps_leave_the_states_right():
    rng = np.random.default_rng(0)
    t = np.arange(10000) / 1000.0 + rng.normal(0, 2e-4, 10000)
    t = np.sort(t)
    stale = rng.choice(np.arange(1, 10000), 400, replace=False)
    states = prepare(_sine_log(1.0, t, stale), FilterChoice(cutoff=10.0))
    w = 2 * np.pi
    assert states.notes["stale_samples"] == len(set(stale))
    assert np.max(np.abs(states.q[:, 0] - np.sin(w * states.t))) < 1e-4
    assert np.max(np.abs(states.ddq[:, 0] + w**2 * np.sin(w * states.t))) < 2e-2 * w**2
    # the torque is left as logged (interpolated only), so its noise stays white
    assert np.max(np.abs(states.tau[:, 0] - np.cos(w * states.t))) < 1e-4
    assert abs(states.dt - 1e-3) < 1e-5


def test_a_creeping_joint_under_one_encoder_count_is_not_stale():
    """A quantised encoder repeats its positions while the arm creeps slower than a count per
    sample (by its velocity): the rows are true and kept; faster, a repeated row is stale."""
    t = np.arange(4000) / 1000.0
    count = 1e-3
    q = (count * np.round(0.02 * t**2 / count))[:, None]  # from rest: under a count per sample at first
    dq = (0.04 * t)[:, None]
    log = JointLog("creep", t, q, dq, dq.copy())
    repeated = int(np.sum(np.all(np.diff(q, axis=0) == 0, axis=1)))
    states = prepare(log, FilterChoice(cutoff=10.0))
    assert repeated > 1000 and states.notes["stale_samples"] == 0
    assert states.notes["repeated_positions_kept"] == repeated
    q[3500] = q[3499]  # at 0.14 rad/s, 0.14 counts a sample: still under a count
    q[3800:3840] = q[3799]  # held 40 ms while it moves 6 counts: stale past the first 2 counts
    states = prepare(JointLog("creep", t, q, dq, dq.copy()), FilterChoice(cutoff=10.0))
    assert 20 < states.notes["stale_samples"] < 40


def test_an_arm_at_rest_is_kept_and_a_stale_sample_while_moving_dropped():
    """An arm held still (its positions repeated exactly, every velocity zero: a plant in stick)
    for 1 s, then moving: the rest is true and kept, where dropping it left a gap the grid may not
    fill (the log was refused) or ramped the interpolation across it."""
    t = np.arange(6000) / 1000.0
    moving = np.clip(t - 1.0, 0.0, None)
    w = 2 * np.pi
    q = (1 - np.cos(w * moving))[:, None] * 0.1
    dq = (w * np.sin(w * moving))[:, None] * 0.1
    tau = dq.copy()
    stale = [3251, 3252, 4321]
    for k in stale:
        q[k], dq[k], tau[k] = q[k - 1], dq[k - 1], tau[k - 1]
    states = prepare(JointLog("rest", t, q, dq, tau), FilterChoice(cutoff=10.0))
    assert states.notes["stale_samples"] == len(stale) < states.notes["repeated_positions_kept"]
    at_rest = states.t < 0.7  # 3 cut-off periods before the start: the zero-phase filter's reach
    assert at_rest.sum() > 300 and np.all(np.abs(states.q[at_rest, 0]) < 1e-6)
    truth = 0.1 * (1 - np.cos(w * np.clip(states.t - 1.0, 0.0, None)))
    assert np.max(np.abs(states.q[:, 0] - truth)) < 5e-4  # the filter rounds the start's kink


def test_a_delay_and_a_run_folders_half_period_shift_the_torque():
    t = np.arange(10000) / 1000.0
    log = _sine_log(1.0, t)
    log.tau = np.cos(2 * np.pi * (t - 0.004))[:, None]  # logged 4 ms late
    states = prepare(log, FilterChoice(cutoff=10.0, delay=0.004))
    assert np.max(np.abs(states.tau[:, 0] - np.cos(2 * np.pi * states.t))) < 1e-4
    log.torque_lag = 0.004  # a torque that holds 4 ms after its stamp, and no delay
    log.tau = np.cos(2 * np.pi * (t + 0.004))[:, None]
    states = prepare(log, FilterChoice(cutoff=10.0))
    assert np.max(np.abs(states.tau[:, 0] - np.cos(2 * np.pi * states.t))) < 1e-4


def _whole_log_states(log, choice):
    """The states by the whole log's filtering at once (the windows' reference): each column
    interpolated on the grid, filtered forwards and backwards, differentiated, the edges cut."""
    fresh = np.concatenate([[True], np.any(np.diff(log.q, axis=0) != 0, axis=1)])  # every one moves
    t = log.t[fresh]
    dt = float(np.median(np.diff(log.t)))
    grid = np.arange(t[0], t[-1], dt)
    sos = scipy.signal.butter(choice.order, choice.cutoff, fs=1.0 / dt, output="sos")

    def on_grid(values, shift=0.0, filter=True):
        out = np.column_stack([np.interp(grid + shift, t, values[fresh, i]) for i in range(values.shape[1])])
        return scipy.signal.sosfiltfilt(sos, out, axis=0) if filter else out

    q = on_grid(log.q)
    dq = on_grid(log.dq) if log.dq is not None else np.gradient(q, dt, axis=0)
    ddq = np.gradient(dq, dt, axis=0)
    tau = on_grid(log.tau, choice.delay - log.torque_lag, filter=choice.torque)
    cut = int(np.ceil(EDGE_PERIODS / choice.cutoff / dt))
    inside = slice(cut, len(grid) - cut)
    # the reversal guard, from first principles: reach rows on each side of every sign change
    reach = int(round(choice.reversal_guard / choice.cutoff / dt))
    guarded = np.zeros(dq.shape, dtype=bool)
    for j in range(dq.shape[1]):
        for f in np.flatnonzero(np.sign(dq[1:, j]) != np.sign(dq[:-1, j])) + 1:
            guarded[max(f - reach, 0) : f + reach, j] = True
    return grid[inside], q[inside], dq[inside], ddq[inside], tau[inside], guarded[inside]


@pytest.mark.parametrize("velocities", [True, False])
def test_the_states_a_window_at_a_time_are_the_whole_logs(velocities):
    """Computed in windows of 3000 samples (each filtered with its margin on both sides), the
    states of a 60 s log with jittered stamps, stale rows and noise equal the whole log's filtering
    at once to rounding at every sample, the cuts included: 1e-12 of each signal's range, 1e-9 for a
    derivative of the filtered q (each central difference scales q's rounding by 1 / dt); a
    strided segment is the same samples."""
    rng = np.random.default_rng(3)
    t = np.sort(np.arange(60000) / 1000.0 + rng.normal(0, 2e-4, 60000))
    w = 2 * np.pi * np.array([0.3, 0.7, 1.9])
    q = np.sin(np.outer(t, w)) + rng.normal(0, 1e-3, (60000, 3))
    dq = w * np.cos(np.outer(t, w)) + rng.normal(0, 1e-2, (60000, 3))
    tau = np.cos(np.outer(t, w)) + rng.normal(0, 1e-1, (60000, 3))
    stale = np.sort(rng.choice(np.arange(1, 60000), 2000, replace=False))
    for k in stale:  # in order: a run of stale rows repeats the last fresh one
        q[k], dq[k] = q[k - 1], dq[k - 1]
    log = JointLog("noisy", t, q, dq if velocities else None, tau, torque_lag=0.0005)
    choice = FilterChoice(cutoff=10.0, delay=0.002, torque=True)
    states = prepare(log, choice)
    truth = _whole_log_states(log, choice)
    windows = list(states.windows(size=3000))
    assert len(windows) > 15 and [w.start for w in windows] == list(range(0, len(states.t), 3000))
    assert np.array_equal(states.t, truth[0])
    differenced = {"ddq"} | (set() if velocities else {"dq"})
    reversal = np.concatenate([w.reversal for w in windows])
    assert 0.02 < reversal.mean() < 0.9 and np.array_equal(reversal, truth[5])  # across the windows' edges
    for name, expected in zip(("q", "dq", "ddq", "tau"), truth[1:5]):
        got = np.concatenate([getattr(w, name) for w in windows])
        error = np.max(np.abs(got - expected) / np.ptp(expected, axis=0))
        assert error < (1e-9 if name in differenced else 1e-12), (name, error)
    strided = np.concatenate([w.ddq for w in states.windows(slice(7, None, 13), size=3000)])
    assert np.max(np.abs(strided - truth[3][7::13]) / np.ptp(truth[3], axis=0)) < 1e-9


def test_quantum_is_the_smallest_step_between_levels():
    assert quantum(np.round(np.linspace(0, 1, 1000) / 0.01) * 0.01) == pytest.approx(0.01)
    assert quantum(np.zeros(5)) == 0.0
