"""Shipped parts written again against the public contracts, as a user would (tests/plugins/test_checked.py):
each must give the run its built-in twin gives."""

import math

import numpy as np

import nnrobust


class Ellipse(nnrobust.Trajectory):
    """Eq. (18): x_d = c + a cos(w t) + b sin(w t)."""

    def __init__(self, robot, center, a, b, omega=1.0):
        self.c, self.a, self.b, self.w = (np.asarray(v, float) for v in (center, a, b, omega))
        self.m = self.c.size

    def __call__(self, t):
        c, s = math.cos(self.w * t), math.sin(self.w * t)
        x = self.c + self.a * c + self.b * s
        dx = self.w * (-self.a * s + self.b * c)
        ddx = -(self.w**2) * (self.a * c + self.b * s)
        return x, dx, ddx


class PaperDisturbance(nnrobust.Disturbance):
    """tau_d = [4 cos 2t, sin t + cos 2t, 2 sin t] N m (Sect. 4), times ``gain``."""

    def __init__(self, robot, gain=1.0):
        assert robot.nq == 3
        self.gain = gain

    def __call__(self, t):
        return self.gain * np.array([4 * math.cos(2 * t), math.sin(t) + math.cos(2 * t), 2 * math.sin(t)])


class Centering(nnrobust.Criterion):
    """h = -1/(2n) sum ((q_i - mid_i) / (max_i - min_i))^2, the joint-centering criterion."""

    def __init__(self, robot):
        self.lower, self.upper = np.asarray(robot.lower_limits), np.asarray(robot.upper_limits)

    def value(self, model, q):
        d = (np.asarray(q) - (self.lower + self.upper) / 2) / (self.upper - self.lower)
        return -float(d @ d) / (2 * q.size)

    def gradient(self, model, q):
        span = self.upper - self.lower
        return -((np.asarray(q) - (self.lower + self.upper) / 2) / span**2) / q.size


class WrongSize(nnrobust.Disturbance):
    """Two torques for any arm."""

    def __init__(self, robot):
        pass

    def __call__(self, t):
        return np.zeros(2)


class NotATrajectory:
    """Has no business in trajectory.class."""


class Locked(Ellipse):
    """The ellipse, holding a lock: it cannot be copied for the controller."""

    def __init__(self, robot, center, a, b, omega=1.0):
        import threading

        super().__init__(robot, center, a, b, omega)
        self.lock = threading.Lock()


class LateNaNEllipse(Ellipse):
    """The ellipse, whose x_d'' turns NaN after t = 0.05 s."""

    def __call__(self, t):
        x, dx, ddx = super().__call__(t)
        return x, dx, ddx * (math.nan if t > 0.05 else 1.0)


class LateNaNDisturbance(PaperDisturbance):
    """The paper's tau_d, NaN on the second joint after t = 0.05 s."""

    def __call__(self, t):
        tau = super().__call__(t)
        if t > 0.05:
            tau[1] = math.nan
        return tau


class LateNaNCentering(Centering):
    """Joint centering whose gradient turns NaN from its 20th call on."""

    calls = 0

    def gradient(self, model, q):
        self.calls += 1
        return super().gradient(model, q) * (math.nan if self.calls >= 20 else 1.0)
