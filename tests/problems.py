"""Shared factories for the tests: the paper's arm, its closed form, seeded random states."""

from __future__ import annotations

import numpy as np

from nnrobust import load_robot
from nnrobust.model import ThreeLinkParameters, ThreeLinkPlanarModel

VERTICAL_GRAVITY = (0.0, -9.81, 0.0)


def paper_robot(gravity=None):
    """The paper's arm from urdf/ (Pinocchio)."""
    return load_robot("three_link_planar", gravity=gravity)


def closed_form_of(robot) -> ThreeLinkPlanarModel:
    """Closed-form model with the beta, p (and gravity) computed from the URDF's inertial data."""
    return ThreeLinkPlanarModel(ThreeLinkParameters.from_pinocchio(robot.model, robot.task_frame))


def random_states(n: int, count: int, seed: int = 0, speed: float = 3.0):
    """``count`` seeded (q, q', q'') triples with angles in [-pi, pi]."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield (rng.uniform(-np.pi, np.pi, n), rng.uniform(-speed, speed, n), rng.uniform(-speed, speed, n))


def finite_difference(f, q: np.ndarray, direction: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Central difference of f at q along direction."""
    return (f(q + h * direction) - f(q - h * direction)) / (2 * h)


class ConstantTorque:
    """A stateless controller holding a constant torque (zero by default), for plant tests."""

    state_size = 0
    signal_names = ()

    def __init__(self, tau):
        self.tau = np.asarray(tau, dtype=float)

    def initial_state(self):
        return np.zeros(0)

    def compute(self, t, q, v, z, period=0.0):
        from nnrobust.controllers import ControlOutput

        return ControlOutput(self.tau.copy(), {})
