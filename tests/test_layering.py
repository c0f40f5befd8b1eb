"""The layering of the package, enforced (docs/architecture: issue 36's floors).

Every module of nnrobust sits on a floor; a module may import its own floor and the floors below,
never above. Imports inside functions count (they are how a cycle hides); ``if TYPE_CHECKING:``
blocks do not (they never run). The floors, from the top:

    tool layer > studies > run folders > experiment > compiled/results > config > loop > rooms
    > model > leaf modules

The imports that still go up are listed in KNOWN, each with the number of places it occurs: a
new one fails this test, and so does a listed one that is gone (remove it from the list, so the
list only shrinks). ``results -> plots`` is the one exception the layering itself allows.
"""

import ast
from collections import Counter
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "nnrobust"

FLOORS = {
    "tool": ("cli", "__init__", "__main__"),
    "studies": ("sweep", "tune", "falsify", "study", "learning", "display", "export", "serve"),
    "run folders": ("run_folder", "run_deltas", "plots", "viewer", "study_folder", "properties", "paired"),
    "experiment": ("experiment", "presets"),
    "compiled/results": ("compiled", "results", "run_info", "verdicts"),
    "config": ("config",),
    "loop": ("simulation",),
    "rooms": ("controllers", "plant", "subtasks", "trajectories", "user_parts", "user_code", "native_law"),
    "model": ("model", "ik"),
    "leaf": ("exceptions", "numeric_limits", "arrays", "search_coordinates", "small_linalg", "kinds",
             "package_version", "key_checks", "progress", "signals",
             "forked", "twins", "shipped_files", "_loop", "_floor_loop", "drawing", "table_text"),
}  # fmt: skip
ORDER = list(FLOORS)[::-1]  # leaf first
FLOOR_OF = {unit: ORDER.index(floor) for floor, units in FLOORS.items() for unit in units}
ALLOWED = {("results", "plots")}

KNOWN: dict[tuple[str, str], int] = {
    # (importing unit, imported unit): places. Empty: add none.
}


def _unit(module: str) -> str:
    """nnrobust.controllers.laws.x -> controllers; nnrobust.cli -> cli."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _imports(path: Path) -> list[str]:
    """The nnrobust modules a file imports, anywhere but under ``if TYPE_CHECKING:``."""
    module = "nnrobust." + ".".join(path.relative_to(PACKAGE).with_suffix("").parts)
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
            out += [a.name for a in node.names if a.name.startswith("nnrobust")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("nnrobust"):
                if node.module is None or target == "nnrobust":  # from . import x: each name a module
                    out += [f"{target}.{a.name}" for a in node.names]
                else:
                    out.append(target)
    return out


def upward_imports() -> Counter:
    """(importing unit, imported unit) -> places, for every import that goes up a floor."""
    found: Counter = Counter()
    for path in PACKAGE.rglob("*.py"):
        mine = _unit("nnrobust." + ".".join(path.relative_to(PACKAGE).with_suffix("").parts))
        for target in _imports(path):
            theirs = _unit(target)
            if theirs == mine or theirs not in FLOOR_OF or (mine, theirs) in ALLOWED:
                continue
            if FLOOR_OF[theirs] > FLOOR_OF[mine]:
                found[(mine, theirs)] += 1
    return found


def test_every_unit_has_a_floor():
    units = {p.stem if p.is_file() else p.name for p in PACKAGE.iterdir() if not p.name.startswith(".")}
    units = {
        u
        for u in units
        if (PACKAGE / u).is_dir() and (PACKAGE / u / "__init__.py").exists() or u.isidentifier()
    }
    units -= {"preset_files", "sweep_files", "__pycache__", "urdf"}
    missing = sorted(u for u in units if u not in FLOOR_OF and not u.startswith("_loop"))
    assert not missing, f"give these a floor in FLOORS: {missing}"


def test_no_import_goes_up_a_floor_beyond_the_known_ones():
    found = upward_imports()
    new = {pair: n for pair, n in found.items() if pair not in KNOWN}
    assert not new, f"imports that go up a floor (importer, imported): places -- {new}"
    over = {pair: n for pair, n in found.items() if pair in KNOWN and n > KNOWN[pair]}
    assert not over, f"more places than known: {over}"
    gone = sorted(pair for pair in KNOWN if pair not in found)
    assert not gone, f"fixed, so remove from KNOWN: {gone}"


def test_the_architecture_page_lists_the_floors_the_test_enforces():
    """docs/architecture.md's table of floors names every unit of FLOORS on its floor, in order
    (the package face stands for ``__init__`` and ``__main__``; C++ modules are not listed)."""
    import re

    text = (PACKAGE.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    table = text[text.index("| floor | units |") :].split("\n\n")[0].splitlines()[2:]
    written = {}
    for row in table:
        floor, units = (cell.strip() for cell in row.strip("|").split("|"))
        written[floor] = {u.strip("/") for u in re.findall(r"`([^`]+)`", units)}
        if "the package face" in units:
            written[floor] |= {"__init__", "__main__"}
    assert list(written) == list(FLOORS)
    for floor, units in FLOORS.items():
        assert written[floor] == {u for u in units if not u.startswith("_loop") and u != "_floor_loop"}, floor


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
