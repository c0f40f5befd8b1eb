"""Paired comparisons (nnrobust.studies.base.paired) against scipy and known distributions: the sign test is
scipy's exact binomial test, the Wilcoxon p-value scipy's, the intervals cover the true median
as often as they claim, and a run that did not complete loses its pair."""

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from nnrobust.studies.base.paired import all_pairs, compare, format_pair


def _frame(a, b, status_a=None, status_b=None):
    n = len(a)
    return pd.DataFrame(
        {
            "sample": [*range(n), *range(n)],
            "controller": ["A"] * n + ["B"] * n,
            "status": [*(status_a or ["completed"] * n), *(status_b or ["completed"] * n)],
            "rms_error_after_2s": [*a, *b],
        }
    )


def test_a_constant_difference_is_exact():
    a = np.linspace(0.001, 0.01, 20)
    entry = compare(_frame(a, a + 0.002), "A", "B")
    assert entry["median_difference"] == pytest.approx(-0.002)
    assert entry["interval"] == pytest.approx([-0.002, -0.002])
    assert (entry["a_better"], entry["ties"], entry["n"]) == (20, 0, 20)
    assert entry["sign_p"] == pytest.approx(2 * 0.5**20)
    assert entry["significant"]
    assert "A better on 20 of 20" in format_pair(entry)


def test_the_tests_are_scipys_on_random_pairs():
    rng = np.random.default_rng(3)
    a = rng.lognormal(-5, 1, 40)
    b = a * rng.lognormal(0.1, 0.3, 40)
    entry = compare(_frame(a, b), "A", "B")
    d = a - b
    k = int(np.sum(d < 0))
    assert entry["a_better"] == k
    assert entry["sign_p"] == pytest.approx(stats.binomtest(k, 40, 0.5).pvalue, rel=1e-12)
    assert entry["wilcoxon_p"] == pytest.approx(stats.wilcoxon(d).pvalue, rel=1e-12)
    assert entry["median_difference"] == pytest.approx(np.median(d))
    low, high = entry["interval"]
    assert low <= np.median(d) <= high


def test_the_interval_covers_the_true_median_as_often_as_it_claims():
    """2000 experiments of 11 pairs (the tuned studies' certification N), d skewed (lognormal -
    1): the order-statistic interval covers the true median at least as often as its exact
    coverage says (98.8 % at N = 11; the binomial 0.1 % lower tail of 2000 x 0.988 is 1955)."""
    from nnrobust.studies.base.paired import order_coverage

    rng = np.random.default_rng(11)
    truth = 1.0 - 1.0  # median of lognormal(0, 1) is 1
    covered = 0
    for _ in range(2000):
        d = rng.lognormal(0.0, 1.0, 11) - 1.0
        entry = compare(_frame(d, np.zeros(11)), "A", "B")
        low, high = entry["interval"]
        covered += low <= truth <= high
    assert entry["interval_coverage"] == pytest.approx(order_coverage(11, 0.05))
    assert order_coverage(11, 0.05) == pytest.approx(1 - 2 * stats.binom.cdf(1, 11, 0.5))  # l = 2
    assert covered >= 1955, covered


def test_the_order_interval_is_the_binomial_one_at_every_n():
    """l is the largest with P(Binomial(N, 1/2) < l) <= 2.5 % (scipy), at least 1: below N = 6 the
    interval is [min, max] and its coverage 1 - 2^(1-N) is what is claimed."""
    from nnrobust.studies.base.paired import order_coverage, order_rank

    for n in range(1, 80):
        l = order_rank(n, 0.05)
        assert stats.binom.cdf(l - 1, n, 0.5) <= 0.025 or l == 1, n
        assert l == 1 or stats.binom.cdf(l, n, 0.5) > 0.025, n
        assert order_coverage(n, 0.05) == pytest.approx(1 - 2 * stats.binom.cdf(l - 1, n, 0.5))
    assert order_rank(5, 0.05) == 1 and order_coverage(5, 0.05) == pytest.approx(1 - 2**-4)
    assert order_rank(6, 0.05) == 1 and order_coverage(6, 0.05) == pytest.approx(1 - 2**-5)  # >= 95 %


def test_the_least_attainable_p_says_when_no_outcome_could_be_significant():
    """With 5 draws the sign test's least p is 2 / 2^5 = 0.0625 > 0.05: A better on 5 of 5 is said
    to be unable to be significant at that N."""
    a = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    entry = compare(_frame(a, a + 1.0), "A", "B")
    assert entry["sign_p"] == pytest.approx(stats.binomtest(5, 5, 0.5).pvalue) == pytest.approx(0.0625)
    assert entry["least_p"] == pytest.approx(0.0625) and not entry["significant"]
    assert "at N = 5 no outcome could be" in format_pair(entry)


def test_holms_correction_is_the_step_down_one():
    """holm() against its definition on random p-values, with untested pairs left out; all_pairs
    marks significance on the adjusted p-values."""
    from nnrobust.studies.base.paired import holm

    rng = np.random.default_rng(4)
    for _ in range(50):
        p = list(rng.uniform(0, 0.2, 6))
        p[2] = None
        tested = sorted((v, i) for i, v in enumerate(p) if v is not None)
        m = len(tested)
        expected = {}
        for rank, (v, i) in enumerate(tested):
            expected[i] = min(1.0, max((m - r) * tested[r][0] for r in range(rank + 1)))
        adjusted = holm(p)
        assert adjusted[2] is None
        assert all(adjusted[i] == pytest.approx(v) for i, v in expected.items())
    rng = np.random.default_rng(5)
    base = rng.lognormal(-5, 1, 12)
    frame = pd.DataFrame(
        {"sample": list(range(12)) * 3, "controller": ["A"] * 12 + ["B"] * 12 + ["C"] * 12,
         "status": ["completed"] * 36, "rms_error_after_2s": [*base, *(base * 1.5), *(base * 1.02)]}
    )  # fmt: skip
    pairs = all_pairs(frame, ["A", "B", "C"])
    raw = [pair["sign_p"] for pair in pairs]
    assert [pair["holm_p"] for pair in pairs] == pytest.approx(holm(raw))
    assert [pair["significant"] for pair in pairs] == [h < 0.05 for h in holm(raw)]


def test_the_effect_size_is_the_median_per_draw_ratio():
    """A's error is 1.3 times B's on every draw: the ratio is 1.3 with a zero-width interval; on
    random draws it is the median of a_i / b_i, inside its order-statistic interval."""
    b = np.linspace(0.001, 0.002, 15)
    entry = compare(_frame(1.3 * b, b), "A", "B")
    assert entry["ratio"] == pytest.approx(1.3) and entry["ratio_interval"] == pytest.approx([1.3, 1.3])
    assert entry["ratio_of_medians"] == pytest.approx(1.3)
    rng = np.random.default_rng(8)
    a, b = rng.lognormal(-5, 1, 30), rng.lognormal(-5, 1, 30)
    entry = compare(_frame(a, b), "A", "B")
    assert entry["ratio"] == pytest.approx(np.median(a / b))
    low, high = entry["ratio_interval"]
    assert low <= entry["ratio"] <= high
    assert entry["ratio_of_medians"] == pytest.approx(np.median(a) / np.median(b))


def test_a_run_that_did_not_complete_loses_its_pair_and_two_are_a_tie():
    a, b = [0.001, 0.001, 0.001, math.nan], [0.002, 0.002, 0.0, math.nan]
    entry = compare(_frame(a, b, status_b=["completed", "diverged", "completed", "diverged"],
                           status_a=["completed"] * 3 + ["refused"]), "A", "B")  # fmt: skip
    assert (entry["a_better"], entry["ties"], entry["n"]) == (2, 1, 4)  # B diverged on 1; both on 3
    assert entry["wilcoxon_p"] is None  # a difference is infinite


def test_a_completed_run_whose_metric_is_undefined_leaves_its_pair_out():
    """A run shorter than 2 s completes with rms_error_after_2s NaN: against a crash it is no
    tie and no win, the pair is left out and counted as undefined."""
    a, b = [math.nan, math.nan, 0.001], [math.nan, math.nan, 0.002]
    entry = compare(_frame(a, b, status_b=["crashed", "completed", "completed"]), "A", "B")
    assert (entry["n"], entry["undefined"], entry["a_better"], entry["ties"]) == (1, 2, 1, 0)
    none = compare(_frame(a[:2], b[:2], status_b=["crashed", "completed"]), "A", "B")
    assert (none["n"], none["undefined"], none["median_difference"]) == (0, 2, None)


def test_every_pair_once_in_order():
    frame = pd.concat([_frame([1.0, 2.0], [2.0, 3.0]), _frame([1.0, 2.0], [2.0, 3.0]).assign(
        controller=lambda f: f["controller"].map({"A": "C", "B": "D"}))])  # fmt: skip
    pairs = all_pairs(frame, ["A", "B", "C"])
    assert [(p["a"], p["b"]) for p in pairs] == [("A", "B"), ("A", "C"), ("B", "C")]
    assert pairs[1]["ties"] == 2 and not pairs[1]["significant"]


def test_one_plant_run_again_is_one_comparison_not_a_significant_test():
    """A case without randomness gives every draw the same plant: 11 identical pairs are one
    comparison repeated. The sign test would call it significant (p = 2 / 2^11); it is not tested."""
    entry = compare(_frame([0.003] * 11, [0.001] * 11), "A", "B")
    assert entry["plants"] == 1 and entry["n"] == 11
    assert entry["median_difference"] == pytest.approx(0.002)
    assert (entry["sign_p"], entry["wilcoxon_p"], entry["significant"]) == (None, None, False)
    assert "one plant" in entry["method"] and "no test" in format_pair(entry)
    # the same differences from plants that differ are a test again
    other = compare(_frame(np.linspace(0.003, 0.004, 11), np.linspace(0.001, 0.002, 11)), "A", "B")
    assert "plants" not in other and other["significant"]


def test_the_coverages_robustness_md_quotes_are_the_formulas():
    """docs/robustness.md quotes the interval's exact coverage at the studies' N."""
    import re
    from pathlib import Path

    from nnrobust.studies.base.paired import order_coverage

    text = (Path(__file__).resolve().parents[3] / "docs" / "robustness.md").read_text()
    quoted = re.search(
        r"whatever the distribution of d: ([\d.]+) % at N = 11, ([\d.]+) % at N = 29, ([\d.]+) % at N = 5",
        text,
    )
    assert quoted, "robustness.md no longer quotes the coverages"
    for value, n in zip(quoted.groups(), (11, 29, 5)):
        assert float(value) == pytest.approx(100 * order_coverage(n, 0.05), abs=0.05), n
