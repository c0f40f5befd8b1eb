"""Results of a run: arrays, metrics, and the run folder written atomically."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.exceptions import NNRobustError
from ..core.small_linalg import det
from ..model.tasks import display_coordinates
from ..plant.limits import available_torque
from ..plant.scaling import limits_or_inf
from . import verdicts
from .run_info import RunInfo
from .simulation import period_substeps

SETTLED_AFTER = 2.0
"""Seconds after which a run is scored: ``rms_error_after_2s`` is the RMS task error over t >= 2 s."""

METRIC_UNITS = {
    "rms_error": "m",
    "rms_error_after_2s": "m",
    "max_error": "m",
    "final_error": "m",
    "rms_orientation_error": "rad",
    "rms_orientation_error_after_2s": "rad",
    "max_orientation_error": "rad",
    "rms_torque": "N m (the norm of the torque vector; N for a prismatic joint's entry)",
    "max_torque": "N m (N for a prismatic joint)",
    "max_torque_cmd": "N m (N for a prismatic joint)",
    "saturated_fraction": "-",
    "max_torque_ratio": "-",
    "max_applied_torque_ratio": "-",
    "rms_torque_ratio": "-",
    "speed_limit_fraction": "-",
    "max_speed_ratio": "-",
    "joints_over_speed_limit": "count",
    "path_size": "m",
    "tracking_error_ratio": "-",
    "h_start_time": "s",
    "max_joint_limit_violation": "rad (m for a prismatic joint)",
    "rms_error_early": "m",
    "rms_error_last_fifth": "m",
    "rho_hat_peak_middle": "m/s^2",
    "rho_hat_peak_last_fifth": "m/s^2",
    "h_start": "criterion's unit",
    "h_end": "criterion's unit",
    "torque_chatter": "N m",
    "min_manipulability": "m^m (m^2 planar, m^3 position; mixed for a pose)",
    "final_rho_hat": "m/s^2",
    "singular_fraction": "-",
    "singular_episodes": "s",
    "simulated_seconds": "s",
    "wall_seconds": "s",
    "realtime_factor": "-",
    "max_inference_time": "s",
    "inference_over_period": "-",
    "max_joint_speed": "rad/s (m/s for a prismatic joint)",
    "plant_step": "s",
    "friction_events": "count",
    "unresolved_events": "count",
    "refined_periods": "count",
    "step_rotation": "rad (m for a prismatic joint)",
}
"""Units of the scalar metrics in metrics.json."""


@dataclass
class Result:
    """A simulated run sampled once per control period T.

    Attributes:
        t: time [s], N.
        q, dq: joint positions [rad], velocities [rad/s], N x n.
        tau: applied joint torques held over [t_k, t_k + T) [N m], N x n.
        tau_cmd: commanded torques (tau is tau_cmd clipped to the effort limits) [N m], N x n.
        x, x_d, e: actual and desired task coordinates and the task error, N x m: positions [m]
            and e = x - x_d, or for a pose task ``[p, log3(R)]`` and ``e = [p - p_d, log3(R R_d^T)]``
            (m, then rad).
        signals: per-sample scalars: ``h`` (criterion), ``manipulability`` (sqrt det J J^T) and
            the controller's (``rho_hat`` [m/s^2], ``eps``, ``z_norm``, and ``damping``: the lambda^2 of the
            damped pseudo-inverse, > 0 during a near-singular episode).
        status: ``completed``, ``diverged`` or ``interrupted``.
        message: why the run stopped early.
        config: the configuration that produced it (TOML text): what reruns it.
        info: what its analysis reads of that configuration, typed (:class:`RunInfo`: the
            criteria and their units, the robot, the task and trajectory), or None.
        wall_seconds: wall-clock time of the simulation [s].
        joint_names: names of the joints.
        chain: world positions of the joint origins and the task frame, N x (n + 1) x 3 [m]
            (for stick figures and the viewer).
        torque_limit: effort limit per joint [N m] (inf: none), or None for ideal actuators.
        velocity_limit: the URDF's velocity limit per joint [rad/s or m/s] (inf: none), or None
            (the speed verdict).
        envelope_speed_limit: the velocity limits of the plant's torque-speed envelope (inf:
            none), or None: the plant had no envelope (``plant.torque_speed``).
        torque_speed_knee: the envelope's knee (-1: none).
        lower_limit, upper_limit: joint position limits [rad or m], or None.
        prismatic: whether each joint is prismatic (units m, m/s, N), or None (all revolute).
        backend: which loop simulated it: ``python``, ``compiled`` or ``hybrid``.
        plant_step: the plant's integration step [s] (control period / substeps), or NaN.
        friction_events: stick-slip events the plant located inside its steps (docs/plant.md).
        unresolved_events: plant steps with more events than it resolves (a warning).
        refined_periods: control periods whose plant step was cut for speed or a stop
            (simulation.max_step_rotation, docs/plant.md#speed-adaptive-step).
        step_rotation: the most a joint turned in one plant step, from its speeds at the ends of
            each period and the step that period used [rad or m] (a warning above
            verdicts.STEP_ROTATION); NaN where unknown.
        plant_engine: the true plant's physics engine, ``pinocchio`` or ``mujoco``
            (docs/engines.md).
        engine_audit: for MuJoCo, its version and the worst relative differences of M, the bias
            and gravity from Pinocchio's at the audit's random states; None for Pinocchio.

    """

    t: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    tau: np.ndarray
    x: np.ndarray
    x_d: np.ndarray
    e: np.ndarray
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    status: str = "completed"
    message: str = ""
    config: str = ""
    wall_seconds: float = float("nan")
    joint_names: list[str] = field(default_factory=list)
    chain: np.ndarray | None = None
    tau_cmd: np.ndarray | None = None
    torque_limit: np.ndarray | None = None
    lower_limit: np.ndarray | None = None
    upper_limit: np.ndarray | None = None
    prismatic: np.ndarray | None = None
    velocity_limit: np.ndarray | None = None
    envelope_speed_limit: np.ndarray | None = None
    torque_speed_knee: float = -1.0
    backend: str = "python"
    plant_step: float = float("nan")
    friction_events: int = 0
    unresolved_events: int = 0
    refined_periods: int = 0
    step_rotation: float = float("nan")
    plant_engine: str = "pinocchio"
    engine_audit: dict | None = None
    info: RunInfo | None = None

    @classmethod
    def from_trace(
        cls,
        trace,
        robot,
        trajectory,
        criterion,
        config,
        wall_seconds: float,
        torque_limit: np.ndarray | None = None,
        substeps: int = 1,
        envelope_speed_limit: np.ndarray | None = None,
        torque_speed_knee: float = -1.0,
    ) -> Result:
        """Add task-space quantities (true kinematics) and the criterion to a simulation trace
        (those the loop recorded already are taken as they are).
        """
        N = trace.t.size
        pose = robot.task == "pose"
        x_d = trajectory.position(trace.t)
        if trace.recorded is not None and not pose:
            chain, h, manip = (trace.recorded[k] for k in ("chain", "h", "manipulability"))
            x = chain[:, -1, : robot.m]  # the last chain point is the task frame
        else:
            x = np.empty((N, robot.m))
            e = np.empty((N, robot.m))
            h = np.full(N, np.nan)
            manip = np.empty(N)
            chain = np.empty((N, robot.nq + 1, 3))
            for k in range(N):
                chain[k] = robot.chain_points(trace.q[k])
                if pose:
                    coords = robot.task_position(trace.q[k])
                    e[k] = trajectory.error(coords, trajectory(trace.t[k])[0])
                    x[k] = display_coordinates("pose", coords)
                else:
                    x[k] = chain[k, -1, : robot.m]  # the last chain point is the task frame
                J = robot.task_jacobian(trace.q[k])
                manip[k] = np.sqrt(max(det(J @ J.T), 0.0))
                if criterion is not None:
                    h[k] = criterion.value(robot, trace.q[k])
        if not pose:
            e = x - x_d
        signals = dict(trace.signals, h=h, manipulability=manip)
        return cls(
            trace.t,
            trace.q,
            trace.dq,
            trace.tau,
            x,
            x_d,
            e,
            signals,
            trace.status,
            trace.message,
            config.to_toml() if config is not None else "",
            wall_seconds,
            list(robot.joint_names),
            chain,
            trace.tau_cmd,
            torque_limit,
            robot.lower_limits,
            robot.upper_limits,
            robot.prismatic,
            plant_step=(config.simulation.control_period / substeps if config is not None else float("nan")),
            friction_events=trace.friction_events,
            unresolved_events=trace.unresolved_events,
            refined_periods=trace.refined_periods,
            step_rotation=step_rotation(trace.dq, config, substeps) if config is not None else float("nan"),
            info=RunInfo.from_config(config, trace.q.shape[1]) if config is not None else None,
            velocity_limit=velocity_limits(robot),
            envelope_speed_limit=envelope_speed_limit,
            torque_speed_knee=torque_speed_knee,
        )

    def available_torque(self) -> np.ndarray | None:
        """The torque each actuator could give at each step, in the direction of its command [N m]
        (N x n): the effort limit, cut at speed by the torque-speed envelope; None: ideal actuators.
        """
        if self.torque_limit is None:
            return None
        limit = np.broadcast_to(self.torque_limit, self.tau.shape)
        if self.torque_speed_knee < 0.0 or self.envelope_speed_limit is None:
            return limit
        tau_cmd = self.tau if self.tau_cmd is None else self.tau_cmd
        return available_torque(limit, tau_cmd, self.dq, self.envelope_speed_limit, self.torque_speed_knee)

    def experiment(self):
        """The :class:`~nnrobust.config.ExperimentConfig` that produced the run (from ``config``)."""
        return _experiment_of(self.config)

    def position_error(self) -> np.ndarray:
        """|position part of e| per sample [m] (the first two or three components)."""
        return np.linalg.norm(self.e[:, :3], axis=1)

    def orientation_error(self) -> np.ndarray | None:
        """|rotation-vector part of e| per sample [rad] for a pose task, else None."""
        return np.linalg.norm(self.e[:, 3:], axis=1) if self.e.shape[1] == 6 else None

    # -- metrics -----------------------------------------------------------------------------
    def metrics(self) -> dict:
        """Scalar summary; units in :data:`METRIC_UNITS`.

        The ``*_error`` metrics measure the position part of e; a pose task adds
        ``*_orientation_error`` (norm of the rotation-vector error).
        """
        err = self.position_error()
        turn = self.orientation_error()
        late = self.t >= SETTLED_AFTER
        tau_norm2 = np.sum(self.tau**2, axis=1)
        dtau = np.linalg.norm(np.diff(self.tau, axis=0), axis=1)

        def rms(a):
            return float(np.sqrt(np.mean(a))) if a.size else float("nan")

        rho = self.signals.get("rho_hat")
        tau_cmd = self.tau if self.tau_cmd is None else self.tau_cmd
        saturated = verdicts.saturation(self.tau, self.available_torque())
        limit = self.torque_limit
        torque_ratio, _ = verdicts.ratio_to_limit(tau_cmd, limit)
        applied_ratio, _ = verdicts.ratio_to_limit(self.tau, limit)
        rms_per_joint = np.sqrt(np.mean(self.tau**2, axis=0)) if self.tau.size else np.zeros(0)
        rms_ratio, _ = verdicts.ratio_to_limit(rms_per_joint[None, :], limit) if self.tau.size else (None, -1)
        over_speed, speed_ratio, speed_joint, joints_over = verdicts.speed_over_limit(
            self.dq, self.velocity_limit
        )
        size = verdicts.path_size(self.x_d)
        lower, upper = self.lower_limit, self.upper_limit
        violation, violating = (
            verdicts.joint_limit_violation(self.q, lower, upper)
            if lower is not None and upper is not None
            else (0.0, -1)
        )
        runaway, rms_early, rms_late = verdicts.runaway(self.t, err)
        growing, rho_middle, rho_late = verdicts.rho_growing(self.t, rho)
        tracking = rms(err[late] ** 2) / size if late.any() else None
        degraded, h_start, h_end, h_start_time = verdicts.subtask_loss(
            self.t, self.signals.get("h"), self.x_d
        )
        degraded = degraded and not (tracking is not None and tracking > verdicts.TRACKING_LOST)
        damping = self.signals.get("damping")
        damped = np.asarray(damping) > 0 if damping is not None else np.zeros(0, dtype=bool)
        simulated = float(self.t[-1] - self.t[0] + (self.t[1] - self.t[0])) if self.t.size > 1 else 0.0
        out = {
            "status": self.status,
            "rms_error": rms(err**2),
            "rms_error_after_2s": rms(err[late] ** 2),
            "max_error": float(err.max()) if err.size else float("nan"),
            "final_error": float(err[-1]) if err.size else float("nan"),
            "rms_torque": rms(tau_norm2),
            "rms_torque_per_joint": rms_per_joint.tolist(),
            "max_torque_per_joint": np.abs(self.tau).max(axis=0).tolist() if self.tau.size else [],
            "max_torque": float(np.abs(self.tau).max()) if self.tau.size else float("nan"),
            "max_torque_cmd": float(np.abs(tau_cmd).max()) if tau_cmd.size else float("nan"),
            "saturated_fraction": saturated,
            "max_torque_ratio": torque_ratio if torque_ratio is not None else 0.0,
            "max_applied_torque_ratio": applied_ratio,
            "rms_torque_ratio": rms_ratio,
            "speed_limit_fraction": over_speed,
            "max_speed_ratio": speed_ratio,
            "speed_limit_joint": speed_joint,
            "joints_over_speed_limit": joints_over,
            "path_size": size,
            "tracking_error_ratio": tracking,
            "max_joint_limit_violation": violation,
            "joint_limit_joint": violating,
            "torque_chatter": rms(dtau**2),
            "min_manipulability": (
                float(np.min(self.signals["manipulability"])) if err.size else float("nan")
            ),
            "final_rho_hat": float(rho[-1]) if rho is not None and rho.size else None,
            "rho_hat_peak_middle": rho_middle if rho is not None else None,
            "rho_hat_peak_last_fifth": rho_late if rho is not None else None,
            "rho_hat_growing": growing,
            "rms_error_early": rms_early,
            "rms_error_last_fifth": rms_late,
            "runaway": runaway,
            "h_start": h_start,
            "h_end": h_end,
            "h_start_time": h_start_time,
            "subtask_degraded": degraded,
            "singular_fraction": float(np.mean(damped)) if damped.size else 0.0,
            "singular_episodes": singular_episodes(self.t, damped),
            "simulated_seconds": simulated,
            "wall_seconds": self.wall_seconds,
            "backend": self.backend,
            "max_joint_speed": float(np.abs(self.dq).max()) if self.dq.size else float("nan"),
            "joint_speed_joint": int(np.argmax(np.abs(self.dq).max(axis=0))) if self.dq.size else -1,
            "plant_step": self.plant_step,
            "friction_events": self.friction_events,
            "unresolved_events": self.unresolved_events,
            "refined_periods": self.refined_periods,
            "step_rotation": self.step_rotation,
            "realtime_factor": simulated / self.wall_seconds if self.wall_seconds > 0 else None,
            "plant_engine": self.plant_engine,
            "engine_audit": self.engine_audit,
            "torque_speed_knee": self.torque_speed_knee,
        }
        if turn is not None:
            out["rms_orientation_error"] = rms(turn**2)
            out["rms_orientation_error_after_2s"] = rms(turn[late] ** 2)
            out["max_orientation_error"] = float(turn.max()) if turn.size else float("nan")
        inference = self.signals.get("inference_time")  # a learned policy's (controllers/laws/policy.py)
        if inference is not None and self.t.size > 1:
            seconds = np.asarray(inference, dtype=float)
            out["max_inference_time"] = float(np.nanmax(seconds)) if np.isfinite(seconds).any() else None
            out["inference_over_period"] = float(np.mean(seconds > self.t[1] - self.t[0]))
        if self.message:
            out["message"] = self.message
        units = (
            ["m/s" if p else "rad/s" for p in self.prismatic]
            if self.prismatic is not None
            else (["rad/s"] * self.q.shape[1])
        )
        out["warnings"] = verdicts.run_warnings(out, self.joint_names, units)
        return out

    # -- files -------------------------------------------------------------------------------
    def summary_rows(self) -> list[tuple[str, str]]:
        """(quantity, value) of the headline metrics, errors in mm: what a notebook shows."""
        m = self.metrics()
        rows = [
            ("status", str(m["status"])),
            ("backend", self.backend),
            ("plant engine", self.plant_engine),
            (
                "simulated",
                f"{self.t[-1] + (self.t[1] - self.t[0] if self.t.size > 1 else 0):.3g} s"
                if self.t.size
                else "0 s",
            ),
        ]
        for key, label, scale, unit in (
            ("rms_error", "RMS error", 1e3, "mm"),
            ("rms_error_after_2s", "RMS error, t >= 2 s", 1e3, "mm"),
            ("max_error", "max error", 1e3, "mm"),
            ("rms_torque", "RMS torque norm", 1.0, "N m"),
            ("rms_torque_ratio", "RMS torque / limit, worst joint", 1.0, ""),
            ("max_speed_ratio", "peak speed / limit", 1.0, ""),
            ("torque_chatter", "chatter", 1.0, "N m"),
            ("saturated_fraction", "saturated steps", 100.0, "%"),
        ):
            value = m.get(key)
            if value is not None:
                rows.append((label, f"{scale * value:.4g} {unit}".rstrip()))
        rows += [("warning", w) for w in m.get("warnings", [])]
        return rows

    def _repr_html_(self) -> str:
        """Jupyter: the summary table. The front door (``import nnrobust``) registers a notebook
        formatter that adds the path and error figures (:func:`nnrobust.outputs.plots.result_html`);
        the figures are drawn above this floor, so the table is what a result shows on its own.
        """
        import html

        rows = "".join(
            f"<tr><td>{html.escape(k)}</td><td>{html.escape(v)}</td></tr>" for k, v in self.summary_rows()
        )
        return f"<table>{rows}</table>"

    def save_npz(self, path: str | Path) -> None:
        """Arrays and signals in one .npz (signals prefixed ``signal_``), uncompressed: zlib saves
        about a fifth (10 s of the Panda: 4.2 MB instead of 5.4 MB) and takes as long as the
        simulation itself (0.18 s).
        """
        arrays = {k: getattr(self, k) for k in ("t", "q", "dq", "tau", "x", "x_d", "e")}
        arrays.update({f"signal_{k}": v for k, v in self.signals.items()})
        arrays["joint_names"] = np.asarray(self.joint_names)
        if self.info is not None:
            arrays["info"] = np.asarray(self.info.to_json())
        for name in OPTIONAL_ARRAYS:
            if getattr(self, name) is not None:
                arrays[name] = getattr(self, name)
        with open(path, "wb") as fh:
            np.savez(fh, **arrays)

    @classmethod
    def load(cls, folder: str | Path) -> Result:
        """Read a run folder written by :func:`write_run`."""
        folder = Path(folder)
        with np.load(folder / "result.npz") as data:
            arrays = {k: data[k] for k in data.files}
        metrics = json.loads((folder / "metrics.json").read_text())
        config = (folder / "config.toml").read_text() if (folder / "config.toml").exists() else ""
        signals = {k[len("signal_") :]: v for k, v in arrays.items() if k.startswith("signal_")}
        optional = {name: arrays.get(name) for name in OPTIONAL_ARRAYS}
        return cls(
            t=arrays["t"],
            q=arrays["q"],
            dq=arrays["dq"],
            tau=arrays["tau"],
            x=arrays["x"],
            x_d=arrays["x_d"],
            e=arrays["e"],
            signals=signals,
            status=metrics.get("status", "completed"),
            message=metrics.get("message", ""),
            config=config,
            wall_seconds=metrics.get("wall_seconds", float("nan")),
            joint_names=arrays["joint_names"].tolist(),
            chain=optional["chain"],
            tau_cmd=optional["tau_cmd"],
            torque_limit=optional["torque_limit"],
            lower_limit=optional["lower_limit"],
            upper_limit=optional["upper_limit"],
            prismatic=optional["prismatic"],
            velocity_limit=optional["velocity_limit"],
            envelope_speed_limit=optional["envelope_speed_limit"],
            torque_speed_knee=metrics.get("torque_speed_knee", -1.0),
            backend=metrics.get("backend", "python"),
            plant_step=metrics.get("plant_step", float("nan")),
            friction_events=metrics.get("friction_events", 0),
            unresolved_events=metrics.get("unresolved_events", 0),
            refined_periods=metrics.get("refined_periods", 0),
            step_rotation=metrics.get("step_rotation", float("nan")),
            plant_engine=metrics.get("plant_engine", "pinocchio"),
            engine_audit=metrics.get("engine_audit"),
            info=_stored_info(arrays, config, arrays["q"].shape[1]),
        )


def _experiment_of(config: str):
    """The experiment of a run's config.toml text."""
    from ..config import from_dict, parse_toml

    return from_dict(parse_toml(config, "config.toml"))


def _stored_info(arrays: dict, config: str, n: int) -> RunInfo | None:
    """result.npz's run info; for a folder written before it had one, read from config.toml."""
    if "info" in arrays:
        return RunInfo.from_json(str(arrays["info"]))
    if not config:
        return None
    try:
        return RunInfo.from_config(_experiment_of(config), n)
    except (NNRobustError, ValueError):  # a configuration this version cannot read
        return None


def velocity_limits(robot) -> np.ndarray | None:
    """The robot's velocity limits [rad/s or m/s], inf where its URDF gives none (or a placeholder);
    None for a model without them (the closed-form arm).
    """
    speed = getattr(robot, "velocity_limits", None)
    return None if speed is None else limits_or_inf(speed)


def step_rotation(dq: np.ndarray, config, substeps: int) -> float:
    """The most a joint turned in one plant step [rad or m]: per control period, the larger of the
    fastest joint's speeds at its two ends times the step the period used
    (simulation.period_substeps; MuJoCo's step is fixed).
    """
    if dq.size == 0 or not np.all(np.isfinite(dq)):
        return float("nan")
    from ..config import step_rotation_limit

    sim, rotation = config.simulation, step_rotation_limit(config)
    speed = np.abs(dq).max(axis=1)
    steps = period_substeps(speed, sim.control_period, substeps, rotation)
    ends = np.maximum(speed, np.append(speed[1:], speed[-1]))
    return float(np.max(ends * sim.control_period / steps))


OPTIONAL_ARRAYS = (
    "chain",
    "tau_cmd",
    "torque_limit",
    "lower_limit",
    "upper_limit",
    "prismatic",
    "velocity_limit",
    "envelope_speed_limit",
)
"""Arrays of result.npz that older run folders or hand-made Results may lack."""

MAX_EPISODES = 20
"""Singular episodes listed in metrics.json (the count is always complete)."""


def singular_episodes(t: np.ndarray, damped: np.ndarray) -> dict:
    """Intervals [start, end] [s] during which J+ was damped (sigma_min(J) below the threshold)."""
    if not damped.size or not damped.any():
        return {"count": 0, "intervals": []}
    edges = np.diff(np.concatenate([[0], damped.astype(int), [0]]))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    intervals = [[float(t[a]), float(t[b])] for a, b in zip(starts, ends)]
    return {"count": len(intervals), "intervals": intervals[:MAX_EPISODES]}


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file and a rename (never a half-written
    file; the umask's mode).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.partial-{os.getpid()}")
    tmp.unlink(missing_ok=True)  # created afresh: never written through a link left in its place
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0), 0o666)
    with os.fdopen(fd, "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(tmp, path)
    return path


def write_json_atomic(path: str | Path, data) -> Path:
    """Write JSON to ``path`` through a temporary file and a rename (never a half-written file)."""
    return write_text_atomic(path, json.dumps(data, indent=2, default=json_default) + "\n")


SUMMARY_BYTES = 200_000_000
"""The most a summary or report read back may have (a study's report is a few MB)."""


def read_json(path: str | Path, what: str, limit: int = SUMMARY_BYTES):
    """A JSON file nnrobust wrote (a summary, a report), read back with one-line errors: a file
    that is missing, larger than ``limit`` bytes, not JSON, or nested too deeply to parse (a
    received folder is not trusted).
    """
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > limit:
            raise NNRobustError(
                f"{path}: {size / 1e6:.0f} MB is more than a {what} has (at most {limit / 1e6:g} MB)"
            )
        return json.loads(path.read_text(encoding="utf-8"))
    except RecursionError as err:
        raise NNRobustError(f"{path}: not a {what}: its JSON nests too deeply") from err
    except (ValueError, UnicodeDecodeError) as err:
        raise NNRobustError(f"{path}: not a {what}: not JSON ({err})") from err
    except OSError as err:
        raise NNRobustError(f"{path}: cannot read the {what}: {err.strerror or err}") from err


def json_default(value):
    """JSON for numpy scalars (``json.dumps(..., default=json_default)``)."""
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to JSON")
