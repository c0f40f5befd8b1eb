"""Properties (--require), their margins, and the statements a sweep makes about them: the exact
binomial (Clopper-Pearson) bound and Wilks' quantile bound, against closed forms and scipy."""

import json
import math

import numpy as np
import pytest
from scipy.stats import beta as beta_distribution
from scipy.stats import binom

from nnrobust.core.exceptions import ConfigError
from nnrobust.run.properties import (
    clopper_pearson_upper,
    run_properties,
    samples_needed,
    wilks_upper,
)


def test_the_sample_sizes_are_the_exact_binomial_ones():
    """No failure: N >= ln(1/beta) / ln(1/(1 - epsilon)), 59 at 5 % / 5 %; k failures: the least N
    with BinomCDF(k; N, epsilon) <= beta (checked one below)."""
    assert samples_needed(0.05, 0.05) == 59 == math.ceil(math.log(1 / 0.05) / math.log(1 / 0.95))
    for eps, b, k in [(0.05, 0.05, 1), (0.01, 0.05, 0), (0.1, 0.01, 3), (0.05, 0.1, 2)]:
        n = samples_needed(eps, b, k)
        assert binom.cdf(k, n, eps) <= b < binom.cdf(k, n - 1, eps)
    assert samples_needed(0.05, 0.05, 1) == 93


def test_planning_is_a_bisection_that_agrees_with_the_certificate():
    """The planned N is the least whose Clopper-Pearson bound, computed as the certificate computes
    it, is at most epsilon; 10000 failures plan at once (N counted up one at a time: 23 s here, and
    for hours at epsilon = 1e-6)."""
    import time

    start = time.perf_counter()
    n = samples_needed(0.05, 0.05, 10_000)
    assert time.perf_counter() - start < 1.0
    assert clopper_pearson_upper(10_000, n, 0.05) <= 0.05 < clopper_pearson_upper(10_000, n - 1, 0.05)
    assert binom.cdf(10_000, n, 0.05) <= 0.05 < binom.cdf(10_000, n - 1, 0.05)
    assert samples_needed(0.01, 1e-9, 100) == 17301  # a confidence of 1 - 1e-9 is computed, not rounded


@pytest.mark.parametrize(
    "claim, words",
    [
        (
            (1e-6, 0.05, 10_000),
            "--epsilon: P(fail) <= 1e-06 with confidence 0.95 and up to 10000 failures needs more "
            "than 1,000,000 samples, more rows than a sweep may have; give --epsilon >= 0.0102 or "
            "fewer --failures",
        ),
        (
            (1e-300, 0.05, 0),
            "needs more than 1,000,000 samples, more rows than a sweep may have; give --epsilon >= 3e-06",
        ),
        ((0.9999999, 1e-300, 0), "--epsilon: P(fail) <= 0.9999999 says next to nothing"),
        ((0.05, 1e-300, 0), "--beta: 1e-300 asks a confidence closer to 1 than double precision can bound"),
        ((0.05, 0.9, 0), "--beta: 0.9 is a confidence 1 - BETA below one half, which proves nothing"),
    ],
)
def test_a_claim_no_sweep_can_make_or_that_says_nothing_is_refused(claim, words):
    """Absurd sample sizes (epsilon 1e-300 raised ZeroDivisionError; 1e-6 with 10000 failures counted
    for hours) and vacuous claims ("P(fail) <= 1 with confidence 1" was printed) are one line each,
    naming the option and what would be valid."""
    with pytest.raises(ConfigError) as err:
        samples_needed(*claim)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_the_sweep_command_refuses_such_a_claim_in_one_line(tmp_path, capsys):
    from nnrobust.cli import main

    sweep = tmp_path / "s.toml"
    sweep.write_text('name = "c"\nbase = "paper-ellipse"\ncontrollers = ["nn"]\nsamples = 6\n')
    require = ["--require", "rms_error<=0.05", "--out", str(tmp_path / "out")]
    for claim in (
        ["--epsilon", "1e-300", "--beta", "0.05"],
        ["--epsilon", "1e-6", "--beta", "0.05", "--failures", "10000"],
    ):
        assert main(["sweep", str(sweep), *require, *claim]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("nnrobust: error: --epsilon: P(fail) <= "), err
    assert not (tmp_path / "out").exists()


def test_a_confidence_never_prints_as_certainty():
    from nnrobust.run.properties import confidence_text

    assert [confidence_text(b) for b in (0.05, 1e-6, 5e-7, 1e-9)] == [
        "0.95",
        "0.999999",
        "1 - 5e-07",
        "1 - 1e-09",
    ]


def test_the_clopper_pearson_bound_is_the_beta_quantile():
    """k = 0 has the closed form 1 - beta^(1/N); k > 0 is Beta^-1(1 - beta; k + 1, N - k), and the
    bound makes the observed k (or fewer) exactly beta-likely."""
    assert clopper_pearson_upper(0, 59, 0.05) == pytest.approx(1 - 0.05 ** (1 / 59), rel=1e-12)
    for k, n in [(1, 93), (3, 40), (10, 200)]:
        p = clopper_pearson_upper(k, n, 0.05)
        assert p == pytest.approx(beta_distribution.ppf(0.95, k + 1, n - k), rel=1e-12)
        assert binom.cdf(k, n, p) == pytest.approx(0.05, rel=1e-6)
    assert clopper_pearson_upper(5, 5, 0.05) == 1.0


def test_wilks_bound_is_the_order_statistic_that_covers_the_quantile():
    """With N = 59 the 95 % quantile is bounded with 95 % confidence by the largest sample; with
    more samples by a lower order statistic; too few samples bound nothing."""
    values = list(np.random.default_rng(0).normal(size=59))
    assert wilks_upper(values, 0.95, 0.05) == max(values)
    values = list(np.random.default_rng(1).normal(size=500))
    bound = wilks_upper(values, 0.95, 0.05)
    r = sorted(values).index(bound) + 1
    assert binom.cdf(r - 1, 500, 0.95) >= 0.95 > binom.cdf(r - 2, 500, 0.95)
    assert wilks_upper(values[:20], 0.95, 0.05) is None


def test_margins_are_signed_and_normalised():
    (error,) = run_properties(["rms_error_after_2s<=0.05"])
    assert error.margin({"status": "completed", "rms_error_after_2s": 0.04}) == pytest.approx(0.2)
    assert error.margin({"status": "completed", "rms_error_after_2s": 0.06}) == pytest.approx(-0.2)
    assert error.margin({"status": "diverged", "rms_error_after_2s": 0.01}) == -math.inf
    assert error.margin({"status": "completed", "rms_error_after_2s": float("nan")}) == -math.inf
    (runaway,) = run_properties(["runaway==false"])
    assert runaway.margin({"status": "completed", "runaway": False}) == 1.0
    assert runaway.margin({"status": "completed", "runaway": True}) == -1.0
    (strict,) = run_properties(["max_torque_ratio<1"])
    assert not strict.holds({"status": "completed", "max_torque_ratio": 1.0})
    assert run_properties(["max_torque_ratio<=1"])[0].holds({"status": "completed", "max_torque_ratio": 1.0})


@pytest.mark.parametrize(
    "texts, words",
    [
        (["rms_error<0.05 mm"], "is not METRIC OP VALUE"),
        (["rms_eror_after_2s<=0.05"], "no metric 'rms_eror_after_2s'; did you mean 'rms_error_after_2s'?"),
        (["rms_error<=nan"], "the bound must be a finite number"),
        (["rms_error<=fast"], "'fast' is not a number"),
        (["runaway<=1"], "runaway is true or false: compare it with == or !="),
        (["rms_error<=1", "rms_error<=1"], "names a property twice"),
    ],
)
def test_bad_properties_get_one_line_errors(texts, words):
    with pytest.raises(ConfigError, match=".*") as err:
        run_properties(texts)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_a_sweep_certifies_each_controller_from_its_rows(scheduler, tmp_path, capsys):
    """--require with --epsilon/--beta: N and k are the rows', p_upper scipy's exact bound; a sweep
    too small for the claim is refused before anything runs unless --allow-small."""
    pytest.importorskip("distributed")
    from nnrobust.cli import main
    from nnrobust.studies.sweep import read_results

    sweep = tmp_path / "s.toml"
    sweep.write_text(
        'name = "c"\nbase = "paper-ellipse"\ncontrollers = ["nn", "no-u0"]\nsamples = 6\n'
        'seed = 2\n[set]\n"simulation.duration" = 2.2\n[vary]\n'
        '"plant.disturbance_scale" = {uniform = [0.0, 3.0]}\n'
    )
    claim = ["--require", "rms_error_after_2s<=0.02", "--epsilon", "0.05", "--beta", "0.05"]
    assert main(["sweep", str(sweep), "--out", str(tmp_path / "out"), *claim]) == 2
    err = capsys.readouterr().err
    assert "needs N >= 59 samples with at most 0 failures; the sweep draws 6" in err
    assert not (tmp_path / "out").exists()
    assert (
        main(
            [
                "sweep",
                str(sweep),
                "--out",
                str(tmp_path / "out"),
                "--scheduler",
                scheduler,
                "--allow-small",
                *claim,
            ]
        )
        == 0
    )
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    frame = read_results(tmp_path / "out")
    for controller in ("nn", "no-u0"):
        rows = frame[frame["controller"] == controller]
        failures = int(((rows["status"] != "completed") | ~(rows["rms_error_after_2s"] <= 0.02)).sum())
        (certificate,) = summary["controllers"][controller]["certificates"]
        assert (certificate["N"], certificate["k"]) == (6, failures)
        expected = 1.0 if failures == 6 else beta_distribution.ppf(0.95, failures + 1, 6 - failures)
        assert certificate["p_upper"] == pytest.approx(expected, rel=1e-12)
        assert certificate["holds"] is False  # six samples prove nothing at 5 %
    assert "P(rms_error_after_2s<=0.02 fails) <=" in capsys.readouterr().out


def test_sequential_stopping_ends_a_refuted_claim_and_keeps_the_rest(scheduler, tmp_path, capsys):
    """--stop-early: no-u0 fails every sample (its error is hundreds of mm), so its claim is
    refuted by its first rows (p_upper(k, 20) > epsilon for any k >= 1) and its other rows are not
    run; the NN's rows, which do not refute it, all run. The certificates say what happened, and a
    resumed sweep does not run the refuted rows either."""
    pytest.importorskip("distributed")
    from nnrobust.cli import main
    from nnrobust.studies.sweep import read_results

    sweep = tmp_path / "s.toml"
    sweep.write_text(
        'name = "c"\nbase = "paper-ellipse"\ncontrollers = ["nn", "no-u0"]\nsamples = 20\n'
        'seed = 2\n[set]\n"simulation.duration" = 2.2\n[vary]\n'
        '"plant.disturbance_scale" = {uniform = [0.5, 1.5]}\n'
    )
    claim = ["--require", "rms_error_after_2s<=0.05", "--epsilon", "0.05", "--beta", "0.05", "--allow-small"]
    out = tmp_path / "out"
    assert (
        main(["sweep", str(sweep), "--out", str(out), "--scheduler", scheduler, "--stop-early", *claim]) == 0
    )
    frame = read_results(out)
    nn, no_u0 = (frame[frame["controller"] == c] for c in ("nn", "no-u0"))
    assert len(nn) == 20 and (nn["rms_error_after_2s"] <= 0.05).all()
    k = int((no_u0["rms_error_after_2s"] > 0.05).sum())
    assert k == len(no_u0) and 1 <= len(no_u0) <= 10
    assert clopper_pearson_upper(1, 20, 0.05) > 0.05  # one failure already refutes 20 samples
    summary = json.loads((out / "summary.json").read_text())
    (stopped,) = summary["controllers"]["no-u0"]["certificates"]
    assert (stopped["N"], stopped["k"], stopped["planned"], stopped["holds"]) == (len(no_u0), k, 20, False)
    assert "sequential stopping: stopped after" in stopped["method"]
    (full,) = summary["controllers"]["nn"]["certificates"]
    assert full["N"] == 20 and "planned" not in full
    assert f"{20 - len(no_u0)} not run (claim already refuted)" in capsys.readouterr().err
    assert (
        main(["sweep", str(sweep), "--out", str(out), "--scheduler", scheduler, "--stop-early", *claim]) == 0
    )
    assert len(read_results(out)) == 20 + len(no_u0)
    assert "0 rows computed" in capsys.readouterr().err


def test_sequential_stopping_needs_a_claim(tmp_path, capsys):
    from nnrobust.cli import main

    assert main(["sweep", "paper-robustness", "--out", str(tmp_path / "o"), "--stop-early"]) == 2
    assert "--stop-early: stops once a claim is refuted" in capsys.readouterr().err
