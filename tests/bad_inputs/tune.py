"""Bad inputs: tuning: its options, its folder, its target."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from nnrobust.core import exceptions as ex

from .common import (
    Case,
    _file,
)


def _tune(folder: Path, *args: str, **kwargs):
    """nnrobust tune's checks, as the command line calls them (nothing runs: each is refused first)."""

    def run():
        from nnrobust.studies.tune import TuneSpec, run_tune

        return run_tune(TuneSpec(*args, **kwargs), folder / "tuning", workers=1)

    return run


def _tune_into(folder: Path, make) -> Callable[[], object]:
    """A tuning into a folder ``make`` prepares."""

    def run():
        from nnrobust.studies.tune import TuneSpec, run_tune

        return run_tune(TuneSpec("paper-ellipse", ["pd"], 4), make(folder), workers=1)

    return run


def _grid_sweep(folder: Path) -> str:
    return str(
        _file(
            folder,
            "grid.toml",
            'name = "g"\nbase = "paper-ellipse"\ncontrollers = ["pd"]\n'
            '[vary]\n"plant.friction_scale" = [0.5, 2.0]\n',
        )
    )


def _user_folder_for_tune(folder: Path) -> Path:
    (folder / "my-study").mkdir(exist_ok=True)
    (folder / "my-study" / "notes.md").write_text("mine")
    return folder / "my-study"


TUNE_CASES = [
    Case(
        "tune: a budget of 0",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 0),
        ex.ConfigError,
        "--budget: must be an integer in [2, 100000]",
    ),
    Case(
        "tune: a budget of 10^9",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 10**9),
        ex.ConfigError,
        "--budget: must be an integer in [2, 100000]",
    ),
    Case(
        "tune: an unknown controller",
        lambda d: _tune(d, "paper-ellipse", ["lqr"], 10),
        ex.ConfigError,
        "--controllers: 'lqr' is not one of nn, sliding-mode, no-u0, computed-torque, pd, ",
    ),
    Case(
        "tune: a class without a search space",
        lambda d: _tune(d, "paper-ellipse", [f"{LAWS}:Counter"], 10),
        ex.ConfigError,
        "--controllers Counter: Counter declares no search space",
    ),
    Case(
        "tune: a controller named twice",
        lambda d: _tune(d, "paper-ellipse", ["pd", "pd"], 10),
        ex.ConfigError,
        "--controllers: needs distinct names",
    ),
    Case(
        "tune: a NaN torque limit",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 10, max_rms_torque=float("nan")),
        ex.ConfigError,
        "--max-rms-torque: must be > 0 [N m]",
    ),
    Case(
        "tune: a saturated fraction above 1",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 10, max_saturated=2.0),
        ex.ConfigError,
        "--max-saturated: must be in [0, 1]",
    ),
    Case(
        "tune: fewer simulations than training samples",
        lambda d: _tune(d, "paper-ellipse", ["pd"], 3, train_samples=4),
        ex.ConfigError,
        "--budget: 3 simulations cannot run one setting on 4 training samples",
    ),
    Case(
        "tune: a sweep file with a grid",
        lambda d: _tune(d, _grid_sweep(d), ["pd"], 10),
        ex.ConfigError,
        "tuning draws its samples from [vary] distributions",
    ),
    Case(
        "tune: --out a folder of the user's",
        lambda d: _tune_into(d, _user_folder_for_tune),
        ex.NNRobustError,
        "my-study exists and is not a tuning folder (no .nnrobust-tune); choose another --out",
    ),
    Case(
        "tune (sweep, falsify): --out inside a file",
        lambda d: _tune_into(d, lambda f: _file(f, "plain-file", "x") / "study"),
        ex.NNRobustError,
        "plain-file is a file, not a folder; choose another --out",
    ),
]

LAWS = Path(__file__).parents[1] / "controllers" / "eq9_again.py"
