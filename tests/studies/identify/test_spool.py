"""A long log read a batch at a time (nnrobust/studies/identify/spool.py and the table readers):
the spooled array reads back what was written, by any rows a reader asks, and a Parquet log of
many row groups, read batch by batch, gives the same log and the same states as one read whole."""

import numpy as np
import pytest

from nnrobust.studies.identify import logs
from nnrobust.studies.identify.logs import JointLog, read_log
from nnrobust.studies.identify.signals import FilterChoice, _repeated_rows, prepare
from nnrobust.studies.identify.spool import Spool, blocks, column_ranges, first_not_finite

pa = pytest.importorskip("pyarrow")
from pyarrow import parquet  # noqa: E402

JOINTS = ("joint1", "joint2", "joint3")


def _spooled(values: np.ndarray, rows_per_append: int = 777) -> Spool:
    out = Spool(values.shape[1])
    for start in range(0, len(values), rows_per_append):
        out.append(values[start : start + rows_per_append])
    return out


def test_a_spool_reads_back_any_rows_it_was_given():
    values = np.random.default_rng(0).normal(size=(150_000, 3))
    spool = _spooled(values)
    assert spool.shape == values.shape and len(spool) == len(values)
    np.testing.assert_array_equal(np.asarray(spool), values)
    np.testing.assert_array_equal(spool[70_000:140_123], values[70_000:140_123])
    rows = np.sort(np.random.default_rng(1).choice(150_000, 500, replace=False))
    rows = rows[(rows > 60_000) & (rows < 90_000)]
    np.testing.assert_array_equal(spool[rows], values[rows])
    np.testing.assert_array_equal(spool[rows, 2], values[rows, 2])
    np.testing.assert_array_equal(spool[:10, 1], values[:10, 1])
    assert [s for s, _ in blocks(spool)] == list(range(0, 150_000, 1 << 16))
    low, high = column_ranges(spool)
    np.testing.assert_array_equal(low, values.min(axis=0))
    np.testing.assert_array_equal(high, values.max(axis=0))
    assert first_not_finite(spool) is None
    values[123_456, 1] = np.nan
    assert first_not_finite(_spooled(values)) == (123_456, 1)
    with pytest.raises(IndexError):
        spool[::2]


def test_stale_rows_across_blocks_are_the_whole_arrays():
    """A row repeating the previous one is found wherever it sits, a block's first row included."""
    rng = np.random.default_rng(2)
    q = rng.normal(size=(200_000, 2))
    for k in (1, 65_535, 65_536, 65_537, 131_072, 199_999, *rng.choice(np.arange(1, 200_000), 300)):
        q[k] = q[k - 1]
    whole = np.concatenate([[False], np.all(np.diff(q, axis=0) == 0, axis=1)])
    np.testing.assert_array_equal(_repeated_rows(_spooled(q)), whole)
    np.testing.assert_array_equal(_repeated_rows(q), whole)


def test_a_parquet_log_read_in_batches_is_the_log_read_whole(tmp_path, monkeypatch):
    """120 s at 1 kHz in row groups of 10 000, read 4096 rows at a time: the same times (from
    timestamps: one origin for every batch), the same signals and the same states."""
    rng = np.random.default_rng(4)
    n = 120_000
    t = np.arange(n) / 1000.0 + rng.normal(0, 1e-4, n)
    start = np.datetime64("2026-11-30T12:00:00", "ns").astype(np.int64)
    w = 2 * np.pi * np.array([0.2, 0.45, 0.9])
    q = 0.4 * np.sin(np.outer(t, w))
    q[rng.choice(np.arange(1, n), 2000)] = np.nan  # marked, then each made stale below
    for k in np.flatnonzero(np.isnan(q[:, 0])):
        q[k] = q[k - 1]
    tau = np.cos(np.outer(t, w)) + rng.normal(0, 0.05, (n, 3))
    table = {"time": pa.array(start + np.round(t * 1e9).astype(np.int64), pa.timestamp("ns"))}
    for i in range(3):
        table[f"q{i}"], table[f"tau{i}"] = q[:, i], tau[:, i]
    path = tmp_path / "log.parquet"
    parquet.write_table(pa.table(table), path, row_group_size=10_000)
    monkeypatch.setattr(logs, "BLOCK", 4096)
    log = read_log([path], JOINTS)
    assert isinstance(log.q, Spool)
    whole = JointLog("whole", (np.round(t * 1e9).astype(np.int64) - np.round(t[0] * 1e9)) / 1e9, q, None, tau)
    np.testing.assert_array_equal(log.t, whole.t)
    np.testing.assert_array_equal(np.asarray(log.q), q)
    np.testing.assert_array_equal(np.asarray(log.tau), tau)
    choice = FilterChoice(cutoff=8.0)
    ours, theirs = prepare(log, choice), prepare(whole, choice)
    assert ours.notes["stale_samples"] == theirs.notes["stale_samples"] > 1000
    np.testing.assert_array_equal(ours.t, theirs.t)
    a, b = ours.whole(), theirs.whole()
    for name in ("q", "dq", "ddq", "tau"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_a_csv_log_is_read_in_blocks_and_a_word_among_its_numbers_is_named(tmp_path, monkeypatch):
    """A CSV file parsed 64 KiB at a time reads as its numbers; a word deep in it (past the first
    block the types were read from) is refused naming its column."""
    from pyarrow import csv

    t = np.arange(20_000) / 1000.0
    columns = {"time": t}
    for i in range(3):
        columns[f"q{i}"], columns[f"tau{i}"] = np.sin(t + i), np.cos(t + i)
    path = tmp_path / "log.csv"
    csv.write_csv(pa.table(columns), path)
    monkeypatch.setattr(logs, "CSV_BLOCK_BYTES", 1 << 16)
    log = read_log([path], JOINTS)
    assert isinstance(log.q, Spool)
    np.testing.assert_array_equal(log.t, t)
    np.testing.assert_array_equal(np.asarray(log.tau)[:, 2], columns["tau2"])
    lines = path.read_text().splitlines()
    fields = lines[15_000].split(",")
    fields[3] = "oops"  # the file's fourth column: q1
    lines[15_000] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(logs.LogError, match=r"log.csv: column 'q1' is not numbers \(.*'oops'"):
        read_log([path], JOINTS)
