"""The documentation site builds with warnings as errors: links between pages, the navigation and
the API reference generated from the docstrings (docs/api.md, mkdocstrings) are all checked."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

import nnrobust

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
CONFIG = ROOT / "mkdocs.yml"


def _nav_files(entry) -> list[str]:
    """Every page path in a mkdocs `nav` (a list of paths, {title: path} and {title: [...]})."""
    if isinstance(entry, str):
        return [entry]
    if isinstance(entry, list):
        return [path for item in entry for path in _nav_files(item)]
    if isinstance(entry, dict):
        return [path for value in entry.values() for path in _nav_files(value)]
    raise TypeError(f"unexpected nav entry {entry!r}")


def test_every_docs_page_is_in_the_nav():
    yaml = pytest.importorskip("yaml")
    nav = _nav_files(yaml.safe_load(CONFIG.read_text())["nav"])
    pages = sorted(path.relative_to(DOCS).as_posix() for path in DOCS.rglob("*.md"))
    assert sorted(set(pages) - set(nav)) == [], "pages in docs/ missing from mkdocs.yml's nav"
    assert sorted(set(nav) - set(pages)) == [], "nav entries in mkdocs.yml with no page in docs/"
    assert len(nav) == len(set(nav)), "a page is listed twice in mkdocs.yml's nav"


def test_every_export_is_in_the_api_reference():
    text = (DOCS / "api.md").read_text()
    whole_modules = set(re.findall(r"^::: ([\w.]+)$", text, flags=re.M))
    missing = []
    for name, module in nnrobust._EXPORTS.items():
        module = "nnrobust" + module
        if module in whole_modules:  # e.g. `::: nnrobust.core.exceptions` documents all its errors
            continue
        if not re.search(rf"^::: {re.escape(module)}(\.\w+)*\.{name}$", text, flags=re.M):
            missing.append(f"{name} (from {module})")
    assert missing == [], "exports of nnrobust without a ::: block in docs/api.md"


def test_docs_build_strict(tmp_path):
    pytest.importorskip("mkdocs")
    site = tmp_path / "site"
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "mkdocs",
            "build",
            "--strict",
            "--site-dir",
            str(site),
            "--config-file",
            str(CONFIG),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, f"mkdocs build --strict failed:\n{done.stdout}\n{done.stderr}"
    api = (site / "api" / "index.html").read_text()
    for name in ("ControllerContext", "run_experiment"):
        assert name in api
