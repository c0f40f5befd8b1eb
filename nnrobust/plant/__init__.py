"""The simulated robot: true model, friction and disturbance."""

from .disturbance import SinusoidalDisturbance
from .friction import Friction
from .plant import Plant
from .scaling import scaled_disturbance, scaled_friction, torque_scale

__all__ = ["Friction", "Plant", "SinusoidalDisturbance", "scaled_disturbance", "scaled_friction",
           "torque_scale"]
