"""The true robot: rigid-body dynamics, friction, disturbance, actuator limits, stops and sensors."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from ..model.base import DynamicsModel
from ..model.pinocchio_model import PinocchioModel
from .disturbance import Disturbance
from .friction import Friction
from .limits import JointStops, available_torque, saturate
from .loads import ExternalLoads, HeldLoads
from .mujoco_engine import MujocoPlant
from .sensing import Sensor


@dataclass
class Plant:
    """M(q) q'' + V_m q' + G + F(q') + tau_d(t) = sat(tau_cmd) + tau_stop(q, q'), eq. (7) made real.

    The controller's command tau_cmd is clipped to the actuators' effort limits (``torque_limit``),
    at speed to their torque-speed envelope where one is set (``torque_speed_knee`` >= 0), and
    reaches the arm ``delay`` control periods after the measurement it was computed from; the hard
    joint-limit stops push back beyond the position limits; the controller sees the state through
    ``sensor``.

    Attributes:
        model: the true dynamics (normally Pinocchio, from the URDF).
        friction: the true friction F(q').
        disturbance: the external disturbance tau_d(t).
        torque_limit: effort limit per joint [N m or N] (inf: unlimited); None: ideal actuators.
        speed_limit: the velocity limit per joint that the torque-speed envelope falls to zero at
            [rad/s or m/s] (inf: none); None: no envelope.
        torque_speed_knee: the envelope's knee, a fraction of ``speed_limit`` in [0, 1) below
            which the full effort is available (:func:`~nnrobust.plant.limits.available_torque`);
            -1: no envelope.
        stops: hard joint-limit stops; None: the arm passes through its limits.
        sensor: what the controller measures (default exact).
        delay: control periods between a measurement and the torque computed from it (>= 0).
        engine: MuJoCo, when it integrates the plant (built by the experiment).
        loads: torque steps and impulses, a tool wrench, payload changes (``[[plant.loads]]``),
            held over each control period from :meth:`begin_period`.
        payload_inertias: for each payload change of ``loads`` in order, the inertia of the
            joint that carries the task frame with that payload; the last entry is that joint's
            inertia before any change (a Pinocchio model, copied for the plant alone).

    """

    model: DynamicsModel
    friction: Friction
    disturbance: Disturbance
    torque_limit: np.ndarray | None = None
    stops: JointStops | None = None
    sensor: Sensor | None = field(default=None)
    delay: int = 0
    engine: MujocoPlant | None = field(default=None, repr=False)
    """A second engine that integrates the plant instead (``plant.engine = "mujoco"``,
    :mod:`nnrobust.plant.mujoco_engine`); None: this class's dynamics, integrated by the loop."""
    loads: ExternalLoads | None = None
    payload_inertias: tuple = field(default=(), repr=False)
    speed_limit: np.ndarray | None = None
    torque_speed_knee: float = -1.0
    sticky: np.ndarray = field(init=False, repr=False)
    """Joints with dry friction that holds them at rest (F_s > 0): integrated as stick-slip."""

    twin_fields = (
        "effort_limit",
        "delay",
        "payload_joint",
        "payload_parameters",
        "envelope_speed_limit",
        "torque_speed_knee",
    )
    """What its compiled twin reads (csrc/plant/plant.hpp) beside its parts'."""
    twin_parts = ("friction", "disturbance", "loads", "sensor", "stops", "engine")
    """Its parts with a compiled twin (csrc/plant/, each part's ``twin_fields``; None: absent)."""

    def __post_init__(self):
        n = self.model.nq
        if self.sensor is None:
            self.sensor = Sensor.ideal(n)
        if self.torque_limit is not None:
            self.torque_limit = np.asarray(self.torque_limit, dtype=float)
        sizes = [
            ("friction.viscous", self.friction.viscous.size),
            ("friction.coulomb", self.friction.coulomb.size),
            ("disturbance", np.size(self.disturbance(0.0))),
            ("sensor", self.sensor.position_noise.size),
        ]
        if self.torque_limit is not None:
            sizes.append(("torque_limit", self.torque_limit.size))
            if np.any(~(self.torque_limit > 0)):
                raise ValueError(f"plant: torque limits must be > 0, got {self.torque_limit.tolist()}")
        if self.stops is not None:
            sizes.append(("stops", self.stops.stiffness.size))
        if self.speed_limit is not None:
            self.speed_limit = np.asarray(self.speed_limit, dtype=float)
            sizes.append(("speed_limit", self.speed_limit.size))
            if np.any(~(self.speed_limit > 0)):
                raise ValueError(f"plant: speed limits must be > 0, got {self.speed_limit.tolist()}")
        if not (self.torque_speed_knee == -1.0 or 0.0 <= self.torque_speed_knee < 1.0):
            raise ValueError(
                f"plant: torque_speed_knee must be in [0, 1) or -1 (none), got {self.torque_speed_knee}"
            )
        for name, size in sizes:
            if size != n:
                raise ValueError(f"plant: {name} has {size} entries, the robot has {n} joints")
        if self.delay < 0:
            raise ValueError(f"plant: delay must be >= 0 control periods, got {self.delay}")
        self.sticky = (self.friction.static > 0) & (self.friction.smoothing <= 0)
        if self.loads is None:
            self.loads = ExternalLoads(n)
        self.held: HeldLoads = self.loads.at(0.0)
        self._carried: int | None = None  # payload changes whose inertia the model holds
        if self.loads.wrenches or self.loads.payloads:
            if not isinstance(self.model, PinocchioModel):
                raise ValueError("plant.loads: a wrench or a payload change needs a Pinocchio model")
            self._pin = self.model
            self._payload_joint = self.model.model.frames[self.model.frame_id].parentJoint
            if self.loads.payloads and len(self.payload_inertias) != len(self.loads.payloads) + 1:
                raise ValueError(
                    "plant: payload_inertias needs one inertia per payload change and one without"
                )

    def begin_period(self, t: float) -> None:
        """Hold the loads of the control period that starts at t [s] (:mod:`.loads`): the joint
        torque and wrench that act over it, and the payload the task frame carries during it.
        """
        loads = self.loads
        assert loads is not None  # __post_init__ sets an empty one
        held = loads.at(t)
        if loads.payloads:
            carried = sum(c.start <= t for c in loads.payloads)  # changes so far (sorted)
            if carried != self._carried:  # set when it changes, not every period
                inertia = self.payload_inertias[carried - 1]  # [-1]: none yet
                self._pin.model.inertias[self._payload_joint] = inertia
                self._carried = carried
        self.held = held

    def load_torque(self, q: np.ndarray) -> np.ndarray:
        """The held loads' torque on the joints, u + J(q)^T w [N m]."""
        held = self.held
        if held.wrench is None:
            return held.torque
        m = self._pin
        J = pin.computeFrameJacobian(m.model, m.data, q, m.frame_id, pin.LOCAL_WORLD_ALIGNED)
        return held.torque + J.T @ held.wrench

    @property
    def effort_limit(self) -> np.ndarray:
        """The actuators' torque limits [N m or N]: ``torque_limit``, inf for ideal actuators."""
        return np.full(self.nq, np.inf) if self.torque_limit is None else self.torque_limit

    @property
    def payload_joint(self) -> int:
        """The joint whose inertia a payload change sets (the task frame's; 0 without changes)."""
        return self._payload_joint if self.loads and self.loads.payloads else 0

    @property
    def payload_parameters(self) -> np.ndarray:
        """``payload_inertias`` as dynamic parameters (pin.Inertia.toDynamicParameters), one
        column each: 10 x (C + 1), the last before any change (10 x 0 without changes).
        """
        columns = [i.toDynamicParameters() for i in self.payload_inertias]
        return np.array(columns, dtype=float).T.reshape(10, -1)

    @property
    def nq(self) -> int:
        """Number of joints n."""
        return self.model.nq

    @property
    def envelope_speed_limit(self) -> np.ndarray:
        """``speed_limit``, inf for a plant without a torque-speed envelope [rad/s or m/s]."""
        return np.full(self.nq, np.inf) if self.speed_limit is None else self.speed_limit

    def available_torque(self, tau_cmd: np.ndarray, v: np.ndarray) -> np.ndarray:
        """What the actuators can give in the direction of ``tau_cmd`` at the joint speeds ``v``:
        the effort limit, cut by the torque-speed envelope while driving [N m or N].
        """
        return available_torque(
            self.effort_limit, tau_cmd, v, self.envelope_speed_limit, self.torque_speed_knee
        )

    def applied_torque(self, tau_cmd: np.ndarray, v: np.ndarray | None = None) -> np.ndarray:
        """The actuators' torque for the command at the joint speeds ``v`` (the true ones at the
        control instant): saturated at the effort limits and, where set, the torque-speed
        envelope [N m]; ``v`` None: at rest.
        """
        if self.torque_limit is None:
            return tau_cmd
        if self.torque_speed_knee < 0.0 or v is None:
            return saturate(tau_cmd, self.torque_limit)
        return saturate(tau_cmd, self.available_torque(tau_cmd, v))

    def acceleration(self, t: float, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Q'' = M^-1 (tau + tau_stop - V_m q' - G - F(q') - tau_d(t)), by ABA for Pinocchio models.

        ``tau`` is the applied (already saturated) actuator torque. This is the slipping law with
        sgn(0) = 0: :meth:`net_torque` with every joint's mode sgn(q'_i).
        """
        return self.model.forward_dynamics(q, v, self.net_torque(t, q, v, tau, np.sign(v).astype(int)))

    def net_torque(
        self,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        tau: np.ndarray,
        mode: np.ndarray,
    ) -> np.ndarray:
        """The torque on the arm but its own dynamics, tau + tau_stop - tau_d - F + the held
        loads (:meth:`load_torque`) [N m].

        A sticky joint's dry friction is F_c mode_i (0 where it is held).
        """
        fr = self.friction
        friction = np.where(self.sticky, fr.viscous * v + fr.coulomb * mode, fr.torque(v))
        net = tau - friction - self.disturbance(t)
        if self.loads:
            net = net + self.load_torque(q)
        if self.stops is not None:
            net = net + self.stops.torque(q, v)
        return net

    def constrained_acceleration(
        self, t: float, q: np.ndarray, v: np.ndarray, tau: np.ndarray, mode: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(q'', f_held) with the friction modes held (:mod:`nnrobust.plant.stick_slip`).

        A sticky joint slips with F_c mode_i (mode +-1) or is held (mode 0: q''_i = 0); f_held is
        the friction torque holding the held joints, in joint order [N m]. Without held joints
        q'' comes from ABA; with them, M_RR q''_R = r_R and f_S = r_S - M_SR q''_R.
        """
        held = self.sticky & (mode == 0)
        net = self.net_torque(t, q, v, tau, mode)
        if not held.any():
            return self.model.forward_dynamics(q, v, net), np.zeros(0)
        M = self.model.mass(q)
        r = net - self.model.bias(q, v)
        free = ~held
        a = np.zeros_like(r)
        if free.any():
            a[free] = np.linalg.solve(M[np.ix_(free, free)], r[free])
        return a, r[held] - M[held] @ a

    def energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """Kinetic plus potential energy, including the stops' springs [J]."""
        stored = self.stops.potential(q) if self.stops is not None else 0.0
        return self.model.kinetic_energy(q, v) + self.model.potential_energy(q) + stored
