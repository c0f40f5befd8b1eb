"""Desired task trajectories x_d(t) with analytic derivatives: one module per shipped path, each
declared beside its class (:data:`PATH_KINDS`), and the pose trajectory over any of them.
"""

from ..core.kinds import import_modules as _import_modules
from .base import Trajectory
from .ellipse import EllipseTrajectory
from .piecewise import PiecewisePolynomialPath, quintic_point_to_point, spline_through
from .pose import PoseTrajectory, PositionPath
from .registry import PATH_KINDS, PathKind, path_key

_import_modules(__name__, __path__)  # every module declares its paths at import (nnrobust.core.kinds)

__all__ = [
    "PATH_KINDS",
    "EllipseTrajectory",
    "PathKind",
    "PiecewisePolynomialPath",
    "PoseTrajectory",
    "PositionPath",
    "Trajectory",
    "path_key",
    "quintic_point_to_point",
    "spline_through",
]
