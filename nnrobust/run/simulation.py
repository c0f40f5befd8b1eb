"""Closed-loop simulation: sampled control with a zero-order hold, RK4 or solve_ivp integration."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..controllers.base import Controller
from ..controllers.custom import checked_output, failed, undeclared
from ..core.exceptions import NNRobustError
from ..core.numeric_limits import MAX_STEP_ROTATION
from ..core.signals import check_interrupt, clear_interrupt
from ..plant.plant import Plant
from ..plant.stick_slip import StickSlipIntegrator, rk4_flow

INTEGRATORS = ("rk4", "solve_ivp")
"""Fixed-step classical Runge-Kutta, or scipy's adaptive DOP853 per control period."""

MAX_SPEED = 1e3
"""A joint faster than this [rad/s or m/s] counts as divergence (both loops)."""


MAX_PERIOD_SUBSTEPS = 10_000
"""The most plant steps one control period is cut into (as simulation.substeps)."""


def step_rate(q: np.ndarray, v: np.ndarray, stops, period: float) -> float:
    """The rate [rad/s] a control period's plant step must resolve: the fastest joint's speed,
    or the ring frequency of a stop a joint is at or would reach within the period, whichever is
    higher (a contact's onset and its rebound bend the trajectory at that rate; docs/plant.md
    #speed-adaptive-step). The compiled twin is closed_loop.cpp's step_rate.
    """
    speed = float(np.max(np.abs(v)))
    return speed if stops is None else max(speed, stops.ringing(q, v, period))


def period_substeps(speed, period: float, substeps: int, max_rotation: float):
    """Plant steps for one control period: ``substeps``, or more when the fastest joint, at its
    speed at the period's start [rad/s or m/s], would turn more than ``max_rotation`` in one
    (Coriolis and centrifugal rates grow with q', and with them the RK4 truncation error; both
    loops, docs/plant.md#speed-adaptive-step). ``max_rotation = inf`` keeps the step fixed.
    ``speed`` may be an array of periods' speeds (results.step_rotation); the compiled loop's
    twin is closed_loop.cpp's period_substeps.
    """
    needed = np.ceil(period * np.asarray(speed, dtype=float) / max_rotation)
    return np.where(needed <= substeps, substeps, np.minimum(needed, MAX_PERIOD_SUBSTEPS)).astype(int)


@dataclass
class Trace:
    """Raw arrays of a simulated run, sampled at the control instants t_k = k T.

    tau[k] is the torque applied over [t_k, t_k + T): the command tau_cmd[k] clipped to the effort
    limits. tau_cmd[k] was computed from the measurement at t_(k-d) for a delay of d periods.

    Attributes:
        t: times [s], shape N.
        q, dq: true joint positions [rad] and velocities [rad/s], N x n.
        tau: applied joint torques [N m], N x n.
        tau_cmd: commanded joint torques [N m], N x n.
        z: controller state at t_k, N x len(z).
        signals: controller signals by name, each of shape N.
        status: "completed", "diverged" or "interrupted".
        message: why the run stopped early, or "".
        recorded: per-sample quantities a loop already computed for the Result (the compiled
            loop: ``chain`` N x (n + 1) x 3, ``manipulability`` and ``h``), or None.
        friction_events: stick-slip events located inside plant steps (:mod:`nnrobust.plant.stick_slip`;
            mode changes when a new command arrives are not counted).
        unresolved_events: integration steps with more events than it resolves.
        refined_periods: control periods whose plant step was cut for speed or a stop (:func:`step_rate`).

    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    tau: np.ndarray
    tau_cmd: np.ndarray
    z: np.ndarray
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    status: str = "completed"
    message: str = ""
    recorded: dict | None = None
    friction_events: int = 0
    unresolved_events: int = 0
    refined_periods: int = 0


def _rk4_step(f, t: float, X: np.ndarray, h: float) -> np.ndarray:
    k1 = f(t, X)
    k2 = f(t + 0.5 * h, X + 0.5 * h * k1)
    k3 = f(t + 0.5 * h, X + 0.5 * h * k2)
    k4 = f(t + h, X + h * k3)
    return X + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def _ivp_flow(plant: Plant, tau: np.ndarray, rtol: float, atol: float):
    """DOP853 over the span with the friction modes held (the smooth pieces of stick-slip)."""
    from scipy.integrate import solve_ivp  # imported only when chosen

    n = plant.nq

    def flow(t, q, v, mode, span):
        def f(s, X):
            return np.concatenate([X[n:], plant.constrained_acceleration(s, X[:n], X[n:], tau, mode)[0]])

        sol = solve_ivp(f, (t, t + span), np.concatenate([q, v]), method="DOP853", rtol=rtol, atol=atol)
        return sol.y[:n, -1], sol.y[n:, -1]

    return flow


def joint_units(model) -> list[str]:
    """Velocity unit of each joint of the model: "m/s" for prismatic joints, else "rad/s"."""
    prismatic = getattr(model, "prismatic", None)
    return ["m/s" if p else "rad/s" for p in prismatic] if prismatic is not None else ["rad/s"] * model.nq


def speed_message(model, v: np.ndarray, max_speed: float, t: float) -> str:
    """Which joint ran away, how fast, in its own unit."""
    i = int(np.argmax(np.abs(v)))
    names = getattr(model, "joint_names", None) or [f"joint {j + 1}" for j in range(v.size)]
    unit = joint_units(model)[i]
    return (
        f"joint {names[i]!r} reached {v[i]:.3g} {unit} (limit for divergence {max_speed:g}) at t = {t:.4f} s"
    )


def simulate(
    plant: Plant,
    controller: Controller,
    q0: np.ndarray,
    v0: np.ndarray,
    duration: float,
    control_period: float = 1e-3,
    substeps: int = 1,
    integrator: str = "rk4",
    max_step_rotation: float = MAX_STEP_ROTATION,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_speed: float = MAX_SPEED,
    progress: Callable[[float, np.ndarray], None] | None = None,
    progress_every: int = 50,
) -> Trace:
    """Simulate plant and sampled controller.

    At each control instant t_k the controller reads the plant's sensor, returns a command and its
    next state; the command reaches the actuators ``plant.delay`` periods later (before that the
    first command is held), is clipped to the effort limits and held over the period while
    (q, q') are integrated with the stops, friction and disturbance acting continuously, and the
    external loads (``[[plant.loads]]``) switched at control instants. Joints
    with dry friction are integrated as stick-slip, their events located inside the step
    (:mod:`nnrobust.plant.stick_slip`).

    Args:
        plant: the true robot with its actuators and sensors.
        controller: the control law.
        q0, v0: initial joint positions [rad] and velocities [rad/s].
        duration: simulated time [s].
        control_period: T, the zero-order-hold period [s].
        substeps: integration steps per control period (RK4 step = T / substeps).
        max_step_rotation: a period whose fastest joint would turn more than this [rad or m] in
            one step is integrated in more (:func:`period_substeps`; RK4 without an engine).
        integrator: "rk4" or "solve_ivp" (DOP853 with rtol, atol, restarted every period).
        max_speed: a joint speed above this [rad/s or m/s] counts as divergence.
        progress: called as progress(t, q) every ``progress_every`` control steps (progress bar,
            live viewer).

    Returns:
        The trace; a diverged or interrupted run returns what was computed, marked as such.

    """
    if integrator not in INTEGRATORS:
        raise ValueError(f"simulation.integrator: {integrator!r} is not one of {INTEGRATORS}")
    n = plant.nq
    steps = int(round(duration / control_period))
    sensor = plant.sensor
    assert sensor is not None  # Plant sets an ideal one when none is given
    sensor.reset()  # every draw from the seed, at the start of each run (as the compiled loop)
    z = controller.initial_state()
    X = np.concatenate([np.asarray(q0, float), np.asarray(v0, float)])
    t_rec = np.arange(steps) * control_period
    q_rec = np.full((steps, n), np.nan)
    v_rec = np.full((steps, n), np.nan)
    tau_rec = np.full((steps, n), np.nan)
    cmd_rec = np.full((steps, n), np.nan)
    z_rec = np.full((steps, z.size), np.nan)
    sig_rec = {name: np.full(steps, np.nan) for name in controller.signal_names}
    commands: deque[np.ndarray] = deque(maxlen=plant.delay + 1)
    tau = np.zeros(n)

    def f(t: float, X: np.ndarray) -> np.ndarray:
        return np.concatenate([X[n:], plant.acceleration(t, X[:n], X[n:], tau)])

    user_code = not type(controller).__module__.startswith("nnrobust.")
    engine = plant.engine
    if engine is not None:  # MuJoCo integrates the plant (nnrobust.plant.mujoco_engine)
        engine.reset(np.asarray(q0, float), np.asarray(v0, float))
    stick_slip = (
        StickSlipIntegrator(plant, np.asarray(v0, float)) if plant.sticky.any() and engine is None else None
    )
    status, message, done = "completed", "", steps
    k, t, refined = 0, 0.0, 0
    try:
        for k in range(steps):
            check_interrupt()  # an interrupt lost in a garbage-collection callback (signals.py)
            t = t_rec[k]
            q, v = X[:n], X[n:]
            try:
                q_m, v_m = sensor.measure(q, v)
                out = controller.compute(t, q_m, v_m, z, control_period)
            except (KeyboardInterrupt, NNRobustError):
                raise
            except (Exception, SystemExit) as err:  # a law may not end the process
                if user_code:
                    raise failed(controller, err, t) from err
                raise
            if user_code:  # checked at every step: a late wrong output is named, never broadcast
                command, signals, state = checked_output(controller, out, n, z.size, t)
            else:
                command, signals, state = out.tau, out.signals, out.state
            commands.append(command)
            tau_cmd = commands[0]  # computed d periods ago (the first command until then)
            tau = plant.applied_torque(tau_cmd, v)
            plant.begin_period(t)  # the loads held over this period (nnrobust.plant.loads)
            q_rec[k], v_rec[k], tau_rec[k], cmd_rec[k], z_rec[k] = q, v, tau, tau_cmd, z
            try:
                for name, value in signals.items():
                    sig_rec[name][k] = value
            except KeyError:
                undeclared(controller, signals)
                raise
            if not (np.all(np.isfinite(command)) and np.all(np.isfinite(X))):
                status, message, done = "diverged", f"non-finite state or torque at t = {t:.4f} s", k + 1
                break
            if np.max(np.abs(v)) > max_speed:
                status, message, done = "diverged", speed_message(plant.model, v, max_speed, t), k + 1
                break
            if progress is not None and k % progress_every == 0:
                progress(t, q)
            if state is not None:
                z = state
            if engine is not None:
                X = np.concatenate(engine.advance(t, tau, control_period, plant.held.torque))
                failure = engine.failure(t)  # a state or torque MuJoCo discarded: the run ends
                if failure:
                    status, message, done = "diverged", failure, k + 1
                    break
                continue
            n_steps = (
                int(
                    period_substeps(
                        step_rate(q, v, plant.stops, control_period),
                        control_period,
                        substeps,
                        max_step_rotation,
                    )
                )
                if integrator == "rk4"
                else substeps
            )
            refined += n_steps != substeps
            h = control_period / n_steps
            if stick_slip is not None:  # q, v: the views of X sliced at the top of the step
                if integrator == "rk4":
                    flow = rk4_flow(plant, tau)
                    for i in range(n_steps):
                        q, v = stick_slip.advance(flow, t + i * h, q, v, tau, h, new_command=i == 0)
                else:
                    q, v = stick_slip.advance(_ivp_flow(plant, tau, rtol, atol), t, q, v, tau, control_period)
                X = np.concatenate([q, v])
            elif integrator == "rk4":
                for i in range(n_steps):
                    X = _rk4_step(f, t + i * h, X, h)
            else:
                from scipy.integrate import solve_ivp  # imported once, and only when chosen

                sol = solve_ivp(f, (t, t + control_period), X, method="DOP853", rtol=rtol, atol=atol)
                X = sol.y[:, -1]
    except KeyboardInterrupt:
        status, message, done = "interrupted", f"interrupted at t = {t:.4f} s", k
        clear_interrupt()
    sl = slice(0, done)
    return Trace(
        t_rec[sl],
        q_rec[sl],
        v_rec[sl],
        tau_rec[sl],
        cmd_rec[sl],
        z_rec[sl],
        {name: arr[sl] for name, arr in sig_rec.items()},
        status,
        message,
        friction_events=stick_slip.events if stick_slip else 0,
        unresolved_events=stick_slip.unresolved if stick_slip else 0,
        refined_periods=refined,
    )
