"""Output folders of many-run commands (sweep, tune, falsify): marked, locked, resumable, and
replaced only in what the command wrote (docs/bad-inputs.md, "Study folders").

A study folder holds a hidden marker, ``.nnrobust-KIND``, with the :class:`Inputs` its rows are
computed from (a user's own ``sweep.toml`` in a folder never makes it one): the options that
change results and the SHA-256 of every file read, by content, never by path. Running the same
study on the same inputs into it resumes, wherever the folder and its inputs have moved; any
difference is refused, naming what changed, unless ``overwrite``, which removes only the
command's own outputs, never the folder, and never a file of the user's. Every Parquet part
records the inputs' key and is named by the SHA-256 of its bytes, so a part copied from another
run, or changed after it was written, is refused by name. The working folder and its ancestors
are never a study folder.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import uuid
from dataclasses import dataclass
from pathlib import Path

from ...core.exceptions import ChangedInputs, NNRobustError
from ...core.folders import check_place, write_new

INPUTS_FIELD = b"nnrobust.inputs"
"""The key of a Parquet part's metadata that holds its study's :attr:`Inputs.key`."""

PART_NAME = re.compile(r"part-[0-9a-f]{12}-([0-9a-f]{32})\.parquet")
"""A part's name: a random id, then the first 32 hex digits of the SHA-256 of its bytes."""
PART_GLOB = "part-*.parquet"
"""The parts among a folder's files (:data:`PART_NAME` checks each found)."""

MAX_MARKER_BYTES = 1_000_000
"""Largest marker read (a study's is a few kB)."""


@dataclass(frozen=True)
class Inputs:
    """What a study's rows are computed from, by content.

    Attributes:
        options: what changes its results, by name (``--budget``, ``[vary] nn.sigma``, ...), each
            as text.
        files: every file it reads, by the role the file plays (``the base experiment``,
            ``the robot's URDF``, ...): (its path when read, the SHA-256 of its bytes). The path
            is for the reader; only the digest counts, so a moved file or folder resumes.
        version: nnrobust's version.

    """

    options: dict[str, str]
    files: dict[str, tuple[str, str]]
    version: str

    @property
    def key(self) -> str:
        """SHA-256 of the options, the files' digests by role, and the version."""
        identity = {
            "version": self.version,
            "options": self.options,
            "files": {role: digest for role, (_, digest) in self.files.items()},
        }
        return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()

    def to_json(self) -> str:
        """The marker's text."""
        files = {role: {"path": path, "sha256": digest} for role, (path, digest) in self.files.items()}
        data = {"key": self.key, "version": self.version, "options": self.options, "files": files}
        return json.dumps(data, indent=1) + "\n"

    @classmethod
    def from_json(cls, text: str) -> Inputs | None:
        """The inputs a marker records, or None if it records none (an earlier nnrobust's)."""
        try:
            data = json.loads(text)
            files = {role: (str(f["path"]), str(f["sha256"])) for role, f in data["files"].items()}
            return cls({str(k): str(v) for k, v in data["options"].items()}, files, str(data["version"]))
        except (ValueError, KeyError, TypeError, AttributeError, RecursionError):
            return None

    def header(self) -> str:
        """Comment lines for the readable copy of the study: the version and every file's digest."""
        lines = [f"# computed by nnrobust {self.version} from these files (SHA-256):"]
        lines += [f"# {role}: {path} {digest}" for role, (path, digest) in self.files.items()]
        return "\n".join(line.replace("\n", " ") for line in lines) + "\n"

    def change_from(self, old: Inputs) -> str:
        """The first difference from ``old``, the inputs a folder's rows were computed from."""
        if old.version != self.version:
            return f"its rows were computed by nnrobust {old.version}, this is {self.version}"
        for name in [*self.options, *(n for n in old.options if n not in self.options)]:
            then, now = old.options.get(name), self.options.get(name)
            if then != now:
                return f"{name} was {then if then is not None else 'not given'}, now {now or 'not given'}"
        for role in [*self.files, *(r for r in old.files if r not in self.files)]:
            then_file, now_file = old.files.get(role), self.files.get(role)
            if then_file is None and now_file is not None:
                return f"it now reads {role}, {now_file[0]}, which its rows did not"
            if now_file is None and then_file is not None:
                return f"its rows read {role}, {then_file[0]}, which it no longer does"
            if then_file is not None and now_file is not None and then_file[1] != now_file[1]:
                return (
                    f"{role}, {now_file[0]}, has changed since its rows were computed (SHA-256 "
                    f"{then_file[1][:12]}... then, {now_file[1][:12]}... now)"
                )
        return "its inputs differ"  # pragma: no cover  (equal keys)


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (:func:`nnrobust.plugins.user_code.file_digest`), or "missing" if it
    cannot be read.
    """
    from ...plugins.user_code import file_digest

    try:
        return file_digest(path)
    except OSError:
        return "missing"


def recorded_inputs(folder: Path, kind: str) -> Inputs | None:
    """The inputs a ``kind`` folder's marker records (None: no marker, or an earlier one)."""
    marker = Path(folder) / marker_name(kind)
    if not marker.is_file() or marker.stat().st_size > MAX_MARKER_BYTES:
        return None
    return Inputs.from_json(marker.read_text(errors="replace"))


def marker_name(kind: str) -> str:
    """The hidden marker file of a ``kind`` folder (sweep, tuning, falsification)."""
    return f".nnrobust-{kind}"


def prepare(
    folder: Path,
    kind: str,
    study: str,
    outputs: tuple[str, ...],
    overwrite: bool,
    what: str,
    parts: str,
    readable: str,
    inputs: Inputs,
) -> None:
    """Create ``folder`` for a ``kind`` study computed from ``inputs``, or accept it for resuming
    the same one; one computed from other inputs is refused, naming what changed, unless
    ``overwrite``, which removes only ``outputs`` (the names the command writes) before the new
    study starts. Then DIR/``parts`` holds the study's Parquet parts (:func:`parts_folder`) and
    DIR/``readable`` its resolved text ``study`` with the inputs' digests, for the reader.
    """
    check_place(folder)
    marker = folder / marker_name(kind)
    if folder.exists() and not marker.is_file() and any(folder.iterdir()):
        raise NNRobustError(
            f"{folder} exists and is not a {what} folder (no {marker.name}); choose another --out"
        )
    old = recorded_inputs(folder, kind)
    if marker.is_file() and (old is None or old.key != inputs.key):
        if not overwrite:
            why = (
                inputs.change_from(old)
                if old is not None
                else "it was written by an nnrobust that did not record its inputs' digests"
            )
            raise ChangedInputs(
                f"{folder} holds a different {what}: {why}; pass --overwrite to replace what the "
                f"{what} wrote, or choose another --out"
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
    write_new(folder / f".{marker.name}.partial", inputs.to_json())
    os.replace(folder / f".{marker.name}.partial", marker)
    parts_folder(folder, parts)
    write_new(folder / f".{readable}.partial", inputs.header() + study)
    os.replace(folder / f".{readable}.partial", folder / readable)


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


def write_part(folder: Path, table, key: str) -> Path:
    """One Parquet part of a pyarrow ``table`` in ``folder``, tied to its study: ``key`` (the
    :attr:`Inputs.key`) in its metadata and the SHA-256 of its bytes in its name; written to a
    hidden file and renamed into place whole.
    """
    import pyarrow.parquet as pq

    metadata = {**(table.schema.metadata or {}), INPUTS_FIELD: key.encode()}
    name = uuid.uuid4().hex[:12]
    tmp = folder / f".part-{name}.parquet.partial"
    pq.write_table(table.replace_schema_metadata(metadata), tmp)
    digest = file_sha256(tmp)
    path = folder / f"part-{name}-{digest[:32]}.parquet"
    os.replace(tmp, path)
    return path


def _check_part(part: Path, key: str) -> None:
    """Refuse a part whose bytes are not those its name records, or written from other inputs."""
    import pyarrow.parquet as pq

    named = PART_NAME.fullmatch(part.name)
    if named is None or not file_sha256(part).startswith(named.group(1)):
        raise NNRobustError(
            f"{part} was changed after it was written, or not written by this study (its bytes "
            "are not those its name records): delete it and run the same command to recompute "
            "its rows"
        )
    written = (pq.read_schema(part).metadata or {}).get(INPUTS_FIELD, b"")
    if written != key.encode():
        raise NNRobustError(
            f"{part} was computed from other inputs than this folder's (a part copied from "
            "another run): delete it and run the same command to recompute its rows"
        )


def read_parts(
    folder: Path, columns: list[str] | None = None, key: str | None = None, ids: tuple[str, ...] = ()
) -> list:
    """Every Parquet part in ``folder`` (part-*.parquet, in name order) as a pyarrow Table of
    ``columns`` (all if None). A damaged part (a study writes every part whole, so something else
    changed it) is refused by name, never skipped or recomputed silently; with ``key`` (the
    study's :attr:`Inputs.key`), so is a part changed after it was written or computed from other
    inputs (:func:`write_part`), and with ``ids`` (the columns naming a row, among ``columns``) a
    row found twice.
    """
    import pyarrow.parquet as pq

    tables = []
    seen: dict[tuple, Path] = {}
    for part in sorted(folder.glob(PART_GLOB)):
        try:
            table = pq.read_table(part, columns=columns)
        except Exception as err:  # pyarrow raises ArrowInvalid, OSError, ...
            raise NNRobustError(
                f"{part} is not a readable Parquet part ({type(err).__name__}); it was changed "
                "after it was written: delete it and run the same command to recompute its rows"
            ) from err
        if key is not None:
            _check_part(part, key)
        for row in zip(*(table.column(c).to_pylist() for c in ids)) if ids else ():
            if row in seen:
                which = ", ".join(f"{c} {v!r}" for c, v in zip(ids, row))
                raise NNRobustError(
                    f"{folder} holds the row of {which} twice ({seen[row].name} and {part.name}: a "
                    "part copied from another run): delete the copy and run the same command"
                )
            seen[row] = part
        tables.append(table)
    return tables
