"""A learned policy as a control law (``controller.kind = "policy"``; docs/learning.md).

At each control instant the policy maps the observation of :mod:`nnrobust.controllers.observation`
(the measured q, q', the desired motion and the task error on the nominal model) to an action
a ∈ [-1, 1]^n, exactly as the learning environment gives it:

- ``action = "torque"``: τ = clip(a, -1, 1) ⊙ τ_max;
- ``action = "residual"``: τ = τ_base + s · clip(a, -1, 1) ⊙ τ_max, with τ_base the command of
  the ``base`` law (eq. 9 with or without u_0, the PD, any shipped law) built as the experiment
  builds that kind, and s = ``residual_scale``;
- ``action = "gains"``: a ∈ [-1, 1]^2 and τ is the ``base`` law's command with its position and
  velocity gains (K_p and K_v of eq. 9, K_p and K_d of the PD) multiplied by G^clip(a_0) and
  G^clip(a_1) for the period, G = ``gain_range``. The robust term's own numbers (the NN's P of
  eq. 16) stay those of the law's own gains.

The policy is an ONNX file run by onnxruntime on the CPU (one thread). Its one input takes the
observation ([d] or [batch, d], float32 or float64) and its first output gives a ([n] or
[batch, n]); a file whose shapes do not match the arm, that is not a model, or that needs an
operator onnxruntime cannot run is refused in one line naming the file. The run records the
file's SHA-256 (config.toml's provenance) and each step's inference time (signal
``inference_time``: the call's wall time, as a real-time loop sees it, preemption included).

With the compiled loop available, a run of this law is a compiled run of its base law driven one
period at a time (``SteppedLoop``): the observation and the base law's command are computed in
C++, only the inference in Python (nnrobust/run/compiled.py, ``simulate_policy``). This module is
its Python reference (the Python loop), and tests/controllers/test_policy.py holds the two equal.
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

import numpy as np

from ...core.exceptions import ConfigError, ControllerError
from ...core.shipped_files import local
from ..base import Controller, ControllerContext, ControlOutput
from ..observation import ObservationLayout, observation
from ..registry import Law, LawParam, register_law, registered_law, shipped_laws

ACTIONS = ("torque", "residual", "gains")
"""The action modes, in the order of the compiled loop's ActionMode (csrc/learning.hpp)."""
GAIN_ACTIONS = 2
"""The size of a ``gains`` action: the factors' exponents on the position and velocity gains."""


def action_scale(action: str, limits, residual_scale: float, gain_range: float) -> np.ndarray:
    """What a clipped action a ∈ [-1, 1] is multiplied by: τ_max (``torque``), s · τ_max
    (``residual``), or ln G for each of the two exponents (``gains``: a factor exp(a ln G) = G^a).
    The law and the learning environment (nnrobust.studies.learning.env) share it.
    """
    if action == "gains":
        return np.full(GAIN_ACTIONS, math.log(gain_range))
    return np.asarray(limits, dtype=float) * (residual_scale if action == "residual" else 1.0)


def base_laws() -> tuple[str, ...]:
    """The laws a policy can act on: every shipped law (the registry's) but those that read a
    file of their own (a policy, a designed excitation's joint-space law): the base is built with
    the experiment's settings alone.
    """

    def own_file(name: str) -> bool:
        law = registered_law(name)
        return law is not None and any(p.path for p in law.params)

    return tuple(name for name in shipped_laws() if not own_file(name))


def policy_params(params: dict | None) -> dict:
    """A policy entry's ``params`` with every parameter the law declares, at its default where the
    entry leaves it out (action ``torque``, base ``pd``, ...): what the law will be built with.
    """
    return {p.name: (params or {}).get(p.name, p.default) for p in LAW.params}


def no_gains(kind: str) -> str:
    """Why a law of ``kind`` cannot be the base of a gains action."""
    return (
        f"{kind!r} has no position and velocity gains an action can set; in gains mode the base law is "
        "an eq. (9) law (nn, no-u0, sliding-mode, computed-torque, rbf-nn) or pd"
    )


def _session(path: Path):
    """An onnxruntime session on one CPU thread, or one line naming the file and what is wrong.
    A file the running task brought with it is read from its copy
    (:func:`nnrobust.core.shipped_files.local`), still named by ``path``.
    """
    try:
        import onnxruntime as ort  # here: onnxruntime, the policy extra
    except ImportError as err:
        raise ConfigError(
            "controller.params.file", "a policy runs on onnxruntime: pip install 'nnrobust[learning]'"
        ) from err
    options = ort.SessionOptions()
    options.intra_op_num_threads = options.inter_op_num_threads = 1
    options.log_severity_level = 3  # errors only: a refusal below says what is wrong
    try:
        return ort.InferenceSession(
            str(local(path)), sess_options=options, providers=["CPUExecutionProvider"]
        )
    except Exception as err:  # onnxruntime's own errors: not a model, an unknown operator, ...
        said = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise ConfigError(
            "controller.params.file", f"{path} is not an ONNX model onnxruntime can run ({said[:300]})"
        ) from err


def _free(dim) -> bool:
    """Whether an ONNX dimension is symbolic ("batch", "d") or unknown: fixed only at run time."""
    return dim is None or isinstance(dim, str)


def _fits(shape, size: int) -> bool:
    """Whether an ONNX shape is [size] or [batch, size] (a free batch dimension, or 1), a symbolic
    length standing for any size (checked by a trial run: :class:`OnnxPolicy`).
    """
    dims = list(shape or [])
    if len(dims) == 2:
        batch, last = dims
        return (batch == 1 or _free(batch)) and (last == size or _free(last))
    return len(dims) == 1 and (dims[0] == size or _free(dims[0]))


class OnnxPolicy:
    """An ONNX file as a function observation (d entries) -> action (n entries), checked."""

    def __init__(self, file: str | Path, d: int, n: int, entries: str = "one entry per joint"):

        path = Path(file)
        if not local(path).is_file():
            raise ConfigError("controller.params.file", f"{str(file)!r} is not a file")
        self.path, self.d, self.n = path, d, n
        self.session = _session(path)
        inputs, outputs = self.session.get_inputs(), self.session.get_outputs()
        if len(inputs) != 1:
            names = ", ".join(i.name for i in inputs)
            raise ConfigError(
                "controller.params.file", f"{path} takes {len(inputs)} inputs ({names}); a policy takes one"
            )
        given, out = inputs[0], outputs[0]
        types = {"tensor(float)": np.float32, "tensor(double)": np.float64}
        if given.type not in types or not _fits(given.shape, d):
            raise ConfigError(
                "controller.params.file",
                f"{path}: its input {given.name!r} is {given.type} {given.shape}; the observation is "
                f"float32 or float64 [{d}] or [batch, {d}] (docs/learning.md#observation)",
            )
        if out.type not in types or not _fits(out.shape, n):
            raise ConfigError(
                "controller.params.file",
                f"{path}: its output {out.name!r} is {out.type} {out.shape}; the action is [{n}] or "
                f"[batch, {n}] ({entries})",
            )
        self.input, self.dtype = given.name, types[given.type]
        self.batched = len(given.shape) == 2
        self.output = out.name
        self.seconds = 0.0  # the last call's wall time, as a real-time loop would see it (the
        # thread's CPU time costs a system call of microseconds a step on this kind of machine)
        if any(_free(d) for d in [*given.shape[-1:], *out.shape[-1:]]):  # a symbolic length: try it
            zero = np.zeros((1, d) if self.batched else d, dtype=self.dtype)
            try:
                (a,) = self.session.run([self.output], {self.input: zero})
            except Exception as err:
                raise ConfigError(
                    "controller.params.file",
                    f"{path}: its input {given.name!r} {given.shape} does not take this arm's observation "
                    f"of {d} entries ({str(err)[:200]})",
                ) from err
            if np.asarray(a).size != n:
                raise ConfigError(
                    "controller.params.file",
                    f"{path}: on this arm's observation of {d} entries it gives {np.asarray(a).size} "
                    f"actions; the action is [{n}] ({entries})",
                )

    def _run(self, feed: dict, t: float) -> np.ndarray:
        """The network's raw action on ``feed`` at ``t`` (n entries of its type), the call's wall
        time in :attr:`seconds`; a failed call or an action of another size is a ControllerError.
        """
        start = time.perf_counter()
        try:
            (a,) = self.session.run([self.output], feed)
        except Exception as err:
            raise ControllerError(f"the policy {self.path} failed at t = {t:g} s: {err}") from err
        self.seconds = time.perf_counter() - start
        if a.size != self.n:
            raise ControllerError(
                f"the policy {self.path} returned {a.size} actions at t = {t:g} s; "
                f"its action has {self.n} entries"
            )
        return a.reshape(-1)

    def __call__(self, obs: np.ndarray, t: float) -> np.ndarray:
        """The action at ``t`` (float64, n entries); a NaN or a wrong shape is a ControllerError."""
        x = np.asarray(obs, dtype=self.dtype)
        a = self._run({self.input: x[None, :] if self.batched else x}, t).astype(float)
        if not np.all(np.isfinite(a)):
            raise ControllerError(self.non_finite(a, t))
        return a

    def non_finite(self, a: np.ndarray, t: float) -> str:
        """The message of a non-finite action ``a`` at ``t``."""
        values = np.asarray(a).reshape(-1)
        return f"the policy {self.path} returned a non-finite action at t = {t:g} s: {values}"

    def on_buffer(self, obs: np.ndarray):
        """A function of t that runs the policy on what the float64 array ``obs`` holds when it
        is called (the compiled loop writes it in place) and returns the raw action (n entries
        of the network's type), the call's wall time in :attr:`seconds`: the hybrid loop's step,
        with no array made per call. The caller checks that the values are finite.
        """
        given = obs if self.dtype == np.float64 else np.empty(obs.shape, self.dtype)
        feed = {self.input: given[None, :] if self.batched else given}
        convert = given is not obs

        def call(t: float) -> np.ndarray:
            if convert:
                given[:] = obs
            return self._run(feed, t)

        return call


class PolicyLaw(Controller):
    """A learned policy (an ONNX file) in torque, residual or gains mode (module docstring).

    Args:
        context: what the experiment hands a controller.
        file: the ONNX file (a relative path in an experiment file is read from its folder).
        action: ``"torque"``, ``"residual"`` or ``"gains"``.
        base: the law whose command a residual is added to, or whose gains the policy sets; in
            torque mode it is built but never computed (the compiled loop observes through it).
        residual_scale: s, the residual's bound as a fraction of the effort limits.
        gain_range: G, the largest factor on a gain (and 1/G the smallest) in gains mode.

    """

    def __init__(
        self,
        context: ControllerContext,
        file: str | None = None,
        action: str = "torque",
        base: str = "pd",
        residual_scale: float = 0.1,
        gain_range: float = 4.0,
    ):

        if file is None:
            raise ConfigError("controller.params.file", "missing: the policy's ONNX file")
        limits = context.torque_limits
        if limits is None or not np.all(np.isfinite(limits)):
            raise ConfigError(
                "plant.torque_limit",
                "a policy's action is scaled by the effort limits: every joint needs one",
            )
        if base == "policy":
            raise ConfigError("controller.params.base", "a policy's base law cannot be a policy")
        self.layout = ObservationLayout(context.n, context.m)
        gains = action == "gains"
        self.policy = (
            OnnxPolicy(file, self.layout.size, GAIN_ACTIONS, "gains mode: the factors' exponents on K_p, K_v")
            if gains
            else OnnxPolicy(file, self.layout.size, context.n)
        )
        self.action, self.mode, self.base_kind = action, ACTIONS.index(action), base
        self.scale = action_scale(action, limits, residual_scale, gain_range)
        self.nominal, self.trajectory = context.nominal, context.trajectory
        self._base: Controller | None = None

    @property
    def base(self) -> Controller | None:
        """The base law, built by the experiment as it builds that kind."""
        return self._base

    @base.setter
    def base(self, law: Controller | None) -> None:
        if law is not None and self.action == "gains" and not law.scale_gains(1.0, 1.0):
            raise ConfigError("controller.params.base", no_gains(self.base_kind))
        self._base = law

    @property
    def state_size(self) -> int:  # type: ignore[override]
        """The base law's state (a residual policy advances it as the base law's run would)."""
        return self.base.state_size if self.base is not None else 0

    @property
    def signal_names(self) -> tuple[str, ...]:  # type: ignore[override]
        """The base law's signals (NaN in torque mode), then ``inference_time`` [s]."""
        return (*(self.base.signal_names if self.base is not None else ()), "inference_time")

    def initial_state(self) -> np.ndarray:
        """The base law's z(0)."""
        return self.base.initial_state() if self.base is not None else np.zeros(0)

    def compute(
        self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray, period: float = 0.0
    ) -> ControlOutput:
        """The command from the observation at t (torque or residual mode)."""
        a = self.policy(observation(self.nominal, self.trajectory, t, q, v), t)
        command = np.clip(a, -1.0, 1.0) * self.scale
        base = self.base
        names = base.signal_names if base is not None else ()
        if self.action == "gains" and base is not None:
            base.scale_gains(math.exp(command[0]), math.exp(command[1]))
        if self.action != "torque" and base is not None:
            out = base.compute(t, q, v, z, period)
            signals = dict(out.signals)
            signals["inference_time"] = self.policy.seconds
            tau = out.tau + command if self.action == "residual" else out.tau
            return ControlOutput(tau, signals, out.state)
        signals = dict.fromkeys(names, float("nan"))
        signals["inference_time"] = self.policy.seconds
        return ControlOutput(command, signals, None)


LAW = register_law(
    Law(
        "policy",
        PolicyLaw,
        "a learned policy from an ONNX file, as the command or a residual on a shipped law "
        "(docs/learning.md)",
        (
            LawParam("file", None, "-", "the policy's ONNX file (docs/learning.md#policy-files)", path=True),
            LawParam(
                "action",
                "torque",
                "-",
                "the action is the command, a residual on the base law, or the base law's gains",
                choices=ACTIONS,
            ),
            LawParam(
                "base",
                "pd",
                "-",
                "the law a residual is added to, or whose gains are set (with the experiment's settings)",
                choices=base_laws,
            ),
            LawParam(
                "residual_scale",
                0.1,
                "-",
                "the residual's bound as a fraction of the effort limits",
                0.0,
                10.0,
                low_open=True,
                search=(0.01, 1.0),
            ),
            LawParam(
                "gain_range",
                4.0,
                "-",
                "G: in gains mode each gain is the base law's times a factor in [1/G, G]",
                1.0,
                100.0,
                low_open=True,
                fixed="the range the policy was trained with: its actions are exponents of G",
            ),
        ),
    )
)


def trained_horizon(file: str | Path) -> float | None:
    """The episode length [s] a policy file was trained on, as its record (``FILE.json``, written
    by the trainer beside the ONNX file) gives it; None where no record says.
    """
    record = Path(f"{file}.json")
    try:
        data = json.loads(record.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    value = data.get("training_duration", data.get("duration")) if isinstance(data, dict) else None
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def horizon_warning(name: str, file: str | Path, duration: float, scored_from: float) -> str:
    """A warning when a policy is scored outside the horizon it was trained on: runs of
    ``duration`` [s] scored from ``scored_from`` [s] on, against the episodes of its record; ""
    when they match or no record says.
    """
    trained = trained_horizon(file)
    if trained is None or duration <= trained + 1e-9:
        return ""
    window = f"scored on t >= {scored_from:g} s" if scored_from < trained else "scored only past it"
    return (
        f"the policy {name} ({Path(file).name}) was trained on {trained:g} s episodes; runs of "
        f"{duration:g} s, {window}, take it outside its training horizon"
    )
