"""Tuning every controller at equal budget (docs/tuning.md). Needs the ``tune`` extra:
``pip install 'nnrobust[tune]'`` (Optuna, with the sweep extra's Dask, pandas and pyarrow).
"""

from .engine import TuneSpec, run_tune
from .space import SearchSpace, arm_scales, search_space

__all__ = ["SearchSpace", "TuneSpec", "arm_scales", "run_tune", "search_space"]
