"""Logs as robots record them: the same synthetic log written as a ROS 2 bag (SQLite 3), an MCAP
file of ROS 2 CDR messages and one of JSON messages, each read back to the samples written (the
joints in the robot's order, a gripper's left out)."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from rosbags.rosbag2 import Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

from nnrobust.core.exceptions import LogError  # noqa: E402
from nnrobust.studies.identify.logs import read_log  # noqa: E402

JOINTS = ("joint1", "joint2", "joint3")
NAMES = ["finger", "joint3", "joint1", "joint2"]  # another order, and a joint the robot lacks
TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)


def _samples(n=400):
    t = 10.0 + np.arange(n) * 1e-3
    q = np.column_stack([np.sin(t + i) for i in range(3)])
    return t, q, np.cos(q), 2 * q


def _message(t, q, dq, tau):
    JointState = TYPESTORE.types["sensor_msgs/msg/JointState"]
    Header = TYPESTORE.types["std_msgs/msg/Header"]
    Time = TYPESTORE.types["builtin_interfaces/msg/Time"]
    order = [JOINTS.index(n) if n in JOINTS else None for n in NAMES]

    def arranged(values):
        return np.array([0.5 if i is None else values[i] for i in order], dtype=np.float64)

    sec = int(t)
    return JointState(
        Header(Time(sec, int(round((t - sec) * 1e9))), ""), NAMES, arranged(q), arranged(dq), arranged(tau)
    )


def _bag(folder):
    path = folder / "bag"
    with Writer(path, version=9) as writer:
        connection = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=TYPESTORE)
        for k, row in enumerate(zip(*_samples())):
            writer.write(connection, k, TYPESTORE.serialize_cdr(_message(*row), "sensor_msgs/msg/JointState"))
    return path


def _mcap(folder, encoding):
    from mcap.writer import Writer as McapWriter

    path = folder / f"log-{encoding}.mcap"
    with open(path, "wb") as stream:
        writer = McapWriter(stream)
        writer.start()
        if encoding == "cdr":
            schema = writer.register_schema(
                "sensor_msgs/msg/JointState",
                "ros2msg",
                TYPESTORE.generate_msgdef("sensor_msgs/msg/JointState")[0].encode(),
            )
        else:
            schema = writer.register_schema("sensor_msgs/JointState", "jsonschema", b"{}")
        channel = writer.register_channel("/joint_states", encoding, schema)
        for k, (t, q, dq, tau) in enumerate(zip(*_samples())):
            if encoding == "cdr":
                data = bytes(TYPESTORE.serialize_cdr(_message(t, q, dq, tau), "sensor_msgs/msg/JointState"))
            else:
                message = _message(t, q, dq, tau)
                data = json.dumps(
                    {
                        "header": {
                            "stamp": {
                                "sec": message.header.stamp.sec,
                                "nanosec": message.header.stamp.nanosec,
                            }
                        },
                        "name": NAMES,
                        "position": message.position.tolist(),
                        "velocity": message.velocity.tolist(),
                        "effort": message.effort.tolist(),
                    }
                ).encode()
            writer.add_message(channel, log_time=k, data=data, publish_time=k)
        writer.finish()
    return path


@pytest.mark.parametrize(
    "make",
    [_bag, lambda f: _mcap(f, "cdr"), lambda f: _mcap(f, "json")],
    ids=["bag", "mcap-cdr", "mcap-json"],
)
def test_a_recorded_log_reads_back_to_the_samples_written(make, tmp_path):
    log = read_log([make(tmp_path)], JOINTS)
    t, q, dq, tau = _samples()
    assert np.allclose(log.t, t, atol=1e-9) and np.array_equal(log.q, q)
    assert np.array_equal(log.dq, dq) and np.array_equal(log.tau, tau)
    assert log.notes["topic_joints_left_out"] == ["finger"]


def test_a_bag_without_the_robots_joints_is_one_line(tmp_path):
    bag = _bag(tmp_path)
    with pytest.raises(LogError, match="its JointState names .* not the robot's joints wrist"):
        read_log([bag], ("joint1", "wrist"))
    with pytest.raises(LogError, match="no topic '/other'; its topics: /joint_states"):
        read_log([bag], JOINTS, topic="/other")


@pytest.mark.parametrize("make", [_bag, lambda f: _mcap(f, "cdr")], ids=["bag", "mcap-cdr"])
def test_a_locked_joint_a_bag_names_is_checked_as_a_tables_is(make, tmp_path):
    """The JointState's entry of a joint the model locks: held still away from 0, a warning; moving,
    a refusal naming it (its motion changes the torques the model predicts)."""
    from nnrobust.studies.identify.logs import check_locked

    path = make(tmp_path)
    still = read_log([path], JOINTS, locked=["finger"])
    assert still.notes["locked"] == {"finger": [0.5, 0.5]} and still.notes["topic_joints_left_out"] == []
    (warning,) = check_locked(still)
    assert "finger is locked at 0 in the model but held at 0.5" in warning
    moving = read_log([path], ("joint1", "joint2"), locked=["joint3"])
    with pytest.raises(LogError, match="joint3 is locked .* but moves over"):
        check_locked(moving)
