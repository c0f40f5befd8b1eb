"""Pinocchio's URDF parser called the one way every loader of the model room calls it: what the
C++ parser prints is caught (never noise on the terminal), and its failure is one
:class:`~nnrobust.core.exceptions.RobotLoadError` naming the robot and quoting the parser. A leaf
of the room: the loaders (``loading``, ``example_robots``) import it, it imports none of them.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile

from ..core.exceptions import RobotLoadError


@contextlib.contextmanager
def parser_messages():
    """Catch what the C++ URDF parser prints on the process's stderr (file descriptor 2), so that
    it never reaches the terminal as noise; the block gets a list that holds the text afterwards.
    """
    said: list[str] = []
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 2)
        try:
            yield said
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            said.append(sink.read(100_000).decode(errors="replace"))


def parsed(name: str, what: str, build):
    """``build()`` (a call of Pinocchio's URDF parser) with what the parser prints caught; its
    failure is one RobotLoadError, "``what``: the error (the parser says: its first line)".
    """
    failure = None
    with parser_messages() as said:
        try:
            return build()
        except (ValueError, RuntimeError) as err:
            failure = err
    printed = [" ".join(line.split()) for line in "".join(said).splitlines() if line.strip()]
    detail = f"{failure} (the parser says: {printed[0]})" if printed else str(failure)
    raise RobotLoadError(name, f"{what}: {detail}") from failure
