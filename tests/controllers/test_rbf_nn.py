"""The shipped function-approximating RBF network (nnrobust/controllers/laws/rbf_nn.py,
csrc/controllers/laws/rbf_nn.cpp): it learns a known uncertainty (an exact nominal model, no friction and a
constant joint torque τ_ext, so η = J M⁻¹ τ_ext), its update is the exact solution of
Ŵ' = F (φ wᵀ − κ ‖w‖ Ŵ) over a period, its compiled twin step by step and over a run, and its
configuration errors.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nnrobust import run_experiment
from nnrobust.config.presets import load_preset
from nnrobust.core.exceptions import ConfigError
from nnrobust.run import compiled
from nnrobust.run.experiment import build

CASES = {
    "paper arm, joint basis": ("paper-ellipse", {}),
    "paper arm, error basis": ("paper-ellipse", {"basis_input": "error", "centers": 3}),
    "Panda": ("panda-ellipse", {"F": 50.0, "k_z": 0.1}),
    "Panda pose": ("panda-pose", {"kappa": 0.0}),
}

TAU_EXT = [2.0, -1.5, 0.5]
"""The known joint torque the network must learn [N m]."""


def _setup(name, duration=0.01):
    preset, params = CASES[name]
    return build(
        load_preset(preset).replace(
            controller={"kind": "rbf-nn", "params": params}, simulation={"duration": duration}
        )
    )


def _known_uncertainty(F, duration=30.0):
    """The paper arm with an exact nominal model, no friction, no disturbance and τ_ext."""
    return load_preset("paper-ellipse").replace(
        nominal={"kind": "urdf", "p": None, "viscous_friction": None},
        plant={
            "friction": "scaled",
            "viscous_level": 0.0,
            "coulomb_level": 0.0,
            "disturbance": "none",
            "loads": [{"kind": "step", "time": 0.0, "torque": TAU_EXT}],
        },
        controller={"kind": "rbf-nn", "params": {"F": F}},
        simulation={"duration": duration},
    )


def test_the_network_learns_the_uncertainty_it_is_given():
    """η = J M⁻¹ τ_ext along the run: over the last 10 s ‖Ŵᵀφ‖ follows ‖η‖ to 30 % RMS (the
    additive basis cannot fit η exactly), and the tracking error over those 10 s is under a tenth
    of the same law with learning off (F = 0), which the torque pushes 0.45 m off the path."""
    learned = run_experiment(_known_uncertainty(F=1.0))
    frozen = run_experiment(_known_uncertainty(F=0.0))
    robot = build(_known_uncertainty(F=1.0)).robot
    late = learned.t > 20.0
    eta = np.array(
        [
            np.linalg.norm(robot.task_jacobian(q) @ np.linalg.solve(robot.mass(q), TAU_EXT))
            for q in learned.q[late]
        ]
    )
    miss = learned.signals["eta_hat_norm"][late] - eta
    assert np.sqrt(np.mean(miss**2) / np.mean(eta**2)) < 0.3
    e_learned, e_frozen = (np.sqrt(np.mean(np.sum(r.e[late] ** 2, axis=1))) for r in (learned, frozen))
    assert e_learned < 0.1 * e_frozen, (e_learned, e_frozen)


def test_the_weight_update_is_the_exact_solution_over_a_period():
    """One step of the law against solve_ivp of Ŵ' = F (φ wᵀ − κ ‖w‖ Ŵ) with (w, φ) held."""
    setup = _setup("paper arm, joint basis")
    law, comp = setup.controller, setup.controller.compensator
    rng = np.random.default_rng(4)
    q, v, y = setup.q0 + 0.1, rng.normal(size=3), rng.normal(size=4) * 0.1
    z = rng.normal(size=comp.state_size)
    period = 0.01
    _, z_next, _ = comp.output(q, v, y, z, period)
    w, phi = comp.BtP @ y, comp.basis(np.concatenate([q, v]))

    def rate(_, flat):
        W = flat.reshape(comp.L, comp.m, order="F")
        return (law.F * (np.outer(phi, w) - law.kappa * np.linalg.norm(w) * W)).reshape(-1, order="F")

    exact = solve_ivp(rate, (0.0, period), z, rtol=1e-12, atol=1e-14).y[:, -1]
    np.testing.assert_allclose(z_next, exact, rtol=1e-9, atol=1e-12)


@pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())
@pytest.mark.parametrize("name", list(CASES))
def test_each_compiled_step_is_its_python_twin(name):
    setup = _setup(name)
    assert compiled.twin_refusal(setup) == ""
    _, nominal, spec = compiled._prepared(setup, 0.01)
    period, module = setup.config.simulation.control_period, compiled._module()
    rng = np.random.default_rng(5)
    lower, upper = setup.robot.working_range
    for _ in range(20):
        t, q = rng.uniform(0.0, 10.0), rng.uniform(lower, upper)
        v, z = rng.uniform(-2.0, 2.0, q.size), rng.normal(size=setup.controller.state_size)
        ours = module.twin_control(nominal, spec, t, q, v, z)
        theirs = setup.controller.compute(t, q, v, z, period)
        scale = max(1.0, np.abs(theirs.tau).max())
        np.testing.assert_allclose(ours.tau, theirs.tau, rtol=0, atol=1e-10 * scale, err_msg=f"{name}: tau")
        np.testing.assert_allclose(ours.z, theirs.state, rtol=0, atol=1e-12 * np.abs(theirs.state).max())
        signals = [theirs.signals[s] for s in setup.controller.signal_names]
        np.testing.assert_allclose(ours.signals, signals, rtol=1e-10, atol=1e-14, err_msg=f"{name}: signals")


@pytest.mark.skipif(not compiled.available(), reason=compiled.unavailable_reason())
def test_the_compiled_run_is_the_python_run():
    results = {
        backend: run_experiment(
            load_preset("panda-ellipse").replace(
                controller={"kind": "rbf-nn"}, simulation={"duration": 0.5, "backend": backend}
            )
        )
        for backend in ("compiled", "python")
    }
    assert results["compiled"].backend == "compiled"
    np.testing.assert_allclose(results["compiled"].q, results["python"].q, rtol=0, atol=1e-9)
    for name in ("eta_hat_norm", "weights_norm"):
        np.testing.assert_allclose(
            results["compiled"].signals[name], results["python"].signals[name], atol=1e-9
        )


@pytest.mark.parametrize(
    "params, message",
    [
        ({"damping_ratio": 0.5}, r"controller.params.damping_ratio: 0.5 is outside"),
        ({"centers": 2.5}, r"controller.params.centers: expected a whole number"),
        ({"error_range": [0.1]}, r"controller.params.error_range: needs 2 entries"),
        ({"basis_input": "task"}, r"controller.params.basis_input: expected one of 'joint', 'error'"),
        ({"F": float("nan")}, r"controller.params.F: nan is outside"),
    ],
)
def test_bad_parameters_are_named(params, message):
    with pytest.raises(ConfigError, match=message):
        load_preset("paper-ellipse").replace(controller={"kind": "rbf-nn", "params": params})
