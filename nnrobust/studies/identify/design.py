"""Excitation design (``nnrobust identify design``; docs/identification.md, "Designing the
excitation"): the finite-Fourier joint trajectory (Swevers, Ganseman, Tukel, De Schutter and Van
Brussel 1997; the form of :class:`.synthetic.FourierTrajectory`) that minimises the condition
number identify checks before it fits (:func:`.fit.identifiability`: the base regressor with
unit-norm columns, friction columns included), within each joint's range, velocity and effort
limits, at rest at its start and at the end of every period; or, as an option, the D-optimal one
(the least-squares region's volume, :data:`CRITERIA`). The search is CMA-ES (Hansen; the ``cma``
package) over the coefficients, with a stated budget of evaluations.

q_i(t) = q0_i + sum_l a_il / (w l) sin(w l t) - b_il / (w l) cos(w l t), w = 2 pi f. At rest at
t = 0 (and so at every period's end) means q'_i(0) = sum_l a_il = 0 and q''_i(0) = w sum_l l b_il
= 0: the last harmonic's a_iL and b_iL are fixed by the others, so the search moves q0 and the
first L - 1 harmonics' coefficients, n (2 L - 1) numbers.

The limits are checked on the objective's samples during the search, and the result on a grid of
1 kHz over a whole period (an evaluation between two samples could exceed a limit the samples
keep): where the fine grid finds a violation the swing is shrunk about q0 until none is left.
The torque checked is the URDF model's own (its bodies and its ``<dynamics>`` friction): the
design is for the robot the URDF describes, as identification starts from it.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ...core.exceptions import ConfigError
from ...model.regressor import (
    ParameterLayout,
    base_parameters,
    friction_regressor,
    position_ranges,
    torque_regressor,
)
from .fit import NormalEquations, base_columns, equation_rows, identifiability
from .signals import FilterChoice, near_reversal
from .synthetic import FourierTrajectory

CHECK_RATE = 1000.0
"""Samples per second of the final limit check [Hz]."""

NO_LIMIT = 1e10
"""A velocity or effort limit at or above this (Pinocchio's value when a URDF gives none), or zero,
is no limit."""

CRITERIA = {
    "condition": "log10 of the condition number of the base regressor with unit-norm columns (identify's)",
    "d-optimal": "-log10 det(W^T W) / p over the base columns in SI units: the confidence region's volume",
}
"""What a design may minimise. The condition number is what identify checks; it is blind to scale
(a trajectory that excites every direction weakly can score as well as one that excites every
direction strongly), and the parameters' standard errors are not. D-optimality (Swevers et al.
1997 discuss both) minimises the volume of the least-squares confidence region with equal noise
on every joint, which is what the box identify writes is made of."""

INFEASIBLE = 1e6
"""The objective of a point beyond a limit: this plus how far beyond (above every point within)."""

SHRINK = 0.98
"""Factor a swing is shrunk by at each step of the final check."""


@dataclass(frozen=True)
class DesignOptions:
    """The design's choices.

    Attributes:
        harmonics: L, harmonics of the trajectory (at least 2: one is fixed by the rest
            condition).
        frequency: f, its base frequency [Hz]; the period is 1 / f.
        samples: samples of one period in the objective.
        position_margin: share of each joint's range kept free at either end.
        velocity_share: share of each joint's velocity limit the trajectory may use.
        torque_share: share of each joint's effort limit the URDF model's torque may use.
        max_velocity: a velocity limit [rad/s] for the joints whose URDF gives none (None: such
            a joint is refused).
        friction: the friction terms of the fit whose condition is minimised.
        stick_band: |q'| under which a joint's row leaves the fit (identify's ``--stick-band``).
        reversal_guard: seconds on either side of a joint's velocity reversal whose rows leave
            the fit (identify's default ``--reversal-guard`` at its default ``--cutoff``).
        evaluations: the search's budget of objective evaluations.
        seed: the search's seed (its start and its samples).
        criterion: what the search minimises (:data:`CRITERIA`).

    """

    harmonics: int = 5
    frequency: float = 0.1
    samples: int = 200
    position_margin: float = 0.05
    velocity_share: float = 0.8
    torque_share: float = 0.8
    max_velocity: float | None = None
    friction: tuple[str, ...] = ("viscous", "coulomb")
    stick_band: float = 0.01
    reversal_guard: float = FilterChoice().reversal_guard / FilterChoice().cutoff
    evaluations: int = 6000
    seed: int = 0
    criterion: str = "condition"

    def check(self) -> None:
        """Each choice in its range (a ConfigError names the option)."""
        rules = (
            ("--harmonics", self.harmonics, 2 <= self.harmonics <= 20, "2 to 20"),
            ("--frequency", self.frequency, 1e-3 <= self.frequency <= 10, "0.001 to 10 Hz"),
            ("--samples", self.samples, 20 <= self.samples <= 5000, "20 to 5000"),
            ("--position-margin", self.position_margin, 0 <= self.position_margin < 0.5, "in [0, 0.5)"),
            ("--velocity-share", self.velocity_share, 0 < self.velocity_share <= 1, "in (0, 1]"),
            ("--torque-share", self.torque_share, 0 < self.torque_share <= 1, "in (0, 1]"),
            ("--evaluations", self.evaluations, 10 <= self.evaluations <= 10**6, "10 to 1e6"),
        )
        for option, value, ok, valid in rules:
            if not ok:
                raise ConfigError(option, f"must be {valid}, got {value}")
        if self.criterion not in CRITERIA:
            raise ConfigError("--criterion", f"{self.criterion!r} is not one of {', '.join(CRITERIA)}")
        if self.max_velocity is not None and not 0 < self.max_velocity < NO_LIMIT:
            raise ConfigError(
                "--max-velocity", f"must be a positive number of rad/s, got {self.max_velocity}"
            )


@dataclass
class Design:
    """A designed excitation.

    Attributes:
        joints: the joints' names, in the model's order.
        trajectory: the trajectory, one period of which is the design.
        condition: its condition number (:func:`.fit.identifiability` on the objective's samples).
        start_condition: the search's start's.
        value: the criterion's value (:data:`CRITERIA`) of the design; ``start_value`` the start's.
        evaluations: objective evaluations spent.
        stop: why the search stopped (CMA-ES's reason, or the budget).
        history: (evaluations, the best criterion value so far; None while no point kept the
            limits) after each generation.
        peaks: per joint, the share of its room used at the 1 kHz check: ``position`` (of the
            range within the margins), ``velocity`` and ``torque`` (of the limit the shares
            allow; NaN where the URDF gives none).
        shrink: the factor the final check shrank the swing by (1: none).
        seconds: the search's wall time [s].

    """

    joints: tuple[str, ...]
    trajectory: FourierTrajectory
    condition: float
    start_condition: float
    evaluations: int
    stop: str
    history: list[tuple[int, float | None]]
    peaks: dict[str, list[float]]
    value: float = math.nan
    start_value: float = math.nan
    shrink: float = 1.0
    seconds: float = 0.0
    limits: dict[str, list[float]] = field(default_factory=dict)


def peak_share(room: dict[str, np.ndarray]) -> float:
    """The largest share of any limit's room used (:meth:`ExcitationProblem.room_used`; a limit
    the URDF does not give, NaN, uses none).
    """
    return max(float(np.nanmax(v, initial=0.0)) for v in room.values())


class ExcitationProblem:
    """The objective of the search and the limits it keeps, for one robot."""

    def __init__(self, model: pin.Model, options: DesignOptions, joints: tuple[str, ...]):
        from ...run.compiled import torque_regressor_of
        from .engine import urdf_parameters

        options.check()
        self.model, self.options, self.n = model, options, model.nv
        self.layout = ParameterLayout(joints, tuple(options.friction))
        base = base_parameters(model, self.layout.names[: 10 * self.n])
        self.columns = base_columns(self.layout, base)
        self.names = [*base.names, *(self.layout.names[c] for c in self.columns[base.rank :])]
        self.urdf = urdf_parameters(model, self.layout)
        self._inertial = torque_regressor_of(model) or (lambda *x: torque_regressor(model, *x))
        low, high = position_ranges(model)
        finite = np.isfinite(low) & np.isfinite(high)
        width = np.where(finite, high - low, 2 * np.pi)
        centre = np.where(finite, (low + high) / 2, 0.0)
        self.low = centre - width * (0.5 - options.position_margin)
        self.high = centre + width * (0.5 - options.position_margin)
        self.position_limited = finite
        self.velocity_limit = self._velocity_limits(joints) * options.velocity_share
        effort = np.asarray(model.effortLimit, dtype=float)
        self.torque_limited = (effort > 0) & (effort < NO_LIMIT)
        self.torque_limit = np.where(self.torque_limited, effort, np.inf) * options.torque_share
        self.centre, self.half = centre, (self.high - self.low) / 2
        L = options.harmonics
        self.unit = self.velocity_limit / L  # a coefficient of 1 uses 1 / L of the velocity room
        self.sample_times = np.arange(options.samples) / (options.samples * options.frequency)

    def _velocity_limits(self, joints) -> np.ndarray:
        limit = np.asarray(self.model.velocityLimit, dtype=float).copy()
        missing = (limit <= 0) | (limit >= NO_LIMIT)
        if missing.any():
            if self.options.max_velocity is None:
                names = ", ".join(j for j, m in zip(joints, missing) if m)
                raise ConfigError(
                    "--max-velocity",
                    f"the URDF gives no velocity limit for {names}: give one (rad/s) with --max-velocity",
                )
            limit[missing] = self.options.max_velocity
        return limit

    @property
    def dimension(self) -> int:
        """Numbers the search moves: q0 and the first L - 1 harmonics' a and b."""
        return self.n * (2 * self.options.harmonics - 1)

    def trajectory(self, x: np.ndarray) -> FourierTrajectory:
        """The trajectory of the search's point ``x`` (module docstring)."""
        n, L = self.n, self.options.harmonics
        q0 = self.centre + self.half * x[:n]
        free = x[n:].reshape(2, n, L - 1) * self.unit[None, :, None]
        harmonic = np.arange(1, L + 1)
        a, b = np.empty((n, L)), np.empty((n, L))
        a[:, :-1], b[:, :-1] = free[0], free[1]
        a[:, -1] = -free[0].sum(axis=1)
        b[:, -1] = -(free[1] * harmonic[:-1]).sum(axis=1) / L
        return FourierTrajectory(q0, a, b, self.options.frequency)

    def regressor(self, q, dq, ddq) -> np.ndarray:
        """The full regressor (bodies, then friction) at N states: N x n x p."""
        return np.concatenate([self._inertial(q, dq, ddq), friction_regressor(self.layout, dq, ddq)], axis=2)

    def condition(self, Y: np.ndarray, dq: np.ndarray) -> float:
        """Identify's condition number of the samples' regressor (rows in stick left out)."""
        return identifiability(self.normal(Y, dq), self.columns, self.names).condition

    def room_used(self, q, dq, Y) -> dict[str, np.ndarray]:
        """Per joint, the peak share of its room each limit leaves (over 1: beyond it)."""
        swing = np.maximum((q - self.centre).max(axis=0), (self.centre - q).max(axis=0))
        tau = Y @ self.urdf
        return {
            "position": np.where(self.position_limited, swing / self.half, np.nan),
            "velocity": np.abs(dq).max(axis=0) / self.velocity_limit,
            "torque": np.where(self.torque_limited, np.abs(tau).max(axis=0) / self.torque_limit, np.nan),
        }

    def excess(self, q, dq, Y) -> float:
        """How far the samples go beyond the limits: 0 within them."""
        over = 0.0
        for share in self.room_used(q, dq, Y).values():
            over += float(np.nansum(np.maximum(np.nan_to_num(share, nan=0.0) - 1.0, 0.0)))
        return over

    def normal(self, Y: np.ndarray, dq: np.ndarray) -> NormalEquations:
        """The samples' normal equations, rows in stick left out (as identify builds them)."""
        normal = NormalEquations.empty(self.n, self.layout.size)
        reach = int(round(self.options.reversal_guard * self.options.samples * self.options.frequency))
        used = equation_rows(self.layout, dq, self.options.stick_band, near_reversal(dq, reach))
        normal.add(Y, np.zeros(dq.shape), used)
        return normal

    def criterion(self, Y: np.ndarray, dq: np.ndarray) -> float:
        """The criterion's value (:data:`CRITERIA`) of samples within the limits."""
        normal = self.normal(Y, dq)
        if self.options.criterion == "d-optimal":
            G = normal.G.sum(axis=0)[np.ix_(self.columns, self.columns)]
            sign, logdet = np.linalg.slogdet(G)
            return -logdet / math.log(10) / len(self.columns) if sign > 0 else INFEASIBLE / 2
        c = identifiability(normal, self.columns, self.names).condition
        return math.log10(c) if np.isfinite(c) else INFEASIBLE / 2

    def objective(self, x: np.ndarray) -> float:
        """The criterion within the limits; beyond them, :data:`INFEASIBLE` + how far beyond (any
        feasible point is better than every infeasible one).
        """
        q, dq, ddq = self.trajectory(np.asarray(x)).states(self.sample_times)
        Y = self.regressor(q, dq, ddq)
        over = self.excess(q, dq, Y)
        return INFEASIBLE + over if over > 0 else self.criterion(Y, dq)

    def check(self, trajectory: FourierTrajectory):
        """The room used per joint (:meth:`room_used`) on the 1 kHz grid."""
        t = np.arange(int(math.ceil(CHECK_RATE / self.options.frequency))) / CHECK_RATE
        q, dq, ddq = trajectory.states(t)
        Y = self.regressor(q, dq, ddq)
        return self.room_used(q, dq, Y)

    def random_at_limits(self, rng: np.random.Generator) -> FourierTrajectory:
        """A random trajectory about the middle of the ranges, at rest where a design is, scaled
        so that its tightest limit is just reached on the 1 kHz grid: what a design is compared
        with (docs/identification.md).
        """
        x = np.concatenate([np.zeros(self.n), rng.normal(0, 1, self.dimension - self.n)])
        trajectory = self.trajectory(x)
        for _ in range(50):
            peak = peak_share(self.check(trajectory))
            if 0.999 <= peak <= 1.0:
                break
            factor = min((1.0 - 1e-4) / peak, 2.0)
            trajectory = FourierTrajectory(
                trajectory.q0, trajectory.a * factor, trajectory.b * factor, trajectory.frequency
            )
        return _within_limits(self, trajectory)[0]

    def start(self, rng: np.random.Generator) -> np.ndarray:
        """A feasible start: random coefficients about the middle of the ranges, scaled until they
        use at most half of every limit's room.
        """
        x = np.concatenate([np.zeros(self.n), rng.normal(0, 1, self.dimension - self.n)])
        for _ in range(200):
            q, dq, ddq = self.trajectory(x).states(self.sample_times)
            peak = peak_share(self.room_used(q, dq, self.regressor(q, dq, ddq)))
            if peak <= 0.5:
                return x
            x[self.n :] *= min(0.9, 0.5 / peak)
        raise ConfigError(
            "--robot",
            "no trajectory about the middle of the joint ranges keeps within the effort limits "
            "(the URDF model's gravity torque there exceeds them?): raise --torque-share",
        )


def design_excitation(
    model: pin.Model, joints: tuple[str, ...], options: DesignOptions = DesignOptions(), say=lambda text: None
) -> Design:
    """The excitation of ``model`` (module docstring), its search progress passed to ``say``."""
    import cma

    started = time.perf_counter()
    problem = ExcitationProblem(model, options, joints)
    rng = np.random.default_rng(options.seed)
    x0 = problem.start(rng)
    start_value = problem.objective(x0)
    q, dq, ddq = problem.trajectory(x0).states(problem.sample_times)
    start_condition = problem.condition(problem.regressor(q, dq, ddq), dq)
    strategy = cma.CMAEvolutionStrategy(
        x0,
        0.3,
        {"seed": options.seed + 1, "maxfevals": options.evaluations, "verbose": -9, "tolfun": 1e-6},
    )
    history: list[tuple[int, float | None]] = []
    last = time.monotonic()
    while not strategy.stop():
        points = strategy.ask()
        strategy.tell(points, [problem.objective(x) for x in points])
        best = float(strategy.result.fbest)
        history.append((int(strategy.result.evaluations), best if best < INFEASIBLE / 2 else None))
        if time.monotonic() - last > 2.0:
            say(
                f"  {strategy.result.evaluations}/{options.evaluations} evaluations: {options.criterion} "
                f"{best:.4g} (start {start_value:.4g})"
            )
            last = time.monotonic()
    stop = ", ".join(f"{k} = {v}" for k, v in strategy.stop().items()) or "budget"
    best_x = strategy.result.xbest if strategy.result.fbest < start_value else x0
    trajectory = problem.trajectory(np.asarray(best_x))
    trajectory, shrink = _within_limits(problem, trajectory)
    peaks = problem.check(trajectory)
    q, dq, ddq = trajectory.states(problem.sample_times)
    Y = problem.regressor(q, dq, ddq)
    condition, value = problem.condition(Y, dq), problem.criterion(Y, dq)
    return Design(
        joints,
        trajectory,
        condition,
        start_condition,
        int(strategy.result.evaluations),
        stop,
        history,
        {k: v.tolist() for k, v in peaks.items()},
        value,
        start_value,
        shrink,
        time.perf_counter() - started,
        {
            "position_low": problem.low.tolist(),
            "position_high": problem.high.tolist(),
            "velocity": problem.velocity_limit.tolist(),
            "torque": problem.torque_limit.tolist(),
        },
    )


def _within_limits(problem: ExcitationProblem, trajectory: FourierTrajectory):
    """The trajectory with its swing about q0 shrunk until the 1 kHz check finds every limit kept."""
    shrink = 1.0
    for _ in range(400):
        if peak_share(problem.check(trajectory)) <= 1.0:
            return trajectory, shrink
        shrink *= SHRINK
        trajectory = FourierTrajectory(
            trajectory.q0, trajectory.a * SHRINK, trajectory.b * SHRINK, trajectory.frequency
        )
    raise ConfigError("--robot", "the designed trajectory could not be brought within the limits")


WAYPOINT_SPACING = 0.01
"""Seconds between the waypoints of the designed path's task-space spline (at least; a long run
spaces them so that it has at most :data:`MAX_DESIGN_WAYPOINTS`)."""

MAX_DESIGN_WAYPOINTS = 5000
"""Most waypoints of a designed path."""


def task_path(arm, trajectory: FourierTrajectory, duration: float) -> tuple[np.ndarray, np.ndarray]:
    """(waypoint times, task positions): where the task frame of ``arm`` is along the joint
    trajectory, every :data:`WAYPOINT_SPACING` seconds over ``duration`` and at its end.
    """
    spacing = max(WAYPOINT_SPACING, duration / MAX_DESIGN_WAYPOINTS)
    times = np.linspace(0.0, duration, int(math.ceil(duration / spacing)) + 1)
    q, _, _ = trajectory.states(times)
    return times, np.array([arm.task_position(qk) for qk in q])


def planar_task(arm, samples: int = 20, seed: int = 0) -> bool:
    """Whether the arm's task frame moves in a plane z = constant (a planar arm: task ``planar``)."""
    rng = np.random.default_rng(seed)
    low, high = position_ranges(arm.model)
    low, high = np.where(np.isfinite(low), low, -np.pi), np.where(np.isfinite(high), high, np.pi)
    z = [arm.task_position(rng.uniform(low, high))[2] for _ in range(samples)]
    return float(np.ptp(z)) < 1e-9


def experiment_toml(
    design: Design, robot: str, task: str, locked: list[str] | None, periods: int, times, points, record: str
) -> str:
    """The experiment file of the design: [robot], the task-space path through the joint
    trajectory's waypoints, the plant without a disturbance (a torque no log records would bias
    the fit), the joint-space law that follows the design (reading ``record``, the design's
    JSON, from the file's folder), and [simulation] starting at rest at q(0) for ``periods``
    periods.
    """
    from ...config.toml_io import dump_toml

    tr = design.trajectory
    q_start, _, _ = tr.states(np.zeros(1))
    robot_section: dict = {"source": robot, "task": task}
    if locked is not None:
        robot_section["locked_joints"] = list(locked)
    data = {
        "name": "excitation",
        "description": (
            f"An excitation trajectory designed by nnrobust identify design: {periods} period(s) of "
            f"{1 / tr.frequency:g} s, condition number {design.condition:.4g}"
        ),
        "robot": robot_section,
        "trajectory": {
            "kind": "waypoints",
            "waypoints": [
                [round(float(v), 12) for v in p] for p in points[:, : 2 if task == "planar" else 3]
            ],
            "waypoint_times": [round(float(t), 12) for t in times],
        },
        # an identification run logs every torque that acts on the arm: no unlogged disturbance
        "plant": {"disturbance": "none"},
        "controller": {"kind": "joint-fourier", "params": {"file": record}},
        "simulation": {"duration": float(times[-1]), "q_seed": [float(v) for v in q_start[0]]},
    }
    header = [
        "# An excitation trajectory for identification, written by nnrobust identify design",
        f"# (docs/identification.md, 'Designing the excitation'). The joint trajectory is in {record}",
        "# beside this file (a finite-Fourier series; run it with a robot's own joint controller).",
        "# Here it is an experiment: the task frame's path along it, and the joint-space law that",
        "# follows it joint by joint (controller.kind = 'joint-fourier'). Run it (nnrobust run), or",
        '# start an experiment from it (base = "this file"); a task-space law (--controller nn, ...)',
        "# follows the design in the task's directions only, its self-motion its subtasks'.",
        f"# condition number {design.condition:.6g} (the search's start: {design.start_condition:.6g})",
        "",
    ]
    return "\n".join(header) + dump_toml(data)


def design_record(
    design: Design, robot: str, joints, options: DesignOptions, periods: int, robot_file
) -> dict:
    """What the design's JSON holds: the joint trajectory, its limits and checks, the search."""
    from dataclasses import asdict

    from ...core.package_version import package_version
    from ..base.folder import file_sha256

    tr = design.trajectory
    return {
        "format": "nnrobust-excitation/1",
        "version": package_version(),
        "robot": robot,
        "robot_sha256": file_sha256(robot_file) if robot_file is not None else None,
        "joints": list(joints),
        "form": "q_i(t) = q0_i + sum_l a_il / (w l) sin(w l t) - b_il / (w l) cos(w l t), w = 2 pi f",
        "frequency": tr.frequency,
        "period": 1 / tr.frequency,
        "periods": periods,
        "q0": tr.q0.tolist(),
        "a": tr.a.tolist(),
        "b": tr.b.tolist(),
        "criterion": options.criterion,
        "criterion_value": design.value,
        "start_criterion_value": design.start_value,
        "condition_number": design.condition,
        "start_condition_number": design.start_condition,
        "evaluations": design.evaluations,
        "stop": design.stop,
        "seconds": design.seconds,
        "shrink": design.shrink,
        "room_used": design.peaks,
        "limits": design.limits,
        "options": {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(options).items()},
        "history": [list(h) for h in design.history],
    }


def write_design(
    robot: str,
    out,
    options: DesignOptions = DesignOptions(),
    periods: int = 2,
    task: str | None = None,
    locked_joints: list[str] | None = None,
    overwrite: bool = False,
    say=lambda text: None,
):
    """Design the excitation of ``robot`` and write ``out`` (the experiment) and ``out`` with the
    suffix ``.json`` (:func:`design_record`), each written whole and then moved into place.
    Returns (design, toml path, json path).
    """
    import json
    import os
    from pathlib import Path

    from ...core.exceptions import NNRobustError
    from ...core.folders import write_new
    from ...model.loading import load_robot

    options.check()
    out = Path(out)
    if out.suffix != ".toml":
        raise ConfigError("--out", f"{out} needs the suffix .toml (an experiment file)")
    record_path = out.with_suffix(".json")
    for path in (out, record_path):
        if path.exists() and not overwrite:
            raise NNRobustError(f"{path} exists; pass --overwrite to replace it")
    if not out.parent.is_dir():
        raise NNRobustError(f"{out.parent} is not a folder (--out)")
    arm = load_robot(robot, task="position", locked_joints=locked_joints)
    joints = tuple(arm.model.names[1:])
    task = task or ("planar" if planar_task(arm) else "position")
    say(
        f"designing {options.harmonics} harmonics at {options.frequency:g} Hz for {len(joints)} joints of "
        f"{robot} (task {task}), {options.evaluations} evaluations"
    )
    design = design_excitation(arm.model, joints, options, say)
    times, points = task_path(arm, design.trajectory, periods / options.frequency)
    source = str(Path(robot).absolute()) if Path(robot).is_file() else robot
    robot_file = Path(robot) if Path(robot).is_file() else None
    text = experiment_toml(design, source, task, locked_joints, periods, times, points, record_path.name)
    record = design_record(design, arm.name, joints, options, periods, robot_file)
    for path, content in ((record_path, json.dumps(record, indent=1) + "\n"), (out, text)):
        tmp = path.with_name(f".{path.name}.tmp")
        write_new(tmp, content)
        os.replace(tmp, path)
    return design, out, record_path
