"""The uncertainty of the estimate: a confidence region for the base parameters at a stated level,
and the test that decides how its covariance is computed (docs/identification.md, "Confidence").

The weighted least-squares estimate has covariance (sum_j G_j / sigma_j^2)^-1 when each joint's
residual is white. A real log's is not: resampling jittered stamps averages neighbours, a
sensor filters, the model misses something slow. So each joint's residual is first tested for
whiteness (Ljung-Box over :data:`LAGS` lags, at level :data:`WHITENESS_LEVEL`). Where it is white
the covariance is the classical one. Where it is not, the joint's noise variance is replaced by its
*long-run* variance, r_j sigma_j^2, with r_j = sum over all lags of the residual's autocorrelation,
estimated by batch means (the variance of means over blocks of :data:`BLOCK_SECONDS`): for
regressors that vary slowly against the noise's correlation time (a trajectory under the filter's
cut-off, noise correlated over milliseconds), the estimate's covariance is then

    C = Gw^-1 (sum_j r_j G_j / sigma_j^2) Gw^-1,   Gw = sum_j G_j / sigma_j^2,

the sandwich form of a heteroscedastic-and-autocorrelation-consistent covariance with one
correction per joint, which needs only the normal equations. The region at confidence 1 - alpha
is the ellipsoid (beta - beta_hat)^T C^-1 (beta - beta_hat) <= chi2_p(1 - alpha); each parameter's
marginal interval is beta_hat_i +- z_(1 - alpha/2) sqrt(C_ii). ``benchmarks/identify_calibration.py``
measures how often the region holds the truth on synthetic logs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.stats

from .fit import NormalEquations

LAGS = 20
"""Lags of the Ljung-Box whiteness test."""

WHITENESS_LEVEL = 0.01
"""A joint's residual is white unless the Ljung-Box test rejects it at this level."""

BLOCK_SECONDS = 0.2
"""The blocks of the batch-means long-run variance [s]: long against the noise's correlation
time (milliseconds), short against the log (dozens of blocks)."""


@dataclass(frozen=True)
class ConfidenceRegion:
    """A confidence region for the base parameters.

    Attributes:
        level: 1 - alpha.
        center: the estimate.
        covariance: C (module docstring).
        radius2: chi2_p(1 - alpha), the ellipsoid's squared radius in C's metric.
        white: per joint, whether its residual passed the whiteness test.
        whiteness_p: per joint, the Ljung-Box p-value.
        long_run: per joint, r_j (1 where white).
        method: the covariance's method, in words.

    """

    level: float
    center: np.ndarray
    covariance: np.ndarray
    radius2: float
    white: list[bool]
    whiteness_p: list[float]
    long_run: list[float]
    method: str

    def distance2(self, beta: np.ndarray) -> float:
        """(beta - center)^T C^-1 (beta - center): beta is in the region when at most ``radius2``."""
        d = np.asarray(beta) - self.center
        return float(d @ np.linalg.solve(self.covariance, d))

    def contains(self, beta: np.ndarray) -> bool:
        """Whether ``beta`` is in the region."""
        return self.distance2(beta) <= self.radius2

    def intervals(self) -> tuple[np.ndarray, np.ndarray]:
        """Each parameter's marginal interval at the region's level: (low, high)."""
        z = scipy.stats.norm.ppf(0.5 + self.level / 2)
        half = z * np.sqrt(np.maximum(np.diag(self.covariance), 0))
        return self.center - half, self.center + half


def ljung_box(e: np.ndarray, lags: int = LAGS) -> float:
    """The Ljung-Box test's p-value that ``e`` (NaN skipped as gaps) is white."""
    x = e[np.isfinite(e)]
    n = len(x)
    if n <= lags + 1:
        return 1.0
    x = x - x.mean()
    denominator = x @ x
    rho = np.array([x[: n - k] @ x[k:] / denominator for k in range(1, lags + 1)])
    q = n * (n + 2) * np.sum(rho**2 / (n - np.arange(1, lags + 1)))
    return float(scipy.stats.chi2.sf(q, lags))


def long_run_ratio(e: np.ndarray, block: int) -> float:
    """R = (long-run variance) / variance of ``e``, by batch means over blocks of ``block``
    samples (NaN samples left out of their block's mean); at least 1.
    """
    blocks = len(e) // block
    if blocks < 8:
        return 1.0
    x = e[: blocks * block].reshape(blocks, block)
    counts = np.sum(np.isfinite(x), axis=1)
    keep = counts >= block // 2
    means = np.nanmean(x[keep], axis=1)
    variance = np.nanvar(e)
    if not variance > 0 or keep.sum() < 8:
        return 1.0
    return float(max(1.0, np.mean(counts[keep]) * np.var(means, ddof=1) / variance))


def confidence_region(
    normal: NormalEquations,
    columns: np.ndarray,
    beta: np.ndarray,
    sigma: np.ndarray,
    residual: np.ndarray,
    dt: float,
    level: float = 0.95,
) -> ConfidenceRegion:
    """The region at ``level`` of the weighted least-squares estimate ``beta`` (module docstring);
    ``residual``: the fit segment's residuals, N x n (NaN: no equation).
    """
    weights = 1 / sigma**2
    Gw = normal.weighted(weights, columns)
    p_values = [ljung_box(residual[:, j]) for j in range(residual.shape[1])]
    white = [p >= WHITENESS_LEVEL for p in p_values]
    block = max(2, int(round(BLOCK_SECONDS / dt)))
    ratio = [1.0 if w else long_run_ratio(residual[:, j], block) for j, w in enumerate(white)]
    inverse = np.linalg.pinv(Gw, hermitian=True)
    if all(white):
        covariance, method = inverse, "classical: every joint's residual white (Ljung-Box)"
    else:
        middle = normal.weighted(weights * np.asarray(ratio), columns)
        covariance = inverse @ middle @ inverse
        method = (
            f"sandwich: the long-run variance (batch means over {BLOCK_SECONDS:g} s blocks) of the joints "
            "whose residual is not white (Ljung-Box)"
        )
    covariance = (covariance + covariance.T) / 2
    radius2 = float(scipy.stats.chi2.ppf(level, len(columns)))
    return ConfidenceRegion(level, np.asarray(beta), covariance, radius2, white, p_values, ratio, method)
