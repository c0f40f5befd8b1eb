"""Logs with a known truth: a finite-Fourier joint trajectory (Swevers et al. 1997, the standard
exciting trajectory), the torque the true model and friction need to follow it exactly, and the
sensors' faults a real log has (noise, quantisation, a delay, jittered stamps, stale samples).
What the identification tests and benchmarks fit to (docs/identification.md, "Synthetic logs").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...model.regressor import position_ranges
from .logs import JointLog


@dataclass(frozen=True)
class FourierTrajectory:
    """q_i(t) = q0_i + sum_l a_il / (w_f l) sin(w_f l t) - b_il / (w_f l) cos(w_f l t): a
    periodic joint trajectory of base frequency ``frequency`` [Hz] and ``a.shape[1]`` harmonics.

    Attributes:
        q0: the mean position per joint [rad].
        a, b: n x L sine and cosine coefficients [rad/s].
        frequency: the base frequency f [Hz] (w_f = 2 pi f).

    """

    q0: np.ndarray
    a: np.ndarray
    b: np.ndarray
    frequency: float

    @classmethod
    def random(
        cls, model: pin.Model, harmonics: int = 5, frequency: float = 0.1, speed: float = 1.0, seed: int = 0
    ):
        """A random trajectory about the middle of the joint ranges, each joint's speed of order
        ``speed`` [rad/s] and its swing kept within a third of its range.
        """
        rng = np.random.default_rng(seed)
        n = model.nv
        low, high = position_ranges(model)
        q0 = (low + high) / 2
        a = rng.normal(0, 1, (n, harmonics))
        b = rng.normal(0, 1, (n, harmonics))
        w = 2 * np.pi * frequency * np.arange(1, harmonics + 1)
        swing = np.sum((np.abs(a) + np.abs(b)) / w, axis=1)
        peak = np.sum(np.abs(a) + np.abs(b), axis=1)
        factor = np.minimum(speed / peak, (high - low) / 6 / swing)
        return cls(q0, a * factor[:, None], b * factor[:, None], frequency)

    def states(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, q', q'' at the times ``t`` (N x n each)."""
        w = 2 * np.pi * self.frequency * np.arange(1, self.a.shape[1] + 1)
        wt = np.outer(t, w)
        s, c = np.sin(wt), np.cos(wt)
        q = self.q0 + s @ (self.a / w).T - c @ (self.b / w).T
        dq = c @ self.a.T + s @ self.b.T
        ddq = -s @ (self.a * w).T + c @ (self.b * w).T
        return q, dq, ddq


@dataclass(frozen=True)
class SensorFaults:
    """What a real log does to the signals.

    Attributes:
        torque_noise: standard deviation of white torque noise per joint [N m].
        position_noise: of white position noise [rad].
        velocity_noise: of white velocity noise [rad/s].
        torque_quantum: the torque's quantisation step [N m] (0: none).
        delay: the torque's delay [s]: the torque logged at t is the one of t - delay.
        jitter: the stamps' standard deviation about the nominal grid [s] (each stamp the time it
            was read at).
        stale: the share of samples that repeat the previous one (its values, a new stamp).

    """

    torque_noise: float = 0.05
    position_noise: float = 1e-6
    velocity_noise: float = 1e-3
    torque_quantum: float = 0.0
    delay: float = 0.0
    jitter: float = 0.0
    stale: float = 0.0


def torque_of(model: pin.Model, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, friction=None, offset=None):
    """Tau = M(q) q'' + N(q, q') + F(q') (+ a constant offset) along a trajectory: N x n."""
    data = model.createData()
    tau = np.array([pin.rnea(model, data, a, b, c) for a, b, c in zip(q, dq, ddq)])
    if friction is not None:
        tau += friction.torque(dq)
    if offset is not None:
        tau += offset
    return tau


def synthetic_log(
    model: pin.Model,
    trajectory: FourierTrajectory,
    duration: float,
    rate: float = 1000.0,
    friction=None,
    faults: SensorFaults = SensorFaults(),
    offset: np.ndarray | None = None,
    seed: int = 0,
) -> JointLog:
    """The log a robot of ``model`` and ``friction`` that follows ``trajectory`` exactly writes,
    with ``faults``: N = duration x rate samples.
    """
    rng = np.random.default_rng(seed)
    nominal = np.arange(int(round(duration * rate))) / rate
    t = nominal + (rng.normal(0, faults.jitter, nominal.shape) if faults.jitter else 0.0)
    t = np.maximum.accumulate(t)
    t[1:] = np.maximum(t[1:], t[:-1] + 1e-3 / rate)  # strictly increasing
    q, dq, _ = trajectory.states(t)
    tq = trajectory.states(t - faults.delay)
    tau = torque_of(model, *tq, friction=friction, offset=offset)
    tau = tau + rng.normal(0, faults.torque_noise, tau.shape)
    if faults.torque_quantum:
        tau = faults.torque_quantum * np.round(tau / faults.torque_quantum)
    q = q + rng.normal(0, faults.position_noise, q.shape)
    dq = dq + rng.normal(0, faults.velocity_noise, dq.shape)
    if faults.stale:
        stale = np.flatnonzero(rng.random(len(t)) < faults.stale)
        stale = stale[stale > 0]
        for k in stale:  # in order: a run of stale samples repeats the last fresh one
            q[k], dq[k], tau[k] = q[k - 1], dq[k - 1], tau[k - 1]
    return JointLog("synthetic", t, q, dq, tau)


def write_csv(log: JointLog, path, joints, named: bool = True) -> None:
    """``log`` as a CSV file ``identify`` reads: a ``time`` column, then ``q``, ``dq`` and ``tau``
    per joint, named ``q.JOINT`` (``named``) or ``q0``, ``q1``, ...
    """
    columns = {"time": log.t}
    for signal, values in (("q", log.q), ("dq", log.dq), ("tau", log.tau)):
        if values is None:  # a log without velocities
            continue
        for i, joint in enumerate(joints):
            columns[f"{signal}.{joint}" if named else f"{signal}{i}"] = values[:, i]
    names = list(columns)
    rows = np.column_stack([columns[c] for c in names])
    np.savetxt(path, rows, delimiter=",", header=",".join(names), comments="", fmt="%.12g")
