"""A user's control law in C++ (docs/extending.md#a-law-in-c): one ``.cpp`` file named in an
experiment like a Python class, ``class = "my_law.cpp:MyLaw"``; and the C++ twin of a kind declared
outside nnrobust (docs/extending.md#a-twin-in-c), named by its ``twin_source``
(:func:`load_twin_source`).

The file is written against the law header the shipped laws use (installed as
``nnrobust/law.hpp``) and names its class with ``NNROBUST_USER_LAW(Class, signals, state size)``.
On first use it is compiled, with the compiler, definitions and options the package's own laws
were compiled with (``native_build.txt``, written by CMakeLists.txt), into a library cached by
the SHA-256 of the file, the headers and the toolchain; the library is loaded into the compiled
loop and registered as a law, and the class returned here is its Python face: a Controller whose
compiled twin is that law, so it runs on the compiled loop (and in sweep, tune, falsify and
study, whose workers compile it from the file that travels with the task). Compiler errors are
the compiler's own lines, with the file and line.
"""

from __future__ import annotations

import fcntl
import functools
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from .exceptions import ConfigError, NNRobustError

SOURCE_SUFFIXES = (".cpp", ".cc", ".cxx")
"""The files a class value names as C++ (``file.cpp:Class``)."""

COMPILER_LINES = 40
"""The most compiler lines an error shows."""

_loaded: dict[str, tuple[str, tuple[str, ...], dict]] = {}
"""Library path -> (registered law name, signal names, search space) of the laws loaded here."""

_twins: dict[str, dict[str, set[str]]] = {}
"""Library path -> {concept: names it registered} of the twins compiled apart loaded here."""

TWIN_DEFINITION = "NNROBUST_TWIN_LIBRARY"
"""Defined when a twin's file is compiled: its registries hand themselves over (registry.hpp)."""


def is_source(path: str | Path) -> bool:
    """Whether a class file is C++."""
    return Path(path).suffix in SOURCE_SUFFIXES


def include_dir() -> Path:
    """The installed headers (``nnrobust/include``, beside the compiled loop's module:
    ``nnrobust/law.hpp`` and the tree it includes).
    """
    try:
        from . import _loop
    except ImportError as err:
        raise NNRobustError(f"a law in C++ runs on the compiled loop, which is not built ({err})") from err
    folder = Path(_loop.__file__).resolve().parent / "include"
    if not (folder / "nnrobust" / "law.hpp").is_file():
        raise NNRobustError(
            f"{folder / 'nnrobust' / 'law.hpp'} is missing: the package was installed without its "
            "compiled loop, which a law in C++ runs on (docs/compiled.md)"
        )
    return folder


def build_info() -> dict[str, str]:
    """The compiler, definitions and options the package's laws were compiled with."""
    info = {}
    for line in (include_dir() / "nnrobust" / "native_build.txt").read_text().splitlines():
        key, _, value = line.partition("=")
        info[key] = value
    return info


def cmeel_prefix() -> Path:
    """The pin wheel's prefix (headers and libraries of Pinocchio, Eigen, Boost)."""
    for folder in sys.path:
        prefix = Path(folder) / "cmeel.prefix"
        if (prefix / "include" / "pinocchio").is_dir():
            return prefix
    raise NNRobustError("Pinocchio's headers (the pin wheel's cmeel.prefix) were not found on sys.path")


def compiler(info: dict[str, str]) -> str:
    """The C++ compiler: the one the package was built with, else CXX, else c++ on PATH."""
    for name in (info.get("compiler", ""), os.environ.get("CXX", ""), "c++", "g++", "clang++"):
        if name and (Path(name).is_file() or shutil.which(name)):
            return name
    raise NNRobustError("a law in C++ needs a C++ compiler: none was found (set CXX)")


def cache_dir() -> Path:
    """Where compiled laws are kept: NNROBUST_CACHE, else ~/.cache/nnrobust (XDG_CACHE_HOME)."""
    root = os.environ.get("NNROBUST_CACHE") or Path(
        os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache", "nnrobust"
    )
    return Path(root) / "laws"


def _toolchain(cxx: str, info: dict[str, str]) -> str:
    """What the library depends on besides the file: the compiler's version, the build's flags and
    every installed header (computed once a process: every run of a sweep asks).
    """
    return _toolchain_digest(cxx, tuple(sorted(info.items())))


@functools.lru_cache(maxsize=8)
def _toolchain_digest(cxx: str, items: tuple[tuple[str, str], ...]) -> str:
    info = dict(items)
    try:
        version = subprocess.run([cxx, "--version"], capture_output=True, text=True, timeout=60).stdout
    except (OSError, subprocess.SubprocessError) as err:
        raise NNRobustError(f"the C++ compiler {cxx} could not be run ({err})") from err
    digest = hashlib.sha256(version.encode() + repr(sorted(info.items())).encode())
    for header in sorted((include_dir() / "nnrobust").rglob("*")):
        if header.is_file():
            digest.update(header.name.encode() + header.read_bytes())
    return digest.hexdigest()


def command(
    source: Path, output: Path, link: list[str] | None = None, definitions: tuple[str, ...] = ()
) -> list[str]:
    """The compile command of a law's library, linked with ``link`` (by default the pin wheel's
    Pinocchio; an export links its own copies, nnrobust.export), with ``definitions`` beside the
    package's own.
    """
    info = build_info()
    prefix = cmeel_prefix()
    defines = [f"-D{d}" for d in (*info.get("definitions", "").split(";"), *definitions) if d]
    options = [o for o in info.get("options", "").split(";") if o]
    return [
        compiler(info),
        "-std=gnu++17",
        "-O3",
        "-DNDEBUG",
        "-fPIC",
        "-shared",
        "-fvisibility=hidden",
        *options,
        *defines,
        "-I",
        str(include_dir()),
        "-I",
        str(include_dir() / "nnrobust"),
        *(f"-isystem{prefix / d}" for d in info.get("includes", "").split(";") if d),
        "-isystem",
        str(prefix / "include"),
        str(source),
        *(
            ["-L", str(prefix / "lib"), "-lpinocchio_default", f"-Wl,-rpath,{prefix / 'lib'}"]
            if link is None
            else link
        ),
        "-o",
        str(output),
    ]


def compiled_library(source: Path, key: str, definitions: tuple[str, ...] = ()) -> tuple[Path, str]:
    """The library of a law's or a twin's file (compiled now unless cached, with ``definitions``):
    (path, SHA-256 of its inputs).
    """
    text = source.read_bytes()
    info = build_info()
    cxx = compiler(info)
    digest = hashlib.sha256(text + repr(definitions).encode() + _toolchain(cxx, info).encode()).hexdigest()
    folder = cache_dir()
    library = folder / f"{''.join(c if c.isalnum() else '_' for c in source.stem)}-{digest[:20]}.so"
    if library.is_file():
        return library, digest
    folder.mkdir(parents=True, exist_ok=True)
    # one compile per library on this machine: other processes (a sweep's workers) wait for it
    with open(library.with_suffix(".lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if library.is_file():
            return library, digest
        fd, tmp = tempfile.mkstemp(suffix=".so", dir=folder)
        os.close(fd)
        try:
            done = subprocess.run(
                command(source, Path(tmp), definitions=definitions),
                capture_output=True,
                text=True,
                timeout=1800,
            )
            if done.returncode != 0:
                lines = [line for line in done.stderr.splitlines() if line.strip()]
                shown = "\n".join(lines[:COMPILER_LINES])
                more = (
                    f"\n... ({len(lines) - COMPILER_LINES} more lines)" if len(lines) > COMPILER_LINES else ""
                )
                raise ConfigError(key, f"compiling {source} failed:\n{shown}{more}")
            os.replace(tmp, library)  # atomic: a reader sees no library or the whole of it
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    return library, digest


def _compiled_loop(key: str, path: Path, what: str):
    """The compiled loop's module, or one line naming ``key`` and the file: ``what`` (a law, a
    twin) in C++ runs on it.
    """
    try:
        from . import _loop
    except ImportError as err:
        raise ConfigError(
            key, f"{path}: {what} in C++ runs on the compiled loop, which is not built ({err})"
        ) from err
    return _loop


def load_native_class(path: Path, source: Path, name: str, base: type, key: str) -> type:
    """The Python face of the law ``name`` in the C++ file ``source`` (``path`` as the experiment
    names it): a subclass of ``base`` (Controller) whose compiled twin is the loaded library.
    """
    if not name.isidentifier():
        raise ConfigError(key, f"{name!r} is not a C++ class name")
    _loop = _compiled_loop(key, path, "a law")
    library, digest = compiled_library(source, key)
    if str(library) not in _loaded:
        twin = f"cpp:{name}:{digest[:16]}"
        try:
            signals, space = _loop.load_law_library(str(library), name, twin)
        except (RuntimeError, ValueError) as err:
            raise ConfigError(key, f"{path}: {err}") from err
        names = tuple(s.strip() for s in signals.split(",") if s.strip())
        _loaded[str(library)] = (twin, names, declared_space(space, name, path, key))
    twin, signal_names, search_space = _loaded[str(library)]
    face = _python_face(base, name, twin, signal_names, digest, path)
    face.native_source = source.resolve()  # type: ignore[attr-defined]  # what an export compiles
    if search_space:
        face.search_space = search_space  # type: ignore[attr-defined]
    return face


def load_twin_source(source: str | Path, concept: str, name: str, owner: str) -> None:
    """Compile (unless cached) and load the C++ file a kind declares as its ``twin_source``, and
    check that it registered the ``concept`` (law, robust term, criterion, path, disturbance)
    ``name`` its Python twin declares; ``owner`` names the declaring class or kind in errors.
    """
    key = f"{owner}.twin_source"
    path = Path(source)
    if not path.is_file():
        raise ConfigError(key, f"{path} is not a file (the C++ twin of the {concept} {name!r})")
    if not is_source(path):
        raise ConfigError(key, f"{path} is not a C++ file (one of {', '.join(SOURCE_SUFFIXES)})")
    _loop = _compiled_loop(key, path, "a twin")
    library, _ = compiled_library(path, key, (TWIN_DEFINITION,))
    if str(library) not in _twins:
        try:
            registered = _loop.load_twin_library(str(library))
        except (RuntimeError, ValueError) as err:
            raise ConfigError(key, f"{path}: {err}") from err
        _twins[str(library)] = {c: set(names.split(",")) for c, names in registered.items()}
    names = _twins[str(library)]
    if name not in names.get(concept, set()):
        found = "; ".join(f"the {c} {', '.join(sorted(n))}" for c, n in sorted(names.items()))
        raise ConfigError(
            key, f"{path} registers {found}, not the {concept} {name!r} that {owner} declares as its twin"
        )


def declared_space(text: str, name: str, path: Path, key: str) -> dict:
    """NNROBUST_USER_LAW_SPACE's "name=low:high[:unit], ..." as a Python law's search_space
    ({param: (low, high, unit)}); the tuner checks the bounds (nnrobust.tune.space.custom_space).
    """
    space = {}
    for entry in (e.strip() for e in text.split(",")):
        if not entry:
            continue
        param, _, bounds = entry.partition("=")
        parts = bounds.split(":")
        try:
            if not param.strip().isidentifier() or len(parts) not in (2, 3):
                raise ValueError
            space[param.strip()] = (float(parts[0]), float(parts[1]), *(p.strip() for p in parts[2:]))
        except ValueError:
            raise ConfigError(
                key, f"{path}: NNROBUST_USER_LAW_SPACE({name}, ...): {entry!r} is not name=low:high[:unit]"
            ) from None
    return space


def _python_face(base: type, name: str, twin: str, signal_names: tuple, digest: str, path: Path) -> type:
    import numpy as np

    from . import _loop

    def __init__(self, context, **params):  # noqa: N807
        self.n = context.n
        # what the compiled controller takes from the experiment beside the law's own fields
        self.pinv, self.nominal_friction = context.pseudo_inverse, context.nominal_friction
        self.params = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in params.items()}
        for k, v in self.params.items():
            setattr(self, k, v)
        self.twin_fields = tuple(sorted(self.params))
        self.state_size = int(_loop.native_law_state(twin, context.n))

    def initial_state(self):
        return np.zeros(self.state_size)

    def compute(self, t, q, v, z, period=0.0):
        raise NNRobustError(
            f"{name} ({path}) is a law in C++: it runs on the compiled loop (simulation.backend "
            "'compiled' or 'auto'), not on the Python or hybrid loop"
        )

    return type(
        name,
        (base,),
        {
            "__init__": __init__,
            "__module__": f"nnrobust_native_{digest[:16]}",
            "__doc__": f"The law {name} in C++ ({path}, inputs SHA-256 {digest}).",
            "twin": twin,
            "native": str(path),
            "native_digest": digest,
            "signal_names": signal_names,
            "initial_state": initial_state,
            "compute": compute,
        },
    )
