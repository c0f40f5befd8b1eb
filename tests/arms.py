"""Arms used across the tests, loaded once per session (example-robot-data parsing takes ~0.5 s)."""

from __future__ import annotations

from functools import cache

import numpy as np

from nnrobust import load_robot

ARM_CASES = [
    ("panda", "position"),
    ("panda", "pose"),
    ("ur5", "position"),
    ("planar7", "planar"),
    ("planar7", "position"),
    ("three_link_planar", "planar"),
]
"""(robot, task kind) pairs for the kinematic and null-space tests."""


@cache
def arm(name: str, task: str):
    """A loaded arm (cached: tests must not change it)."""
    return load_robot(name, task=task)


def random_configurations(robot, count: int, seed: int = 0) -> list[np.ndarray]:
    """Seeded configurations inside the joint limits (clipped to +-pi)."""
    rng = np.random.default_rng(seed)
    low, high = robot.working_range
    return [rng.uniform(low, high) for _ in range(count)]
