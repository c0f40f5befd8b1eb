"""Meshcat views of runs: offline HTML animations and a live viewer bound to loopback."""

from .scene import RunScene, SceneRecorder, animation_html, draw_run
from .server import LiveViewer, start_viewer

__all__ = ["LiveViewer", "RunScene", "SceneRecorder", "animation_html", "draw_run", "start_viewer"]
