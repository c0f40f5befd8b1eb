"""The virtual robot (nnrobust/outputs/serve/, csrc/serve/; docs/serve.md) with controllers in other
processes: the exported law's driver closes the loop and, in lockstep, the served run is the
simulated run exactly; a hostile client's datagrams are each refused with a logged reason, never
applied; silence trips the watchdog. Nothing here depends on the machine's timing: the wall-clock
runs assert only what holds however late the processes are scheduled.
"""

import json
import shutil
import socket
import struct
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from nnrobust.cli import main
from nnrobust.config.presets import load_preset
from nnrobust.outputs.export import export_law
from nnrobust.outputs.run_folder import load_run as load_result
from nnrobust.outputs.serve import serve
from nnrobust.run import compiled

pytestmark = [
    pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason()),
    pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler"),
]

ROOT = Path(__file__).resolve().parents[2]
HEADER = struct.Struct("<IHHQdII")  # csrc/serve/protocol.h
MAGIC, VERSION = 0x53524E4E, 1
HELLO, INFO, STATE, COMMAND, END = 1, 2, 3, 4, 5


def _config(duration=2.5):
    return load_preset("paper-ellipse-noisy").replace(simulation={"duration": duration})


def _serve_with(config, folder, client, **options):
    """serve() with ``client(port)`` started once the robot listens."""
    started = []

    def ready(port):
        started.append(client(port))

    record = serve(config, folder, plots=False, on_ready=ready, **options)
    for process in started:
        if isinstance(process, subprocess.Popen):
            process.wait(timeout=120)
        elif isinstance(process, threading.Thread):
            process.join(timeout=120)
    return record


def test_in_lockstep_the_served_run_is_the_simulated_run(tmp_path):
    """The exported law's driver in another process, the robot in lockstep: every command is
    applied, and the run's arrays are the compiled simulation's bit for bit."""
    config = _config()
    law = tmp_path / "law"
    export_law(config, law)
    record = _serve_with(
        config,
        tmp_path / "run",
        lambda port: subprocess.Popen([law / "bin" / "drive", str(port)]),
        lockstep=True,
        wait_seconds=60,
    )
    steps = 2500
    assert record["periods"] == record["commands_in_time"] == steps and record["deadline_misses"] == 0
    assert record["rejected"] == {} and record["stopped"] == ""
    served = load_result(tmp_path / "run")
    from nnrobust.run.experiment import run_experiment

    simulated = run_experiment(config.replace(simulation={"backend": "compiled"}))
    np.testing.assert_array_equal(served.tau, simulated.tau)
    np.testing.assert_array_equal(served.q, simulated.q)
    assert record["tracking_ratio"] == 1.0
    timing = json.loads((tmp_path / "run" / "timing.json").read_text())
    assert timing["round_trip_latency_us"]["count"] == steps


def test_at_wall_clock_every_period_is_accounted_for(tmp_path):
    """At 1 kHz on a busy machine some commands may be late: whatever happened, each period is
    a command in time or a miss, each accepted command has its latency, and the run completes."""
    config = _config(1.0)
    law = tmp_path / "law"
    export_law(config, law)
    record = _serve_with(
        config,
        tmp_path / "run",
        lambda port: subprocess.Popen([law / "bin" / "drive", str(port)]),
        watchdog=10**6,
    )
    assert record["periods"] == 1000 == record["commands_in_time"] + record["deadline_misses"]
    assert record["round_trip_latency_us"]["count"] == record["commands_in_time"]
    assert record["period_lateness_us"]["count"] == 1000
    assert record["served"]["status"] == "completed"
    late = sum(n for reason, n in record["rejected"].items() if "past period" in reason)
    assert late <= record["deadline_misses"]  # a late command is one of the missed periods'


def _packet(kind, seq, n, values=(), t=0.0, magic=MAGIC, version=VERSION):
    return HEADER.pack(magic, version, kind, seq, t, n, 0) + struct.pack(f"<{len(values)}d", *values)


def _hostile_client(port, n, log):
    """Says HELLO, then at each STATE sends one of every bad datagram and then the period's good
    command (a zero torque), in lockstep; a flood of junk at period 5."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    other = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.settimeout(30)
    robot = ("127.0.0.1", port)
    sock.sendto(_packet(HELLO, 0, n), robot)
    info = HEADER.unpack_from(sock.recv(65536))
    log.append(info)
    zero = [0.0] * n
    while True:
        data = sock.recv(65536)
        magic, _, kind, seq, t, count, _ = HEADER.unpack_from(data)
        if kind == END:
            return
        bad = [
            b"\x00" * 7,  # shorter than the header
            _packet(COMMAND, seq, n, zero, magic=0xDEADBEEF),  # wrong magic
            _packet(COMMAND, seq, n, zero[:-1]),  # wrong size
            _packet(COMMAND, seq, n, [float("nan")] + zero[1:]),  # not finite
            _packet(COMMAND, seq + 1, n, zero),  # a period not measured yet
            _packet(STATE, seq, n, zero + zero),  # not a command
        ]
        if seq > 0:
            bad.append(_packet(COMMAND, seq - 1, n, [50.0] * n))  # replayed: the last period's
        for datagram in bad:
            sock.sendto(datagram, robot)
        other.sendto(_packet(COMMAND, seq, n, [40.0] * n), robot)  # another sender
        if seq == 5:
            for _ in range(2000):  # a flood (what the socket's buffer cannot hold the kernel drops)
                sock.sendto(b"junk" * 100, robot)
            time.sleep(0.2)  # so that the period's good command is not one of the dropped
        sock.sendto(_packet(COMMAND, seq, n, zero), robot)
        sock.sendto(_packet(COMMAND, seq, n, [30.0] * n), robot)  # a second command: refused


def test_a_hostile_client_gets_logged_refusals_never_applied(tmp_path):
    config = _config(0.05)
    log = []

    def client(port):
        thread = threading.Thread(target=_hostile_client, args=(port, 3, log), daemon=True)
        thread.start()
        return thread

    record = _serve_with(config, tmp_path / "run", client, lockstep=True, wait_seconds=30, compare=False)
    assert log and log[0][2] == INFO and log[0][5] == 3  # INFO: n = 3
    assert record["periods"] == record["commands_in_time"] == 50
    rejected = record["rejected"]
    for reason in (
        "a datagram shorter than the header",
        "a wrong magic number or protocol version",
        "a COMMAND of the wrong size (needs 3 torques)",
        "a COMMAND with a torque that is not finite",
        "a COMMAND of a period not yet measured",
        "not a COMMAND",
        "another sender than the controller",
    ):
        assert rejected.get(reason, 0) >= 40, (reason, rejected)
    assert rejected.get("a COMMAND of a past period (late, replayed or out of order)", 0) >= 40
    assert len(record["first_rejections"]) == 100  # bounded, whatever the flood
    served = load_result(tmp_path / "run")
    # only the good zero commands were applied (the plant's torque: zero, then friction-free zero)
    assert np.all(served.tau_cmd == 0.0)


def test_silence_trips_the_watchdog(tmp_path):
    """A controller that says HELLO and then nothing: the robot holds zero torque for the
    watchdog's periods, then stops (its protective stop), and says so."""
    config = _config(1.0)

    def client(port):
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.sendto(_packet(HELLO, 0, 3), ("127.0.0.1", port))
        return sock

    record = _serve_with(config, tmp_path / "run", client, watchdog=5, compare=False)
    assert record["periods"] == 5 and record["deadline_misses"] == 5
    assert "protective stop" in record["stopped"]
    assert record["served"]["status"] == "interrupted"


def test_no_controller_and_a_taken_port_are_refused(tmp_path, capsys):
    with pytest.raises(Exception, match="no controller said HELLO"):
        serve(_config(0.1), tmp_path / "run", wait_seconds=0.2, compare=False, plots=False)
    busy = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    busy.bind(("127.0.0.1", 0))
    port = busy.getsockname()[1]
    code = main(
        ["serve", "paper-ellipse", "--out", str(tmp_path / "r2"), "--port", str(port), "--wait", "0.2"]
    )
    assert code == 2 and f"cannot listen on 127.0.0.1:{port}" in capsys.readouterr().err
    busy.close()


@pytest.mark.parametrize("action", ["torque", "residual", "nn"])
def test_a_law_in_python_drives_a_served_robot_as_the_hybrid_loop_runs_it(action, tmp_path):
    """``nnrobust drive`` in another process: the ONNX policy (no C++ twin) computes each command
    in Python from the STATE datagram; in lockstep every command is applied, and the served run
    is the hybrid loop's simulation (the compiled plant calling the same Python law once a period):
    bit for bit for a torque policy and for the eq. (9) law's Python twin (its NN weights the
    state drive carries from period to period); to rounding for a residual on no-u0, whose base
    law the hybrid loop steps in C++ and drive in Python (the twins agree to 1e-12)."""
    pytest.importorskip("onnxruntime")
    import sys

    from nnrobust.run.experiment import run_experiment

    config = _config()
    if action != "nn":
        policy = {"file": str(ROOT / "examples" / "policies" / f"{action}.onnx"), "action": action}
        if action == "residual":
            policy["base"] = "no-u0"
        config = config.replace(controller={"kind": "policy", "params": policy})
    experiment = tmp_path / "policy.toml"
    experiment.write_text(config.to_toml())
    argv = [sys.executable, "-m", "nnrobust", "drive", str(experiment), "--quiet", "--port"]
    record = _serve_with(
        config,
        tmp_path / "run",
        lambda port: subprocess.Popen([*argv, str(port)]),
        lockstep=True,
        wait_seconds=60,
    )
    assert record["periods"] == record["commands_in_time"] == 2500 and record["rejected"] == {}
    assert record["simulated_backend"] == ("compiled" if action == "nn" else "hybrid")
    served = load_result(tmp_path / "run")
    simulated = run_experiment(config.replace(simulation={"backend": "hybrid"}))
    if action != "residual":
        np.testing.assert_array_equal(served.tau, simulated.tau)
        np.testing.assert_array_equal(served.q, simulated.q)
    else:
        np.testing.assert_allclose(served.tau, simulated.tau, rtol=0, atol=1e-9)
        np.testing.assert_allclose(served.q, simulated.q, rtol=0, atol=1e-9)


def test_drive_without_a_robot_is_one_error_within_its_wait(capsys):
    """No robot on the port: drive says so once its --wait has passed (never a hang)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]  # bound by no robot: HELLO goes unanswered
        started = time.monotonic()
        code = main(["drive", "paper-ellipse", "--port", str(port), "--wait", "0.5"])
    assert code != 0 and time.monotonic() - started < 30
    said = capsys.readouterr().err
    assert f"no datagram from the robot at 127.0.0.1:{port} for 0.5 s" in said, said


def test_in_lockstep_a_controller_gone_stops_the_robot_after_one_wait(tmp_path):
    """Lockstep: a controller that answers five periods and goes: the sixth period waits --wait
    seconds, then the robot stops (a protective stop, the run marked interrupted), where it held
    the last command for 20 waits of the watchdog."""

    def client(port):
        def answer():
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            sock.settimeout(30)
            sock.sendto(_packet(HELLO, 0, 3), ("127.0.0.1", port))
            sock.recv(65536)  # INFO
            for _ in range(5):
                _, _, kind, seq, _, _, _ = HEADER.unpack_from(sock.recv(65536))
                sock.sendto(_packet(COMMAND, seq, 3, [0.0] * 3), ("127.0.0.1", port))
            sock.close()

        thread = threading.Thread(target=answer)
        thread.start()
        return thread

    started = time.monotonic()
    record = _serve_with(
        _config(1.0), tmp_path / "run", client, lockstep=True, wait_seconds=1.0, compare=False
    )
    assert record["commands_in_time"] == 5 and record["periods"] == 6 and record["deadline_misses"] == 1
    assert record["stopped"].startswith("protective stop: no command within 1.0")
    assert record["served"]["status"] == "interrupted"
    assert time.monotonic() - started < 60
