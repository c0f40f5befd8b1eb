"""The compiled backend's foundation: the extension loads, and simulates exactly the model Python built.

`make test` sets NNROBUST_REQUIRE_COMPILED=1 when a C++ compiler is on the machine, so a build
that silently fell back to Python fails here instead of skipping.
"""

import os
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from nnrobust import compiled
from nnrobust.exceptions import NNRobustError
from nnrobust.model.perturbation import perturb_inertias

from .arms import arm, random_configurations

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from closed_loop import python_floor_loop  # noqa: E402  (the benchmark's Python twin of the floor)

from .problems import VERTICAL_GRAVITY, paper_robot

needs_extension = pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())


def test_the_extension_is_built_where_a_compiler_is():
    if os.environ.get("NNROBUST_REQUIRE_COMPILED") == "1":
        assert compiled.available(), compiled.unavailable_reason()


def _robots():
    panda = arm("panda", "pose")
    return {
        "paper arm": paper_robot(),
        "paper arm, vertical plane": paper_robot(VERTICAL_GRAVITY),
        "panda, fingers locked": panda,
        "panda, perturbed inertias": (perturb_inertias(panda.model, 1.1, 0.9, 0.2, 0.01, seed=3),
                                      panda.task_frame),
        "planar7": arm("planar7", "planar"),
    }


@needs_extension
@pytest.mark.parametrize("name", list(_robots()))
def test_the_same_model_on_both_sides(name):
    """M, V_m v + G and the task frame's Jacobian agree to 1e-12 on random states (the C++ copy
    comes from Pinocchio's serialization of the model Python built)."""
    robot = _robots()[name]
    model, frame = robot if isinstance(robot, tuple) else (robot.model, robot.task_frame)
    loaded = compiled.load_model(model, frame)
    data, fid = model.createData(), model.getFrameId(frame)
    assert loaded.nq == model.nq
    rng = np.random.default_rng(5)
    low = np.maximum(model.lowerPositionLimit, -np.pi)
    high = np.minimum(model.upperPositionLimit, np.pi)
    for _ in range(20):
        q, v = rng.uniform(low, high), rng.uniform(-2, 2, model.nv)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        np.testing.assert_allclose(loaded.mass(q), M, rtol=0, atol=1e-12)
        bias = pin.rnea(model, data, q, v, np.zeros(model.nv))
        np.testing.assert_allclose(loaded.bias(q, v), bias, rtol=0, atol=1e-12 * max(1, np.abs(bias).max()))
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        np.testing.assert_allclose(loaded.frame_jacobian(q), J, rtol=0, atol=1e-12)


@needs_extension
@pytest.mark.parametrize("name, task", [("panda", "position"), ("planar7", "planar")])
def test_the_floor_loop_is_the_python_loop(name, task):
    """The bare C++ loop that benchmarks/closed_loop.py times computes what its Python twin does."""
    robot = arm(name, task)
    q0 = random_configurations(robot, 1, seed=2)[0]
    v0 = np.linspace(-0.5, 0.5, robot.nq)
    loaded = compiled.load_model(robot.model, robot.task_frame)
    ours = compiled.floor_loop(loaded, q0, v0, 200, 1e-3)
    theirs = python_floor_loop(robot.model, robot.task_frame, q0, v0, 200, 1e-3)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-10)


def test_without_the_extension_the_package_says_why(monkeypatch):
    """A machine without a compiler: available() is False, the reason says how to get the loop,
    and asking for it is one clear error, not an ImportError from deep inside."""
    import importlib

    def missing(name):
        raise ImportError(f"No module named {name!r}")

    monkeypatch.setattr(compiled, "_MODULE", None)
    monkeypatch.setattr(compiled, "_REASON", "")
    monkeypatch.setattr(importlib, "import_module", missing)
    assert not compiled.available()
    assert "reinstall nnrobust with a C++ compiler" in compiled.unavailable_reason()
    with pytest.raises(NNRobustError, match="the compiled loop is not built"):
        robot = paper_robot()
        compiled.load_model(robot.model, robot.task_frame)
