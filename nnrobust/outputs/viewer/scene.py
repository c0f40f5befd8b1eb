"""A run drawn with meshcat: the arm's URDF visuals, the desired path, the end-effector trace and
an animation in simulated time; recorded offline into a self-contained HTML file.
"""

from __future__ import annotations

import base64
import os
import warnings

import meshcat
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
import umsgpack
from meshcat.servers.tree import SceneTree, find_node, walk

from ...core.exceptions import NNRobustError
from ...model.loading import load_visual_model
from ...run.results import Result
from ...run.run_info import RunInfo

VIEWER_JS = os.path.join(os.path.dirname(meshcat.__file__), "viewer", "dist", "main.min.js")

ROBOT_NODE = "robot"
DESIRED_COLOR = 0x222222
TRACE_COLOR = 0x2CA02C
TARGET_COLOR = 0xD62728
SEEK_SCRIPT = """
function nnrobustSeek() {
  var m = /t=([0-9.]+)/.exec(window.location.hash);
  if (m) { viewer.animator.pause(); viewer.animator.seek(parseFloat(m[1])); }
}
nnrobustSeek();
window.addEventListener("hashchange", nnrobustSeek);
"""
"""Open ``animation.html#t=2.5`` to show the arm paused at t = 2.5 s."""


def meshcat_visualizer_class():
    """Pinocchio's MeshcatVisualizer, imported without trimesh: ``pinocchio.visualize`` also loads
    its viser viewer, which imports trimesh (about 1 s, for a viewer nnrobust does not use) and
    turns itself off when that import fails.
    """
    import sys

    block = "trimesh" not in sys.modules
    if block:
        sys.modules["trimesh"] = None  # "import trimesh" raises ImportError
    try:
        from pinocchio.visualize import MeshcatVisualizer
    finally:
        if block and sys.modules.get("trimesh", 0) is None:
            del sys.modules["trimesh"]

    class UniformObjVisualizer(MeshcatVisualizer):
        """Pinocchio's visualizer, with OBJ meshes sent as :func:`uniform_obj` makes them."""

        def loadMeshFromFile(self, geometry_object):
            """An OBJ file with the same vertex attributes on every face; other formats as Pinocchio
            loads them.
            """
            path = geometry_object.meshPath
            if path and os.path.splitext(path)[1].lower() == ".obj":
                with open(path, encoding="utf-8", errors="replace") as fh:
                    return mg.MeshGeometry(uniform_obj(fh.read()), "obj")
            return super().loadMeshFromFile(geometry_object)

    return UniformObjVisualizer


def uniform_obj(text: str) -> str:
    """The OBJ text with every face's vertices written alike: texture coordinates (``v/vt``) and
    normals (``v//vn``) kept only where every face has them.

    Exporters mix faces with and without them when only some faces are textured; meshcat's
    browser side merges the file's parts into one geometry and fails on parts whose attributes
    differ ("mergeBufferGeometries() failed", then a TypeError that leaves the arm half drawn).
    """
    lines = text.splitlines()
    faces = [line.split()[1:] for line in lines if line.startswith("f ")]
    refs = [corner.split("/") for face in faces for corner in face]
    textured = all(len(r) > 1 and r[1] for r in refs)
    normals = all(len(r) > 2 and r[2] for r in refs)
    if textured and normals or not refs or all(len(r) == 1 for r in refs):
        return text  # already uniform

    def corner(ref: list[str]) -> str:
        parts = ref + ["", ""]
        if textured:
            return f"{parts[0]}/{parts[1]}/{parts[2]}" if normals else f"{parts[0]}/{parts[1]}"
        return f"{parts[0]}//{parts[2]}" if normals else parts[0]

    out = [
        ("f " + " ".join(corner(c.split("/")) for c in line.split()[1:])) if line.startswith("f ") else line
        for line in lines
    ]
    return "\n".join(out) + "\n"


class SceneRecorder:
    """A meshcat window that keeps the scene tree in memory instead of sending it to a server.

    ``meshcat.Visualizer(window=SceneRecorder())`` accepts every drawing command; :meth:`html`
    then writes what meshcat's own server would serve as static HTML, with no socket opened.
    """

    def __init__(self):
        self.tree = SceneTree()

    def send(self, command) -> None:
        """Store one drawing command, as meshcat's server does."""
        data = command.lower()
        path = [p for p in data["path"].split("/") if p]
        blob = umsgpack.packb(data)
        kind = data["type"]
        if kind == "delete":
            if path:
                parent = find_node(self.tree, path[:-1])
                if path[-1] in parent:
                    del parent[path[-1]]
            else:
                self.tree = SceneTree()
            return
        node = find_node(self.tree, path)
        if kind == "set_transform":
            node.transform = blob
        elif kind == "set_object":
            node.object, node.properties = blob, []
        elif kind == "set_property":
            node.properties.append(blob)
        elif kind == "set_animation":
            node.animation = blob

    def html(self, title: str = "nnrobust") -> str:
        """A self-contained page (viewer JavaScript and scene inline) that plays offline."""
        commands, animations = [], []
        for node in walk(self.tree):
            blobs = [node.object] if node.object is not None else []
            blobs += node.properties
            blobs += [node.transform] if node.transform is not None else []
            commands += [create_command(b) for b in blobs]
            if node.animation is not None:  # after every object it animates exists
                animations.append(create_command(node.animation))
        commands += animations
        with open(VIEWER_JS, encoding="utf-8") as fh:
            viewer_js = fh.read()
        return (
            "<!DOCTYPE html>\n<html>\n<head><meta charset=utf-8><title>"
            f'{_escape(title)}</title></head>\n<body style="margin: 0">\n'
            '<div id="meshcat-pane" style="width: 100vw; height: 100vh; overflow: hidden"></div>\n'
            f"<script>{viewer_js}</script>\n<script>\n"
            'var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));\n'
            "function nnrobustApply(b64) {\n"
            "  viewer.handle_command_bytearray(Uint8Array.from(atob(b64), c => c.charCodeAt(0)));\n"
            "}\n" + "".join(commands) + SEEK_SCRIPT + "</script>\n</body>\n</html>\n"
        )


def create_command(blob: bytes) -> str:
    """JavaScript that applies one packed meshcat command synchronously, in document order
    (meshcat's own static HTML uses fetch(), which applies the commands after the page's scripts).
    """
    encoded = base64.b64encode(blob).decode("ascii")
    return f'nnrobustApply("{encoded}");\n'


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _line(points: np.ndarray, color: int) -> mg.Line:
    return mg.Line(
        mg.PointsGeometry(np.ascontiguousarray(points.T, dtype=np.float32)),
        mg.LineBasicMaterial(color=color, linewidth=2),
    )


def world_points(positions: np.ndarray, plane_z) -> np.ndarray:
    """Task positions (N x m, or one m-vector) as world points N x 3 [m].

    The first three coordinates are the position (for a pose, the rest is orientation); a planar
    task's points are placed at height ``plane_z`` (a number or one per point).
    """
    positions = np.atleast_2d(positions)
    npos = min(positions.shape[1], 3)
    points = np.empty((positions.shape[0], 3))
    points[:, :npos] = positions[:, :npos]
    if npos < 3:
        points[:, npos:] = np.reshape(plane_z, (-1, 1))
    return points


def tip_positions(result: Result) -> tuple[np.ndarray, np.ndarray]:
    """World positions of the actual and desired task point, N x 3 each [m]."""
    chain = _chain(result)
    actual = chain[:, -1, :]
    return actual, world_points(result.x_d, actual[:, 2])


def _chain(result: Result) -> np.ndarray:
    """The run's recorded joint origins and task point, N x (n + 1) x 3 [m]."""
    if result.chain is None:
        raise NNRobustError("this run has no recorded chain (result.npz lacks 'chain'); run it again")
    return result.chain


class RunScene:
    """The meshcat drawing of one run: robot visuals from the URDF, paths and a tip marker.

    Args:
        vis: a meshcat Visualizer (live, or on a :class:`SceneRecorder`).
        info: the run's robot (source, locked joints, chain, mesh folders): a :class:`RunInfo`.

    """

    def __init__(self, vis: meshcat.Visualizer, info: RunInfo):
        MeshcatVisualizer = meshcat_visualizer_class()  # noqa: N806 - a class

        locked = None if info.locked_joints is None else list(info.locked_joints)
        model, visual = load_visual_model(info.robot_source, locked, info.chain, info.mesh_folders or ())
        self.vis = vis
        self.robot = MeshcatVisualizer(model, None, visual)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # unsupported geometry is skipped
            self.robot.initViewer(viewer=vis)
            self.robot.loadViewerModel(ROBOT_NODE)
        vis["target"].set_object(mg.Sphere(0.012), mg.MeshLambertMaterial(color=TARGET_COLOR))

    def show(self, q: np.ndarray, target: np.ndarray | None = None, viewer=None) -> None:
        """Place the arm at q (and the target marker) in ``viewer`` (default the scene's own)."""
        self.robot.viewer = viewer if viewer is not None else self.vis
        try:
            self.robot.display(np.asarray(q, dtype=float))
            if target is not None:
                self.robot.viewer["target"].set_transform(_translation(target))
        finally:
            self.robot.viewer = self.vis

    def draw_paths(self, desired: np.ndarray, actual: np.ndarray | None = None) -> None:
        """The desired path (dark) and the actual end-effector trace (green), N x 3 each."""
        self.vis["paths/desired"].set_object(_line(desired, DESIRED_COLOR))
        if actual is not None and len(actual) > 1:
            self.vis["paths/actual"].set_object(_line(actual, TRACE_COLOR))

    def frame_camera(self, points: np.ndarray) -> None:
        """Aim the camera at the middle of ``points`` (the arm over the run and the paths) from the
        front-right, a little above, far enough that all of them are in view.
        """
        target, eye = camera_placement(points)
        self.vis["/Cameras/default"].set_transform(_translation(target))  # the orbit centre
        offset = eye - target  # meshcat's camera node is y-up: world (x, y, z) -> (x, z, -y)
        self.vis["/Cameras/default/rotated/<object>"].set_property(
            "position", [float(offset[0]), float(offset[2]), float(-offset[1])]
        )

    def animate(self, result: Result, desired: np.ndarray, fps: float = 30.0) -> None:
        """Arm and target (``desired``, N x 3) over the run, a keyframe every 1/fps s simulated."""
        times = np.arange(result.t[0], result.t[-1] + 1e-9, 1.0 / fps)
        index = np.minimum(np.searchsorted(result.t, times), result.t.size - 1)
        poses = PoseRecorder()
        for k in index:
            self.show(result.q[k], desired[k], viewer=poses)
        self.vis.set_animation(poses.animation(self.vis, fps), play=True, repetitions=1_000_000)  # "forever"


class PoseRecorder:
    """Stands in for a meshcat viewer while the arm is placed at every keyframe: it keeps each
    node's position and orientation, which :meth:`animation` sends as one track per node and
    property (times and values as typed arrays, not a dictionary per keyframe).
    """

    def __init__(self):
        self.poses: dict[str, tuple[list, list]] = {}

    def __getitem__(self, name: str) -> _NodePoses:
        return _NodePoses(self.poses.setdefault(name, ([], [])))

    def animation(self, vis: meshcat.Visualizer, fps: float) -> KeyframeAnimation:
        """The recorded poses as an animation of the nodes of ``vis``, one keyframe per 1/fps s."""
        return KeyframeAnimation(
            {vis[name].path.lower(): (np.array(p), np.array(q)) for name, (p, q) in self.poses.items()}, fps
        )


class _NodePoses:
    __slots__ = ("positions", "quaternions")

    def __init__(self, lists):
        self.positions, self.quaternions = lists

    def set_transform(self, matrix: np.ndarray) -> None:
        """Keep the position and rotation of a homogeneous matrix; a mesh's scale (Pinocchio puts
        it in the matrix) is divided out as three.js does, so the scale set on the node stays.
        """
        rotation = matrix[:3, :3] / np.linalg.norm(matrix[:3, :3], axis=0)
        if np.linalg.det(rotation) < 0:  # a mirrored mesh: three.js flips its first axis
            rotation[:, 0] = -rotation[:, 0]
        self.positions.append(matrix[:3, 3])
        self.quaternions.append(pin.Quaternion(rotation).coeffs())  # x, y, z, w: three.js's order


class KeyframeAnimation:
    """meshcat's ``set_animation`` payload for tracks given whole: node path -> (F x 3 positions,
    F x 4 quaternions x, y, z, w), keyframe k at k / fps seconds.
    """

    def __init__(self, tracks: dict[str, tuple[np.ndarray, np.ndarray]], fps: float):
        self.tracks, self.fps = tracks, fps

    def lower(self) -> list[dict]:
        """The payload as meshcat's ``Animation.lower`` gives it, each track's keys as typed arrays."""

        def track(name, kind, values):
            return {
                "name": name,
                "type": kind,
                "times": _float32(np.arange(len(values))),
                "values": _float32(values),
            }

        return [
            {
                "path": path,
                "clip": {
                    "fps": self.fps,
                    "name": "default",
                    "tracks": [
                        track(".position", "vector3", positions),
                        track(".quaternion", "quaternion", quaternions),
                    ],
                },
            }
            for path, (positions, quaternions) in self.tracks.items()
        ]


def _float32(values: np.ndarray) -> umsgpack.Ext:
    """A Float32Array for meshcat's viewer (its MessagePack extension 0x17)."""
    return umsgpack.Ext(0x17, np.ascontiguousarray(values, dtype=np.float32).tobytes())


CAMERA_FOV = 75.0
"""meshcat's vertical field of view [deg]."""

CAMERA_DIRECTION = np.array([1.0, -1.0, 0.8]) / np.linalg.norm([1.0, -1.0, 0.8])
"""From the target towards the eye: front-right, a little above."""


def camera_placement(points: np.ndarray, margin: float = 0.15) -> tuple[np.ndarray, np.ndarray]:
    """(target, eye) [m] for a camera that sees every point: the target is the middle of their
    bounding box, and the eye is far enough along :data:`CAMERA_DIRECTION` that their bounding
    sphere, grown by ``margin`` for the links' meshes around the joint origins, fits the vertical
    field of view.
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    target = (points.min(axis=0) + points.max(axis=0)) / 2
    radius = max(float(np.max(np.linalg.norm(points - target, axis=1))) + margin, 0.3)
    distance = radius / np.sin(np.radians(CAMERA_FOV / 2))
    return target, target + distance * CAMERA_DIRECTION


def _translation(p: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def draw_run(vis: meshcat.Visualizer, result: Result, fps: float = 30.0) -> RunScene:
    """The whole run in ``vis``: robot (from ``result.info``), desired path, actual trace, animation."""
    scene = RunScene(vis, _info(result))
    actual, desired = tip_positions(result)
    scene.draw_paths(desired, actual)
    scene.frame_camera(np.vstack([desired, _chain(result).reshape(-1, 3)]))
    scene.show(result.q[0], desired[0])
    scene.animate(result, desired, fps)
    return scene


def _info(result: Result) -> RunInfo:
    if result.info is None:
        raise NNRobustError("the run does not say which robot it ran (no run info): it cannot be drawn")
    return result.info


def animation_html(result: Result, fps: float = 30.0) -> str:
    """A self-contained HTML animation of the run (plays offline; ``#t=SECONDS`` pauses there)."""
    info = _info(result)  # refused before anything is drawn
    recorder = SceneRecorder()
    draw_run(meshcat.Visualizer(window=recorder), result, fps)
    return recorder.html(f"{info.name}: {info.controller}")
