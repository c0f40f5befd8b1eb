"""The virtual robot (``nnrobust serve``, docs/serve.md): an experiment's plant in real time.

The compiled plant (friction, disturbance, limits, sensor, delay: everything the experiment's
``[plant]`` and ``[sensing]`` say) is paced by the wall clock at the control period and speaks
the UDP protocol of csrc/serve/protocol.h on 127.0.0.1: at each control instant it sends the
measured state and expects a torque command before the next one. A command that is late,
missing, malformed, not finite, replayed, out of order or from another sender is not applied:
the robot holds its last command and logs the reason; after ``watchdog`` periods without a
command it stops, as a real arm's protective stop does. The controller runs in another process:
an exported law (nnrobust.outputs.export) through the driver that ships with it, or anything that
speaks the protocol.

The run folder is the simulated run's (config.toml, result.npz, metrics.json, figures) plus
timing.json: deadline misses, round-trip latency and period lateness (p50, p99, max), every
rejected datagram by reason, and the same experiment simulated (its own controller, compiled)
beside the served run's tracking and verdicts.
"""

from __future__ import annotations

import time
from pathlib import Path

from ...core.exceptions import NNRobustError

COMPARED = ("rms_error_after_2s", "max_error", "rms_torque", "saturated_fraction", "max_speed_ratio")
"""The metrics timing.json puts side by side, served and simulated."""


def _quantiles(values, scale: float = 1e6) -> dict:
    """p50, p99 and max of ``values`` in µs (None each when there are none)."""
    import numpy as np

    x = np.asarray(values, dtype=float) * scale
    if x.size == 0:
        return {"p50": None, "p99": None, "max": None, "count": 0}
    return {
        "p50": float(np.percentile(x, 50)),
        "p99": float(np.percentile(x, 99)),
        "max": float(x.max()),
        "count": int(x.size),
    }


def timing_record(report, period: float, lockstep: bool = False) -> dict:
    """timing.json's timing part from the virtual robot's ServeReport."""
    return {
        "period_s": period,
        "periods": int(report.periods),
        "commands_in_time": int(report.accepted),
        "deadline_misses": int(report.misses),
        "round_trip_latency_us": _quantiles(report.latency),
        "period_lateness_us": _quantiles(report.lateness),
        "rejected": {reason: int(count) for reason, count in sorted(report.rejected.items())},
        "first_rejections": [{"t": float(t), "reason": reason} for t, reason in report.events],
        "stopped": report.stopped,
        "scheduling": report.scheduling,
        "lockstep": lockstep,
    }


MAX_WAIT = 86_400.0
"""The longest a robot waits for its controller [s] (a day)."""


def serve(
    config,
    out: str | Path,
    *,
    host: str = "127.0.0.1",
    port: int = 0,
    watchdog: int = 20,
    wait_seconds: float = 30.0,
    realtime: bool = False,
    lockstep: bool = False,
    overwrite: bool = False,
    compare: bool = True,
    plots: bool = True,
    on_ready=None,
) -> dict:
    """Serve ``config``'s plant in real time until its run ends; write the run folder ``out``
    (with timing.json) and return timing.json's contents. ``on_ready(port)`` is called once the
    socket listens, before the robot waits for its controller; ``realtime`` runs the robot's
    thread under SCHED_FIFO where the machine allows it (timing.json's ``scheduling`` says);
    ``lockstep`` drops the wall clock: each period waits for its command (up to ``wait_seconds``),
    so that a controller's logic is checked apart from its timing.
    """
    from ...run import compiled
    from ...run.experiment import build, result_of, run_experiment
    from ...run.results import write_json_atomic
    from ..run_folder import check_out_folder, locked, write_run

    if not 0 <= port <= 65535:
        raise NNRobustError(f"serve: --port {port} is not a port (0 to 65535; 0: a free one)")
    if watchdog < 1:
        raise NNRobustError(f"serve: --watchdog {watchdog}: needs at least 1 period")
    if (
        isinstance(wait_seconds, bool)
        or not isinstance(wait_seconds, (int, float))
        or not (0 < wait_seconds <= MAX_WAIT)
    ):
        raise NNRobustError(
            f"serve: --wait {wait_seconds}: the seconds to wait for the controller are a number in "
            f"(0, {MAX_WAIT:g}]"
        )
    folder = check_out_folder(out, overwrite)
    setup = build(config)
    refusal = compiled.hybrid_refusal(setup)
    if refusal:
        raise NNRobustError(f"serve needs the compiled plant: {refusal}")
    duration, period = config.simulation.duration, config.simulation.control_period
    spec = compiled.loop_spec(setup, duration, external=True)
    plant = compiled.load_model(setup.plant.model.pinocchio_model, setup.robot.task_frame)
    try:
        robot = compiled._module().VirtualRobot(
            plant, spec, host, port, wait_seconds, watchdog, realtime, lockstep
        )
    except (RuntimeError, ValueError) as err:
        raise NNRobustError(str(err)) from err
    with locked(folder):
        if on_ready is not None:
            on_ready(robot.port)
        start = time.perf_counter()
        report = robot.run()
        wall = time.perf_counter() - start
        if not report.connected:
            raise NNRobustError(f"serve: {report.stopped}; nothing was run")
        trace = compiled._trace(setup, spec, robot.finish())
        if report.stopped:
            trace.message = f"{report.stopped} at t = {trace.t[-1] if trace.t.size else 0.0:.3f} s"
        served = result_of(setup, trace, wall, "served")
        record = timing_record(report, period, lockstep)
        mine = served.metrics()
        record["served"] = {k: mine.get(k) for k in COMPARED} | {"status": served.status}
        record["served_verdicts"] = list(mine.get("warnings", []))
        if compare:
            # the compiled loop; a law with no compiled twin (a policy, a Python class) in the hybrid
            # loop, the compiled plant calling it once a period, as a Python controller drives the robot
            simulated = run_experiment(config.replace(simulation={"backend": "auto"}))
            theirs = simulated.metrics()
            record["simulated_backend"] = simulated.backend
            record["simulated"] = {k: theirs.get(k) for k in COMPARED} | {"status": theirs.get("status")}
            record["simulated_verdicts"] = list(theirs.get("warnings", []))
            a, b = mine.get("rms_error_after_2s"), theirs.get("rms_error_after_2s")
            record["tracking_ratio"] = a / b if a is not None and b else None
        written = write_run(folder, served, overwrite=overwrite, plots=plots, animation=plots)
        write_json_atomic(Path(written) / "timing.json", record)
    record["folder"] = str(written)
    return record
