"""Paired comparison of two controllers on the same draws of the uncertainty set.

A sweep runs every controller on the same samples (common random numbers: sample i is the same
plant, noise and disturbance for each), so two controllers are compared sample by sample, on
the differences d_i = m_A(i) - m_B(i) of a metric m (lower is better), never on two marginal
distributions. For N samples with a result for both:

- **median difference** med(d) with a percentile bootstrap confidence interval: the median of
  ``resamples`` resamples of the N differences with replacement (seeded, so a report reruns to
  the same digits); the interval is their (alpha/2, 1 - alpha/2) quantiles;
- **A better on k of N**: k = #{d_i < 0}, ties #{d_i = 0} reported apart;
- **sign test**: the two-sided exact binomial p-value of k successes in the N - ties untied
  pairs at probability 1/2 (``scipy.stats.binomtest``), valid for any distribution of d;
- **Wilcoxon signed-rank test**: two-sided p-value of ``scipy.stats.wilcoxon`` on the untied
  differences (assumes d symmetric about its median; reported beside the sign test), None when
  a difference is not finite;
- **significant**: the sign test's p-value below alpha (the test that assumes nothing).

Where every sample gave both controllers the same values (one plant: a case without randomness,
whose draws are the same experiment run again), the N pairs are one comparison repeated, not N:
the difference is reported, with ``plants`` = 1, and there is no test (p-values None, not
significant). Counting the repeats as samples would call any difference significant.

A run that did not complete (diverged, refused, crashed) has no metric: it counts as worse than
any completed run (+inf), so a controller that diverges where the other does not loses that
pair; a pair where neither completed is a tie. A completed run whose metric is not defined (NaN:
``rms_error_after_2s`` of a run shorter than 2 s) leaves its pair out, counted in ``undefined``:
it is neither better nor worse.
"""

from __future__ import annotations

import math

import numpy as np

METRIC = "rms_error_after_2s"
RESAMPLES = 10_000
ALPHA = 0.05
BOOTSTRAP_MAX = 50_000
"""Pairs up to which the interval is bootstrapped (10^4 resamples of 5 x 10^4 take about 10 s);
beyond, the order-statistic interval of the median, exact and as cheap as a sort."""

METHOD = (
    "paired by sample (common random numbers); d = A - B (lower is better); median of d with a "
    "{confidence:g} % percentile bootstrap interval ({resamples} resamples, seed {seed}); "
    "A better on k of N (d < 0); two-sided exact sign test on the untied pairs; Wilcoxon "
    "signed-rank test beside it; a run that did not complete counts as +inf"
)

ONE_PLANT = (
    "; every sample gave both the same values (one plant: the draws are the same experiment run "
    "again), so the pairs are one comparison and no test is made"
)


def _values(rows, metric: str) -> dict[int, float]:
    """Sample -> the metric: +inf where the run did not complete, NaN where it completed with the
    metric undefined.
    """
    out = {}
    for sample, status, value in zip(rows["sample"], rows["status"], rows[metric]):
        if status != "completed":
            out[int(sample)] = math.inf
        else:
            out[int(sample)] = math.nan if value is None else float(value)
    return out


def _bootstrap(d: np.ndarray, alpha: float, resamples: int, seed: int) -> tuple[float, float]:
    """The percentile bootstrap interval of median(d), in chunks of at most 10^7 draws."""
    rng, n = np.random.default_rng(seed), d.size
    chunk = max(1, 10_000_000 // n)
    medians = np.concatenate(
        [
            np.median(d[rng.integers(0, n, size=(min(chunk, resamples - i), n))], axis=1)
            for i in range(0, resamples, chunk)
        ]
    )
    low, high = np.quantile(medians, [alpha / 2, 1 - alpha / 2], method="inverted_cdf")
    return float(low), float(high)


def _order_interval(d: np.ndarray, alpha: float) -> tuple[float, float]:
    """[d_(l), d_(n+1-l)], l the largest with P(Binomial(n, 1/2) < l) <= alpha/2: covers the
    median with probability >= 1 - alpha whatever the distribution.
    """
    from scipy import stats

    n, s = d.size, np.sort(d)
    j = int(stats.binom.ppf(alpha / 2, n, 0.5))  # the least j with P(B <= j) >= alpha/2
    if stats.binom.cdf(j, n, 0.5) > alpha / 2:
        j -= 1  # the largest with P(B <= j) <= alpha/2
    low = max(j + 1, 1)
    return float(s[low - 1]), float(s[n - low])


def compare(
    frame,
    a: str,
    b: str,
    metric: str = METRIC,
    alpha: float = ALPHA,
    resamples: int = RESAMPLES,
    seed: int = 0,
) -> dict:
    """The paired comparison of controllers ``a`` and ``b`` in a sweep's rows (a pandas frame with
    ``sample``, ``controller``, ``status`` and ``metric`` columns): see the module docstring.
    """
    from scipy import stats

    va = _values(frame[frame["controller"] == a], metric)
    vb = _values(frame[frame["controller"] == b], metric)
    common = sorted(set(va) & set(vb))
    samples = [s for s in common if not (math.isnan(va[s]) or math.isnan(vb[s]))]
    x = np.array([va[s] for s in samples], dtype=float)
    y = np.array([vb[s] for s in samples], dtype=float)
    with np.errstate(invalid="ignore"):
        d = x - y
    d[np.isinf(x) & np.isinf(y)] = 0.0  # neither completed: a tie
    n = d.size
    out: dict = {
        "a": a,
        "b": b,
        "metric": metric,
        "n": n,
        "undefined": len(common) - n,
        "method": METHOD.format(confidence=100 * (1 - alpha), resamples=resamples, seed=seed),
    }
    if n == 0:
        return {**out, "median_difference": None, "interval": None, "a_better": 0, "ties": 0,
                "sign_p": None, "wilcoxon_p": None, "significant": False}  # fmt: skip
    better, ties = int(np.sum(d < 0)), int(np.sum(d == 0))
    if n > 1 and len(set(zip(x.tolist(), y.tolist()))) == 1:  # one plant: one comparison, repeated
        return {**out, "method": out["method"] + ONE_PLANT, "plants": 1, "median_difference": float(d[0]),
                "interval": [float(d[0]), float(d[0])], "a_better": better, "ties": ties, "sign_p": None,
                "wilcoxon_p": None, "significant": False}  # fmt: skip
    untied = n - ties
    sign_p = float(stats.binomtest(better, untied, 0.5).pvalue) if untied else 1.0
    if n <= BOOTSTRAP_MAX:
        low, high = _bootstrap(d, alpha, resamples, seed)
    else:  # the distribution-free interval of the median: order statistics of Binomial(n, 1/2)
        out["method"] += f"; beyond {BOOTSTRAP_MAX} pairs the order-statistic interval of the median"
        low, high = _order_interval(d, alpha)
    nonzero = d[d != 0]
    wilcoxon_p = (
        float(stats.wilcoxon(nonzero).pvalue) if nonzero.size and np.all(np.isfinite(nonzero)) else None
    )
    return {
        **out,
        "median_difference": float(np.median(d)),
        "interval": [float(low), float(high)],
        "a_better": better,
        "ties": ties,
        "sign_p": sign_p,
        "wilcoxon_p": wilcoxon_p,
        "significant": bool(sign_p < alpha),
    }


def all_pairs(frame, controllers: list[str], **options) -> list[dict]:
    """:func:`compare` for every pair of ``controllers`` (in their order: A before B)."""
    return [compare(frame, a, b, **options) for i, a in enumerate(controllers) for b in controllers[i + 1 :]]


def format_pair(entry: dict, scale: float = 1e3, unit: str = "mm") -> str:
    """One line: median difference [interval], k of N, the sign test's p-value, and whether the
    ranking is significant.
    """
    a, b, n = entry["a"], entry["b"], entry["n"]
    if not n:
        return f"{a} vs {b}: no sample with a result for both"

    def num(value) -> str:  # null in a report: not finite (runs that did not complete)
        return "inf" if value is None else f"{scale * value:.4g}"

    low, high = entry["interval"]
    if entry.get("plants") == 1:
        return (
            f"{a} - {b}: {num(entry['median_difference'])} {unit} on every one of {n} samples, one plant "
            "(the same experiment each time): no test"
        )
    verdict = "significant" if entry["significant"] else "not significant"
    wilcoxon = "" if entry["wilcoxon_p"] is None else f", Wilcoxon p = {entry['wilcoxon_p']:.3g}"
    ties = f" ({entry['ties']} ties)" if entry["ties"] else ""
    infinite = (
        " (a run that did not complete counts as +inf)"
        if None in (entry["median_difference"], low, high)
        or not all(math.isfinite(v) for v in (entry["median_difference"], low, high))
        else ""
    )
    return (
        f"{a} - {b}: median {num(entry['median_difference'])} {unit} [{num(low)}, {num(high)}]{infinite}; "
        f"{a} better on {entry['a_better']} of {n}{ties}; sign test p = {entry['sign_p']:.3g}{wilcoxon} "
        f"({verdict})"
    )
