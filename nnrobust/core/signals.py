"""Signals: SIGTERM and SIGHUP stop work like Ctrl-C, an interrupt is never lost, and a few
renames that must not be split hold all three back.
"""

from __future__ import annotations

import contextlib
import signal
import sys

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

_pending = False
_active = 0  # nesting depth of signals_as_interrupt blocks
_stopping = False  # stages run side by side are asked to stop (stop_stages)
_held = 0  # nesting depth of signals_held blocks


def check_interrupt() -> None:
    """Raise KeyboardInterrupt if a stop signal arrived whose KeyboardInterrupt was lost.

    Python runs a signal handler between bytecodes, wherever the main thread is. When that is a
    garbage-collection callback (a weakref's, a __del__), the KeyboardInterrupt it raises is
    "ignored" and the work would go on; long loops call this at each step so that it does not.
    """
    if _pending or _stopping:
        raise KeyboardInterrupt


def stop_stages(stop: bool = True) -> None:
    """Ask the work running on other threads (stages of a study run side by side) to stop at
    their next :func:`check_interrupt`, or, with ``stop=False``, lift that request once they have.
    A signal's own flag is cleared as each block that handled it ends; this one is not.
    """
    global _stopping
    _stopping = stop


def clear_interrupt() -> None:
    """The interrupt has been handled (a run was stopped and marked ``interrupted``)."""
    global _pending
    _pending = False


def _stop(signum, frame):
    global _pending
    _pending = True
    if _active and not _held:  # outside a block the work is over (or not begun): remember, do not raise
        raise KeyboardInterrupt


@contextlib.contextmanager
def signals_held():
    """Ctrl-C, SIGTERM and SIGHUP only noted in the block (a cluster being closed, stages being
    stopped: work that a KeyboardInterrupt cut short would leave half done); a stop noted there
    is raised as it ends, unless an exception already leaves the block. Unlike
    :func:`signals_deferred` it holds a signal whichever thread the system delivers it to.
    """
    global _held
    _held += 1
    try:
        yield
    finally:
        _held -= 1
    if _pending and _active and not _held:
        raise KeyboardInterrupt


def install_stop_handlers() -> None:
    """Route Ctrl-C, SIGTERM and SIGHUP through this module for the rest of the process (the
    command line's entry point): inside a :func:`signals_as_interrupt` block they interrupt,
    outside it (before the command starts its work, after it has finished) they are only noted,
    so that a signal in the last instants never turns a finished run into a traceback.
    """
    for sig in STOP_SIGNALS:
        signal.signal(sig, _stop)


def _unraisable(hook):
    def quiet(unraisable):
        if unraisable.exc_type is KeyboardInterrupt:  # remembered in _pending; no traceback
            return
        hook(unraisable)

    return quiet


@contextlib.contextmanager
def signals_as_interrupt():
    """Ctrl-C, SIGTERM and SIGHUP raise KeyboardInterrupt in the block and are remembered until
    handled: partial results are kept, servers and clusters are closed on the way out (no
    orphan process), and an interrupt that lands in a garbage-collection callback is neither
    printed as a traceback nor lost.
    """
    global _active
    previous = {}
    for sig in STOP_SIGNALS:
        try:
            if signal.getsignal(sig) is not _stop:
                previous[sig] = signal.signal(sig, _stop)
        except (ValueError, OSError):  # not the main thread
            pass
    hook = sys.unraisablehook
    sys.unraisablehook = _unraisable(hook)
    _active += 1
    try:
        if _pending and not _held:  # noted before the block (the command's imports): stop now
            raise KeyboardInterrupt
        yield
    finally:
        _active -= 1
        sys.unraisablehook = hook
        for sig, old in previous.items():
            signal.signal(sig, old)
        clear_interrupt()


@contextlib.contextmanager
def signals_deferred():
    """Hold Ctrl-C, SIGTERM and SIGHUP back for the block; they are delivered when it ends."""
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    except (ValueError, OSError):  # pragma: no cover - platforms without pthread_sigmask
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def ignore_stop_signals() -> None:
    """Ignore Ctrl-C, SIGTERM and SIGHUP from now on: the command's work is done.

    At its teardown the interpreter resets handlers written in Python to the default, which would
    let a late signal kill the finished process; an ignored signal stays ignored.
    """
    for sig in STOP_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
