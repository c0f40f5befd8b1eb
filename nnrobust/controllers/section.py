"""The controllers room's sections of an experiment file: ``[controller]`` and ``[nn]``, their
defaults read from the kinds' declarations (:mod:`nnrobust.controllers.registry`). Their builder:
:func:`nnrobust.controllers.build.build_controller`. Imported by the package face after every
kind is declared.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from ..core.exceptions import ConfigError
from ..core.key_checks import DeclaredKeys, check_choice
from .registry import (
    PAPER_KINDS,
    controller_kinds,
    declared_default,
    declared_params,
    paper_kinds,
    registered_law,
)


@dataclass
class ControllerConfig(DeclaredKeys):
    """Which control law and its gains.

    Attributes:
        kind: ``nn`` (eq. 9 with the NN compensator), ``no-u0`` (eq. 9 with u_0 = 0),
            ``computed-torque`` (eq. 9 with u_0 = 0 and the true model and friction as nominal:
            what perfect model knowledge buys), ``sliding-mode`` (eq. 9 with a fixed-gain
            boundary-layer sliding-mode u_0) or ``pd``.
        Kp, Kv, k, coulomb_smoothing: eq. (9)'s gains [1/s^2, 1/s] (m entries or one for all;
            Kv^2 > Kp is required by eq. (17)), self-motion gain [1/s] and F-hat's sign smoothing
            [rad/s], as nnrobust/controllers/task_space.py declares them.
        pinv_threshold, pinv_max_damping: the damped pseudo-inverse's [m/rad], as
            nnrobust/controllers/pseudoinverse.py declares them.
        pd_Kp, pd_Kd, pd_null_damping: the PD baseline's, as ``pd`` declares them
            (nnrobust/controllers/task_space.py).
        sliding_gain, sliding_boundary: the sliding-mode u_0's, as ``sliding-mode`` declares them
            (nnrobust/controllers/sliding_mode.py). docs/controller.md's key reference lists every
            declared key with its unit, default and valid values.
        class_: for ``kind = "custom"``, the controller class (TOML key ``class``):
            ``"file.py:Class"`` (a path relative to the experiment file) or ``"package.module:Class"``,
            a subclass of :class:`nnrobust.Controller` (docs/extending.md).
        params: for ``kind = "custom"``, the keyword arguments of the class's constructor (TOML
            table ``[controller.params]``).

    """

    kind: str = "nn"
    Kp: list[float] = field(default_factory=lambda: declared_default("controller.Kp"))
    Kv: list[float] = field(default_factory=lambda: declared_default("controller.Kv"))
    k: float = declared_default("controller.k")
    pinv_threshold: float = declared_default("controller.pinv_threshold")
    pinv_max_damping: float = declared_default("controller.pinv_max_damping")
    pd_Kp: list[float] = field(default_factory=lambda: declared_default("controller.pd_Kp"))
    pd_Kd: list[float] = field(default_factory=lambda: declared_default("controller.pd_Kd"))
    pd_null_damping: float | None = declared_default("controller.pd_null_damping")
    coulomb_smoothing: float = declared_default("controller.coulomb_smoothing")
    sliding_gain: float = declared_default("controller.sliding_gain")
    sliding_boundary: float = declared_default("controller.sliding_boundary")
    class_: str | None = None
    params: dict | None = None
    SECTION: ClassVar[str] = "controller"

    @classmethod
    def kind_params(cls):
        """The keys the paper's kinds and the keys they share declare."""
        return declared_params()


CONTROLLER_KINDS = paper_kinds()
"""The paper's kinds, the built-in values of ``controller.kind`` set by flat keys, as their modules
declare them (:class:`nnrobust.controllers.registry.PaperKind`), when nnrobust was imported; the
registered laws (:func:`controller_kinds`) take ``[controller.params]``, and ``custom`` names a
user's class (``controller.class``)."""


EQ9_KINDS = tuple(name for name, kind in PAPER_KINDS.items() if kind.eq9)
"""The kinds that are the task-space law of eq. (9), whose Kp and Kv eq. (17) constrains (when
nnrobust was imported; :func:`is_eq9` asks the declarations)."""


def is_eq9(kind: str) -> bool:
    """Whether ``controller.kind`` is one of the paper's kinds that is eq. (9)'s law."""
    declared = PAPER_KINDS.get(kind)
    return declared is not None and declared.eq9


def needs_lyapunov(kind: str) -> bool:
    """Whether ``controller.kind``'s robust term is built on eq. (16)'s P: Kv^2 > Kp (eq. 17)."""
    declared = PAPER_KINDS.get(kind)
    return declared is not None and declared.lyapunov


@dataclass
class NNConfig(DeclaredKeys):
    """The NN robust compensator, eqs. (15)-(17): its keys, their units, defaults and ranges as
    the ``nn`` kind declares them (nnrobust/controllers/nn_compensator.py; docs/controller.md's
    key reference).
    """

    law: str = declared_default("nn.law")
    F: float = declared_default("nn.F")
    gamma: float = declared_default("nn.gamma")
    eps0: float = declared_default("nn.eps0")
    eps_min: float = declared_default("nn.eps_min")
    sigma: float = declared_default("nn.sigma")
    basis_input: str = declared_default("nn.basis_input")
    centers: int = declared_default("nn.centers")
    width: float = declared_default("nn.width")
    bias: bool = declared_default("nn.bias")
    velocity_range: float = declared_default("nn.velocity_range")
    error_range: list[float] = field(default_factory=lambda: declared_default("nn.error_range"))
    SECTION: ClassVar[str] = "nn"

    @classmethod
    def kind_params(cls):
        """The keys the paper's kinds declare."""
        return declared_params()


GAIN_KEYS = ("Kp", "Kv", "pd_Kp", "pd_Kd")
"""The controller's task gains that take one value for all m coordinates or one per coordinate."""


def full_gain(values: list[float], m: int) -> list[float]:
    """A task gain as m entries: one value repeated for every task coordinate, or as given."""
    return list(values) * m if len(values) == 1 else list(values)


def check_controller(c: ControllerConfig, nn: NNConfig, m: int, where: str) -> None:
    """The rules that read only ``[controller]`` and ``[nn]``, for a task of ``m`` coordinates
    (``where`` says where m comes from, for messages): the kind, the gains' sizes, every declared
    key against its declaration, eq. (17)'s Kv^2 > Kp where the robust term is built on P, the NN's
    floor. A law's
    ``[controller.params]`` are checked with the user's classes. Changes nothing.
    """
    check_choice("controller.kind", c.kind, controller_kinds())
    for name in GAIN_KEYS:
        values = getattr(c, name)
        if len(values) not in (1, m):
            raise ConfigError(
                f"controller.{name}", f"has {len(values)} entries, {where} (or give one value for all)"
            )
    sections = {"controller": c, "nn": nn}
    for p in declared_params():  # each kind's own keys, eq. (9)'s and the pseudo-inverse's
        section, field = p.name.split(".")
        value = getattr(sections[section], field)
        if not (value is None and p.default is None):  # unset: the kind sizes it itself
            p.check(value, None, m, p.name)
    pairs = zip(full_gain(c.Kp, m), full_gain(c.Kv, m))
    for kp, kv in pairs if needs_lyapunov(c.kind) else ():  # the laws whose u_0 is built on P
        if kv * kv <= kp:
            raise ConfigError(
                "controller.Kv",
                f"Kv^2 = {kv * kv:g} must exceed Kp = {kp:g}: Q = diag(2 Kp^2, 2 Kv^2 - 2 Kp) of "
                "eq. (17) must be positive definite for the Lyapunov function y^T P y to decrease",
            )
    if nn.eps_min > nn.eps0:
        raise ConfigError("nn.eps_min", f"the floor {nn.eps_min} must not exceed nn.eps0 = {nn.eps0}")


def inert_controller_keys(c: ControllerConfig, nn: NNConfig) -> dict[str, str]:
    """The keys the controller's kind does not read (``section.key``, or ``section.`` for a whole
    section), each with the choice that makes it so: eq. (9)'s gains under another law, the other
    kinds' own keys, what a kind declares it ignores (:class:`PaperKind`), the NN basis range
    its input does not use.
    """
    inert: dict[str, str] = {}

    def mark(keys, why):
        for key in keys:
            inert.setdefault(key, why)

    kind = f"controller.kind = {c.kind!r}"
    if registered_law(c.kind) is not None:  # its own parameters; it may read subtasks and nominal
        mark(["controller.Kp", "controller.Kv", "controller.k"], f"{kind} is not eq. (9)")
    elif not is_eq9(c.kind):
        mark(["controller.Kp", "controller.Kv", "controller.k", "subtasks."], f"{kind} is not eq. (9)")
        mark(["controller.coulomb_smoothing", "nominal.viscous_friction", "nominal.coulomb_friction"], kind)
    own = PAPER_KINDS[c.kind].keys if c.kind in PAPER_KINDS else ()
    for declared in PAPER_KINDS.values():  # the other kinds' own keys, unless this one reads them
        mark([key for key in declared.keys if key not in own], kind)
    for key, why in PAPER_KINDS[c.kind].ignores if c.kind in PAPER_KINDS else ():
        mark([key], why)
    if c.kind == "custom":
        mark(["controller.pinv_threshold", "controller.pinv_max_damping"], kind)
    if is_eq9(c.kind) and c.k == 0:
        mark(["subtasks."], "controller.k = 0 (no self-motion)")
    if c.kind == "nn" and nn.basis_input == "joint":
        mark(["nn.error_range"], "nn.basis_input = 'joint'")
    if c.kind == "nn" and nn.basis_input == "error":
        mark(["nn.velocity_range"], "nn.basis_input = 'error'")
    return inert
