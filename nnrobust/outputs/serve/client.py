"""A controller of a served robot in Python (docs/serve.md, "A controller in Python"):
``nnrobust drive`` answers the virtual robot's STATE datagrams with COMMANDs computed by the
experiment's own law in this process, so that a law without a C++ twin (an ONNX policy, a
custom Python class) drives a served robot as an exported law's ``bin/drive`` does.

The law sees what ``bin/drive`` passes an exported law: the period's time and the measured q and
v of the STATE datagram; nothing of the plant. The protocol is ``csrc/serve/protocol.h``'s: a
32-byte header (magic, version, type, seq, t, n, reserved), then the doubles.
"""

from __future__ import annotations

import socket
import struct
import time

import numpy as np

from ...core.exceptions import NNRobustError

HEADER = struct.Struct("<IHHQdII")
"""The header of every datagram (csrc/serve/protocol.h)."""

MAGIC, VERSION = 0x53524E4E, 1
HELLO, INFO, STATE, COMMAND, END = 1, 2, 3, 4, 5


def _packet(kind: int, seq: int, n: int, t: float = 0.0, values: np.ndarray | None = None) -> bytes:
    head = HEADER.pack(MAGIC, VERSION, kind, seq, t, n, 0)
    return head if values is None else head + np.asarray(values, dtype="<f8").tobytes()


def drive(setup, port: int, host: str = "127.0.0.1", wait: float = 60.0) -> dict:
    """Drive the robot served on ``host``:``port`` with ``setup``'s controller (a built
    experiment, :func:`nnrobust.run.experiment.build`) until its END; returns what happened:
    ``periods`` answered, the robot's ``n`` and ``period``, the ``ignored`` datagrams (another
    sender's, or not the protocol's) and the law's ``step_us`` (median time of one step [µs]).
    """
    controller = setup.controller
    n = setup.plant.nq
    period = setup.config.simulation.control_period
    robot = (host, port)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.settimeout(wait)
    try:
        sock.sendto(_packet(HELLO, 0, n), robot)
        info = _receive(sock, robot)
        if info[2] != INFO:
            raise NNRobustError(f"the robot at {host}:{port} answered HELLO with type {info[2]}, not INFO")
        if info[5] != n or not np.isclose(info[4], period, rtol=0, atol=1e-12):
            raise NNRobustError(
                f"the robot at {host}:{port} has {info[5]} joints and a period of {info[4]:g} s; this "
                f"controller's experiment has {n} joints and {period:g} s: drive it with the experiment "
                "it serves"
            )
        z = controller.initial_state()
        answered, ignored, steps = 0, 0, []
        while True:
            data, sender = sock.recvfrom(65536)
            if sender != _address(robot) or len(data) < HEADER.size:
                ignored += 1
                continue
            magic, version, kind, seq, t, count, _ = HEADER.unpack_from(data)
            if (magic, version) != (MAGIC, VERSION):
                ignored += 1
                continue
            if kind == END:
                break
            if kind != STATE or count != n or len(data) != HEADER.size + 16 * n:
                ignored += 1
                continue
            state = np.frombuffer(data, dtype="<f8", offset=HEADER.size)
            started = time.perf_counter()
            out = controller.compute(t, state[:n].copy(), state[n:].copy(), z, period)
            steps.append(time.perf_counter() - started)
            tau = np.asarray(out.tau, dtype=float)
            if tau.shape != (n,):
                raise NNRobustError(f"the law returned {tau.shape} torques at t = {t:g} s; the robot has {n}")
            sock.sendto(_packet(COMMAND, seq, n, t, tau), robot)
            if out.state is not None:
                z = out.state
            answered += 1
    except TimeoutError as err:
        raise NNRobustError(
            f"no datagram from the robot at {host}:{port} for {wait:g} s (is nnrobust serve running there, "
            "and did its run end?)"
        ) from err
    finally:
        sock.close()
    return {
        "periods": answered,
        "n": n,
        "period": period,
        "ignored": ignored,
        "step_us": float(np.median(steps) * 1e6) if steps else None,
    }


def _address(robot: tuple[str, int]) -> tuple[str, int]:
    """The robot's address as recvfrom gives it (a name resolved)."""
    return socket.gethostbyname(robot[0]), robot[1]


def _receive(sock: socket.socket, robot: tuple[str, int]) -> tuple:
    """The next header from the robot (another sender's datagrams skipped)."""
    while True:
        data, sender = sock.recvfrom(65536)
        if sender == _address(robot) and len(data) >= HEADER.size:
            head = HEADER.unpack_from(data)
            if head[:2] == (MAGIC, VERSION):
                return head
