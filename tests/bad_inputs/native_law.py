"""Bad inputs: a law in C++."""

from __future__ import annotations

import os
from pathlib import Path

from nnrobust.core import exceptions as ex

from .common import (
    Case,
    _file,
    _toml,
)
from .custom import (
    RunExperiment,
)
from .study import (
    BROKEN_LAWS,
)


def _native_run(folder: Path, cls: str, params: str = "") -> RunExperiment:
    """An experiment file whose controller is a class of a copy of broken_laws.cpp, run."""
    (folder / "broken_laws.cpp").write_text(BROKEN_LAWS.read_text())
    return RunExperiment(
        _toml(
            folder,
            f'base = "paper-ellipse"\n[controller]\nkind = "custom"\nclass = "broken_laws.cpp:{cls}"\n'
            f"{params}\n[simulation]\nduration = 0.01\n",
        ).path
    )


def _damaged_library(folder: Path):
    """A law's cached library truncated, then asked for again (in a cache of the folder's)."""

    def run():
        from nnrobust.plugins import native_law

        source = _file(folder, "tiny.cpp", 'extern "C" int tiny(void) { return 1; }\n')
        before = os.environ.get("NNROBUST_CACHE")
        os.environ["NNROBUST_CACHE"] = str(folder / "cache")
        try:
            library, _ = native_law.compiled_library(source, "controller.class")
            library.write_bytes(library.read_bytes()[:100])
            return native_law.compiled_library(source, "controller.class")
        finally:
            if before is None:
                del os.environ["NNROBUST_CACHE"]
            else:
                os.environ["NNROBUST_CACHE"] = before

    return run


NATIVE_LAW_CASES = [
    Case(
        "law in C++: an exception in compute",
        lambda d: _native_run(d, "Throws"),
        ex.ControllerError,
        "broken_laws.cpp) threw in its compute at t = 0.006 s: std::out_of_range: index 7 of 3",
    ),
    Case(
        "law in C++: a torque of the wrong size",
        lambda d: _native_run(d, "WrongTorque"),
        ex.ControllerError,
        "broken_laws.cpp) returned a torque of 4 entries at t = 0.006 s; the arm has 3 joints",
    ),
    Case(
        "law in C++: a state of the wrong size",
        lambda d: _native_run(d, "WrongState"),
        ex.ControllerError,
        "broken_laws.cpp) returned a state of 2 entries at t = 0.006 s; its state "
        "size is 0 (NNROBUST_USER_LAW's third argument)",
    ),
    Case(
        "law in C++: a missing parameter",
        lambda d: _native_run(d, "NeedsKp"),
        ex.ControllerError,
        "broken_laws.cpp) could not be built: std::invalid_argument: controller.params "
        "needs the field Kp (a law in C++: give controller.params.Kp",
    ),
    Case(
        "law in C++: a damaged cached library",
        _damaged_library,
        None,
        "is damaged or missing (its bytes are not those recorded when it was compiled); compiling it again",
        UserWarning,
    ),
]
"""A law in C++ that fails as a Python law may: the same one-line ControllerError, naming the law
and its file. (One that exits, crashes or never returns ends the process with one line:
tests/plugins/test_native_law_failures.py.)"""
