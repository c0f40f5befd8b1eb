"""Reading a log's table (nnrobust/studies/identify/logs.py): column names in any case, and a
time column of timestamps (Parquet's, or a CSV's ISO times) as seconds from the first sample."""

import numpy as np
import pytest

from nnrobust.core.exceptions import NNRobustError
from nnrobust.studies.identify.logs import read_log

pa = pytest.importorskip("pyarrow")
from pyarrow import csv, parquet  # noqa: E402

JOINTS = ("joint1", "joint2", "joint3")


def _columns(names=("time", "q{i}", "dq{i}", "tau{i}")) -> dict:
    t = np.arange(500) / 1000.0
    out = {names[0]: t}
    for i in range(3):
        out[names[1].format(i=i, j=JOINTS[i])] = 0.3 * np.sin(2 * np.pi * 0.5 * t + i)
        out[names[2].format(i=i, j=JOINTS[i])] = 0.3 * np.pi * np.cos(2 * np.pi * 0.5 * t + i)
        out[names[3].format(i=i, j=JOINTS[i])] = np.sin(t + i)
    return out


def _same(a, b):
    for name in ("t", "q", "dq", "tau"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_column_names_are_read_in_any_case(tmp_path):
    plain, shouting = tmp_path / "plain.csv", tmp_path / "upper.csv"
    csv.write_csv(pa.table(_columns()), plain)
    csv.write_csv(pa.table(_columns(("Time", "Q{i}", "DQ{i}", "TAU{i}"))), shouting)
    _same(read_log([shouting], JOINTS), read_log([plain], JOINTS))
    named = tmp_path / "named.csv"  # joint names in another case too
    csv.write_csv(pa.table(_columns(("TIME", "q.{j}", "Velocity.{j}", "Effort.{j}"))), named)
    csv.write_csv(pa.table(_columns(("time", "q.{j}", "velocity.{j}", "effort.{j}"))), plain)
    _same(read_log([named], [j.upper() for j in JOINTS]), read_log([plain], JOINTS))


def test_two_columns_that_differ_only_in_case_are_refused(tmp_path):
    columns = _columns()
    columns["Q1"] = columns["q1"] + 1.0
    path = tmp_path / "log.csv"
    csv.write_csv(pa.table(columns), path)
    with pytest.raises(NNRobustError, match="the columns Q1, q1 differ only in upper and lower case"):
        read_log([path], JOINTS)


@pytest.mark.parametrize("unit", ["s", "ms", "us", "ns"])
def test_a_timestamp_time_column_is_seconds_from_the_first_sample(unit, tmp_path):
    columns = _columns()
    plain = tmp_path / "plain.parquet"
    parquet.write_table(pa.table(columns), plain)
    start = np.datetime64("2026-11-30T12:00:00", "ns").astype(np.int64)  # an epoch far from 0
    ticks = start + np.round(columns["time"] * 1e9).astype(np.int64)
    per = {"s": 10**9, "ms": 10**6, "us": 10**3, "ns": 1}[unit]
    stamped = dict(columns, time=pa.array(ticks // per, pa.timestamp(unit)))
    if unit == "s":  # whole seconds cannot hold a 1 kHz log: stamps every 1 s
        stamped["time"] = pa.array(start // per + np.arange(500), pa.timestamp(unit))
    path = tmp_path / "stamped.parquet"
    parquet.write_table(pa.table(stamped), path)
    log = read_log([path], JOINTS)
    expected = np.arange(500.0) if unit == "s" else columns["time"]
    np.testing.assert_allclose(log.t, expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(log.q, read_log([plain], JOINTS).q)
