"""The simulated robot: true model, friction and disturbance."""

from .disturbance import SinusoidalDisturbance
from .friction import Friction
from .plant import Plant

__all__ = ["Friction", "Plant", "SinusoidalDisturbance"]
