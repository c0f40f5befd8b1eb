"""From a log as recorded to the states a fit reads: stale samples dropped, one uniform time grid,
a zero-phase low-pass filter, velocities and accelerations (docs/identification.md, "Signals").

What each step does, and why:

- **Stale samples** (a row whose positions repeat the previous row's exactly although, by its
  velocity, a joint moved more than two encoder counts since they last changed: the
  controller's loop read an old packet) are dropped; the grid below fills them in. A row at
  rest, or creeping under a count per sample, repeats its positions too and is true: it is kept
  (the plant's stick-slip holds a joint still; dropping the rest left a gap the grid may not
  fill). The torque is not asked to repeat: a stale state may come beside a fresh torque
  reading. A log without velocities cannot tell the two: every repeated row is dropped.
- **Resampling**: the stamps of a real log jitter (the Panda's: 0.7 to 8.8 ms around 1 ms);
  every signal is interpolated linearly onto the grid of the log's median step.
- **Filtering**: q and q' pass a Butterworth low-pass forwards and backwards
  (``scipy.signal.sosfiltfilt``: zero phase, the magnitude squared), so noise above the cut-off
  does not reach q''. The torque is left as logged unless asked (:class:`FilterChoice`): its
  noise then stays white, which the fit's covariance assumes and the report's whiteness test checks.
- **Differentiation**: q' is the log's own (filtered), or the central difference of the
  filtered q when the log has none; q'' is the central difference of the filtered q'. Both are
  biased by a known factor at frequency f (:func:`amplitude_gain`), under 0.5 % up to half the
  cut-off at the default order (a test measures it on a known signal).
- The samples within :data:`EDGE_PERIODS` cut-off periods of either end are dropped: the filter's
  start-up transient.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
import scipy.signal

from ...core.exceptions import LogError
from .logs import JointLog
from .spool import blocks

MAX_GAP_PERIODS = 0.5
"""The longest gap between fresh samples, in cut-off periods (the Panda log's is 0.09 at 10 Hz)."""

EDGE_PERIODS = 3.0
"""Cut-off periods dropped at each end of the log (the zero-phase filter's transients)."""


@dataclass(frozen=True)
class FilterChoice:
    """The low-pass every signal passes (a stated choice; docs/identification.md).

    Attributes:
        cutoff: the -3 dB frequency of one pass [Hz] (the zero-phase pair is -6 dB there).
        order: the Butterworth order of one pass.
        delay: the torque's measurement delay [s]: tau(t + delay) is paired with q(t).
        torque: whether the torque passes the filter too (default no: its noise is then white and
            independent of the states, so least squares is unbiased, its covariance holds, and a
            Coulomb switch in the torque stays as sharp as the regressor's sgn(q')).
        reversal_guard: cut-off periods on either side of a joint's velocity reversal whose
            samples leave the fit for that joint (0: none). At a reversal Coulomb friction flips:
            where a law commands the torque (a closed loop, a real robot), q'' jumps by
            2 F_c / M there, and the filter smears that jump over about a cut-off period on each
            side, where the filtered q'' is not the motion's.

    """

    cutoff: float = 10.0
    order: int = 4
    delay: float = 0.0
    torque: bool = False
    reversal_guard: float = 1.5


WINDOW = 1 << 16
"""Samples of the states computed at once (a multiple of the fit's batch): memory is a window's,
not the log's."""

QUANTUM_ROWS = 100_000
"""The samples each signal's quantisation is read from (the report's note; a sensor's resolution
shows in any stretch of its log)."""

MARGIN_PERIODS = 20.0
"""Cut-off periods of signal on each side of a window that its filtering reads too. The zero-phase
filter's response to where the window is cut decays as its slowest pole, whose time constant is
0.42 cut-off periods at order 4 (0.5 / pi / cos(3 pi / 8)): within 20 periods to e^-48 of the
signal, below rounding, so a window equals the whole log's filtering (a test: to 1e-12)."""


@dataclass
class Window:
    """The states of samples ``start:stop`` of the grid: positions, velocities, accelerations and
    torques, each (stop - start) x n.
    """

    start: int
    q: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    tau: np.ndarray
    reversal: np.ndarray | None = None
    """Per sample and joint, whether it is within the reversal guard of a velocity reversal
    (:attr:`FilterChoice.reversal_guard`; None: no guard)."""


def near_reversal(dq: np.ndarray, reach: int) -> np.ndarray:
    """Per row and column, whether it is within ``reach`` rows of a sign change of ``dq`` (a joint's
    velocity reversal: between two rows of opposite signs, or at a zero between them).
    """
    flips = np.zeros(dq.shape, dtype=bool)
    if reach <= 0 or len(dq) < 2:
        return flips
    sign = np.sign(dq)
    flips[1:] = sign[1:] != sign[:-1]
    # a flip between rows f - 1 and f (flips[f]) marks rows f - reach .. f + reach - 1, reach on
    # each side: row r is marked by the flips f in r - reach + 1 .. r + reach (a running count)
    counts = np.cumsum(np.vstack([np.zeros((1, dq.shape[1]), int), flips.astype(int)]), axis=0)
    rows = np.arange(len(dq))
    high = np.minimum(rows + reach + 1, len(dq))
    low = np.maximum(rows - reach + 1, 0)
    return (counts[high] - counts[low]) > 0


@dataclass
class States:
    """The states a fit reads, on a uniform grid, computed a window at a time (:meth:`windows`)
    from the log: memory holds the grid's times and one window, whatever the log's length.

    Attributes:
        t: times [s], N.
        dt: the grid's step [s].
        notes: what was done to the log, for the report (stale rows, jitter, quantisation).
        compute: ``(start, stop) -> Window`` of the grid's samples ``start:stop``.
        n: joints.

    """

    t: np.ndarray
    dt: float
    notes: dict
    compute: Callable[[int, int], Window]
    n: int

    def windows(self, segment: slice = slice(None), size: int = WINDOW) -> Iterator[Window]:
        """The states of ``segment``, window by window from its start: ``size`` samples of the grid
        at a time (a step over 1 takes every step-th of them).
        """
        start, stop, step = segment.indices(len(self.t))
        length = step * max(1, size // step)  # grid samples a window computes: a whole number of steps
        for first in range(start, stop, length):
            window = self.compute(first, min(first + length, stop))
            if step == 1:
                yield window
            else:
                part = slice(None, None, step)  # copies: a view would keep the whole window alive
                q, dq, ddq, tau = (x[part].copy() for x in (window.q, window.dq, window.ddq, window.tau))
                reversal = window.reversal[part].copy() if window.reversal is not None else None
                yield Window(first, q, dq, ddq, tau, reversal)

    def whole(self, segment: slice = slice(None)) -> Window:
        """The states of ``segment`` at once (for tests and short logs: memory grows with it)."""
        parts = list(self.windows(segment))
        if not parts:
            return Window(0, *(np.zeros((0, self.n)),) * 4)
        reversal = (
            np.concatenate([w.reversal for w in parts])
            if all(w.reversal is not None for w in parts)
            else None
        )
        q, dq, ddq, tau = (np.concatenate([getattr(w, k) for w in parts]) for k in ("q", "dq", "ddq", "tau"))
        return Window(parts[0].start, q, dq, ddq, tau, reversal)

    @property
    def q(self) -> np.ndarray:
        """Every position, N x n (:meth:`whole`)."""
        return self.whole().q

    @property
    def dq(self) -> np.ndarray:
        """Every velocity, N x n (:meth:`whole`)."""
        return self.whole().dq

    @property
    def ddq(self) -> np.ndarray:
        """Every acceleration, N x n (:meth:`whole`)."""
        return self.whole().ddq

    @property
    def tau(self) -> np.ndarray:
        """Every torque, N x n (:meth:`whole`)."""
        return self.whole().tau


def amplitude_gain(frequency: float, choice: FilterChoice, dt: float, derivatives: int) -> float:
    """The factor by which the zero-phase filter and ``derivatives`` central differences scale a
    sinusoid of ``frequency`` [Hz]: |H(f)|^2 (sin(w dt) / (w dt))^derivatives.
    """
    sos = scipy.signal.butter(choice.order, choice.cutoff, fs=1.0 / dt, output="sos")
    _, h = scipy.signal.sosfreqz(sos, worN=[frequency], fs=1.0 / dt)
    w = 2 * np.pi * frequency * dt
    return float(np.abs(h[0]) ** 2 * (np.sinc(w / np.pi) ** derivatives))


def quantum(values: np.ndarray) -> float:
    """The smallest step between two different values of a signal (its quantisation, or 0 when
    a signal has no repeated level).
    """
    ordered = np.sort(np.ravel(values))
    steps = np.diff(ordered)  # sorted: no step is negative
    del ordered
    steps = steps[steps > 0]
    return float(steps.min()) if steps.size else 0.0


def _repeated_rows(values) -> np.ndarray:
    """Whether each row repeats the previous row's values exactly (the first row: no)."""
    repeated, last = np.zeros(len(values), dtype=bool), None
    for start, block in blocks(values):
        joined = block if last is None else np.concatenate([last, block])
        repeated[start + (last is None) : start + len(block)] = np.all(np.diff(joined, axis=0) == 0, axis=1)
        last = block[-1:]
    return repeated


STALE_COUNTS = 2.0
"""Encoder counts a joint must have moved, by its velocity, since its positions last changed for a
repeated row to be stale (one count may pass legitimately before a quantised encoder steps)."""


def _moved_rows(t: np.ndarray, dq, repeated: np.ndarray, count: float) -> np.ndarray:
    """Whether, by its velocity, some joint moved more than :data:`STALE_COUNTS` counts since the
    positions last changed (the time since the last row that did not repeat its predecessor).
    """
    moved = np.zeros(len(t), dtype=bool)
    last_fresh = 0
    for start, block in blocks(dq):
        rows = np.arange(start, start + len(block))
        fresh_index = np.where(repeated[rows], -1, rows)
        fresh_index[0] = max(fresh_index[0], last_fresh)
        fresh_index = np.maximum.accumulate(fresh_index)
        last_fresh = int(fresh_index[-1])
        elapsed = t[rows] - t[fresh_index]
        moved[rows] = np.abs(block).max(axis=1) * elapsed > STALE_COUNTS * count
    return moved


def stale_rows(log: JointLog, count: float) -> tuple[np.ndarray, np.ndarray]:
    """(stale, repeated): the rows whose positions repeat the previous row's exactly, and of those
    the stale ones: where by its velocity some joint moved more than :data:`STALE_COUNTS` counts
    of the encoder (``count``: :func:`quantum` of the positions) since its positions last
    changed. A row at rest, or one creeping under a count per sample, repeats its positions and
    is true. A log without velocities cannot tell: every repeated row is stale.
    """
    repeated = _repeated_rows(log.q)
    if log.dq is None:
        return repeated, repeated
    return repeated & _moved_rows(log.t, log.dq, repeated, count), repeated


def _new_torque_rows(tau, rows: np.ndarray) -> int:
    """How many of ``rows`` (sorted, none the first) have a torque other than the previous row's."""
    if rows.size == 0:
        return 0
    return int(np.sum(np.any(tau[rows] != tau[rows - 1], axis=1)))


def prepare(log: JointLog, choice: FilterChoice = FilterChoice()) -> States:
    """The log on a uniform grid, filtered and differentiated (the module's steps, in order)."""
    steps = np.diff(log.t)
    q_quantum = quantum(log.q[:QUANTUM_ROWS])  # an encoder count: the stale rule's and the notes'
    stale, repeated = stale_rows(log, q_quantum)
    new_torque = _new_torque_rows(log.tau, np.flatnonzero(stale))  # read at the stale rows alone
    keep = ~stale
    t = log.t[keep]  # the signals' fresh rows are taken column by column (on_grid)
    dt = float(np.median(steps))  # the log's own rate (the stale rows dropped leave wider steps)
    duration = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    nyquist = 0.5 / dt if dt > 0 else 0.0
    if not 0 < choice.cutoff < 0.8 * nyquist:
        units = " (are the times in seconds?)" if not 1e-5 <= dt <= 0.1 else ""
        raise LogError(
            f"{log.source}: the filter's cut-off {choice.cutoff:g} Hz must be positive and below 80 % of the "
            f"log's Nyquist frequency {nyquist:.4g} Hz (its median step is {dt * 1e3:.4g} ms){units}"
        )
    gaps = np.diff(t)
    longest = int(np.argmax(gaps)) if len(gaps) else 0
    if len(gaps) and gaps[longest] > MAX_GAP_PERIODS / choice.cutoff:
        raise LogError(
            f"{log.source}: no sample between {t[longest]:.6g} s and {t[longest + 1]:.6g} s; a gap over "
            f"{MAX_GAP_PERIODS:g} cut-off period ({MAX_GAP_PERIODS / choice.cutoff * 1e3:.3g} ms) would be "
            "filled with made-up samples: identify the parts on either side apart"
        )
    edge = EDGE_PERIODS / choice.cutoff
    if duration <= 2 * edge + 10 * dt:
        raise LogError(
            f"{log.source}: {duration:.3g} s of log; a fit at a {choice.cutoff:g} Hz cut-off needs more than "
            f"{2 * edge:.3g} s (its filter's transients are dropped at both ends)"
        )
    grid = np.arange(t[0], t[-1], dt)

    sos = scipy.signal.butter(choice.order, choice.cutoff, fs=1.0 / dt, output="sos")
    cut = int(np.ceil(edge / dt))
    margin = int(np.ceil(MARGIN_PERIODS / choice.cutoff / dt))
    if not 0 <= choice.reversal_guard <= MARGIN_PERIODS / 2:
        raise LogError(
            f"--reversal-guard must be 0 to {MARGIN_PERIODS / 2:g} cut-off periods, "
            f"got {choice.reversal_guard:g}"
        )
    guard = int(round(choice.reversal_guard / choice.cutoff / dt))
    fresh = np.flatnonzero(keep)  # the log's rows on which the grid is interpolated
    tau_shift = choice.delay - log.torque_lag

    def compute(start: int, stop: int) -> Window:
        """The grid's samples ``cut + start : cut + stop``, from the log's rows they are
        interpolated from and ``margin`` samples more on each side (filtered, then cut off).
        """
        lo, hi = max(0, cut + start - margin), min(len(grid), cut + stop + margin)
        on = grid[lo:hi]

        def on_grid(values: np.ndarray, shift: float = 0.0, filter: bool = True) -> np.ndarray:
            first = max(int(np.searchsorted(t, on[0] + shift, side="right")) - 1, 0) if len(on) else 0
            last = int(np.searchsorted(t, on[-1] + shift, side="left")) + 1 if len(on) else 0
            rows = values[fresh[first:last]]  # the window's fresh rows, read once
            out = np.empty((len(on), values.shape[1]))
            for i in range(values.shape[1]):  # a column at a time: the temporaries are a column's
                column = np.interp(on + shift, t[first:last], rows[:, i])
                out[:, i] = scipy.signal.sosfiltfilt(sos, column) if filter else column
            return out

        q = on_grid(log.q)
        dq = on_grid(log.dq) if log.dq is not None else np.gradient(q, dt, axis=0)
        ddq = np.gradient(dq, dt, axis=0)
        tau = on_grid(log.tau, tau_shift, filter=choice.torque)
        inside = slice(cut + start - lo, cut + stop - lo)
        reversal = near_reversal(dq, guard)[inside] if guard > 0 else None  # the margin's reversals too
        return Window(start, q[inside], dq[inside], ddq[inside], tau[inside], reversal)

    notes = {
        "samples": int(len(log.t)),
        "stale_samples": int(stale.sum()),
        "stale_with_new_torque": new_torque,
        "repeated_positions_kept": int(np.sum(repeated & ~stale)),
        "median_step_ms": dt * 1e3,
        "step_range_ms": [float(steps.min() * 1e3), float(steps.max() * 1e3)],
        "step_jitter_ms": float(np.std(np.diff(t)) * 1e3),
        "grid_samples": int(len(grid) - 2 * cut),
        "edge_dropped_s": cut * dt,
        "quantum": {  # of the first QUANTUM_ROWS samples
            "q": q_quantum,
            "dq": quantum(log.dq[:QUANTUM_ROWS]) if log.dq is not None else None,
            "tau": quantum(log.tau[:QUANTUM_ROWS]),
        },
        "velocity": "logged, filtered" if log.dq is not None else "central difference of the filtered q",
        "filter": {
            "kind": "butterworth, zero phase (sosfiltfilt)",
            "cutoff_hz": choice.cutoff,
            "order": choice.order,
            "torque_filtered": choice.torque,
        },
        "torque_lag_s": log.torque_lag,
        "delay_s": choice.delay,
    }
    return States(grid[cut : len(grid) - cut], dt, notes, compute, log.q.shape[1])
