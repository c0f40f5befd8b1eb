"""A law in C++ that exits, crashes or loops (csrc/user_code.cpp) ends `nnrobust run` with one line
naming the law and a nonzero exit, and a sweep's rows name it; one that returns keeps the run's
usual ending. Each law is one class of tests/plugins/broken_laws.cpp, compiled once.
"""

import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from nnrobust.run import compiled

pytestmark = [
    pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason()),
    pytest.mark.skipif(shutil.which("c++") is None, reason="no C++ compiler"),
]

LAWS = Path(__file__).resolve().parent / "broken_laws.cpp"


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """One compile of broken_laws.cpp for the module (its first test waits for it)."""
    return tmp_path_factory.mktemp("law-cache")


def _experiment(folder: Path, cls: str, duration: float = 0.05) -> Path:
    path = folder / f"{cls}.toml"
    path.write_text(
        f'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "{LAWS}:{cls}"\n'
        f"[simulation]\nduration = {duration}\n"
    )
    return path


def _command(folder: Path, cls: str, duration: float = 0.05, python: tuple[str, ...] = ()) -> list[str]:
    return [sys.executable, *python, "-m", "nnrobust.cli", "run", str(_experiment(folder, cls, duration))] + [
        "--backend", "compiled", "--out", str(folder / "out"), "--quiet", "--no-plots", "--no-animation",
    ]  # fmt: skip


def _env(cache: Path) -> dict:
    return {**os.environ, "NNROBUST_CACHE": str(cache)}


def _run(cache, folder, cls, python=()):
    return subprocess.run(
        _command(folder, cls, python=python), capture_output=True, text=True, timeout=600, env=_env(cache)
    )


@pytest.mark.parametrize(
    "cls, call",
    [
        ("Exits", "exit(0)"),
        ("QuickExits", "quick_exit(0)"),
        ("UnderscoreExits", "_exit(0)"),
        ("Aborts", "abort()"),
    ],
)
def test_a_law_that_ends_the_process_is_named_and_the_exit_is_not_zero(cls, call, cache, tmp_path):
    done = _run(cache, tmp_path, cls)
    assert done.returncode == 70, done.stderr
    assert (
        f"nnrobust: the law {cls} ({LAWS}) called {call} inside its compute: a law may not end" in done.stderr
    )


def test_a_law_that_crashes_is_named_and_dies_of_its_signal(cache, tmp_path):
    """The line, then the previous handler (faulthandler's here: its dump follows), then the
    signal's death."""
    done = _run(cache, tmp_path, "WritesThroughNull", python=("-X", "faulthandler"))
    assert done.returncode == -signal.SIGSEGV
    said = done.stderr.index(f"the law WritesThroughNull ({LAWS}) crashed inside its compute: SIGSEGV")
    assert "Fatal Python error: Segmentation fault" in done.stderr[said:]


def _stopped(cache, folder, cls, sig, duration):
    child = subprocess.Popen(
        _command(folder, cls, duration), stderr=subprocess.PIPE, text=True, env=_env(cache)
    )
    try:
        assert child.stderr is not None
        assert child.stderr.readline() == f"{cls}: now\n"  # inside the run, the library loaded
        child.send_signal(sig)
        return child.wait(timeout=120), child.stderr.read()
    finally:
        child.kill()
        child.wait()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_law_that_never_returns_is_ended_after_a_stop_signal(sig, cache, tmp_path):
    code, err = _stopped(cache, tmp_path, "Loops", sig, 5.0)
    assert code == 130, err
    assert (
        f"nnrobust: the law Loops ({LAWS}) did not return within 2 s after the stop signal ({sig.name})"
        in err
    )


def test_a_law_that_returns_is_interrupted_as_any_run(cache, tmp_path):
    code, err = _stopped(cache, tmp_path, "Sleeps", signal.SIGINT, 60.0)
    assert code == 1 and "run interrupted" in err and "did not return" not in err, err
    assert (tmp_path / "out" / "metrics.json").is_file()


def test_a_law_that_ends_its_worker_is_named_in_the_sweep(cache, tmp_path):
    """std::exit(0) on a dask worker: the worker dies with exit code 70, its nanny restarts it,
    and the rows are crashed, naming the law (exit 0 before: no worker restarted, and a study
    ended after 120 s on "the cluster has had no worker")."""
    pytest.importorskip("distributed")
    from nnrobust.studies.sweep import read_results

    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        'name = "exits"\nbase = "paper-ellipse"\n'
        f'controllers = ["no-u0", {{name = "mine", class = "{LAWS}:Exits"}}]\n'
        'samples = 1\n[set]\n"simulation.duration" = 2.2\n'
    )
    done = subprocess.run(
        [sys.executable, "-m", "nnrobust.cli", "sweep", str(sweep), "--out", str(tmp_path / "out")]
        + ["--workers", "2", "--quiet"],
        capture_output=True,
        text=True,
        timeout=600,
        env=_env(cache),
    )
    assert done.returncode == 1, done.stderr
    rows = read_results(tmp_path / "out").set_index("controller")
    assert rows.loc["no-u0", "status"] == "completed" and rows.loc["mine", "status"] == "crashed"
    assert f"; it ran the law Exits in C++ ({LAWS})" in rows.loc["mine", "message"]
    assert f"the law Exits ({LAWS}) called exit(0)" in done.stderr


def test_an_error_names_the_file_the_run_loaded(cache, tmp_path, monkeypatch):
    """Two files of the same content share one library: each run's error names its own file."""
    from nnrobust.config import load_config
    from nnrobust.core.exceptions import ControllerError
    from nnrobust.run.experiment import run_experiment

    monkeypatch.setenv("NNROBUST_CACHE", str(cache))
    for name in ("a", "b", "a"):
        folder = tmp_path / name
        folder.mkdir(exist_ok=True)
        shutil.copy(LAWS, folder / "laws.cpp")
        (folder / "run.toml").write_text(
            'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "laws.cpp:Throws"\n'
            "[simulation]\nduration = 0.01\n"
        )
        with pytest.raises(ControllerError, match=f"^the law Throws \\({folder / 'laws.cpp'}\\) threw"):
            run_experiment(load_config(folder / "run.toml"))
