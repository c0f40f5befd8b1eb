"""Joint-space computed torque along a designed excitation (``controller.kind = "joint-fourier"``;
compiled twin csrc/controllers/laws/joint_fourier.cpp; docs/identification.md, "Designing the
excitation"): the law that runs ``nnrobust identify design``'s joint trajectory as it was
designed, every joint along it, where the task-space laws follow it in the task's directions only.

    q_d(t)  = q0 + Σ_l (a_l sin(w l t) − b_l cos(w l t)) / (w l)
    q̇_d(t)  = Σ_l a_l cos(w l t) + b_l sin(w l t)
    q̈_d(t)  = Σ_l w l (b_l cos(w l t) − a_l sin(w l t))
    τ       = M̂(q) (q̈_d + K_v (q̇_d − q̇) + K_p (q_d − q)) + N̂(q, q̇) + F̂(q̇)

with K_p = ω² and K_v = 2 ζ ω, the joint error's closed loop a critically damped (ζ = 1) second
order system of bandwidth ω on the nominal model. The default ω = 100 rad/s is a stiff joint servo,
as a robot's own joint controller is (the sampling limit at 1 kHz is 2 000 rad/s): at 20 rad/s the
paper arm's unmodelled friction and disturbance hold its third joint 0.56 rad RMS off the design,
at 150 rad/s 0.009 rad. q0, a, b and f are read from the design's
record (``traj.json``); the experiment's path must be the task frame's along q_d(t) (the
experiment file identify design writes), which the law checks where it is built: its metrics
then measure how closely the arm follows the designed motion.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ...core.exceptions import ConfigError
from ...core.search_coordinates import bandwidth_range
from ..base import Controller, ControllerContext, ControlOutput
from ..registry import Law, LawParam, register_law

PATH_TOLERANCE = 1e-6
"""Largest distance [m] between the experiment's path and the task frame along q_d(t) at the
instants checked (the design's spline through the task positions is within 1e-9 of it there)."""

PATH_CHECKS = 25
"""Instants of the first period at which the path is checked."""


def read_excitation(file: str | Path, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(q0, a, b, f) of a design's record (``nnrobust identify design``'s JSON), checked for an arm
    of ``n`` joints; a ConfigError names the file and what is wrong.
    """
    where = "controller.params.file"
    try:
        data = json.loads(Path(file).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError) as err:
        raise ConfigError(where, f"{file}: not a readable JSON file ({err})") from err
    if not isinstance(data, dict) or not str(data.get("format", "")).startswith("nnrobust-excitation/"):
        raise ConfigError(where, f"{file} is not a design's record (nnrobust identify design writes one)")
    try:
        q0 = np.asarray(data["q0"], dtype=float)
        a, b = np.asarray(data["a"], dtype=float), np.asarray(data["b"], dtype=float)
        frequency = float(data["frequency"])
    except (KeyError, TypeError, ValueError) as err:
        raise ConfigError(where, f"{file}: its q0, a, b and frequency must be numbers ({err})") from err
    if q0.shape != (n,) or a.ndim != 2 or a.shape[0] != n or a.shape != b.shape:
        raise ConfigError(
            where,
            f"{file} designs {q0.size} joints with a {a.shape} and b {b.shape}; the arm has {n} joints "
            "(q0: n numbers, a and b: n rows of one coefficient per harmonic)",
        )
    values = np.concatenate([q0, a.ravel(), b.ravel(), [frequency]])
    if not np.all(np.isfinite(values)) or not frequency > 0:
        raise ConfigError(where, f"{file}: its coefficients must be finite and its frequency positive")
    return q0, a, b, frequency


class JointFourierTracking(Controller):
    """Joint-space computed torque along a finite-Fourier joint trajectory (the module docstring)."""

    def __init__(self, context: ControllerContext, file=None, bandwidth=100.0, damping_ratio=1.0):
        if file is None:
            raise ConfigError(
                "controller.params.file",
                "joint-fourier follows a designed joint trajectory: give the design's record, "
                'file = "traj.json" (nnrobust identify design writes it)',
            )
        n = context.n
        self.q_mean, self.sine, self.cosine, frequency = read_excitation(file, n)
        self.omega = 2 * math.pi * frequency
        self.harmonics = self.sine.shape[1]
        self.Kp, self.Kv = float(bandwidth) ** 2, 2.0 * float(damping_ratio) * float(bandwidth)
        self.nominal, self.friction = context.nominal, context.nominal_friction
        self._check_path(context, file)

    def reference(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q_d, q̇_d, q̈_d) at t, harmonic by harmonic (as the compiled twin sums them)."""
        q, dq, ddq = self.q_mean.copy(), np.zeros_like(self.q_mean), np.zeros_like(self.q_mean)
        for l in range(self.harmonics):
            rate = self.omega * (l + 1)
            s, c = math.sin(rate * t), math.cos(rate * t)
            a, b = self.sine[:, l], self.cosine[:, l]
            q += (a * s - b * c) / rate
            dq += a * c + b * s
            ddq += rate * (b * c - a * s)
        return q, dq, ddq

    def _check_path(self, context: ControllerContext, file) -> None:
        """The experiment's path is the task frame's along q_d(t) (the module docstring)."""
        nominal, path = context.nominal, context.trajectory
        period = 2 * math.pi / self.omega
        for t in np.linspace(0.0, period, PATH_CHECKS):
            frame = nominal.task_position(self.reference(float(t))[0])
            x_d = path(float(t))[0]
            if frame.shape != x_d.shape or np.linalg.norm(frame[: x_d.size] - x_d) > PATH_TOLERANCE:
                raise ConfigError(
                    "controller.params.file",
                    f"the task frame along {Path(file).name}'s joint trajectory is not the experiment's "
                    f"path (at t = {t:.3g} s: {np.round(frame, 4).tolist()} against "
                    f"{np.round(x_d, 4).tolist()} m): run the experiment file identify design wrote "
                    'beside it, or start yours from it (base = "traj.toml")',
                )

    def compute(
        self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray, period: float = 0.0
    ) -> ControlOutput:
        """τ = M̂(q) (q̈_d + K_v (q̇_d − q̇) + K_p (q_d − q)) + N̂(q, q̇) + F̂(q̇)."""
        q_d, dq_d, ddq_d = self.reference(t)
        a = ddq_d + self.Kv * (dq_d - v) + self.Kp * (q_d - q)
        return ControlOutput(self.nominal.inverse_dynamics(q, v, a) + self.friction.torque(v))


LAW = register_law(
    Law(
        "joint-fourier",
        JointFourierTracking,
        "joint-space computed torque along a designed excitation's joint trajectory (nnrobust "
        "identify design's traj.json): every joint along the design",
        (
            LawParam("file", None, "-", "the design's record, traj.json (docs/identification.md)", path=True),
            LawParam(
                "bandwidth",
                100.0,
                "rad/s",
                "ω: K_p = ω², K_v = 2 ζ ω (a stiff joint servo)",
                1e-6,
                1e6,
                search=bandwidth_range,
                high_reason="sampling: w (1/2 + delay) T = 1",
            ),
            LawParam(
                "damping_ratio",
                1.0,
                "-",
                "ζ of the joint error's closed loop",
                1e-3,
                1e3,
                search=(0.3, 3.0),
            ),
        ),  # fmt: skip
        twin="joint_fourier",
        twin_fields=("q_mean", "sine", "cosine", "omega", "Kp", "Kv"),
    )
)
