"""Exceptions of nnrobust: one root, one subclass per kind of problem."""

from __future__ import annotations

import re
from decimal import Decimal
from pathlib import Path

MAX_MESSAGE = 1000
"""Characters of a message at most: longer ones keep their start and end, the middle elided."""


LONG_NUMBER = re.compile(r"(?<![\w.+])(?<!\w-)(\d[\d_]*(?:\.\d+)?(?:[eE][-+]?\d+)?)(?![\w.])")
"""A number written out in a message (not part of a name, a path or a digest)."""

MAX_DIGITS = 20
"""Digits of a number a message shows as written: longer ones (a 300-digit integer given for a
value) are shown to 6 significant digits, as %.6g shows them."""


def _shortened(match: re.Match) -> str:
    text = match.group(1)
    digits = sum(c.isdigit() for c in text.split("e")[0].split("E")[0])
    if digits <= MAX_DIGITS:
        return text
    try:
        mantissa, e, exponent = format(Decimal(text.replace("_", "")), ".6g").partition("e")
    except ArithmeticError:  # an exponent beyond what Decimal holds
        return text[:8] + f"... ({len(text)} characters)"
    if "." in mantissa:
        mantissa = mantissa.rstrip("0").rstrip(".")
    return mantissa + e + exponent


def one_line(text: str, limit: int = MAX_MESSAGE) -> str:
    r"""A message fit for one terminal line: control characters escaped (a newline shows as \n),
    numbers of more than 20 digits shown to 6 significant digits, at most ``limit`` characters
    with the middle elided.
    """
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    text = LONG_NUMBER.sub(_shortened, text)
    if len(text) > limit:
        head, tail = limit - limit // 5 - 40, limit // 5
        text = f"{text[:head]} ... [{len(text) - head - tail} characters elided] ... {text[-tail:]}"
    return text


class NNRobustError(Exception):
    """Root of every error nnrobust raises on purpose; its text is one line of bounded length."""

    def __str__(self) -> str:
        return one_line(super().__str__())


class RobotLoadError(NNRobustError):
    """A robot description could not be loaded (file, XML, robot name)."""

    def __init__(self, source: str, reason: str):
        self.source = source
        self.reason = reason
        super().__init__(f"{source}: {reason}")


class UrdfRefused(RobotLoadError):
    """A URDF that is not read at all: too large, or with DTD/entity declarations."""


class UrdfSyntaxError(RobotLoadError):
    """A URDF that is not well-formed XML (line and column in the message)."""


class UrdfStructureError(RobotLoadError):
    """A URDF whose links and joints do not form one tree: dangling or duplicate names,
    several roots, a link with two parents, no <robot> root.
    """


class KinematicCycle(UrdfStructureError):
    """A URDF whose joints form a closed loop."""


class InvalidInertia(RobotLoadError):
    """A link with non-positive mass or an inertia that is not physical."""


class UnsafePath(RobotLoadError):
    """A mesh path that resolves outside the allowed folders."""


class FrameNotFound(NNRobustError):
    """The requested task frame is not in the model."""

    def __init__(self, frame: str, available: list[str]):
        self.frame = frame
        self.available = available
        super().__init__(f"task frame {frame!r} not found; frames in the model: {', '.join(available)}")


class ChangedInputs(NNRobustError):
    """A folder holds what other inputs computed; refused unless overwriting
    (nnrobust/studies/base/folder.py).
    """


class ConfigError(NNRobustError):
    """An experiment configuration value is invalid."""

    def __init__(self, key: str, message: str):
        self.key = key
        self.message = message  # what follows the key (a key may itself hold ": ")
        super().__init__(f"{key}: {message}")


class LogError(NNRobustError):
    """A robot's log cannot be identified from: unreadable, a column missing or of the wrong length,
    a NaN, times out of order, or a log that does not excite what the fit needs (the file and
    column named).
    """


class ModelMismatch(NNRobustError):
    """A model cannot represent the requested robot (wrong structure or size)."""


class RunFolderExists(NNRobustError):
    """The output folder of a run already exists and overwriting was not asked for."""


class ControllerError(NNRobustError):
    """A controller broke the contract of :class:`nnrobust.Controller` while running: a torque of the
    wrong shape, a signal it did not declare, a state of the wrong size, or an exception of its own.
    """


class RunFolderError(NNRobustError):
    """The output folder cannot take a run: a file, a link, a folder of the user's, locked, or
    not writable.
    """


class ExtrasInterrupted(KeyboardInterrupt):
    """Ctrl-C (or SIGTERM, SIGHUP) while plots or the animation were written: the run folder is
    complete without them.
    """

    def __init__(self, folder: Path, when: str = "while writing plots"):
        super().__init__(
            f"interrupted {when}; the arrays and metrics are saved in {folder}/ "
            f"('nnrobust plot {folder}' draws the plots and the animation)"
        )
        self.folder = folder
