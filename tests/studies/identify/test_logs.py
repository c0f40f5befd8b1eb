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


def test_a_locked_joints_position_is_read_and_checked(tmp_path):
    """A table's position column named after a locked joint: moving, the log is refused (the model
    holds the joint still); held still away from its neutral value, a warning."""
    from nnrobust.core.exceptions import LogError
    from nnrobust.studies.identify.logs import check_locked

    columns = _columns(("time", "q.{j}", "dq.{j}", "tau.{j}"))
    t = columns["time"]
    for name, values, verdict in (
        ("moving", 0.02 * np.sin(t), "moves over"),
        ("open", np.full(t.size, 0.04), "held at 0.04"),
        ("closed", np.zeros(t.size), None),
    ):
        path = tmp_path / f"{name}.csv"
        csv.write_csv(pa.table({**columns, "Q.Gripper": values}), path)
        log = read_log([path], JOINTS, locked=["gripper"])
        assert log.notes["locked"]["gripper"] == [float(values.min()), float(values.max())]
        if verdict == "moves over":
            with pytest.raises(LogError, match="gripper is locked .* but moves over"):
                check_locked(log)
        else:
            warnings = check_locked(log)
            assert (verdict in warnings[0]) if verdict else warnings == []
    assert "locked" not in read_log([path], JOINTS).notes  # nothing locked: nothing read


def test_identify_refuses_a_log_in_which_a_locked_finger_moves(tmp_path, capsys):
    from nnrobust.cli import main
    from nnrobust.model.loading import load_robot

    model = load_robot("panda", task="position").model  # the fingers locked: the robot's rule
    joints = model.names[1:]
    t = np.arange(2000) / 1000.0
    columns = {"time": t}
    for i, joint in enumerate(joints):
        columns[f"q.{joint}"] = 0.2 * np.sin(t + i)
        columns[f"dq.{joint}"] = 0.2 * np.cos(t + i)
        columns[f"tau.{joint}"] = np.sin(t)
    columns["q.panda_finger_joint1"] = 0.02 + 0.01 * np.sin(3 * t)
    path = tmp_path / "panda.csv"
    csv.write_csv(pa.table(columns), path)
    code = main(["identify", str(path), "--robot", "panda", "--out", str(tmp_path / "out"), "--quiet"])
    assert code == 2 and "panda_finger_joint1 is locked" in capsys.readouterr().err
