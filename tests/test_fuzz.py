"""Fuzzing the command line: random and mutated URDFs and experiment files, written to disk and run
through ``nnrobust run`` in a subprocess bounded in time and memory; and signals at random
instants of a run. Whatever the input: exit 0, 1 (a run that failed, with its folder) or 2 with
one line, never a traceback, never a file outside --out; whatever the instant: a complete run
folder, a partial one marked as such, or the previous run intact."""

from __future__ import annotations

import json
import random
import re
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

MEMORY = 4 * 1024**3  # address space per input [bytes]
SECONDS = 300  # wall time per input (generous: the suite runs on busy machines)
ATTEMPTS = 5  # of a signal meant for the imports that may land in the simulation on a busy machine

WEIRD_VALUES = [
    "nan",
    "inf",
    "-inf",
    "",
    "1e400",
    "-1",
    "0",
    "x",
    "9" * 400,
    "1 2",
    "0 0 0 0",
    "1e-320",
    "\x00",
    "\u202e",
    "1,5",
    "0x10",
    "  3  ",
]
WEIRD_TOML = [
    "nan",
    "inf",
    "-1",
    "0",
    "1e300",
    "-1e300",
    "9" * 400,
    '"x"',
    '""',
    "true",
    "[]",
    "[[1.0]]",
    "[1.0, 2.0]",
    "{a = 1}",
    '"' + "a" * 5000 + '"',
    '"\\u0000\\u001b"',
    "[" * 60 + "]" * 60,
]


def _limits():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY, MEMORY))


def _run_cli(folder: Path, target: str) -> tuple[int, str]:
    out = folder / "out"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "nnrobust.cli",
            "run",
            target,
            "--out",
            str(out),
            "--quiet",
            "--no-animation",
            "--no-plots",
        ],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=SECONDS,
        preexec_fn=_limits,
    )
    return proc.returncode, proc.stderr


def _check_outcome(folder: Path, inputs: set[str], code: int, stderr: str) -> None:
    assert "Traceback" not in stderr, stderr[-3000:]
    lines = [line for line in stderr.splitlines() if line.strip() and not line.startswith("warning: ")]
    if code == 2:
        assert len(lines) == 1 and lines[0].startswith("nnrobust: error: "), stderr[-3000:]
        assert len(lines[0]) <= 1100
    else:
        assert code in (0, 1), (code, stderr[-3000:])
        marker = json.loads((folder / "out" / ".nnrobust-run").read_text())
        assert (marker["status"] == "completed") == (code == 0)
    left = {p.name for p in folder.iterdir()} - inputs - {"out"}
    assert not left, f"files written outside --out: {left}"


EXPERIMENT = """[robot]
source = "arm.urdf"
[nominal]
kind = "urdf"
[simulation]
duration = 0.05
"""
"""A short run of the paper's arm from its URDF file, which the fuzzer damages."""


def _mutate_urdf(text: str, rng: random.Random) -> str:
    """One to three random damages: an attribute's value, a deleted attribute or element, a
    duplicated element, a truncation, or stray bytes."""
    for _ in range(rng.randint(1, 3)):
        kind = rng.randrange(6)
        attributes = list(re.finditer(r'(\w+)="([^"]*)"', text))
        if kind == 0 and attributes:
            m = rng.choice(attributes)
            text = text[: m.start(2)] + rng.choice(WEIRD_VALUES).replace('"', "") + text[m.end(2) :]
        elif kind == 1 and attributes:
            m = rng.choice(attributes)
            text = text[: m.start()] + text[m.end() :]
        elif kind == 2:
            elements = list(re.finditer(r"<(\w+)[^<>]*/>", text))
            if elements:
                m = rng.choice(elements)
                text = text[: m.start()] + text[m.end() :]
        elif kind == 3:
            elements = list(re.finditer(r"<(\w+)[^<>]*/>", text))
            if elements:
                m = rng.choice(elements)
                text = text[: m.end()] + m.group(0) + text[m.end() :]
        elif kind == 4:
            text = text[: rng.randrange(len(text))]
        else:
            at = rng.randrange(len(text))
            text = text[:at] + rng.choice(["<", ">", "&", "\x01", "]]>", "<!--", "\ufffd"]) + text[at:]
    return text


@settings(
    max_examples=12,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(seed=st.integers(0, 2**32 - 1))
def test_mutated_urdfs(seed, tmp_path_factory):
    folder = tmp_path_factory.mktemp("urdf")
    from nnrobust import paper_arm_urdf

    text = _mutate_urdf(paper_arm_urdf().read_text(), random.Random(seed))
    (folder / "arm.urdf").write_text(text, encoding="utf-8", errors="surrogateescape")
    (folder / "e.toml").write_text(EXPERIMENT)
    code, stderr = _run_cli(folder, "e.toml")
    _check_outcome(folder, {"arm.urdf", "e.toml"}, code, stderr)


def _mutate_toml(text: str, rng: random.Random) -> str:
    lines = text.splitlines()
    for _ in range(rng.randint(1, 3)):
        kind = rng.randrange(5)
        values = [i for i, line in enumerate(lines) if " = " in line]
        if kind == 0 and values:
            i = rng.choice(values)
            lines[i] = lines[i].split(" = ")[0] + " = " + rng.choice(WEIRD_TOML)
        elif kind == 1 and values:
            del lines[rng.choice(values)]
        elif kind == 2:
            lines.insert(
                rng.randrange(len(lines) + 1),
                rng.choice(["bogus = 1", "[bogus]", "[robot]", "name = 'a/../b'", "x.y.z = 1"]),
            )
        elif kind == 3:
            cut = rng.randrange(len("\n".join(lines)))
            lines = "\n".join(lines)[:cut].splitlines()
        else:
            i = rng.randrange(len(lines) + 1)
            lines.insert(i, rng.choice(["\x00", "\x1b[2J", "'''", '"', "= 1", "[[robot]]"]))
    return "\n".join(lines) + "\n"


@settings(
    max_examples=14,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(seed=st.integers(0, 2**32 - 1))
def test_mutated_experiment_files(seed, tmp_path_factory):
    from nnrobust.config.presets import load_preset

    folder = tmp_path_factory.mktemp("toml")
    base = load_preset("paper-line").replace(simulation={"duration": 0.05}).to_toml()
    (folder / "e.toml").write_text(
        _mutate_toml(base, random.Random(seed)), encoding="utf-8", errors="surrogateescape"
    )
    code, stderr = _run_cli(folder, "e.toml")
    _check_outcome(folder, {"e.toml"}, code, stderr)


@pytest.mark.parametrize("seed", range(3))
def test_a_signal_at_a_random_instant(seed, tmp_path):
    """SIGINT, SIGTERM or SIGHUP at a random instant of `run --overwrite` over a completed run
    (during import, the simulation or the writing of outputs): afterwards the folder is the
    previous run or a new complete one, a partial run is beside it and marked, nothing else is
    left, and no process survives."""
    rng = random.Random(seed)
    out = tmp_path / "run"
    cmd = [
        sys.executable,
        "-m",
        "nnrobust.cli",
        "run",
        "paper-line",
        "--out",
        str(out),
        "--overwrite",
        "--duration",
        "1.5",
        "--backend",
        "python",
        "--quiet",
    ]
    subprocess.run(cmd, check=True, timeout=SECONDS, capture_output=True)
    before = (out / "result.npz").read_bytes()
    sig = rng.choice([signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
    proc = subprocess.Popen(cmd + ["--set", "controller.Kp=[12.0]"], stderr=subprocess.PIPE, text=True)
    time.sleep(rng.uniform(0.2, 6.0))
    proc.send_signal(sig)
    code = proc.wait(timeout=SECONDS)
    stderr = proc.stderr.read()
    assert "Traceback" not in stderr, stderr
    marker = json.loads((out / ".nnrobust-run").read_text())
    assert marker["status"] == "completed"
    if (out / "result.npz").read_bytes() != before:  # the new run finished before the signal came
        assert code in (0, 130) and marker["extras"] in ("complete", "interrupted")
        assert "Kp = [12.0" in (out / "config.toml").read_text()
    names = {p.name for p in tmp_path.iterdir()}
    assert names <= {"run", "run.interrupted"}, names
    if "run.interrupted" in names:
        partial = json.loads((tmp_path / "run.interrupted" / ".nnrobust-run").read_text())
        assert partial["status"] == "interrupted"
    assert proc.poll() is not None


def _loaded(pid: int, library: str) -> bool:
    """Whether process ``pid`` has mapped a shared library whose path holds ``library``."""
    try:
        return library in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


@pytest.mark.parametrize(
    "entry, sig",
    [(["-m", "nnrobust.cli"], signal.SIGINT), (["-m", "nnrobust"], signal.SIGTERM)],
)
def test_a_signal_during_the_imports_exits_130_with_one_line(entry, sig, tmp_path):
    """A stop signal while the command line is still importing its modules (the json accelerator,
    which its first lines import, is mapped): the command stops as soon as its work would start,
    exit 130, one line, no traceback, nothing written. Watched through /proc, not timed: on a busy
    machine the child can reach its simulation before the signal does, and then the run's own
    interrupt is the answer (exit 1, "run interrupted", its partial result marked so); such an
    attempt is checked for that and made again, up to ATTEMPTS times."""
    if not Path("/proc/self/maps").is_file():
        pytest.skip("needs /proc to see the child's imports")
    for attempt in range(ATTEMPTS):
        where = tmp_path / str(attempt)
        where.mkdir()
        out = where / "run"
        cmd = [sys.executable, *entry, "run", "paper-line", "--out", str(out), "--backend", "python"]
        proc = subprocess.Popen([*cmd, "--quiet"], stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + SECONDS
        while not _loaded(proc.pid, "/_json.") and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.001)
        proc.send_signal(sig)
        code = proc.wait(timeout=SECONDS)
        stderr = proc.stderr.read()
        if stderr.startswith("run interrupted: interrupted at t = "):  # too late: the run's answer
            assert code == 1 and "Traceback" not in stderr, (code, stderr)
            assert json.loads((out / ".nnrobust-run").read_text())["status"] == "interrupted"
            continue
        assert code == 130 and stderr == "nnrobust: interrupted\n", (code, stderr)
        assert not out.exists() and list(where.iterdir()) == []
        return
    pytest.fail(f"the signal reached the run's simulation in all {ATTEMPTS} attempts, never its imports")
