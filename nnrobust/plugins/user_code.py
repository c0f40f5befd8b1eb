"""A user's class named in an experiment file: ``"file.py:Class"`` (a file; a relative path is
read from the experiment file's folder) or ``"package.module:Class"`` (an importable module),
built as ``Class(first, **params)`` (docs/extending.md).

A file is imported once per content: its module is named after its SHA-256, so an edited file is
imported afresh and a run records exactly which code it ran. Every failure is one ConfigError
that names the key (``controller.class``, ``trajectory.class``, ...).
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

from ..core.exceptions import ConfigError, NNRobustError


def class_file(spec: str) -> Path | None:
    """The file a class value names (``file.py:Class``), or None for a module path."""
    where = spec.rpartition(":")[0]
    if where.endswith((".py", ".cpp", ".cc", ".cxx")) or "/" in where or "\\" in where:
        return Path(where)
    return None


def file_digest(path: str | Path) -> str:
    """SHA-256 of a file's bytes, read a block at a time (a log of an hour is hundreds of MB)."""
    with open(path, "rb") as file:
        return hashlib.file_digest(file, "sha256").hexdigest()


TRAVELS_ALONE = (
    "; only the class file travels to a worker of --scheduler: a module it imports must be "
    "installed there, not a file beside it (docs/robustness.md#a-cluster-without-shared-files)"
)
"""What an import error of a class file sent to a worker adds (:mod:`nnrobust.core.shipped_files`)."""


def _source(path: Path, key: str) -> Path:
    """The file a class value names, or the copy of it the running task brought with it
    (:func:`~nnrobust.core.shipped_files.local`); refused when there is none.
    """
    from ..core.shipped_files import local

    source = local(path)
    if not source.is_file():
        raise ConfigError(
            key,
            f"{str(path)!r} is not a file (a relative path in an experiment file is read "
            "from the file's folder)",
        )
    return source


def _import_file(path: Path, key: str):
    """The module of a class file, imported once per content. A file the running task brought
    with it (:func:`~nnrobust.core.shipped_files.local`) is read from its copy, still named by
    ``path``.
    """
    from ..core.shipped_files import shipped

    source = _source(path, key)
    digest = file_digest(source)
    name = f"nnrobust_user_{''.join(c if c.isalnum() else '_' for c in path.stem)}_{digest[:16]}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, source)
    if spec is None or spec.loader is None:
        raise ConfigError(key, f"{str(path)!r} cannot be imported as Python")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look the module up by name
    try:
        spec.loader.exec_module(module)
    except Exception as err:
        del sys.modules[name]
        hint = TRAVELS_ALONE if isinstance(err, ImportError) and shipped(path) else ""
        raise ConfigError(key, f"importing {path} raised {located(err, path)}{hint}") from err
    return module


def located(err: BaseException, path: Path | None = None) -> str:
    """'ValueError: message (file.py, line 12)': the error and the innermost frame in user code."""
    frames = traceback.extract_tb(err.__traceback__)
    if isinstance(err, SyntaxError) and err.lineno:
        return f"SyntaxError: {err.msg} ({Path(err.filename or '?').name}, line {err.lineno})"
    package = str(Path(__file__).resolve().parents[1])  # nnrobust/: frames of the package are not the user's
    user = [f for f in frames if not f.filename.startswith(package)]
    where = f" ({Path(user[-1].filename).name}, line {user[-1].lineno})" if user else ""
    return f"{type(err).__name__}: {err}{where}"


def load_class(spec: str, base: type, key: str) -> type:
    """The subclass of ``base`` that ``spec`` names; every failure is one ConfigError on ``key``."""
    where, _, name = spec.rpartition(":")
    if not where or not name:
        raise ConfigError(key, f'{spec!r}: give "file.py:Class" or "package.module:Class"')
    path = class_file(spec)
    if path is not None and Path(path).suffix in (".cpp", ".cc", ".cxx"):  # a law in C++
        from .native_law import load_native_class

        return load_native_class(path, _source(path, key), name, base, key)
    if path is not None:
        module = _import_file(path, key)
    else:
        try:
            module = importlib.import_module(where)
        except ModuleNotFoundError as err:
            raise ConfigError(
                key, f'no module {where!r} ({err}); give a file as "file.py:{name}" or install the package'
            ) from err
        except Exception as err:
            raise ConfigError(key, f"importing {where} raised {located(err)}") from err
    cls = getattr(module, name, None)
    what = f"{base.__name__}s"
    if cls is None:
        found = sorted(
            k
            for k, v in vars(module).items()
            if isinstance(v, type) and issubclass(v, base) and v.__module__ == module.__name__
        )
        close = difflib.get_close_matches(name, found, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ConfigError(key, f"{where} has no {name!r}{hint} {what} there: {', '.join(found) or 'none'}")
    if not (isinstance(cls, type) and issubclass(cls, base)):
        raise ConfigError(
            key,
            f"{where}:{name} is not a subclass of nnrobust.{base.__name__} (it is "
            f"{type(cls).__name__} {getattr(cls, '__name__', '')!r})",
        )
    if inspect.isabstract(cls):
        missing = ", ".join(sorted(getattr(cls, "__abstractmethods__", ())))
        raise ConfigError(key, f"{where}:{name} does not implement {missing}")
    return cls


def check_params(cls: type, params: dict, params_key: str) -> None:
    """The constructor takes ``(first, **params)``: every key known, every required one given."""
    try:
        signature = inspect.signature(cls.__init__)  # type: ignore[misc]  # the class's own constructor
    except (TypeError, ValueError):  # a constructor without a signature: let the call decide
        return
    parameters = list(signature.parameters.values())[2:]  # self, the first argument
    if any(p.kind is p.VAR_KEYWORD for p in parameters):
        return
    names = [p.name for p in parameters if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    for key in params:
        if key not in names:
            close = difflib.get_close_matches(key, names, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ConfigError(
                f"{params_key}.{key}",
                f"{cls.__name__} takes no such parameter{hint} Parameters: {', '.join(names) or 'none'}",
            )
    missing = [
        p.name for p in parameters if p.default is p.empty and p.name in names and p.name not in params
    ]
    if missing:
        raise ConfigError(params_key, f"{cls.__name__} needs {', '.join(missing)}")


def construct(spec: str, params: dict | None, base: type, key: str, params_key: str, first, first_name: str):
    """``Class(first, **params)``, the class loaded and its parameters checked first;
    ``first_name`` names the first argument in errors (context, robot).
    """
    cls = load_class(spec, base, key)
    params = dict(params or {})
    check_params(cls, params, params_key)
    try:
        return cls(first, **params)
    except NNRobustError:
        raise
    except Exception as err:
        raise ConfigError(
            params_key, f"{cls.__name__}({first_name}, **params) raised {located(err)}"
        ) from err
