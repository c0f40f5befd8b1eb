"""Honest verdicts on a run: saturation, joint-limit violation, parameter drift and runaway error.

Each check turns the recorded arrays into a number for metrics.json and, past a documented
threshold, a one-line warning that the command line prints (docs/plant.md#verdicts).
"""

from __future__ import annotations

import math

import numpy as np

SATURATION_WARNING = 0.01
"""Fraction of control steps with a saturated command above which a run gets a warning."""

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
"""The subtask degrades: h at the end below h at the start by more than this fraction of
max(|h(0)|, spread of h over the run)."""


def saturation(tau_cmd: np.ndarray, limit: np.ndarray | None) -> tuple[float, float]:
    """(fraction of steps where some joint's command exceeds its limit, max |tau_cmd| / limit)."""
    if limit is None or tau_cmd.size == 0 or not np.any(np.isfinite(limit)):
        return 0.0, 0.0
    ratio = np.abs(tau_cmd) / limit
    return float(np.mean(np.any(ratio > 1.0, axis=1))), float(np.max(ratio))


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


def subtask_loss(h: np.ndarray | None) -> tuple[bool, float, float]:
    """(the criterion ends lower than it started, h(0), h at the end)."""
    if h is None or h.size < 2 or not np.all(np.isfinite(h[[0, -1]])):
        return False, float("nan"), float("nan")
    scale = max(abs(float(h[0])), float(np.nanmax(h) - np.nanmin(h)), 1e-12)
    return float(h[-1]) < float(h[0]) - SUBTASK_LOSS * scale, float(h[0]), float(h[-1])


def run_warnings(metrics: dict, joint_names: list[str], units: list[str]) -> list[str]:
    """The warnings of a run, from its metrics (see the module constants for the thresholds)."""
    out = []
    if metrics["saturated_fraction"] > SATURATION_WARNING:
        out.append(
            f"torque saturation: the command exceeded the effort limit in "
            f"{100 * metrics['saturated_fraction']:.1f} % of the steps (peak "
            f"{metrics['max_torque_ratio']:.2f}x the limit)"
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
            f"subtask degraded: h fell from {metrics['h_start']:.3g} to {metrics['h_end']:.3g} "
            "(model error acts in the null space too, docs/controller.md)"
        )
    return out
