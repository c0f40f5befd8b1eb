"""A user's law in C++ (nnrobust/plugins/native_law.py; docs/extending.md#a-law-in-c): one .cpp file named
like a Python class is compiled on first use (cached by SHA-256), loaded into the compiled loop
and run there; with its Python twin (examples/custom_controller.py's TaskPD) it gives the same
run; a broken file gets the compiler's own lines.
"""

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import ConfigError
from nnrobust.run import compiled
from nnrobust.run.experiment import build, run_experiment

pytestmark = [
    pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason()),
    pytest.mark.skipif(shutil.which("c++") is None, reason="no C++ compiler"),
]

ROOT = Path(__file__).resolve().parents[2]
CPP = ROOT / "examples" / "controllers" / "task_pd.cpp"
PY = ROOT / "examples" / "custom_controller.py"
PARAMS = {"Kp": 100.0, "Kd": 20.0, "damping": 5.0}


@pytest.fixture(scope="module", autouse=True)
def law_cache(tmp_path_factory):
    """One compile of the example for the session, in a cache of its own (shared by the test
    processes: the first compiles, the others wait for it)."""
    base = tmp_path_factory.getbasetemp()
    cache = (base.parent if base.name.startswith("popen-gw") else base) / "law-cache"
    old = os.environ.get("NNROBUST_CACHE")
    os.environ["NNROBUST_CACHE"] = str(cache)
    yield cache
    if old is None:
        del os.environ["NNROBUST_CACHE"]
    else:
        os.environ["NNROBUST_CACHE"] = old


def _config(preset, cls, **simulation):
    return load_preset(preset).replace(
        simulation={"duration": 1.0, **simulation},
        controller={"kind": "custom", "class": cls, "params": PARAMS},
    )


@pytest.mark.parametrize("preset", ["paper-ellipse-noisy", "panda-ellipse"])
def test_the_cpp_law_runs_compiled_and_is_its_python_twin(preset, tmp_path):
    from nnrobust.run.experiment import compare_twins

    config = load_preset(preset).replace(simulation={"duration": 1.0})
    twins = compare_twins(config, f"{CPP}:TaskPD", f"{PY}:TaskPD", PARAMS)
    assert twins["backends"] == ("compiled", "hybrid")
    assert twins["statuses"] == ("completed", "completed")
    assert twins["tau_cmd"] < 1e-9 and twins["q"] < 1e-9 and twins["signals"]["effort"] < 1e-9, twins
    # a Python version that is not the C++ law's twin is told apart: its Kd term doubled
    off = tmp_path / "task_pd_off.py"
    off.write_text(PY.read_text().replace("- self.Kd * de", "- 2.0 * self.Kd * de"))
    assert compare_twins(config, f"{CPP}:TaskPD", f"{off}:TaskPD", PARAMS)["tau_cmd"] > 1e-3
    # what ran is recorded: the file's SHA-256 in the run's configuration
    from nnrobust.plugins.user_code import file_digest

    assert (
        f"sha256: {file_digest(CPP)}"
        in run_experiment(_config(preset, f"{CPP}:TaskPD", duration=0.01)).config
    )


def test_the_library_is_cached_by_content(law_cache, tmp_path):
    """One compile per content: the same file again is the same library, untouched; an edit is a
    new library (a file without the law header: the cache does not care what it holds)."""
    from nnrobust.plugins.native_law import compiled_library

    source = tmp_path / "cached.cpp"
    source.write_text('extern "C" int cached_value(void) { return 1; }\n')
    first, digest = compiled_library(source, "controller.class")
    stamp = first.stat().st_mtime_ns
    again, same = compiled_library(source, "controller.class")  # no second compile
    assert (again, same, again.stat().st_mtime_ns) == (first, digest, stamp)
    assert first.parent == law_cache / "laws"
    source.write_text('extern "C" int cached_value(void) { return 2; }\n')
    edited, other = compiled_library(source, "controller.class")
    assert edited != first and other != digest and first.is_file() and edited.is_file()


def test_a_compile_error_shows_the_compilers_lines(tmp_path):
    broken = tmp_path / "broken.cpp"
    # no header: the compiler stops at once (the law header costs seconds of parsing)
    broken.write_text("// a law with a typo\nstruct Broken {\n  int x = undefined_name;\n};\n")
    with pytest.raises(
        ConfigError, match=r"(?s)compiling .*broken\.cpp failed:.*broken\.cpp:3:.*undefined_name"
    ):
        build(_config("paper-ellipse", f"{broken}:Broken"))


def test_a_file_without_the_registration_is_refused(tmp_path):
    bare = tmp_path / "bare.cpp"
    # the class, but never named by NNROBUST_USER_LAW (no law header: it compiles in a moment)
    bare.write_text("struct TaskPD {\n  double Kp = 1.0;\n};\n")
    with pytest.raises(ConfigError, match=r"no NNROBUST_USER_LAW\(TaskPD, signals, state size\)"):
        build(_config("paper-ellipse", f"{bare}:TaskPD"))


def test_the_python_loop_refuses_it_with_the_reason():
    with pytest.raises(Exception, match="is a law in C\\+\\+: it runs on the compiled loop"):
        run_experiment(_config("paper-ellipse", f"{CPP}:TaskPD", backend="python", duration=0.01))


def test_a_cpp_law_joins_a_sweep_and_its_rows_are_the_python_twins(tmp_path, monkeypatch):
    """A controllers entry with a .cpp class: the file travels with the tasks, each Dask worker
    loads the library (compiled once on this machine), its rows run on the compiled loop and equal
    its Python twin's rows."""
    pytest.importorskip("distributed")
    import json

    from nnrobust.cli import main
    from nnrobust.studies.sweep import read_results

    shutil.copy(CPP, tmp_path / "task_pd.cpp")
    shutil.copy(PY, tmp_path / "task_pd.py")
    (tmp_path / "sweep.toml").write_text(
        """
name = "cpp"
base = "paper-ellipse"
controllers = [
  {name = "cpp", class = "task_pd.cpp:TaskPD", params = {Kp = 100.0, Kd = 20.0, damping = 5.0}},
  {name = "py", class = "task_pd.py:TaskPD", params = {Kp = 100.0, Kd = 20.0, damping = 5.0}},
]
samples = 2
[set]
"simulation.duration" = 2.2
[vary]
"plant.disturbance_scale" = {uniform = [0.5, 2.0]}
"""
    )
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", "sweep.toml", "--out", "out", "--workers", "2", "--quiet"]) == 0
    frame = read_results(tmp_path / "out").sort_values(["controller", "sample"])
    cpp, py = frame[frame["controller"] == "cpp"], frame[frame["controller"] == "py"]
    assert list(cpp["status"]) == list(py["status"]) == ["completed"] * 2
    np.testing.assert_allclose(
        cpp["rms_error_after_2s"].to_numpy(), py["rms_error_after_2s"].to_numpy(), rtol=1e-6
    )
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert set(summary["controllers"]) == {"cpp", "py"}


def test_a_cpp_law_is_tuned_in_the_space_it_declares(tmp_path):
    """--controllers takes file.cpp:Class: the space its NNROBUST_USER_LAW_SPACE declares is
    searched, and its best setting reruns (on the compiled loop) to its training metrics."""
    pytest.importorskip("optuna")
    from nnrobust.config import apply_overrides
    from nnrobust.studies.base.plan import base_config, draw, experiment
    from nnrobust.studies.tune import TuneSpec, run_tune
    from nnrobust.studies.tune.engine import sweep_of

    short = tmp_path / "short.toml"
    short.write_text(load_preset("paper-ellipse-noisy").replace(simulation={"duration": 2.5}).to_toml())
    spec = TuneSpec(str(short), [f"{CPP}:TaskPD"], 8, train_samples=2, validation=1, seed=5)
    summary = run_tune(spec, tmp_path / "out", workers=2)
    entry = summary["controllers"]["TaskPD"]
    names = {"controller.params.Kp", "controller.params.Kd", "controller.params.damping"}
    assert set(entry["space"]) == names
    declared_low = {w["param"]: w["old"] for w in entry["widened"] if w["side"] == "low"}
    assert (  # its declared bound, or where the tuner widened it from
        declared_low.get("controller.params.Kp", entry["space"]["controller.params.Kp"]["low"]) == 10.0
        and entry["space"]["controller.params.Kd"]["unit"] == "1/s"
    )
    best = entry["best"]
    assert best is not None and set(best["params"]) == names
    sweep = sweep_of(spec)
    runs = [
        run_experiment(
            apply_overrides(experiment(sweep, base_config(sweep), draw(sweep, s), "TaskPD"), best["params"])
        )
        for s in (0, 1)
    ]
    assert {r.backend for r in runs} == {"compiled"}
    mean = np.mean([r.metrics()["rms_error_after_2s"] for r in runs])
    assert mean == pytest.approx(best["train"]["rms_error_after_2s"], rel=1e-9)


def test_a_bad_space_declaration_names_the_entry(tmp_path):
    # the four functions NNROBUST_USER_LAW and NNROBUST_USER_LAW_SPACE define, written out (the
    # law header costs seconds of parsing; the loader reads only these)
    bad = tmp_path / "bad_space.cpp"
    bad.write_text(
        '#define API extern "C" __attribute__((visibility("default")))\n'
        "API void *nnrobust_law_factory_TaskPD(const void *, void *) { return nullptr; }\n"
        'API const char *nnrobust_law_signals_TaskPD(void) { return ""; }\n'
        "API int nnrobust_law_state_TaskPD(int) { return 0; }\n"
        'API const char *nnrobust_law_space_TaskPD(void) { return "Kp=ten:1e5"; }\n'
    )
    with pytest.raises(ConfigError, match=r"NNROBUST_USER_LAW_SPACE\(TaskPD, \.\.\.\): 'Kp=ten:1e5' is not"):
        build(_config("paper-ellipse", f"{bad}:TaskPD"))


def test_a_cpp_law_is_falsified_and_its_worst_plant_reruns(tmp_path):
    """falsify --controllers file.cpp:Class searches the box for the C++ law like any other; the
    worst plant's command reruns it (on the compiled loop) to the same metric."""
    pytest.importorskip("cma")
    import json
    import shlex

    from nnrobust.cli import main
    from nnrobust.studies.falsify import FalsifySpec, run_falsify

    sweep = tmp_path / "fz.toml"
    sweep.write_text(
        f'name = "fz"\nbase = "paper-ellipse"\nseed = 4\n'
        f'controllers = [{{name = "cpp", class = "{CPP}:TaskPD", '
        "params = {Kp = 100.0, Kd = 20.0, damping = 5.0}}]\n"
        '[set]\n"simulation.duration" = 2.5\n[vary]\n"plant.disturbance_scale" = {uniform = [0.0, 4.0]}\n'
    )
    spec = FalsifySpec(str(sweep), ["cpp"], ["rms_error<=0.02"], 8, seed=1)
    summary = run_falsify(spec, tmp_path / "out", workers=2)
    entry = summary["controllers"]["cpp"]
    assert entry["simulations"] == 8
    words = shlex.split(entry["worst"]["command"])
    assert (
        main([*words[1:], "--out", str(tmp_path / "again"), "--quiet", "--no-plots", "--no-animation"]) == 0
    )
    again = json.loads((tmp_path / "again" / "metrics.json").read_text())
    assert again["backend"] == "compiled"
    assert again["rms_error"] == entry["worst"]["metrics"]["rms_error"]


def test_a_study_takes_a_cpp_law_through_every_stage(tmp_path):
    """A study with the C++ law beside the shipped pd: tuned, validated, certified, falsified and
    rerun on the second engine like any law, on the compiled loop, its file's SHA-256 among the
    report's inputs."""
    pytest.importorskip("distributed")
    pytest.importorskip("optuna")
    pytest.importorskip("cma")
    import importlib.util
    import json

    from nnrobust.cli import main
    from nnrobust.plugins.user_code import file_digest

    mujoco = importlib.util.find_spec("mujoco") is not None
    shutil.copy(CPP, tmp_path / "task_pd.cpp")
    (tmp_path / "study.toml").write_text(
        'name = "cpp"\ncases = ["paper-ellipse-noisy"]\n'
        'controllers = ["pd", {name = "taskpd-cpp", class = "task_pd.cpp:TaskPD", '
        "params = {Kp = 100.0, Kd = 20.0, damping = 5.0}}]\n"
        'require = ["rms_error_after_2s<=0.002"]\n'
        '[set]\n"simulation.duration" = 2.5\n'
        '[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
        "[budgets]\ntune = 8\nseeds = 1\ntrain_samples = 1\nvalidation = 2\nepsilon = 0.5\nbeta = 0.2\n"
        f"falsify = 4\nmargin = false\nsecond_engine = {str(mujoco).lower()}\n"
    )
    out = tmp_path / "out"
    assert main(["study", str(tmp_path / "study.toml"), "--out", str(out), "--workers", "2", "--quiet"]) == 0
    report = json.loads((out / "report.json").read_text())
    case = report["cases"]["paper-ellipse-noisy"]
    stages = ("tune", "validate", "certify", "falsify") + (("engine",) if mujoco else ())
    assert all(case["stages"][s] == "finished" for s in stages), case["stages"]
    entry = case["controllers"]["taskpd-cpp"]
    assert entry["backend"] == "compiled" and entry["step_cost_us"] > 0
    assert entry["tuned"]["seeds"] and entry["certificates"] and "command" in entry["worst"]
    assert set(entry["tuned"]["settings"]) == {f"controller.params.{k}" for k in PARAMS}  # its declared space
    if mujoco:
        assert entry["engines"]["mujoco"]["rows"] == 3
    assert report["inputs"][str(tmp_path / "task_pd.cpp")] == file_digest(CPP)


def test_a_law_compiled_apart_runs_outside_the_loops_arena():
    """A shipped law's step takes its temporaries from the loop's arena (no system allocator in
    it: tests/run/test_loop_profile.py); a user's law, compiled apart without the allocator's
    wrappers, allocates as it will, and its run is the same run either way."""

    module = compiled._module()
    shipped = build(load_preset("panda-ellipse").replace(simulation={"duration": 0.05}))
    assert module.law_in_arena(compiled.loop_spec(shipped, 0.05))
    setup = build(_config("panda-ellipse", f"{CPP}:TaskPD", duration=0.05))
    trace = compiled.simulate_compiled(setup, 0.05)  # loads and registers its library
    assert not module.law_in_arena(compiled.loop_spec(setup, 0.05))
    assert np.isfinite(trace.tau_cmd).all() and trace.t.size == 50
