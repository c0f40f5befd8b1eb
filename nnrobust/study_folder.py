"""Output folders of many-run commands (sweep, tune, falsify): marked, locked, resumable, and
replaced only in what the command wrote (docs/bad-inputs.md, "Run folders").

A study folder holds a hidden marker, ``.nnrobust-KIND``, with the resolved study it belongs to
(a user's own ``sweep.toml`` in a folder never makes it one). Running the same study into it
resumes; a different study is refused unless ``overwrite``, which removes only the command's
own outputs, never the folder, and never a file of the user's. The working folder and its
ancestors are never a study folder.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from pathlib import Path

from .exceptions import NNRobustError


def marker_name(kind: str) -> str:
    """The hidden marker file of a ``kind`` folder (sweep, tuning, falsification)."""
    return f".nnrobust-{kind}"


def check_place(folder: Path, option: str = "--out") -> None:
    """Refuse a folder that is the working folder or one of its ancestors, or a file."""
    here = Path.cwd().resolve()
    target = folder.resolve()
    if target == here or target in here.parents:
        raise NNRobustError(
            f"{option} {folder}: is the working folder or one of its ancestors; a study "
            "writes into a folder of its own (e.g. --out out/study)"
        )
    if folder.exists() and not folder.is_dir():
        raise NNRobustError(f"{option} {folder}: is a file, not a folder; choose another {option}")
    blocking = next((p for p in folder.parents if p.exists()), None)
    if blocking is not None and not blocking.is_dir():
        raise NNRobustError(f"{option} {folder}: {blocking} is a file, not a folder; choose another {option}")


@contextlib.contextmanager
def held(folder: Path):
    """The study folder checked (:func:`check_place`) and locked for the block: a second command
    into it fails at once instead of writing every row twice.
    """
    from .run_folder import locked

    check_place(folder)
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise NNRobustError(f"cannot create {folder.parent}: {err.strerror or err}") from err
    with locked(folder):
        yield folder


def prepare(
    folder: Path,
    kind: str,
    study: str,
    outputs: tuple[str, ...],
    overwrite: bool,
    what: str,
    parts: str,
    readable: str,
) -> None:
    """Create ``folder`` for a ``kind`` study (its resolved text ``study``), or accept it for
    resuming the same one; a different one is refused unless ``overwrite``, which removes only
    ``outputs`` (the names the command writes) before the new study starts. Then DIR/``parts``
    holds the study's Parquet parts (:func:`parts_folder`) and DIR/``readable`` its resolved text,
    for the reader.
    """
    check_place(folder)
    marker = folder / marker_name(kind)
    if folder.exists() and not marker.is_file() and any(folder.iterdir()):
        raise NNRobustError(
            f"{folder} exists and is not a {what} folder (no {marker.name}); choose another --out"
        )
    if marker.is_file() and marker.read_text() != study:
        if not overwrite:
            raise NNRobustError(
                f"{folder} holds a different {what} ({marker.name} differs); pass "
                f"--overwrite to replace what the {what} wrote, or choose another --out"
            )
        for name in outputs:
            path = folder / name
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            elif path.exists() or path.is_symlink():
                path.unlink()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise NNRobustError(f"cannot create {folder}: {err.strerror or err}") from err
    write_new(folder / f".{marker.name}.partial", study)
    os.replace(folder / f".{marker.name}.partial", marker)
    parts_folder(folder, parts)
    write_new(folder / f".{readable}.partial", study)
    os.replace(folder / f".{readable}.partial", folder / readable)


def write_new(path: Path, text: str) -> None:
    """Write ``text`` to a file created afresh: whatever was at ``path`` (a planted symlink, a
    stale partial file) is removed first, and the file is created exclusively, so nothing is
    written through a link.
    """
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o644)
    with os.fdopen(fd, "w", encoding="utf-8") as fh:
        fh.write(text)


def parts_folder(folder: Path, name: str) -> Path:
    """DIR/name, the folder of a study's Parquet parts, created if missing; refused if something
    else holds its place.
    """
    path = folder / name
    if path.exists() and (path.is_symlink() or not path.is_dir()):
        raise NNRobustError(
            f"{path} is not a folder: a study keeps its rows there as Parquet parts; move it away "
            "and run the same command to resume"
        )
    path.mkdir(exist_ok=True)
    return path


def read_parts(folder: Path, columns: list[str] | None = None) -> list:
    """Every Parquet part in ``folder`` (part-*.parquet, in name order) as a pyarrow Table of
    ``columns`` (all if None). A damaged part (a study writes every part whole, so something else
    changed it) is refused by name, never skipped or recomputed silently.
    """
    import pyarrow.parquet as pq

    tables = []
    for part in sorted(folder.glob("part-*.parquet")):
        try:
            tables.append(pq.read_table(part, columns=columns))
        except Exception as err:  # pyarrow raises ArrowInvalid, OSError, ...
            raise NNRobustError(
                f"{part} is not a readable Parquet part ({type(err).__name__}); it was changed "
                "after it was written: delete it and run the same command to recompute its rows"
            ) from err
    return tables
