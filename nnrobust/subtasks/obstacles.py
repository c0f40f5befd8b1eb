"""Clearance from spherical obstacles for the arm's links, modelled as capsules between joints."""

from __future__ import annotations

import numpy as np

from ..model.base import DynamicsModel
from .base import Criterion
from .registry import CriterionKind, declare


class SphereObstacles(Criterion):
    """h = -1/2 sum_{links s, obstacles o} max(0, d_0 - d_so)^2.

    d_so is the clearance between obstacle o (centre c_o, radius r_o) and link s, the segment
    between consecutive chain points (joint origins and the task frame) thickened by
    ``link_radius``: d = |c - p*| - r_o - link_radius with p* the closest point of the segment.
    Only pairs closer than the influence distance d_0 contribute, so h = 0 and grad h = 0 when the
    arm is clear, and h is continuously differentiable. The gradient is exact: with
    p* = (1 - t) a + t b, dd/dq = -n^T ((1 - t) J_a + t J_b), n = (c - p*) / |c - p*| (t moves
    only where dd/dt = 0).

    Args:
        centers: obstacle centres, K x 3 [m] (world).
        radii: obstacle radii, K [m].
        influence: d_0 [m].
        link_radius: thickness of every link [m].

    """

    def __init__(self, centers, radii, influence: float = 0.1, link_radius: float = 0.0):
        self.centers = np.atleast_2d(np.asarray(centers, dtype=float))
        self.radii = np.atleast_1d(np.asarray(radii, dtype=float))
        if self.centers.shape[1:] != (3,) or self.radii.shape != (self.centers.shape[0],):
            raise ValueError(
                f"obstacles: need K x 3 centres and K radii, got {self.centers.shape} and {self.radii.shape}"
            )
        if np.any(self.radii < 0) or influence <= 0 or link_radius < 0:
            raise ValueError("obstacles: radii and link_radius must be >= 0 and influence > 0")
        self.influence = float(influence)
        self.link_radius = float(link_radius)

    def _pairs(self, points: np.ndarray):
        """Closest points: t (S x K), direction n (S x K x 3), clearance d (S x K)."""
        a, b = points[:-1, None, :], points[1:, None, :]  # S x 1 x 3
        ab = b - a
        c = self.centers[None, :, :]
        length2 = np.maximum(np.sum(ab**2, axis=2), 1e-300)
        t = np.clip(np.sum((c - a) * ab, axis=2) / length2, 0.0, 1.0)
        closest = a + t[:, :, None] * ab
        gap = c - closest
        dist = np.maximum(np.linalg.norm(gap, axis=2), 1e-12)
        return t, gap / dist[:, :, None], dist - self.radii[None, :] - self.link_radius

    def clearance(self, model: DynamicsModel, q: np.ndarray) -> float:
        """Smallest link-obstacle clearance [m] (negative: penetration)."""
        return float(self._pairs(model.chain_points(q))[2].min())

    def value(self, model: DynamicsModel, q: np.ndarray) -> float:
        """h(q) <= 0."""
        depth = np.maximum(0.0, self.influence - self._pairs(model.chain_points(q))[2])
        return -0.5 * float(np.sum(depth**2))

    def gradient(self, model: DynamicsModel, q: np.ndarray) -> np.ndarray:
        """Sum (d_0 - d) dd/dq over the pairs within d_0."""
        t, normal, d = self._pairs(model.chain_points(q))
        depth = np.maximum(0.0, self.influence - d)  # S x K
        if not np.any(depth):
            return np.zeros(q.size)
        Js = model.chain_jacobians(q)  # (S + 1) x 3 x n
        # sum over pairs of depth * (-n^T ((1 - t) J_a + t J_b))
        wa = -(depth * (1 - t))[:, :, None] * normal  # S x K x 3
        wb = -(depth * t)[:, :, None] * normal
        return np.einsum("skx,sxn->n", wa, Js[:-1]) + np.einsum("skx,sxn->n", wb, Js[1:])


def _obstacles(sc, robot) -> SphereObstacles:
    spheres = np.asarray(sc.obstacles, dtype=float)
    return SphereObstacles(spheres[:, :3], spheres[:, 3], sc.obstacle_influence, sc.link_radius)


declare(
    CriterionKind(
        "obstacles",
        SphereObstacles,
        "-0.5 sum max(0, d0 - clearance)^2 over links and subtasks.obstacles",
        lambda m: "m$^2$",
        _obstacles,
        lambda c: {
            "centers": c.centers,
            "radii": c.radii,
            "influence": c.influence,
            "link_radius": c.link_radius,
        },
    ),
)
