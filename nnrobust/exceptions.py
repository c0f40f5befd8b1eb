"""Exceptions of nnrobust: one root, one subclass per kind of problem."""

from __future__ import annotations


class NNRobustError(Exception):
    """Root of every error nnrobust raises on purpose."""


class RobotLoadError(NNRobustError):
    """A robot description could not be loaded (file, XML, robot name)."""

    def __init__(self, source: str, reason: str):
        self.source = source
        self.reason = reason
        super().__init__(f"{source}: {reason}")


class FrameNotFound(NNRobustError):
    """The requested task frame is not in the model."""

    def __init__(self, frame: str, available: list[str]):
        self.frame = frame
        self.available = available
        super().__init__(
            f"task frame {frame!r} not found; frames in the model: {', '.join(available)}"
        )


class ConfigError(NNRobustError):
    """An experiment configuration value is invalid."""

    def __init__(self, key: str, message: str):
        self.key = key
        super().__init__(f"{key}: {message}")


class ModelMismatch(NNRobustError):
    """A model cannot represent the requested robot (wrong structure or size)."""


class RunFolderExists(NNRobustError):
    """The output folder of a run already exists and overwriting was not asked for."""
