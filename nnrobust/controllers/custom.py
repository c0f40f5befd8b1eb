"""User controllers: ``controller.kind = "custom"`` builds ``controller.class`` as
``Class(context, **controller.params)`` (docs/extending.md).

``controller.class`` is ``"file.py:Class"`` (a file; relative paths are read from the experiment
file's folder) or ``"package.module:Class"`` (an importable module). A file is imported once per
content: its module is named after its SHA-256, so an edited file is imported afresh and a run
records exactly which code it ran.
"""

from __future__ import annotations

import difflib
import hashlib
import importlib
import importlib.util
import inspect
import sys
import traceback
from pathlib import Path

import numpy as np

from ..exceptions import ConfigError, ControllerError, NNRobustError
from .base import Controller, ControllerContext

KEY = "controller.class"


def class_file(spec: str) -> Path | None:
    """The file a ``controller.class`` value names (``file.py:Class``), or None for a module path."""
    where = spec.rpartition(":")[0]
    if where.endswith(".py") or "/" in where or "\\" in where:
        return Path(where)
    return None


def file_digest(path: str | Path) -> str:
    """SHA-256 of a controller file's bytes."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _import_file(path: Path):
    if not path.is_file():
        raise ConfigError(
            KEY,
            f"{str(path)!r} is not a file (a relative path in an experiment file is read "
            "from the file's folder)",
        )
    digest = file_digest(path)
    name = f"nnrobust_user_{''.join(c if c.isalnum() else '_' for c in path.stem)}_{digest[:16]}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise ConfigError(KEY, f"{str(path)!r} cannot be imported as Python")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look the module up by name
    try:
        spec.loader.exec_module(module)
    except Exception as err:
        del sys.modules[name]
        raise ConfigError(KEY, f"importing {path} raised {_located(err, path)}") from err
    return module


def _located(err: BaseException, path: Path | None = None) -> str:
    """'ValueError: message (file.py, line 12)': the error and the innermost frame in user code."""
    frames = traceback.extract_tb(err.__traceback__)
    if isinstance(err, SyntaxError) and err.lineno:
        return f"SyntaxError: {err.msg} ({Path(err.filename or '?').name}, line {err.lineno})"
    package = str(Path(__file__).resolve().parent.parent)
    user = [f for f in frames if not f.filename.startswith(package)]
    where = f" ({Path(user[-1].filename).name}, line {user[-1].lineno})" if user else ""
    return f"{type(err).__name__}: {err}{where}"


def load_class(spec: str) -> type[Controller]:
    """The Controller subclass ``spec`` names; every failure is one ConfigError on controller.class."""
    where, _, name = spec.rpartition(":")
    path = class_file(spec)
    if path is not None:
        module = _import_file(path)
    else:
        try:
            module = importlib.import_module(where)
        except ModuleNotFoundError as err:
            raise ConfigError(
                KEY, f'no module {where!r} ({err}); give a file as "file.py:{name}" or install the package'
            ) from err
        except Exception as err:
            raise ConfigError(KEY, f"importing {where} raised {_located(err)}") from err
    cls = getattr(module, name, None)
    if cls is None:
        found = sorted(
            k
            for k, v in vars(module).items()
            if isinstance(v, type) and issubclass(v, Controller) and v.__module__ == module.__name__
        )
        close = difflib.get_close_matches(name, found, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ConfigError(
            KEY, f"{where} has no {name!r}{hint} Controllers there: {', '.join(found) or 'none'}"
        )
    if not (isinstance(cls, type) and issubclass(cls, Controller)):
        raise ConfigError(
            KEY,
            f"{where}:{name} is not a subclass of nnrobust.Controller (it is "
            f"{type(cls).__name__} {getattr(cls, '__name__', '')!r})",
        )
    if inspect.isabstract(cls):
        missing = ", ".join(sorted(cls.__abstractmethods__))
        raise ConfigError(KEY, f"{where}:{name} does not implement {missing}")
    return cls


def check_params(cls: type, params: dict) -> None:
    """The constructor takes ``(context, **params)``: every key known, every required one given."""
    try:
        signature = inspect.signature(cls.__init__)  # type: ignore[misc]  # the class's own constructor
    except (TypeError, ValueError):  # a constructor without a signature: let the call decide
        return
    parameters = list(signature.parameters.values())[2:]  # self, context
    if any(p.kind is p.VAR_KEYWORD for p in parameters):
        return
    names = [p.name for p in parameters if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    for key in params:
        if key not in names:
            close = difflib.get_close_matches(key, names, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ConfigError(
                f"controller.params.{key}",
                f"{cls.__name__} takes no such parameter{hint} Parameters: {', '.join(names) or 'none'}",
            )
    missing = [
        p.name for p in parameters if p.default is p.empty and p.name in names and p.name not in params
    ]
    if missing:
        raise ConfigError("controller.params", f"{cls.__name__} needs {', '.join(missing)}")


def build_custom(spec: str, params: dict | None, context: ControllerContext) -> Controller:
    """``Class(context, **params)``, checked against the contract before it runs."""
    cls = load_class(spec)
    params = dict(params or {})
    check_params(cls, params)
    try:
        controller = cls(context, **params)  # type: ignore[call-arg]  # a subclass's constructor
    except NNRobustError:
        raise
    except Exception as err:
        raise ConfigError(
            "controller.params", f"{cls.__name__}(context, **params) raised {_located(err)}"
        ) from err
    names = controller.signal_names
    if isinstance(names, str) or not all(isinstance(s, str) for s in names):
        raise ConfigError(KEY, f"{cls.__name__}.signal_names must be a tuple of names, got {names!r}")
    try:
        z0 = np.asarray(controller.initial_state(), dtype=float)
    except Exception as err:
        raise ConfigError(KEY, f"{cls.__name__}.initial_state() raised {_located(err)}") from err
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


def failed(controller: Controller, err: Exception, t: float) -> ControllerError:
    """An exception raised inside a controller's compute, located."""
    return ControllerError(f"{type(controller).__name__}.compute raised at t = {t:g} s: {_located(err)}")
