"""The uncertainty of the estimate: a confidence region for the base parameters at a stated level,
and the test that decides how its covariance is computed (docs/identification.md, "Confidence").

The weighted least-squares estimate has covariance (sum_j G_j / sigma_j^2)^-1 when each joint's
residual is white. A real log's is not: resampling jittered stamps averages neighbours, a
sensor filters, the model misses something slow. So each joint's residual is first tested for
whiteness (Ljung-Box over :data:`LAGS` lags, at level :data:`WHITENESS_LEVEL`). Where it is white
the covariance is the classical one. Where it is not, the joint's noise variance is replaced by its
*long-run* variance, r_j sigma_j^2, with r_j = sum over all lags of the noise's autocorrelation,
estimated by batch means over blocks of :data:`BLOCK_SECONDS` (:func:`long_run_ratios`): for
regressors that vary slowly against the noise's correlation time, the estimate's covariance is then

    C = Gw^-1 (sum_j r_j G_j / sigma_j^2) Gw^-1,   Gw = sum_j G_j / sigma_j^2,

the sandwich form of a heteroscedastic-and-autocorrelation-consistent covariance with one
correction per joint, which needs only the normal equations and per-block sums.

Two biases of batch means on a *fitted* residual are corrected or avoided. The fit absorbs the
part of the noise that looks like its regressors, which move slowly: a block sum of the residual
has the variance K_b sigma^2 - S_b^T Gw^-1 S_b of white noise (K_b rows, S_b the sum of their
regressor rows), not K_b sigma^2, a leverage that grows with the block (19 % of the variance at
0.5 s blocks on a 21 s Panda fit): each joint's ratio is divided by its share left,
1 - sum_b w_j S_bj^T Gw^-1 S_bj / sum_b K_bj. And the noise that matters is the noise at the
regressors' frequencies: a filtered acceleration's noise, M(q) times the derivative of a
low-passed noise, has its power near the cut-off and none at zero frequency, which short blocks
count and the estimate never sees; blocks of :data:`BLOCK_SECONDS` (0.5 s, a pass band of about
1 Hz) leave it out. The region at confidence 1 - alpha
is the ellipsoid (beta - beta_hat)^T C^-1 (beta - beta_hat) <= chi2_p(1 - alpha); each parameter's
marginal interval is beta_hat_i +- z_(1 - alpha/2) sqrt(C_ii). ``benchmarks/identify_calibration.py``
measures how often the region holds the truth on synthetic logs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.stats

from .fit import NormalEquations, regressor_rows

LAGS = 20
"""Lags of the Ljung-Box whiteness test."""

WHITENESS_LEVEL = 0.01
"""A joint's residual is white unless the Ljung-Box test rejects it at this level."""

BLOCK_SECONDS = 0.5
"""The blocks of the batch-means long-run variance [s]: long against the noise's correlation
time and the filter's (milliseconds, and 1/(2 pi f_c) = 16 ms at 10 Hz), so that the estimate
reads the noise at the trajectory's frequencies; short against the log (dozens of blocks). On
synthetic Panda logs the corrected ratios of blocks of 0.5 and 1 s agree within the estimate's
noise, where 0.05 to 0.2 s blocks count the acceleration's filtered noise (docs/identification.md)."""


@dataclass
class BlockSums:
    """Per block of consecutive samples and per joint: the residual's sum over the block's rows,
    the rows counted, and the sum of the regressor rows (the fitted columns) over them; what the
    residual's long-run variance and its leverage correction read (:func:`long_run_ratios`). A
    trailing part block is left out.
    """

    residual: np.ndarray
    rows: np.ndarray
    regressor: np.ndarray


class Autocorrelation:
    """A series' autocorrelations at lags 1 to ``lags``, summed chunk by chunk (memory of the
    lags only): what :func:`ljung_box` computes of the whole series, NaN samples skipped as gaps.
    """

    def __init__(self, lags: int = LAGS):
        self.lags = lags
        self.count, self.total, self.squares = 0, 0.0, 0.0
        self.products = np.zeros(lags)
        self.head = np.zeros(0)
        self.tail = np.zeros(0)

    def add(self, values: np.ndarray) -> None:
        """The next samples of the series."""
        x = np.asarray(values, dtype=float)
        x = x[np.isfinite(x)]
        if not len(x):
            return
        joined = np.concatenate([self.tail, x])
        start = len(self.tail)
        for k in range(1, self.lags + 1):  # the pairs whose later sample is in this chunk
            first = max(0, start - k)
            if first < len(joined) - k:
                self.products[k - 1] += joined[first : len(joined) - k] @ joined[first + k :]
        self.count += len(x)
        self.total += float(x.sum())
        self.squares += float(x @ x)
        if len(self.head) < self.lags:
            self.head = np.concatenate([self.head, x[: self.lags - len(self.head)]])
        self.tail = joined[-self.lags :]

    def p_value(self) -> float:
        """The Ljung-Box test's p-value that the series is white."""
        n, lags = self.count, self.lags
        if n <= lags + 1:
            return 1.0
        mean = self.total / n
        denominator = self.squares - n * mean**2
        if not denominator > 0:
            return 1.0
        k = np.arange(1, lags + 1)
        first = np.array([self.total - self.tail[len(self.tail) - j :].sum() for j in k])  # x_0..x_(n-k-1)
        later = np.array([self.total - self.head[:j].sum() for j in k])  # x_k..x_(n-1)
        rho = (self.products - mean * (first + later) + (n - k) * mean**2) / denominator
        q = n * (n + 2) * np.sum(rho**2 / (n - k))
        return float(scipy.stats.chi2.sf(q, lags))


def residual_statistics(
    model, layout, states, band: float, segment: slice, phi: np.ndarray, columns: np.ndarray, block: int
) -> tuple[BlockSums, list[float]]:
    """One pass over the residual of ``phi`` on ``states[segment]`` (:func:`.fit.regressor_rows`,
    batch by batch): its :class:`BlockSums` over blocks of ``block`` samples and each joint's
    Ljung-Box p-value. Memory: the blocks and the lags, not the segment.
    """
    length = len(states.t[segment])
    blocks, n = length // block, layout.n
    out = BlockSums(np.zeros((blocks, n)), np.zeros((blocks, n)), np.zeros((blocks, n, len(columns))))
    series = [Autocorrelation() for _ in range(n)]
    start = 0
    for Y, tau, used in regressor_rows(model, layout, states, band, segment):
        e = np.where(used, tau - Y @ phi, np.nan)
        for j in range(n):
            series[j].add(e[:, j])
        index = (start + np.arange(len(tau))) // block
        start += len(tau)
        keep = index < blocks
        if not keep.any():
            continue
        index, kept = index[keep], used[keep]
        rows = Y[keep][:, :, columns] * kept[:, :, None]
        first = np.flatnonzero(np.r_[True, index[1:] != index[:-1]])  # each block's first row here
        at = index[first]
        out.residual[at] += np.add.reduceat(np.nan_to_num(e[keep]), first, axis=0)
        out.rows[at] += np.add.reduceat(kept.astype(float), first, axis=0)
        out.regressor[at] += np.add.reduceat(rows, first, axis=0)
    return out, [s.p_value() for s in series]


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


MIN_BLOCKS = 40
"""The fewest blocks a ratio is estimated from: a fit shorter than 40 blocks of
:data:`BLOCK_SECONDS` (20 s) gets shorter blocks (its ratio's noise, about sqrt(2 / B), kept
under a quarter; shorter blocks err on the wide side, counting some of the filtered noise)."""


def block_length(dt: float, samples: int) -> int:
    """The samples of a block for a fit segment of ``samples`` at the step ``dt``: :data:`BLOCK_SECONDS`,
    or less where that leaves fewer than :data:`MIN_BLOCKS` blocks (at least 2 samples).
    """
    return max(2, min(int(round(BLOCK_SECONDS / dt)), samples // MIN_BLOCKS))


def long_run_ratios(sums: BlockSums, sigma: np.ndarray, inverse: np.ndarray) -> np.ndarray:
    """Each joint's r_j from the block sums of a fitted residual (module docstring): the mean
    squared block sum per row over sigma_j^2, with the fit's leverage taken out (1 where there are
    under 8 full blocks, or nothing is left of the variance).
    """
    counts = sums.rows.sum(axis=0)
    if len(sums.rows) < 8:
        return np.ones(len(sigma))
    leverage = np.einsum("bjp,pq,bjq->j", sums.regressor, inverse, sums.regressor)
    left = counts * sigma**2 - leverage
    ratio = np.sum(sums.residual**2, axis=0) / np.where(left > 0, left, np.nan)
    return np.where(np.isfinite(ratio) & (ratio > 0), ratio, 1.0)


def confidence_region(
    normal: NormalEquations,
    columns: np.ndarray,
    beta: np.ndarray,
    sigma: np.ndarray,
    sums: BlockSums,
    p_values: list[float],
    level: float = 0.95,
) -> ConfidenceRegion:
    """The region at ``level`` of the weighted least-squares estimate ``beta`` (module docstring)
    from the fit segment's residual statistics (:func:`residual_statistics`): its block sums over
    :func:`block_length` and each joint's whiteness p-value.
    """
    weights = 1 / sigma**2
    Gw = normal.weighted(weights, columns)
    white = [p >= WHITENESS_LEVEL for p in p_values]
    inverse = np.linalg.pinv(Gw, hermitian=True)
    ratios = long_run_ratios(sums, sigma, inverse)
    ratio = [1.0 if w else float(r) for w, r in zip(white, ratios)]
    if all(white):
        covariance, method = inverse, "classical: every joint's residual white (Ljung-Box)"
    else:
        middle = normal.weighted(weights * np.asarray(ratio), columns)
        covariance = inverse @ middle @ inverse
        method = (
            f"sandwich: the long-run variance (batch means over {BLOCK_SECONDS:g} s blocks, the fit's "
            "leverage taken out) of the joints whose residual is not white (Ljung-Box)"
        )
    covariance = (covariance + covariance.T) / 2
    radius2 = float(scipy.stats.chi2.ppf(level, len(columns)))
    return ConfidenceRegion(level, np.asarray(beta), covariance, radius2, white, p_values, ratio, method)
