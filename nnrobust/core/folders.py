"""The one folder protocol every output of nnrobust follows: a folder is locked while a command
writes it (a hidden lock file beside it, held with flock: a second writer is refused at once,
naming the first), files are created afresh (never written through a link left in their place),
a folder of the command's own is refused where a link or a file stands, and the working folder or
an ancestor of it is never an output.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
from pathlib import Path

from .exceptions import NNRobustError, RunFolderError


@contextlib.contextmanager
def locked(folder: str | Path):
    """Hold an exclusive lock on ``folder`` (a hidden ``.<name>.lock`` beside it) for the block:
    a second run into the same folder fails at once, naming the process that holds it.
    """
    folder = Path(folder)
    lock = folder.parent / f".{folder.name}.lock"
    try:
        if lock.is_symlink():  # not a lock nnrobust made: never truncate what it points to
            lock.unlink()
        fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
    except OSError as err:
        raise RunFolderError(f"cannot create {lock}: {err.strerror or err}") from err
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as err:
            if err.errno not in (errno.EAGAIN, errno.EACCES):
                raise
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
            raise RunFolderError(
                f"another nnrobust run (pid {holder}) is writing {folder}; wait for it to "
                "finish or choose another --out"
            ) from None
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, str(os.getpid()).encode(), 0)
            yield folder
        finally:
            with contextlib.suppress(OSError):
                os.unlink(lock)
    finally:
        os.close(fd)


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
    check_place(folder)
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise NNRobustError(f"cannot create {folder.parent}: {err.strerror or err}") from err
    with locked(folder):
        yield folder


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


def own_folder(path: Path) -> Path:
    """``path`` as a folder of the study's own, created if missing: a symbolic link or a file in
    its place (planted in the out folder, or left by something else) is refused, so nothing a
    study writes lands outside its folder.
    """
    if path.is_symlink() or (path.exists() and not path.is_dir()):
        what = "a symbolic link" if path.is_symlink() else "not a folder"
        raise NNRobustError(
            f"{path} is {what}: a study writes only into folders of its own; move it away, or "
            "choose another --out"
        )
    try:
        path.mkdir(exist_ok=True)
    except OSError as err:
        raise NNRobustError(f"cannot create {path}: {err.strerror or err}") from err
    return path
