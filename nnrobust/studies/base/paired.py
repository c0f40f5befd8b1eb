"""Paired comparison of two controllers on the same draws of the uncertainty set.

A sweep runs every controller on the same samples (common random numbers: sample i is the same
plant, noise and disturbance for each), so two controllers are compared sample by sample, on
the differences d_i = m_A(i) - m_B(i) of a metric m (lower is better), never on two marginal
distributions. For N samples with a result for both:

- **median difference** med(d) with a distribution-free confidence interval of the median: the
  order statistics [d_(l), d_(N+1-l)], l the largest with P(Binomial(N, 1/2) < l) <= alpha/2,
  which cover the median with probability >= 1 - alpha whatever the distribution of d (its exact
  coverage, 1 - 2 P(Binomial(N, 1/2) < l), is reported: 98.8 % at N = 11). Below N = 6 no two order
  statistics reach 1 - alpha: the interval is [min, max] and its coverage, 1 - 2^(1-N), is said.
  (A percentile bootstrap of the median covers about 93 % at the N studies use:
  benchmarks/interval_coverage.py.)
- **effect size**: the median of the per-draw ratios m_A(i) / m_B(i) (both completed, m_B > 0)
  with the same order-statistic interval: "A's error is r times B's on the typical draw"; and
  the ratio of the two medians, for the reader who compares them;
- **A better on k of N**: k = #{d_i < 0}, ties #{d_i = 0} reported apart;
- **sign test**: the two-sided exact binomial p-value of k successes in the N - ties untied
  pairs at probability 1/2 (``scipy.stats.binomtest``), valid for any distribution of d; and the
  **least p attainable** at that N, min(1, 2^(1-(N - ties))): where it is not below alpha no
  outcome of these draws could be significant, and the comparison says so;
- **Wilcoxon signed-rank test**: two-sided p-value of ``scipy.stats.wilcoxon`` on the untied
  differences (assumes d symmetric about its median; reported beside the sign test), None when
  a difference is not finite;
- **Holm's correction** (:func:`all_pairs`): a case compares every pair of its controllers, so
  each sign test's p-value is also given Holm-adjusted over those pairs (``holm_p``: the
  step-down family-wise correction), and **significant** is the adjusted p-value below alpha;
  a single comparison (:func:`compare`) is significant when its own p-value is.

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
"""Resamples of :func:`bootstrap_interval` (kept for the coverage benchmark, no longer reported)."""
ALPHA = 0.05

METHOD = (
    "paired by sample (common random numbers); d = A - B (lower is better); median of d with its "
    "distribution-free order-statistic interval (nominal {confidence:g} %, its exact coverage "
    "beside it); the median of the per-draw ratios A / B with the same interval; A better on k of N "
    "(d < 0); two-sided exact sign test on the untied pairs, with the least p attainable at that N; "
    "Wilcoxon signed-rank test beside it; a run that did not complete counts as +inf"
)
HOLM = "; significance after Holm's correction over the case's {pairs} pairs"

ONE_PLANT = (
    "; every sample gave both the same values (one plant: the draws are the same experiment run "
    "again), so the pairs are one comparison and no test is made"
)


def metric_values(rows, metric: str) -> dict[int, float]:
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


def bootstrap_interval(d: np.ndarray, alpha: float, resamples: int, seed: int) -> tuple[float, float]:
    """The percentile bootstrap interval of median(d), in chunks of at most 10^7 draws (what the
    comparisons reported before the order-statistic interval; benchmarks/interval_coverage.py
    measures both).
    """
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


def order_rank(n: int, alpha: float) -> int:
    """l, the largest with P(Binomial(n, 1/2) < l) <= alpha/2 (at least 1): [d_(l), d_(n+1-l)]
    covers the median with probability >= 1 - alpha where l > 1 exists, else it is [min, max].
    """
    from scipy import stats

    j = int(stats.binom.ppf(alpha / 2, n, 0.5))  # the least j with P(B <= j) >= alpha/2
    if stats.binom.cdf(j, n, 0.5) > alpha / 2:
        j -= 1  # the largest with P(B <= j) <= alpha/2
    return max(j + 1, 1)


def order_coverage(n: int, alpha: float) -> float:
    """The exact coverage of the order-statistic interval of the median of n draws:
    1 - 2 P(Binomial(n, 1/2) < l), whatever the (continuous) distribution.
    """
    from scipy import stats

    return float(1 - 2 * stats.binom.cdf(order_rank(n, alpha) - 1, n, 0.5))


def order_interval(d: np.ndarray, alpha: float) -> tuple[float, float]:
    """[d_(l), d_(n+1-l)] (:func:`order_rank`): covers the median with probability
    >= min(1 - alpha, :func:`order_coverage`) whatever the distribution.
    """
    n, s = d.size, np.sort(d)
    low = order_rank(n, alpha)
    return float(s[low - 1]), float(s[n - low])


def least_p(untied: int) -> float:
    """The least two-sided sign-test p-value ``untied`` pairs can give: every pair one way."""
    return min(1.0, 2.0 * 0.5**untied) if untied else 1.0


def holm(pvalues: list[float | None]) -> list[float | None]:
    """Holm's step-down adjusted p-values of a family of tests (None: no test, left out): the
    i-th smallest of m is multiplied by m - i + 1, made non-decreasing, capped at 1.
    """
    tested = sorted((p, i) for i, p in enumerate(pvalues) if p is not None)
    m, out, running = len(tested), list(pvalues), 0.0
    for rank, (p, i) in enumerate(tested):
        running = max(running, min(1.0, (m - rank) * p))
        out[i] = running
    return out


def _ratios(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The per-draw ratios x_i / y_i where both completed and y_i > 0."""
    keep = np.isfinite(x) & np.isfinite(y) & (y > 0)
    return x[keep] / y[keep]


def compare(frame, a: str, b: str, metric: str = METRIC, alpha: float = ALPHA) -> dict:
    """The paired comparison of controllers ``a`` and ``b`` in a sweep's rows (a pandas frame with
    ``sample``, ``controller``, ``status`` and ``metric`` columns): see the module docstring.
    """
    from scipy import stats

    va = metric_values(frame[frame["controller"] == a], metric)
    vb = metric_values(frame[frame["controller"] == b], metric)
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
        "method": METHOD.format(confidence=100 * (1 - alpha)),
    }
    empty = {"interval_coverage": None, "ratio": None, "ratio_interval": None, "ratio_of_medians": None,
             "sign_p": None, "least_p": None, "wilcoxon_p": None, "significant": False}  # fmt: skip
    if n == 0:
        return {**out, **empty, "median_difference": None, "interval": None, "a_better": 0, "ties": 0}
    better, ties = int(np.sum(d < 0)), int(np.sum(d == 0))
    finite = np.isfinite(x) & np.isfinite(y)
    medians = (np.median(x[finite]), np.median(y[finite])) if finite.any() else (math.nan, math.nan)
    ratio_of_medians = float(medians[0] / medians[1]) if medians[1] > 0 else None
    if n > 1 and len(set(zip(x.tolist(), y.tolist()))) == 1:  # one plant: one comparison, repeated
        ratios = _ratios(x[:1], y[:1])
        return {**out, **empty, "method": out["method"] + ONE_PLANT, "plants": 1,
                "median_difference": float(d[0]), "interval": [float(d[0]), float(d[0])], "a_better": better,
                "ties": ties, "ratio": float(ratios[0]) if ratios.size else None,
                "ratio_of_medians": ratio_of_medians}  # fmt: skip
    untied = n - ties
    sign_p = float(stats.binomtest(better, untied, 0.5).pvalue) if untied else 1.0
    low, high = order_interval(d, alpha)
    ratios = _ratios(x, y)
    nonzero = d[d != 0]
    wilcoxon_p = (
        float(stats.wilcoxon(nonzero).pvalue) if nonzero.size and np.all(np.isfinite(nonzero)) else None
    )
    return {
        **out,
        "median_difference": float(np.median(d)),
        "interval": [float(low), float(high)],
        "interval_coverage": order_coverage(n, alpha),
        "ratio": float(np.median(ratios)) if ratios.size else None,
        "ratio_interval": list(order_interval(ratios, alpha)) if ratios.size else None,
        "ratio_of_medians": ratio_of_medians,
        "a_better": better,
        "ties": ties,
        "sign_p": sign_p,
        "least_p": least_p(untied),
        "wilcoxon_p": wilcoxon_p,
        "significant": bool(sign_p < alpha),
    }


def all_pairs(frame, controllers: list[str], alpha: float = ALPHA, **options) -> list[dict]:
    """:func:`compare` for every pair of ``controllers`` (in their order: A before B), each sign
    test's p-value Holm-adjusted over the pairs (``holm_p``), ``significant`` on the adjusted one.
    """
    pairs = [
        compare(frame, a, b, alpha=alpha, **options)
        for i, a in enumerate(controllers)
        for b in controllers[i + 1 :]
    ]
    for pair, adjusted in zip(pairs, holm([p["sign_p"] for p in pairs])):
        pair["holm_p"] = adjusted
        pair["significant"] = adjusted is not None and adjusted < alpha
        pair["method"] += HOLM.format(pairs=len(pairs))
    return pairs


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
    if entry.get("least_p") is not None and entry["least_p"] >= ALPHA:
        verdict = f"not significant: at N = {n} no outcome could be, the least p is {entry['least_p']:.3g}"
    wilcoxon = "" if entry["wilcoxon_p"] is None else f", Wilcoxon p = {entry['wilcoxon_p']:.3g}"
    if entry.get("holm_p") is not None:
        wilcoxon = f", Holm-adjusted p = {entry['holm_p']:.3g}{wilcoxon}"
    ties = f" ({entry['ties']} ties)" if entry["ties"] else ""
    infinite = (
        " (a run that did not complete counts as +inf)"
        if None in (entry["median_difference"], low, high)
        or not all(math.isfinite(v) for v in (entry["median_difference"], low, high))
        else ""
    )
    coverage = entry.get("interval_coverage")
    cover = f" ({100 * coverage:.3g} % interval)" if coverage is not None else ""
    ratio = entry.get("ratio")
    effect = ""
    if ratio is not None:
        r_low, r_high = entry.get("ratio_interval") or (ratio, ratio)
        effect = f"; {a} / {b} = {ratio:.3g} [{r_low:.3g}, {r_high:.3g}] on the typical draw"
    return (
        f"{a} - {b}: median {num(entry['median_difference'])} {unit} [{num(low)}, {num(high)}]{cover}"
        f"{infinite}{effect}; {a} better on {entry['a_better']} of {n}{ties}; sign test p = "
        f"{entry['sign_p']:.3g}{wilcoxon} ({verdict})"
    )
