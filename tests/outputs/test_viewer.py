"""The 3-D views of a run: the offline HTML animation, the loopback-only live viewer, and the
animation rendered by headless Chromium (skipped only where Chromium cannot run)."""

import html
import json
import os
import re
import shutil
import socket
import subprocess
from pathlib import Path

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.config import ExperimentConfig
from nnrobust.config.presets import load_preset
from nnrobust.model import paper_arm_urdf
from nnrobust.outputs.run_folder import write_run
from nnrobust.run.experiment import run_experiment
from nnrobust.run.results import Result

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--window-size=640,480",
    "--virtual-time-budget=2000",
]


@pytest.fixture(scope="module")
def paper_run(tmp_path_factory):
    """A 3 s run of the paper's arm, written with its animation."""
    config = load_preset("paper-ellipse").replace(simulation={"duration": 3.0})
    folder = tmp_path_factory.mktemp("runs") / "paper"
    write_run(folder, run_experiment(config), plots=False)
    return folder


def test_animation_is_one_self_contained_file(paper_run):
    html = (paper_run / "animation.html").read_text()
    assert "new MeshCat.Viewer" in html and "handle_command" in html
    assert "<script src" not in html and "<link" not in html  # nothing fetched from elsewhere
    assert "nnrobustSeek" in html  # #t=SECONDS pauses the replay there
    assert len(html) > 500_000  # the viewer's JavaScript is inline


def test_animation_of_a_meshed_robot_embeds_its_meshes(tmp_path):
    from nnrobust.outputs.viewer import animation_html

    config = load_preset("panda-ellipse").replace(simulation={"duration": 0.1})
    result = run_experiment(config)
    html = animation_html(result)
    assert "panda" in html and len(html) > 5_000_000  # the Panda's meshes travel in the file


def test_animation_tracks_equal_meshcats_own_keyframes():
    """The poses of every node, recorded for all keyframes at once and sent as typed arrays, are
    the keyframes meshcat's own Animation records one by one (its quaternion comes from the
    scaled matrix by an eigen-decomposition), to float32 precision, on the Panda's meshes."""
    import meshcat
    from meshcat.animation import Animation

    from nnrobust.outputs.viewer.scene import PoseRecorder, RunScene, SceneRecorder, tip_positions

    config = load_preset("panda-ellipse").replace(simulation={"duration": 0.5})
    result = run_experiment(config)
    vis = meshcat.Visualizer(window=SceneRecorder())
    scene = RunScene(vis, result.info)
    _, desired = tip_positions(result)
    index = np.arange(0, result.t.size, 33)
    reference, poses = Animation(default_framerate=30), PoseRecorder()
    for frame, k in enumerate(index):
        with reference.at_frame(vis, frame) as keyframe:
            scene.show(result.q[k], desired[k], viewer=keyframe)
        scene.show(result.q[k], desired[k], viewer=poses)
    expected = {entry["path"]: entry["clip"] for entry in reference.lower()}
    ours = poses.animation(vis, 30).lower()
    assert sorted(entry["path"] for entry in ours) == sorted(expected) and len(ours) > 10
    for entry in ours:
        for track, theirs in zip(entry["clip"]["tracks"], expected[entry["path"]]["tracks"]):
            assert (track["name"], track["type"]) == (theirs["name"], theirs["type"])
            times = np.frombuffer(track["times"].data, dtype=np.float32)
            np.testing.assert_array_equal(times, [key["time"] for key in theirs["keys"]])
            values = np.frombuffer(track["values"].data, dtype=np.float32).reshape(times.size, -1)
            wanted = np.array([key["value"] for key in theirs["keys"]])
            if track["name"] == ".quaternion":  # q and -q are the same rotation
                wanted *= np.sign(np.sum(values * wanted, axis=1, keepdims=True))
            np.testing.assert_allclose(values, wanted, atol=1e-6)


@pytest.mark.parametrize("name", ["panda", "anymal_c", "talos_full", "kinova"])
def test_visual_geometry_matches_pinocchios_own_parse(name):
    """The viewer's geometry (meshes set aside, read by the viewer) places every visual where
    Pinocchio's own parse of the URDF does, with the same mesh files, scales and colours."""
    import warnings

    import pinocchio as pin

    from nnrobust.model.example_robots import example_robot
    from nnrobust.model.loading import load_visual_model

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model, visual = load_visual_model(name, locked_joints=[])
    robot = example_robot(name)
    reference_model = pin.buildModelFromUrdf(str(robot.urdf))
    reference = pin.buildGeomFromUrdf(
        reference_model, str(robot.urdf), pin.GeometryType.VISUAL, package_dirs=list(robot.package_dirs)
    )
    assert visual.ngeoms == reference.ngeoms > 0
    for ours, theirs in zip(visual.geometryObjects, reference.geometryObjects):
        assert (ours.name, ours.parentJoint, ours.parentFrame) == (
            theirs.name,
            theirs.parentJoint,
            theirs.parentFrame,
        )
        np.testing.assert_allclose(ours.placement.homogeneous, theirs.placement.homogeneous, atol=1e-12)
        assert Path(ours.meshPath).resolve() == Path(theirs.meshPath).resolve() or not theirs.meshPath
        np.testing.assert_allclose(ours.meshScale, theirs.meshScale)
        np.testing.assert_allclose(ours.meshColor, theirs.meshColor)


def test_the_camera_sees_the_whole_arm_and_path():
    """Every chain point of a Panda run (and the meshes around them) lies inside the camera's
    field of view: the camera aims at their middle, not at the base."""
    from nnrobust.outputs.viewer.scene import CAMERA_FOV, camera_placement, tip_positions

    result = run_experiment(load_preset("panda-ellipse").replace(simulation={"duration": 2.0}))
    _, desired = tip_positions(result)
    points = np.vstack([desired, result.chain.reshape(-1, 3)])
    target, eye = camera_placement(points)
    axis = (target - eye) / np.linalg.norm(target - eye)
    rays = points - eye
    angles = np.degrees(np.arccos(np.clip(rays @ axis / np.linalg.norm(rays, axis=1), -1, 1)))
    assert angles.max() < CAMERA_FOV / 2 - 5  # room for the hand's mesh around its joint origins
    assert target[2] > 0.3  # the middle of the arm, not its base at the origin


def test_run_folders_name_every_figure_that_plots_draws():
    from nnrobust.outputs import plots
    from nnrobust.outputs.run_folder import FIGURE_NAMES

    assert tuple(plots.FIGURES) == FIGURE_NAMES


def _listening_addresses(pid: int) -> list[str]:
    """Local addresses of the LISTEN TCP sockets of process pid (Linux /proc)."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    addresses = []
    for table, width in (("/proc/net/tcp", 8), ("/proc/net/tcp6", 32)):
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "0A" and fields[9] in inodes:  # 0A = LISTEN
                hex_ip, hex_port = fields[1].split(":")
                if width == 8:
                    ip = socket.inet_ntop(socket.AF_INET, bytes.fromhex(hex_ip)[::-1])
                else:
                    raw = bytes.fromhex(hex_ip)  # four little-endian 32-bit words
                    words = b"".join(raw[i : i + 4][::-1] for i in range(0, 16, 4))
                    ip = socket.inet_ntop(socket.AF_INET6, words)
                addresses.append(f"{ip}:{int(hex_port, 16)}")
    return addresses


@pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux /proc to list sockets")
def test_viewer_listens_on_loopback_only(paper_run):
    from nnrobust.outputs.viewer import draw_run, start_viewer

    result = Result.load(paper_run)
    with start_viewer() as viewer:
        draw_run(viewer.vis, result)
        addresses = _listening_addresses(viewer.process.pid)
        assert len(addresses) >= 2, addresses  # web server and ZeroMQ socket
        assert all(a.startswith("127.0.0.1:") for a in addresses), addresses
        assert viewer.web_url.startswith("http://127.0.0.1:")
    assert viewer.process.poll() is not None  # stopped on exit


def test_view_command_serves_a_run(paper_run, capsys):
    assert main(["view", str(paper_run), "--seconds", "0.2"]) == 0
    assert "http://127.0.0.1:" in capsys.readouterr().err
    assert main(["view", str(paper_run.parent / "missing")]) == 2


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def _screenshot(browser: str, page: Path, instant: float, out: Path, profile: Path) -> np.ndarray:
    import matplotlib.image

    cmd = [
        browser,
        *CHROMIUM_FLAGS,
        f"--user-data-dir={profile}",
        f"--screenshot={out}",
        f"{page.resolve().as_uri()}#t={instant}",
    ]
    done = subprocess.run(cmd, capture_output=True, timeout=120, check=False)
    if not out.exists():
        pytest.fail(f"Chromium wrote no screenshot (exit {done.returncode}): {done.stderr[-500:]!r}")
    return matplotlib.image.imread(out)[:, :, :3]


def test_browser_draws_the_arm_and_it_moves(paper_run, tmp_path):
    """Headless Chromium renders animation.html at t = 0.5 s and t = 2.5 s, and the same scene
    without the robot: the arm is where the pictures differ from that background, and it moved."""
    browser = _chromium()
    if browser is None:
        pytest.skip("Chromium is not installed (make test installs Debian's chromium where it can)")
    import meshcat

    from nnrobust.outputs.viewer import SceneRecorder, draw_run

    result = Result.load(paper_run)
    recorder = SceneRecorder()
    draw_run(meshcat.Visualizer(window=recorder), result)
    meshcat.Visualizer(window=recorder)["robot"].delete()
    background_page = tmp_path / "background.html"
    background_page.write_text(recorder.html())
    page = paper_run / "animation.html"
    early = _screenshot(browser, page, 0.5, tmp_path / "early.png", tmp_path / "p1")
    late = _screenshot(browser, page, 2.5, tmp_path / "late.png", tmp_path / "p2")
    background = _screenshot(browser, background_page, 0.5, tmp_path / "bg.png", tmp_path / "p3")
    arm_early = np.abs(early - background).sum(axis=2) > 0.1
    arm_late = np.abs(late - background).sum(axis=2) > 0.1
    moved = np.abs(early - late).sum(axis=2) > 0.1
    assert arm_early.sum() > 500 and arm_late.sum() > 500  # the arm is drawn
    assert moved.sum() > 200  # and it moved between the two instants
    assert (moved & ~(arm_early | arm_late)).sum() < 0.05 * moved.sum()  # only the arm changed


CONSOLE_HOOK = """<script>
window.nnrobustErrors = [];
(function () {
  var error = console.error;
  console.error = function () {
    window.nnrobustErrors.push(Array.prototype.join.call(arguments, " "));
    error.apply(console, arguments);
  };
  window.addEventListener("error", function (e) { window.nnrobustErrors.push("uncaught: " + e.message); });
  setTimeout(function () {
    var out = document.createElement("pre");
    out.id = "nnrobust-errors";
    out.textContent = JSON.stringify(window.nnrobustErrors);
    document.body.appendChild(out);
  }, 1500);
})();
</script>"""
"""Collects console.error calls and uncaught exceptions, and writes them into the page."""


def console_errors(browser: str, page: Path, tmp_path: Path) -> list[str]:
    """What a page sends to console.error or throws, loaded in headless Chromium (its DOM dumped
    after 2 s of virtual time)."""
    hooked = tmp_path / f"hooked-{page.name}"
    hooked.write_text(page.read_text().replace("<head>", "<head>" + CONSOLE_HOOK, 1))
    cmd = [
        browser,
        *CHROMIUM_FLAGS,
        f"--user-data-dir={tmp_path / 'console-profile'}",
        "--dump-dom",
        hooked.resolve().as_uri(),
    ]
    done = subprocess.run(cmd, capture_output=True, timeout=120, check=False, text=True)
    found = re.search(r'<pre id="nnrobust-errors">(.*?)</pre>', done.stdout, re.S)
    if not found:
        pytest.fail(f"the page did not load in Chromium (exit {done.returncode}): {done.stderr[-500:]!r}")
    return json.loads(html.unescape(found.group(1)))


MIXED_OBJ = (
    "\n".join(
        ["o box"]
        + [f"v {x} {y} {z}" for x in (0, 0.1) for y in (0, 0.05) for z in (0, 0.3)]
        + ["vt 0 0", "vt 1 0", "vt 1 1", "vn 1 0 0"]
        + ["f 1/1/1 2/2/1 4/3/1", "f 5/1/1 7/2/1 8/3/1", "f 1//1 5//1 6//1", "f 3//1 4//1 8//1"]
    )
    + "\n"
)
"""An OBJ whose faces mix texture coordinates with none, as exporters write partly textured parts."""


def test_the_browser_reports_no_error_for_a_run_or_a_mixed_obj_mesh(paper_run, tmp_path):
    """The animation loads without a console error: the paper's arm, and an arm whose link is an
    OBJ with mixed faces (which meshcat's browser side cannot merge unless they are made alike)."""
    browser = _chromium()
    if browser is None:
        pytest.skip("Chromium is not installed (make test installs Debian's chromium where it can)")
    from nnrobust.outputs.viewer.scene import uniform_obj

    assert console_errors(browser, paper_run / "animation.html", tmp_path) == []
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "box.obj").write_text(MIXED_OBJ)
    urdf = (
        paper_arm_urdf()
        .read_text()
        .replace(
            '<geometry><box size="0.40 0.04 0.03"/></geometry>',
            '<geometry><mesh filename="meshes/box.obj"/></geometry>',
            1,
        )
    )
    (tmp_path / "arm.urdf").write_text(urdf)
    config = ExperimentConfig().replace(
        robot={"source": str(tmp_path / "arm.urdf")}, simulation={"duration": 0.5}
    )
    write_run(tmp_path / "run", run_experiment(config))
    assert console_errors(browser, tmp_path / "run" / "animation.html", tmp_path) == []
    uniform = uniform_obj(MIXED_OBJ)
    assert "f 1//1 2//1 4//1" in uniform and "f 1//1 5//1 6//1" in uniform  # texture dropped everywhere
    assert uniform_obj(uniform) == uniform


def test_progress_bar_reports_simulated_time_and_speed():
    import io

    from nnrobust.core.progress import ProgressBar

    stream = io.StringIO()
    bar = ProgressBar(4.0, stream=stream, delay=0.0)
    for t in np.arange(0.0, 4.0, 0.05):
        bar(t)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 3  # a line per quarter on a non-terminal (25, 50, 75 %)
    assert "1.00 / 4.00 s simulated" in lines[0] and "x real time" in lines[0]


def test_cli_help_for_every_command(capsys):
    for command in ("run", "plot", "presets", "robots", "compare", "view", "bench"):
        with pytest.raises(SystemExit) as exit_info:
            main([command, "--help"])
        assert exit_info.value.code == 0
        assert "usage: nnrobust" in capsys.readouterr().out
    assert main(["bench", "no_such_benchmark"]) == 2


def test_robots_command_lists_the_known_arms(capsys):
    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    for name, frame in (("panda", "panda_hand_tcp"), ("ur5", "tool0"), ("planar7", "tool")):
        assert any(line.split()[:1] == [name] and frame in line for line in out.splitlines())


def test_module_server_refuses_an_address_it_cannot_bind():
    from nnrobust.core.exceptions import NNRobustError
    from nnrobust.outputs.viewer import start_viewer

    before = set(_children_of(os.getpid()))  # e.g. multiprocessing's resource tracker, from other tests
    with pytest.raises(NNRobustError, match="cannot listen on 203.0.113.1:7999: .*use an address of this"):
        start_viewer(host="203.0.113.1", port=7999, timeout=30)
    assert set(_children_of(os.getpid())) <= before  # no server process was left behind


@pytest.mark.parametrize(
    "args, message",
    [
        (["--port", "0"], "--port 0: a TCP port is 1 to 65535"),
        (["--port", "99999"], "--port 99999: a TCP port is 1 to 65535"),
        (["--host", "no-such-host.invalid"], "--host 'no-such-host.invalid' is not an address"),
    ],
)
def test_view_refuses_bad_addresses_in_one_line(paper_run, capsys, args, message):
    assert main(["view", str(paper_run), "--seconds", "0", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err


def test_command_port_stays_on_loopback_when_the_page_is_shared():
    """--host 0.0.0.0 shares the web page; the unauthenticated ZeroMQ command port stays on 127.0.0.1."""
    from nnrobust.outputs.viewer import start_viewer

    with start_viewer(host="0.0.0.0") as viewer:
        addresses = _listening_addresses(viewer.process.pid)
        assert any(a.startswith("0.0.0.0:") for a in addresses), addresses  # the page
        zmq = [a for a in addresses if not a.startswith("0.0.0.0:")]
        assert zmq and all(a.startswith("127.0.0.1:") for a in zmq), addresses


def test_the_server_does_not_outlive_a_killed_parent(tmp_path):
    """kill -9 of the process that started the viewer: the server exits too (no orphan)."""
    import signal
    import subprocess
    import sys
    import time

    script = (
        "from nnrobust.outputs.viewer import start_viewer\n"
        "v = start_viewer()\nprint(v.process.pid, flush=True)\nimport time\ntime.sleep(60)\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    server = int(parent.stdout.readline())
    parent.send_signal(signal.SIGKILL)
    parent.wait()
    deadline = time.monotonic() + 10
    while _running(server) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _running(server)


def _running(pid: int) -> bool:
    """Whether process pid exists and is not a zombie."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _children_of(pid: int) -> list[int]:
    """Live child processes of pid, from /proc (zombies already reaped do not count)."""
    children = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            children.append(int(stat.parent.name))
    return children


def test_run_with_live_view_streams_the_arm(tmp_path, monkeypatch, capsys):
    """run --view starts the loopback viewer, runs, redraws the finished run, then serves it
    (here stopped at once instead of waiting for Ctrl-C)."""
    import nnrobust.cli.runs as cli

    served = []
    monkeypatch.setattr(
        cli,
        "_serve_until_interrupted",
        lambda viewer, seconds=None: served.append(viewer.process.poll() is None),
    )
    assert (
        main(
            [
                "run",
                "paper-ellipse",
                "--duration",
                "0.5",
                "--view",
                "--no-plots",
                "--out",
                str(tmp_path / "run"),
            ]
        )
        == 0
    )
    assert served == [True]  # the server was up when the run was shown
    assert "live view: http://127.0.0.1:" in capsys.readouterr().err


def test_command_line_basics(capsys):
    """--version, bare `nnrobust` prints the help with the exit codes, and a closed pipe (as with
    `nnrobust presets | head -1`) ends the command quietly."""
    import subprocess
    import sys

    from nnrobust import __version__

    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0 and capsys.readouterr().out.strip() == f"nnrobust {__version__}"
    assert main([]) == 0
    shown = capsys.readouterr().out
    assert "usage: nnrobust" in shown and "exit codes:" in shown and "130" in shown
    pipe = subprocess.run(
        f"{sys.executable} -m nnrobust.cli presets | head -1",
        shell=True,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert pipe.stdout.count("\n") == 1 and pipe.stderr == "", pipe.stderr


def test_an_ipv6_host_gets_a_url_a_browser_can_open():
    """--host ::1 printed http://::1:7000/static/, which no browser opens; the host goes in brackets."""
    from nnrobust.outputs.viewer.server import url_for

    assert url_for("http://::1:7000/static/", "::1") == "http://[::1]:7000/static/"
    assert url_for("http://127.0.0.1:7000/static/", "127.0.0.1") == "http://127.0.0.1:7000/static/"
    assert url_for("http://[::1]:7000/static/", "[::1]") == "http://[::1]:7000/static/"
