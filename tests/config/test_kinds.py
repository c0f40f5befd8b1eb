"""The one shape of every registry of kinds (nnrobust/core/kinds.py): the paper's kinds, the registered
laws, the criteria, the paths and the disturbances are each a Kinds, filled by their room's
modules when the room is imported."""

import importlib.util
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from nnrobust.controllers.nn_compensator import error_dynamics, lyapunov_P
from nnrobust.core.kinds import Kinds
from nnrobust.plant.disturbance import Disturbance
from nnrobust.run import compiled
from nnrobust.subtasks.base import Criterion
from nnrobust.trajectories import Trajectory

TWINS = Path(__file__).resolve().with_name("twins")
"""The C++ twins of the kinds declared below, each compiled apart on first use."""


@dataclass(frozen=True)
class Kind:
    name: str
    value: int


def test_a_kind_is_declared_once_by_name_in_order():
    kinds = Kinds("widget")
    kinds.declare(Kind("b", 1), Kind("a", 2))
    kinds.declare(Kind("b", 1))  # the same declaration again: a module imported twice
    assert list(kinds) == ["b", "a"] and kinds["a"].value == 2
    with pytest.raises(ValueError, match="a widget named 'b' is already declared"):
        kinds.declare(Kind("b", 3))


def test_every_registry_is_a_kinds_filled_when_its_room_is_imported():
    import nnrobust.controllers  # noqa: F401  (the rooms' package faces discover their kinds)
    import nnrobust.plant  # noqa: F401
    import nnrobust.subtasks  # noqa: F401
    import nnrobust.trajectories  # noqa: F401
    from nnrobust.controllers.registry import LAWS, PAPER_KINDS
    from nnrobust.plant.disturbance import DISTURBANCE_KINDS
    from nnrobust.subtasks.registry import CRITERION_KINDS
    from nnrobust.trajectories.registry import PATH_KINDS

    expected = {
        "controller kind": (PAPER_KINDS, {"nn", "no-u0", "sliding-mode", "computed-torque", "pd"}),
        "control law": (LAWS, {"slotine-li", "rbf-nn", "policy"}),
        "criterion": (CRITERION_KINDS, {"manipulability", "joint_limits", "paper"}),
        "path": (PATH_KINDS, {"ellipse", "point_to_point", "waypoints"}),
        "disturbance": (DISTURBANCE_KINDS, {"paper"}),
    }
    for concept, (kinds, names) in expected.items():
        assert isinstance(kinds, Kinds) and kinds.concept == concept
        assert names <= set(kinds), (concept, sorted(kinds))


def _paper(**sections):
    from nnrobust.config.presets import load_preset

    return load_preset("paper-ellipse").replace(simulation={"duration": 0.05}, **sections)


# One extra kind of each concept, declared as a user's package would declare it, each with its own
# C++ twin (tests/config/twins/): its class, its declaration (in the test below) and its twin.


@dataclass(frozen=True)
class FigureEight(Trajectory):
    """x_d(t) = c + a cos(w t) + stretch b sin(2 w t)."""

    center: np.ndarray
    axis_a: np.ndarray
    axis_b: np.ndarray
    omega: float
    stretch: float

    twin = "figure-eight"
    twin_fields = ("center", "axis_a", "axis_b", "omega", "stretch")
    twin_source = TWINS / "figure_eight.cpp"

    def __post_init__(self):
        object.__setattr__(self, "m", np.asarray(self.center).size)

    def __call__(self, t):
        w, c, s2, c2 = (
            self.omega,
            np.cos(self.omega * t),
            np.sin(2 * self.omega * t),
            np.cos(2 * self.omega * t),
        )
        a, b, k = np.asarray(self.axis_a), np.asarray(self.axis_b), self.stretch
        x = self.center + a * c + k * b * s2
        return x, -w * np.sin(w * t) * a + 2 * w * k * c2 * b, -(w**2) * c * a - 4 * w**2 * k * s2 * b

    def error(self, x, x_d):
        return x - x_d


class Twisted(Criterion):
    """h = -0.5 (c^T q)^2, c = (twist, -1, 1, -1, ...)."""

    def __init__(self, twist):
        self.twist = twist

    def coefficients(self, n):
        return np.array([self.twist] + [(-1.0) ** i for i in range(1, n)])

    def value(self, model, q):
        return -0.5 * float(self.coefficients(q.size) @ q) ** 2

    def gradient(self, model, q):
        c = self.coefficients(q.size)
        return -float(c @ q) * c


@dataclass(frozen=True)
class Pulse(Disturbance):
    """tau_d(t) = level weights sin(3 t)."""

    level: float
    weights: np.ndarray

    twin = "pulse"
    twin_fields = ("level", "weights")
    twin_source = TWINS / "pulse.cpp"

    def __call__(self, t):
        return self.level * np.sin(3.0 * t) * self.weights


class SmoothSign:
    """u_0 = -gain tanh(w / boundary) entry by entry, w = B^T P y. Stateless."""

    state_size, signal_names = 0, ()
    twin = "smooth-sign"
    twin_fields = ("BtP", "gain", "boundary")
    twin_source = TWINS / "smooth_sign.cpp"

    def __init__(self, Kp, Kv, gain, boundary):
        self.gain, self.boundary = gain, boundary
        self.BtP = error_dynamics(Kp, Kv)[1].T @ lyapunov_P(Kp, Kv)

    def initial_state(self):
        return np.zeros(0)

    def output(self, q, v, y, z, period):
        return -self.gain * np.tanh(self.BtP @ y / self.boundary), z, {}


def _example_task_pd():
    spec = importlib.util.spec_from_file_location(
        "taskpd_example", Path(__file__).parents[2] / "examples" / "custom_controller.py"
    )
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    return example.TaskPD


def _declare_kinds(monkeypatch):
    """Declare the five kinds into the registries, as a user's module does when imported."""
    from nnrobust.controllers.registry import LAWS, PAPER_KINDS, Law, LawParam, PaperKind
    from nnrobust.controllers.task_space import eq9_law
    from nnrobust.plant.disturbance import DISTURBANCE_KINDS, DisturbanceKind
    from nnrobust.subtasks import CRITERION_KINDS, CriterionKind
    from nnrobust.trajectories import PATH_KINDS, PathKind

    ellipse = PATH_KINDS["ellipse"]
    eight = PathKind(
        "figure-eight",
        "c + a cos(w t) + stretch b sin(2 w t)",
        (*ellipse.keys, "stretch"),
        "as `ellipse`, and `stretch`",
        ellipse.check,
        ellipse.dimension,
        lambda tc, robot, q_seed: FigureEight(
            np.asarray(tc.center, float),
            np.asarray(tc.axis_a, float),
            np.asarray(tc.axis_b, float),
            tc.omega,
            tc.stretch,
        ),  # fmt: skip
        params=(LawParam("trajectory.stretch", 0.5, "-", "factor on axis_b", 0.0, 2.0, low_open=True),),
    )
    twisted = CriterionKind(
        "twisted",
        Twisted,
        "-0.5 ((twist, -1, 1, ...)^T q)^2",
        lambda m: "rad$^2$",
        lambda sc, robot: Twisted(sc.twist),
        twin_fields=lambda c: {"twist": c.twist},
        params=(LawParam("subtasks.twist", 0.25, "-", "first joint's coefficient", -4.0, 4.0),),
        twin_source=TWINS / "twisted.cpp",
    )
    pulse = DisturbanceKind(
        "pulse",
        "plant.pulse_level (1, 2, ..., n) sin(3 t)",
        lambda pc, robot, tau_ref: Pulse(pc.pulse_level, np.arange(1.0, robot.nq + 1.0)),
        params=(LawParam("plant.pulse_level", 1.5, "N m", "amplitude", 0.0, 20.0),),
    )

    def smooth_build(parts):
        c = parts.controller
        term = SmoothSign(np.diag(c.Kp), np.diag(c.Kv), c.softness * c.sliding_gain, c.sliding_boundary)
        return eq9_law(parts, term)

    smooth = PaperKind(
        "smooth-sign",
        "eq. (9) with u_0 = -softness K tanh(w / Phi)",
        "the experiment's",
        smooth_build,
        keys=("controller.sliding_gain", "controller.sliding_boundary", "controller.softness"),
        params=(LawParam("controller.softness", 0.5, "-", "share of the gain", 0.0, 1.0, fixed="a test's"),),
    )
    pd_law = Law(
        "task-pd-here",
        _example_task_pd(),
        "the example's task-space PD, registered from a test",
        (LawParam("Kp", 400.0, "1/s^2", "stiffness", 0.0, 1e6, low_open=True, search=(10.0, 1e5)),),
        twin="task-pd-here",
        twin_fields=("Kp", "Kd", "damping"),
        twin_source=TWINS / "task_pd_here.cpp",
    )
    monkeypatch.setitem(PATH_KINDS, eight.name, eight)
    monkeypatch.setitem(CRITERION_KINDS, twisted.name, twisted)
    monkeypatch.setitem(DISTURBANCE_KINDS, pulse.name, pulse)
    monkeypatch.setitem(PAPER_KINDS, smooth.name, smooth)
    monkeypatch.setitem(LAWS, pd_law.name, pd_law)


CASES = [  # (the kind chosen, its key, its default, a value out of its range, its docs table)
    ({"trajectory": {"kind": "figure-eight"}}, "trajectory.stretch", 0.5, 3.0, "path_kinds"),
    ({"subtasks": {"criteria": ["twisted"]}}, "subtasks.twist", 0.25, -9.0, "criterion_kinds"),
    ({"plant": {"disturbance": "pulse"}}, "plant.pulse_level", 1.5, 50.0, "disturbance_kinds"),
    ({"controller": {"kind": "smooth-sign"}}, "controller.softness", 0.5, 1.5, "paper_kind_keys"),
    ({"controller": {"kind": "task-pd-here"}}, "controller.params.Kp", 400.0, -1.0, "registered_laws"),
]


@pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())
@pytest.mark.parametrize("case", range(len(CASES)), ids=[c[1] for c in CASES])
def test_a_kind_of_each_concept_declared_here_brings_its_own_key_and_twin(case, monkeypatch):
    """Issue 36: a path, a criterion, a disturbance, a robust term (a paper kind) and a registered
    law, each declared from this module with one key of its own (a LawParam) and its own C++ twin
    (tests/config/twins/, compiled apart): each is a valid choice; its key is defaulted,
    range-checked, settable by --set, inert under another kind and in the rendered docs tables; the
    run takes the compiled loop with its twin; and the twin is its Python class, component by
    component (the one twin-test case each)."""
    from nnrobust.config import apply_overrides, inert_keys
    from nnrobust.controllers.registry import LAWS
    from nnrobust.core.exceptions import ConfigError
    from nnrobust.run.experiment import build, run_experiment

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "docs"))
    import render_tables

    _declare_kinds(monkeypatch)
    sections, key, default, beyond, table = CASES[case]
    config = _paper(**sections)  # a valid choice
    section, _, name = key.partition(".")
    law_param = name.startswith("params.")
    holder = getattr(config, section)
    value = LAWS["task-pd-here"].resolve(holder.params, None, 2)["Kp"] if law_param else getattr(holder, name)
    assert value == default, key  # defaulted
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):  # range-checked
        apply_overrides(config, {key: beyond})
    text = getattr(render_tables, table)()
    assert f"`{name.removeprefix('params.')}`" in text or f"`{key}`" in text, key  # in the docs
    half = apply_overrides(config, {key: default / 2})  # settable, and written back to config.toml
    if law_param:
        assert half.to_dict()["controller"]["params"] == {"Kp": default / 2}
        with pytest.raises(ConfigError, match="controller.params"):  # under another kind: refused
            _paper(controller={"kind": "nn", "params": {"Kp": 1.0}})
    else:
        assert getattr(getattr(half, section), name) == default / 2
        assert half.to_dict()[section][name] == default / 2
        assert key in inert_keys(_paper()), key  # inert under the preset's own kinds
        with pytest.raises(ConfigError, match="is not a list"):  # one number: no entry to index
            apply_overrides(config, {f"{key}[0]": default})
    result = run_experiment(half)
    assert (result.status, result.backend) == ("completed", "compiled"), key
    if section == "trajectory":  # result.npz's info: the section as the file has it, flat
        assert result.info.trajectory["stretch"] == default / 2 and "extra" not in result.info.trajectory
    _twin_case(build(half.replace(simulation={"duration": 0.01})), section)


def _twin_case(setup, section):
    """The compiled component against its Python class at random states (tests/core/test_twins.py's
    comparisons): the control step (path, robust term, law), the criterion, or the plant's q''."""
    assert compiled.twin_refusal(setup) == ""
    robot, nominal, spec = compiled._prepared(setup, 0.01)
    module, rng = compiled._module(), np.random.default_rng(3)
    for _ in range(10):
        t, q, v = rng.uniform(0.0, 10.0), rng.uniform(-2.5, 2.5, 3), rng.uniform(-2.0, 2.0, 3)
        if section == "subtasks":
            pairs = [
                (
                    module.twin_criterion_gradient(nominal, spec, q),
                    setup.criterion.gradient(setup.nominal, q),
                ),
                (module.twin_criterion_value(robot, spec, q), setup.criterion.value(setup.robot, q)),
            ]
        elif section == "plant":
            tau = rng.uniform(-5.0, 5.0, 3)
            setup.plant.begin_period(t)
            pairs = [
                (
                    module.twin_plant_acceleration(robot, spec, t, q, v, tau),
                    setup.plant.acceleration(t, q, v, tau),
                )
            ]
        else:
            z = setup.controller.initial_state()
            ours = module.twin_control(nominal, spec, t, q, v, z)
            pairs = [
                (ours.tau, setup.controller.compute(t, q, v, z, setup.config.simulation.control_period).tau)
            ]
        for ours, theirs in pairs:
            np.testing.assert_allclose(ours, theirs, rtol=1e-10, atol=1e-10)


def test_a_twin_file_is_checked_against_its_declaration(tmp_path):
    """A twin_source that registers another name, a shipped name, or nothing is refused in one
    line naming the file; so is a path that is not a C++ file."""
    from nnrobust.core.exceptions import ConfigError
    from nnrobust.plugins.native_law import load_twin_source

    if not compiled.available():
        pytest.skip(compiled.unavailable_reason())
    with pytest.raises(ConfigError, match=r"registers the path figure-eight, not the path 'eight'"):
        load_twin_source(TWINS / "figure_eight.cpp", "path", "eight", "Eight")
    shipped = tmp_path / "shipped.cpp"
    shipped.write_text(
        (TWINS / "figure_eight.cpp")
        .read_text()
        .replace('NNROBUST_PATH("figure-eight"', 'NNROBUST_PATH("ellipse"')
    )
    with pytest.raises(ConfigError, match=r"registers the path 'ellipse', the name of a shipped twin"):
        load_twin_source(shipped, "path", "ellipse", "Eight")
    bare = tmp_path / "bare.cpp"
    bare.write_text("int unrelated = 1;\n")
    with pytest.raises(ConfigError, match="it registers nothing"):
        load_twin_source(bare, "path", "eight", "Eight")
    with pytest.raises(ConfigError, match=r"Eight\.twin_source.*not a C\+\+ file"):
        load_twin_source(Path(__file__), "path", "eight", "Eight")
