"""Performance criteria h(q) for self-motion, eq. (3)."""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ..model.base import DynamicsModel


class Criterion(ABC):
    """A performance criterion h(q) to be maximised by self-motion, with its gradient."""

    @abstractmethod
    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """h(q)."""

    @abstractmethod
    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """dh/dq, shape n."""


class WeightedCriteria(Criterion):
    """h = sum_i w_i h_i with the weights scaled so that sum_i w_i = C, eq. (4).

    Args:
        criteria: the h_i.
        weights: positive relative weights w_i (scaled to sum to C).
        C: the constant of eq. (4).

    """

    def __init__(self, criteria: list[Criterion], weights: list[float] | None = None, C: float = 1.0):
        weights = [1.0] * len(criteria) if weights is None else list(weights)
        if len(weights) != len(criteria):
            raise ValueError(f"subtasks: {len(criteria)} criteria but {len(weights)} weights")
        if any(w <= 0 for w in weights) or C <= 0:
            raise ValueError(f"subtasks: weights {weights} and C = {C} must be positive")
        total = sum(weights)
        self.criteria = list(criteria)
        self.weights = np.asarray(weights, dtype=float) * (C / total)
        self.C = C

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """sum_i w_i h_i(q)."""
        return float(sum(w * c.value(model, q) for w, c in zip(self.weights, self.criteria)))

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """sum_i w_i grad h_i(q)."""
        return sum(w * c.gradient(model, q) for w, c in zip(self.weights, self.criteria))
