"""What a learned controller sees: the observation layout (docs/learning.md), versioned.

The observation holds only what a real controller may know, at the control instant t_k:

====== ============== ======================================================================
name   entries        what
====== ============== ======================================================================
q      n              the measured joint positions q_m (the sensor's noise and quantisation)
dq     n              the measured joint velocities q'_m
p_d    min(m, 3)      the desired task position x_d's position part [m]
e      m              the task error e = x(q_m) - x_d on the nominal model (a rotation error
                      for a pose task, as ``trajectory.error``)
de     m              e' = J(q_m) q'_m - x_d'
dx_d   m              x_d'
ddx_d  m              x_d''
====== ============== ======================================================================

x(q_m) and J(q_m) are the nominal model's (the controller's), never the true plant's. The
compiled loop computes the same vector (``SteppedLoop::observe``, csrc/closed_loop.cpp); this
module is its Python reference, and tests/studies/learning/test_env.py holds the two equal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

OBSERVATION_VERSION = 1
"""The layout's version: a policy trained on one layout is refused on another."""


@dataclass(frozen=True)
class ObservationLayout:
    """The observation's fields for an arm of ``n`` joints and a task of ``m`` coordinates."""

    n: int
    m: int

    @property
    def fields(self) -> tuple[tuple[str, int], ...]:
        """(name, entries) of each field, in order."""
        n, m = self.n, self.m
        return (("q", n), ("dq", n), ("p_d", min(m, 3)), ("e", m), ("de", m), ("dx_d", m), ("ddx_d", m))

    @property
    def size(self) -> int:
        """Entries in all: 2 n + min(m, 3) + 4 m."""
        return sum(size for _, size in self.fields)

    def slices(self) -> dict[str, slice]:
        """Each field's slice of the observation vector."""
        out, start = {}, 0
        for name, size in self.fields:
            out[name] = slice(start, start + size)
            start += size
        return out

    def describe(self) -> dict:
        """The layout as JSON (recorded beside a policy file, compared when it is loaded)."""
        return {
            "version": OBSERVATION_VERSION,
            "n": self.n,
            "m": self.m,
            "fields": [list(f) for f in self.fields],
        }


def observation(nominal, trajectory, t: float, q_m: np.ndarray, v_m: np.ndarray) -> np.ndarray:
    """The observation at ``t`` from the measured ``(q_m, v_m)``: the Python reference of the
    compiled loop's ``SteppedLoop::observe`` (same formulas, in the same order).
    """
    x, J, _ = nominal.task_state(q_m, v_m)
    x_d, dx_d, ddx_d = trajectory(t)
    e = trajectory.error(x, x_d)
    de = J @ v_m - dx_d
    p = min(e.size, 3)
    return np.concatenate([q_m, v_m, x[:p] - e[:p], e, de, dx_d, ddx_d])
