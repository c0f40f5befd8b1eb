"""Paired comparisons (nnrobust.paired) against scipy and known distributions: the sign test is
scipy's exact binomial test, the Wilcoxon p-value scipy's, the intervals cover the true median
as often as they claim, and a run that did not complete loses its pair."""

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from nnrobust.paired import _order_interval, all_pairs, compare, format_pair


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


@pytest.mark.parametrize("interval", ["bootstrap", "order statistics"])
def test_the_interval_covers_the_true_median_as_often_as_it_claims(interval):
    """200 experiments of 60 pairs, d ~ N(1, 1): the 95 % interval must cover 1 in at least 88 %
    of them (the binomial 0.1 % lower tail of 200 x 0.95 is 178)."""
    rng = np.random.default_rng(11)
    covered = 0
    for i in range(200):
        d = rng.normal(1.0, 1.0, 60)
        if interval == "bootstrap":
            entry = compare(_frame(d, np.zeros(60)), "A", "B", resamples=2000, seed=i)
            low, high = entry["interval"]
        else:
            low, high = _order_interval(d, 0.05)
        covered += low <= 1.0 <= high
    assert covered >= 178, covered


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
