"""Export a control law out of Python (``nnrobust export``, docs/export.md).

An exported law is the compiled twin of an experiment's controller, the same C++ code the compiled
loop runs (csrc/controllers/, csrc/model/, csrc/subtasks/, csrc/trajectories/), as a shared library
with a C header (csrc/export/nnrobust_law.h) and a CMake package: ``nnrobust_law_create()``,
``nnrobust_law_step(law, t, q, v, tau)``, ``nnrobust_law_destroy(law)``. Its settings and its
nominal model travel as numbers in a text description (every number in C's exact hexadecimal
notation) compiled into ``libnnrobust_law``; the code is ``libnnrobust_core``, built with the
package, next to the Pinocchio libraries it links (copied from the pin wheel): no Python, no URDF
parser at run time.

The folder it writes::

    include/nnrobust_law.h            the C API
    lib/libnnrobust_law.so            the law (its description) -> libnnrobust_core.so -> Pinocchio
    bin/replay, bin/drive             the examples, built
    lib/cmake/nnrobust_law/           find_package(nnrobust_law): target nnrobust_law::nnrobust_law
    src/law_data.c                    the source of libnnrobust_law (the description as a string)
    law.description                   the description itself (nnrobust_law_create_from reads it)
    include/protocol.h                the virtual robot's protocol (nnrobust serve, docs/serve.md)
    example/                          replay.c: measured states in, torques out; drive.c: the
                                      controller of a virtual robot
    config.toml, export.json          the experiment it came from; what was written, with SHA-256s
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path
from urllib.parse import quote

from ...core.exceptions import NNRobustError

FORMAT = "nnrobust-law 1"
"""The first line of a description, read by csrc/export/law_api.cpp."""

MARKER = "export.json"
"""The file that makes a folder an export (``--overwrite`` replaces only such folders)."""

_PARAM_MAPS = (
    "nominal_params",
    "nominal_friction",
    "path_params",
    "pose_params",
    "law_params",
    "robust_params",
)
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*\Z")


def _number(x) -> str:
    """A float64 exactly, as C's strtod reads it (hexadecimal; inf, -inf, nan)."""
    return float(x).hex()


def _text(s: str) -> str:
    """A string as one token: '=' then its percent-encoding (so "" is "=")."""
    return "=" + quote(s, safe="")


def _matrix_line(key: str, x) -> str:
    import numpy as np

    x = np.atleast_2d(np.asarray(x, dtype=float))
    if x.ndim != 2:
        raise NNRobustError(f"export: the field {key} has {x.ndim} dimensions; the law's fields are matrices")
    return f"mat {key} {x.shape[0]} {x.shape[1]} " + " ".join(_number(v) for v in x.ravel())


def _vector_line(key: str, x) -> str:
    import numpy as np

    x = np.asarray(x, dtype=float).ravel()
    return f"vec {key} {x.size} " + " ".join(_number(v) for v in x)


def _params_lines(prefix: str, params: dict) -> list[str]:
    lines = []
    for name in sorted(params):
        if not _NAME.match(name):
            raise NNRobustError(f"export: the field name {name!r} of {prefix} is not an identifier")
        lines.append(_matrix_line(f"{prefix}/{name}", params[name]))
    return lines


ABSURD_COMMAND = 10.0
"""A step whose command exceeds a joint's effort limit this many times returns status 2."""

ABSURD_COMMAND_WITHOUT_LIMIT = 1e6
"""[N m or N] The bound of a joint without an effort limit (no actuator comes near it)."""

ABSURD_POSITION = 1e6
"""[rad or m] The bound on the measured position of a joint without a range (a continuous one)."""


def absurd_bounds(setup) -> dict:
    """What a step's status 2 compares against (docs/export.md#absurd-values): per joint, the
    command bound, ABSURD_COMMAND times its effort limit (the plant's, else the URDF's; without
    one ABSURD_COMMAND_WITHOUT_LIMIT), and the range of a plausible measured position, the joint's
    range widened by its width on each side (without one, +-ABSURD_POSITION).
    """
    import numpy as np

    robot = setup.robot
    effort = setup.plant.torque_limit if setup.plant.torque_limit is not None else robot.effort_limits
    effort = np.asarray(effort, dtype=float)
    bound = np.where(
        np.isfinite(effort) & (effort > 0), ABSURD_COMMAND * effort, ABSURD_COMMAND_WITHOUT_LIMIT
    )
    lower, upper = np.asarray(robot.lower_limits, float), np.asarray(robot.upper_limits, float)
    width = upper - lower
    ranged = (
        np.isfinite(width)
        & (width > 0)
        & (np.abs(lower) < ABSURD_POSITION)
        & (np.abs(upper) < ABSURD_POSITION)
    )
    return {
        "command_bound": bound,
        "measured_lower": np.where(ranged, lower - width, -ABSURD_POSITION),
        "measured_upper": np.where(ranged, upper + width, ABSURD_POSITION),
    }


def description(
    spec, model, n: int, comments: tuple[str, ...] | list[str] = (), bounds: dict | None = None
) -> str:
    """The text description of a compiled controller (LoopSpec ``spec`` with its law's fields, the
    nominal model's ModelSpec ``model`` or None) that csrc/export/law_api.cpp rebuilds it from;
    with ``bounds`` (:func:`absurd_bounds`), what its step refuses as absurd (status 2).
    """
    lines = [FORMAT, *(f"# {c}" for c in comments)]
    lines += [
        f"int n {n}",
        f"int m {spec.m}",
        f"num period {_number(spec.period)}",
        f"str nominal {_text(spec.nominal)}",
        f"str path {_text(spec.path)}",
        f"int pose {int(spec.pose)}",
        f"str law {_text(spec.law)}",
        f"int law_signals {spec.law_signals}",
        f"str robust {_text(spec.robust)}",
        f"num pinv_threshold {_number(spec.pinv_threshold)}",
        f"num pinv_max_damping {_number(spec.pinv_max_damping)}",
        _vector_line("z0", spec.z0),
        *(_vector_line(name, values) for name, values in (bounds or {}).items()),
    ]
    for name in _PARAM_MAPS:
        lines += _params_lines(name, getattr(spec, name))
    criteria = list(spec.criteria)
    lines.append(f"strs criteria {len(criteria)} " + " ".join(_text(c) for c in criteria))
    for i, params in enumerate(spec.criterion_params):
        lines += _params_lines(f"criterion_params/{i}", params)
    if criteria:
        lines.append(_vector_line("criterion_weights", spec.criterion_weights))
    if model is not None:
        lines += [
            f"strs model/joint_types {len(model.joint_types)} "
            + " ".join(_text(t) for t in model.joint_types),
            f"strs model/joint_names {len(model.joint_names)} "
            + " ".join(_text(t) for t in model.joint_names),
            f"ints model/parents {len(model.parents)} " + " ".join(str(int(p)) for p in model.parents),
            _matrix_line("model/axes", model.axes),
            _matrix_line("model/rotations", model.rotations),
            _matrix_line("model/translations", model.translations),
            _matrix_line("model/inertias", model.inertias),
            _vector_line("model/armature", model.armature),
            _vector_line("model/gravity", model.gravity),
            f"str model/frame_name {_text(model.frame_name)}",
            f"int model/frame_joint {int(model.frame_joint)}",
            _matrix_line("model/frame_rotation", model.frame_rotation),
            _vector_line("model/frame_translation", model.frame_translation),
        ]
    return "\n".join(lines) + "\n"


def core_library() -> Path:
    """libnnrobust_core, built and installed with the package (CMakeLists.txt)."""
    from ...run import compiled

    if not compiled.available():
        raise NNRobustError(f"export needs the compiled backend: {compiled.unavailable_reason()}")
    from ... import _loop

    core = Path(_loop.__file__).parent / "libnnrobust_core.so"
    if not core.is_file():
        raise NNRobustError(
            f"{core} is missing: the package was built without it; reinstall nnrobust (make .venv/.installed)"
        )
    return core


def c_header(name: str = "nnrobust_law.h") -> Path:
    """A header an export ships (the law's C API, nnrobust_law.h; the virtual robot's protocol,
    protocol.h): installed with the package, or in csrc/ in a checkout.
    """
    package = Path(__file__).resolve().parents[2]  # nnrobust/
    for candidate in (
        package / "include" / name,
        package.parent / "csrc" / "export" / name,
        package.parent / "csrc" / "serve" / name,
    ):
        if candidate.is_file():
            return candidate
    raise NNRobustError(f"{name} is missing (looked in {package / 'include'}); reinstall nnrobust")


def bundled_libraries(core: Path) -> dict[str, Path]:
    """The shared libraries libnnrobust_core needs that are not the system's (Pinocchio and its
    dependencies from the pin wheel), by the name the loader looks for.
    """
    try:
        listing = subprocess.run(
            ["ldd", str(core)], capture_output=True, text=True, check=True, timeout=60
        ).stdout
    except (OSError, subprocess.SubprocessError) as err:
        raise NNRobustError(f"export: could not list the libraries {core} needs with ldd ({err})") from err
    system = ("/lib/", "/lib64/", "/usr/lib/", "/usr/lib64/", "/usr/local/lib/")
    found = {}
    for line in listing.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[1] == "=>":
            if parts[2] == "not":
                raise NNRobustError(f"export: {core} needs {parts[0]}, which the loader cannot find")
            path = Path(parts[2])
            if not str(path.resolve()).startswith(system):
                found[parts[0]] = path
    return found


def c_compiler() -> str:
    """The C compiler (CC, else cc, gcc or clang on PATH)."""
    for name in (os.environ.get("CC", ""), "cc", "gcc", "clang"):
        if name and shutil.which(name.split()[0]):
            return name
    raise NNRobustError(
        "export: no C compiler found (set CC, or install cc); --no-build writes the sources only"
    )


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


LAW_DATA = """/* The law exported by `nnrobust export` from {name}: its description (law.description),
 * compiled into libnnrobust_law (docs/export.md). Generated; do not edit. */
#include "nnrobust_law.h"

static const char description[] =
{literal};

NNROBUST_LAW_API nnrobust_law *nnrobust_law_create(void) {{ return nnrobust_law_create_from(description); }}
"""

NATIVE_LAW_DATA = """/* The law exported by `nnrobust export` from {name}: its description (law.description)
 * and the user's law {cls} of src/{source}, compiled together into libnnrobust_law (docs/export.md).
 * Generated; do not edit. */
#include "nnrobust_law.h"

static const char description[] =
{literal};

/* the factory NNROBUST_USER_LAW({cls}, ...) defines in src/{source} (its address only) */
extern void nnrobust_law_factory_{cls}(void);

NNROBUST_LAW_API nnrobust_law *nnrobust_law_create(void) {{
  if (nnrobust_law_add_native("{twin}", nnrobust_law_factory_{cls}) != 0) return 0;
  return nnrobust_law_create_from(description);
}}
"""

CMAKE_CONFIG = """# find_package(nnrobust_law): the law exported by `nnrobust export` (docs/export.md) as
# the imported target nnrobust_law::nnrobust_law (its header, libnnrobust_law, libnnrobust_core).
get_filename_component(_nnrobust_law_prefix "${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
if(NOT TARGET nnrobust_law::nnrobust_law)
  add_library(nnrobust_law::core SHARED IMPORTED)
  set_target_properties(nnrobust_law::core PROPERTIES
    IMPORTED_LOCATION "${_nnrobust_law_prefix}/lib/libnnrobust_core.so"
    IMPORTED_SONAME "libnnrobust_core.so")
  add_library(nnrobust_law::nnrobust_law SHARED IMPORTED)
  set_target_properties(nnrobust_law::nnrobust_law PROPERTIES
    IMPORTED_LOCATION "${_nnrobust_law_prefix}/lib/libnnrobust_law.so"
    IMPORTED_SONAME "libnnrobust_law.so"
    INTERFACE_INCLUDE_DIRECTORIES "${_nnrobust_law_prefix}/include"
    INTERFACE_LINK_LIBRARIES nnrobust_law::core)
endif()
set(nnrobust_law_FOUND TRUE)
"""

EXAMPLE_CMAKE = """cmake_minimum_required(VERSION 3.18)
project(nnrobust_law_examples LANGUAGES C)
# cmake -S example -B build -DCMAKE_PREFIX_PATH=<the export folder>
find_package(nnrobust_law REQUIRED)
add_executable(replay replay.c)  # measured states in, torques out
target_link_libraries(replay PRIVATE nnrobust_law::nnrobust_law)
add_executable(drive drive.c)  # the controller of a virtual robot (nnrobust serve)
target_link_libraries(drive PRIVATE nnrobust_law::nnrobust_law)
add_executable(time_step time_step.c)  # the step timed, its heap allocations counted
target_link_libraries(time_step PRIVATE nnrobust_law::nnrobust_law)
"""


def _c_literal(text: str) -> str:
    """``text`` as a C string literal, one source line per line of text."""
    out = []
    for line in text.splitlines(keepends=True):
        escaped = line.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        out.append(f'    "{escaped}"')
    return "\n".join(out) or '    ""'


EXAMPLES = ("replay", "drive", "time_step")
"""The example programs an export ships (example/NAME.c) and builds (bin/NAME)."""


def example_source(name: str) -> str:
    """An example program shipped with an export: replay.c (states in, torques out), drive.c
    (the controller of a virtual robot, docs/serve.md) or time_step.c (the step timed, its heap
    allocations counted).
    """
    return (Path(__file__).resolve().parent / name).read_text(encoding="utf-8")


def build_law_library(folder: Path, compiler: str, native: str | None = None) -> None:
    """Compile src/law_data.c into lib/libnnrobust_law.so against lib/libnnrobust_core.so (with
    the user's law src/``native`` for a law in C++), and the example programs into bin/ (their run
    path: ../lib, wherever the folder is moved).
    """
    lib = folder / "lib"
    link = ["-L", str(lib), "-lnnrobust_core", "-Wl,-soname,libnnrobust_law.so", "-Wl,-rpath,$ORIGIN"]
    data = ["-I", str(folder / "include"), str(folder / "src" / "law_data.c")]
    if native is None:
        command = [*compiler.split(), "-O2", "-fPIC", "-shared", "-fvisibility=hidden", *data, *link]
        _compile([*command, "-o", str(lib / "libnnrobust_law.so")], compiler, "src/law_data.c")
    else:
        _build_native(folder, compiler, native, data, link)
    (folder / "bin").mkdir(exist_ok=True)
    for program in EXAMPLES:  # the examples, built: bin/replay, bin/drive, bin/time_step
        source = str(folder / "example" / f"{program}.c")
        _compile(
            [*compiler.split(), "-O2", "-I", str(folder / "include"), source, "-L", str(folder / "lib"),
             "-lnnrobust_law", "-lnnrobust_core", "-Wl,-rpath,$ORIGIN/../lib",
             "-o", str(folder / "bin" / program)],
            compiler, f"example/{program}.c",
        )  # fmt: skip


def _build_native(folder: Path, compiler: str, native: str, data: list[str], link: list[str]) -> None:
    """libnnrobust_law of a law in C++: law_data.c and the user's file src/``native``, compiled
    as the compiled loop compiles it (nnrobust.plugins.native_law.command) and linked against the core,
    the Pinocchio library the export ships, and the core's allocator wrappers (the same --wrap
    options as the core: the user's step allocates from the law's arena too).
    """
    from ...plugins.native_law import build_info, command

    wrapped = [f"-Wl,--wrap={name}" for name in build_info().get("wrapped", "").split(";") if name]
    pinocchio = sorted((folder / "lib").glob("libpinocchio_default.so*"))
    with tempfile.TemporaryDirectory() as scratch:
        data_object = Path(scratch) / "law_data.o"
        _compile(
            [*compiler.split(), "-O2", "-fPIC", "-c", *data, "-o", str(data_object)],
            compiler,
            "src/law_data.c",
        )
        cxx = command(
            folder / "src" / native,
            folder / "lib" / "libnnrobust_law.so",
            [str(data_object), *link, *map(str, pinocchio[:1]), *wrapped],
        )
        _compile(cxx, cxx[0], f"src/{native}")


def _copy_headers(native: Path, folder: Path) -> None:
    """The headers a law in C++ includes (the compile's dependency list, nnrobust.plugins.native_law),
    copied beside its file in ``folder``/src at the same relative paths: the export compiles them
    with it, wherever the folder goes. One that would land outside the folder is refused.
    """
    from ...plugins.native_law import dependencies

    for header, _ in dependencies(native, "controller.class"):
        relative = os.path.relpath(header, native.parent)
        target = Path(os.path.normpath(folder / "src" / relative))
        if not target.is_relative_to(folder):
            raise NNRobustError(
                f"export: {native} includes {header}, outside its folder by more than the export's "
                "src/ would hold; keep the headers a law includes in its folder (or below it)"
            )
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(header, target)


def _compile(command: list[str], compiler: str, what: str) -> None:
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=600)
    except (OSError, subprocess.SubprocessError) as err:
        raise NNRobustError(f"export: {compiler} could not be run ({err})") from err
    if done.returncode != 0:
        raise NNRobustError(f"export: {compiler} failed on {what}:\n{done.stderr.strip()}")


def recorded_steps(config, duration: float | None = None):
    """A compiled run of ``config`` as an exported law sees it: (inputs, torques), one row per
    control instant, inputs = (t, measured q, measured v) and torques = what the compiled law
    commanded there (and the loop applied). Replaying the inputs through the export must give the
    torques (tests/outputs/test_export.py, benchmarks/export_step.py).
    """
    import numpy as np

    from ...controllers.laws.policy import ACTIONS
    from ...run.compiled import stepped_loop
    from ...run.experiment import build as build_setup

    residual = ACTIONS.index("residual")
    setup = build_setup(config)
    loop, _ = stepped_loop(setup, config.simulation.duration if duration is None else duration)
    inputs, torques = [], []
    zero = np.zeros(setup.plant.nq)
    while loop.running:
        inputs.append(np.concatenate([[loop.time], loop.measured_q, loop.measured_v]))
        torques.append(np.array(loop.control().tau))
        loop.act(zero, residual)  # the law's own command (and state update), plus nothing
    return np.array(inputs), np.array(torques)


def export_law(config, out: str | Path, *, overwrite: bool = False, build: bool = True) -> dict:
    """Write the export of ``config``'s controller into the folder ``out`` (atomically: a
    half-written export is never left under that name); returns export.json's contents.
    """
    from ...config import controller_label
    from ...core.package_version import package_version
    from ...run.compiled import law_spec
    from ...run.experiment import build as build_setup

    folder = Path(out)
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        if not overwrite:
            raise NNRobustError(f"{folder} exists; pass --overwrite to replace it")
        if not (folder / MARKER).is_file():
            raise NNRobustError(f"{folder} is not an export (no {MARKER}); --overwrite replaces only exports")
    core = core_library()
    compiler = c_compiler() if build else ""
    setup = build_setup(config)
    spec, model = law_spec(setup)
    native = getattr(type(setup.controller), "native_source", None)  # a law in C++ of the user's
    n = int(setup.plant.nq)
    label = controller_label(config)
    text = description(
        spec,
        model,
        n,
        [
            f"{config.name}: controller {label}, law {spec.law}, nominal model {spec.nominal}",
            f"written by nnrobust {package_version()}",
        ],
        absurd_bounds(setup),
    )
    folder.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))
    try:
        for sub in ("include", "lib/cmake/nnrobust_law", "src", "example"):
            (tmp / sub).mkdir(parents=True)
        shutil.copyfile(c_header(), tmp / "include" / "nnrobust_law.h")
        (tmp / "law.description").write_text(text, encoding="utf-8")
        if native is None:
            law_data = LAW_DATA.format(name=config.name, literal=_c_literal(text))
        else:
            shutil.copyfile(native, tmp / "src" / native.name)
            _copy_headers(native, tmp)
            law_data = NATIVE_LAW_DATA.format(
                name=config.name, literal=_c_literal(text), cls=type(setup.controller).__name__,
                source=native.name, twin=spec.law,
            )  # fmt: skip
        (tmp / "src" / "law_data.c").write_text(law_data, encoding="utf-8")
        shutil.copyfile(core, tmp / "lib" / "libnnrobust_core.so")
        for name, path in bundled_libraries(core).items():
            shutil.copyfile(path, tmp / "lib" / name)
        (tmp / "lib" / "cmake" / "nnrobust_law" / "nnrobust_law-config.cmake").write_text(
            CMAKE_CONFIG, encoding="utf-8"
        )
        shutil.copyfile(c_header("protocol.h"), tmp / "include" / "protocol.h")
        for example in EXAMPLES:
            (tmp / "example" / f"{example}.c").write_text(example_source(f"{example}.c"), encoding="utf-8")
        (tmp / "example" / "CMakeLists.txt").write_text(EXAMPLE_CMAKE, encoding="utf-8")
        (tmp / "config.toml").write_text(config.to_toml(), encoding="utf-8")
        if build:
            build_law_library(tmp, compiler, None if native is None else native.name)
        info = {
            "format": "nnrobust-export 1",
            "nnrobust": package_version(),
            "experiment": config.name,
            "controller": label,
            "law": spec.law,
            "law_source": None if native is None else f"src/{native.name}",
            "robust_term": spec.robust,
            "nominal_model": spec.nominal,
            "joints": n,
            "task_rows": int(spec.m),
            "period": float(spec.period),
            "state_size": int(len(spec.z0)),
            "built": build,
            "compiler": compiler,
            "files": {str(p.relative_to(tmp)): _sha256(p) for p in sorted(tmp.rglob("*")) if p.is_file()},
        }
        (tmp / MARKER).write_text(json.dumps(info, indent=2) + "\n", encoding="utf-8")
        if folder.exists():
            old = folder.with_name(f".{folder.name}.old")
            shutil.rmtree(old, ignore_errors=True)
            folder.rename(old)
            tmp.rename(folder)
            shutil.rmtree(old, ignore_errors=True)
        else:
            tmp.rename(folder)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return info


def time_steps(folder: str | Path, inputs, repeats: int = 3, prefix: list[str] | tuple = ()) -> dict | None:
    """The exported law of ``folder`` stepped through ``inputs`` (rows t, q, v: recorded_steps)
    ``repeats`` times by its bin/time_step, out of Python: steps, heap allocations per step (every
    call to the malloc family in the process during the steps) and the step's time p50, p99 and
    max [us]. ``prefix`` runs it under another command (``chrt -f 80``); None when that command
    refuses (no permission for real-time scheduling).
    """
    import numpy as np

    program = Path(folder) / "bin" / "time_step"
    if not program.is_file():
        raise NNRobustError(f"{program} is missing: export without --no-build to time the law")
    with tempfile.TemporaryDirectory() as scratch:
        data = Path(scratch) / "inputs.bin"
        np.ascontiguousarray(inputs, dtype=np.float64).tofile(data)
        try:
            done = subprocess.run(
                [*prefix, str(program), str(data), str(repeats)], capture_output=True, text=True, timeout=3600
            )
        except (OSError, subprocess.SubprocessError) as err:
            raise NNRobustError(f"{program} could not be run ({err})") from err
    if done.returncode != 0:
        if prefix:
            return None
        raise NNRobustError(f"{program} failed: {done.stderr.strip()}")
    steps, allocations, *times = (int(x) for x in done.stdout.split())
    ns = np.array(times, dtype=float)
    return {
        "steps": steps,
        "allocations_per_step": allocations / steps,
        "p50_us": float(np.percentile(ns, 50)) / 1e3,
        "p99_us": float(np.percentile(ns, 99)) / 1e3,
        "max_us": float(ns.max()) / 1e3,
    }
