"""A user's control law in C++ (docs/extending.md#a-law-in-c): one ``.cpp`` file named in an
experiment like a Python class, ``class = "my_law.cpp:MyLaw"``; and the C++ twin of a kind declared
outside nnrobust (docs/extending.md#a-twin-in-c), named by its ``twin_source``
(:func:`load_twin_source`).

The file is written against the law header the shipped laws use (installed as
``nnrobust/law.hpp``) and names its class with ``NNROBUST_USER_LAW(Class, signals, state size)``.
On first use it is compiled, with the compiler, definitions and options the package's own laws
were compiled with (``native_build.txt``, written by CMakeLists.txt), into a library cached by
everything the compiler read (:func:`library`: the file, the headers it includes, recorded from
the compile's dependency file, and the toolchain; a damaged library is compiled again); the
library is loaded into the compiled loop and registered as a law (its exits, crashes, exceptions
and hangs said with its name: csrc/user_code.cpp), and the class returned here is its Python
face: a Controller whose compiled twin is that law, so it runs on the compiled loop (and in
sweep, tune, falsify and study, whose workers compile it from the file and headers that travel
with the task). Compiler errors are the compiler's own lines, with the file and line.
"""

from __future__ import annotations

import fcntl
import functools
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

from ..core.exceptions import ConfigError, NNRobustError

SOURCE_SUFFIXES = (".cpp", ".cc", ".cxx")
"""The files a class value names as C++ (``file.cpp:Class``)."""

COMPILER_LINES = 40
"""The most compiler lines an error shows."""

_loaded: dict[tuple[str, str], tuple[str, tuple[str, ...], dict]] = {}
"""(Library path, class) -> (registered law name, signal names, search space) of the laws loaded
here (a file may define several)."""

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
        from .. import _loop
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
    """What the library depends on besides the file and its own headers: the compiler's version,
    the build's flags, every installed header of nnrobust and the versions of the packages whose
    headers it is compiled against (computed once a process: every run of a sweep asks).
    """
    return _toolchain_digest(cxx, tuple(sorted(info.items())))


HEADER_PACKAGES = ("pin", "cmeel-eigen", "cmeel-boost", "cmeel-urdfdom-headers")
"""The packages whose headers a law is compiled against (-isystem, never listed as its own
dependencies): their versions are part of every library's key."""


@functools.lru_cache(maxsize=8)
def _toolchain_digest(cxx: str, items: tuple[tuple[str, str], ...]) -> str:
    from importlib import metadata

    info = dict(items)
    try:
        version = subprocess.run([cxx, "--version"], capture_output=True, text=True, timeout=60).stdout
    except (OSError, subprocess.SubprocessError) as err:
        raise NNRobustError(f"the C++ compiler {cxx} could not be run ({err})") from err
    digest = hashlib.sha256(version.encode() + repr(sorted(info.items())).encode())
    for package in HEADER_PACKAGES:
        try:
            digest.update(f"{package}=={metadata.version(package)}".encode())
        except metadata.PackageNotFoundError:
            digest.update(f"{package} missing".encode())
    for header in sorted((include_dir() / "nnrobust").rglob("*")):
        if header.is_file():
            digest.update(header.name.encode() + header.read_bytes())
    return digest.hexdigest()


def header_dirs(info: dict[str, str]) -> list[Path]:
    """The include folders of Pinocchio and the libraries it uses (``native_build.txt``'s
    ``includes``, relative to a cmeel prefix), each found in the cmeel prefix of this Python that
    holds it: the runtime's (the build's may have been a temporary environment). A folder found in
    none is one error naming it and the package to install.
    """
    prefixes = [Path(folder) / "cmeel.prefix" for folder in sys.path]
    prefixes = [cmeel_prefix(), *(p for p in prefixes if p.is_dir())]
    found = []
    for relative in (d for d in info.get("includes", "").split(";") if d):
        where = next((p / relative for p in prefixes if (p / relative).is_dir()), None)
        if where is None:
            package = {"include/eigen3": "cmeel-eigen", "include/urdfdom_headers": "cmeel-urdfdom-headers"}
            hint = package.get(relative, "the package that provides it")
            raise NNRobustError(
                f"a law in C++ is compiled against {relative} of a cmeel prefix, which no folder of "
                f"sys.path holds ({', '.join(str(p) for p in dict.fromkeys(prefixes))}): install "
                f"{hint} (a dependency of nnrobust: `pip install nnrobust` installs it)"
            )
        found.append(where)
    return list(dict.fromkeys(found))


def command(
    source: Path,
    output: Path,
    link: list[str] | None = None,
    definitions: tuple[str, ...] = (),
    flags: tuple[str, ...] = (),
) -> list[str]:
    """The compile command of a law's library, linked with ``link`` (by default the pin wheel's
    Pinocchio; an export links its own copies, nnrobust.outputs.export), with ``definitions`` beside the
    package's own and ``flags`` (the cache's dependency file and wrappers) before the file.
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
        *(f"-isystem{d}" for d in header_dirs(info)),
        "-isystem",
        str(prefix / "include"),
        *flags,
        str(source),
        *(
            ["-L", str(prefix / "lib"), "-lpinocchio_default", f"-Wl,-rpath,{prefix / 'lib'}"]
            if link is None
            else link
        ),
        "-o",
        str(output),
    ]


EXIT_CALLS = ("exit", "_exit", "_Exit", "quick_exit", "abort")
"""The calls that end a process: a law's library is linked with each wrapped (``--wrap``), so
that one made inside a law ends the process with a line naming the law and exit code 70
(csrc/user_code.cpp), never as if the run had succeeded."""

MANIFEST = 1
"""The version of a cached law's manifest (``NAME-KEY.json`` beside its libraries)."""


@dataclass(frozen=True)
class Library:
    """A law's or a twin's compiled library.

    Attributes:
        path: the library in the cache.
        digest: SHA-256 of everything it was compiled from: the file, the headers it includes
            (``dependencies``), the definitions and the toolchain (:func:`_toolchain`).
        dependencies: the user's headers the compiler read (the ``.d`` file of ``-MMD``: neither
            the file itself, nor nnrobust's installed headers, nor system and ``-isystem``
            headers, which the toolchain's digest covers), each as (its path relative to the
            file's folder, its SHA-256), sorted.

    """

    path: Path
    digest: str
    dependencies: tuple[tuple[str, str], ...]


def compiled_library(source: Path, key: str, definitions: tuple[str, ...] = ()) -> tuple[Path, str]:
    """The library of a law's or a twin's file (compiled now unless cached, with ``definitions``):
    (path, SHA-256 of its inputs, the headers it includes among them).
    """
    found = library(source, key, definitions)
    return found.path, found.digest


def dependencies(source: Path, key: str, definitions: tuple[str, ...] = ()) -> list[tuple[str, str]]:
    """The user's headers the file ``source`` includes, as (path, SHA-256): what a study records
    beside the file and sends to its workers with it. Compiled now unless cached; () when the
    compiled loop is not built (such a law is refused when it runs).
    """
    try:
        include_dir()
    except NNRobustError:
        return []
    folder = Path(os.path.abspath(source)).parent
    return [
        (os.path.normpath(folder / relative), digest)
        for relative, digest in library(source, key, definitions).dependencies
    ]


def compiled_inputs(source: Path) -> Library | None:
    """The library a run of the law in ``source`` ran (its present inputs' variant, never
    compiled here), or None: what a run's configuration records (config.toml_io).
    """
    try:
        include_dir()
        return library(source, "controller.class", compile=False)
    except (NNRobustError, OSError):
        return None


def _sha256(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


_verified: dict[str, tuple[int, int, int, str]] = {}
"""Library path -> (inode, size, mtime) when this process last found its SHA-256 as recorded, and
that SHA-256 (a sweep's runs ask for the same library again and again)."""


def _intact(path: Path, sha256: str) -> bool:
    """Whether the library file holds the bytes its manifest recorded (never a truncated or
    damaged file handed to dlopen: that ends the process with SIGBUS).
    """
    try:
        info = path.stat()
    except OSError:
        return False
    stamp = (info.st_ino, info.st_size, info.st_mtime_ns)
    if _verified.get(str(path)) == (*stamp, sha256):
        return True
    if _sha256(path) != sha256:
        return False
    _verified[str(path)] = (*stamp, sha256)
    return True


def _variants(manifest: Path) -> list[dict]:
    """The variants a manifest records (none when it is missing, unreadable or of another
    version: the law is then compiled again).
    """
    try:
        data = json.loads(manifest.read_text())
        if data.get("manifest") != MANIFEST or not isinstance(data.get("variants"), list):
            return []
        return [v for v in data["variants"] if isinstance(v, dict)]
    except (OSError, ValueError, AttributeError):
        return []


def _matching(variants: list[dict], base: Path, folder: Path, source: Path, warn: bool) -> Library | None:
    """The variant whose every recorded header still has its SHA-256 (ccache's direct mode) and
    whose library is intact; with ``warn``, a damaged library of a matching variant is said.
    """
    for variant in variants:
        try:
            deps = tuple((str(r), str(d)) for r, d in variant["dependencies"])
            path = folder / str(variant["library"])
            digest, sha256 = str(variant["digest"]), str(variant["sha256"])
        except (KeyError, TypeError, ValueError):
            continue
        if path.parent != folder or any(_sha256(base / r) != d for r, d in deps):
            continue
        if _intact(path, sha256):
            return Library(path, digest, deps)
        if warn:
            warnings.warn(
                f"the cached library of {source} in {folder} is damaged or missing (its bytes are not "
                "those recorded when it was compiled); compiling it again",
                stacklevel=3,
            )
    return None


def _read_depfile(path: Path, cwd: Path) -> list[Path]:
    """The prerequisites of a Make rule written by ``-MMD -MF`` (a backslash before an escaped
    space, ``$$`` a dollar sign), as absolute paths.
    """
    text = path.read_text().replace("\\\n", " ")
    _, _, rest = text.partition(": ")
    names, word, i = [], "", 0
    while i < len(rest):
        c = rest[i]
        if c == "\\" and i + 1 < len(rest) and rest[i + 1] in " #\\":
            word, i = word + rest[i + 1], i + 2
            continue
        if c == "$" and rest[i + 1 : i + 2] == "$":
            word, i = word + "$", i + 2
            continue
        if c.isspace():
            if word:
                names.append(word)
            word, i = "", i + 1
            continue
        word, i = word + c, i + 1
    if word:
        names.append(word)
    return [Path(os.path.normpath(cwd / name)) for name in names]


def library(source: Path, key: str, definitions: tuple[str, ...] = (), compile: bool = True) -> Library:
    """The library of a law's or a twin's file, compiled now unless a cached one was compiled from
    the same inputs. A manifest per file and toolchain (its primary key: the file's bytes, the
    definitions, the toolchain) lists the variants compiled so far, each with the headers the
    compiler read and their SHA-256 and the library's own SHA-256: a variant is used only when
    every header still has its SHA-256 and its library is intact; else the file is compiled
    again, into a new variant (a damaged library is replaced, with a warning). Without
    ``compile``, a file not compiled yet is a ConfigError.
    """
    source = Path(os.path.abspath(source))
    text = source.read_bytes()
    info = build_info()
    cxx = compiler(info)
    primary = hashlib.sha256(text + repr(definitions).encode() + _toolchain(cxx, info).encode()).hexdigest()
    folder = cache_dir()
    stem = "".join(c if c.isalnum() else "_" for c in source.stem)
    manifest = folder / f"{stem}-{primary[:20]}.json"
    found = _matching(_variants(manifest), source.parent, folder, source, warn=False)
    if found is not None:
        return found
    if not compile:
        raise ConfigError(key, f"{source} has no library compiled from its present inputs")
    folder.mkdir(parents=True, exist_ok=True)
    # one compile per file and toolchain on this machine: other processes (a sweep's workers) wait
    with open(manifest.with_suffix(".lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        variants = _variants(manifest)
        found = _matching(variants, source.parent, folder, source, warn=True)
        if found is not None:
            return found
        with tempfile.TemporaryDirectory(dir=folder, prefix=".compile-") as scratch:
            built, depfile = Path(scratch) / "law.so", Path(scratch) / "law.d"
            flags = ("-MMD", "-MF", str(depfile), "-MT", "law", *(f"-Wl,--wrap={c}" for c in EXIT_CALLS))
            done = subprocess.run(
                command(source, built, definitions=definitions, flags=flags),
                capture_output=True,
                text=True,
                timeout=1800,
                cwd=scratch,
            )
            if done.returncode != 0:
                lines = [line for line in done.stderr.splitlines() if line.strip()]
                shown = "\n".join(lines[:COMPILER_LINES])
                more = (
                    f"\n... ({len(lines) - COMPILER_LINES} more lines)" if len(lines) > COMPILER_LINES else ""
                )
                raise ConfigError(key, f"compiling {source} failed:\n{shown}{more}")
            installed = include_dir() / "nnrobust"
            deps = []
            for path in _read_depfile(depfile, Path(scratch)):
                if path == source or path.is_relative_to(installed):
                    continue
                sha256 = _sha256(path)
                if sha256 is None:
                    raise ConfigError(key, f"{source}: the header {path} it includes cannot be read")
                deps.append((os.path.relpath(path, source.parent), sha256))
            dependencies = tuple(sorted(set(deps)))
            listed = "".join(f"{r}\0{d}\n" for r, d in dependencies)
            digest = hashlib.sha256(f"{primary}\n{listed}".encode()).hexdigest()
            path = folder / f"{stem}-{digest[:20]}.so"
            sha256 = _sha256(built) or ""
            os.replace(built, path)  # atomic: a reader sees no library or the whole of it
        entry = {"digest": digest, "library": path.name, "sha256": sha256, "dependencies": dependencies}
        variants = [v for v in variants if v.get("digest") != digest] + [entry]
        tmp = manifest.with_name(f".{manifest.name}.{os.getpid()}")
        data = {"manifest": MANIFEST, "source": str(source), "variants": variants}
        tmp.write_text(json.dumps(data, indent=1))
        os.replace(tmp, manifest)  # atomic too: read without the lock
    return Library(path, digest, dependencies)


def _compiled_loop(key: str, path: Path, what: str):
    """The compiled loop's module, or one line naming ``key`` and the file: ``what`` (a law, a
    twin) in C++ runs on it.
    """
    try:
        from .. import _loop
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
    label = f"the law {name} ({path})"
    if (str(library), name) not in _loaded:
        twin = f"cpp:{name}:{digest[:16]}"
        try:
            signals, space = _loop.load_law_library(str(library), name, twin, label)
        except (RuntimeError, ValueError) as err:
            raise ConfigError(key, f"{path}: {err}") from err
        names = tuple(s.strip() for s in signals.split(",") if s.strip())
        _loaded[str(library), name] = (twin, names, declared_space(space, name, path, key))
    twin, signal_names, search_space = _loaded[str(library), name]
    _loop.name_law(twin, label)  # its errors name this file (another of the same content shares it)
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
            registered = _loop.load_twin_library(str(library), f"the twin file {path}")
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
    ({param: (low, high, unit)}); the tuner checks the bounds (nnrobust.studies.tune.space.custom_space).
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

    from .. import _loop

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
