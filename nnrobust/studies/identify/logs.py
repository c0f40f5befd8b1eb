"""A robot's joint log, read from the files robots and simulators write: time, positions,
velocities (optional) and torques, one row per sample (docs/identification.md, "Logs").

- **CSV** (a header row) and **Parquet**: a time column (``time``, ``t``, ``stamp`` or
  ``timestamp``, in seconds) and per signal one column per joint, named by index from 0 (``q0``,
  ``q_0``, ``q[0]``) or by joint (``q.panda_joint1``, ``q_panda_joint1``); the signals are ``q``
  (also ``position``), ``dq`` (``velocity``) and ``tau`` (``torque``, ``effort``).
- **Plain text**, one file per signal, as the Gaz et al. Panda log ships: each file either one
  number per line (sample after sample, every joint of a sample in turn) or one sample per line;
  the file's name says its signal (``time``, ``position``, ``velocity``, ``torque``), a folder of
  such files may be given whole.
- **A run folder** nnrobust wrote (``result.npz``): every simulated run is a log.
- **A ROS 2 bag** (a folder with ``metadata.yaml``) or an **MCAP file**: its
  ``sensor_msgs/msg/JointState`` messages (:mod:`.bags`).

Reading checks what no fit can repair, each in one line naming the file and column: a column
missing or of another length, a value that is not a finite number, and times that go back or repeat.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...core.exceptions import LogError, NNRobustError
from .bags import is_bag, read_bag
from .spool import BLOCK, Spool, block_value, first_not_finite

TIME_COLUMNS = ("time", "t", "stamp", "timestamp")
"""Names a time column may have [s]."""

SIGNALS = {
    "q": ("q", "position", "pos"),
    "dq": ("dq", "velocity", "velocities", "vel", "qd"),
    "tau": ("tau", "torque", "effort"),
}
"""Each signal and the names its columns (or text files) may start with."""

TEXT_SUFFIXES = (".txt", ".dat", ".log")

CSV_BLOCK_BYTES = 4 << 20
"""Bytes of a CSV file parsed at a time."""
"""Plain-text files of one signal each."""


@dataclass
class JointLog:
    """A log as read: N samples of n joints, in the file's own units (rad, rad/s, N m).

    Attributes:
        source: what was read (the files, for messages and the record).
        t: sample times [s], N, strictly increasing.
        q: positions, N x n (an array, or a :class:`.spool.Spool` a table is read into).
        dq: velocities, N x n, or None when the log has none (they are then differentiated).
        tau: joint torques, N x n (the torque the joint delivers, gravity included).
        files: every file read, for the record's digests.
        torque_lag: how far after its stamp a torque sample's value holds on average [s]: half a
            control period for a run folder's torque, held over [t_k, t_k + T).

    """

    source: str
    t: np.ndarray
    q: Any
    dq: Any
    tau: Any
    files: list[Path] = field(default_factory=list)
    torque_lag: float = 0.0
    notes: dict = field(default_factory=dict)

    @property
    def samples(self) -> int:
        """N."""
        return len(self.t)

    def segment(self, start: int, stop: int) -> JointLog:
        """Samples ``start:stop``."""
        dq = None if self.dq is None else self.dq[start:stop]
        return JointLog(
            self.source,
            self.t[start:stop],
            self.q[start:stop],
            dq,
            self.tau[start:stop],
            self.files,
            self.torque_lag,
        )


def read_log(
    given: Sequence[str | Path], joints: Sequence[str], topic: str | None = None, locked: Sequence[str] = ()
) -> JointLog:
    """The log in ``given`` (files or folders of one format) for the robot's ``joints``; ``topic``:
    a bag's or MCAP file's JointState topic, where it has several. ``locked``: the joints the model
    holds at their neutral value; a table's position columns named after one of them (or a bag's
    JointState entries) are read into ``notes["locked"]`` (name -> its least and largest value),
    for :func:`check_locked`.
    """
    paths = [Path(p) for p in given]
    if not paths:
        raise LogError("identify needs at least one log file or folder")
    for path in paths:
        if not path.exists():
            raise LogError(f"{path}: no such file or folder")
    if len(paths) == 1 and is_bag(paths[0]):
        t, q, dq, tau, notes = read_bag(paths[0], joints, topic, locked)
        files = sorted(p for p in paths[0].iterdir() if p.is_file()) if paths[0].is_dir() else [paths[0]]
        log = JointLog(str(paths[0]), t, q, dq, tau, files, notes=notes)
        return _checked(
            log, joints, {"t": "the header stamps", "q": "position", "dq": "velocity", "tau": "effort"}
        )
    if len(paths) == 1 and paths[0].is_dir():
        folder = paths[0]
        if (folder / "result.npz").is_file():
            return _run_folder(folder, joints)
        texts = sorted(p for p in folder.iterdir() if p.suffix in TEXT_SUFFIXES)
        if not texts:
            raise LogError(
                f"{folder}: neither a run folder (result.npz) nor a folder of text files "
                "(*.txt, one per signal)"
            )
        return _text_files(texts, joints)
    suffixes = {p.suffix.lower() for p in paths}
    if len(paths) == 1 and suffixes <= {".csv", ".parquet", ".pq"}:
        return _table(paths[0], joints, locked)
    if suffixes <= set(TEXT_SUFFIXES):
        return _text_files(paths, joints)
    raise LogError(
        f"{', '.join(map(str, paths))}: give one CSV or Parquet file, one run folder, one ROS 2 bag or "
        f"MCAP file, or the text files of one log (one per signal: {', '.join(TEXT_SUFFIXES)})"
    )


def _run_folder(folder: Path, joints: Sequence[str]) -> JointLog:
    from ...outputs.run_folder import load_run  # here: the run folder's reader sits a floor below

    try:
        result = load_run(folder)
    except NNRobustError as err:
        raise LogError(str(err)) from err
    period = float(np.median(np.diff(result.t))) if len(result.t) > 1 else 0.0
    log = JointLog(
        str(folder), result.t, result.q, result.dq, result.tau, [folder / "result.npz"], period / 2
    )
    return _checked(log, joints, {"q": "q", "dq": "dq", "tau": "tau", "t": "t"})


def _table(path: Path, joints: Sequence[str], locked: Sequence[str] = ()) -> JointLog:
    """A CSV or Parquet log, read a batch of rows at a time into :class:`.spool.Spool` files, so
    that a long log's signals are never all in memory.
    """
    try:
        if path.suffix.lower() == ".csv":
            import pyarrow as pa  # here: pyarrow is the identify extra's
            from pyarrow import csv

            table = csv.open_csv(path)  # its header and first block, for the names
            column_names = table.schema.names

            def batches(wanted, path=path):  # the time column's type inferred, the signals' float
                return csv.open_csv(
                    path,
                    read_options=csv.ReadOptions(block_size=CSV_BLOCK_BYTES),
                    convert_options=csv.ConvertOptions(
                        include_columns=wanted, column_types={name: pa.float64() for name in wanted[1:]}
                    ),
                )
        else:
            from pyarrow import parquet

            table = parquet.ParquetFile(path)
            column_names = table.schema_arrow.names

            def batches(wanted, file=table):  # a row group at a time: iter_batches over the whole
                for group in range(file.num_row_groups):  # file decodes it all before the first batch
                    yield from file.iter_batches(batch_size=BLOCK, row_groups=[group], columns=wanted)
    except ImportError as err:
        raise LogError(
            f"{path}: reading CSV and Parquet logs needs pyarrow: pip install 'nnrobust[identify]'"
        ) from err
    except Exception as err:  # pyarrow's ArrowInvalid and OSError: a file that is not a table
        raise LogError(f"{path}: not a readable table ({type(err).__name__}: {str(err)[:200]})") from err
    stripped = [name.strip() for name in column_names]  # "time, q0" as spreadsheets write it
    twice = sorted({name for name in stripped if stripped.count(name) > 1})
    if twice:
        raise LogError(f"{path}: the columns {', '.join(twice)} appear twice; each signal of each joint once")
    # names match in any case ("Time", "TAU0", "q.Panda_Joint1"): two that differ only in case are refused
    folded = [name.casefold() for name in stripped]
    alike = sorted({name for name, key in zip(stripped, folded) if folded.count(key) > 1})
    if alike:
        raise LogError(
            f"{path}: the columns {', '.join(alike)} differ only in upper and lower case; column names are "
            "read in any case, so keep one of them"
        )
    columns = dict(zip(folded, column_names))  # each column's name in the file
    shown = dict(zip(folded, stripped))  # each column as the file names it, for the messages
    time = next((c for c in TIME_COLUMNS if c in columns), None)
    if time is None:
        raise LogError(
            f"{path}: no time column (one of {', '.join(TIME_COLUMNS)}); its columns: "
            f"{_listed(dict(zip(stripped, folded)))}"
        )
    names = {"t": shown[time]}
    found: dict[str, list[str]] = {}
    for signal, prefixes in SIGNALS.items():
        chosen = _signal_columns(path, columns, prefixes, [j.casefold() for j in joints], joints)
        if chosen is None:
            if signal == "dq":
                continue
            raise LogError(
                f"{path}: no {signal} columns for the robot's {len(joints)} joints (e.g. {prefixes[0]}0..."
                f"{prefixes[0]}{len(joints) - 1} or {prefixes[0]}.{joints[0]}); its columns: "
                f"{_listed(dict(zip(stripped, folded)))}"
            )
        found[signal] = chosen
        names[signal] = f"{shown[chosen[0]]}..{shown[chosen[-1]]}"
    held_keys = {}
    for joint in locked:  # a locked joint's position, where the log names it
        for prefix in SIGNALS["q"]:
            key = next(
                (f.casefold() for f in (f"{prefix}.{joint}", f"{prefix}_{joint}") if f.casefold() in columns),
                None,
            )
            if key is not None:
                held_keys[joint] = key
                break
    wanted = [time, *(c for chosen in found.values() for c in chosen), *held_keys.values()]
    arrays = {signal: Spool(len(chosen)) for signal, chosen in found.items()}
    times, origin = [], None
    held = {joint: [np.inf, -np.inf] for joint in held_keys}
    try:
        parts = iter(batches([columns[c] for c in dict.fromkeys(wanted)]))
    except Exception as err:  # a column the schema names that cannot be read
        raise LogError(f"{path}: not a readable table ({type(err).__name__}: {str(err)[:200]})") from err
    while True:
        try:
            batch = next(parts, None)
        except Exception as err:  # pyarrow's ArrowInvalid and OSError: damaged rows, a word among numbers
            text = str(err)
            number = re.search(r"CSV column #(\d+)", text)
            if number and int(number.group(1)) < len(stripped):
                raise LogError(
                    f"{path}: column {stripped[int(number.group(1))]!r} is not numbers ({text[:200]})"
                ) from err
            raise LogError(f"{path}: rows cannot be read ({type(err).__name__}: {text[:200]})") from err
        if batch is None:
            break
        at = {name: i for i, name in enumerate(batch.schema.names)}

        def read(key, batch=batch, at=at):
            return batch.column(at[columns[key]])

        seconds, origin = _seconds(path, shown[time], read(time), origin)
        times.append(seconds)
        for signal, chosen in found.items():
            arrays[signal].append(np.column_stack([_numbers(path, shown[c], read(c)) for c in chosen]))
        for joint, key in held_keys.items():
            values = _numbers(path, shown[key], read(key))
            if values.size:
                low, high = held[joint]
                held[joint] = [min(low, float(np.nanmin(values))), max(high, float(np.nanmax(values)))]
    del table, batches
    t = np.concatenate(times) if times else np.zeros(0)
    log = JointLog(str(path), t, arrays["q"], arrays.get("dq"), arrays["tau"], [path])
    if held:
        log.notes["locked"] = held
    return _checked(log, joints, names)


LOCKED_TOLERANCE = 1e-3
"""How far [rad or m] a locked joint may sit from its neutral value in a log, or move in it."""


def check_locked(log: JointLog) -> list[str]:
    """A locked joint that moves in the log is refused (the model holds it still: its motion
    changes every torque of the joints before it); one held still away from its neutral value
    is a warning (the model holds it at 0: its links sit elsewhere). Returns the warnings.
    """
    said = []
    for joint, (low, high) in log.notes.get("locked", {}).items():
        if high - low > LOCKED_TOLERANCE:
            raise LogError(
                f"{log.source}: {joint} is locked (robot.locked_joints, or the robot's rule) but moves over "
                f"[{low:.4g}, {high:.4g}] in the log; the model holds it still, so unlock it "
                "(--locked-joints without it) or log it at rest"
            )
        if max(abs(low), abs(high)) > LOCKED_TOLERANCE:
            said.append(
                f"{joint} is locked at 0 in the model but held at {0.5 * (low + high):.4g} in the log; "
                "the bodies it carries sit elsewhere in the model"
            )
    return said


def _signal_columns(
    path: Path, columns: dict, prefixes: Sequence[str], joints: Sequence[str], named: Sequence[str]
) -> list[str] | None:
    """The columns of one signal, joint by joint (their case-folded names; ``joints`` are the
    robot's joint names case-folded, ``named`` as the robot names them, for the messages), or None
    if the log has none of them; a log with them in two forms, or with an indexed column past the
    robot's joints, is refused.
    """
    chosen: list[str] | None = None
    for prefix in prefixes:
        for form in (
            f"{prefix}{{i}}",
            f"{prefix}_{{i}}",
            f"{prefix}[{{i}}]",
            f"{prefix}.{{j}}",
            f"{prefix}_{{j}}",
        ):
            names = [form.format(i=i, j=j) for i, j in enumerate(joints)]
            present = [n in columns for n in names]
            if all(present):
                if chosen is not None:
                    raise LogError(
                        f"{path}: both {chosen[0]}.. and {names[0]}.. are {prefix} columns of the robot's "
                        "joints; keep one of them"
                    )
                chosen = names
                beyond = form.format(i=len(joints), j="")
                if "{i}" in form and beyond in columns:
                    raise LogError(
                        f"{path}: a column {beyond}: the log has more joints than the robot's "
                        f"{len(joints)} ({', '.join(named)}); name the columns by joint, or lock or drop "
                        "the others"
                    )
            elif any(present):
                missing = [n for n, p in zip(names, present) if not p]
                raise LogError(
                    f"{path}: the log has some {prefix} columns but not {', '.join(missing)} (one per joint: "
                    f"{', '.join(named)})"
                )
    return chosen


def _column(path: Path, name: str, read):
    """A column of a table (or its next batch of rows), read now (a Parquet file's from the file)."""
    try:
        return read()
    except Exception as err:  # pyarrow's ArrowInvalid and OSError: a damaged column
        raise LogError(
            f"{path}: column {name!r} cannot be read ({type(err).__name__}: {str(err)[:200]})"
        ) from err


def _seconds(path: Path, name: str, column, origin: int | None = None) -> tuple[np.ndarray, int | None]:
    """The time column in seconds, and the origin of the next batch's: numbers as they are, a
    timestamp or a duration (Parquet's, or a CSV's ISO times) as seconds since the log's first
    sample (``origin``, its integer ticks; the first batch's first when None), from the integer
    ticks (no rounding).
    """
    import pyarrow as pa

    kind = column.type
    if pa.types.is_timestamp(kind) or pa.types.is_duration(kind):
        ticks = column.cast(pa.int64()).to_numpy(zero_copy_only=False)
        if column.null_count:
            raise LogError(f"{path}: column {name!r} has {column.null_count} empty time stamps")
        per_second = {"s": 1, "ms": 1_000, "us": 1_000_000, "ns": 1_000_000_000}[kind.unit]
        if not ticks.size:
            return ticks.astype(float), origin
        origin = int(ticks[0]) if origin is None else origin
        return (ticks - origin) / per_second, origin
    return _numbers(path, name, column), origin


def _numbers(path: Path, name: str, column) -> np.ndarray:
    try:
        values = np.asarray(column.to_numpy(zero_copy_only=False), dtype=float)
    except (TypeError, ValueError) as err:
        raise LogError(f"{path}: column {name!r} is not numbers ({str(err)[:120]})") from err
    return values


def _text_files(paths: Sequence[Path], joints: Sequence[str]) -> JointLog:
    by_signal: dict[str, Path] = {}
    for path in paths:
        stem = path.stem.lower()
        tokens = set(re.split(r"[^a-z]+", stem))
        matches = [
            s
            for s, names in (("t", ("time", "stamp", "timestamp", "t")), *SIGNALS.items())
            if _named(stem, tokens, names)
        ]
        if len(matches) != 1:
            raise LogError(
                f"{path}: its name must say which one signal it holds (time, position, velocity or torque)"
                + (f"; it names {matches}" if matches else "")
            )
        if matches[0] in by_signal:
            raise LogError(
                f"{path} and {by_signal[matches[0]]} both hold {matches[0]}: give one file per signal"
            )
        by_signal[matches[0]] = path
    for needed in ("t", "q", "tau"):
        if needed not in by_signal:
            what = {"t": "time", "q": "position", "tau": "torque"}[needed]
            raise LogError(
                f"{', '.join(map(str, paths))}: no {what} file among them (its name must say '{what}')"
            )
    t = _text(by_signal["t"], 1)
    arrays = {s: _text(p, len(joints), len(t)) for s, p in by_signal.items() if s != "t"}
    log = JointLog(
        str(by_signal["t"].parent),
        t[:, 0],
        arrays["q"],
        arrays.get("dq"),
        arrays["tau"],
        list(by_signal.values()),
    )
    return _checked(log, joints, {s: p.name for s, p in by_signal.items()})


def _named(stem: str, tokens: set[str], names: Sequence[str]) -> bool:
    return any(n in tokens or (len(n) > 3 and n in stem) for n in names)


def _text(path: Path, n: int, samples: int | None = None) -> np.ndarray:
    try:
        values = np.loadtxt(path, dtype=float, ndmin=2)
    except (OSError, ValueError) as err:
        raise LogError(f"{path}: not a text file of numbers ({str(err)[:160]})") from err
    if values.shape[1] == 1 and n > 1:
        if values.shape[0] % n:
            raise LogError(f"{path}: {values.shape[0]} numbers, not a whole number of samples of {n} joints")
        values = values.reshape(-1, n)
    if values.shape[1] != n:
        raise LogError(f"{path}: {values.shape[1]} numbers per line, the robot has {n} joints")
    if samples is not None and values.shape[0] != samples:
        raise LogError(f"{path}: {values.shape[0]} samples, the time file has {samples}")
    return values


def _checked(log: JointLog, joints: Sequence[str], names: dict[str, str]) -> JointLog:
    """The log refused, in one line naming the column, when no fit could use it."""
    n = len(joints)
    N = len(log.t)
    if N < 2:
        raise LogError(f"{log.source}: {N} samples; a fit needs a trajectory")
    for signal in ("q", "dq", "tau"):
        values = getattr(log, signal)
        if values is None:
            continue
        if values.ndim != 2 or values.shape[1] != n:
            raise LogError(
                f"{log.source}: {names[signal]} has {values.shape[-1]} joints, the robot has {n}: "
                f"{list(joints)}"
            )
        if len(values) != N:
            raise LogError(
                f"{log.source}: {names[signal]} has {len(values)} samples, the time column has {N}"
            )
    for signal in ("t", "q", "dq", "tau"):
        values = getattr(log, signal)
        if values is None:
            continue
        bad = first_not_finite(values)
        if bad is not None:
            column = names[signal] if values.ndim == 1 else f"{names[signal]} (joint {joints[bad[1]]})"
            raise LogError(
                f"{log.source}: {column} is {block_value(values, bad)} at sample {bad[0]}; every value must "
                "be a finite number"
            )
    steps = np.diff(log.t)
    if np.any(steps < 0):
        k = int(np.argmax(steps < 0))
        raise LogError(
            f"{log.source}: {names['t']} goes back at sample {k + 1} ({log.t[k]:.9g} s then "
            f"{log.t[k + 1]:.9g} s); sort the log by time"
        )
    if np.any(steps == 0):
        k = int(np.argmax(steps == 0))
        raise LogError(
            f"{log.source}: {names['t']} repeats {log.t[k]:.9g} s at samples {k} and {k + 1}; each sample "
            "needs its own time"
        )
    return log


def _listed(columns: dict) -> str:
    names = list(columns)
    return ", ".join(names[:12]) + (f", ... ({len(names)} in all)" if len(names) > 12 else "")
