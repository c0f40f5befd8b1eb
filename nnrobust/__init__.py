"""nnrobust: robust neural-network control of redundant manipulators, built on Pinocchio."""

from .exceptions import NNRobustError
from .model import (
    DynamicsModel,
    PinocchioModel,
    ThreeLinkParameters,
    ThreeLinkPlanarModel,
    load_robot,
    paper_arm_urdf,
)

__version__ = "0.1.0"

__all__ = [
    "DynamicsModel",
    "NNRobustError",
    "PinocchioModel",
    "ThreeLinkParameters",
    "ThreeLinkPlanarModel",
    "load_robot",
    "paper_arm_urdf",
]
