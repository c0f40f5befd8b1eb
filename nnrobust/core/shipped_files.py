"""Files that travel with a cluster's tasks (docs/robustness.md, "A cluster without shared files").

A command run on a cluster it did not start (``--scheduler``) cannot count on the workers seeing
the client's files. The client reads every file its rows are computed from once, each checked
against the SHA-256 its study recorded (:func:`bundle_of`), and sends them with the tasks as one
:class:`Bundle`. On a worker, a task runs within the bundle (:func:`run_within`): the files are
written once into a cache folder of the bundle's own, mirroring the client's absolute paths, each
checked against its SHA-256 (:func:`materialise`); then every open of a user's file (the URDF, a
class file, a policy's ONNX file) reads, through :func:`local`, the copy of the client's path.
Paths keep naming the client's files in configurations, rows and messages: only the bytes come
from the copy, so that a row is the same whichever machine computed it.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import shutil
import tempfile
import threading
import uuid
import weakref
from collections.abc import Callable, Iterable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass
from pathlib import Path, PurePosixPath, PureWindowsPath
from typing import Any

from .exceptions import NNRobustError

CACHE = "nnrobust-inputs"
"""The folder of the temporary folder (``tempfile.gettempdir()``) where a worker keeps the
bundles it received, one folder each, named by :attr:`Bundle.digest` (per user: ``-<uid>``)."""


@dataclass(frozen=True)
class ShippedFile:
    """One file of a :class:`Bundle`.

    Attributes:
        mirror: where its copy lies in the bundle's folder: the client's absolute path without
            its root (``home/me/arm.urdf``), "/"-separated.
        sha256: the SHA-256 the client's study recorded for it.
        data: its bytes, as the client read them.

    """

    mirror: str
    sha256: str
    data: bytes


@dataclass(frozen=True, eq=False)
class Bundle:
    """The files a command's rows read, by the path the run's configuration names them with.
    Compared by identity: each bundle a worker receives is checked once (:func:`materialise`).
    """

    files: dict[str, ShippedFile]

    @property
    def digest(self) -> str:
        """SHA-256 of the paths and their files' digests: the name of the bundle's cache folder."""
        text = "\n".join(f"{path}\0{f.mirror}\0{f.sha256}" for path, f in sorted(self.files.items()))
        return hashlib.sha256(text.encode()).hexdigest()


def _key(path: str | os.PathLike) -> str:
    """A path as the bundle and :func:`local` compare it (``a//b/./c`` is ``a/b/c``)."""
    return os.path.normpath(os.fspath(path))


def _mirror(path: str) -> str:
    """The client's absolute path of ``path`` without its root, "/"-separated (a Windows drive
    ``C:`` becomes a folder ``C``).
    """
    absolute = os.path.abspath(path)
    pure = PureWindowsPath(absolute) if os.name == "nt" else PurePosixPath(absolute)
    parts = list(pure.parts[1:])
    if pure.drive:
        parts.insert(0, pure.drive.rstrip(":").replace("\\", "_").strip("_") or "drive")
    return "/".join(parts)


def bundle_of(files: Iterable[tuple[str, str]]) -> Bundle:
    """The bundle of ``files``, (path, SHA-256) pairs as a study records them
    (:attr:`nnrobust.studies.base.folder.Inputs.files`), read now. What is not a regular file (a robot's
    name, URDF text, a file that was missing) is left out: a worker has no copy of it either. A
    file whose bytes are no longer those its digest was taken of is one error naming it.
    """
    shipped: dict[str, ShippedFile] = {}
    for path, sha256 in files:
        if not os.path.isfile(path):
            continue
        try:
            data = Path(path).read_bytes()
        except OSError as err:
            raise NNRobustError(
                f"{path}: cannot read it to send to the workers: {err.strerror or err}"
            ) from err
        now = hashlib.sha256(data).hexdigest()
        if now != sha256:
            raise NNRobustError(
                f"{path}: changed while the command ran (SHA-256 {sha256[:12]}... when its inputs were "
                f"recorded, {now[:12]}... now); run the command again"
            )
        shipped[_key(path)] = ShippedFile(_mirror(path), sha256, data)
    return Bundle(shipped)


def cache_root() -> Path:
    """The folder of this user's bundles in the temporary folder (:data:`CACHE`)."""
    uid = getattr(os, "getuid", None)
    return Path(tempfile.gettempdir()) / (f"{CACHE}-{uid()}" if uid else CACHE)


def _checked(bundle: Bundle) -> None:
    """Every file's bytes as they arrived against the SHA-256 the client recorded."""
    for path, file in bundle.files.items():
        parts = PurePosixPath(file.mirror).parts
        if not parts or file.mirror.startswith("/") or any(p in ("..", ".") for p in parts):
            raise NNRobustError(f"{path}: the bundle places it at {file.mirror!r}, outside its folder")
        now = hashlib.sha256(file.data).hexdigest()
        if now != file.sha256:
            raise NNRobustError(
                f"{path}: its bytes on this worker have SHA-256 {now[:12]}..., not the client's "
                f"{file.sha256[:12]}...; refused (damaged on the way?)"
            )


def _copies(bundle: Bundle, folder: Path) -> dict[str, Path]:
    return {path: folder.joinpath(*PurePosixPath(f.mirror).parts) for path, f in bundle.files.items()}


def _intact(bundle: Bundle, folder: Path) -> bool:
    """Whether ``folder`` holds every file of the bundle with its SHA-256."""
    for path, copy in _copies(bundle, folder).items():
        try:
            if hashlib.sha256(copy.read_bytes()).hexdigest() != bundle.files[path].sha256:
                return False
        except OSError:
            return False
    return True


def _own_folder(root: Path) -> None:
    """``root`` a folder of this user's (made, readable by no one else, if missing): never a
    link, nor another user's, whose files a task would otherwise run.
    """
    root.mkdir(mode=0o700, parents=True, exist_ok=True)
    info = os.lstat(root)
    uid = getattr(os, "getuid", None)
    if root.is_symlink() or (uid is not None and info.st_uid != uid()):
        raise NNRobustError(
            f"{root}: a link or another user's folder; the worker keeps the files it is sent in a "
            "folder of its own (set TMPDIR to one for the worker)"
        )


_LOCK = threading.Lock()
_READY: dict[Path, dict[str, Path]] = {}
"""The bundles' folders this process has checked on disk: folder -> {client path: copy}."""
_RECEIVED: weakref.WeakSet[Bundle] = weakref.WeakSet()
"""The bundles this process has received and checked (one object serves every task of a
worker while it holds the shared future)."""


def materialise(bundle: Bundle, root: Path | None = None) -> dict[str, Path]:
    """The bundle's files on this machine, {path as the run names it: its copy}: written into
    ``root/<digest>/`` (default :func:`cache_root`), each at the client's absolute path, once per
    machine. Each file's bytes are checked against the SHA-256 the client recorded first, once
    per bundle received (a mismatch is one error naming the file). The folder is written whole
    under another name and renamed into place, so that tasks running together on one machine
    never see half of it; a folder found with other contents is replaced.
    """
    root = cache_root() if root is None else Path(root)
    folder = root / bundle.digest
    with _LOCK:
        if bundle not in _RECEIVED:
            _checked(bundle)
            _RECEIVED.add(bundle)
        known = _READY.get(folder)
        if known is not None and folder.is_dir():
            return known
        _own_folder(root)
        if folder.is_dir() and not _intact(bundle, folder):
            stale = root / f".{bundle.digest}.stale-{uuid.uuid4().hex}"
            with contextlib.suppress(OSError):
                os.rename(folder, stale)
                shutil.rmtree(stale, ignore_errors=True)
        if not folder.is_dir():
            staging = root / f".{bundle.digest}.{uuid.uuid4().hex}"
            try:
                for path, copy in _copies(bundle, staging).items():
                    copy.parent.mkdir(parents=True, exist_ok=True)
                    copy.write_bytes(bundle.files[path].data)
            except OSError as err:
                shutil.rmtree(staging, ignore_errors=True)
                raise NNRobustError(
                    f"{root}: cannot write the files sent to this worker ({err.strerror or err}); "
                    "give it room, or set TMPDIR to another folder for the worker"
                ) from err
            try:
                os.rename(staging, folder)
            except OSError:  # another process put it in place first
                shutil.rmtree(staging, ignore_errors=True)
            if not _intact(bundle, folder):
                raise NNRobustError(f"{folder}: the files written there are not those sent; refused")
        copies = _copies(bundle, folder)
        _READY[folder] = copies
        return copies


_COPIES: ContextVar[dict[str, Path] | None] = ContextVar("nnrobust_shipped_files", default=None)
"""The copies of the bundle the running task reads (a context variable: a worker runs tasks in
threads)."""


def local(path: str | os.PathLike) -> Path:
    """Where to read ``path``, a file the client names: its copy when the running task brought
    the file with it (:func:`within`), else ``path`` itself.
    """
    copies = _COPIES.get()
    if copies:
        copy = copies.get(_key(path))
        if copy is not None:
            return copy
    return Path(path)


def shipped(path: str | os.PathLike) -> bool:
    """Whether ``path`` is read from a copy the running task brought with it."""
    copies = _COPIES.get()
    return copies is not None and _key(path) in copies


@contextlib.contextmanager
def within(bundle: Bundle, root: Path | None = None) -> Iterator[dict[str, Path]]:
    """The block reads the bundle's files from their copies on this machine (:func:`materialise`
    into ``root``, :func:`local`).
    """
    token = _COPIES.set(materialise(bundle, root))
    try:
        yield _COPIES.get() or {}
    finally:
        _COPIES.reset(token)


def run_within(bundle: Bundle, function: Callable[..., Any], *args: Any) -> Any:
    """``function(*args)`` run within ``bundle`` (:func:`within`): what a task of a cluster that
    does not see the client's files runs.
    """
    with within(bundle):
        return function(*args)
