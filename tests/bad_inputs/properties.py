"""Bad inputs: --require properties."""

from __future__ import annotations

from nnrobust.core import exceptions as ex

from .common import (
    Case,
)
from .scheduler import (
    _claim,
    _require,
)

PROPERTY_CASES = [
    Case(
        "--require: a property of the machine, not the run",
        lambda d: _require("wall_seconds<=0.01"),
        ex.ConfigError,
        "wall_seconds measures the machine and its load, not the controller",
    ),
    Case(
        "--require: not an expression",
        lambda d: _require("rms_error < 0.05 mm"),
        ex.ConfigError,
        "is not METRIC OP VALUE with OP one of <= >= == != < >",
    ),
    Case(
        "--require: an unknown metric",
        lambda d: _require("rms_eror_after_2s<=0.05"),
        ex.ConfigError,
        "no metric 'rms_eror_after_2s'; did you mean 'rms_error_after_2s'?",
    ),
    Case(
        "--require: a NaN bound",
        lambda d: _require("rms_error<=nan"),
        ex.ConfigError,
        "the bound must be a finite number, got nan",
    ),
    Case(
        "--require: a flag compared by size",
        lambda d: _require("runaway<=1"),
        ex.ConfigError,
        "runaway is true or false: compare it with == or != to true or false",
    ),
    Case(
        "--epsilon of 0",
        lambda d: _claim(0.0, 0.05),
        ex.ConfigError,
        "--epsilon: must be a probability in (0, 1)",
    ),
    Case(
        "--beta of 1", lambda d: _claim(0.05, 1.0), ex.ConfigError, "--beta: must be a probability in (0, 1)"
    ),
    Case(
        "--failures of 10^9",
        lambda d: _claim(0.05, 0.05, 10**9),
        ex.ConfigError,
        "--failures: must be an integer in [0, 10000]",
    ),
    Case(
        "--epsilon of 1e-300",
        lambda d: _claim(1e-300, 0.05),
        ex.ConfigError,
        "--epsilon: P(fail) <= 1e-300 with confidence 0.95 needs more than 1,000,000 samples",
    ),
    Case(
        "--epsilon 1e-6 with --failures 10000",
        lambda d: _claim(1e-6, 0.05, 10_000),
        ex.ConfigError,
        "give --epsilon >= 0.0102 or fewer --failures",
    ),
    Case(
        "--epsilon of 0.9999999",
        lambda d: _claim(0.9999999, 0.05),
        ex.ConfigError,
        "--epsilon: P(fail) <= 0.9999999 says next to nothing",
    ),
    Case(
        "--beta of 1e-300",
        lambda d: _claim(0.05, 1e-300),
        ex.ConfigError,
        "--beta: 1e-300 asks a confidence closer to 1 than double precision can bound",
    ),
]
