"""The one shape of every registry of kinds (nnrobust/kinds.py): the paper's kinds, the registered
laws, the criteria, the paths and the disturbances are each a Kinds, filled by their room's
modules when the room is imported."""

from dataclasses import dataclass

import pytest

from nnrobust.kinds import Kinds


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
    from nnrobust.presets import load_preset

    return load_preset("paper-ellipse").replace(simulation={"duration": 0.05}, **sections)


def test_a_kind_of_each_concept_declared_here_brings_its_own_key(monkeypatch):
    """Issue 36: a path, a criterion, a disturbance, a robust term (a paper kind) and a registered
    law, each declared from this module with one key of its own (a LawParam): each is a valid
    choice; its key is defaulted, range-checked, settable by --set, inert under another kind and in
    the rendered docs tables; and the run builds it (on the compiled loop where its class has a
    twin: the path, criterion, disturbance and robust term reuse shipped twins' classes)."""
    import importlib.util
    import sys
    from pathlib import Path

    import numpy as np

    from nnrobust.config import apply_overrides, inert_keys
    from nnrobust.controllers.registry import LAWS, PAPER_KINDS, Law, LawParam, PaperKind
    from nnrobust.controllers.sliding_mode import SlidingModeCompensator
    from nnrobust.controllers.task_space import eq9_law
    from nnrobust.exceptions import ConfigError
    from nnrobust.experiment import build, run_experiment
    from nnrobust.plant.disturbance import DISTURBANCE_KINDS, DisturbanceKind, SinusoidalDisturbance
    from nnrobust.subtasks import CRITERION_KINDS, CriterionKind, JointSmoothness
    from nnrobust.trajectories import PATH_KINDS, EllipseTrajectory, PathKind

    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "docs"))
    import render_tables

    ellipse = PATH_KINDS["ellipse"]
    stretched = PathKind(
        "stretched",
        "the ellipse with axis_a times trajectory.stretch",
        (*ellipse.keys, "stretch"),
        "as `ellipse`, and `stretch`",
        ellipse.check,
        ellipse.dimension,
        lambda tc, robot, q_seed: EllipseTrajectory(
            np.asarray(tc.center, float),
            tc.stretch * np.asarray(tc.axis_a, float),
            np.asarray(tc.axis_b, float),
            tc.omega,
            tc.phase,
        ),  # fmt: skip
        params=(LawParam("trajectory.stretch", 0.5, "-", "factor on axis_a", 0.0, 2.0, low_open=True),),
    )
    twisted = CriterionKind(
        "twisted",
        JointSmoothness,
        "-0.5 ((twist, -1, 1)^T q)^2",
        lambda m: "rad$^2$",
        lambda sc, robot: JointSmoothness((sc.twist, -1.0, 1.0)),
        params=(LawParam("subtasks.twist", 0.25, "-", "first joint's coefficient", -4.0, 4.0),),
    )
    pulse = DisturbanceKind(
        "pulse",
        "one harmonic at 3 rad/s of plant.pulse_level on every joint",
        lambda pc, robot, tau_ref: SinusoidalDisturbance(
            np.full((robot.nq, 1), pc.pulse_level), np.array([3.0]), np.zeros((robot.nq, 1))
        ),
        params=(LawParam("plant.pulse_level", 1.5, "N m", "amplitude", 0.0, 20.0),),
    )

    def soft_build(parts):
        c = parts.controller
        term = SlidingModeCompensator(
            np.diag(c.Kp), np.diag(c.Kv), c.softness * c.sliding_gain, c.sliding_boundary
        )
        return eq9_law(parts, term)

    soft = PaperKind(
        "soft-sliding",
        "the sliding-mode term at controller.softness of its gain",
        "the experiment's",
        soft_build,
        keys=("controller.sliding_gain", "controller.sliding_boundary", "controller.softness"),
        params=(LawParam("controller.softness", 0.5, "-", "share of the gain", 0.0, 1.0, fixed="a test's"),),
    )
    spec = importlib.util.spec_from_file_location(
        "taskpd_example", Path(__file__).parents[2] / "examples" / "custom_controller.py"
    )
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    pd_law = Law(
        "task-pd-here",
        example.TaskPD,
        "the example's task-space PD, registered from a test",
        (LawParam("Kp", 400.0, "1/s^2", "stiffness", 0.0, 1e6, low_open=True, search=(10.0, 1e5)),),
    )
    monkeypatch.setitem(PATH_KINDS, stretched.name, stretched)
    monkeypatch.setitem(CRITERION_KINDS, twisted.name, twisted)
    monkeypatch.setitem(DISTURBANCE_KINDS, pulse.name, pulse)
    monkeypatch.setitem(PAPER_KINDS, soft.name, soft)
    monkeypatch.setitem(LAWS, pd_law.name, pd_law)

    cases = [  # (section, choice, key, default, a value out of its range, the table)
        ({"trajectory": {"kind": "stretched"}}, "trajectory.stretch", 0.5, 3.0, render_tables.path_kinds),
        (
            {"subtasks": {"criteria": ["twisted"]}},
            "subtasks.twist",
            0.25,
            -9.0,
            render_tables.criterion_kinds,
        ),
        (
            {"plant": {"disturbance": "pulse"}},
            "plant.pulse_level",
            1.5,
            50.0,
            render_tables.disturbance_kinds,
        ),
        (
            {"controller": {"kind": "soft-sliding"}},
            "controller.softness",
            0.5,
            1.5,
            render_tables.paper_kind_keys,
        ),
        (
            {"controller": {"kind": "task-pd-here"}},
            "controller.params.Kp",
            400.0,
            -1.0,
            render_tables.registered_laws,
        ),
    ]
    for sections, key, default, beyond, table in cases:
        config = _paper(**sections)  # a valid choice
        section, _, name = key.partition(".")
        law_param = name.startswith("params.")
        holder = getattr(config, section)
        if law_param:  # a law's parameters resolve to their declared defaults
            value = LAWS["task-pd-here"].resolve(holder.params, None, 2)["Kp"]
        else:
            value = getattr(holder, name)
        assert value == default, key  # defaulted
        with pytest.raises(ConfigError, match=key.replace(".", r"\.")):  # range-checked
            apply_overrides(config, {key: beyond})
        assert f"`{name.removeprefix('params.')}`" in table() or f"`{key}`" in table(), key  # in the docs
        half = apply_overrides(config, {key: default / 2})  # settable, and written back to config.toml
        if law_param:
            assert half.to_dict()["controller"]["params"] == {"Kp": default / 2}
        else:
            assert getattr(getattr(half, section), name) == default / 2
            assert half.to_dict()[section][name] == default / 2
            assert key in inert_keys(_paper()), key  # inert under the preset's own kinds
            with pytest.raises(ConfigError, match="is not a list"):  # one number: no entry to index
                apply_overrides(config, {f"{key}[0]": default})
        result = run_experiment(half)
        assert result.status == "completed", (key, result.status)
        if section == "trajectory":  # result.npz's info: the section as the file has it, flat
            assert result.info.trajectory["stretch"] == default / 2 and "extra" not in result.info.trajectory
        assert result.backend == ("hybrid" if law_param else "compiled"), key
    with pytest.raises(ConfigError, match="controller.params"):  # a law's key under another kind: refused
        _paper(controller={"kind": "nn", "params": {"Kp": 1.0}})
    soft_setup = build(_paper(controller={"kind": "soft-sliding"}))
    assert soft_setup.controller.compensator.gain == 0.5 * soft_setup.config.controller.sliding_gain
    assert build(_paper(plant={"disturbance": "pulse"})).plant.disturbance.amplitude[0, 0] == 1.5
