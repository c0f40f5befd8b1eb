"""Honest verdicts on a run: saturation, speed and joint limits, lost tracking, parameter drift,
runaway error and a degraded subtask.

Each check turns the recorded arrays into a number for metrics.json and, past a documented
threshold, a one-line warning that the command line prints (docs/plant.md#verdicts).
"""

from __future__ import annotations

import math

import numpy as np

FLAGS = ("runaway", "rho_hat_growing", "subtask_degraded")
"""The verdicts that are true or false (a row's boolean columns; a property may require one)."""

SATURATION_WARNING = 0.01
"""Fraction of control steps with a saturated actuator above which a run gets a warning."""

AT_LIMIT = 1e-6
"""An actuator is saturated when its applied torque is within this fraction of the torque it can
give (so a law that clips its own command at the limit is counted too)."""

TRACKING_LOST = 0.1
"""Tracking is lost when the RMS error after 2 s exceeds this fraction of the path's size."""

PATH_SIZE_FLOOR = 0.05
"""[m] The path's size is at least this (a set point has none of its own)."""

SAME_POINT = 0.005
"""Two instants are at the same point of the path when their desired positions are closer than
this fraction of the path's size (the subtask verdict compares h there)."""

RUNAWAY_RATIO = 3.0
"""Runaway: RMS error over the last fifth above this times the RMS over [2 s, 40 %] ..."""

RUNAWAY_MIN_ERROR = 0.01
"""... and above this [m]."""

RHO_GROWTH = 1.25
"""rho-hat keeps growing: its peak over the last fifth of the run above this times its peak over
[20 %, 60 %] of the run (peaks, since a bounded rho-hat over a joint-space basis oscillates with
the arm's motion) ..."""

RHO_MIN = 1.0
"""... and above this [m/s^2] (a negligible bound may drift)."""

STEP_ROTATION = 0.05
"""[rad or m] A joint that moves more than this in one plant step makes the RK4 step too long for
the dynamics its speed excites (Coriolis and centrifugal rates scale with q'): results may depend
on the step (docs/plant.md). The speed-adaptive step keeps it below simulation.max_step_rotation
(0.02) at each period's start; the warning fires where a period's speed outgrew that."""

SUBTASK_LOSS = 0.05
"""The subtask degrades: at the end of the run h is lower than it was at the same point of the path
after 2 s by more than this fraction of max(|h| there, spread of h after 2 s)."""


def saturation(tau: np.ndarray, available: np.ndarray | None) -> float:
    """Fraction of steps where some joint's applied torque ``tau`` is at the torque its actuator
    can give (``available``, N x n or n; within :data:`AT_LIMIT`): the actuator gives all it has,
    whether it cut the command or the law asked for exactly that much.
    """
    if available is None or tau.size == 0:
        return 0.0
    at_limit = np.abs(tau) >= (1.0 - AT_LIMIT) * available
    return float(np.mean(np.any(at_limit & np.isfinite(available), axis=1)))


def ratio_to_limit(value: np.ndarray, limit: np.ndarray | None) -> tuple[float | None, int]:
    """(max over samples and joints of |value| / limit, that joint; -1 if none) over the joints
    with a finite limit; (None, -1) where no joint has one.
    """
    if limit is None or value.size == 0 or not np.any(np.isfinite(limit)):
        return None, -1
    ratio = np.abs(value) / limit
    worst = np.max(ratio.reshape(-1, limit.size), axis=0)
    i = int(np.argmax(worst))
    return float(worst[i]), i


def speed_over_limit(dq: np.ndarray, limit: np.ndarray | None) -> tuple[float | None, float | None, int, int]:
    """(fraction of steps where some joint moves faster than its velocity limit, the peak
    |q'_i| / limit_i, that joint, how many joints exceed their limits); (None, None, -1, 0) where
    no joint's limit is known.
    """
    peak, joint = ratio_to_limit(dq, limit)
    if peak is None or limit is None:
        return None, None, -1, 0
    over = np.abs(dq) > limit
    return float(np.mean(np.any(over, axis=1))), peak, joint, int(np.sum(np.any(over, axis=0)))


def path_size(x_d: np.ndarray) -> float:
    """The desired path's size: the diagonal of its positions' bounding box, at least
    :data:`PATH_SIZE_FLOOR` [m].
    """
    if x_d.size == 0:
        return PATH_SIZE_FLOOR
    p = x_d[:, :3]
    return max(float(np.linalg.norm(np.ptp(p, axis=0))), PATH_SIZE_FLOOR)


def joint_limit_violation(q: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> tuple[float, int]:
    """(largest distance beyond a position limit [rad or m], index of that joint; -1 if none)."""
    if q.size == 0:
        return 0.0, -1
    beyond = np.maximum(q - upper, 0.0) + np.maximum(lower - q, 0.0)
    worst = np.max(beyond, axis=0)
    i = int(np.argmax(worst))
    return float(worst[i]), (i if worst[i] > 0 else -1)


def runaway(t: np.ndarray, error: np.ndarray) -> tuple[bool, float, float]:
    """(error grows over the run, RMS over [2 s, 40 %], RMS over the last fifth) [m].

    Defined for runs of at least 5 s (so that [2 s, 40 %] is not empty).
    """
    if t.size < 2 or t[-1] < 5.0:
        return False, float("nan"), float("nan")
    end = t[-1]
    early = error[(t >= 2.0) & (t <= 0.4 * end)]
    late = error[t >= 0.8 * end]
    rms_early, rms_late = float(np.sqrt(np.mean(early**2))), float(np.sqrt(np.mean(late**2)))
    return (rms_late > RUNAWAY_RATIO * rms_early and rms_late > RUNAWAY_MIN_ERROR), rms_early, rms_late


def rho_growing(t: np.ndarray, rho: np.ndarray | None) -> tuple[bool, float, float]:
    """(rho-hat keeps growing, its peak over [20 %, 60 %] of the run, its peak over the last fifth)."""
    if rho is None or rho.size < 10 or not np.all(np.isfinite(rho)):
        return False, float("nan"), float("nan")
    end = t[-1]
    middle = float(np.max(rho[(t >= 0.2 * end) & (t <= 0.6 * end)]))
    late = float(np.max(rho[t >= 0.8 * end]))
    return late > RHO_GROWTH * middle and late > RHO_MIN, middle, late


SUBTASK_WINDOW = 1.0
"""[s] The subtask verdict compares h at least this long before the end of the run."""


def subtask_loss(t: np.ndarray, h: np.ndarray | None, x_d: np.ndarray) -> tuple[bool, float, float, float]:
    """(the criterion ends lower than at the same point of the path earlier, h there, h at the
    end, the time it was there [s]).

    h depends on where the task is, so h at the end is compared with h at an earlier instant t*
    (t* >= 2 s, at least :data:`SUBTASK_WINDOW` before the end) at the same point of the path:
    the first instant whose desired position is within :data:`SAME_POINT` of the path's size of
    the final one and after which the path left that point and came back (a periodic path), or
    where the path holds still until the end (a point-to-point or waypoint path's last hold).
    Without such an instant (a path that never returns, a run shorter than one lap) there is no
    verdict (NaN); nor on a run that lost the path (Result.metrics: the arm is not at the point
    the comparison assumes).
    """
    nan = float("nan")
    none = (False, nan, nan, nan)
    if h is None or h.size < 2 or not np.isfinite(h[-1]):
        return none
    p = x_d[:, :3]
    far = np.linalg.norm(p - p[-1], axis=1) > SAME_POINT * path_size(x_d)
    allowed = (t >= 2.0) & (t <= t[-1] - SUBTASK_WINDOW)
    if far.any():
        last_away = int(np.flatnonzero(far)[-1])  # the path's last time away from the final point
        back = np.flatnonzero(allowed & ~far & (np.arange(t.size) < last_away))
        hold = np.flatnonzero(allowed & (np.arange(t.size) > last_away))
        candidates = back if back.size else hold
    else:  # a set point
        candidates = np.flatnonzero(allowed)
    if not candidates.size:
        return none
    k = int(candidates[0])
    if not np.isfinite(h[k]):
        return none
    late = h[t >= 2.0]
    spread = late[np.isfinite(late)]
    scale = max(abs(float(h[k])), float(np.ptp(spread)) if spread.size else 0.0, 1e-12)
    return float(h[-1]) < float(h[k]) - SUBTASK_LOSS * scale, float(h[k]), float(h[-1]), float(t[k])


def run_warnings(metrics: dict, joint_names: list[str], units: list[str]) -> list[str]:
    """The warnings of a run, from its metrics (see the module constants for the thresholds)."""
    out = []
    if metrics["saturated_fraction"] > SATURATION_WARNING:
        peak = metrics.get("max_torque_ratio")
        envelope = " (its effort limit, cut at speed by the torque-speed envelope)"
        out.append(
            f"torque saturation: an actuator gave all the torque it can"
            f"{envelope if metrics.get('torque_speed_knee', -1.0) >= 0 else ''} in "
            f"{100 * metrics['saturated_fraction']:.1f} % of the steps"
            + (f" (command peak {peak:.3g}x the effort limit)" if peak else "")
        )
    speed = metrics.get("max_speed_ratio")
    if speed is not None and speed > 1.0:
        i = metrics["speed_limit_joint"]
        joints = metrics.get("joints_over_speed_limit", 1)
        hint = (
            ""
            if metrics.get("torque_speed_knee", -1.0) >= 0
            else " (plant.torque_speed = 'urdf' models the cut)"
        )
        out.append(
            f"joint speed: joint {joint_names[i]!r} reached {speed:.3g}x its velocity limit; "
            f"{joints} joint{'s' if joints != 1 else ''} over a limit in "
            f"{metrics['speed_limit_fraction'] * 100:.3g} % of the steps. A real arm's drive would fault "
            f"or cut the torque{hint}"
        )
    late = metrics.get("inference_over_period")
    if late:
        out.append(
            f"deadline missed: the policy's inference took longer than the control period in "
            f"{100 * late:.3g} % of the steps (up to {1e6 * metrics['max_inference_time']:.3g} µs); a real "
            "controller would miss those deadlines (the simulation waited for it)"
        )
    lost = metrics.get("tracking_error_ratio")
    if lost is not None and lost > TRACKING_LOST:
        out.append(
            f"tracking lost: RMS error after 2 s {1e3 * metrics['rms_error_after_2s']:.3g} mm is "
            f"{lost:.3g}x the path's size {1e3 * metrics['path_size']:.3g} mm (threshold {TRACKING_LOST:g})"
        )
    if metrics["max_joint_limit_violation"] > 0:
        i = metrics["joint_limit_joint"]
        unit = "m" if units[i] == "m/s" else "rad"
        out.append(
            f"joint stop: joint {joint_names[i]!r} went {metrics['max_joint_limit_violation']:.3g} "
            f"{unit} beyond its limit"
        )
    if metrics.get("rho_hat_growing"):
        out.append(
            f"rho-hat keeps growing: peak {metrics['rho_hat_peak_middle']:.3g} over [20 %, 60 %] "
            f"of the run, {metrics['rho_hat_peak_last_fifth']:.3g} over the last fifth "
            "(parameter drift; nn.sigma > 0 bounds it)"
        )
    if metrics.get("runaway"):
        out.append(
            f"runaway: RMS error {1e3 * metrics['rms_error_last_fifth']:.3g} mm over the last "
            f"fifth against {1e3 * metrics['rms_error_early']:.3g} mm over [2 s, 40 %]"
        )
    turn = metrics.get("step_rotation")
    if turn is None:  # a run folder from before the speed-adaptive step
        turn = metrics.get("max_joint_speed", 0.0) * metrics.get("plant_step", float("nan"))
    if turn > STEP_ROTATION:
        i = metrics["joint_speed_joint"]
        unit = "m" if units[i] == "m/s" else "rad"
        out.append(
            f"plant step too long: joint {joint_names[i]!r} reached {metrics['max_joint_speed']:.3g} "
            f"{units[i]} and turned up to {turn:.3g} {unit} in one plant step (docs/plant.md); the "
            "metrics may depend on the step: set simulation.max_step_rotation lower, or "
            f"simulation.substeps {math.ceil(turn / STEP_ROTATION)}x higher"
        )
    if metrics.get("unresolved_events"):
        out.append(
            f"plant not converged: {metrics['unresolved_events']} plant steps held more stick-slip "
            "events than the integrator resolves (docs/plant.md); set simulation.substeps higher"
        )
    if metrics.get("subtask_degraded"):
        out.append(
            f"subtask degraded: at the same point of the path h fell from {metrics['h_start']:.3g} "
            f"(t = {metrics.get('h_start_time', float('nan')):.3g} s) to {metrics['h_end']:.3g} at the end "
            "(model error acts in the null space too, docs/controller.md)"
        )
    return out
