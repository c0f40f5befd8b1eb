"""Hostile input: each bad URDF or experiment file gets its own error class and a clear message,
the command line answers with exit code 2 and one line, and docs/bad-inputs.md is up to date."""

import re
import sys
import warnings
from pathlib import Path

import pytest

from nnrobust.cli import main
from nnrobust.core.exceptions import NNRobustError
from tests.bad_inputs import (
    CASES,
    CONFIG_CASES,
    CUSTOM_CASES,
    NATIVE_LAW_CASES,
    PART_CASES,
    URDF_CASES,
    message_of,
    render_table,
)
from tests.bad_inputs.common import BuildExperiment, ReadConfig

DOCS = Path(__file__).resolve().parents[1] / "docs" / "bad-inputs.md"


@pytest.mark.parametrize("case", CASES, ids=[c.what for c in CASES])
def test_bad_input_gets_its_error_and_message(case, tmp_path):
    action = case.make(tmp_path)
    if case.error is None:
        with pytest.warns(case.warns, match=re.escape(case.fragment)):
            action()
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(case.error) as info:
            action()
    assert isinstance(info.value, NNRobustError)
    assert case.fragment in str(info.value)


@pytest.mark.parametrize(
    "case", [c for c in URDF_CASES if c.error is not None and "frame" not in c.what], ids=lambda c: c.what
)
def test_command_line_answers_a_bad_urdf_with_one_line(case, tmp_path, capsys, monkeypatch):
    """The same URDFs named in an experiment file: exit code 2, one 'nnrobust: error:' line."""
    import nnrobust.model.loading as loading

    captured = {}

    def spy(source, *args, **kwargs):  # learn which source the case loads, then load it via the CLI
        captured["source"] = str(source)
        raise StopIteration

    monkeypatch.setattr(loading, "load_robot", spy)
    import nnrobust

    monkeypatch.setattr(nnrobust, "load_robot", spy)
    try:
        case.make(tmp_path)()
    except StopIteration:
        pass
    monkeypatch.undo()
    source = captured["source"]
    if source.lstrip().startswith("<"):
        path = tmp_path / "inline.urdf"
        path.write_text(source)
        source = str(path)
    experiment = tmp_path / "bad.toml"
    experiment.write_text(f'[robot]\nsource = "{source}"\n')
    capsys.readouterr()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(["run", str(experiment), "--out", str(tmp_path / "run"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("nnrobust: error: "), err
    assert not (tmp_path / "run").exists()


REFUSED = [c for c in CONFIG_CASES + CUSTOM_CASES + PART_CASES + NATIVE_LAW_CASES if c.error is not None]


@pytest.mark.parametrize("case", REFUSED, ids=[c.what for c in REFUSED])
def test_command_line_answers_a_bad_experiment_with_one_line(case, tmp_path, capsys):
    action = case.make(tmp_path)
    if isinstance(action, BuildExperiment):
        path = tmp_path / "experiment.toml"
        path.write_text(action.toml())
    else:
        assert isinstance(action, ReadConfig)
        path = action.path
    code = main(["run", str(path), "--out", str(tmp_path / "run"), "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and err[0].startswith("nnrobust: error: ") and case.fragment in err[0], err
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(
    "argv, flag",
    [
        (["--budget", "0"], "--budget"),
        (["--budget", "1000000000"], "--budget"),
        (["--budget", "10", "--max-rms-torque", "nan"], "--max-rms-torque"),
        (["--budget", "10", "--max-saturated", "2"], "--max-saturated"),
    ],
)
def test_command_line_answers_a_bad_tuning_with_one_line(argv, flag, tmp_path, capsys):
    from nnrobust.cli import main

    code = main(["tune", "paper-ellipse", "--controllers", "pd", "--out", str(tmp_path / "t"), *argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("nnrobust: error:") and flag in err[0]
    assert not (tmp_path / "t").exists()


def test_docs_table_is_up_to_date(tmp_path):
    assert DOCS.read_text() == render_table(tmp_path), "run: python -m tests.bad_inputs"


def test_messages_are_single_lines(tmp_path):
    for case in CASES:
        assert "\n" not in message_of(case, tmp_path), case.what


def _chain(n: int) -> str:
    parts = ['<robot name="r"><link name="l0"/>']
    parts += [
        f'<joint name="j{i}" type="fixed"><parent link="l{i - 1}"/><child link="l{i}"/></joint>'
        f'<link name="l{i}"/>'
        for i in range(1, n)
    ]
    return "".join(parts) + "</robot>"


def _lines_run(action) -> int:
    """The Python lines ``action`` executes (a count, the same on a busy machine as on a quiet one)."""
    count = 0

    def trace(frame, event, arg):
        nonlocal count
        if event == "line":
            count += 1
        return trace

    sys.settrace(trace)
    try:
        action()
    finally:
        sys.settrace(None)
    return count


def test_a_long_chain_is_checked_in_linear_time():
    """The tree and cycle checks are linear in the links: doubling a chain doubles the Python lines
    they execute (a walk per link to the root, which took 59 s for 3000 links, would quadruple
    them); and 45 000 links (4.8 MB, near the element limit) are checked."""
    from nnrobust.model.urdf_check import check_urdf

    small, large = (_lines_run(lambda n=n: check_urdf(_chain(n), "<long chain>")) for n in (1000, 2000))
    assert large / small < 2.3, (small, large)
    check_urdf(_chain(45_000), "<long chain>")


STL = """solid t
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 0.1 0 0
vertex 0 0.1 0
endloop
endfacet
endsolid t
"""


def _ros_workspace(root: Path, missing: bool = False) -> Path:
    """ws/src/my_arm/{urdf/arm.urdf, meshes/l1.stl, meshes/l2.stl}: meshes as package://my_arm/..."""
    from tests.bad_inputs.common import arm

    pkg = root / "ws" / "src" / "my_arm"
    (pkg / "urdf").mkdir(parents=True)
    (pkg / "meshes").mkdir()
    (pkg / "meshes" / "l1.stl").write_text(STL)
    if not missing:
        (pkg / "meshes" / "l2.stl").write_text(STL)
    text = arm(
        visual='<visual><geometry><mesh filename="package://my_arm/meshes/l1.stl"/></geometry></visual>'
    )
    head, tail = text.rsplit("</inertial></link>", 1)  # link l2 gets the second mesh
    text = (
        head + '</inertial><visual><geometry><mesh filename="package://my_arm/meshes/l2.stl"/></geometry>'
        "</visual></link>" + tail
    )
    assert text.count("package://") == 2
    path = pkg / "urdf" / "arm.urdf"
    path.write_text(text)
    return path


def _mesh_files(visual) -> list[str]:
    return sorted(Path(g.meshPath).name for g in visual.geometryObjects if g.meshPath)


def test_package_meshes_in_a_ros_workspace_resolve(tmp_path):
    from nnrobust.model.loading import load_visual_model

    _, visual = load_visual_model(_ros_workspace(tmp_path))
    assert _mesh_files(visual) == ["l1.stl", "l2.stl"]


def test_one_missing_mesh_costs_only_its_part(tmp_path):
    from nnrobust.model.loading import load_visual_model

    with pytest.warns(UserWarning, match="l2.stl' not found"):
        _, visual = load_visual_model(_ros_workspace(tmp_path, missing=True))
    assert _mesh_files(visual) == ["l1.stl"]


def test_ros_package_path_and_text_urdfs_follow_the_mesh_rules(tmp_path, monkeypatch):
    """A URDF copied elsewhere finds package:// meshes through ROS_PACKAGE_PATH; given as text, it
    reads meshes below the working folder only."""
    from nnrobust.model.loading import load_visual_model

    original = _ros_workspace(tmp_path)
    elsewhere = tmp_path / "elsewhere" / "arm.urdf"
    elsewhere.parent.mkdir()
    elsewhere.write_text(original.read_text())
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws" / "src"))
    assert _mesh_files(load_visual_model(elsewhere)[1]) == ["l1.stl", "l2.stl"]
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    text = original.read_text().replace("package://my_arm/", "ws/src/my_arm/")
    monkeypatch.chdir(tmp_path)
    assert _mesh_files(load_visual_model(text)[1]) == ["l1.stl", "l2.stl"]
    monkeypatch.chdir(tmp_path / "elsewhere")  # the same text elsewhere: the meshes are not below it
    with pytest.warns(UserWarning, match="not found"):
        assert _mesh_files(load_visual_model(text)[1]) == []


def test_a_mistyped_set_key_gets_the_suggestion_a_file_gets(capsys):
    assert main(["run", "paper-ellipse", "--set", "controller.Kpp=[10.0]"]) == 2
    err = capsys.readouterr().err
    assert "controller.Kpp: unknown key; did you mean 'controller.Kp'? Valid keys: controller.kind" in err
    assert main(["run", "paper-ellipse", "--set", "controller.zzz=1"]) == 2
    assert "controller.zzz: unknown key. Valid keys:" in capsys.readouterr().err


def test_a_toml_date_in_set_is_refused_before_anything_runs(tmp_path, capsys):
    """A TOML date-time given to a custom law's parameter was simulated, then lost the run when
    config.toml was written (TypeError: cannot write datetime to TOML); now one line, nothing run."""
    laws = Path(__file__).parent / "controllers" / "eq9_again.py"
    words = [
        "run",
        "paper-ellipse",
        "--set",
        "controller.kind=custom",
        "--set",
        f"controller.class={laws}:NeedsGain",
    ]
    words += ["--set", "controller.params.gain=1.0", "--set", "controller.params.limit=1979-05-27T07:32:00Z"]
    assert main([*words, "--set", "simulation.duration=0.1", "--out", str(tmp_path / "run"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "nnrobust: error: --set controller.params.limit: is a TOML date-time (1979-05-27T07:32:00+00:00), "
        'which no key takes; to pass text, quote it: "1979-05-27T07:32:00+00:00"'
    ]
    assert not (tmp_path / "run").exists()


def test_quiet_prints_no_warning(tmp_path, capsys):
    """--quiet is "print nothing but errors": the xarm6 URDF's inertia warning is not printed (the
    run's own warnings stay in metrics.json)."""
    source = Path(__file__).parent / "data" / "pybullet" / "xarm" / "xarm6_robot.urdf"
    path = tmp_path / "x.toml"
    path.write_text(
        f'[robot]\nsource = "{source}"\ntask = "position"\n[trajectory]\n'
        "center = [0.45, 0.0, 0.5]\naxis_a = [0.1, 0.0, 0.0]\naxis_b = [0.0, 0.1, 0.0]\n"
        "[simulation]\nduration = 0.2\n"
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert (
            main(
                ["run", str(path), "--out", str(tmp_path / "run"), "--quiet", "--no-plots", "--no-animation"]
            )
            == 0
        )
    assert not [w for w in caught if "inertial data" in str(w.message)]
    assert capsys.readouterr().err == ""


def test_compare_prints_no_control_characters_from_a_received_folder(tmp_path, capsys):
    """A metrics.json whose texts carry terminal escapes (a received run folder) is printed with
    them escaped: the table and the verdict changes are plain text."""
    import json

    from nnrobust.cli import main

    for name in ("a", "b"):
        assert main(["run", "paper-ellipse", "--duration", "0.3", "--out", str(tmp_path / name),
                     "--quiet", "--no-plots", "--no-animation"]) == 0  # fmt: skip
    path = tmp_path / "a" / "metrics.json"
    metrics = json.loads(path.read_text())
    metrics["status"] = "completed\x1b[2J\x1b[31mEVIL"
    metrics["warnings"] = ["joint speed: \x1b[31mred"]
    path.write_text(json.dumps(metrics))
    capsys.readouterr()
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    out = capsys.readouterr()
    assert "\x1b" not in out.out + out.err
    assert "completed\\x1b[2J" in out.out


def test_long_numbers_in_messages_are_shown_to_six_digits(capsys):
    """A 300-digit integer given for a value was echoed whole into errors and warnings; every
    message line shows numbers of more than 20 digits as %.6g does (names, paths and digests
    that hold digits are left as they are)."""
    from nnrobust.cli.console import warning_line as _warning_line
    from nnrobust.core.exceptions import ConfigError, one_line

    assert one_line(f"got {'9' * 300} and -{'1' * 30}") == "got 1e+300 and -1.11111e+29"
    assert one_line(f"x = 0.{'0' * 300}1, y = 0.30000000000000004") == "x = 1e-301, y = 0.30000000000000004"
    kept = f"part-{'0' * 32}.parquet sha {'1' * 64}ab run_{'2' * 25}"
    assert one_line(kept) == kept
    assert str(ConfigError("samples", f"got {'9' * 300}")) == "samples: got 1e+300"
    _warning_line(UserWarning(f"value {'7' * 300}"), UserWarning, "f", 1)
    assert capsys.readouterr().err == "warning: value 7.77778e+299\n"


def test_bench_refuses_an_out_that_is_a_file_before_any_benchmark(tmp_path, capsys, monkeypatch):
    """bench --out FILE ran 91 s of benchmark, then ended in a traceback writing its JSON."""
    import subprocess

    def no_benchmark(*args, **kwargs):
        raise AssertionError("a benchmark ran before --out was checked")

    monkeypatch.setattr(subprocess, "Popen", no_benchmark)
    (tmp_path / "file").write_text("")
    (tmp_path / "folder" / "step_scaling.json").mkdir(parents=True)
    for out, words in (
        ("file", "exists and is not a folder; bench writes one <name>.json per benchmark"),
        ("file/sub", "cannot make the folder (Not a directory)"),
        ("folder", "step_scaling.json is a folder; the benchmark writes a file there"),
    ):
        assert main(["bench", "step_scaling", "--out", str(tmp_path / out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"nnrobust: error: --out {tmp_path / out}: "), err
        assert words in err[0], err


def test_a_preset_typo_gets_a_suggestion_on_every_command(tmp_path, capsys):
    """run, sweep and tune named the presets but not the one a typo was close to."""
    sweep = tmp_path / "s.toml"
    sweep.write_text('name = "s"\nbase = "paper-elipse"\ncontrollers = ["pd"]\n')
    for words in (
        ["run", "paper-elipse"],
        ["sweep", str(sweep), "--out", str(tmp_path / "s")],
        ["tune", "paper-elipse", "--controllers", "pd", "--budget", "4", "--out", str(tmp_path / "t")],
    ):
        assert main(words) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "'paper-elipse' is neither" in err[0], err
        assert "; did you mean 'paper-ellipse'? presets: panda-ellipse" in err[0], err


def test_a_utf8_byte_order_mark_is_read_as_nothing(tmp_path):
    """A file saved with a UTF-8 BOM (as editors on Windows do) reads as the same file without it
    (it was "Invalid statement (at line 1, column 1)")."""
    from nnrobust.config import load_config

    text = 'base = "paper-ellipse"\n[simulation]\nduration = 3.0\n'
    (tmp_path / "plain.toml").write_text(text)
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + text.encode())
    plain, bom = (load_config(tmp_path / name) for name in ("plain.toml", "bom.toml"))
    assert bom.simulation.duration == 3.0 and bom.to_toml() == plain.to_toml().replace("plain", "bom")
