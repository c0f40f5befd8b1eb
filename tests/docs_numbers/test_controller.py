"""The numbers docs/controller.md quotes: each against its data file, and the reruns behind them."""

from tests.docs_numbers.common import (
    CASE_B,
    _row,
    quoted_figures_test,
)

QUOTES: list[tuple] = [
    (
        "docs/controller.md",
        r"smoothness: ([\d.]+) mm against",
        "paper_reproduction",
        _row(CASE_B, "NN, defaults"),
        1e3,
    ),
    (
        "docs/controller.md",
        r"paper's law's (\d+) mm, but",
        "paper_reproduction",
        _row(CASE_B, "NN, paper's law, ideal actuators"),
        1e3,
    ),
    (
        "docs/controller.md",
        r"tracks to ([\d.]+) mm at",
        "paper_reproduction",
        _row(CASE_B, "NN, tuned (Kp 400, Kv 40, sigma 0.5), 120 s"),
        1e3,
    ),
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)
