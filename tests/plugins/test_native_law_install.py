"""A law in C++ compiles wherever nnrobust is installed by plain pip: every header the law compile
reads is installed by a declared runtime dependency (cmeel-eigen, ...), found in the runtime's
cmeel prefix, never in the temporary environment pip built the package in (issue 50, item 11:
`pip install nnrobust` in a fresh venv failed on "Eigen/Dense: No such file or directory").

A second build of the package is too slow for the suite, and so is a pip install of its
dependencies on a loaded machine (about 5 minutes here): a fresh venv gets the files pip installed
here for the package's declared runtime dependencies and theirs (each distribution's RECORD,
linked, the versions checked against the declared requirements) and nothing else, and the
installed package (its modules, its built _loop module and include/) copied in; a law is then
compiled and run there.
"""

import os
import shutil
import subprocess
import venv
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement

from nnrobust.run import compiled

pytestmark = [
    pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason()),
    pytest.mark.skipif(shutil.which("c++") is None, reason="no C++ compiler"),
]

ROOT = Path(__file__).resolve().parents[2]


def _closure(requirements: list[Requirement]) -> dict[str, metadata.Distribution]:
    """The installed distributions these requirements (and theirs, extras aside) name, each
    checked against the version it is required at."""
    found: dict[str, metadata.Distribution] = {}
    pending = list(requirements)
    while pending:
        requirement = pending.pop()
        if requirement.marker is not None and not requirement.marker.evaluate({"extra": ""}):
            continue
        name = requirement.name.lower().replace("_", "-")
        dist = metadata.distribution(requirement.name)
        assert requirement.specifier.contains(dist.version, prereleases=True), (requirement, dist.version)
        if name in found:
            continue
        found[name] = dist
        pending += [Requirement(r) for r in dist.requires or []]
    return found


def test_a_law_compiles_with_only_the_declared_runtime_dependencies(tmp_path):
    import nnrobust
    from nnrobust import _loop

    declared = [Requirement(r) for r in metadata.requires("nnrobust") or []]
    assert any(r.name == "cmeel-eigen" and str(r.specifier).startswith("==") for r in declared), declared
    venv.create(tmp_path / "v", with_pip=False)
    python = tmp_path / "v" / "bin" / "python"
    site = subprocess.run(
        [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True, text=True, check=True,
    ).stdout.strip()  # fmt: skip
    for dist in _closure(declared).values():
        for name in dist.files or []:
            if name.parts[0] == ".." or name.suffix == ".pyc":
                continue
            target = Path(site) / name
            target.parent.mkdir(parents=True, exist_ok=True)
            if not target.exists():
                target.symlink_to(Path(str(dist.locate_file(name))).resolve())
    package = Path(site) / "nnrobust"  # the package as installed: its modules and its built files
    shutil.copytree(Path(nnrobust.__file__).parent, package, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(Path(_loop.__file__).parent, package, dirs_exist_ok=True)
    shutil.copy(ROOT / "examples" / "controllers" / "task_pd.cpp", tmp_path / "task_pd.cpp")
    (tmp_path / "run.toml").write_text(
        'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "task_pd.cpp:TaskPD"\n'
        "params = {Kp = 100.0, Kd = 20.0, damping = 5.0}\n[simulation]\nduration = 0.05\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    done = subprocess.run(
        [python, "-m", "nnrobust.cli", "run", "run.toml", "--backend", "compiled", "--out", "out"]
        + ["--no-plots", "--no-animation", "--quiet"],
        capture_output=True,
        text=True,
        timeout=900,
        cwd=tmp_path,
        env={**env, "NNROBUST_CACHE": str(tmp_path / "cache")},
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert '"backend": "compiled"' in (tmp_path / "out" / "metrics.json").read_text()
