"""User controllers: ``controller.kind = "custom"`` builds ``controller.class`` as
``Class(context, **controller.params)`` (docs/extending.md; loaded by :mod:`nnrobust.user_code`),
checked against the contract before and at its first step.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import ConfigError, ControllerError
from ..user_code import construct, located
from .base import Controller, ControllerContext

KEY = "controller.class"


def build_custom(spec: str, params: dict | None, context: ControllerContext) -> Controller:
    """``Class(context, **params)``, checked against the contract before it runs."""
    controller = construct(spec, params, Controller, KEY, "controller.params", context, "context")
    cls = type(controller)
    names = controller.signal_names
    if isinstance(names, str) or not all(isinstance(s, str) for s in names):
        raise ConfigError(KEY, f"{cls.__name__}.signal_names must be a tuple of names, got {names!r}")
    try:
        z0 = np.asarray(controller.initial_state(), dtype=float)
    except Exception as err:
        raise ConfigError(KEY, f"{cls.__name__}.initial_state() raised {located(err)}") from err
    if z0.ndim != 1:
        raise ConfigError(KEY, f"{cls.__name__}.initial_state() must return a vector, got shape {z0.shape}")
    return controller


def check_output(controller: Controller, out, n: int, state_size: int, t: float) -> None:
    """The first output of a controller: a torque per joint, declared signals, a state of z's size."""
    name = type(controller).__name__
    tau = np.asarray(getattr(out, "tau", None), dtype=float) if hasattr(out, "tau") else None
    if tau is None:
        raise ControllerError(f"{name}.compute must return a ControlOutput, got {type(out).__name__}")
    if tau.shape != (n,):
        raise ControllerError(
            f"{name}.compute returned a torque of shape {tau.shape} at t = {t:g} s; the arm has {n} joints"
        )
    undeclared(controller, out.signals)
    if out.state is not None and np.shape(out.state) != (state_size,):
        raise ControllerError(
            f"{name}.compute returned a state of shape {np.shape(out.state)}; "
            f"initial_state() has {state_size} entries"
        )


def undeclared(controller: Controller, signals: dict) -> None:
    """Refuse a signal the controller did not declare in ``signal_names``."""
    extra = [s for s in signals if s not in controller.signal_names]
    if extra:
        raise ControllerError(
            f"{type(controller).__name__}.compute returned signal {extra[0]!r}, which "
            "is not "
            f"in its signal_names {tuple(controller.signal_names)}; declare it there"
        )


def failed(controller: Controller, err: BaseException, t: float) -> ControllerError:
    """An exception raised inside a controller's compute, located (a SystemExit too: a law may not
    end the process, which would lose the run and exit as if it had succeeded).
    """
    said = f"{type(controller).__name__}.compute raised at t = {t:g} s: {located(err)}"
    if isinstance(err, SystemExit):
        said += "; a control law may not end the process"
    return ControllerError(said)
