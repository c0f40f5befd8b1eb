"""Bad inputs: run folders and the meshcat viewer."""

from __future__ import annotations

import json
import os
from pathlib import Path

from nnrobust.core import exceptions as ex
from nnrobust.outputs.run_folder import RunFolderError

from .common import (
    Case,
    _file,
)


def _fifo(folder: Path) -> Path:
    import os

    path = folder / "pipe.toml"
    os.mkfifo(path)
    return path


def _check_out(folder: Path, overwrite: bool = False):
    from nnrobust.outputs.run_folder import check_out_folder

    return lambda: check_out_folder(folder, overwrite)


def _user_folder(folder: Path) -> Path:
    path = folder / "mine"
    path.mkdir()
    (path / "notes.txt").write_text("my notes")
    return path


def _symlink(folder: Path) -> Path:
    (folder / "real").mkdir()
    (folder / "link").symlink_to(folder / "real")
    return folder / "link"


def _locked_twice(folder: Path):
    from nnrobust.outputs.run_folder import locked

    def action():
        with locked(folder / "run"), locked(folder / "run"):
            pass

    return action


def _damaged_run(folder: Path, damage: str):
    """A run folder written by a short run, then damaged; the action reads it back."""
    import numpy as np

    from nnrobust.config.presets import load_preset
    from nnrobust.outputs.run_folder import load_run, write_run
    from nnrobust.run.experiment import run_experiment

    run = folder / damage
    write_run(
        run,
        run_experiment(load_preset("paper-line").replace(simulation={"duration": 0.05})),
        plots=False,
        animation=False,
    )
    if damage == "truncated":
        data = (run / "result.npz").read_bytes()
        (run / "result.npz").write_bytes(data[: len(data) // 2])
    elif damage == "garbled":
        (run / "metrics.json").write_text("{not json")
    elif damage == "fifo":
        (run / "config.toml").unlink()
        os.mkfifo(run / "config.toml")
    elif damage == "zero":
        (run / "metrics.json").unlink()
        (run / "metrics.json").symlink_to("/dev/zero")
    elif damage == "bomb":  # a member whose central directory says it expands to 4.29 GB
        import zipfile

        with zipfile.ZipFile(run / "result.npz", "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("t.npy", bytes(1 << 16))
        data = bytearray((run / "result.npz").read_bytes())
        entry = data.rindex(b"PK\x01\x02")  # the central directory record; its size field at +24
        data[entry + 24 : entry + 28] = (0xFFFFFFF0).to_bytes(4, "little")
        (run / "result.npz").write_bytes(bytes(data))
    elif damage == "claims":  # t.npy's header claims 10^13 samples (80 TB); 64 bytes follow it
        import io
        import zipfile

        header = io.BytesIO()
        np.lib.format.write_array_header_1_0(
            header, {"descr": "<f8", "fortran_order": False, "shape": (10**13,)}
        )
        with zipfile.ZipFile(run / "result.npz") as archive:
            members = {name: archive.read(name) for name in archive.namelist()}
        members["t.npy"] = header.getvalue() + bytes(64)
        with zipfile.ZipFile(run / "result.npz", "w") as archive:
            for name, data in members.items():
                archive.writestr(name, data)
    elif damage == "shape":
        arrays = dict(np.load(run / "result.npz"))
        arrays["q"] = arrays["q"][:-1]
        np.savez(run / "result.npz", **arrays)
    elif damage in ("text", "complex"):
        arrays = dict(np.load(run / "result.npz"))
        arrays["t"] = arrays["t"].astype(str if damage == "text" else complex)
        np.savez(run / "result.npz", **arrays)
    elif damage == "deep":
        (run / "metrics.json").write_text("[" * 200_000 + "]" * 200_000)
    elif damage == "string":
        metrics = json.loads((run / "metrics.json").read_text())
        metrics["rms_error"] = "small"
        (run / "metrics.json").write_text(json.dumps(metrics))
    else:
        np.savez(run / "result.npz", t=np.array([object()], dtype=object))
    return lambda: load_run(run)


def _viewer(host: str = "127.0.0.1", port: int | None = None):
    from nnrobust.outputs.viewer.server import check_listen_address

    return lambda: check_listen_address(host, port)


VIEWER_CASES = [
    Case(
        "viewer --port 0", lambda d: _viewer(port=0), ex.NNRobustError, "--port 0: a TCP port is 1 to 65535"
    ),
    Case(
        "viewer --port 99999",
        lambda d: _viewer(port=99999),
        ex.NNRobustError,
        "--port 99999: a TCP port is 1 to 65535",
    ),
    Case(
        "viewer --host that does not resolve",
        lambda d: _viewer("no-such-host.invalid"),
        ex.NNRobustError,
        "--host 'no-such-host.invalid' is not an address or host name this machine can resolve",
    ),
    Case(
        "viewer --host of another machine",
        lambda d: _viewer("203.0.113.1", 7999),
        ex.NNRobustError,
        "the viewer cannot listen on 203.0.113.1:7999",
    ),
]

RUN_FOLDER_CASES = [
    Case(
        "--out naming a file",
        lambda d: _check_out(_file(d, "taken", "x")),
        RunFolderError,
        "taken exists and is not a folder",
    ),
    Case(
        "--out naming a symbolic link",
        lambda d: _check_out(_symlink(d)),
        RunFolderError,
        "link is a symbolic link",
    ),
    Case("--out .", lambda d: _check_out(Path(".")), RunFolderError, "not '.' or '..'"),
    Case(
        "--out inside a file",
        lambda d: _check_out(_file(d, "plain", "x") / "run"),
        RunFolderError,
        "plain is a file, not a folder",
    ),
    Case(
        "existing run folder without --overwrite",
        lambda d: _check_out(_file(d, "old", "x").parent),
        ex.RunFolderExists,
        "exists; pass --overwrite",
    ),
    Case(
        "--overwrite on a folder of the user's",
        lambda d: _check_out(_user_folder(d), True),
        RunFolderError,
        "mine is not a run folder (no .nnrobust-run)",
    ),
    Case(
        "a second run into a folder another run is writing",
        _locked_twice,
        RunFolderError,
        "another nnrobust run (pid ",
    ),
    Case(
        "truncated result.npz",
        lambda d: _damaged_run(d, "truncated"),
        RunFolderError,
        "a damaged run folder (result.npz is not an .npz archive: File is not a zip file)",
    ),
    Case(
        "garbled metrics.json",
        lambda d: _damaged_run(d, "garbled"),
        RunFolderError,
        "a damaged run folder (metrics.json cannot be read",
    ),
    Case(
        "object array in result.npz (would need unpickling)",
        lambda d: _damaged_run(d, "pickled"),
        RunFolderError,
        "a damaged run folder (result.npz: t.npy holds Python objects, which are never unpickled)",
    ),
    Case(
        "a received run whose config.toml is a FIFO",
        lambda d: _damaged_run(d, "fifo"),
        RunFolderError,
        "config.toml is not a regular file; a run folder holds regular files",
    ),
    Case(
        "a received run whose metrics.json links to /dev/zero",
        lambda d: _damaged_run(d, "zero"),
        RunFolderError,
        "metrics.json is a symbolic link; a run folder holds regular files",
    ),
    Case(
        "a zip bomb as result.npz (a few kB said to expand to 4.29 GB)",
        lambda d: _damaged_run(d, "bomb"),
        RunFolderError,
        "result.npz would expand to 4.29 GB; at most 4 GB is read",
    ),
    Case(
        "q shorter than t",
        lambda d: _damaged_run(d, "shape"),
        RunFolderError,
        "a damaged run folder (result.npz: q has shape",
    ),
    Case(
        "an array header claiming 80 TB (numpy would allocate it before reading)",
        lambda d: _damaged_run(d, "claims"),
        RunFolderError,
        "a damaged run folder (result.npz: t.npy's header claims shape (10000000000000,) of float64, "
        "8e+04 GB, but holds 64 bytes)",
    ),
    Case(
        "t saved as text",
        lambda d: _damaged_run(d, "text"),
        RunFolderError,
        "a damaged run folder (result.npz: t holds <U",
    ),
    Case(
        "t saved as complex numbers",
        lambda d: _damaged_run(d, "complex"),
        RunFolderError,
        "a damaged run folder (result.npz: t holds complex128 values, not real numbers)",
    ),
    Case(
        "metrics.json nested 200,000 deep",
        lambda d: _damaged_run(d, "deep"),
        RunFolderError,
        "metrics.json is nested too deeply",
    ),
    Case(
        "a string where metrics.json holds a number",
        lambda d: _damaged_run(d, "string"),
        RunFolderError,
        "metrics.json: rms_error is str 'small', not a number",
    ),
]
