"""Dynamics models: the interface, the Pinocchio-backed model and the closed-form 3-link model."""

from .base import DynamicsModel
from .loading import ARMS, PAPER_ARM, default_task_frame, load_robot, paper_arm_urdf
from .pinocchio_model import PinocchioModel
from .planar_chain import planar_chain_urdf
from .tasks import TASK_KINDS
from .three_link import ThreeLinkParameters, ThreeLinkPlanarModel

__all__ = [
    "ARMS",
    "DynamicsModel",
    "PAPER_ARM",
    "PinocchioModel",
    "TASK_KINDS",
    "ThreeLinkParameters",
    "ThreeLinkPlanarModel",
    "default_task_frame",
    "load_robot",
    "paper_arm_urdf",
    "planar_chain_urdf",
]
