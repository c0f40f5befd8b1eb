"""The numbers docs/plant.md quotes: each against its data file, and the reruns behind them."""

from tests.docs_numbers.common import (
    _convergence,
    _drift_ratio,
    quoted_figures_test,
)

QUOTES: list[tuple] = [
    (
        "docs/plant.md",
        r"Quartering θ cuts the drift\s+(\d+)×",
        "adaptive_step",
        _drift_ratio(0.02, 0.005),
        1.0,
    ),
    (
        "docs/plant.md",
        r"Quartering θ cuts the drift\s+\d+× and (\d+)×",
        "adaptive_step",
        _drift_ratio(0.04, 0.01),
        1.0,
    ),
    (
        "docs/plant.md",
        r"its chatter medians differ by ([\d.]+) % between",
        "plant_convergence",
        _convergence("paper-line", "torque_chatter_median_difference"),
        1e2,
    ),
    (
        "docs/plant.md",
        r"between the steps \(p = ([\d.]+)\)",
        "plant_convergence",
        _convergence("paper-line", "torque_chatter_p"),
        1.0,
    ),
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)
