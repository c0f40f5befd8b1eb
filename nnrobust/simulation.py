"""Closed-loop simulation: zero-order-hold control, RK4 or solve_ivp integration."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from .controllers.base import Controller
from .plant.plant import Plant

INTEGRATORS = ("rk4", "solve_ivp")
"""Fixed-step classical Runge-Kutta, or scipy's adaptive DOP853 per control period."""


@dataclass
class Trace:
    """Raw arrays of a simulated run, sampled at the control instants t_k = k T.

    tau[k] is the torque held over [t_k, t_k + T).

    Attributes:
        t: times [s], shape N.
        q, dq: joint positions [rad] and velocities [rad/s], N x n.
        tau: joint torques [N m], N x n.
        z: controller state, N x len(z).
        signals: controller signals by name, each of shape N.
        status: "completed", "diverged" or "interrupted".
        message: why the run stopped early, or "".

    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    tau: np.ndarray
    z: np.ndarray
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    status: str = "completed"
    message: str = ""


def _rk4_step(f, t: float, X: np.ndarray, h: float) -> np.ndarray:
    k1 = f(t, X)
    k2 = f(t + 0.5 * h, X + 0.5 * h * k1)
    k3 = f(t + 0.5 * h, X + 0.5 * h * k2)
    k4 = f(t + h, X + h * k3)
    return X + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def simulate(
    plant: Plant,
    controller: Controller,
    q0: np.ndarray,
    v0: np.ndarray,
    duration: float,
    control_period: float = 1e-3,
    substeps: int = 1,
    integrator: str = "rk4",
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_speed: float = 1e3,
    progress: Callable[[float, np.ndarray], None] | None = None,
    progress_every: int = 50,
) -> Trace:
    """Simulate plant and controller; the torque is held constant over each control period.

    The controller's internal state z is integrated together with (q, q') by the same method.

    Args:
        plant: the true robot.
        controller: the control law.
        q0, v0: initial joint positions [rad] and velocities [rad/s].
        duration: simulated time [s].
        control_period: T, the zero-order-hold period [s].
        substeps: integration steps per control period (RK4 step = T / substeps).
        integrator: "rk4" or "solve_ivp" (DOP853 with rtol, atol, restarted every period).
        max_speed: a joint speed above this [rad/s] counts as divergence.
        progress: called as progress(t, q) every ``progress_every`` control steps (progress bar,
            live viewer).

    Returns:
        The trace; a diverged or interrupted run returns what was computed, marked as such.

    """
    if integrator not in INTEGRATORS:
        raise ValueError(f"simulation.integrator: {integrator!r} is not one of {INTEGRATORS}")
    n = plant.nq
    steps = int(round(duration / control_period))
    z0 = controller.initial_state()
    X = np.concatenate([np.asarray(q0, float), np.asarray(v0, float), z0])
    nz = z0.size
    t_rec = np.arange(steps) * control_period
    q_rec = np.full((steps, n), np.nan)
    v_rec = np.full((steps, n), np.nan)
    tau_rec = np.full((steps, n), np.nan)
    z_rec = np.full((steps, nz), np.nan)
    sig_rec = {name: np.full(steps, np.nan) for name in controller.signal_names}
    tau = np.zeros(n)

    def f(t: float, X: np.ndarray) -> np.ndarray:
        q, v, z = X[:n], X[n : 2 * n], X[2 * n :]
        return np.concatenate(
            [v, plant.acceleration(t, q, v, tau), controller.state_derivative(t, q, v, z)]
        )

    h = control_period / substeps
    status, message, done = "completed", "", steps
    try:
        for k in range(steps):
            t = t_rec[k]
            q, v, z = X[:n], X[n : 2 * n], X[2 * n :]
            out = controller.compute(t, q, v, z)
            tau = out.tau
            q_rec[k], v_rec[k], tau_rec[k], z_rec[k] = q, v, tau, z
            for name, value in out.signals.items():
                sig_rec[name][k] = value
            if not (np.all(np.isfinite(tau)) and np.all(np.isfinite(X))):
                status, message, done = "diverged", f"non-finite state or torque at t = {t:.4f} s", k + 1
                break
            if np.max(np.abs(v)) > max_speed:
                status = "diverged"
                message = f"joint speed {np.max(np.abs(v)):.3g} rad/s > {max_speed:g} at t = {t:.4f} s"
                done = k + 1
                break
            if progress is not None and k % progress_every == 0:
                progress(t, q)
            if integrator == "rk4":
                for i in range(substeps):
                    X = _rk4_step(f, t + i * h, X, h)
            else:
                sol = solve_ivp(f, (t, t + control_period), X, method="DOP853", rtol=rtol, atol=atol)
                X = sol.y[:, -1]
    except KeyboardInterrupt:
        status, message, done = "interrupted", f"interrupted at t = {t:.4f} s", k
    sl = slice(0, done)
    return Trace(
        t_rec[sl], q_rec[sl], v_rec[sl], tau_rec[sl], z_rec[sl],
        {name: arr[sl] for name, arr in sig_rec.items()}, status, message,
    )
