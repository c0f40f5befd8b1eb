"""The confidence region against what is known: the whiteness test on white and coloured noise,
the long-run variance of an AR(1) process against its closed form, and the region's coverage of
the true parameters over logs whose truth is known."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from nnrobust.model.loading import load_robot
from nnrobust.model.perturbation import perturb_inertias
from nnrobust.model.region import region_from_fit
from nnrobust.model.regressor import ParameterLayout, base_parameters, inertial_vector
from nnrobust.plant.friction import Friction
from nnrobust.studies.identify import fit
from nnrobust.studies.identify.confidence import (
    Autocorrelation,
    BlockSums,
    block_length,
    confidence_region,
    ljung_box,
    long_run_ratios,
    residual_statistics,
)
from nnrobust.studies.identify.signals import FilterChoice, prepare
from nnrobust.studies.identify.synthetic import FourierTrajectory, SensorFaults, synthetic_log


def _ar1(phi, n, seed):
    return scipy.signal.lfilter([1.0], [1.0, -phi], np.random.default_rng(seed).standard_normal(n))


def test_the_whiteness_test_tells_white_from_coloured_noise():
    white = [ljung_box(np.random.default_rng(s).standard_normal(5000)) for s in range(20)]
    assert sum(p < 0.01 for p in white) <= 2  # its level: about 1 in 100 rejected
    assert all(ljung_box(_ar1(0.3, 5000, s)) < 1e-6 for s in range(5))


def test_the_whiteness_test_summed_chunk_by_chunk_is_the_whole_series_one():
    """Autocorrelation (the fit's one pass) against ljung_box of the whole series, NaN gaps and
    chunks of every size from 1 sample on."""
    rng = np.random.default_rng(2)
    for e in (rng.standard_normal(5000), _ar1(0.2, 5000, 1), _ar1(0.05, 5000, 2)):
        e = e + 3.0  # a mean: the centring summed apart
        e[rng.random(len(e)) < 0.05] = np.nan
        streamed = Autocorrelation()
        for x in e[:50]:  # chunks shorter than the lags
            streamed.add(np.array([x]))
        cuts = np.sort(rng.choice(np.arange(51, len(e)), 60, replace=False))
        for part in np.split(e[50:], cuts - 50):
            streamed.add(part)
        assert streamed.p_value() == pytest.approx(ljung_box(e), rel=1e-9, abs=1e-12)


def _series_ratio(e: np.ndarray, block: int, regressor: np.ndarray | None = None) -> float:
    """long_run_ratios of one series in blocks (no fit: no leverage, unless ``regressor``)."""
    blocks = len(e) // block
    sums = BlockSums(
        e[: blocks * block].reshape(blocks, block).sum(axis=1)[:, None],
        np.full((blocks, 1), float(block)),
        np.zeros((blocks, 1, 1)) if regressor is None else regressor,
    )
    return float(long_run_ratios(sums, np.array([e.std()]), np.eye(1))[0])


@pytest.mark.parametrize("phi", [0.5, 0.8])
def test_the_long_run_ratio_of_an_ar1_process_is_its_closed_form(phi):
    """sum over all lags of phi^|k| = (1 + phi) / (1 - phi): 3 and 9."""
    estimates = [_series_ratio(_ar1(phi, 100_000, s), 200) for s in range(4)]
    assert np.mean(estimates) == pytest.approx((1 + phi) / (1 - phi), rel=0.1)
    assert _series_ratio(np.random.default_rng(0).standard_normal(100_000), 200) == pytest.approx(
        1.0, abs=0.25
    )


def test_the_fits_leverage_is_taken_out_of_a_fitted_residuals_ratio():
    """White noise fitted to 40 slow regressors (sines up to 1 Hz): the block sums (0.5 s) of its
    residual lose the regressors' share (39 % here), and the ratio that takes the leverage out is
    1 again (40 noises: a standard error of 0.03), where the raw batch means fall to 0.6."""
    rng = np.random.default_rng(3)
    t = np.arange(40_000) * 1e-3
    Y = np.column_stack([np.sin(2 * np.pi * k * t / 40) for k in range(1, 41)])  # 40 slow columns
    raw, corrected = [], []
    for _ in range(40):
        e = rng.standard_normal(len(t))
        fitted = e - Y @ np.linalg.lstsq(Y, e, rcond=None)[0]
        sigma = np.array([fitted.std()])
        blocks = len(t) // 500
        sums = BlockSums(
            fitted.reshape(blocks, 500).sum(axis=1)[:, None],
            np.full((blocks, 1), 500.0),
            Y.reshape(blocks, 500, -1).sum(axis=1)[:, None, :],
        )
        inverse = np.linalg.inv(Y.T @ Y / sigma[0] ** 2)  # Gw^-1, each row weighted 1 / sigma^2
        raw_sums = BlockSums(sums.residual, sums.rows, np.zeros_like(sums.regressor))
        # the raw batch means, without the clamp at 1
        raw.append(np.sum(sums.residual**2) / (blocks * 500 * sigma[0] ** 2))
        corrected.append(float(long_run_ratios(sums, sigma, inverse)[0]))
        assert long_run_ratios(raw_sums, sigma, inverse)[0] == pytest.approx(raw[-1])  # no leverage: raw
    assert np.mean(raw) < 0.7 and np.mean(corrected) == pytest.approx(1.0, abs=0.1), (raw, corrected)


def _coverage(logs: int, classical: bool = False) -> tuple[float, float]:
    """The shares of synthetic logs (a true robot 20 % off the URDF, jittered stamps, 2 % stale
    samples, quantisation) whose true base parameters lie in the 95 % region, and in its box
    (nnrobust.model.region: the region's principal coordinates, each within +-c)."""
    model = load_robot("three_link_planar").model
    layout = ParameterLayout(tuple(model.names[1:]))
    base = base_parameters(model, layout.names[:30])
    columns, P = fit.base_columns(layout, base), fit.base_projector(layout, base)
    faults = SensorFaults(torque_noise=0.05, torque_quantum=0.005, jitter=1e-4, stale=0.02)
    inside = in_box = 0
    for s in range(logs):
        true = perturb_inertias(model, relative_error=0.2, com_error=0.01, seed=100 + s)
        friction = Friction(
            np.full(3, 0.05) * (1 + 0.5 * np.random.default_rng(s).random(3)), np.full(3, 0.3)
        )
        trajectory = FourierTrajectory.random(model, seed=s, speed=1.5)
        states = prepare(
            synthetic_log(true, trajectory, 20.0, friction=friction, faults=faults, seed=s), FilterChoice()
        )
        split = int(0.7 * len(states.t))
        rows = fit.normal_equations(model, layout, states, 0.01, slice(0, split))
        least = fit.weighted_least_squares(rows, columns)
        phi = np.zeros(layout.size)
        phi[columns] = least.beta
        block = block_length(states.dt, split)
        sums, white = residual_statistics(model, layout, states, 0.01, slice(0, split), phi, columns, block)
        if classical:
            white = [1.0] * len(white)  # every joint taken for white
        region = confidence_region(rows, columns, least.beta, least.sigma, sums, white, 0.95)
        truth = P @ np.concatenate([inertial_vector(true), friction.viscous, friction.coulomb])
        inside += region.contains(truth)
        box = region_from_fit("", layout, [], 0.95, "", least.beta, region.covariance, P, phi)
        in_box += np.max(np.abs(box.coordinates(truth))) <= box.half_width
    return inside / logs, in_box / logs


def test_the_95_percent_region_holds_the_truth_about_95_percent_of_the_time():
    """20 logs: at least 17 inside the region, and inside its box (a correct 95 % set fails this
    with probability 1.6 %; the seeds are fixed). The classical covariance, which takes the
    resampled residuals for white, covers far less on the same logs: the correction is what makes
    the level true."""
    region, box = _coverage(20)
    assert region >= 17 / 20 and box >= 17 / 20
    assert max(_coverage(20, classical=True)) < 0.85
