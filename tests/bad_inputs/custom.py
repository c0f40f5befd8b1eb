"""Bad inputs: a user's controller class."""

from __future__ import annotations

from pathlib import Path

from nnrobust.core import exceptions as ex

from .common import (
    Case,
    ReadConfig,
    _toml,
)
from .tune import (
    LAWS,
)


def _custom(folder: Path, cls: str, params: str = "", duration: float = 0.1) -> ReadConfig:
    """An experiment file with a custom controller from a copy of tests/controllers/eq9_again.py."""
    (folder / "laws.py").write_text(LAWS.read_text())
    return _toml(
        folder,
        f'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "laws.py:{cls}"\n'
        f"{params}\n[simulation]\nduration = {duration}\n",
    )


class RunExperiment(ReadConfig):
    """Read an experiment file and run it."""

    def __call__(self):
        from nnrobust.run.experiment import run_experiment

        return run_experiment(super().__call__())


def _custom_run(folder: Path, cls: str, params: str = "", duration: float = 0.1) -> RunExperiment:
    return RunExperiment(_custom(folder, cls, params, duration).path)


def _late(breach: str) -> str:
    return f'[controller.params]\nbreach = "{breach}"'


CUSTOM_CASES = [
    Case(
        "custom: no class",
        lambda d: _toml(d, 'base = "paper-ellipse"\n[controller]\nkind = "custom"\n'),
        ex.ConfigError,
        "controller.class: kind = 'custom' needs the class",
    ),
    Case(
        "custom: class with a built-in kind",
        lambda d: _toml(d, 'base = "paper-ellipse"\n[controller]\nclass = "laws.py:Eq9"\n'),
        ex.ConfigError,
        "controller.class: is read only with kind = 'custom' (kind is 'nn')",
    ),
    Case(
        "custom: a file that is not there",
        lambda d: RunExperiment(
            _toml(d, 'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "nope.py:Eq9"\n').path
        ),
        ex.ConfigError,
        "nope.py' is not a file",
    ),
    Case(
        "custom: a class not in the file",
        lambda d: _custom_run(d, "Eq"),
        ex.ConfigError,
        "has no 'Eq'; did you mean 'Eq9'?",
    ),
    Case(
        "custom: not a Controller",
        lambda d: _custom_run(d, "NotAController"),
        ex.ConfigError,
        "is not a subclass of nnrobust.Controller",
    ),
    Case(
        "custom: compute not implemented",
        lambda d: _custom_run(d, "Abstract"),
        ex.ConfigError,
        "does not implement compute",
    ),
    Case(
        "custom: an unknown parameter",
        lambda d: _custom_run(d, "Eq9", "[controller.params]\nKp = 1.0\nKvv = 2.0"),
        ex.ConfigError,
        "controller.params.Kvv: Eq9 takes no such parameter; did you mean 'Kv'?",
    ),
    Case(
        "custom: a missing parameter",
        lambda d: _custom_run(d, "Eq9", "[controller.params]\nKp = 1.0"),
        ex.ConfigError,
        "controller.params: Eq9 needs Kv",
    ),
    Case(
        "custom: the constructor refuses a value",
        lambda d: _custom_run(d, "NeedsGain", "[controller.params]\ngain = -1.0"),
        ex.ConfigError,
        "NeedsGain(context, **params) raised ValueError: gain must be >= 0, got -1.0 (laws.py, line",
    ),
    Case(
        "custom: an undeclared signal",
        lambda d: _custom_run(d, "Undeclared"),
        ex.ControllerError,
        "returned signal 'surprise', which is not in its signal_names",
    ),
    Case(
        "custom: a torque of the wrong size",
        lambda d: _custom_run(d, "WrongShape"),
        ex.ControllerError,
        "returned a torque of shape (4,) at t = 0 s; the arm has 3 joints",
    ),
    Case(
        "custom: an exception in compute",
        lambda d: _custom_run(d, "Raises"),
        ex.ControllerError,
        "Raises.compute raised at t = 0.011 s: IndexError: list index out of range (laws.py, line",
    ),
    Case(
        "custom: compute ends the process (sys.exit)",
        lambda d: _custom_run(d, "Exits"),
        ex.ControllerError,
        "Exits.compute raised at t = 0.011 s: SystemExit: 0 (laws.py, line",
    ),
    Case(
        "custom: a scalar torque after the first step",
        lambda d: _custom_run(d, "LateBreach", _late("scalar")),
        ex.ControllerError,
        "LateBreach.compute returned a torque of shape () at t = 0.051 s; the arm has 3 joints",
    ),
    Case(
        "custom: a tuple instead of a ControlOutput after the first step",
        lambda d: _custom_run(d, "LateBreach", _late("tuple")),
        ex.ControllerError,
        "LateBreach.compute must return a ControlOutput, got tuple at t = 0.051 s",
    ),
    Case(
        "custom: a signal that is not a number after the first step",
        lambda d: _custom_run(d, "LateBreach", _late("signal")),
        ex.ControllerError,
        "LateBreach.compute returned signal 'elapsed' = 'soon' at t = 0.051 s; a signal is one number",
    ),
    Case(
        "custom: a state whose record passes simulation.memory_limit",
        lambda d: _custom_run(d, "BigState", duration=20.0),
        ex.ConfigError,
        "simulation.memory_limit: this run needs about 96 GB (20 s at 0.001 s per step, 3 joints, a state "
        "of 200000 and 1 signals per step)",
    ),
    Case(
        "custom: a signal named like one every run records",
        lambda d: _custom_run(d, "NamesH"),
        ex.ConfigError,
        "controller.class: NamesH.signal_names: 'h' is a signal every run records itself (h, manipulability)",
    ),
    Case(
        "custom: a signal name that is a path",
        lambda d: _custom_run(d, "NamesAPath"),
        ex.ConfigError,
        "controller.class: NamesAPath.signal_names: '../../../evil' is not a signal name",
    ),
    Case(
        "custom: a state no run could hold",
        lambda d: _custom_run(d, "HugeState"),
        ex.ConfigError,
        "controller.class: HugeState.state_size must be a whole number in [0, 1e+07], got 1000000000",
    ),
]


PARTS = Path(__file__).parents[1] / "parts" / "again.py"
