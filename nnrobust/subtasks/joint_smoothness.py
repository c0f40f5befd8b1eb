"""The paper's joint-smoothness term and its composition with manipulability, eq. (19)."""

from __future__ import annotations

import numpy as np

from ..core.exceptions import ConfigError
from ..model.base import DynamicsModel
from .base import Criterion
from .manipulability import HalfDetManipulability
from .registry import CriterionKind, declare

PAPER_SMOOTHNESS = (0.5, -1.0, 1.0)
"""(q3 - 0.5 q2) - 0.5 (q2 - q1) = 0.5 q1 - q2 + q3: the coefficients c of eq. (19)."""


class JointSmoothness(Criterion):
    """h = -0.5 (c^T q)^2: penalises a linear combination of joint angles.

    With c = (0.5, -1, 1) this is the second term of eq. (19); the maximum is on c^T q = 0.
    """

    def __init__(self, coefficients: tuple[float, ...] = PAPER_SMOOTHNESS):
        self.c = np.asarray(coefficients, dtype=float)

    def _check(self, q: np.ndarray) -> None:
        if q.size != self.c.size:
            raise ValueError(
                f"joint smoothness has {self.c.size} coefficients, the robot has {q.size} joints"
            )

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """-0.5 (c^T q)^2."""
        self._check(q)
        return -0.5 * float(self.c @ q) ** 2

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """-(c^T q) c."""
        self._check(q)
        return -float(self.c @ q) * self.c


class PaperCriterion(Criterion):
    """h(q) = 0.5 det(J J^T) - 0.5 ((q3 - 0.5 q2) - 0.5 (q2 - q1))^2, eq. (19)."""

    def __init__(self):
        self._terms = (HalfDetManipulability(), JointSmoothness(PAPER_SMOOTHNESS))

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """h(q) of eq. (19)."""
        return sum(term.value(model, q) for term in self._terms)

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """Grad h(q) of eq. (19), analytic."""
        return sum(term.gradient(model, q) for term in self._terms)


def _paper(sc, robot) -> PaperCriterion:
    if robot.nq != 3:
        raise ConfigError(
            "subtasks.criteria",
            f"'paper' (eq. 19) is for 3 joints, the robot has {robot.nq}; use e.g. 'manipulability' "
            "and 'joint_centering'",
        )
    return PaperCriterion()


def _smoothness(sc, robot) -> JointSmoothness:
    c = sc.smoothness_coefficients or list(PAPER_SMOOTHNESS)
    if len(c) != robot.nq:
        raise ConfigError(
            "subtasks.smoothness_coefficients", f"has {len(c)} entries, the robot has {robot.nq} joints"
        )
    return JointSmoothness(tuple(float(x) for x in c))


declare(
    CriterionKind(
        "paper",
        PaperCriterion,
        "eq. (19): 0.5 det(J J^T) - 0.5 (0.5 q1 - q2 + q3)^2 (three joints)",
        lambda m: "m$^4$ + rad$^2$",
        _paper,
        lambda criterion: {"coefficients": PAPER_SMOOTHNESS},
        det=True,
    ),
    CriterionKind(
        "joint_smoothness",
        JointSmoothness,
        "-0.5 (c^T q)^2 with c = subtasks.smoothness_coefficients",
        lambda m: "rad$^2$",
        _smoothness,
        lambda criterion: {"coefficients": criterion.c},
    ),
)
