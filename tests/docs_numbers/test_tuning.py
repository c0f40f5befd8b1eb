"""The numbers docs/tuning.md quotes: each against its data file, and the reruns behind them."""

from tests.docs_numbers.common import (
    _best,
    _read,
    _rerun_best,
    quoted_figures_test,
)

QUOTES: list[tuple] = [
    ("docs/tuning.md", r"held-out errors NN ([\d.]+) mm", "tune_noisy_case_b", _best("nn"), 1e3),
    ("docs/tuning.md", r"errors NN [\d.]+ mm, no-u0 ([\d.]+) mm", "tune_noisy_case_b", _best("no-u0"), 1e3),
    ("docs/tuning.md", r"PD ([\d.]+) mm and sliding mode", "tune_noisy_case_b", _best("pd"), 1e3),
    ("docs/tuning.md", r"RBF network ([\d.]+) mm and\s+Slotine", "tune_noisy_case_b", _best("rbf-nn"), 1e3),
    (
        "docs/tuning.md",
        r"Slotine–Li ([\d.]+) mm \(its summary",
        "tune_noisy_case_b",
        _best("slotine-li"),
        1e3,
    ),
    (
        "docs/tuning.md",
        r"and sliding mode\s+([\d.]+) mm, each at least",
        "tune_noisy_case_b",
        _best("sliding-mode"),
        1e3,
    ),
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)


def test_the_nn_best_setting_of_the_tuning_example_reproduces():
    """docs/tuning.md's command (noisy case b): the NN's best setting, rerun on its training sample."""
    summary = _read("tune_noisy_case_b")
    _rerun_best(summary, list(summary["controllers"]), "nn")
