"""Eq. (9) with u_0 = 0, written from docs/extending.md alone (numpy and the context, no nnrobust
internals): the built-in no-u0 law must be reproduced by it. Also the broken controllers that
the contract's checks must refuse, one class each.
"""

import numpy as np

from nnrobust import Controller, ControlOutput


class Eq9(Controller):
    """a = J+ (x_d'' - J'q' - Kv e' - Kp e) + k (I - J+J)(grad h - q'); tau = M-hat a + N-hat."""

    signal_names = ("pinv_damping_free",)
    search_space = {"Kp": (1.0, 1e5, "1/s^2"), "Kv": (1.0, 1e3, "1/s")}  # what nnrobust tune searches

    def __init__(self, context, Kp, Kv):
        self.ctx = context
        self.Kp = np.diag(np.broadcast_to(np.asarray(Kp, float), (context.m,)))
        self.Kv = np.diag(np.broadcast_to(np.asarray(Kv, float), (context.m,)))

    def compute(self, t, q, v, z, period=0.0):
        ctx = self.ctx
        x, J, jdot_v = ctx.nominal.task_state(q, v)
        xd, dxd, ddxd = ctx.trajectory(t)
        e, de = ctx.trajectory.error(x, xd), J @ v - dxd
        J_pinv = ctx.pseudo_inverse.matrix(J)
        a = J_pinv @ (ddxd - jdot_v - self.Kv @ de - self.Kp @ e)
        grad = ctx.criterion.gradient(ctx.nominal, q) if ctx.criterion is not None else 0.0
        a += ctx.null_space_gain * (np.eye(ctx.n) - J_pinv @ J) @ (grad - v)
        tau = ctx.nominal.inverse_dynamics(q, v, a) + ctx.nominal_friction.torque(v)
        return ControlOutput(tau, {"pinv_damping_free": 1.0})


class Counter(Controller):
    """A stateful law: z counts control periods in seconds; tau = 0."""

    state_size = 1
    signal_names = ("elapsed",)

    def __init__(self, context):
        self.n = context.n

    def compute(self, t, q, v, z, period=0.0):
        return ControlOutput(np.zeros(self.n), {"elapsed": float(z[0])}, z + period)


class Undeclared(Counter):
    def compute(self, t, q, v, z, period=0.0):
        return ControlOutput(np.zeros(self.n), {"elapsed": 0.0, "surprise": 1.0}, z)


class WrongShape(Counter):
    def compute(self, t, q, v, z, period=0.0):
        return ControlOutput(np.zeros(self.n + 1), {}, z)


class Raises(Counter):
    def compute(self, t, q, v, z, period=0.0):
        if t > 0.01:
            return ControlOutput(np.zeros(self.n), {}, [][0])
        return ControlOutput(np.zeros(self.n), {}, z)


class Exits(Counter):
    def compute(self, t, q, v, z, period=0.0):
        if t > 0.01:
            raise SystemExit(0)
        return ControlOutput(np.zeros(self.n), {}, z)


class NeedsGain(Controller):
    def __init__(self, context, gain, *, limit=1.0):
        if gain < 0:
            raise ValueError(f"gain must be >= 0, got {gain}")
        self.n = context.n

    def compute(self, t, q, v, z, period=0.0):
        return ControlOutput(np.zeros(self.n))


class Abstract(Controller):
    pass


class NotAController:
    pass


class AdaptsItsModel(Counter):
    """An adaptive law's natural move: it scales its nominal model's inertias in place (tau = 0)."""

    def __init__(self, context):
        super().__init__(context)
        self.model = context.nominal.pinocchio_model

    def compute(self, t, q, v, z, period=0.0):
        if t == 0.0:
            for j in range(1, self.model.njoints):
                body = self.model.inertias[j]
                self.model.inertias[j] = type(body)(3.0 * body.mass, body.lever, 3.0 * body.inertia)
        return super().compute(t, q, v, z, period)


def _shift_arrays(part, by, seen):
    """Add ``by`` to every float array inside ``part`` (its attributes, lists and tuples), in place."""
    if id(part) in seen:
        return
    seen.add(id(part))
    if isinstance(part, np.ndarray) and part.dtype == float:
        part += by
    elif isinstance(part, (list, tuple)):
        for item in part:
            _shift_arrays(item, by, seen)
    elif hasattr(part, "__dict__"):
        for item in vars(part).values():
            _shift_arrays(item, by, seen)


class MovesTheReference(Counter):
    """Writes into every array of its trajectory and criterion (tau = 0)."""

    def __init__(self, context):
        super().__init__(context)
        self.parts = (context.trajectory, context.criterion)

    def compute(self, t, q, v, z, period=0.0):
        if t == 0.0:
            _shift_arrays(self.parts, 0.2, set())
        return super().compute(t, q, v, z, period)


class EndsItsProcess(Controller):
    """tau = 0 until t > ``after`` s, then ``os._exit`` (a law that ends its process: a segfault in
    a C extension does the same to a dask worker)."""

    search_space = {"after": (0.1, 100.0, "s")}

    def __init__(self, context, after=0.3):
        self.n, self.after = context.n, after

    def compute(self, t, q, v, z, period=0.0):
        if t > self.after:
            import os

            os._exit(3)
        return ControlOutput(np.zeros(self.n))


class RaisesBaseException(EndsItsProcess):
    def compute(self, t, q, v, z, period=0.0):
        if t > self.after:
            raise BaseException("not an Exception")
        return ControlOutput(np.zeros(self.n))


class LateBreach(Counter):
    """A stateful law whose output breaks the contract after t = 0.05 s in the way ``breach``
    names (``"ints"`` and ``"strided"`` are valid outputs: a list of ints, a strided view)."""

    def __init__(self, context, breach):
        super().__init__(context)
        self.breach = breach

    def compute(self, t, q, v, z, period=0.0):
        out = super().compute(t, q, v, z, period)
        if t <= 0.05:
            return out
        n, breach = self.n, self.breach
        if breach == "ints":
            return ControlOutput([0] * n, out.signals, out.state)
        if breach == "strided":
            return ControlOutput(np.zeros(2 * n)[::2], out.signals, out.state)
        if breach == "scalar":
            return ControlOutput(0.0, out.signals, out.state)
        if breach == "size":
            return ControlOutput(np.zeros(n - 1), out.signals, out.state)
        if breach == "tuple":
            return (out.tau, out.signals, out.state)
        if breach == "words":
            return ControlOutput(["a"] * n, out.signals, out.state)
        if breach == "signal":
            return ControlOutput(out.tau, {"elapsed": "soon"}, out.state)
        if breach == "nan":
            return ControlOutput(np.full(n, np.nan), out.signals, out.state)
        if breach == "state":
            return ControlOutput(out.tau, out.signals, np.zeros(3))
        raise ValueError(breach)


class BigState(Counter):
    """A state of 200 000 entries: 20 s of it at 1 ms is 96 GB of record."""

    state_size = 200_000


class HugeState(Counter):
    """A state no run could hold (8 GB a vector)."""

    state_size = 10**9


class RaisesLate(Controller):
    """tau = 0 until t = 1 s, then an exception: every run fails, after its first step passed."""

    search_space = {"gain": (0.1, 10.0, "1")}

    def __init__(self, context, gain=1.0):
        self.n = context.n

    def compute(self, t, q, v, z, period=0.0):
        if t > 1.0:
            raise RuntimeError("boom after 1 s")
        return ControlOutput(np.zeros(self.n))


class NamesH(Counter):
    """Declares a signal named like one every run records (h)."""

    signal_names = ("elapsed", "h")


class NamesAPath(Counter):
    """Declares a signal whose name is a path."""

    signal_names = ("elapsed", "../../../evil")
