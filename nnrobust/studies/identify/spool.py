"""A log's N x n signals kept on disk and read by rows, so that reading, checking and preparing a
long log holds a block of it at a time, not the whole (docs/identification.md, "Long logs").

:class:`Spool` is the file-backed array a streaming reader writes (CSV and Parquet are read a batch
of rows at a time); every other reader's signals are ordinary arrays. :func:`blocks`
and indexing by sorted rows read either kind, so the checks and the states have one path for both.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator

import numpy as np

BLOCK = 1 << 16
"""Rows read at a time by :func:`blocks`."""


class Spool:
    """An N x n float64 array in an unnamed temporary file (gone when the object is), appended
    to a block of rows at a time and read back by row ranges (``pread``: no mapping, so what is
    resident is what is read).
    """

    ndim = 2

    def __init__(self, columns: int):
        self._file = tempfile.TemporaryFile(prefix="nnrobust-log-")
        self.columns, self.rows = columns, 0

    @property
    def shape(self) -> tuple[int, int]:
        """(N, n)."""
        return self.rows, self.columns

    def __len__(self) -> int:
        return self.rows

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        """The whole array (for tests and short logs: memory grows with it)."""
        return self.read(0, self.rows) if dtype is None else self.read(0, self.rows).astype(dtype)

    def append(self, block: np.ndarray) -> None:
        """Rows at the end (``block``: k x n)."""
        block = np.ascontiguousarray(block, dtype=np.float64)
        self._file.write(block.tobytes())
        self.rows += len(block)

    def read(self, start: int, stop: int) -> np.ndarray:
        """Rows ``start:stop`` (clipped to the array), a fresh array."""
        start, stop = max(0, start), min(self.rows, stop)
        if stop <= start:
            return np.zeros((0, self.columns))
        self._file.flush()
        width = 8 * self.columns
        data = os.pread(self._file.fileno(), (stop - start) * width, start * width)
        return np.frombuffer(data, dtype=np.float64).reshape(stop - start, self.columns).copy()

    def __getitem__(self, key):
        """Rows by a slice (step 1) or a sorted index array, optionally with a column: what the
        log's readers of rows ask (``values[rows]``, ``values[rows, j]``, ``values[:, j]``).
        """
        rows, column = key if isinstance(key, tuple) else (key, slice(None))
        if isinstance(rows, slice):
            start, stop, step = rows.indices(self.rows)
            if step != 1:
                raise IndexError("a spooled log's rows are read in order, step 1")
            return self.read(start, stop)[:, column]
        rows = np.asarray(rows)
        if rows.size == 0:
            return np.zeros((0, self.columns))[:, column]
        first = int(rows.min())
        return self.read(first, int(rows.max()) + 1)[rows - first][:, column]


def blocks(values, size: int = BLOCK) -> Iterator[tuple[int, np.ndarray]]:
    """(start, rows start:start + size) of an array or a :class:`Spool`, in order."""
    for start in range(0, len(values), size):
        yield start, values[start : start + size]


def column_ranges(values) -> tuple[np.ndarray, np.ndarray]:
    """Each column's least and largest value."""
    low = np.full(values.shape[1], np.inf)
    high = np.full(values.shape[1], -np.inf)
    for _, block in blocks(values):
        if len(block):
            low, high = np.minimum(low, block.min(axis=0)), np.maximum(high, block.max(axis=0))
    return low, high


def first_not_finite(values) -> tuple[int, ...] | None:
    """The index (row, or row and column) of the first value that is not a finite number, or None."""
    for start, block in blocks(values):
        bad = np.argwhere(~np.isfinite(block))
        if bad.size:
            return (start + int(bad[0][0]), *(int(i) for i in bad[0][1:]))
    return None


def block_value(values, index: tuple[int, ...]) -> float:
    """The value at ``index`` (row, or row and column)."""
    return float(np.asarray(values[index[0] : index[0] + 1])[(0, *index[1:])])
