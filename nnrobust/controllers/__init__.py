"""Controllers: the task-space law of eq. (9), the NN compensator, sliding mode and baselines."""

from importlib import import_module as _import_module

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

# the registered laws (nnrobust/controllers/laws/), after the paper's kinds: declaration order is
# the order kinds are listed in (nnrobust.core.kinds)
_import_module(f"{__name__}.laws")
