"""An exported law (nnrobust/outputs/export.py, csrc/export/; docs/export.md) against the compiled loop it
came from: a C program linked to the export, fed the measured states of a compiled run (at each
control instant, what the loop's sensor gave its law), returns the torques the loop's law
commanded there, bit for bit, without one heap allocation in a step; several law objects are
independent; bad descriptions and folders are refused with a message that names what is wrong.
"""

import ctypes
import hashlib
import json
import shutil
import subprocess
import sys
from pathlib import Path
from urllib.parse import quote

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import NNRobustError
from nnrobust.outputs.export import description, export_law, recorded_steps, time_steps
from nnrobust.run import compiled
from nnrobust.run.experiment import build

pytestmark = [
    pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason()),
    pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler"),
]

CASES = {
    # the NN compensator (state: the adaptive weights) on the closed-form nominal model, noisy sensor
    "paper arm, NN, noisy": ("paper-ellipse-noisy", {}),
    # a registered law on a perturbed Pinocchio nominal model (spatial task, criteria)
    "Panda, slotine-li": ("panda-ellipse", {"controller": {"kind": "slotine-li"}}),
    # a pose task (orientation error through log3), PD
    "Panda pose, PD": ("panda-pose", {"controller": {"kind": "pd"}}),
}
DURATION = 0.3
ROOT = Path(__file__).resolve().parents[2]


def _config(name):
    preset, changes = CASES[name]
    return load_preset(preset).replace(simulation={"duration": DURATION}, **changes)


def _compiled_run(config):
    return recorded_steps(config, DURATION)


def _compile_replay(folder):
    program = folder / "replay"
    subprocess.run(
        ["cc", "-O2", "-I", folder / "include", folder / "example" / "replay.c", "-L", folder / "lib",
         "-lnnrobust_law", "-lnnrobust_core", f"-Wl,-rpath,{folder / 'lib'}", "-o", program],
        check=True, capture_output=True, timeout=300,
    )  # fmt: skip
    return program


def _replay(program, inputs, *args):
    text = "\n".join(" ".join(repr(float(x)) for x in row) for row in inputs) + "\n"
    done = subprocess.run(
        [program, *args], input=text, capture_output=True, text=True, timeout=300, check=True
    )
    return np.array([[float(x) for x in line.split()] for line in done.stdout.splitlines()])


@pytest.mark.parametrize("name", list(CASES))
def test_a_c_program_replays_the_compiled_loops_torques(name, tmp_path):
    config = _config(name)
    inputs, torques = _compiled_run(config)
    info = export_law(config, tmp_path / "law")
    assert info["joints"] == torques.shape[1] and info["built"]
    program = _compile_replay(tmp_path / "law")
    ours = _replay(program, inputs)
    assert ours.shape == torques.shape
    np.testing.assert_allclose(ours, torques, rtol=0, atol=1e-12)
    # the same law read from its description file at run time
    again = _replay(program, inputs, tmp_path / "law" / "law.description")
    np.testing.assert_array_equal(again, ours)


def _library(folder):
    core = ctypes.CDLL(str(folder / "lib" / "libnnrobust_core.so"))
    law = ctypes.CDLL(str(folder / "lib" / "libnnrobust_law.so"))
    law.nnrobust_law_create.restype = ctypes.c_void_p
    law.nnrobust_law_create_from.restype = ctypes.c_void_p
    law.nnrobust_law_create_from.argtypes = [ctypes.c_char_p]
    law.nnrobust_law_last_error.restype = ctypes.c_char_p
    law.nnrobust_law_dof.argtypes = [ctypes.c_void_p]
    law.nnrobust_law_reset.argtypes = [ctypes.c_void_p]
    law.nnrobust_law_destroy.argtypes = [ctypes.c_void_p]
    law.nnrobust_law_period.argtypes = [ctypes.c_void_p]
    law.nnrobust_law_period.restype = ctypes.c_double
    double_p = ctypes.POINTER(ctypes.c_double)
    law.nnrobust_law_step.argtypes = [ctypes.c_void_p, ctypes.c_double, double_p, double_p, double_p]
    return law, core


def _step(lib, handle, row, n):
    q = np.ascontiguousarray(row[1 : 1 + n])
    v = np.ascontiguousarray(row[1 + n :])
    tau = np.zeros(n)
    p = ctypes.POINTER(ctypes.c_double)
    status = lib.nnrobust_law_step(
        handle, row[0], q.ctypes.data_as(p), v.ctypes.data_as(p), tau.ctypes.data_as(p)
    )
    return status, tau


def test_law_objects_are_independent_and_reset_restarts_one(tmp_path):
    """Two objects stepped in turn on different runs each give their own run's torques (no
    shared state); reset brings one back to its initial adaptive weights."""
    config = _config("paper arm, NN, noisy")
    inputs, torques = _compiled_run(config)
    other_inputs, other_torques = _compiled_run(config.replace(sensing={"seed": 7}))
    export_law(config, tmp_path / "law")
    lib, _ = _library(tmp_path / "law")
    a, b = lib.nnrobust_law_create(), lib.nnrobust_law_create()
    assert a and b and lib.nnrobust_law_dof(a) == 3
    assert lib.nnrobust_law_period(a) == config.simulation.control_period
    n = 3
    for k in range(len(inputs)):
        status_a, tau_a = _step(lib, a, inputs[k], n)
        status_b, tau_b = _step(lib, b, other_inputs[k], n)
        assert status_a == status_b == 0
        np.testing.assert_array_equal(tau_a, torques[k])
        np.testing.assert_array_equal(tau_b, other_torques[k])
    assert not np.array_equal(torques[-1], other_torques[-1])  # the runs did differ
    lib.nnrobust_law_reset(a)
    for k in range(5):
        np.testing.assert_array_equal(_step(lib, a, inputs[k], n)[1], torques[k])
    lib.nnrobust_law_destroy(a)
    lib.nnrobust_law_destroy(b)


def test_an_absurd_measurement_or_command_is_status_2(tmp_path):
    """q = 1e300 (a measurement beyond the joint's range) or a command above 10 times its effort
    limit: status 2, the command not to be applied, the law's state not advanced (status 0 and a
    1e300 N m command before)."""
    config = _config("paper arm, NN, noisy")
    inputs, torques = _compiled_run(config)
    export_law(config, tmp_path / "law")
    text = (tmp_path / "law" / "law.description").read_text()
    assert "vec command_bound 3 " in text and "vec measured_upper 3 " in text
    lib, _ = _library(tmp_path / "law")
    law, n = lib.nnrobust_law_create(), 3
    far = inputs[0].copy()
    far[1] = 1e300  # the first joint's position
    status, tau = _step(lib, law, far, n)
    assert status == 2 and not lib.nnrobust_law_last_error()
    fast = inputs[0].copy()
    fast[1 + n :] = 1e5  # positions in range, joint speeds of 1e5 rad/s: a command far above 60 N m
    status, tau = _step(lib, law, fast, n)
    assert status == 2 and np.abs(tau).max() > 600.0
    for k in range(3):  # the adaptive weights were not advanced by the refused steps
        status, tau = _step(lib, law, inputs[k], n)
        assert status == 0
        np.testing.assert_array_equal(tau, torques[k])
    lib.nnrobust_law_destroy(law)


def test_a_bad_description_is_refused_with_the_line_it_names(tmp_path):
    config = _config("paper arm, NN, noisy")
    export_law(config, tmp_path / "law")
    lib, _ = _library(tmp_path / "law")
    text = (tmp_path / "law" / "law.description").read_text()
    cases = {
        "nnrobust-law 2\n": "first line",
        text.replace("str law =task_space\n", "str law =no-such-law\n"): "unknown law no-such-law",
        text.replace("int m 2", "int m two"): "two is not an integer",
        text + "mat law_params/Kp 2 2 0x1p0\n": "ends too soon",
        text + "num frobnicate 0x1p0\n": "unknown num entry frobnicate",
        "\n".join(line for line in text.splitlines() if not line.startswith("mat law_params/Kp")): "Kp",
    }
    for bad, expected in cases.items():
        assert lib.nnrobust_law_create_from(bad.encode()) is None
        assert expected in lib.nnrobust_law_last_error().decode(), expected
    assert lib.nnrobust_law_create_from(None) is None


def test_the_description_carries_every_number_exactly():
    """Each number is written in C's hexadecimal notation, which float.fromhex (and strtod) read
    back to the same float64: the nominal model's and the law's fields, inf and nan included."""
    setup = build(_config("Panda, slotine-li"))
    spec, model = compiled.law_spec(setup)
    text = description(spec, model, 7)
    assert text.startswith("nnrobust-law 1\n")
    for line in text.splitlines()[1:]:
        kind, key, *values = line.split()
        if kind == "mat":
            rows, cols, *numbers = values
            assert len(numbers) == int(rows) * int(cols), key
            [float.fromhex(x) for x in numbers]
    inertias = next(line for line in text.splitlines() if line.startswith("mat model/inertias "))
    numbers = np.array([float.fromhex(x) for x in inertias.split()[4:]]).reshape(-1, 13)
    np.testing.assert_array_equal(numbers, model.inertias)


def test_the_cli_exports_and_refuses_what_it_cannot(tmp_path, capsys):
    out = tmp_path / "law"
    assert main(["export", "paper-ellipse", "--out", str(out), "--set", "simulation.duration=1.0"]) == 0
    info = json.loads((out / "export.json").read_text())
    assert (info["law"], info["robust_term"]) == ("task_space", "nn_compensator")
    assert info["files"]["lib/libnnrobust_law.so"] and "config.toml" in info["files"]
    assert (out / "lib" / "libpinocchio_default.so").is_file()  # standalone: Pinocchio travels along
    capsys.readouterr()
    assert main(["export", "paper-ellipse", "--out", str(out)]) == 2
    assert "pass --overwrite" in capsys.readouterr().err
    assert main(["export", "paper-ellipse", "--out", str(out), "--overwrite", "--quiet"]) == 0
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    assert main(["export", "paper-ellipse", "--out", str(tmp_path / "mine"), "--overwrite"]) == 2
    assert "not an export" in capsys.readouterr().err
    assert (tmp_path / "mine" / "notes.txt").read_text() == "keep"


def test_a_custom_controller_is_refused(tmp_path):
    config = load_preset("paper-ellipse").replace(
        controller={"kind": "custom", "class": f"{ROOT / 'examples' / 'custom_controller.py'}:TaskPD"}
    )
    with pytest.raises(NNRobustError, match="cannot be exported: a custom controller"):
        export_law(config, tmp_path / "law")
    assert not (tmp_path / "law").exists()


@pytest.mark.parametrize("name", list(CASES))
def test_a_step_never_calls_the_system_allocator(name, tmp_path):
    """The export's bin/time_step (example/time_step.c) wraps glibc's malloc family for the whole
    process (Pinocchio's libraries included) and counts every call made during the steps, none
    during create."""
    config = _config(name)
    inputs, _ = _compiled_run(config)
    folder = tmp_path / "law"
    export_law(config, folder)
    timed = time_steps(folder, inputs, repeats=2)  # the export's bin/time_step
    assert timed["steps"] == 2 * len(inputs) and timed["allocations_per_step"] == 0
    assert 0 < timed["p50_us"] <= timed["p99_us"] <= timed["max_us"]
    lib, _ = _library(folder)
    lib.nnrobust_law_heap_requests.argtypes = [ctypes.c_void_p]
    handle = lib.nnrobust_law_create()
    for row in inputs[:20]:
        assert _step(lib, handle, row, (inputs.shape[1] - 1) // 2)[0] == 0
    assert lib.nnrobust_law_heap_requests(handle) == 0  # nothing overflowed the arena
    lib.nnrobust_law_destroy(handle)


def test_a_tuned_law_exports_at_its_tuned_setting_and_replays(tmp_path):
    """--tuned takes a tuning's summary as sweep and falsify do: the export runs the best setting
    (its config.toml has it), and replays the compiled run of that setting."""
    from nnrobust.config import load_config

    summary = ROOT / "docs" / "data" / "tune_noisy_case_b.json"
    best = json.loads(summary.read_text())["controllers"]["slotine-li"]["best"]["params"]
    out = tmp_path / "law"
    argv = ["export", "paper-ellipse-noisy", "--controller", "slotine-li", "--tuned", str(summary)]
    assert main([*argv, "--out", str(out), "--quiet"]) == 0
    config = load_config(out / "config.toml")
    assert config.controller.kind == "slotine-li"
    assert config.controller.params["Lambda"] == best["controller.params.Lambda"]
    config = config.replace(simulation={"duration": DURATION})
    inputs, torques = _compiled_run(config)
    ours = _replay(_compile_replay(out), inputs)
    np.testing.assert_allclose(ours, torques, rtol=0, atol=1e-12)


def test_a_studys_kept_setting_exports_from_its_report(tmp_path, capsys):
    """--tuned REPORT.json#CASE: the kept setting a study certified (docs/data/tuned_paper.json's
    noisy case b) is the one exported; on the case's own experiment no warning is said."""
    from nnrobust.config import load_config

    report = ROOT / "docs" / "data" / "tuned_paper.json"
    kept = json.loads(report.read_text())["cases"]["paper-ellipse-noisy"]["controllers"]["slotine-li"]
    argv = ["export", "paper-ellipse-noisy", "--controller", "slotine-li", "--no-build", "--quiet"]
    out = tmp_path / "law"
    assert main([*argv, "--tuned", f"{report}#paper-ellipse-noisy", "--out", str(out)]) == 0
    assert "warning" not in capsys.readouterr().err
    params = load_config(out / "config.toml").controller.params
    for key, value in kept["tuned"]["settings"].items():
        assert params[key.removeprefix("controller.params.")] == value, key


def test_set_wins_over_tuned_and_other_tunings_and_inert_keys_are_said(tmp_path, capsys):
    summary = str(ROOT / "docs" / "data" / "tune_noisy_case_b.json")
    out = tmp_path / "law"
    argv = ["export", "paper-ellipse-noisy", "--controller", "slotine-li", "--tuned", summary]
    assert main([*argv, "--set", "controller.params.Lambda=5.0", "--out", str(out), "--quiet"]) == 0
    from nnrobust.config import load_config

    assert load_config(out / "config.toml").controller.params["Lambda"] == 5.0
    capsys.readouterr()
    argv = [
        "export",
        "paper-ellipse",
        "--controller",
        "slotine-li",
        "--tuned",
        summary,
        "--set",
        "controller.Kp=[1.0]",
    ]
    with pytest.warns(UserWarning) as said:
        assert main([*argv, "--out", str(tmp_path / "other")]) == 0
    text = " ".join(str(w.message) for w in said)
    assert "that tuning was of paper-ellipse-noisy, not paper-ellipse" in text
    assert "--set controller.Kp changes nothing here" in text


def test_a_python_class_named_by_controller_is_refused_with_the_reason(tmp_path, capsys):
    law = f"{ROOT / 'examples' / 'custom_controller.py'}:TaskPD"
    assert main(["export", "paper-ellipse", "--controller", law, "--out", str(tmp_path / "law")]) == 2
    assert "is Python code, with no C++ twin to export" in capsys.readouterr().err


LEAKY = """
// A law that keeps memory its step allocated: its member is sized in compute, not in its constructor.
struct Leaky : nnrobust::Law {
  Vector kept;
  Leaky(const LawParams &, LawContext &) {}
  Output compute(double, const Vector &q, const Vector &, const Vector &z) override {
    kept = 2.0 * q;  // allocates on the first step, from the step's arena
    return {Vector::Zero(q.size()), z, Vector()};
  }
};
NNROBUST_USER_LAW(Leaky, "", 0)
"""


@pytest.mark.skipif(shutil.which("c++") is None, reason="no C++ compiler")
def test_a_law_in_cpp_exports_with_its_file_and_replays(tmp_path):
    """A user's law in one C++ file (examples/controllers/task_pd.cpp, named as controller.class)
    is compiled into the export's libnnrobust_law with its source; a C program replays the compiled
    loop's torques bit for bit, with no allocation in a step (the user's code allocates from the
    law's arena too). A law whose step keeps memory it allocated gets -1 and the reason."""
    source = tmp_path / "task_pd.cpp"
    # with a header of its own beside it, which the export copies beside its file
    (tmp_path / "leaky.hpp").write_text(f"#pragma once\n{LEAKY}")
    source.write_text(
        (ROOT / "examples" / "controllers" / "task_pd.cpp").read_text() + '#include "leaky.hpp"\n'
    )
    params = {"Kp": 100.0, "Kd": 20.0, "damping": 5.0}
    config = load_preset("panda-ellipse").replace(
        simulation={"duration": DURATION},
        controller={"kind": "custom", "class": f"{source}:TaskPD", "params": params},
    )
    inputs, torques = _compiled_run(config)
    folder = tmp_path / "law"
    info = export_law(config, folder)
    assert info["law"].startswith("cpp:TaskPD:") and info["law_source"] == "src/task_pd.cpp"
    assert (folder / "src" / "task_pd.cpp").read_bytes() == source.read_bytes()
    assert info["files"]["src/task_pd.cpp"] == hashlib.sha256(source.read_bytes()).hexdigest()
    assert (folder / "src" / "leaky.hpp").read_bytes() == (tmp_path / "leaky.hpp").read_bytes()
    np.testing.assert_array_equal(_replay(_compile_replay(folder), inputs), torques)
    # no allocation in a step, the user's code included (the hook of the export's bin/time_step)
    timed = time_steps(folder, inputs, repeats=1)
    assert (timed["steps"], timed["allocations_per_step"]) == (len(inputs), 0)
    # in a process of its own, as a program uses it (this one holds the compiled loop, whose
    # symbols a law library loaded here would bind to): the description alone does not carry the
    # code, and Leaky, registered by hand, keeps its step's memory: both are refused with the reason
    leaky = (
        (folder / "law.description")
        .read_text()
        .replace(f"str law ={quote(info['law'], safe='')}", "str law =cpp%3ALeaky%3Atest")
    )
    (tmp_path / "leaky.description").write_text(leaky)
    script = f"""
import ctypes
lib = ctypes.CDLL({str(folder / "lib" / "libnnrobust_law.so")!r})
lib.nnrobust_law_create_from.restype = ctypes.c_void_p
lib.nnrobust_law_last_error.restype = ctypes.c_char_p
lib.nnrobust_law_add_native.argtypes = [ctypes.c_char_p, ctypes.c_void_p]
lib.nnrobust_law_step.argtypes = [ctypes.c_void_p, ctypes.c_double] + [ctypes.POINTER(ctypes.c_double)] * 3
print(lib.nnrobust_law_create_from({(folder / "law.description").read_bytes()!r}))
print(lib.nnrobust_law_last_error().decode())
factory = ctypes.cast(lib.nnrobust_law_factory_Leaky, ctypes.c_void_p)
print(lib.nnrobust_law_add_native(b"cpp:Leaky:test", factory))
handle = lib.nnrobust_law_create_from({leaky.encode()!r})
x = (ctypes.c_double * 7)()
print(lib.nnrobust_law_step(handle, 0.0, x, x, x))
print(lib.nnrobust_law_last_error().decode())
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    lines = done.stdout.splitlines()
    assert done.returncode == 0 and len(lines) == 5, done.stderr
    assert lines[0] == "None" and "is a user's law in C++: create it with nnrobust_law_create" in lines[1]
    assert lines[2] == "0" and lines[3] == "-1"
    assert "the step kept 1 block(s) of memory it allocated" in lines[4]


def test_a_studys_cpp_law_exports_by_its_name_and_replays_its_certification_run(tmp_path):
    """`export --tuned REPORT.json#CASE --controller NAME` for a law in C++ the study named
    taskpd-cpp: the report carries the entry its certification ran (its class and tuned params),
    so the law exports by that name (it was "has no best setting for 'custom'") and a C program
    replays the certification's first draw to its torques."""
    pytest.importorskip("distributed")
    pytest.importorskip("optuna")
    from nnrobust.config import load_config
    from nnrobust.studies.base.plan import base_config, draw, experiment, load_sweep
    from nnrobust.studies.study import load_study

    shutil.copy(ROOT / "examples" / "controllers" / "task_pd.cpp", tmp_path / "task_pd.cpp")
    (tmp_path / "study.toml").write_text(
        'name = "cpp"\ncases = ["paper-ellipse-noisy"]\n'
        'controllers = [{name = "taskpd-cpp", class = "task_pd.cpp:TaskPD"}]\n'
        'require = ["rms_error_after_2s<=0.002"]\n[set]\n"simulation.duration" = 2.5\n'
        '[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
        "[budgets]\ntune = 6\nseeds = 1\ntrain_samples = 1\nvalidation = 2\nepsilon = 0.5\nbeta = 0.2\n"
        "falsify = 0\n"
    )
    out = tmp_path / "out"
    assert main(["study", str(tmp_path / "study.toml"), "--out", str(out), "--workers", "2", "--quiet"]) == 0
    assert load_study(tmp_path / "study.toml").controllers == ["taskpd-cpp"]
    law = tmp_path / "law"
    argv = ["export", "paper-ellipse-noisy", "--tuned", f"{out / 'report.json'}#paper-ellipse-noisy"]
    assert (
        main(
            [
                *argv,
                "--controller",
                "taskpd-cpp",
                "--set",
                "simulation.duration=2.5",
                "--out",
                str(law),
                "--quiet",
            ]
        )
        == 0
    )
    kept = json.loads((out / "report.json").read_text())["cases"]["paper-ellipse-noisy"]["controllers"][
        "taskpd-cpp"
    ]
    exported = load_config(law / "config.toml").controller
    assert exported.params == {
        k.removeprefix("controller.params."): v for k, v in kept["tuned"]["settings"].items()
    }
    certify = load_sweep(out / "cases" / "paper-ellipse-noisy" / "certify.toml")
    run = experiment(certify, base_config(certify), draw(certify, 0), "taskpd-cpp-tuned")
    inputs, torques = recorded_steps(run, DURATION)
    np.testing.assert_array_equal(_replay(_compile_replay(law), inputs), torques)
