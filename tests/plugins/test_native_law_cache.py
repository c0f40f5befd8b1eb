"""The cache of a law's library (nnrobust/plugins/native_law.py): keyed by everything the compiler read,
the headers a law includes beside it among them (ccache's direct mode: the .d file of -MMD,
each header's SHA-256 in a manifest), and never trusting a damaged library.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.run import compiled
from nnrobust.run.experiment import run_experiment

pytestmark = [
    pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason()),
    pytest.mark.skipif(shutil.which("c++") is None, reason="no C++ compiler"),
]

# a library without the law header: it compiles in a moment
TINY = '#include "gain.hpp"\nextern "C" double tiny_gain(void) { return GAIN; }\n'

# a law whose gain is its header's: tau = -GAIN q
GAINED = """#include "nnrobust/law.hpp"
#include "gain.hpp"

struct Gained : nnrobust::Law {
  Gained(const nnrobust::LawParams &, nnrobust::LawContext &) {}
  nnrobust::Output compute(double, const nnrobust::Vector &q, const nnrobust::Vector &,
                           const nnrobust::Vector &z) override {
    return {-GAIN * q, z, nnrobust::Vector(0)};
  }
};

NNROBUST_USER_LAW(Gained, "", 0)
"""


def _gain(value: float) -> str:
    return f"#pragma once\nconstexpr double GAIN = {value!r};\n"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("NNROBUST_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache" / "laws"


def _folder(root: Path, name: str, source: str, gain: float) -> Path:
    folder = root / name
    folder.mkdir()
    (folder / "law.cpp").write_text(source)
    (folder / "gain.hpp").write_text(_gain(gain))
    return folder / "law.cpp"


def test_a_header_is_part_of_the_key(cache, tmp_path):
    """Two folders with the same .cpp and other headers: two libraries; an edited header: another
    library; the header as it was: the first library again, not compiled again."""
    from nnrobust.plugins.native_law import compiled_library

    a = _folder(tmp_path, "a", TINY, 1.0)
    b = _folder(tmp_path, "b", TINY, 2.0)
    (first, digest), (second, other) = compiled_library(a, "k"), compiled_library(b, "k")
    assert first != second and digest != other
    stamp = first.stat().st_mtime_ns
    (a.parent / "gain.hpp").write_text(_gain(2.0))
    assert compiled_library(a, "k") == (second, other)  # the same inputs by content, wherever they lie
    (a.parent / "gain.hpp").write_text(_gain(1.0))
    assert compiled_library(a, "k") == (first, digest) and first.stat().st_mtime_ns == stamp


def test_an_edited_header_changes_the_torques_and_the_recorded_digest(cache, tmp_path):
    a = _folder(tmp_path, "a", GAINED, 0.0)

    def run():
        config = load_preset("paper-ellipse").replace(
            simulation={"duration": 0.02, "backend": "compiled"},
            controller={"kind": "custom", "class": f"{a}:Gained"},
        )
        result = run_experiment(config)
        return result.tau_cmd, result.config

    zero, before = run()
    (a.parent / "gain.hpp").write_text(_gain(50.0))
    gained, after = run()
    assert np.all(zero == 0.0) and np.abs(gained).max() > 1.0
    lines = {line.rpartition(":")[0]: line for line in before.splitlines() if "sha256" in line}
    changed = [key for key, line in lines.items() if line not in after]
    assert sorted(changed) == ["# controller includes gain.hpp sha256", "# controller inputs sha256"]


def test_a_damaged_library_is_compiled_again(cache, tmp_path):
    """A truncated library is never handed to dlopen (SIGBUS): its SHA-256 is not the one its
    manifest recorded, so it is compiled again, with a warning; the run works."""
    a = _folder(tmp_path, "a", GAINED, 3.0)
    (tmp_path / "run.toml").write_text(
        f'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "{a}:Gained"\n'
        "[simulation]\nduration = 0.02\n"
    )

    def run(out):
        return subprocess.run(
            [sys.executable, "-m", "nnrobust.cli", "run", str(tmp_path / "run.toml"), "--backend", "compiled"]
            + ["--out", str(tmp_path / out), "--no-plots", "--no-animation"],
            capture_output=True,
            text=True,
            timeout=600,
            env={**os.environ, "NNROBUST_CACHE": str(cache.parent)},
        )

    assert run("first").returncode == 0
    (built,) = cache.glob("*.so")
    size = built.stat().st_size
    with open(built, "r+b") as handle:
        handle.truncate(size // 3)
    done = run("second")
    assert done.returncode == 0, done.stderr
    assert "the cached library of" in done.stderr and "is damaged" in done.stderr
    assert built.stat().st_size == size


def test_a_study_records_the_headers_and_sends_them_to_its_workers(cache, tmp_path):
    """A sweep's inputs name each header its C++ law includes: an edited header is a changed input
    (a resume is refused, naming it), and the files sent to workers that do not see the client's
    hold it, so that such a worker compiles the law from them."""
    from nnrobust.core.shipped_files import bundle_of, local, within
    from nnrobust.plugins.native_law import library
    from nnrobust.studies.base.plan import load_sweep, study_inputs

    a = _folder(tmp_path, "a", TINY, 1.0)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        'name = "h"\nbase = "paper-ellipse"\ncontrollers = [{name = "cpp", class = "a/law.cpp:Gained"}]\n'
    )
    spec = load_sweep(sweep)
    before = study_inputs(spec)
    role = "the header gain.hpp that the class file of controller cpp includes"
    assert before.files[role][0] == str(a.parent / "gain.hpp")
    bundle = bundle_of(before.files.values())
    assert str(a.parent / "gain.hpp") in bundle.files
    (a.parent / "gain.hpp").write_text(_gain(5.0))
    after = study_inputs(spec)
    assert after.key != before.key
    assert after.change_from(before).startswith(f"{role}, {a.parent / 'gain.hpp'}, has changed")
    # a worker without the client's files: the folder gone, the law compiled from the bundle
    (a.parent / "gain.hpp").write_text(_gain(1.0))
    shutil.move(a.parent, tmp_path / "gone")
    with within(bundle, tmp_path / "worker"):
        assert local(a) != a and library(local(a), "k").dependencies[0][0] == "gain.hpp"
