"""Logs as robots record them: ``sensor_msgs/msg/JointState`` messages in a ROS 2 bag (a folder
with ``metadata.yaml``, SQLite 3 or MCAP storage) or in an MCAP file (ROS 2 CDR or JSON
encoding), read with the ``rosbags`` and ``mcap`` packages: no ROS installation.

Each message gives a sample: its header's stamp (the message's log time where the stamp is zero),
and the position, velocity and effort of every joint it names, matched to the robot's joints by
name (joints of the message that the robot does not have, a gripper's, are left out and
reported). The topic is the only one of that type, or ``topic``.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ...core.exceptions import LogError

JOINT_STATE = "sensor_msgs/msg/JointState"
"""The message type a joint log is read from."""


def is_bag(path: Path) -> bool:
    """Whether ``path`` is a ROS 2 bag folder or an MCAP file."""
    return (path.is_dir() and (path / "metadata.yaml").is_file()) or path.suffix.lower() == ".mcap"


def read_bag(path: Path, joints: Sequence[str], topic: str | None = None, locked: Sequence[str] = ()):
    """(t, q, dq or None, tau, notes) of the JointState messages of ``path``; ``notes["locked"]``:
    each of the ``locked`` joints the messages name, with its least and largest position (for
    :func:`.logs.check_locked`).
    """
    messages = _bag_messages(path, topic) if path.is_dir() else _mcap_messages(path, topic)
    return _samples(path, messages, joints, locked)


def _bag_messages(path: Path, topic: str | None):
    try:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore
    except ImportError as err:
        raise LogError(
            f"{path}: reading a ROS 2 bag needs rosbags: pip install 'nnrobust[identify]'"
        ) from err
    try:
        with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
            connections = _chosen(path, [(c.topic, c.msgtype) for c in reader.connections], topic)
            chosen = [c for c in reader.connections if c.topic == connections]
            for connection, stamp, raw in reader.messages(connections=chosen):
                message = reader.deserialize(raw, connection.msgtype)
                yield _fields(message, stamp)
    except LogError:
        raise
    except Exception as err:  # rosbags' own errors: a damaged or foreign bag
        raise LogError(f"{path}: not a readable ROS 2 bag ({type(err).__name__}: {str(err)[:200]})") from err


def _mcap_messages(path: Path, topic: str | None):
    try:
        from mcap.reader import make_reader
    except ImportError as err:
        raise LogError(f"{path}: reading MCAP needs mcap: pip install 'nnrobust[identify]'") from err
    typestore = None
    try:
        with open(path, "rb") as stream:
            reader = make_reader(stream)
            summary = reader.get_summary()
            channels = summary.channels if summary is not None else {}
            schemas = summary.schemas if summary is not None else {}
            kinds = [(c.topic, _schema_name(schemas.get(c.schema_id))) for c in channels.values()]
            name = _chosen(path, kinds, topic)
            for schema, channel, message in reader.iter_messages(topics=[name]):
                if channel.message_encoding == "cdr":
                    if typestore is None:
                        from rosbags.typesys import Stores, get_typestore

                        typestore = get_typestore(Stores.ROS2_HUMBLE)
                    yield _fields(typestore.deserialize_cdr(message.data, JOINT_STATE), message.log_time)
                elif channel.message_encoding == "json":
                    yield _json_fields(json.loads(message.data), message.log_time)
                else:
                    raise LogError(
                        f"{path}: topic {name} is encoded {channel.message_encoding!r}; nnrobust reads cdr "
                        "(ROS 2) and json"
                    )
    except LogError:
        raise
    except Exception as err:  # mcap's own errors: a truncated or foreign file
        raise LogError(f"{path}: not a readable MCAP file ({type(err).__name__}: {str(err)[:200]})") from err


def _schema_name(schema) -> str:
    """A channel's message type as ROS 2 writes it (``sensor_msgs/msg/JointState``)."""
    name = "" if schema is None else schema.name
    package, _, kind = name.partition("/")
    return name if "/msg/" in name or not kind else f"{package}/msg/{kind}"


def _chosen(path: Path, topics: list[tuple[str, str]], topic: str | None) -> str:
    """The topic to read: ``topic``, or the one JointState topic of the log."""
    if topic is not None:
        if topic not in [t for t, _ in topics]:
            raise LogError(
                f"{path}: no topic {topic!r}; its topics: {', '.join(sorted({t for t, _ in topics}))}"
            )
        return topic
    states = sorted({t for t, kind in topics if kind == JOINT_STATE})
    if len(states) != 1:
        what = "no" if not states else f"{len(states)}"
        listed = ", ".join(states) or "its topics: " + ", ".join(sorted({t for t, _ in topics}))
        raise LogError(f"{path}: {what} {JOINT_STATE} topics ({listed}); name one with --topic")
    return states[0]


def _fields(message, log_time: int) -> tuple:
    stamp = message.header.stamp
    t = stamp.sec + stamp.nanosec * 1e-9 if (stamp.sec or stamp.nanosec) else log_time * 1e-9
    return (
        t,
        list(message.name),
        np.asarray(message.position),
        np.asarray(message.velocity),
        np.asarray(message.effort),
    )


def _json_fields(message: dict, log_time: int) -> tuple:
    stamp = message.get("header", {}).get("stamp", {})
    sec, nanosec = stamp.get("sec", 0), stamp.get("nanosec", stamp.get("nsec", 0))
    t = sec + nanosec * 1e-9 if (sec or nanosec) else log_time * 1e-9
    return (
        t,
        list(message.get("name", [])),
        np.asarray(message.get("position", []), dtype=float),
        np.asarray(message.get("velocity", []), dtype=float),
        np.asarray(message.get("effort", []), dtype=float),
    )


def _samples(path: Path, messages, joints: Sequence[str], locked: Sequence[str] = ()):
    times, q, dq, tau, held = [], [], [], [], []
    index = None
    names: list[str] = []
    velocities = True
    for k, (t, names_k, position, velocity, effort) in enumerate(messages):
        if index is None:
            names = names_k
            missing = [j for j in joints if j not in names]
            if missing:
                raise LogError(
                    f"{path}: its JointState names {names}, not the robot's joints {', '.join(missing)}"
                )
            index = [names.index(j) for j in joints]
            kept = [j for j in locked if j in names]
            still = [names.index(j) for j in kept]
        elif names_k != names:
            raise LogError(f"{path}: message {k} names the joints {names_k}, the first {names}")
        if len(position) != len(names) or len(effort) != len(names):
            raise LogError(
                f"{path}: message {k} has {len(position)} positions and {len(effort)} efforts for "
                f"{len(names)} joints; a log needs both for every joint"
            )
        velocities = velocities and len(velocity) == len(names)
        times.append(t)
        q.append(position[index])
        dq.append(velocity[index] if len(velocity) == len(names) else np.zeros(len(joints)))
        tau.append(effort[index])
        held.append(position[still])
    if index is None:
        raise LogError(f"{path}: its JointState topic has no message")
    extra = [n for n in names if n not in joints]
    notes: dict = {"topic_joints_left_out": [n for n in extra if n not in kept]}
    if kept:
        positions = np.array(held)
        notes["locked"] = {
            j: [float(positions[:, i].min()), float(positions[:, i].max())] for i, j in enumerate(kept)
        }
    return np.array(times), np.array(q), (np.array(dq) if velocities else None), np.array(tau), notes
