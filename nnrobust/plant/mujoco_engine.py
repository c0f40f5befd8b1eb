"""MuJoCo as a second, independent true plant (``plant.engine = "mujoco"``, docs/engines.md).

The MuJoCo model is built by MuJoCo's own URDF importer from the same resolved URDF that
Pinocchio parsed (visual and collision geometry set aside: the dynamics need no mesh), then
completed through MjSpec with what the importer does not make:

- one motor per actuated joint, in the controller's joint order, its force range the effort
  limit (the loop saturates the command first, so the range only restates it);
- the joints that Pinocchio's model locks deleted (held at zero, as ``robot.locked_joints``);
- viscous friction as joint ``damping`` and Coulomb friction as ``frictionloss`` (MuJoCo's soft
  dry-friction constraint, not sgn(q'): a joint held below its level creeps), with the stiffest
  time constant MuJoCo advises at a 1 ms step (:data:`CONSTRAINT_TIME_CONSTANT`);
- the joint limits as MuJoCo limit constraints when ``plant.joint_stops`` is on (a soft
  constraint with time constant 1/omega of the stop's ring frequency, at least
  :data:`CONSTRAINT_TIME_CONSTANT`);
- ``plant.armature`` on the diagonal of M (Pinocchio's true model gets the same);
- the timestep equal to the plant step, the integrator ``plant.mujoco_integrator``, Pinocchio's
  gravity, and no contacts.

The disturbance tau_d(t) enters as ``qfrc_applied`` = -tau_d at the middle of each step.

Before a run is trusted its compiled model is audited (:func:`audit`): M(q), the bias
V_m(q, q') q' + G(q) and G(q) of MuJoCo against Pinocchio's at random states; a model that
differs by more than :data:`AUDIT_TOLERANCE` is refused with the term and the joint named.

A state that blows up does not reach the loop as NaN: MuJoCo answers a non-finite or huge
position, velocity or acceleration with a warning and resets the state to the model's q = 0, and
a huge torque command by applying none. Both loops read those warnings after every step and end
the run there as diverged (:meth:`MujocoPlant.failure`), as the Pinocchio plant's non-finite
state does.
"""

from __future__ import annotations

import ctypes
import functools
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core.exceptions import ConfigError, ModelMismatch, RobotLoadError

ENGINES = ("pinocchio", "mujoco")
"""The true plant's physics engines (``plant.engine``)."""

MUJOCO_INTEGRATORS = ("rk4", "implicitfast", "euler", "implicit")
"""MuJoCo's integrators (``plant.mujoco_integrator``). RK4, the default, is fourth order like this
package's plant and converged at its step; the others are first order (implicitfast is MuJoCo's
own advice) and at 1 ms they break laws tuned to the sampling limit (docs/engines.md)."""

CONSTRAINT_TIME_CONSTANT = 2e-3
"""Time constant [s] of MuJoCo's frictionloss and limit constraints, at least (and at least two
plant steps, MuJoCo's stability advice). Fixed, so that a finer step converges to the same
model. MuJoCo's default, 0.02 s, lets a joint held below its Coulomb level creep ten times
faster (docs/engines.md)."""


BAD_STATE_WARNINGS = {
    "mjWARN_BADQPOS": ("position", "resets the state to q = 0"),
    "mjWARN_BADQVEL": ("velocity", "resets the state to q = 0"),
    "mjWARN_BADQACC": ("acceleration", "resets the state to q = 0"),
    "mjWARN_BADCTRL": ("control", "applies zero torque instead"),
}
"""MuJoCo's warnings on a value non-finite or above its mjMAXVAL (1e10): what it found bad and
what it does then, which would go on silently from a state or a torque other than the loop's."""


def constraint_time_constant(h: float) -> float:
    """The constraints' time constant at the plant step ``h`` [s]."""
    return max(CONSTRAINT_TIME_CONSTANT, 2.0 * h)


AUDIT_TOLERANCE = 1e-8
"""Largest relative difference of M, bias or gravity between the engines that a run accepts."""

AUDIT_STATES = 16
"""Random states (q within the joint ranges, q' within +-2 rad/s) of the load-time audit."""

AUDIT_TERMS = ("mass_matrix", "bias", "gravity")

INSTALL_HINT = "plant.engine = 'mujoco' needs MuJoCo: pip install 'nnrobust[mujoco]'"


def import_mujoco():
    """The ``mujoco`` module, or one ConfigError that says which extra installs it."""
    try:
        import mujoco  # here: MuJoCo, an optional engine
    except ImportError as err:
        raise ConfigError("plant.engine", f"{INSTALL_HINT} ({err})") from None
    return mujoco


def mujoco_version() -> str:
    """MuJoCo's version ("" when it is not installed)."""
    try:
        import mujoco  # here: MuJoCo, an optional engine
    except ImportError:
        return ""
    return str(mujoco.__version__)


def dynamics_only(text: str) -> str:
    """The URDF without its visual and collision geometry (no mesh is needed for the dynamics)."""
    root = ET.fromstring(text)
    for link in root.iter("link"):
        for child in list(link):
            if child.tag in ("visual", "collision"):
                link.remove(child)
    for extra in [e for e in root if e.tag in ("gazebo", "transmission", "mujoco")]:
        root.remove(extra)
    return ET.tostring(root, encoding="unicode")


@dataclass
class MujocoPlant:
    """A compiled MuJoCo model of the true robot and its state, stepped one control period at a time.

    Attributes:
        model, data: MuJoCo's ``MjModel`` and ``MjData``.
        qpos_index, dof_index: where joint i of the controller's order sits in qpos and qvel.
        substeps: MuJoCo steps per control period (its timestep is the plant step).
        audit: the worst relative difference of each term (:func:`audit`).

    """

    model: Any
    data: Any
    qpos_index: np.ndarray
    dof_index: np.ndarray
    disturbance: Any
    substeps: int
    integrator: str
    audit: dict[str, float] = field(default_factory=dict)

    twin_fields = ("qpos_index", "dof_index", "substeps")
    """What its compiled twin reads (csrc/plant/mujoco_engine.hpp), beside :meth:`addresses`."""

    def reset(self, q0: np.ndarray, v0: np.ndarray) -> None:
        """Start a run at (q0, q'0): MuJoCo's state reset, then set (warm starts cleared)."""
        mujoco = import_mujoco()
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self.qpos_index] = q0
        self.data.qvel[self.dof_index] = v0
        mujoco.mj_forward(self.model, self.data)

    def advance(
        self, t: float, tau: np.ndarray, period: float, load: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(q, q') after one control period with the applied torque ``tau`` and the joint torque
        ``load`` of ``[[plant.loads]]`` held.
        """
        mujoco = import_mujoco()
        d, h = self.data, period / self.substeps
        d.ctrl[:] = tau
        warned, bad = d.warning.number, _bad_state_warnings()
        for i in range(self.substeps):
            d.qfrc_applied[self.dof_index] = -self.disturbance(t + (i + 0.5) * h)
            if load is not None:
                d.qfrc_applied[self.dof_index] += load
            mujoco.mj_step(self.model, d)
            if any(warned[w] for w in bad):  # MuJoCo reset the state or zeroed tau: the run ends
                break
        return d.qpos[self.qpos_index].copy(), d.qvel[self.dof_index].copy()

    def failure(self, t: float) -> str:
        """Why the run cannot go on ("" when it can): a bad state or command MuJoCo warned of since
        :meth:`reset` (:data:`BAD_STATE_WARNINGS`), with the joint, for a run stopped in the
        control period from ``t`` [s].
        """
        warned = self.data.warning
        counts = warned.number
        for w, (name, (what, then)) in zip(_bad_state_warnings(), BAD_STATE_WARNINGS.items()):
            if counts[w]:
                return (
                    f"MuJoCo's bad {what} ({name}: non-finite or above 1e10 at joint "
                    f"{self._joint_of(what, int(warned.lastinfo[w]))!r}) at t = {t:.4f} s; MuJoCo "
                    f"{then}, so the run ends here"
                )
        return ""

    def _joint_of(self, what: str, index: int) -> str:
        """The joint of the qpos address, dof or actuator that MuJoCo's warning names."""
        m = self.model
        if what == "position":
            joints = np.flatnonzero(m.jnt_qposadr == index)
        elif what == "control":
            joints = m.actuator_trnid[index : index + 1, 0] if 0 <= index < m.nu else []
        else:
            joints = m.dof_jntid[index : index + 1] if 0 <= index < m.nv else []
        return m.joint(int(joints[0])).name if len(joints) else "?"

    def addresses(self) -> dict[str, int]:
        """Raw addresses for the compiled loop, which calls MuJoCo's ``mj_step`` itself: the
        function (from the library the ``mujoco`` module loaded), the model, the data, and the
        qpos, qvel, ctrl and qfrc_applied arrays inside the data (they live as long as it does),
        and the counts of the warnings on which MuJoCo resets the state (:data:`BAD_STATE_WARNINGS`).
        """
        mujoco = import_mujoco()
        folder = Path(mujoco.__file__).parent
        libraries = (
            sorted(folder.glob("libmujoco.so*"))
            + sorted(folder.glob("libmujoco*.dylib"))
            + sorted(folder.glob("mujoco.dll"))
        )
        if not libraries:
            raise ConfigError(
                "plant.engine",
                f"MuJoCo's C library is not in {folder}; the compiled loop "
                "cannot call it (simulation.backend = 'python' can)",
            )
        step = ctypes.cast(ctypes.CDLL(str(libraries[0])).mj_step, ctypes.c_void_p).value
        d = self.data
        counts = d.warning.number  # a strided view of mjData's warning[i].number
        warned = {
            f"warned_{what}": counts.ctypes.data + w * counts.strides[0]
            for w, (what, _) in zip(_bad_state_warnings(), BAD_STATE_WARNINGS.values())
        }
        return {
            "step": int(step or 0),
            "model": int(self.model._address),
            "data": int(d._address),
            "qpos": d.qpos.ctypes.data,
            "qvel": d.qvel.ctypes.data,
            "ctrl": d.ctrl.ctypes.data,
            "qfrc_applied": d.qfrc_applied.ctypes.data,
            **warned,
        }


@functools.cache
def _bad_state_warnings() -> tuple[int, ...]:
    """The indices in mjData's warning array of :data:`BAD_STATE_WARNINGS`, in its order."""
    mujoco = import_mujoco()
    return tuple(int(getattr(mujoco.mjtWarning, name)) for name in BAD_STATE_WARNINGS)


def _spec(mujoco, robot, name: str):
    text = getattr(robot, "urdf_text", None)
    if text is None:
        raise ConfigError(
            "plant.engine",
            f"{name} is built by example-robot-data's own code, not from one URDF "
            "file; MuJoCo imports URDF files (choose a robot with a URDF, or the pinocchio engine)",
        )
    try:
        return mujoco.MjSpec.from_string(dynamics_only(text))
    except Exception as err:  # MuJoCo raises ValueError with its parser's message
        raise RobotLoadError(name, f"MuJoCo's URDF importer refused it: {err}") from err


def build_mujoco_plant(
    robot,
    plant,
    period: float,
    substeps: int,
    integrator: str = "rk4",
    armature: np.ndarray | None = None,
    stiction: float = 1.0,
    payload: tuple | None = None,
) -> MujocoPlant:
    """The MuJoCo model of ``plant`` (a :class:`~nnrobust.plant.Plant` on the Pinocchio model
    ``robot``), compiled and audited; refused with the reason named where the engines would not
    simulate the same arm. ``payload``: (joint name, pin.Inertia in that joint's frame), a body
    added to the one the joint moves (``plant.payload``).
    """
    mujoco = import_mujoco()
    if integrator not in MUJOCO_INTEGRATORS:
        raise ConfigError(
            "plant.mujoco_integrator", f"{integrator!r} is not one of {', '.join(MUJOCO_INTEGRATORS)}"
        )
    if stiction != 1.0:
        raise ConfigError(
            "plant.stiction",
            f"MuJoCo's frictionloss has one level (static = Coulomb); got "
            f"{stiction}: set it to 1 with plant.engine = 'mujoco'",
        )
    name, n = robot.name, robot.nq
    spec = _spec(mujoco, robot, name)
    keep = list(robot.joint_names)
    joints = {j.name: j for j in spec.joints}
    missing = [j for j in keep if j not in joints]
    if missing:
        raise ModelMismatch(
            f"{name}: MuJoCo's URDF importer made no joint {missing}; its joints: {sorted(joints)}"
        )
    locked = {jname for jname in joints if jname not in keep}
    for equality in list(spec.equalities):  # the importer's <mimic> couplings of locked joints
        if {equality.name1, equality.name2} & locked:
            spec.delete(equality)
    for jname in locked:  # locked by Pinocchio's reduced model, at zero
        spec.delete(joints[jname])
    pin_model = robot.pinocchio_model
    arm = np.zeros(n) if armature is None else np.asarray(armature, float)
    M_inv = np.linalg.inv(robot.mass(robot.mid_configuration))
    h = period / substeps
    for i, jname in enumerate(keep):
        joint = joints[jname]
        joint.damping = [float(plant.friction.viscous[i]), 0.0, 0.0]  # a, b, c of a v + b v|v| + c v^3
        joint.frictionloss = float(plant.friction.coulomb[i])
        joint.solref_friction = [constraint_time_constant(h), 1.0]
        joint.armature = float(arm[i])
        joint.stiffness = [0.0, 0.0, 0.0]
        stops = plant.stops
        bounded = stops is not None and np.isfinite(stops.lower[i]) and np.isfinite(stops.upper[i])
        joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE if bounded else mujoco.mjtLimited.mjLIMITED_FALSE
        if bounded:
            joint.range = [float(stops.lower[i]), float(stops.upper[i])]
            omega = np.sqrt(stops.stiffness[i] * M_inv[i, i])
            joint.solref_limit = [max(1.0 / omega, constraint_time_constant(h)), 1.0]
        motor = spec.add_actuator(name=f"motor_{jname}", target=jname, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        motor.gainprm[0] = 1.0
        limit = np.inf if plant.torque_limit is None else float(plant.torque_limit[i])
        motor.forcelimited = (
            mujoco.mjtLimited.mjLIMITED_TRUE if np.isfinite(limit) else mujoco.mjtLimited.mjLIMITED_FALSE
        )
        if np.isfinite(limit):
            motor.forcerange = [-limit, limit]
    if payload is not None:
        jname, inertia = payload
        body = joints[jname].parent  # the body the joint moves
        # at the joint's frame, its centre of mass at the lever (MuJoCo fuses it into the body)
        body.add_body(
            name="nnrobust_payload",
            pos=[0.0, 0.0, 0.0],
            ipos=np.asarray(inertia.lever, float),
            mass=float(inertia.mass),
            inertia=np.diag(inertia.inertia).astype(float),
            explicitinertial=True,
        )
    spec.option.timestep = h
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    spec.option.gravity = np.asarray(pin_model.gravity.linear, float)
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    try:
        model = spec.compile()
    except Exception as err:
        raise RobotLoadError(name, f"MuJoCo cannot compile the model: {err}") from err
    qpos = np.array([model.jnt_qposadr[model.joint(j).id] for j in keep])
    dofs = np.array([model.jnt_dofadr[model.joint(j).id] for j in keep])
    engine = MujocoPlant(model, mujoco.MjData(model), qpos, dofs, plant.disturbance, substeps, integrator)
    if model.nv != n or model.nu != n:
        raise ModelMismatch(
            f"{name}: MuJoCo's model has {model.nv} degrees of freedom and {model.nu} motors, "
            f"Pinocchio's {n} joints"
        )
    engine.audit = audit(engine, robot)
    return engine


def _random_states(robot, count: int, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    low, high = robot.lower_limits, robot.upper_limits
    low = np.where(np.isfinite(low), low, -np.pi)
    high = np.where(np.isfinite(high), high, np.pi)
    return [(rng.uniform(low, high), rng.uniform(-2.0, 2.0, robot.nq)) for _ in range(count)]


def engine_terms(engine: MujocoPlant, q: np.ndarray, v: np.ndarray) -> dict[str, np.ndarray]:
    """MuJoCo's M(q), bias (q_frc_bias: V_m q' + G) and G(q), in the controller's joint order."""
    mujoco = import_mujoco()
    m, d = engine.model, mujoco.MjData(engine.model)
    d.qpos[engine.qpos_index] = q
    d.qvel[engine.dof_index] = v
    mujoco.mj_forward(m, d)
    full = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, full)
    dofs = engine.dof_index
    terms = {"mass_matrix": full[np.ix_(dofs, dofs)], "bias": d.qfrc_bias[dofs].copy()}
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    terms["gravity"] = d.qfrc_bias[dofs].copy()
    return terms


def _differences(mj: dict[str, np.ndarray], pn: dict[str, np.ndarray]) -> dict[str, tuple[float, int]]:
    """Per term: (relative difference, the joint where it is largest).

    M: |dM_ij| / sqrt(M_ii M_jj) (scale-free, so a light wrist counts as much as the shoulder);
    bias and gravity: |d_i| / max |term| (the vector's own scale; floored at 1e-9 N m).
    """
    M = pn["mass_matrix"]
    scale = np.sqrt(np.outer(np.diag(M), np.diag(M)))
    dM = np.abs(mj["mass_matrix"] - M) / scale
    out = {"mass_matrix": (float(dM.max()), int(np.unravel_index(np.argmax(dM), dM.shape)[0]))}
    for term in ("bias", "gravity"):
        diff = np.abs(mj[term] - pn[term])
        out[term] = (float(diff.max() / max(np.abs(pn[term]).max(), 1e-9)), int(np.argmax(diff)))
    return out


def audit(
    engine: MujocoPlant, robot, tolerance: float = AUDIT_TOLERANCE, states: int = AUDIT_STATES
) -> dict[str, float]:
    """Compare MuJoCo's compiled model with Pinocchio's at random states; the worst relative
    difference of each term, or ModelMismatch naming the term, the joint and its body where one
    exceeds ``tolerance``.
    """
    worst = dict.fromkeys(AUDIT_TERMS, 0.0)
    for q, v in _random_states(robot, states):
        pn = {"mass_matrix": robot.mass(q), "bias": robot.bias(q, v), "gravity": robot.gravity(q)}
        for term, (diff, joint) in _differences(engine_terms(engine, q, v), pn).items():
            worst[term] = max(worst[term], diff)
            if not diff <= tolerance:
                name = robot.joint_names[joint]
                body = engine.model.body(engine.model.jnt_bodyid[engine.model.joint(name).id]).name
                raise ModelMismatch(
                    f"{robot.name}: MuJoCo's model differs from Pinocchio's in the "
                    f"{term.replace('_', ' ')} by {diff:.3g} (relative, tolerance {tolerance:g}) at joint "
                    f"{name!r} (link {body!r}): its "
                    "URDF importer read the inertial data differently; the run is refused "
                    "(docs/engines.md)"
                )
    return worst
