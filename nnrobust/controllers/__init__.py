"""Controllers: the task-space law of eq. (9), the NN compensator, sliding mode and baselines."""

from .base import Controller, ControllerContext, ControlOutput
from .basis import AdditiveRBFBasis
from .nn_compensator import NNCompensator, error_dynamics, lyapunov_P, lyapunov_Q
from .pseudoinverse import DampedPseudoInverse, project_null_space
from .sliding_mode import SlidingModeCompensator
from .task_space import TaskSpaceController, TaskSpacePD

__all__ = [
    "AdditiveRBFBasis",
    "ControlOutput",
    "Controller",
    "ControllerContext",
    "DampedPseudoInverse",
    "NNCompensator",
    "SlidingModeCompensator",
    "TaskSpaceController",
    "TaskSpacePD",
    "error_dynamics",
    "lyapunov_P",
    "lyapunov_Q",
    "project_null_space",
]
