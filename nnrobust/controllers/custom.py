"""User controllers: ``controller.kind = "custom"`` builds ``controller.class`` as
``Class(context, **controller.params)`` (docs/extending.md; loaded by :mod:`nnrobust.plugins.user_code`),
checked against the contract before and at its first step.
"""

from __future__ import annotations

import re

import numpy as np

from ..core.exceptions import ConfigError, ControllerError
from ..plugins.user_code import construct, located
from .base import Controller, ControllerContext, ControlOutput

KEY = "controller.class"

SIGNAL_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")
"""A signal's name: it becomes an array's name in result.npz (``signal_NAME``) and a plot title."""

RESERVED_SIGNALS = ("h", "manipulability")
"""The signals every run records itself (nnrobust.run.results.Result.from_trace)."""

MAX_STATE = 10**7
"""The most entries a user's controller state may have (80 MB a vector; the record of a run holds
one per control step, bounded by simulation.memory_limit)."""


def build_custom(spec: str, params: dict | None, context: ControllerContext) -> Controller:
    """``Class(context, **params)``, checked against the contract before it runs."""
    controller = construct(spec, params, Controller, KEY, "controller.params", context, "context")
    cls = type(controller)
    names = controller.signal_names
    if isinstance(names, str) or not all(isinstance(s, str) for s in names):
        raise ConfigError(KEY, f"{cls.__name__}.signal_names must be a tuple of names, got {names!r}")
    for name in names:
        if not SIGNAL_NAME.fullmatch(name):
            raise ConfigError(
                KEY,
                f"{cls.__name__}.signal_names: {name[:40]!r} is not a signal name (1-64 letters, digits "
                "or '_', not starting with a digit: it names an array of result.npz)",
            )
        if name in RESERVED_SIGNALS:
            raise ConfigError(
                KEY,
                f"{cls.__name__}.signal_names: {name!r} is a signal every run records itself "
                f"({', '.join(RESERVED_SIGNALS)}); name yours otherwise",
            )
    if len(set(names)) != len(names):
        raise ConfigError(KEY, f"{cls.__name__}.signal_names names a signal twice: {names!r}")
    size = controller.state_size
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or not 0 <= size <= MAX_STATE:
        raise ConfigError(
            KEY, f"{cls.__name__}.state_size must be a whole number in [0, {MAX_STATE:.0e}], got {size!r}"
        )
    try:
        z0 = np.asarray(controller.initial_state(), dtype=float)
    except Exception as err:
        raise ConfigError(KEY, f"{cls.__name__}.initial_state() raised {located(err)}") from err
    if z0.ndim != 1:
        raise ConfigError(KEY, f"{cls.__name__}.initial_state() must return a vector, got shape {z0.shape}")
    return controller


def checked_output(controller: Controller, out, n: int, state_size: int, t: float):
    """(tau, signals, state) of one output of a user's controller, checked at every control step:
    a :class:`ControlOutput` whose torque is n numbers (a list of ints will do), whose signals are
    declared numbers and whose state is None or z's size. Anything else is a ControllerError that
    names the class, what it returned and when (never a traceback from deep in the loop, never a
    scalar torque broadcast to every joint).
    """
    if not isinstance(out, ControlOutput):
        got = type(out).__name__
        raise ControllerError(
            f"{_name(controller)}.compute must return a ControlOutput, got {got} at t = {t:g} s"
        )
    tau = out.tau
    if type(tau) is not np.ndarray or tau.dtype != np.float64:
        tau = _numbers(controller, tau, "a torque", t)
    if tau.shape != (n,):
        raise ControllerError(
            f"{_name(controller)}.compute returned a torque of shape {tau.shape} at t = {t:g} s; "
            f"the arm has {n} joints"
        )
    signals = out.signals
    if signals:
        if not isinstance(signals, dict):
            raise ControllerError(
                f"{_name(controller)}.compute returned signals as {type(signals).__name__} at t = {t:g} s; "
                "give a dict of name -> number"
            )
        undeclared(controller, signals)
        for key, value in signals.items():
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ControllerError(
                    f"{_name(controller)}.compute returned signal {key!r} = {_shown(value)} at t = {t:g} s; "
                    "a signal is one number"
                )
    state = out.state
    if state is not None:
        if type(state) is not np.ndarray or state.dtype != np.float64:
            state = _numbers(controller, state, "a state", t)
        if state.shape != (state_size,):
            raise ControllerError(
                f"{_name(controller)}.compute returned a state of shape {state.shape} at t = {t:g} s; "
                f"initial_state() has {state_size} entries"
            )
    return tau, signals, state


def _name(controller: Controller) -> str:
    return type(controller).__name__


def _shown(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _numbers(controller: Controller, value, what: str, t: float) -> np.ndarray:
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError) as err:
        raise ControllerError(
            f"{_name(controller)}.compute returned {what} that is not numbers at t = {t:g} s: "
            f"{_shown(value)} ({err})"
        ) from err


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
