"""URDFs as other projects publish them (issue 34, items 7 and 8): foreign XML namespace prefixes
no xmlns declares, and meshes kept outside the URDF's folder. The dynamics read neither; the viewer
reads meshes only from the folders the rules and ``robot.mesh_folders`` allow, and a run folder
reruns from its config.toml alone."""

import re
import sys
import threading
import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from nnrobust import load_robot
from nnrobust.cli import main
from nnrobust.core.exceptions import UrdfSyntaxError
from nnrobust.model.example_robots import example_robot
from nnrobust.model.loading import load_visual_model, paper_arm_urdf
from nnrobust.model.urdf_check import (
    MeshOutsideFoldersWarning,
    MissingMeshWarning,
    UndeclaredPrefixWarning,
)
from nnrobust.outputs.run_folder import load_run

OPENED: list[str] | None = None
"""Files the recording thread opens while a test records them (:func:`opened`), else None."""

RECORDING: int | None = None
"""The thread that records: another thread's opens (a cluster's monitor reading /proc/PID/stat,
left by an earlier test in this worker) are not the test's."""


def _audit(event: str, args: tuple) -> None:
    if (
        OPENED is not None
        and threading.get_ident() == RECORDING
        and event == "open"
        and isinstance(args[0], (str, bytes, Path))
    ):
        OPENED.append(str(Path(args[0] if not isinstance(args[0], bytes) else args[0].decode()).resolve()))


sys.addaudithook(_audit)  # an audit hook cannot be removed: it records only inside opened()


class opened:  # noqa: N801 - used as a function: `with opened() as files:`
    """The files this thread opens inside the block (Python's ``open`` audit event)."""

    def __enter__(self) -> list[str]:
        global OPENED, RECORDING
        OPENED, RECORDING = [], threading.get_ident()
        return OPENED

    def __exit__(self, *exc) -> None:
        global OPENED, RECORDING
        OPENED, RECORDING = None, None


def _recorded(call, *args, **kwargs):
    """(what ``call`` returns, the messages of every warning it gave)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = call(*args, **kwargs)
    return out, [str(w.message) for w in caught]


def _mass_matrices_agree(a: pin.Model, b: pin.Model, seed: int = 0) -> None:
    """M(q) and the bias forces of two models agree to 1e-12 at seeded random states."""
    assert (a.nq, a.nv, list(a.names)) == (b.nq, b.nv, list(b.names))
    da, db = a.createData(), b.createData()
    rng = np.random.default_rng(seed)
    for _ in range(5):
        q, v = rng.uniform(-3, 3, a.nq), rng.normal(size=a.nv)
        np.testing.assert_allclose(pin.crba(a, da, q), pin.crba(b, db, q), rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            pin.nonLinearEffects(a, da, q, v), pin.nonLinearEffects(b, db, q, v), rtol=0, atol=1e-12
        )


# ---- item 7: undeclared namespace prefixes ------------------------------------------------


def _prefixed_ur5(tmp_path: Path) -> tuple[Path, Path]:
    """example-robot-data's UR5 copied as it is, and with what a curated collection adds: a
    ``drake:acceleration`` on every <limit>, a ``<gazebo:plugin>`` and a ``<xacro:property>``
    leftover, none of their prefixes declared."""
    original = example_robot("ur5").urdf
    assert original is not None
    text = original.read_text()
    clean = tmp_path / "ur5_clean.urdf"
    clean.write_text(text)
    assert "xmlns:drake" not in text and text.count("<limit ") == 6
    prefixed_text = text.replace("<limit ", '<limit drake:acceleration="2.5" ').replace(
        "</robot>",
        '  <gazebo:plugin filename="libgz_ros2_control.so" name="gz_ros2_control">\n'
        "    <parameters>controllers.yaml</parameters>\n  </gazebo:plugin>\n"
        '  <xacro:property name="safety" value="0.1"/>\n</robot>',
    )
    prefixed = tmp_path / "ur5_prefixed.urdf"
    prefixed.write_text(prefixed_text)
    return clean, prefixed


def test_undeclared_prefixes_load_with_one_warning_and_the_same_dynamics(tmp_path):
    """A UR5 with drake: and gazebo: names no xmlns declares loads, with exactly one warning more
    than the clean copy (naming those two, not its declared xacro:), and M(q) and the bias forces
    equal the clean copy's and Pinocchio's own parse of the prefixed file to 1e-12."""
    clean, prefixed = _prefixed_ur5(tmp_path)
    ours, said = _recorded(load_robot, prefixed)
    reference, said_clean = _recorded(load_robot, clean)
    extra = [m for m in said if m not in said_clean]
    assert extra == [
        f"{prefixed}: undeclared XML namespace prefixes drake, gazebo: their elements and "
        "attributes are ignored"  # xacro: is declared on the UR5's <robot>
    ]
    assert len(said) == len(said_clean) + 1
    _mass_matrices_agree(ours.model, reference.model)
    theirs = pin.buildModelFromUrdf(str(prefixed))  # Pinocchio alone reads the file as published
    assert theirs.nq == ours.model.nq
    _mass_matrices_agree(ours.model, theirs)


def test_one_undeclared_prefix_is_named_in_the_singular(tmp_path):
    clean, _ = _prefixed_ur5(tmp_path)
    path = tmp_path / "one.urdf"
    path.write_text(clean.read_text().replace("<limit ", '<limit drake:acceleration="2.5" '))
    with pytest.warns(UndeclaredPrefixWarning) as caught:
        load_robot(path)
    said = [str(w.message) for w in caught if issubclass(w.category, UndeclaredPrefixWarning)]
    assert said == [f"{path}: undeclared XML namespace prefix drake: its elements and attributes are ignored"]


@pytest.mark.parametrize(
    "damage, reason",
    [
        (("</gazebo:plugin>", "</plugin>"), "mismatched tag"),
        (("<parameters>controllers.yaml", "<parameters>&controllers;"), "undefined entity"),
        (('name="safety"', 'name="safety" name="again"'), "duplicate attribute"),
        (
            ('drake:acceleration="2.5"', 'drake:acceleration="2.5" drake:acceleration="3"'),
            "duplicate attribute",
        ),
    ],
)
def test_a_prefixed_file_that_is_also_malformed_is_refused_naming_the_file(tmp_path, damage, reason):
    """Declaring the prefixes repairs nothing else: a mismatched tag, an undefined entity or a
    repeated attribute is still refused, in one line naming the file and the place."""
    _, prefixed = _prefixed_ur5(tmp_path)
    prefixed.write_text(prefixed.read_text().replace(*damage, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # and before any warning about the prefixes
        with pytest.raises(UrdfSyntaxError) as info:
            load_robot(prefixed)
    message = str(info.value)
    assert re.fullmatch(
        rf"{re.escape(str(prefixed))}: malformed XML at line \d+, column \d+: {reason}", message
    ), message


def test_the_viewer_and_the_mimic_rule_read_a_prefixed_file(tmp_path):
    """The viewer parses the file again (its visuals), and the mimic rule before the check: both
    read it with its prefixes declared."""
    text = (
        paper_arm_urdf()
        .read_text()
        .replace('effort="60"', 'drake:acceleration="2.5" effort="60"')
        .replace(
            '<joint name="joint3"',
            '<joint name="joint3" gazebo:ignored="1"',
        )
    )
    mimic = text.replace("</robot>", "") + (
        '<joint name="mimic3" type="revolute"><parent link="link3"/><child link="tip3"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>'
        '<mimic joint="joint3"/></joint><link name="tip3"><inertial><mass value="0.1"/>'
        '<inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link></robot>'
    )
    path = tmp_path / "arm.urdf"
    path.write_text(mimic)
    robot, said = _recorded(load_robot, path)
    assert robot.joint_names == ["joint1", "joint2", "joint3"]  # the mimic joint is locked
    assert sum("undeclared XML namespace prefixes drake, gazebo" in m for m in said) == 1
    (model, visual), said = _recorded(load_visual_model, path)
    assert model.nq == 3 and len(visual.geometryObjects) == 5
    assert not [m for m in said if "undeclared" in m]  # said once, by the dynamics' load


# ---- item 8: meshes outside the URDF's folder --------------------------------------------

STL = (
    "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0.1 0 0\nvertex 0 0.1 0\n"
    "endloop\nendfacet\nendsolid t\n"
)


def _vendor_package(root: Path, prefixed: bool = False) -> Path:
    """A vendor description package: desc/urdf/robots/arm.urdf (the paper's arm) with its link
    meshes in desc/meshes, named ``../../meshes/linkN.stl`` (outside the URDF's folder and the
    one above it); returns the URDF."""
    robots, meshes = root / "desc" / "urdf" / "robots", root / "desc" / "meshes"
    robots.mkdir(parents=True)
    meshes.mkdir()
    text = paper_arm_urdf().read_text()
    for n, size in ((1, "0.40 0.04 0.03"), (2, "0.36 0.035 0.03"), (3, "0.30 0.03 0.03")):
        (meshes / f"link{n}.stl").write_text(STL)
        box = f'<geometry><box size="{size}"/></geometry>'
        assert box in text
        text = text.replace(box, f'<geometry><mesh filename="../../meshes/link{n}.stl"/></geometry>')
    if prefixed:
        text = text.replace('effort="60"', 'drake:acceleration="2.5" effort="60"')
    path = robots / "arm.urdf"
    path.write_text(text)
    return path


def _mesh_files(visual: pin.GeometryModel) -> list[str]:
    return sorted(Path(g.meshPath).name for g in visual.geometryObjects if g.meshPath.endswith(".stl"))


def test_meshes_outside_the_urdf_folder_never_block_the_dynamics(tmp_path):
    """The dynamics load no mesh, wherever the paths lead (even a URL or /etc/passwd), and give
    the same model as the paper's arm; nothing is opened but the URDF."""
    path = _vendor_package(tmp_path)
    path.write_text(
        path.read_text()
        .replace("../../meshes/link2.stl", "/etc/passwd")
        .replace("../../meshes/link3.stl", "http://example.com/link3.stl")
    )
    with opened() as files:
        robot, said = _recorded(load_robot, path)
    assert [f for f in files if not Path(f).is_dir()] == [str(path.resolve())]  # the parser's stderr
    # is caught in an unnamed temporary file (an open of the temporary folder)
    assert not [m for m in said if "mesh" in m]
    _mass_matrices_agree(robot.model, load_robot(paper_arm_urdf()).model)


def test_the_viewer_reads_meshes_only_from_the_allowed_folders(tmp_path, monkeypatch):
    """Outside the allowed folders the viewer opens nothing (one warning says how many meshes it
    leaves out and names robot.mesh_folders); robot.mesh_folders lets it read that folder only,
    not a file a symbolic link inside it leads out to."""
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    path = _vendor_package(tmp_path)
    meshes = tmp_path / "desc" / "meshes"
    secret = tmp_path / "secret.stl"
    secret.write_text(STL)
    (meshes / "link3.stl").unlink()
    (meshes / "link3.stl").symlink_to(secret)  # inside a listed folder, leading out of it
    with opened() as files:
        (_, visual), said = _recorded(load_visual_model, path)
    assert _mesh_files(visual) == [] and not [f for f in files if f.endswith(".stl")]
    assert said == [
        f"{path}: 3 visual meshes lie outside the folders meshes are read from (first: "
        "'../../meshes/link1.stl'); the run's dynamics do not need them; the viewer draws them "
        "only from folders listed in robot.mesh_folders (besides the URDF's folder, the one above "
        "it and ROS_PACKAGE_PATH)"
    ]
    with opened() as files:
        (_, visual), said = _recorded(load_visual_model, path, mesh_folders=[str(meshes)])
    assert _mesh_files(visual) == ["link1.stl", "link2.stl"]
    assert [m for m in said if "lies outside" in m] == [
        f"{path}: 1 visual mesh lies outside the folders meshes are read from (first: "
        "'../../meshes/link3.stl'); the run's dynamics do not need it; the viewer draws it only "
        "from folders listed in robot.mesh_folders (besides the URDF's folder, the one above it "
        "and ROS_PACKAGE_PATH)"
    ]
    assert str(secret.resolve()) not in files


def _run(argv: list[str], capsys) -> tuple[int, str, list[str]]:
    """(exit code, stderr, warnings not printed) of a command."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main(argv)
    return code, capsys.readouterr().err, [str(w.message) for w in caught]


def test_a_run_on_a_vendor_layout_reruns_from_its_config_toml_alone(tmp_path, capsys, monkeypatch):
    """robot.mesh_folders, relative to the experiment file, is recorded absolute in the run's
    config.toml: rerun from it elsewhere, with no environment variable, the run is the same bit for
    bit and the animation draws the same meshes, read from that folder only. Each warning about
    the URDF is said once per run."""
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    path = _vendor_package(tmp_path / "vendor", prefixed=True)
    meshes = (tmp_path / "vendor" / "desc" / "meshes").resolve()
    experiment = tmp_path / "vendor" / "experiment.toml"
    experiment.write_text(
        'base = "paper-ellipse"\n[robot]\nsource = "desc/urdf/robots/arm.urdf"\n'
        'mesh_folders = ["desc/meshes"]\n[simulation]\nduration = 0.05\n'
    )
    first = tmp_path / "first"
    with opened() as files:
        code, err, unprinted = _run(["run", str(experiment), "--out", str(first), "--no-plots"], capsys)
    assert code == 0, err
    said = err + "\n".join(unprinted)
    assert said.count("undeclared XML namespace prefix drake") == 1
    assert "outside the folders" not in said and "not found" not in said
    stl = sorted(f for f in files if f.endswith(".stl"))
    assert stl == [str(meshes / f"link{n}.stl") for n in (1, 2, 3)]
    recorded = (first / "config.toml").read_text()
    assert f"mesh_folders = [{str(meshes)!r}]".replace("'", '"') in recorded
    assert f'source = "{path.resolve()}"' in recorded

    monkeypatch.chdir(tmp_path)  # from elsewhere: nothing relative to the experiment's folder
    with opened() as files:
        code, err, _ = _run(
            ["run", str(first / "config.toml"), "--out", str(tmp_path / "again"), "--no-plots"], capsys
        )
    assert code == 0, err
    assert sorted(f for f in files if f.endswith(".stl")) == stl
    a, b = load_run(first), load_run(tmp_path / "again")
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.tau, b.tau)
    assert b.info is not None and b.info.mesh_folders == (str(meshes),)
    assert _mesh_files(load_visual_model(b.info.robot_source, mesh_folders=b.info.mesh_folders)[1]) == [
        "link1.stl",
        "link2.stl",
        "link3.stl",
    ]


def test_a_run_that_found_meshes_through_ros_package_path_reruns_without_it(tmp_path, capsys, monkeypatch):
    """The way out that is not recorded (ROS_PACKAGE_PATH) still works, and a run folder made with
    it reruns from its config.toml once it is unset: the same run bit for bit, one warning that
    names robot.mesh_folders, and no mesh read."""
    path = _vendor_package(tmp_path / "vendor")
    experiment = tmp_path / "experiment.toml"
    experiment.write_text(
        f'base = "paper-ellipse"\n[robot]\nsource = "{path}"\n[simulation]\nduration = 0.05\n'
    )
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "vendor" / "desc"))
    first = tmp_path / "first"
    with opened() as files:
        code, err, _ = _run(["run", str(experiment), "--out", str(first), "--no-plots"], capsys)
    assert code == 0, err
    assert len([f for f in files if f.endswith(".stl")]) == 3
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    with opened() as files:
        code, err, unprinted = _run(
            ["run", str(first / "config.toml"), "--out", str(tmp_path / "again"), "--no-plots"], capsys
        )
    assert code == 0, err
    assert not [f for f in files if f.endswith(".stl")]
    said = err + "\n".join(unprinted)
    assert said.count("3 visual meshes lie outside the folders meshes are read from") == 1, said
    assert "robot.mesh_folders" in said
    np.testing.assert_array_equal(load_run(first).q, load_run(tmp_path / "again").q)


def test_a_missing_mesh_is_said_once_per_run(tmp_path, capsys):
    """A visual mesh that does not exist: one warning in the whole run (it was said by the
    dynamics' load and again by the animation's)."""
    path = tmp_path / "arm.urdf"
    path.write_text(
        paper_arm_urdf()
        .read_text()
        .replace(
            '<geometry><box size="0.40 0.04 0.03"/></geometry>',
            '<geometry><mesh filename="meshes/missing.stl"/></geometry>',
        )
    )
    experiment = tmp_path / "experiment.toml"
    experiment.write_text(
        f'base = "paper-ellipse"\n[robot]\nsource = "{path}"\n[simulation]\nduration = 0.05\n'
    )
    code, err, unprinted = _run(
        ["run", str(experiment), "--out", str(tmp_path / "run"), "--no-plots"], capsys
    )
    assert code == 0, err
    said = err + "\n".join(unprinted)
    assert said.count("meshes/missing.stl' not found") == 1, said


def test_mesh_folders_in_an_experiment_file_are_read_from_its_folder(tmp_path):
    """Relative entries of robot.mesh_folders are from the experiment file's folder, as
    robot.source; the filesystem root is refused, in one line naming the key."""
    from nnrobust.config import load_config
    from nnrobust.core.exceptions import ConfigError

    (tmp_path / "sub").mkdir()
    experiment = tmp_path / "sub" / "experiment.toml"
    experiment.write_text('[robot]\nmesh_folders = ["../meshes", "/abs/meshes"]\n')
    config = load_config(experiment)
    assert config.robot.mesh_folders == [str((tmp_path / "meshes").resolve()), "/abs/meshes"]
    experiment.write_text('[robot]\nmesh_folders = ["/"]\n')
    with pytest.raises(ConfigError, match=r"robot.mesh_folders: '/' is not a folder to read meshes from"):
        load_config(experiment)


def test_a_missing_mesh_warning_names_the_mesh(tmp_path):
    """The viewer's missing-mesh warning: one, naming the first mesh and how many are missing."""
    path = _vendor_package(tmp_path)
    for n in (1, 2):
        (tmp_path / "desc" / "meshes" / f"link{n}.stl").unlink()
    with pytest.warns(MissingMeshWarning) as caught:
        _, visual = load_visual_model(path, mesh_folders=[tmp_path / "desc" / "meshes"])
    said = [
        str(w.message)
        for w in caught
        if issubclass(w.category, (MissingMeshWarning, MeshOutsideFoldersWarning))
    ]
    assert len(said) == 1 and said[0].startswith(
        f"{path}: 2 visual meshes not found (first: '../../meshes/link1.stl'"
    )
    assert _mesh_files(visual) == ["link3.stl"]
