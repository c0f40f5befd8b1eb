"""The compiled backend: the extension module ``nnrobust._loop`` (C++ against Pinocchio, built
during ``pip install`` when a C++ compiler is there; docs/compiled.md).

The package works without it: :func:`available` says whether it loaded and :func:`unavailable_reason`
why not, and everything else runs on the Python reference implementation.
"""

from __future__ import annotations

import contextlib
import importlib

import pinocchio as pin

from ..core.exceptions import ControllerError, NNRobustError

_MODULE = None
_REASON = ""


def _load():
    global _MODULE, _REASON
    if _MODULE is None and not _REASON:
        try:
            _MODULE = importlib.import_module("nnrobust._loop")
        except ImportError as err:
            _REASON = (
                f"the compiled loop is not built ({err}); reinstall nnrobust with a C++ compiler "
                "(g++ and cmake) to build it"
            )
    return _MODULE


def _module():
    """The extension module, or one clear error saying why it is missing."""
    module = _load()
    if module is None:
        raise NNRobustError(_REASON)
    return module


def available() -> bool:
    """Whether the compiled extension loaded."""
    return _load() is not None


def unavailable_reason() -> str:
    """Why the compiled extension is not available ("" when it is)."""
    _load()
    return _REASON


COMPILED_JOINTS = frozenset(
    f"JointModel{kind}"
    for kind in (
        "RX", "RY", "RZ", "PX", "PY", "PZ", "RUBX", "RUBY", "RUBZ",
        "RevoluteUnaligned", "PrismaticUnaligned", "RevoluteUnboundedUnaligned",
    )
)  # fmt: skip
"""Joint types the C++ side rebuilds (csrc/model/model.cpp): every joint of a fixed-base arm's URDF."""


def model_spec(model: pin.Model, frame: str):
    """A Pinocchio model as the numbers its dynamics and kinematics read (joint types, parents,
    placements, inertias, armature, gravity, the task frame): the C++ side rebuilds exactly this
    model from them (csrc/model/model.cpp).
    """
    import numpy as np

    spec = _module().ModelSpec()
    joints = range(1, model.njoints)
    kinds = [model.joints[j].shortname() for j in joints]
    unknown = sorted(set(kinds) - COMPILED_JOINTS)
    if unknown:
        raise NNRobustError(f"a joint of type {unknown[0]} has no compiled twin")
    spec.joint_types, spec.joint_names = kinds, [model.names[j] for j in joints]
    spec.parents = [int(model.parents[j]) for j in joints]
    axes = [getattr(model.joints[j].extract(), "axis", np.zeros(3)) for j in joints]
    spec.axes = np.array(axes, dtype=float).reshape(-1, 3)
    placements = [model.jointPlacements[j] for j in joints]
    spec.rotations = np.vstack([p.rotation for p in placements]).reshape(-1, 3)
    spec.translations = np.array([p.translation for p in placements], dtype=float).reshape(-1, 3)
    inertias = [model.inertias[j] for j in joints]
    spec.inertias = np.array(
        [[i.mass, *i.lever, *np.asarray(i.inertia).ravel()] for i in inertias], dtype=float
    ).reshape(-1, 13)
    spec.armature = np.asarray(model.armature, dtype=float)
    spec.gravity = np.asarray(model.gravity.linear, dtype=float)
    task = model.frames[model.getFrameId(frame)]
    spec.frame_name, spec.frame_joint = frame, int(task.parentJoint)
    spec.frame_rotation, spec.frame_translation = task.placement.rotation, task.placement.translation
    return spec


def load_model(model: pin.Model, frame: str):
    """The C++ copy of a Pinocchio model (exactly this model, rebuilt from :func:`model_spec`),
    with ``frame`` as its task frame.
    """
    return _module().LoadedModel(model_spec(model, frame))


def torque_regressor_of(model: pin.Model):
    """A function (q, q', q'') of N samples -> Y, N x n x 10 n, in one C++ call per batch
    (csrc/model/regressor.hpp): the twin of :func:`nnrobust.model.regressor.torque_regressor`,
    for identification's rows. None when the compiled loop is not built or the model has a joint
    it has no twin of.
    """
    import numpy as np

    joints = (model.joints[j].shortname() for j in range(1, model.njoints))
    if not available() or any(kind not in COMPILED_JOINTS for kind in joints):
        return None
    loaded = load_model(model, model.frames[model.nframes - 1].name)
    regressor = _module().torque_regressor

    def rows(q, v, a):
        q, v, a = (np.ascontiguousarray(x, dtype=float).reshape(len(q), -1) for x in (q, v, a))
        return regressor(loaded, q, v, a).reshape(len(q), model.nv, -1)

    return rows


# ---- the compiled closed loop ---------------------------------------------------------------------


def twin_refusal(setup) -> str:
    """Why this experiment has no compiled twin ("" when it has one).

    The compiled loop covers (docs/compiled.md) every component whose class declares a compiled
    twin (``twin`` and ``twin_fields``): the eq. (9) law (no u_0, the NN compensator with either
    basis, the sliding-mode term; computed torque), the task-space PD and the registered laws;
    the closed-form three-link nominal model or any Pinocchio nominal model (perturbed or
    exact); planar, position and pose tasks; the shipped paths and the pose trajectory over any
    of them; every shipped criterion (paper, half_det_manipulability and manipulability not on
    pose tasks); and the whole plant (friction, sinusoidal disturbance, saturation, stops,
    sensor noise, quantisation, delay), integrated by RK4.
    """
    return _plant_refusal(setup) or law_refusal(setup)


def law_refusal(setup) -> str:
    """Why this experiment's controller (its law, robust term, nominal model, path and criteria)
    has no compiled twin ("" when it has one): the part of :func:`twin_refusal` an exported law
    needs (nnrobust.outputs.export).
    """
    from ..controllers.registry import registered_law
    from ..trajectories import PoseTrajectory

    if not available():
        return unavailable_reason()
    config, controller = setup.config, setup.controller
    refusal = _criterion_refusal(setup)
    if refusal:
        return refusal
    law = registered_law(config.controller.kind)
    if law is None and is_custom(controller) and not getattr(type(controller), "native", None):
        return f"a custom controller ({type(controller).__name__}) runs in Python: --backend hybrid or python"
    path = setup.trajectory.path if type(setup.trajectory) is PoseTrajectory else setup.trajectory
    term = getattr(controller, "compensator", None)
    checks = [
        (
            (law.twin if law is not None else own_twin(controller)) is not None,
            f"controller.kind {config.controller.kind!r}",
        ),
        (own_twin(setup.nominal) is not None, "the nominal model"),
        (own_twin(path) is not None, "the trajectory"),
        (law is not None or term is None or own_twin(term) is not None, "a custom robust term"),
    ]
    for ok, what in checks:
        if not ok:
            return f"{what} has no compiled twin yet"
    return ""


def own_twin(component) -> str | None:
    """The compiled twin a component's own class declares (``twin``; a subclass that does not
    declare one has none), or None.
    """
    return type(component).__dict__.get("twin")


def twin_source(holder):
    """The C++ file a class or a kind's declaration names as its twin's (``twin_source``: a kind
    declared outside nnrobust, docs/extending.md#a-twin-in-c), or None: the twin is shipped. A
    class's own declaration only, as :func:`own_twin`.
    """
    return (
        holder.__dict__.get("twin_source")
        if isinstance(holder, type)
        else getattr(holder, "twin_source", None)
    )


def _registered(holder, concept: str, name: str | None) -> str | None:
    """``name``, the twin of ``holder`` (a class or a kind's declaration), registered: the C++ file
    it declares as its ``twin_source`` is compiled (unless cached) and loaded first.
    """
    source = twin_source(holder)
    if source is not None and name is not None:
        from ..plugins.native_law import load_twin_source

        owner = holder.__name__ if isinstance(holder, type) else f"the {concept} kind {holder.name!r}"
        load_twin_source(source, concept, name, owner)
    return name


def _twin_holders(setup) -> list:
    """The classes and declarations whose twins the controller's spec names (law_spec's parts)."""
    from ..controllers.registry import registered_law
    from ..trajectories import PoseTrajectory

    path = setup.trajectory.path if isinstance(setup.trajectory, PoseTrajectory) else setup.trajectory
    law = registered_law(setup.config.controller.kind)
    term = getattr(setup.controller, "compensator", None)
    criteria = setup.criterion.criteria if setup.criterion is not None else []
    holders = [type(path), law if law is not None else type(setup.controller), *map(_twin_of, criteria)]
    return holders + ([type(term)] if law is None and term is not None else [])


def is_custom(controller) -> bool:
    """Whether a controller is a user's class (not one of nnrobust's own laws)."""
    return not type(controller).__module__.startswith("nnrobust.")


def _plant_refusal(setup) -> str:
    """Why the compiled plant cannot simulate this experiment ("" when it can): the part of
    :func:`twin_refusal` that the hybrid loop needs too (plant, integrator, task, criterion).
    """
    if not available():
        return unavailable_reason()
    config = setup.config
    kinds = {j.shortname() for j in setup.plant.model.pinocchio_model.joints[1:]}
    checks = [
        (kinds <= COMPILED_JOINTS, f"a joint of type {min(kinds - COMPILED_JOINTS, default='')}"),
        (own_twin(setup.plant.disturbance) is not None, "a custom disturbance"),
        (config.simulation.integrator == "rk4", f"the integrator {config.simulation.integrator!r}"),
        (setup.plant.friction.smoothing <= 0, "a smoothed plant friction"),
    ]
    for ok, what in checks:
        if not ok:
            return f"{what} has no compiled twin yet"
    return _criterion_refusal(setup)


def _criterion_refusal(setup) -> str:
    """Why the task or the weighted criterion has no compiled twin ("" when both have one)."""
    from ..subtasks import WeightedCriteria

    criterion = setup.criterion
    checks = [
        (setup.robot.task in ("planar", "position", "pose"), f"a {setup.robot.task!r} task"),
        (
            criterion is None
            or (
                isinstance(criterion, WeightedCriteria)
                and all(_twin_of(c) is not None for c in criterion.criteria)
            ),
            "a criterion",
        ),
        (
            criterion is None
            or setup.robot.task != "pose"
            or not any((kind := _twin_of(c)) is not None and kind.det for c in criterion.criteria),
            "a manipulability criterion on a pose task",
        ),
    ]
    for ok, what in checks:
        if not ok:
            return f"{what} has no compiled twin yet"
    return ""


def hybrid_refusal(setup) -> str:
    """Why the hybrid loop (compiled plant, Python controller) cannot run this experiment ("" when
    it can).
    """
    return _plant_refusal(setup)


def _twin_of(criterion):
    """The declaration of a shipped criterion with a compiled twin (None for a user's)."""
    from ..subtasks import kind_of

    kind = kind_of(criterion)
    return kind if kind is not None and kind.twin_fields is not None else None


def _criterion_spec(s, setup, f) -> None:
    """The weighted criterion of the experiment into the spec (h is recorded on the true robot):
    each criterion's name and the fields its declaration gives its twin.
    """
    criterion = setup.criterion
    if criterion is None:
        return
    kinds = [_twin_of(c) for c in criterion.criteria]
    s.criteria = [_registered(kind, "criterion", kind.name) for kind in kinds]
    s.criterion_params = [kind.twin_values(c) for kind, c in zip(kinds, criterion.criteria)]
    s.criterion_weights = f(criterion.weights)


def engine_addresses(engine) -> dict:
    """MuJoCo's addresses (MujocoPlant.addresses) as its compiled twin reads them: each a whole
    number, exact as a float64 below 2^53 (a user-space address is below 2^48).
    """
    from ..core.twins import field_array

    where = engine.addresses()
    for name, address in where.items():
        if not 0 < address < 2**53:
            raise NNRobustError(f"plant.engine: MuJoCo's {name} address {address:#x} does not fit a float64")
    return {name: field_array(float(address)) for name, address in where.items()}


def contiguous(x):
    """``x`` as the C++ side takes an array: contiguous float64."""
    import numpy as np

    return np.ascontiguousarray(x, dtype=float)


def loop_spec(setup, duration: float, external: bool = False):
    """The compiled loop's description of a built experiment (every array it needs); with
    ``external``, of its plant alone (the hybrid loop: the controller is called in Python).
    """
    from ..config import step_rotation_limit
    from ..core.twins import twin_parts, twin_values
    from .simulation import MAX_PERIOD_SUBSTEPS, MAX_SPEED

    f = contiguous
    module = _module()
    sim, plant, controller = setup.config.simulation, setup.plant, setup.controller
    steps = int(round(duration / sim.control_period))
    s = module.LoopSpec()
    s.period, s.substeps, s.steps, s.max_speed = sim.control_period, setup.substeps, steps, MAX_SPEED
    s.max_step_rotation, s.max_period_substeps = step_rotation_limit(setup.config), MAX_PERIOD_SUBSTEPS
    s.q0, s.v0 = f(setup.q0), f(setup.v0)
    s.plant_params, parts = twin_values(plant, plant.twin_fields), twin_parts(plant)
    parts["sensor"].update(plant.sensor.twin_draws(steps))  # the run's draws from the seed
    if plant.engine is not None:  # MuJoCo steps the plant, from (q0, v0)
        plant.engine.reset(setup.q0, setup.v0)
        parts["engine"].update(engine_addresses(plant.engine))
    s.plant_parts = parts
    s.disturbance = _registered(type(plant.disturbance), "disturbance", own_twin(plant.disturbance))
    s.m = setup.robot.m
    _criterion_spec(s, setup, f)
    if external:  # the hybrid loop: the law is Python's, only its state size matters here
        s.law = "external"
        s.z0 = f(controller.initial_state())
        return s
    _law_spec(s, setup, f)
    return s


def _law_spec(s, setup, f) -> None:
    """The controller into the spec: its nominal model, desired motion, pseudo-inverse, friction
    estimate, law (with its robust term) and initial state.
    """
    from ..controllers.registry import registered_law
    from ..core.twins import twin_values
    from ..model import ThreeLinkPlanarModel
    from ..plant.friction import Friction
    from ..trajectories import PoseTrajectory

    plant, controller = setup.plant, setup.controller
    nominal = setup.nominal
    s.nominal = nominal.twin
    if isinstance(nominal, ThreeLinkPlanarModel):
        s.nominal_params = twin_values(nominal.params, nominal.params.twin_fields)
    path = setup.trajectory
    if isinstance(path, PoseTrajectory):
        s.pose, s.pose_params = True, twin_values(path, path.twin_fields)
        path = path.path
    s.path, s.path_params = _registered(type(path), "path", path.twin), twin_values(path, path.twin_fields)
    # the law's own pseudo-inverse and F-hat, else the experiment's (a registered law's class may
    # keep only its context, as a custom controller does)
    context = setup.controller_context
    pinv = getattr(controller, "pinv", None) or context.pseudo_inverse
    s.pinv_threshold, s.pinv_max_damping = pinv.threshold, pinv.max_damping
    friction = (
        getattr(controller, "nominal_friction", None)
        or (context.nominal_friction if context is not None else None)
        or Friction.none(plant.nq)
    )
    s.nominal_friction = twin_values(friction, friction.twin_fields)
    law = registered_law(setup.config.controller.kind)
    if law is not None:  # a registered law's twin and its declared fields
        s.law, s.law_params = _registered(law, "law", law.twin), law.twin_values(controller)
    else:  # one of the task-space laws (eq. 9 or the PD), with eq. (9)'s robust term
        s.law = _registered(type(controller), "law", controller.twin)
        s.law_params = twin_values(controller, controller.twin_fields)
        term = getattr(controller, "compensator", None)
        if term is not None:
            s.robust = _registered(type(term), "robust term", term.twin)
            s.robust_params = twin_values(term, term.twin_fields)
    s.law_signals = len(controller.signal_names)
    s.z0 = f(controller.initial_state())


def law_spec(setup):
    """The compiled controller of a built experiment alone, as an exported law runs it
    (nnrobust.outputs.export): (LoopSpec with the controller's and criteria's fields, the nominal
    Pinocchio model's ModelSpec or None for the closed form). Refused without a twin.
    """
    from ..controllers.registry import registered_law

    custom = registered_law(setup.config.controller.kind) is None and is_custom(setup.controller)
    if custom and not getattr(type(setup.controller), "native", None):
        raise NNRobustError(
            f"this controller cannot be exported: a custom controller ({type(setup.controller).__name__}) "
            "is Python code, with no C++ twin to export"
        )
    if is_policy(setup.controller):  # before law_refusal: its message would say "no twin yet"
        raise NNRobustError(
            "this controller cannot be exported: a learned policy (controller.kind = 'policy') is an "
            "ONNX network run by onnxruntime, with no C++ twin; export its base law "
            f"({setup.controller.base_kind}) and run the network beside it"
        )
    refusal = law_refusal(setup)
    if refusal:
        raise NNRobustError(f"this controller cannot be exported: {refusal}")
    apart = [twin_source(h) for h in _twin_holders(setup) if twin_source(h) is not None]
    if apart:
        raise NNRobustError(
            f"this controller cannot be exported: its twin in {apart[0]} is compiled apart, and an "
            "export carries the shipped twins and a law in C++ only"
        )

    f = contiguous
    s = _module().LoopSpec()
    s.period, s.m = setup.config.simulation.control_period, setup.robot.m
    _criterion_spec(s, setup, f)
    _law_spec(s, setup, f)
    model = model_spec(setup.nominal.model, setup.nominal.task_frame) if s.nominal == "pinocchio" else None
    return s, model


def _prepared(setup, duration: float):
    """(plant model, nominal model or None, spec) of a built experiment, refused without a twin."""
    refusal = twin_refusal(setup)
    if refusal:
        raise NNRobustError(f"simulation.backend = 'compiled': {refusal}")
    spec = loop_spec(setup, duration)
    plant = load_model(setup.plant.model.pinocchio_model, setup.robot.task_frame)
    nominal = (
        load_model(setup.nominal.model, setup.nominal.task_frame) if spec.nominal == "pinocchio" else None
    )
    return plant, nominal, spec


def _trace(setup, spec, out):
    """The Trace of a finished compiled run (what simulation.simulate returns)."""
    import numpy as np

    from ..core.signals import clear_interrupt
    from .simulation import Trace, speed_message

    done, period = out.done, setup.config.simulation.control_period
    t = np.arange(done) * period
    signals = {}  # the law's, in its signal_names order (the hybrid loop records its own)
    if spec.law != "external":
        names = setup.controller.signal_names
        signals = {name: np.asarray(out.signals)[:done, i] for i, name in enumerate(names)}
    message = ""
    if out.status == "diverged":
        k = out.divergence_index
        engine = setup.plant.engine  # MuJoCo, which resets a bad state it finds
        if out.divergence_joint < 0:
            failure = engine.failure(t[k]) if engine is not None else ""
            message = failure or f"non-finite state or torque at t = {t[k]:.4f} s"
        else:
            message = speed_message(setup.plant.model, np.asarray(out.dq)[k], spec.max_speed, t[k])
    elif out.status == "interrupted":
        message = f"interrupted at t = {done * period:.4f} s"
        clear_interrupt()
    z = np.asarray(out.z)[:done] if spec.z0.size else np.zeros((done, 0))
    n = setup.plant.nq
    recorded = {
        "chain": np.asarray(out.chain)[:done].reshape(done, n + 1, 3),
        "manipulability": np.asarray(out.manipulability)[:done],
        "h": np.asarray(out.h)[:done],
    }
    return Trace(
        t,
        np.asarray(out.q)[:done],
        np.asarray(out.dq)[:done],
        np.asarray(out.tau)[:done],
        np.asarray(out.tau_cmd)[:done],
        z,
        signals,
        out.status,
        message,
        recorded,
        out.friction_events,
        out.unresolved_events,
        out.refined_periods,
    )


def simulate_compiled(setup, duration: float):
    """Run a built experiment on the compiled loop; returns the same Trace as simulation.simulate."""
    from ..core.signals import check_interrupt

    check_interrupt()
    plant, nominal, spec = _prepared(setup, duration)
    with _user_law_errors():
        out = _module().run_loop(plant, spec, nominal)
    return _trace(setup, spec, out)


def allocation_counter() -> str:
    """The path of the allocation counter built with the extension
    (``benchmarks/allocation_counter.cpp``), to preload (``LD_PRELOAD``) in a process that
    :func:`profile_compiled` should count allocations in; "" where it was not built (not Linux).
    """
    from pathlib import Path

    path = Path(_module().__file__).with_name("libnnrobust_allocation_counter.so")
    return str(path) if path.exists() else ""


def profile_compiled(setup, duration: float) -> tuple[dict, object]:
    """One compiled run with its step's parts timed (``LoopSpec.profile``): ``{part: (µs per
    step, system-allocator calls per step)}`` for each of the loop's parts (``nnrobust._loop.
    LOOP_PARTS``: law, bookkeeping, record, plant, measure), and the run's Trace. The calls are
    None unless :func:`allocation_counter` is preloaded in this process
    (``benchmarks/loop_profile.py`` does it). The run is the unprofiled run's, bit for bit.
    """
    import math

    from ..core.signals import check_interrupt

    check_interrupt()
    plant, nominal, spec = _prepared(setup, duration)
    spec.profile = True
    with _user_law_errors():
        out = _module().run_loop(plant, spec, nominal)
    steps = max(out.done, 1)
    parts = {
        name: (1e6 * seconds / steps, None if math.isnan(calls) else calls / steps)
        for name, seconds, calls in zip(_module().LOOP_PARTS, out.part_seconds, out.part_allocations)
    }
    return parts, _trace(setup, spec, out)


@contextlib.contextmanager
def _user_law_errors():
    """A law compiled apart that throws, returns arrays of the wrong size or misses a parameter
    (nnrobust._loop.UserLawError, its message naming the law and its file) is a ControllerError,
    as a Python law's is.
    """
    try:
        yield
    except _module().UserLawError as err:
        raise ControllerError(str(err)) from None


class _HybridLaw:
    """A Python controller as the hybrid loop calls it: law(t, q, v, z) -> (tau, z_next), with its
    signals recorded here and the contract checked as simulation.simulate checks it.
    """

    def __init__(self, controller, steps: int, n: int, period: float):
        import numpy as np

        from ..controllers import custom

        self.controller, self.n, self.period, self.k = controller, n, period, 0
        self.signals = {name: np.full(steps, np.nan) for name in controller.signal_names}
        self._custom, self._asarray = custom, np.asarray

    def __call__(self, t, q, v, z):
        """(tau, z_next) at t, or None when the run is interrupted."""
        controller, k = self.controller, self.k
        try:
            out = controller.compute(t, q, v, z, self.period)
        except KeyboardInterrupt:  # Ctrl-C, SIGTERM: the run stops, marked interrupted, and keeps its steps
            return None
        except (Exception, SystemExit) as err:  # a law may not end the process
            if isinstance(err, NNRobustError):
                raise
            raise self._custom.failed(controller, err, t) from err
        # checked at every step (a list of ints is a valid torque: the loop is given float64)
        tau, given, state = self._custom.checked_output(controller, out, self.n, z.size, t)
        signals = self.signals
        for name, value in given.items():
            signals[name][k] = value
        self.k = k + 1
        return tau, z if state is None else state


def simulate_hybrid(setup, duration: float):
    """Run a built experiment whose controller is Python's on the compiled plant (the hybrid
    loop): the same Trace as simulation.simulate, the controller called once per period.
    """
    from ..core.signals import check_interrupt

    check_interrupt()
    refusal = hybrid_refusal(setup)
    if refusal:
        raise NNRobustError(f"simulation.backend = 'hybrid': {refusal}")
    spec = loop_spec(setup, duration, external=True)
    plant = load_model(setup.plant.model.pinocchio_model, setup.robot.task_frame)
    law = _HybridLaw(setup.controller, spec.steps, setup.plant.nq, spec.period)
    trace = _trace(setup, spec, _module().run_hybrid(plant, spec, law))
    trace.signals = {name: values[: trace.t.size] for name, values in law.signals.items()}
    return trace


def stepped_loop(setup, duration: float):
    """A built experiment's compiled loop one control period at a time, with its compiled law
    (the learning environment's: nnrobust.studies.learning); returns (SteppedLoop, LoopSpec).
    """
    plant, nominal, spec = _prepared(setup, duration)
    return _module().SteppedLoop(plant, nominal, spec, True), spec


def stepped_trace(setup, spec, loop):
    """The Trace of a SteppedLoop's run so far (what simulation.simulate returns); call once."""
    return _trace(setup, spec, loop.finish())


def is_policy(controller) -> bool:
    """Whether a controller is a learned policy (``controller.kind = "policy"``)."""
    from ..controllers.laws.policy import PolicyLaw

    return isinstance(controller, PolicyLaw)


def simulate_policy(setup, duration: float):
    """Run a built experiment whose law is a learned policy on the compiled loop: its base law's
    loop driven one period at a time (the observation and the base law's command in C++, the
    policy's inference in Python; the Python loop's PolicyLaw is the reference). The same Trace
    as simulation.simulate, with the signal ``inference_time`` [s].
    """
    import dataclasses

    import numpy as np

    from ..core.signals import check_interrupt

    policy = setup.controller
    config = setup.config.replace(controller={"kind": policy.base_kind, "params": None})
    base = dataclasses.replace(setup, config=config, controller=policy.base)
    refusal = twin_refusal(base)
    if refusal:
        raise NNRobustError(f"simulation.backend = 'hybrid': the policy's base law: {refusal}")
    loop, spec = stepped_loop(base, duration)
    mode, scale, network = policy.mode, np.asarray(policy.scale, dtype=float), policy.policy
    obs = np.empty(policy.layout.size)
    run = network.on_buffer(obs)
    seconds = np.full(spec.steps, np.nan)
    observe, act = loop.observe_into, loop.act_action
    k, going = 0, loop.running
    try:
        while going:  # the observation, the clip and the scaling in C++: only the network here
            check_interrupt()
            observe(obs)
            a = run(k * spec.period)
            seconds[k] = network.seconds
            status = act(a, scale, mode)
            if status < 0:
                raise ControllerError(network.non_finite(a, loop.time))
            going = status > 0
            k += 1
    except KeyboardInterrupt:
        loop.end("interrupted")
    trace = _trace(base, spec, loop.finish())
    trace.signals["inference_time"] = seconds[: trace.t.size]
    return trace


def simulate_batch(setups: list, durations: list[float] | None = None, threads: int | None = None) -> list:
    """Run several built experiments on the compiled loop, on C++ threads with the GIL released
    (default: one per core); returns their Traces in order. Each run has its own copy of its
    models and records only its own arrays, whose size build() bounded (simulation.memory_limit).
    Ctrl-C and SIGTERM stop every run; each keeps what it computed, marked ``interrupted``.
    """
    import os

    from ..core.signals import check_interrupt

    check_interrupt()
    durations = durations or [s.config.simulation.duration for s in setups]
    if len(durations) != len(setups):
        raise NNRobustError(f"simulate_batch: {len(setups)} experiments but {len(durations)} durations")
    prepared = [_prepared(setup, duration) for setup, duration in zip(setups, durations)]
    plants, nominals, specs = (list(column) for column in zip(*prepared)) if prepared else ([], [], [])
    with _user_law_errors():
        outs = _module().run_batch(plants, nominals, specs, threads or os.cpu_count() or 1)
    return [_trace(setup, spec, out) for setup, spec, out in zip(setups, specs, outs)]
