"""One figure drawn at a time in this process: pyplot's figure registry and matplotlib's text
parser are not thread-safe, and a study's stages run on threads side by side
(:func:`nnrobust.studies.study.engine.side_by_side`), each drawing its own figures (a tuning's Pareto
fronts, a falsification's convergence).
"""

from __future__ import annotations

import functools
import threading

LOCK = threading.RLock()


def drawn_alone(function):
    """``function`` (one that draws with matplotlib) run while no other thread draws."""

    @functools.wraps(function)
    def alone(*args, **kwargs):
        with LOCK:
            return function(*args, **kwargs)

    return alone
