"""Robustness sweeps: one experiment over many samples of the uncertainty set, on dask.distributed
(docs/robustness.md). Needs the ``sweep`` extra: ``pip install 'nnrobust[sweep]'``.
"""

from ..base.plan import SweepSpec, draw, load_sweep, parse_sweep, rerun_command
from .engine import read_results, run_sweep

__all__ = ["SweepSpec", "draw", "load_sweep", "parse_sweep", "read_results", "rerun_command", "run_sweep"]
