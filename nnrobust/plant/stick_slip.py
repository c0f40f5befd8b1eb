"""Integration of the plant through Coulomb friction's sign changes: stick-slip with located events.

F(q') = F_d q' + F_c sgn(q') is discontinuous at q' = 0, where sgn is set-valued: a joint at rest
is held by any friction torque f with |f| <= F_s (F_s >= F_c, the static level; F_s = F_c is the
plain Coulomb law). A fixed RK4 step across the switch is first order at best and makes a resting
joint chatter at a fake speed of order F_c h / I. Here each sticky joint (F_s > 0) has a mode,
slipping forward (+1), backward (-1) or stuck (0), and within a mode the right-hand side is smooth:

    slipping:  F_i = F_d,i q'_i + F_c,i mode_i
    stuck:     q'_i = 0, q''_i = 0, and f_i = (tau - N - M q'')_i is the friction that holds it.

With S the stuck joints and R the rest, M_RR q''_R = r_R and f_S = r_S - M_SR q''_R, where
r = tau + tau_stop - tau_d - F_d q' - F_c mode - V_m q' - G (docs/plant.md). A step that ends
with an event is cut at it: a slipping joint whose speed reaches zero, or a stuck joint whose
holding torque exceeds F_s. The event is located to within ``EVENT_TOLERANCE`` by the Illinois
method on re-integrations of the step's start, the mode is switched there, and the step goes on.

At an event (and at every new command) the joints at rest choose their modes (``settle``) by
the set-valued law itself: with M q'' = r - f, the friction of the joints at rest minimises
1/2 (r - f)^T M^-1 (r - f) over |f_i| <= F_s,i (a box-constrained QP in the Delassus matrix,
solved exactly by ``box_qp``), so a joint is held exactly when static friction can hold it
with the others doing what they do. csrc/plant/stick_slip.hpp is the compiled twin, step for step.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

EVENT_TOLERANCE = 1e-12
"""Width [s] to which an event's time is located (or a residual below 1e-12 of its scale)."""

MAX_EVENTS = 64
"""Events handled in one integration step; past it the step is taken as it is and counted."""

MAX_LOCATE_ITERATIONS = 60

Flow = Callable[[float, np.ndarray, np.ndarray, np.ndarray, float], tuple[np.ndarray, np.ndarray]]
"""(t, q, v, mode, span) -> (q, v) after span [s] with the modes held."""


def rk4_flow(plant, tau: np.ndarray) -> Flow:
    """One classical Runge-Kutta step of the given span with the modes held."""

    def accel(t, q, v, mode):
        return plant.constrained_acceleration(t, q, v, tau, mode)[0]

    def flow(t, q, v, mode, h):
        a1 = accel(t, q, v, mode)
        v2 = v + 0.5 * h * a1
        a2 = accel(t + 0.5 * h, q + 0.5 * h * v, v2, mode)
        v3 = v + 0.5 * h * a2
        a3 = accel(t + 0.5 * h, q + 0.5 * h * v2, v3, mode)
        v4 = v + h * a3
        a4 = accel(t + h, q + h * v3, v4, mode)
        q_next = q + (h / 6.0) * (v + 2.0 * v2 + 2.0 * v3 + v4)
        v_next = v + (h / 6.0) * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        return q_next, v_next

    return flow


def box_qp(W: np.ndarray, c: np.ndarray, bound: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Minimise 1/2 f^T W f - c^T f subject to |f_i| <= bound_i (W positive definite), exactly.

    A primal active-set method from f = 0: solve on the free entries, stop at the first bound in
    the way, and release a bound entry whose multiplier has the wrong sign. Returns f and the side
    of each entry (+1 / -1 at its bound, 0 inside). With W = (M^-1)_RR and c = (M^-1 r)_R this is
    the friction of the joints at rest: q''_R = c - W f, zero where f is inside its bound, and of
    the sign of f where f is at it (maximal dissipation).
    """
    k = c.size
    f = np.zeros(k)
    side = np.zeros(k, dtype=int)
    for _ in range(4 * k + 8):
        free = side == 0
        target = f.copy()
        if free.any():
            rhs = c[free] - W[np.ix_(free, ~free)] @ f[~free]
            target[free] = np.linalg.solve(W[np.ix_(free, free)], rhs)
        d = target - f
        step, blocking = 1.0, -1
        for i in np.flatnonzero(free):
            if d[i] != 0.0:
                room = ((bound[i] if d[i] > 0 else -bound[i]) - f[i]) / d[i]
                if room < step:
                    step, blocking = room, int(i)
        f = f + step * d
        if blocking >= 0:
            side[blocking] = 1 if d[blocking] > 0 else -1
            f[blocking] = side[blocking] * bound[blocking]
            continue
        a = c - W @ f  # q''_R: a bound entry must move the way its friction opposes
        wrong = np.where(side != 0, -side * a, -np.inf)
        worst = int(np.argmax(wrong))
        if not wrong[worst] > 0.0:
            break
        side[worst] = 0
    return f, side


def settle(plant, t: float, q: np.ndarray, v: np.ndarray, tau: np.ndarray, mode: np.ndarray) -> np.ndarray:
    """Modes of the sticky joints at rest (q'_i = 0), from the set-valued law.

    The joints at rest R take the friction f_R that solves :func:`box_qp` with the static levels
    F_s: held (mode 0) where f_i is inside them, else sliding the way f_i points. Joints that
    break away slide on the Coulomb level F_c < F_s, so with stiction the choice is made again
    with F_c for them and the others held; a held joint that then needs more than F_s breaks
    away too.
    """
    mode = mode.copy()
    rest = np.flatnonzero(plant.sticky & (v == 0.0))
    if rest.size == 0:
        return mode
    mode[rest] = 0
    M = plant.model.mass(q)
    r = plant.net_torque(t, q, v, tau, mode) - plant.model.bias(q, v)
    W = np.linalg.inv(M)[np.ix_(rest, rest)]
    c = np.linalg.solve(M, r)[rest]
    static, coulomb = plant.friction.static[rest], plant.friction.coulomb[rest]
    f, side = box_qp(W, c, static)
    slides = side != 0
    while slides.any() and np.any(static[slides] > coulomb[slides]):
        f, side = box_qp(W, c, np.where(slides, coulomb, np.inf))
        broke = ~slides & (np.abs(f) > static)
        if not broke.any():
            break
        slides = slides | broke
    a = c - W @ f
    mode[rest] = np.where((side != 0) & (side * a > 0), side, 0)
    return mode


def _events(plant, t, q, v, tau, mode, slipping, held):
    """Event functions, each >= 0 while its mode holds: mode_i q'_i for the slipping joints,
    1 - |f_i| / F_s,i for the held ones.
    """
    slip = mode[slipping] * v[slipping]
    if held.size == 0:
        return slip
    hold = plant.constrained_acceleration(t, q, v, tau, mode)[1]
    return np.concatenate([slip, 1.0 - np.abs(hold) / plant.friction.static[held]])


def _locate(g: Callable[[float], float], lo: float, g_lo: float, hi: float, g_hi: float) -> float:
    """The smallest span in (lo, hi] found with g <= 0, to EVENT_TOLERANCE (Illinois method)."""
    side = 0
    for _ in range(MAX_LOCATE_ITERATIONS):
        if hi - lo <= EVENT_TOLERANCE or g_hi >= -1e-12:
            break
        s = hi - g_hi * (hi - lo) / (g_hi - g_lo)
        if not lo < s < hi:
            s = 0.5 * (lo + hi)
        gs = g(s)
        if gs <= 0.0:
            hi, g_hi = s, gs
            if side == -1:
                g_lo *= 0.5
            side = -1
        else:
            lo, g_lo = s, gs
            if side == 1:
                g_hi *= 0.5
            side = 1
    return hi


def _event_time(g: Callable[[float], float], g_start: float, span: float, g_end: float) -> float | None:
    """When in (0, span] an event function that ends at g_end <= 0 reaches zero.

    From g_start > 0 the root is located; from g_start < 0 the mode is already wrong (s = 0). A
    joint just released starts at g = 0 and moves the way its mode says: its event is the next
    zero, bracketed from the first of span / 2, span / 4, ... where g > 0; if there is none down
    to EVENT_TOLERANCE the joint barely moved and the event is left to the next step (None).
    """
    if g_start > 0:
        return _locate(g, 0.0, g_start, span, g_end)
    if g_start < 0:
        return 0.0
    s = 0.5 * span
    while s > EVENT_TOLERANCE:
        gs = g(s)
        if gs > 0:
            return _locate(g, s, gs, span, g_end)
        s *= 0.5
    return None


class StickSlipIntegrator:
    """Advances the plant over one control period with the torque held, events located.

    Attributes:
        mode: per joint, +1 / -1 slipping forward / backward, 0 held by static friction (only
            the sticky joints' entries are used).
        events: events located so far.
        unresolved: steps in which more than MAX_EVENTS events occurred (taken as they were).

    """

    def __init__(self, plant, v0: np.ndarray):
        self.plant = plant
        self.mode = np.where(np.asarray(v0) < 0, -1, 1).astype(int)
        self.mode[plant.sticky & (np.asarray(v0) == 0.0)] = 0
        self.events = 0
        self.unresolved = 0

    def advance(
        self,
        flow: Flow,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        tau: np.ndarray,
        h: float,
        new_command: bool = True,
    ) -> tuple[np.ndarray, np.ndarray]:
        """(q, v) at t + h from (q, v) at t under the torque tau, switching modes at events.

        ``new_command``: tau changed since the last call, so the joints at rest choose again
        (within a command, the events keep the modes consistent).
        """
        plant = self.plant
        sticky = plant.sticky
        if new_command and (sticky & (v == 0.0)).any():
            self.mode = settle(plant, t, q, v, tau, self.mode)
        end = t + h
        for _ in range(MAX_EVENTS + 1):
            mode = self.mode
            slipping = np.flatnonzero(sticky & (mode != 0))
            held = np.flatnonzero(sticky & (mode == 0))
            span = end - t
            q1, v1 = flow(t, q, v, mode, span)
            g_end = _events(plant, end, q1, v1, tau, mode, slipping, held)
            triggered = np.flatnonzero(g_end <= 0.0)
            if triggered.size == 0:
                return q1, v1
            g_start = _events(plant, t, q, v, tau, mode, slipping, held)
            first, which = span, -1
            for i in triggered:

                def g(s, i=i):
                    qs, vs = flow(t, q, v, mode, s)
                    return _events(plant, t + s, qs, vs, tau, mode, slipping, held)[i]

                s_i = _event_time(g, g_start[i], span, g_end[i])
                if s_i is not None and (s_i < first or which < 0):
                    first, which = s_i, int(i)
            if which < 0:  # only events the step cannot resolve: a joint that barely moves
                return q1, v1
            if first >= span:
                q, v = q1, v1
            elif first > 0.0:
                q, v = flow(t, q, v, mode, first)
            t = t + first
            if which < slipping.size:
                v = v.copy()
                v[slipping[which]] = 0.0
            self.events += 1
            self.mode = settle(plant, t, q, v, tau, mode)
            if which >= slipping.size:  # a held joint breaks away toward its holding torque
                joint = held[which - slipping.size]
                if self.mode[joint] == 0:
                    hold = plant.constrained_acceleration(t, q, v, tau, mode)[1]
                    self.mode[joint] = 1 if hold[which - slipping.size] > 0 else -1
            if first >= span:
                return q, v
        self.unresolved += 1
        return q, v
