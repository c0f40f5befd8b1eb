"""The compiled step's parts, timed and counted (LoopSpec.profile; benchmarks/loop_profile.py):
a profiled run is the run, the parts account for no more than the run's time, and the loop's own
parts make no call to the system allocator (counted by benchmarks/allocation_counter.cpp,
preloaded in a child process)."""

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.run import compiled
from nnrobust.run.experiment import build

pytestmark = pytest.mark.skipif(not compiled.available(), reason="the compiled loop is not built")

PARTS = ("law", "bookkeeping", "record", "plant", "measure")


def test_a_profiled_run_is_the_run_and_its_parts_fit_in_its_time():
    setup = build(load_preset("paper-ellipse-noisy").replace(simulation={"duration": 1.0}))
    plain = compiled.simulate_compiled(setup, 1.0)
    start = time.perf_counter()
    parts, trace = compiled.profile_compiled(setup, 1.0)
    wall = time.perf_counter() - start
    for name in ("q", "dq", "tau", "tau_cmd"):
        np.testing.assert_array_equal(getattr(trace, name), getattr(plain, name))
    assert tuple(parts) == PARTS
    assert all(us >= 0.0 and calls is None for us, calls in parts.values())  # no counter preloaded here
    assert parts["law"][0] > 0.0 and parts["plant"][0] > 0.0
    assert sum(us for us, _ in parts.values()) * 1e-6 * trace.t.size <= wall


COUNTED = """
import ctypes, json
from nnrobust.config.presets import load_preset
from nnrobust.run import compiled
from nnrobust.run.experiment import build

process = ctypes.CDLL(None)  # the process's symbols: the preloaded malloc comes first
counted = process.nnrobust_allocations
libc = process
libc.malloc.restype = ctypes.c_void_p
libc.free.argtypes = [ctypes.c_void_p]
before = counted()
blocks = [libc.malloc(64) for _ in range(1000)]
made = counted() - before
for block in blocks:
    libc.free(block)
rows = {}
for preset in ("paper-ellipse", "panda-ellipse"):
    for duration in (0.5, 1.5):
        setup = build(load_preset(preset).replace(simulation={"duration": duration}))
        parts = compiled.profile_compiled(setup, duration)[0]
        steps = round(duration / setup.config.simulation.control_period)
        counted = {name: (us, round(calls * steps)) for name, (us, calls) in parts.items()}
        rows[f"{preset} {duration}"] = counted
print(json.dumps({"made": made, "rows": rows}))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the allocation counter is glibc's")
def test_the_counter_counts_and_the_loops_own_parts_never_allocate():
    counter = compiled.allocation_counter()
    assert counter, "the allocation counter was not built with the extension"
    out = subprocess.run(
        [sys.executable, "-c", COUNTED],
        env={**os.environ, "LD_PRELOAD": counter},
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    result = json.loads(out.stdout.splitlines()[-1])
    assert 1000 <= result["made"] < 1100  # the 1000 blocks asked for, and what ctypes adds
    for preset in ("paper-ellipse", "panda-ellipse"):
        short, long = ({n: c for n, (_, c) in result["rows"][f"{preset} {d}"].items()} for d in (0.5, 1.5))
        # the law's step takes its temporaries from the loop's arena; the kinematics' buffers are
        # sized before the first step; the bookkeeping's only calls are the interrupt poll's
        # (Python's signal check, every 256 steps)
        assert long["law"] == 0 and long["record"] == 0 and long["measure"] == 0, (preset, long)
        assert long["bookkeeping"] <= 1500 // 256, (preset, long)
        # the stick-slip plant makes each size's workspace the first time it needs it, within the
        # first 500 steps here: the 1000 steps after them allocate nothing
        assert short["plant"] > 0 and long["plant"] == short["plant"], (preset, short, long)


def _bench_check():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_check.py"
    spec = importlib.util.spec_from_file_location("bench_check", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _loop_rows(compiled_us: float, hybrid_us: float) -> dict:
    rows = [("floor, C++", 5.0), ("nnrobust, compiled loop", compiled_us), ("slotine-li, compiled loop", 7.0)]
    rows += [("TaskPD, hybrid loop", hybrid_us), ("TaskPD, compute alone", 60.0)]
    return {"rows": [{"preset": "arm", "contender": c, "step_seconds": 1e-6 * us} for c, us in rows]}


def _profile(law_us: float, law_calls: float) -> dict:
    rows = [("law", law_us, law_calls), ("plant", 4.0, 0.0)]
    return {
        "rows": [
            {"preset": "arm", "law": "nn", "part": p, "us_per_step": us, "allocations_per_step": c}
            for p, us, c in rows
        ]
    }


def test_bench_check_says_which_goal_is_missed_and_which_part_grew(tmp_path, capsys):
    check = _bench_check()
    stored = tmp_path / "stored.json"
    stored.write_text(json.dumps(_profile(2.0, 50.0)))
    cases = {
        "met": (_loop_rows(7.5, 68.0), _profile(2.1, 50.0), 0),  # 1.5x the floor, 8 µs beyond compute
        "slow": (_loop_rows(8.5, 68.0), _profile(3.2, 55.0), 1),  # 1.7x: missed, and the law grew
        "hybrid": (_loop_rows(7.5, 75.0), _profile(2.0, 50.0), 1),  # 15 µs beyond compute
    }
    for name, (loop, profile, code) in cases.items():
        (tmp_path / "loop.json").write_text(json.dumps(loop))
        (tmp_path / "profile.json").write_text(json.dumps(profile))
        args = [str(tmp_path / "loop.json"), str(tmp_path / "profile.json"), "--stored", str(stored)]
        assert check.main(args) == code, name
        out = capsys.readouterr().out
        if name == "slow":
            assert "MISS arm: nn compiled / C++ floor: 1.70" in out and "ok   arm: slotine-li" in out
            assert "arm, nn, law: 2.00 -> 3.20 µs per step" in out and "50.0 -> 55.0 allocations" in out
        if name == "hybrid":
            assert "MISS arm: hybrid overhead [µs]: 15.00" in out and "no part grew" in out
