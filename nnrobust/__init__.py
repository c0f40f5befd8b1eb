"""nnrobust: robust neural-network control of redundant manipulators, built on Pinocchio.

The names below are imported on first use, so that ``import nnrobust`` (and the command line's
start) stays fast and interruptible.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    # the workflow: load, configure, build, run, write, plot
    "load_robot": ".model",
    "load_preset": ".presets",
    "preset_names": ".presets",
    "load_config": ".config",
    "ExperimentConfig": ".config",
    "apply_overrides": ".config",
    "build": ".experiment",
    "Setup": ".experiment",
    "run_experiment": ".experiment",
    "Result": ".results",
    "write_run": ".run_folder",
    "load_run": ".run_folder",
    "plot_run": ".plots",
    "plot_comparison": ".plots",
    # many runs: sweeps and tuning (the sweep and tune extras)
    "load_sweep": ".sweep",
    "run_sweep": ".sweep",
    "read_results": ".sweep",
    "TuneSpec": ".tune",
    "run_tune": ".tune",
    "FalsifySpec": ".falsify",
    "run_falsify": ".falsify",
    "load_study": ".study",
    "run_study": ".study",
    # a sweep's, tuning's, falsification's or study's summary, shown as HTML in Jupyter
    "load_summary": ".display",
    # the contract of a controller of your own (docs/extending.md)
    "Controller": ".controllers",
    "ControlOutput": ".controllers",
    "ControllerContext": ".controllers",
    # ... and of a trajectory, disturbance or self-motion criterion of your own
    "Trajectory": ".trajectories",
    "Disturbance": ".plant.disturbance",
    "Criterion": ".subtasks.base",
    # models
    "DynamicsModel": ".model",
    "PinocchioModel": ".model",
    "ThreeLinkParameters": ".model",
    "ThreeLinkPlanarModel": ".model",
    "paper_arm_urdf": ".model",
    # errors
    "NNRobustError": ".exceptions",
    "ConfigError": ".exceptions",
    "ControllerError": ".exceptions",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    if name == "__version__":
        from .package_version import package_version

        globals()["__version__"] = value = package_version()
        return value
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'nnrobust' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
