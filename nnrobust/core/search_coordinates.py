"""A search coordinate: what a kind declares for the tuner (``nnrobust tune``) about one of its
keys, and the ranges the laws share. A leaf module: the laws and the robust terms declare their
coordinates here without importing the tuner (nnrobust/studies/tune/space.py searches them).
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass


@dataclass(frozen=True)
class Param:
    """One search coordinate: log-uniform on [low, high].

    Attributes:
        name: the coordinate's name (``bandwidth``, ``damping_ratio`` or a dotted config key).
        low, high: its bounds.
        unit: its unit.
        low_reason, high_reason: why a bound is physical (never widened), or "".
        weak: for a robust term's knob, the end (``low`` or ``high``) at which the term does least;
            "" for the gains.
        range_low, range_high: the values the law accepts (a registered law's declared range):
            a bound is never widened past them, and one on them is physical.

    """

    name: str
    low: float
    high: float
    unit: str
    low_reason: str = ""
    high_reason: str = ""
    weak: str = ""
    range_low: float = 0.0
    range_high: float = math.inf

    def reason(self, side: str) -> str:
        """Why the bound on ``side`` is physical (never widened), or ""."""
        if side == "low":
            end = self.low <= self.range_low
            return self.low_reason or (f"the law's range ends at {self.low:g}" if end else "")
        end = self.high >= self.range_high
        return self.high_reason or (f"the law's range ends at {self.high:g}" if end else "")

    def position(self, value: float) -> float:
        """Where value sits in [low, high], 0 to 1 on the log scale."""
        return (math.log(value) - math.log(self.low)) / (math.log(self.high) - math.log(self.low))


def bandwidth_range(scales: dict) -> tuple[float, float]:
    """A loop bandwidth's search range [rad/s]: from one oscillation per run to the sampling limit
    w (1/2 + d) T = 1 (period T, delay d periods).
    """
    return 2 * math.pi / scales["duration"], 1.0 / ((0.5 + scales["delay"]) * scales["period"])


def controller_seed(name: str) -> int:
    """The part of a controller's search seeds that is its own: from its name (a stable hash), so
    its tuning and its falsification are the same in any run that holds it, whatever the other
    controllers and their order.
    """
    return zlib.crc32(name.encode())
