"""The designed excitation's joint-space law (nnrobust/controllers/laws/joint_fourier.py,
csrc/controllers/laws/joint_fourier.cpp): its reference is the design's trajectory and its
derivatives (finite differences); with the true model as its nominal one the arm follows the
design but for the zero-order hold's first-order error, and a start off it decays as
e'' + K_v e' + K_p e = 0 says; its compiled twin equals it step by step and over a run; a file
that is not the experiment's is refused with one line.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from nnrobust import run_experiment
from nnrobust.config import load_config
from nnrobust.core.exceptions import ConfigError
from nnrobust.run import compiled
from nnrobust.run.experiment import build
from nnrobust.studies.identify.design import DesignOptions, write_design
from nnrobust.studies.identify.synthetic import FourierTrajectory


@pytest.fixture(scope="module")
def design(tmp_path_factory):
    """A design of the paper's arm (a small budget) and its experiment file."""
    out = tmp_path_factory.mktemp("design") / "traj.toml"
    write_design("three_link_planar", out, DesignOptions(evaluations=200, seed=1), periods=1)
    return out


def _exact(config, **simulation):
    """The experiment with the true model as the controller's, no friction and no disturbance."""
    return config.replace(
        nominal={"kind": "urdf"},
        plant={"friction_scale": 0.0, "disturbance": "none"},
        simulation={**simulation},
    )


def test_the_reference_is_the_design_and_its_derivatives(design):
    setup = build(load_config(design))
    law = setup.controller
    record = json.loads(design.with_suffix(".json").read_text())
    truth = FourierTrajectory(
        np.array(record["q0"]), np.array(record["a"]), np.array(record["b"]), record["frequency"]
    )
    h = 1e-5
    for t in (0.0, 1.7, 6.25, 9.99):
        q, dq, ddq = law.reference(t)
        tq, tdq, tddq = (x[0] for x in truth.states(np.array([t])))
        np.testing.assert_allclose(q, tq, atol=1e-12)
        np.testing.assert_allclose(dq, tdq, atol=1e-12)
        np.testing.assert_allclose(ddq, tddq, atol=1e-11)
        ahead, behind = law.reference(t + h)[0], law.reference(t - h)[0]
        np.testing.assert_allclose((ahead - behind) / (2 * h), dq, atol=1e-7)
    np.testing.assert_allclose(law.reference(0.0)[1:], 0.0, atol=1e-12)  # the design starts at rest


def test_with_the_true_model_the_arm_follows_the_design_to_the_hold_s_first_order(design):
    """The only error left is the zero-order hold's (the torque held over a period while the
    motion's changes): it halves with the period."""
    config = _exact(load_config(design), duration=4.0)
    law = build(config).controller
    worst = []
    for period in (1e-3, 5e-4):
        result = run_experiment(config.replace(simulation={"control_period": period}))
        planned = np.array([law.reference(t)[0] for t in result.t])
        worst.append(np.max(np.abs(result.q - planned)))
    assert worst[0] < 3e-4
    assert 0.45 < worst[1] / worst[0] < 0.55, worst


def test_a_start_off_the_design_decays_as_the_closed_loop_says(design):
    """e'' + K_v e' + K_p e = 0 from e(0) = e0, e'(0) = 0: with zeta = 1, e(t) = e0 (1 + w t) e^(-w t)."""
    w = 10.0
    config = _exact(load_config(design), duration=1.0, backend="python")
    config = config.replace(controller={"params": {**config.controller.params, "bandwidth": w}})
    config = config.replace(simulation={"initial_task_offset": [0.01, 0.0]})
    result = run_experiment(config)
    law = build(config).controller
    e = result.q - np.array([law.reference(t)[0] for t in result.t])
    e0 = e[0]
    assert np.max(np.abs(e0)) > 1e-3
    for k in (100, 300, 600):
        t = result.t[k]
        np.testing.assert_allclose(e[k], e0 * (1 + w * t) * math.exp(-w * t), atol=2e-3 * np.abs(e0).max())


@pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())
def test_each_compiled_step_is_its_python_twin_and_so_is_the_run(design):
    config = load_config(design)
    setup = build(config)
    assert compiled.twin_refusal(setup) == ""
    _, nominal, spec = compiled._prepared(setup, 0.01)
    module = compiled._module()
    rng = np.random.default_rng(2)
    lower, upper = setup.robot.working_range
    for _ in range(20):
        t, q = rng.uniform(0.0, 20.0), rng.uniform(lower, upper)
        v = rng.uniform(-2.0, 2.0, q.size)
        ours = module.twin_control(nominal, spec, t, q, v, np.zeros(0))
        theirs = setup.controller.compute(t, q, v, np.zeros(0), 1e-3)
        np.testing.assert_allclose(
            ours.tau, theirs.tau, rtol=0, atol=1e-12 * max(1.0, np.abs(theirs.tau).max())
        )
    runs = {
        b: run_experiment(config.replace(simulation={"duration": 2.0, "backend": b}))
        for b in ("compiled", "python")
    }
    assert runs["compiled"].backend == "compiled"
    np.testing.assert_allclose(runs["compiled"].q, runs["python"].q, rtol=0, atol=1e-11)


def test_an_experiment_whose_path_is_not_the_design_s_is_refused(design):
    config = load_config(design).replace(trajectory={"kind": "ellipse"})
    with pytest.raises(ConfigError, match=r"controller.params.file.*not the experiment's path"):
        build(config)


def test_a_file_that_is_not_a_design_is_refused_with_its_name(design, tmp_path):
    config = load_config(design)
    two_joints = {"format": "nnrobust-excitation/1", "q0": [0, 0], "a": [[0]], "b": [[0]], "frequency": 0.1}
    for text, match in (
        ("{", "not a readable JSON file"),
        ('{"format": "other"}', "not a design's record"),
        (json.dumps(two_joints), "designs 2 joints"),
    ):
        bad = tmp_path / "bad.json"
        bad.write_text(text)
        with pytest.raises(ConfigError, match=match) as err:
            build(config.replace(controller={"params": {"file": str(bad)}}))
        assert "bad.json" in str(err.value)
    with pytest.raises(ConfigError, match="give the design's record"):
        build(config.replace(controller={"kind": "joint-fourier", "params": {}}))
