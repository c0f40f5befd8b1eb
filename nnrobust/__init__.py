"""nnrobust: robust neural-network control of redundant manipulators, built on Pinocchio.

The names below are imported on first use, so that ``import nnrobust`` (and the command line's
start) stays fast and interruptible.
"""

from __future__ import annotations

import importlib
import sys

_EXPORTS = {
    # the workflow: load, configure, build, run, write, plot
    "load_robot": ".model",
    "load_preset": ".config.presets",
    "preset_names": ".config.presets",
    "load_config": ".config",
    "ExperimentConfig": ".config",
    "apply_overrides": ".config",
    "build": ".run.experiment",
    "Setup": ".run.experiment",
    "run_experiment": ".run.experiment",
    "Result": ".run.results",
    "write_run": ".outputs.run_folder",
    "load_run": ".outputs.run_folder",
    "plot_run": ".outputs.plots",
    "plot_comparison": ".outputs.plots",
    # many runs: sweeps and tuning (the sweep and tune extras)
    "load_sweep": ".studies.base.plan",
    "run_sweep": ".studies.sweep",
    "read_results": ".studies.sweep",
    "TuneSpec": ".studies.tune",
    "run_tune": ".studies.tune",
    "FalsifySpec": ".studies.falsify",
    "run_falsify": ".studies.falsify",
    "load_study": ".studies.study",
    "run_study": ".studies.study",
    # a sweep's, tuning's, falsification's or study's summary, shown as HTML in Jupyter
    "load_summary": ".studies.study.summaries",
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
    "NNRobustError": ".core.exceptions",
    "ConfigError": ".core.exceptions",
    "ControllerError": ".core.exceptions",
}

__all__ = sorted(_EXPORTS)


def _result_html(result) -> str:
    from .outputs.plots import result_html

    return result_html(result)


def _show_results_with_figures() -> bool:
    """In IPython (a Jupyter kernel), show a run's :class:`Result` as its table and figures.

    The formatter is registered by the class's module and name, so nothing is imported until a
    result is shown; ``run/`` stays below ``outputs/`` (``Result._repr_html_`` alone is the
    table). Returns whether a shell was there to register with.
    """
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    if shell is None:
        return False
    html = shell.display_formatter.formatters["text/html"]
    html.for_type_by_name("nnrobust.run.results", "Result", _result_html)
    return True


_SHOWN_WITH_FIGURES = _show_results_with_figures()


def __getattr__(name: str):
    global _SHOWN_WITH_FIGURES
    if not _SHOWN_WITH_FIGURES:  # IPython started after ``import nnrobust``
        _SHOWN_WITH_FIGURES = _show_results_with_figures()
    if name == "__version__":
        from .core.package_version import package_version

        globals()["__version__"] = value = package_version()
        return value
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name], __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'nnrobust' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(list(globals()) + __all__)
