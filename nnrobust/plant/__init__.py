"""The simulated robot: true model, friction, disturbance, actuator limits, stops and sensors."""

from .disturbance import Disturbance, SinusoidalDisturbance
from .friction import Friction
from .limits import JointStops, saturate
from .plant import Plant
from .scaling import scaled_disturbance, scaled_friction, torque_scale
from .sensing import Sensor

__all__ = [
    "Friction",
    "JointStops",
    "Plant",
    "Sensor",
    "Disturbance",
    "SinusoidalDisturbance",
    "saturate",
    "scaled_disturbance",
    "scaled_friction",
    "torque_scale",
]
