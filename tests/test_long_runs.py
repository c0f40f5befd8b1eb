"""Long runs: the defaults stay bounded for 120 s with saturation; the paper's law gets flagged.

These are the acceptance runs of the honest-plant work (docs/plant.md); each takes 15-35 s.
"""

import numpy as np
import pytest

from nnrobust.config.presets import load_preset
from nnrobust.run.experiment import build, run_experiment

EFFORT = np.array([60.0, 40.0, 20.0])  # urdf/three_link_planar.urdf


def _rms(result, start, end):
    err = result.position_error()
    window = (result.t >= start) & (result.t < end)
    return float(np.sqrt(np.mean(err[window] ** 2)))


@pytest.mark.parametrize("preset", ["paper-ellipse", "paper-line"])
def test_defaults_stay_bounded_for_120_s_with_saturation(preset):
    result = run_experiment(load_preset(preset).replace(simulation={"duration": 120.0}))
    metrics = result.metrics()
    assert metrics["status"] == "completed"
    assert np.all(np.abs(result.tau) <= EFFORT + 1e-12)
    assert _rms(result, 100.0, 120.0) <= 2.0 * _rms(result, 2.0, 20.0)
    for key in ("saturated_fraction", "max_torque_ratio", "max_joint_limit_violation", "warnings"):
        assert key in metrics
    assert not metrics["runaway"] and not metrics["rho_hat_growing"]
    assert not any(w.startswith(("runaway", "rho-hat")) for w in metrics["warnings"])
    # sigma-modification bounds rho-hat: its peak over the last fifth is not above the middle's
    assert metrics["rho_hat_peak_last_fifth"] <= 1.25 * metrics["rho_hat_peak_middle"]


def test_the_papers_law_with_a_large_gain_is_flagged():
    """F = 50, eps_min = 0, sigma = 0 over 60 s: rho-hat grows without bound and the run says so."""
    config = load_preset("paper-ellipse").replace(
        nn={"F": 50.0, "eps_min": 0.0, "sigma": 0.0}, simulation={"duration": 60.0}
    )
    metrics = run_experiment(config).metrics()
    assert metrics["warnings"]
    assert metrics["rho_hat_growing"]
    assert any(w.startswith("rho-hat keeps growing") for w in metrics["warnings"])


def test_papers_law_from_a_real_run_eps_decays_exactly_and_Z_only_grows():
    """sigma = 0: eps(t_k) = eps0 e^(-gamma t_k) at every sample and every weight is non-decreasing."""
    config = load_preset("paper-ellipse-paper-law").replace(simulation={"duration": 3.0})
    setup = build(config)
    result = run_experiment(config, setup=setup)
    comp = setup.controller.compensator
    eps = result.signals["eps"]
    np.testing.assert_allclose(eps, comp.eps0 * np.exp(-comp.gamma * result.t), rtol=1e-12)
    assert np.all(np.diff(result.signals["z_norm"]) >= 0)
    assert np.all(np.diff(result.signals["rho_hat"][result.t > 0.5]) > -1e9)  # finite, recorded


def test_sigma_modification_bounds_Z_by_omega_over_sigma():
    """sigma > 0: every weight stays below sup |omega| / sigma (phi <= 1), from a real run."""
    config = load_preset("paper-ellipse").replace(simulation={"duration": 6.0})
    setup = build(config)
    result = run_experiment(config, setup=setup)
    comp, robot, trajectory = setup.controller.compensator, setup.robot, setup.trajectory
    de = np.array([robot.task_jacobian(q) @ v for q, v in zip(result.q, result.dq)]) - np.array(
        [trajectory(t)[1] for t in result.t]
    )
    omega = result.e @ np.diag(config.controller.Kp) + de @ np.diag(config.controller.Kv)
    bound = np.linalg.norm(omega, axis=1).max() / comp.sigma
    assert 0 < np.linalg.norm(result.signals["z_norm"], np.inf)
    Z = np.array([z for z in result.signals["z_norm"]])
    assert np.all(Z <= np.sqrt(comp.L) * bound)
    # each weight is a running average of its drive |w| phi_i / sigma: below its largest value
    # so far (without the leakage the weights integrate the drive and pass it within seconds)
    weights = _trace(setup).z[:, : comp.L]
    drive = np.array(
        [
            np.linalg.norm(comp.omega(y)) * comp.basis(comp.network_input(q, v, y))
            for q, v, y in zip(result.q, result.dq, _errors(result, setup))
        ]
    )
    ceiling = np.maximum.accumulate(np.maximum(drive / comp.sigma, weights[0]), axis=0)
    assert np.all(weights <= ceiling * (1 + 1e-6) + 1e-12)


def _trace(setup):
    """The run's raw trace (with the controller state z_k), on the backend run_experiment uses."""
    from nnrobust.run.experiment import choose_backend
    from nnrobust.run.simulation import simulate

    sim = setup.config.simulation
    if choose_backend(setup) == "compiled":
        from nnrobust.run.compiled import simulate_compiled

        return simulate_compiled(setup, sim.duration)
    return simulate(setup.plant, setup.controller, setup.q0, setup.v0, sim.duration, sim.control_period)


def _errors(result, setup):
    """y_k = [e, e'] as the controller saw it (ideal sensing), from the recorded states."""
    robot, trajectory = setup.robot, setup.trajectory
    out = []
    for t, q, v, e in zip(result.t, result.q, result.dq, result.e):
        out.append(np.concatenate([e, robot.task_jacobian(q) @ v - trajectory(t)[1]]))
    return out
