"""The layering of the package, read from its folders (docs/architecture.md's floors).

Every module's unit is the folder it sits in: ``nnrobust/<unit>/...``, or, under ``studies/``,
``studies/<unit>/...`` (the study commands' shared base and each command are units of their own).
The floors are one bottom-first list (:data:`FLOORS`); a unit may import its own unit and the
floors below it, never a floor above, and never a sibling on its own floor (sweep, tune, falsify
and learning stand side by side on the base: what two of them need goes down into the base).
Imports inside functions count (they are how a cycle hides); ``if TYPE_CHECKING:`` blocks do not
(they never run), and there is no exception (:data:`ALLOWED` is empty: a notebook's figures of a
run are registered by the front door, not imported by ``run/``). No private name (``_name``) is
imported from another unit, the compiled extension aside; no module is longer than
:data:`MAX_LINES` and no function longer than :data:`MAX_FUNCTION` but the ones
:data:`LONG_FUNCTIONS` names, a list that may only shrink.
"""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "nnrobust"

FLOORS = [
    ["core"],
    ["plugins"],
    ["model"],
    ["plant", "subtasks", "trajectories"],
    ["controllers"],
    ["config"],
    ["run"],
    ["outputs"],
    ["studies/base"],
    ["studies/sweep", "studies/tune", "studies/falsify", "studies/learning", "studies/identify"],
    ["studies/study"],
    ["cli"],
    ["__init__", "__main__"],
]
"""The floors, bottom first: each a list of the units (folders) that stand on it side by side."""

EXTENSIONS = ("_loop", "_floor_loop")
"""The compiled extension modules at the top of the package (below every floor)."""

DATA_FOLDERS = {"preset_files", "sweep_files", "include", "urdf"}
"""Folders of the package that hold data, not modules (include/ and urdf/ are installed by CMake)."""

FLOOR_OF = {unit: i for i, units in enumerate(FLOORS) for unit in units} | {e: -1 for e in EXTENSIONS}
ALLOWED: set[tuple[str, str]] = set()
"""Imports allowed up a floor: none (the issue's one allowed exception, run -> outputs for
``Result._repr_html_``'s figures, is gone: the front door registers them with IPython)."""

MAX_LINES = 800
MAX_FUNCTION = 150
LONG_FUNCTIONS = {
    # module:function -> lines; may only shrink (remove an entry once it is short)
    "run/simulation.py:simulate": 169,  # the Python loop of eqs. (9)-(18), one step inline
}


def unit_of(module: str) -> str:
    """nnrobust.studies.sweep.engine -> studies/sweep; nnrobust.run.results -> run; nnrobust -> __init__."""
    parts = module.split(".")[1:]
    if not parts:
        return "__init__"
    if parts[0] in EXTENSIONS:
        return parts[0]
    if parts == ["studies"]:  # the face of the studies' folder stands on their base
        return "studies/base"
    for k in range(len(parts), 0, -1):
        unit = "/".join(parts[:k])
        if unit in FLOOR_OF:
            return unit
    return "?" + "/".join(parts)


def module_of(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(["nnrobust", *parts])


def _imports(path: Path) -> list[tuple[str, str | None, int]]:
    """(module, imported name or None, line) of every nnrobust import of a file, anywhere but under
    ``if TYPE_CHECKING:``."""
    module = module_of(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skipped = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skipped.update(id(n) for child in node.body for n in ast.walk(child))
    out = []
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.Import):
            out += [(a.name, None, node.lineno) for a in node.names if a.name.startswith("nnrobust")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("nnrobust"):
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    if alias.name in EXTENSIONS:
                        out.append((sub, None, node.lineno))
                        continue
                    is_module = (PACKAGE.parent / sub.replace(".", "/")).with_suffix(".py").exists() or (
                        PACKAGE.parent / sub.replace(".", "/") / "__init__.py"
                    ).exists()
                    out.append((sub, None, node.lineno) if is_module else (target, alias.name, node.lineno))
    return out


def _edges():
    """(importing unit, imported unit, file, line, name) of every import between two units."""
    for path in sorted(PACKAGE.rglob("*.py")):
        mine = unit_of(module_of(path))
        for target, name, line in _imports(path):
            theirs = unit_of(target)
            if theirs != mine:
                yield mine, theirs, str(path.relative_to(PACKAGE)), line, name


def test_the_top_of_the_package_is_its_floors():
    """The top of nnrobust/ is the front door, the data folders and one package per floor."""
    top = {p.name for p in PACKAGE.iterdir() if not p.name.startswith((".", "__pycache__"))}
    top = {n for n in top if not n.startswith(EXTENSIONS)}  # the compiled modules
    floors = {unit.split("/")[0] for units in FLOORS for unit in units} - {"__init__", "__main__"}
    expected = {"__init__.py", "__main__.py", *DATA_FOLDERS, *floors}
    assert top <= expected and floors <= top, (sorted(top - expected), sorted(floors - top))


def test_every_module_has_a_unit():
    unknown = sorted(
        {str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py") if unit_of(module_of(p)).startswith("?")}
    )
    assert not unknown, f"give these a unit in FLOORS: {unknown}"


def test_no_import_goes_up_a_floor():
    up = [e for e in _edges() if FLOOR_OF[e[1]] > FLOOR_OF[e[0]] and (e[0], e[1]) not in ALLOWED]
    assert not up, f"imports that go up a floor (importer, imported, file, line): {up}"
    used = {(e[0], e[1]) for e in _edges()}
    assert ALLOWED <= used, f"the allowed exception is gone: remove it from ALLOWED ({ALLOWED - used})"


def test_siblings_never_import_each_other():
    side = [e for e in _edges() if FLOOR_OF[e[1]] == FLOOR_OF[e[0]] and e[1] not in EXTENSIONS]
    assert not side, f"imports between units of one floor (what both need goes into the floor below): {side}"


def test_no_private_name_crosses_a_unit():
    crossing = [
        e
        for e in _edges()
        if e[4] and e[4].startswith("_") and not e[4].startswith("__") and e[1] not in EXTENSIONS
    ]
    assert not crossing, (
        f"private names imported from another unit (make them public in a shared base): {crossing}"
    )


def test_modules_and_functions_are_sizes_a_reader_can_hold():
    long_modules, long_functions = [], {}
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        lines = text.count("\n")
        if lines > MAX_LINES:
            long_modules.append((str(path.relative_to(PACKAGE)), lines))
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                size = node.end_lineno - node.lineno + 1
                if size > MAX_FUNCTION:
                    long_functions[f"{path.relative_to(PACKAGE)}:{node.name}"] = size
    assert not long_modules, f"modules over {MAX_LINES} lines: {long_modules}"
    new = {k: v for k, v in long_functions.items() if k not in LONG_FUNCTIONS or v > LONG_FUNCTIONS[k]}
    assert not new, f"functions over {MAX_FUNCTION} lines (or longer than listed): {new}"
    gone = sorted(k for k in LONG_FUNCTIONS if k not in long_functions)
    assert not gone, f"no longer long, so remove from LONG_FUNCTIONS: {gone}"


COMMENTED_LOCAL_IMPORTS = ("model", "plant", "subtasks", "trajectories", "controllers", "config")
"""Where an import inside a function must say why it is there (a comment on its lines or above)."""


def test_an_import_inside_a_function_of_a_room_or_config_says_why():
    """The rooms and config/ import at the top; an import left inside a function (a cycle it
    unties, a slow package imported on first use) carries a comment saying so."""
    silent = []
    for unit in COMMENTED_LOCAL_IMPORTS:
        for path in sorted((PACKAGE / unit).rglob("*.py")):
            lines = path.read_text(encoding="utf-8").splitlines()
            for function in ast.walk(ast.parse("\n".join(lines))):
                if not isinstance(function, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    continue
                for node in ast.walk(function):
                    if not isinstance(node, (ast.Import, ast.ImportFrom)):
                        continue
                    said = lines[node.lineno - 2 : node.end_lineno]
                    if not any("#" in line for line in said):
                        silent.append(f"{path.relative_to(PACKAGE)}:{node.lineno}")
    assert not silent, f"imports inside functions with no comment saying why (hoist, or say why): {silent}"


def test_the_architecture_page_lists_the_floors_the_test_enforces():
    """docs/architecture.md's table of floors names, from the top, every unit of FLOORS on its floor
    (each unit as its folder, ``name/``; the package face stands for ``__init__`` and ``__main__``)."""
    import re

    text = (PACKAGE.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    table = text[text.index("| floor | units |") :].split("\n\n")[0].splitlines()[2:]
    written = []
    for row in table:
        floor, units = (cell.strip() for cell in row.strip("|").split("|"))
        found = {u.strip("/") for u in re.findall(r"`([^`]+/)`", units)}
        if "the package face" in units:
            found |= {"__init__", "__main__"}
        written.append(found)
    assert written[::-1] == [set(units) for units in FLOORS]


ROOM_FACES = {
    "model": "from .nominal import build_nominal_model",
    "plant": "from .build import build_plant",
    "subtasks": "from .build import build_criterion",
    "trajectories": "from .build import build_trajectory",
    "controllers": "from .build import build_controller",
}
"""Each room's builder, as its package face would import it."""

SCRATCH_IMPORT = """
import sys
sys.meta_path = [f for f in sys.meta_path if "editable" not in type(f).__module__]
sys.path.insert(0, {scratch!r})
import {first}
import nnrobust.config
import nnrobust
assert nnrobust.__file__.startswith({scratch!r}), nnrobust.__file__
print("imported", {first!r})
"""


def test_every_room_face_may_import_its_builder_and_section(tmp_path):
    """Issue 36: in a scratch copy of the package, every room's package face imports its own
    builder and section; then importing the configuration (or a room first) still works: no room
    needs the configuration, so no cycle hides behind the faces' discipline."""
    import shutil
    import subprocess
    import sys

    scratch = tmp_path / "scratch"
    shutil.copytree(PACKAGE, scratch / "nnrobust", ignore=shutil.ignore_patterns("__pycache__"))
    for room, line in ROOM_FACES.items():
        face = scratch / "nnrobust" / room / "__init__.py"
        face.write_text(face.read_text(encoding="utf-8") + f"\n{line}\nfrom .section import *  # noqa\n")
    for first in ("nnrobust.config", *(f"nnrobust.{room}" for room in ROOM_FACES)):
        code = SCRATCH_IMPORT.format(scratch=str(scratch), first=first)
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0 and f"imported {first}" in done.stdout, (first, done.stderr[-2000:])


THEMED = {
    "test_docs_build.py",  # the docs site builds, every export documented
    "test_examples.py",  # examples/ run as a user runs them
    "test_fuzz.py",  # mutated experiment files, URDFs and signals at random instants
    "test_hard_conditions.py",  # stiff, singular and saturated runs
    "test_hostile_input.py",  # docs/bad-inputs.md: each hostile input and its one line
    "test_layering.py",  # this file
    "test_long_runs.py",  # long simulations
    "test_presets_any_arm.py",  # every preset on every arm known to work
    "test_readme.py",  # README.md's commands
}
"""The themed suites, at the top of tests/: each spans the package. Every other test file sits in
the folder of the package it tests, tests/<package>/test_<module or package>.py."""

THEMED_FOLDERS = {
    "docs_numbers",  # every number of README.md and docs/, one file per page: test_<page>.py
}
"""Themed suites of several files, each a folder at the top of tests/."""


def test_the_tests_mirror_the_tree():
    tests = PACKAGE.parent / "tests"
    assert {p.name for p in tests.glob("test_*.py")} == THEMED
    astray = []
    for path in sorted(tests.rglob("test_*.py")):
        rel = path.relative_to(tests)
        if rel.parts[0] in THEMED_FOLDERS:
            continue
        if len(rel.parts) > 1 and not PACKAGE.joinpath(*rel.parts[:-1]).is_dir():
            astray.append(str(rel))
    assert not astray, f"test files outside a folder of the package's tree: {astray}"
