"""Build an experiment from its configuration and run it: ``run_experiment(config) -> Result``.

Each part is built in its own room: the plant in nnrobust/plant/build.py, the nominal model in
nnrobust/model/nominal.py, the trajectory in nnrobust/trajectories/build.py, the criterion in
nnrobust/subtasks/build.py and the controller in nnrobust/controllers/build.py. This module
composes them, with what needs several at once: the initial state, the workspace, stiffness and
memory checks, the plant's step and the backend.
"""

from __future__ import annotations

import dataclasses
import hashlib
import time
import warnings
from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from ..config import (
    MAX_SUBSTEPS,
    ExperimentConfig,
    disturbance_kind,
    nominal_kind,
    provenance_header,
    step_rotation_limit,
)
from ..controllers import (
    Controller,
    ControllerContext,
    DampedPseudoInverse,
)
from ..controllers.build import build_context, build_controller
from ..core.exceptions import ConfigError, ModelMismatch, NNRobustError
from ..model import (
    DynamicsModel,
    PinocchioModel,
    load_robot,
)
from ..model.ik import reach, seed_configuration, solve_ik
from ..model.nominal import build_nominal_model, nominal_friction
from ..model.tasks import pose_vector, split_pose
from ..plant import (
    Plant,
)
from ..plant.build import (
    build_engine,
    build_plant,
    true_model,
)
from ..plant.loads import LOAD_KEYS, LOAD_UNITS
from ..plant.scaling import PLAUSIBLE_EFFORT_RATIO, implausible_efforts
from ..subtasks import Criterion
from ..subtasks.build import build_criterion
from ..trajectories import Trajectory, path_key
from ..trajectories.build import build_trajectory
from .results import Result
from .simulation import simulate


@dataclass
class Setup:
    """Everything a run needs, built from a configuration (inspectable before running)."""

    config: ExperimentConfig
    robot: PinocchioModel
    plant: Plant
    nominal: DynamicsModel
    trajectory: Trajectory
    criterion: Criterion | None
    controller: Controller
    q0: np.ndarray
    v0: np.ndarray
    controller_context: ControllerContext | None = None
    substeps: int = 1
    """Plant steps per control period: simulation.substeps, or chosen (:func:`plant_step`)."""


def initial_state(
    config: ExperimentConfig, robot: PinocchioModel, trajectory: Trajectory
) -> tuple[np.ndarray, np.ndarray]:
    """q(0) by IK of x_d(0) + offset from the seed; q'(0) = J+ x_d'(0) (no initial velocity error)."""
    sim = config.simulation
    xd0, dxd0, _ = trajectory(0.0)
    offset = (
        np.zeros(trajectory.m)
        if sim.initial_task_offset is None
        else np.asarray(sim.initial_task_offset, dtype=float)
    )
    if offset.shape != (trajectory.m,):
        raise ConfigError("simulation.initial_task_offset", f"needs {trajectory.m} entries")
    if robot.task == "pose":
        p, R = split_pose(xd0)
        target = pose_vector(p + offset[:3], pin.exp3(offset[3:]) @ R)
    else:
        target = xd0 + offset
    q0 = reach(
        robot,
        target,
        seed_configuration(sim.q_seed, robot),
        "x_d(0) + offset",
        f"trajectory.{path_key(config.trajectory)}",
    )
    J = robot.task_jacobian(q0)
    v0 = DampedPseudoInverse().matrix(J) @ dxd0
    return q0, v0


WORKSPACE_SAMPLES = 48
"""Instants at which check_workspace solves the inverse kinematics."""


_REACHABLE: set[tuple] = set()
"""Paths this process has found reachable (:func:`check_workspace`): a sweep's samples share
their arm and path, and the check's inverse kinematics costs a tenth of a short run."""


def _reach_key(config: ExperimentConfig, robot: PinocchioModel, q0: np.ndarray, samples: int) -> tuple:
    """What the workspace check depends on: the arm (its configuration and its URDF's text, or
    its name where code builds it), the path, the duration and q(0).
    """
    text = getattr(robot, "urdf_text", None)
    digest = hashlib.sha256(text.encode()).hexdigest() if text else robot.name
    return (
        repr(config.robot),
        repr(config.trajectory),
        config.simulation.duration,
        q0.tobytes(),
        samples,
        digest,
    )


REACHED = 1e-4
"""Task error [m] under which check_workspace takes an instant's point for reached."""

FRESH_SEEDS = 8
"""Random starts the workspace check tries at an instant the last solution does not reach."""


def _fresh_seeds(robot: PinocchioModel, q0: np.ndarray, rng: np.random.Generator):
    """Starts of the inverse kinematics other than the last solution: q(0), the middle of the
    joint ranges, then random configurations within them (a joint without limits within +-pi).
    """
    low = np.where(np.isfinite(robot.lower_limits), robot.lower_limits, -np.pi)
    high = np.where(np.isfinite(robot.upper_limits), robot.upper_limits, np.pi)
    yield q0
    yield (low + high) / 2
    for _ in range(FRESH_SEEDS):
        yield rng.uniform(low, high)


def check_workspace(
    config: ExperimentConfig,
    robot: PinocchioModel,
    trajectory: Trajectory,
    q0: np.ndarray,
    samples: int = WORKSPACE_SAMPLES,
) -> None:
    """Refuse a trajectory the arm cannot reach within its joint limits, before the run.

    Inverse kinematics at ``samples`` instants over the run (each from the previous solution, and
    where that does not reach the point from fresh starts, :func:`_fresh_seeds`, until one is out
    of reach); the message names the worst instant and point. A path found reachable is remembered for the
    process (:data:`_REACHABLE`).
    """
    key = _reach_key(config, robot, q0, samples)
    if key in _REACHABLE:
        return
    times = np.linspace(0.0, config.simulation.duration, samples)
    q, worst = q0, (0.0, 0.0, np.zeros(0))
    rng, retry = np.random.default_rng(0), True
    for t in times:
        target = trajectory(float(t))[0]
        q, residual = solve_ik(robot, target, q, robot.lower_limits, robot.upper_limits)
        for seed in _fresh_seeds(robot, q0, rng) if residual > REACHED and retry else ():
            # the last solution may lead into a local minimum at a joint limit: start afresh
            q_other, other = solve_ik(robot, target, seed, robot.lower_limits, robot.upper_limits)
            if other < residual:
                q, residual = q_other, other
            if residual <= REACHED:
                break
        retry = retry and residual <= REACHED  # once a point is out of reach, the path is refused
        if residual > worst[1]:
            worst = (float(t), residual, target)
    t, residual, target = worst
    if residual > REACHED:
        p = split_pose(target)[0] if robot.task == "pose" else target
        raise ConfigError(
            "trajectory",
            f"leaves the workspace: at t = {t:.3g} s the point {np.round(p, 4).tolist()} m is out of "
            f"reach within the joint limits (task error {residual:.3g} left after inverse "
            "kinematics); move the path (trajectory.center and axes, goal or waypoints)",
        )
    if len(_REACHABLE) > 1024:
        _REACHABLE.clear()
    _REACHABLE.add(key)


RK4_STABLE_STEP = 2.5
"""h * lambda below which RK4 is stable for a real decaying mode (the exact limit is 2.785)."""


def check_mass_matrix(robot: PinocchioModel, q0: np.ndarray) -> None:
    """Refuse a robot whose M(q0) is singular: a joint that moves (almost) no inertia, e.g. a link
    turning about its own axis, cannot be accelerated by any finite torque model.
    """
    M = robot.mass(q0)
    eigenvalues, vectors = np.linalg.eigh(M) if np.all(np.isfinite(M)) else (np.array([np.nan]), None)
    if vectors is None or not eigenvalues[0] > 1e-10 * max(eigenvalues[-1], 1e-300):
        joint = robot.joint_names[int(np.argmax(np.abs(vectors[:, 0])))] if vectors is not None else "?"
        raise ModelMismatch(
            f"{robot.name}: M(q) is singular at q(0) (smallest eigenvalue "
            f"{eigenvalues[0]:.3g}): joint {joint!r} moves (almost) no inertia; check its "
            "axis and the inertias of the links it moves"
        )


STOP_STEP = 1.0
"""h omega of a joint stop sized to the plant step: RK4 is stable up to 2.83, accurate below 1."""

MAX_STOP_YIELD = 0.05
"""Most a softened stop may yield at the joint's torque scale [rad or m] (the default stiffness
yields 0.01)."""


def plant_step(config: ExperimentConfig, plant: Plant, q0: np.ndarray) -> int:
    """Plant steps per control period: ``simulation.substeps`` as given (refused if unstable,
    :func:`check_stiffness`), or, when it is not given, chosen so that the plant converges.

    Unset, the stops are first sized from each joint's effective inertia m_i = 1/(M(q0)^-1)_ii: a
    stop that would make RK4 diverge at the 1-step default (h omega > 2.5) is softened to
    K_i = m_i / h^2 (h omega = 1), if it then still holds the joint's torque scale within
    :data:`MAX_STOP_YIELD`. What that cannot settle (a
    stop of a light link with a large effort, fast viscous friction) sets the substeps. Each is
    said in one warning.
    """
    sim = config.simulation
    given = sim.requested_substeps
    if given is not None or sim.integrator != "rk4":
        check_stiffness(config, plant, q0, given or 1)
        return given or 1
    T, names = sim.control_period, plant.model.joint_names
    M_inv = np.linalg.inv(plant.model.mass(q0))
    needed, reasons = 1, []
    stops = plant.stops
    if stops is not None:
        bounded = np.isfinite(stops.upper - stops.lower)
        omega = np.where(bounded, np.sqrt(stops.stiffness * np.diag(M_inv)), 0.0)
        sized = np.minimum(stops.stiffness, (STOP_STEP / T) ** 2 / np.diag(M_inv))
        yield_at_scale = stops.stiffness / (sized * config.plant.joint_stop_stiffness)
        soften = bounded & (omega * T > RK4_STABLE_STEP) & (yield_at_scale <= MAX_STOP_YIELD)
        if soften.any():
            stops = replace(stops, stiffness=np.where(soften, sized, stops.stiffness))
            plant.stops = stops
            joints = ", ".join(f"{names[i]!r} ({yield_at_scale[i]:.2g} rad)" for i in np.flatnonzero(soften))
            warnings.warn(
                f"joint stops sized to the plant step: the stops of {joints} are softened to their "
                f"effective inertia / h^2 (they ring at 1/h = {1 / T:g} rad/s, and yield so much "
                "at the joint's torque scale; set simulation.substeps to keep them stiff; "
                "docs/plant.md)",
                stacklevel=3,
            )
            omega = np.where(bounded, np.sqrt(stops.stiffness * np.diag(M_inv)), 0.0)
        i = int(np.argmax(omega))
        if T * omega[i] > RK4_STABLE_STEP:
            needed = _substeps_needed(T, omega[i])
            reasons.append(
                f"the stop of joint {names[i]!r} rings at {omega[i]:.3g} rad/s (a light link with "
                "a large effort)"
            )
    if np.any(plant.friction.viscous):
        fastest = float(np.max(np.linalg.eigvals(M_inv @ np.diag(plant.friction.viscous)).real))
        if T * fastest > RK4_STABLE_STEP:
            needed = max(needed, _substeps_needed(T, fastest))
            reasons.append(f"viscous friction has a mode of {fastest:.3g} 1/s (light outer links)")
    if needed > MAX_SUBSTEPS:
        raise ConfigError(
            "simulation.substeps",
            f"the plant is too stiff for RK4 at any practical step: {'; '.join(reasons)} asks for "
            f"{needed:,} steps per control period (at most {MAX_SUBSTEPS:,}); lower the friction or "
            "the stop stiffness, or shorten simulation.control_period",
        )
    if needed > 1:
        warnings.warn(
            f"simulation.substeps = {needed} chosen (plant step {T / needed:.3g} s): "
            f"{'; '.join(reasons)}; RK4 would diverge at {T:g} s. Set simulation.substeps to "
            "choose",
            stacklevel=3,
        )
    return needed


def stop_rings(plant: Plant, q0: np.ndarray) -> None:
    """Give the plant's stops their ring frequencies sqrt(K_i (M(q0)^-1)_ii) [rad/s], which the
    adaptive step resolves while a joint is at its stop (simulation.step_rate).
    """
    stops = plant.stops
    if stops is not None:
        bounded = np.isfinite(stops.upper) | np.isfinite(stops.lower)
        M_inv_diag = np.diag(np.linalg.inv(plant.model.mass(q0)))
        plant.stops = replace(stops, ring=np.where(bounded, np.sqrt(stops.stiffness * M_inv_diag), 0.0))


def check_stiffness(config: ExperimentConfig, plant: Plant, q0: np.ndarray, substeps: int) -> None:
    """Refuse an RK4 step that viscous friction or the joint stops make unstable.

    Viscous friction B on a joint that carries light outer links is a fast decaying mode of
    q'' = -M^-1 B q' + ...: its rate lambda = max eig(M(q0)^-1 B) grows quickly with the number
    of links (about 4e3 1/s for a 15-link chain with 3 % viscous level), and RK4 diverges when
    h lambda > 2.785. A joint stop of stiffness K_i oscillates at about sqrt(K_i (M^-1)_ii), and
    RK4 is unstable for h omega > 2.83. Checked once, at q(0).
    """
    sim = config.simulation
    if sim.integrator != "rk4":
        return
    h = sim.control_period / substeps
    M_inv = np.linalg.inv(plant.model.mass(q0))
    if np.any(plant.friction.viscous):
        fastest = float(np.max(np.linalg.eigvals(M_inv @ np.diag(plant.friction.viscous)).real))
        if h * fastest > RK4_STABLE_STEP:
            raise ConfigError(
                "simulation.substeps",
                f"viscous friction makes the dynamics stiff (fastest friction mode {fastest:.3g} 1/s "
                f"at q(0)); the RK4 step {h:.3g} s would diverge: set substeps >= "
                f"{_substeps_needed(sim.control_period, fastest)}, or lower plant.viscous_level / "
                "plant.viscous_friction",
            )
    if plant.stops is not None:
        omega = np.sqrt(plant.stops.stiffness * np.diag(M_inv))
        omega[~np.isfinite(plant.stops.upper - plant.stops.lower)] = 0.0
        i = int(np.argmax(omega))
        if h * omega[i] > RK4_STABLE_STEP:
            raise ConfigError(
                "plant.joint_stop_stiffness",
                f"the stop of joint {plant.model.joint_names[i]!r} rings at {omega[i]:.3g} rad/s "
                f"(light outer links); the RK4 step {h:.3g} s would diverge in contact: set "
                f"simulation.substeps >= {_substeps_needed(sim.control_period, omega[i])}, or lower "
                "plant.joint_stop_stiffness",
            )


def _substeps_needed(period: float, rate: float) -> int:
    return int(np.ceil(period * rate / RK4_STABLE_STEP))


def build_nominal(config: ExperimentConfig, robot: PinocchioModel) -> DynamicsModel:
    """The controller's nominal model of ``config``: ``[nominal]``'s model of the resolved kind, or
    the true model (armature and payload included) for computed-torque control
    (:func:`nnrobust.model.nominal.build_nominal_model`).
    """
    exact = true_model(config.plant, robot).model if config.controller.kind == "computed-torque" else None
    return build_nominal_model(config.nominal, robot, nominal_kind(config), exact)


def build(config: ExperimentConfig) -> Setup:
    """Load the robot and build plant, nominal model, controller and initial state.

    The configuration is checked again first, as an experiment file is: a configuration changed
    after it was loaded (``config.controller.kind = "lqr"``, a negative gain, a NaN duration)
    is refused with the key named, never run as something else.
    """
    config = checked(config)
    rc = config.robot
    robot = load_robot(
        rc.source,
        rc.task_frame,
        rc.task,
        tuple(rc.gravity) if rc.gravity else None,
        rc.locked_joints,
        rc.chain,
    )
    if robot.task != "pose" and config.trajectory.dimension != robot.m:
        raise ConfigError(
            f"trajectory.{path_key(config.trajectory)}",
            f"has {config.trajectory.dimension} entries per point, the {rc.task!r} task has m = {robot.m}",
        )
    if robot.m > robot.nq:
        raise ConfigError(
            "robot.task",
            f"m = {robot.m} > n = {robot.nq}: the arm has fewer joints than the "
            "task has coordinates (choose a smaller task or a longer robot.chain)",
        )
    if robot.m == robot.nq:
        warnings.warn(
            f"{robot.name}: not redundant (n = m = {robot.nq}): the null-space subtask has no room "
            "and eq. (9) is plain task-space control",
            stacklevel=2,
        )
    check_memory(config, robot.nq, robot.m)
    sim = config.simulation
    trajectory = build_trajectory(config.trajectory, robot, sim.q_seed)
    plant = build_plant(
        config.plant,
        config.sensing,
        robot,
        disturbance_kind=disturbance_kind(config),
        period=sim.control_period,
        duration=sim.duration,
    )
    nominal = build_nominal(config, robot)
    criterion = build_criterion(config.subtasks, robot)
    q0, v0 = initial_state(config, robot, trajectory)
    check_mass_matrix(robot, q0)
    substeps = plant_step(config, plant, q0)
    stop_rings(plant, q0)
    build_engine(config.plant, plant, sim.control_period, substeps)
    context = build_context(
        config.controller,
        robot,
        nominal,
        trajectory,
        criterion,
        plant,
        q0,
        period=sim.control_period,
        nominal_friction=nominal_friction(config.nominal, robot.nq),
        trajectory_key="trajectory.class" if config.trajectory.kind == "custom" else "trajectory.kind",
    )
    controller = build_controller(
        config.controller, config.nn, robot, nominal, trajectory, criterion, plant.friction, context
    )
    check_memory(config, robot.nq, robot.m, controller)  # with the law's own state and signals
    check_workspace(config, robot, trajectory, q0)
    return Setup(config, robot, plant, nominal, trajectory, criterion, controller, q0, v0, context, substeps)


def checked(config: ExperimentConfig) -> ExperimentConfig:
    """A validated copy of a configuration (types and values, as :func:`config.from_dict` checks
    an experiment file's).
    """
    from .. import config as config_module
    from ..config import from_dict

    if not isinstance(config, ExperimentConfig):
        raise ConfigError("config", f"expected an ExperimentConfig, got {type(config).__name__}")
    for field in dataclasses.fields(ExperimentConfig):  # a section replaced after loading
        section = getattr(config, field.name)
        wanted = vars(config_module).get(field.type) if isinstance(field.type, str) else field.type
        if isinstance(wanted, type) and dataclasses.is_dataclass(wanted) and not isinstance(section, wanted):
            got = f"{type(section).__name__} {section!r}"[:200]
            raise ConfigError(field.name, f"expected a {wanted.__name__} section, got {got}")
    try:
        data = config.to_dict()
    except (TypeError, ValueError, RecursionError) as err:
        raise ConfigError("config", f"cannot be read as a configuration: {err}") from err
    return from_dict(data)


DATA_BYTES_PER_CUBED_JOINT = 31.3
"""Bytes one ``pinocchio.Data`` of an n-joint chain takes, per n^3 (measured on planar50 to
planar200: 31.1 to 32.1); 0.85 GB for 300 joints."""

MODEL_COPIES = 6
"""Models with their data a run may hold at once: the plant's, the nominal's and the compiled
loop's copies of both, with their kinematics."""


def memory_estimate(
    config: ExperimentConfig, n: int, m: int, state_size: int | None = None, signals: int = 8
) -> float:
    """Bytes a run takes: its recorded arrays, times 3 for the copies made while the result is
    assembled and written (per control step q, q', tau, tau_cmd (4n), the chain (3(n + 1)),
    x, x_d, e (3 x 6 at most), the controller's state (``state_size``; before the controller is
    built, the compensator's 1 + inputs x centres + 1), sensor draws (2n) and its ``signals``, in
    float64), plus :data:`MODEL_COPIES` Pinocchio models with their data, which grow as n^3
    (:data:`DATA_BYTES_PER_CUBED_JOINT`).
    """
    sim, nn = config.simulation, config.nn
    steps = sim.duration / sim.control_period
    if state_size is None:
        inputs = 2 * n if nn.basis_input == "joint" else 2 * m
        state_size = 2 + inputs * nn.centers
    per_step = 4 * n + 3 * (n + 1) + 18 + state_size + 2 * n + signals
    return 3 * 8 * steps * per_step + MODEL_COPIES * DATA_BYTES_PER_CUBED_JOINT * n**3


def available_memory() -> float | None:
    """Bytes the machine has available now (Linux's MemAvailable), or None where unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def check_memory(config: ExperimentConfig, n: int, m: int, controller: Controller | None = None) -> None:
    """Refuse, before anything runs, a run whose estimated memory (:func:`memory_estimate`) would
    not fit simulation.memory_limit, or the memory the machine has available, whichever is less
    (a limit set higher than the machine cannot keep the kernel from killing the run). Called
    again once the controller is built, with its own state size and signals (a user's law may
    declare any).
    """
    sim = config.simulation
    if controller is None:
        need, law = memory_estimate(config, n, m) / 1e9, ""
    else:
        # (a user's state_size was checked when it was built: nnrobust.controllers.custom)
        state, signals = int(controller.state_size), len(controller.signal_names)
        need = memory_estimate(config, n, m, state, signals) / 1e9
        law = f", a state of {state} and {signals} signals per step"
    what = (
        f"this run needs about {need:.3g} GB ({sim.duration:g} s at {sim.control_period:g} s per step, "
        f"{n} joints{law})"
    )
    if need > sim.memory_limit:
        raise ConfigError(
            "simulation.memory_limit",
            f"{what} and the limit is {sim.memory_limit:g} GB; "
            "shorten simulation.duration, lengthen control_period or raise memory_limit",
        )
    available = available_memory()
    if available is not None and need > available / 1e9:
        raise ConfigError(
            "simulation.memory_limit",
            f"{what} and this machine has {available / 1e9:.3g} GB available; "
            "shorten simulation.duration or lengthen control_period",
        )


def choose_backend(setup: Setup) -> str:
    """``compiled``, ``hybrid`` or ``python`` for ``simulation.backend``. ``auto`` takes the
    compiled loop where the experiment has a compiled twin, the hybrid loop (compiled plant, the
    Python controller once per period) where only the controller's side has none (a custom
    controller or trajectory), else the Python loop; one warning
    when the extension itself is missing.
    """
    from . import compiled

    wanted = setup.config.simulation.backend
    if wanted == "python":
        return "python"
    if wanted == "hybrid":
        refusal = compiled.hybrid_refusal(setup)
        if refusal:
            raise ConfigError("simulation.backend", f"'hybrid' cannot run this experiment: {refusal}")
        return "hybrid"
    refusal = compiled.twin_refusal(setup)
    if wanted == "compiled" and refusal:
        raise ConfigError("simulation.backend", f"'compiled' cannot run this experiment: {refusal}")
    if not refusal:
        return "compiled"
    if not compiled.hybrid_refusal(setup):  # a Python-only part: a custom controller or trajectory
        return "hybrid"
    if not compiled.available():
        warnings.warn(f"running on the Python backend: {refusal}", stacklevel=3)
    return "python"


def run_experiment(config: ExperimentConfig, progress=None, setup: Setup | None = None) -> Result:
    """Build (unless ``setup`` is given) and simulate; the Result holds arrays, signals and the
    configuration. ``progress(t, q)`` is called every 50 control steps (the compiled backend calls
    it once, at the end). ``wall_seconds`` is the simulation loop's wall time alone.
    """
    setup = setup or build(config)
    config = setup.config  # the checked copy: what ran is what is recorded
    sim = config.simulation
    backend = choose_backend(setup)
    start = time.perf_counter()
    if backend == "compiled":
        from .compiled import simulate_compiled

        trace = simulate_compiled(setup, sim.duration)
    elif backend == "hybrid":
        from .compiled import is_policy, simulate_hybrid, simulate_policy

        if is_policy(setup.controller):  # the base law compiled, the inference in Python
            trace = simulate_policy(setup, sim.duration)
        else:
            trace = simulate_hybrid(setup, sim.duration)
    else:
        trace = simulate(
            setup.plant,
            setup.controller,
            setup.q0,
            setup.v0,
            sim.duration,
            sim.control_period,
            setup.substeps,
            sim.integrator,
            step_rotation_limit(config),
            progress=progress,
        )
    wall = time.perf_counter() - start
    if backend != "python" and progress is not None and trace.t.size:
        progress(float(trace.t[-1]), trace.q[-1])
    return result_of(setup, trace, wall, backend)


def result_of(setup: Setup, trace, wall: float, backend: str) -> Result:
    """The Result of a built experiment's trace (the run's, or a learning episode's), simulated
    in ``wall`` seconds on ``backend``: task-space quantities, verdicts and provenance.
    """
    config = setup.config
    if trace.status == "diverged":
        trace.message += "; " + likely_cause(setup, trace)
    result = Result.from_trace(
        trace,
        setup.robot,
        setup.trajectory,
        setup.criterion,
        config,
        wall,
        setup.plant.torque_limit,
        setup.substeps,
        setup.plant.speed_limit,
        setup.plant.torque_speed_knee,
    )
    result.backend = backend
    engine = setup.plant.engine
    if engine is not None:
        from ..plant.mujoco_engine import AUDIT_STATES, AUDIT_TOLERANCE, mujoco_version

        result.plant_engine = "mujoco"
        result.engine_audit = {
            "version": mujoco_version(),
            "integrator": engine.integrator,
            "states": AUDIT_STATES,
            "tolerance": AUDIT_TOLERANCE,
            **engine.audit,
        }
    if result.config:
        result.config = provenance_header(config) + result.config
    return result


LOAD_BLAME_PERIODS = 10
"""A run diverging within this many control periods after a load starts blames the load."""


def _numbers(value) -> str:
    """A number or a list of them, each to 3 significant digits: ``[1e+09, 0, 0]``."""
    values = np.atleast_1d(np.asarray(value, dtype=float))
    text = ", ".join(f"{v:.3g}" for v in values)
    return text if np.ndim(value) == 0 else f"[{text}]"


def _load_just_before(config: ExperimentConfig, end: float) -> str:
    """The ``[[plant.loads]]`` entry that started at most :data:`LOAD_BLAME_PERIODS` control
    periods before ``end`` (the run's last time), described with its size; "" if none did.
    """
    period = config.simulation.control_period
    for i, entry in reversed(list(enumerate(config.plant.loads or ()))):
        start = float(entry["time"])
        if not 0.0 <= end - start <= LOAD_BLAME_PERIODS * period:
            continue
        kind = entry["kind"]
        keys = LOAD_KEYS[kind]
        sizes = [(key, f"{_numbers(entry[key])} {LOAD_UNITS[key]}") for key in keys if key in entry]
        size = sizes[0][1] if len(keys) == 1 else " and ".join(f"{key} {text}" for key, text in sizes)
        ago = round((end - start) / period)
        periods = f"{ago} control period{'' if ago == 1 else 's'}"
        when = "as it started" if ago < 1 else f"{periods} after it started"
        return f"plant.loads[{i}], the {kind} of {size} at t = {start:g} s: the run diverged {when}"
    return ""


def likely_cause(setup: Setup, trace) -> str:
    """A guess at why a run diverged, from its last finite state (for the divergence message)."""
    finite = np.flatnonzero(np.all(np.isfinite(trace.q), axis=1) & np.all(np.isfinite(trace.dq), axis=1))
    q = trace.q[finite[-1]] if finite.size else setup.q0
    robot, config, names = setup.robot, setup.config, setup.robot.joint_names
    if setup.criterion is not None and config.controller.k > 0:
        grad = config.controller.k * np.abs(setup.criterion.gradient(robot, q))
        i = int(np.argmax(grad))
        if grad[i] > 1e3:
            return (
                f"likely cause: an exploding criterion gradient (k dh/dq = {grad[i]:.3g} on joint "
                f"{names[i]!r}); lower controller.k or check subtasks.criteria"
            )
    effort, bad = robot.effort_limits, implausible_efforts(robot)
    if np.any(bad) and setup.plant.torque_limit is not None:
        i = int(np.flatnonzero(bad)[np.argmax(effort[bad])])
        return (
            f"likely cause: an implausible effort limit ({effort[i]:.3g} on joint {names[i]!r}, over "
            f"{PLAUSIBLE_EFFORT_RATIO:g}x what the arm needs), so torque saturation does not bound the "
            "command; set plant.torque_limits or the URDF's effort"
        )
    last = trace.tau_cmd[-1] if trace.tau_cmd.size else np.zeros(0)
    if finite.size == len(trace.t) and not np.all(np.isfinite(last)):
        return (
            f"cause: {type(setup.controller).__name__}.compute returned a non-finite torque "
            f"{last.tolist()} from a finite state (check the law's gains, divisions and state)"
        )
    load = _load_just_before(config, float(trace.t[-1]) if len(trace.t) else 0.0)
    if load:
        return f"likely cause: {load}"
    if setup.plant.torque_limit is None:
        peak = float(np.nanmax(np.abs(trace.tau_cmd))) if trace.tau_cmd.size else float("nan")
        return (
            f"likely cause: the commanded torque grew without bound (peak {peak:.3g} N m) with no "
            "actuator limits (plant.torque_limits = 'none')"
        )
    return "likely cause: the closed loop is unstable for these gains and this model error"


def compare_twins(config, cpp: str, python: str, params: dict | None = None) -> dict:
    """The twin test of a law given in C++ and in Python (docs/extending.md#a-law-in-c): the
    experiment ``config`` (an ExperimentConfig) run with ``controller.class = cpp``
    ("file.cpp:Class", on the compiled loop) and with ``python`` ("file.py:Class", on the hybrid
    loop), both with ``params`` (default: the experiment's ``controller.params``). Returns the
    largest differences over the run: ``tau_cmd`` (over the largest commanded torque, at least
    1), ``q`` [rad or m], and each signal both declare (over its largest magnitude, at least 1),
    with each run's backend and status. Twins agree to rounding (1e-9 here for
    examples/controllers/task_pd.cpp and examples/custom_controller.py).
    """
    runs = []
    for cls in (cpp, python):
        controller: dict = {"kind": "custom", "class": cls}
        if params is not None:
            controller["params"] = params
        runs.append(run_experiment(config.replace(controller=controller)))
    ours, theirs = runs
    if ours.tau_cmd is None or theirs.tau_cmd is None or ours.tau_cmd.shape != theirs.tau_cmd.shape:
        raise NNRobustError(
            f"the twins' runs differ in length ({ours.status}: {len(ours.t)} steps; {theirs.status}: "
            f"{len(theirs.t)} steps)"
        )

    def relative(a, b) -> float:
        return float(np.max(np.abs(a - b), initial=0.0) / max(1.0, float(np.max(np.abs(b), initial=0.0))))

    return {
        "backends": (ours.backend, theirs.backend),
        "statuses": (ours.status, theirs.status),
        "tau_cmd": relative(ours.tau_cmd, theirs.tau_cmd),
        "q": float(np.max(np.abs(ours.q - theirs.q), initial=0.0)),
        "signals": {
            name: relative(np.asarray(ours.signals[name]), np.asarray(theirs.signals[name]))
            for name in ours.signals.keys() & theirs.signals.keys()
        },
    }
