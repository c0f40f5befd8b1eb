"""The fit on logs whose truth is known (a different true robot drawn around the URDF, the plant's
friction law, sensor noise): the base parameters within their standard errors, the physical model
physical, and the held-out residual at the noise floor."""

from __future__ import annotations

import numpy as np
import pytest

from nnrobust.model.loading import load_robot
from nnrobust.model.perturbation import perturb_inertias
from nnrobust.model.regressor import (
    ParameterLayout,
    base_parameters,
    body_problems,
    inertial_vector,
    with_inertial_vector,
)
from nnrobust.plant.friction import Friction
from nnrobust.studies.identify import fit
from nnrobust.studies.identify.signals import FilterChoice, prepare
from nnrobust.studies.identify.synthetic import FourierTrajectory, SensorFaults, synthetic_log

NOISE = 0.05


def _fitted(source, duration, seed=0, faults=SensorFaults(torque_noise=NOISE, torque_quantum=0.001)):
    model = load_robot(source, task="position").model
    n = model.nv
    true = perturb_inertias(model, relative_error=0.2, com_error=0.01, seed=seed + 10)
    friction = Friction(np.full(n, 0.05), np.full(n, 0.3))
    trajectory = FourierTrajectory.random(model, seed=seed, speed=1.5)
    log = synthetic_log(true, trajectory, duration, friction=friction, faults=faults, seed=seed)
    states = prepare(log, FilterChoice(cutoff=10.0))
    layout = ParameterLayout(tuple(model.names[1:]))
    base = base_parameters(model, layout.names[: 10 * n])
    columns = fit.base_columns(layout, base)
    split = int(0.7 * len(states.t))
    fit_rows = fit.normal_equations(model, layout, states, 0.01, slice(0, split))
    held = fit.normal_equations(model, layout, states, 0.01, slice(split, None))
    truth = fit.base_projector(layout, base) @ np.concatenate(
        [inertial_vector(true), friction.viscous, friction.coulomb]
    )
    return model, layout, base, columns, fit_rows, held, truth


@pytest.mark.parametrize("source, duration", [("three_link_planar", 30.0), ("panda", 20.0)])
def test_least_squares_finds_the_true_base_parameters_within_their_errors(source, duration):
    model, layout, base, columns, fit_rows, held, truth = _fitted(source, duration)
    names = list(base.names) + layout.names[10 * layout.n :]
    excitation = fit.identifiability(fit_rows, columns, names)
    assert excitation.unexcited == [] and excitation.condition < 1e3
    least = fit.weighted_least_squares(fit_rows, columns)
    z = (least.beta - truth) / np.sqrt(np.diag(least.covariance))
    assert np.max(np.abs(z)) < 4.5, names[int(np.argmax(np.abs(z)))]
    assert 0.4 < np.median(np.abs(z)) < 1.0  # |N(0, 1)| has median 0.674: the errors are the errors
    # the noise is the noise: its level, white, found joint by joint
    assert np.allclose(least.sigma, NOISE, rtol=0.05)


@pytest.mark.parametrize("source, duration", [("three_link_planar", 30.0), ("panda", 20.0)])
def test_the_physical_model_is_physical_and_predicts_held_out_torques_to_the_noise(source, duration):
    model, layout, base, columns, fit_rows, held, truth = _fitted(source, duration, seed=1)
    least = fit.weighted_least_squares(fit_rows, columns)
    prior = np.concatenate([inertial_vector(model), np.zeros(layout.size - 10 * layout.n)])
    phi = fit.physically_consistent(fit_rows, layout, least.sigma, prior)
    assert np.all(fit.least_pseudo_inertia_eigenvalues(phi, layout.n) >= fit.PSD_MARGIN * 0.99)
    assert body_problems(with_inertial_vector(model, phi)) == []
    assert np.all(held.rms(phi) < 1.2 * NOISE)
    # it costs the fit next to nothing where the truth is physical
    full = np.zeros(layout.size)
    full[columns] = least.beta
    assert np.all(fit_rows.rms(phi) < 1.01 * fit_rows.rms(full))


def test_the_physical_fit_stays_physical_on_a_short_noisy_log():
    """6 s of log with ten times the noise: the constrained fit's bodies stay physical and its
    friction non-negative, whatever least squares makes of the data."""
    model, layout, base, columns, fit_rows, held, truth = _fitted(
        "panda", 6.0, seed=2, faults=SensorFaults(torque_noise=0.5)
    )
    least = fit.weighted_least_squares(fit_rows, columns)
    prior = np.concatenate([inertial_vector(model), np.zeros(layout.size - 10 * layout.n)])
    phi = fit.physically_consistent(fit_rows, layout, least.sigma, prior)
    assert np.all(fit.least_pseudo_inertia_eigenvalues(phi, layout.n) > 0)
    assert np.all(phi[layout.friction_slice("viscous")] >= 0) and np.all(
        phi[layout.friction_slice("coulomb")] >= 0
    )


@pytest.mark.parametrize("source, expected", [("three_link_planar", [0]), ("panda", [0, 1])])
def test_the_armatures_no_log_separates_are_the_regrouping_rules(source, expected):
    """Khalil's regrouping of rotor inertias: a serial arm's first joint turns about an axis fixed
    in the base, so its rotor inertia and the links' moment about that axis are one base
    direction. A second joint perpendicular to the first (the Panda's) likewise: its link's
    moment about its own axis ZZ2 moves only its own torque, with q''_2, as its rotor inertia
    does. A second joint parallel to the first (the planar arm's) is not: its links' moment
    also drives the first joint's torque."""
    model = load_robot(source, task="position").model
    base = base_parameters(model, ParameterLayout(tuple(model.names[1:]), (), False).names)
    assert fit.unidentifiable_armature(model, base) == expected
