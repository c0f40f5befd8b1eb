"""The numbers docs/learning.md quotes: each against its data file, and the reruns behind them."""

from tests.docs_numbers.common import (
    _example_convergence,
    _example_median,
    _example_passed,
    _learning,
    quoted_figures_test,
)

QUOTES: list[tuple] = [
    (
        "docs/learning.md",
        r"the residual\nreaches ([\d.]+) mm",
        "example_study",
        _example_median("learned-residual"),
        1e3,
    ),
    (
        "docs/learning.md",
        r"and the torque policy ([\d.]+) mm: both",
        "example_study",
        _example_median("learned-torque"),
        1e3,
    ),
    (
        "docs/learning.md",
        r"the PD meets the whole requirement on (\d+) of 29",
        "example_study",
        _example_passed("pd"),
        1.0,
    ),
    ("docs/learning.md", r"draws\n\(([\d.]+) mm\), the NN", "example_study", _example_median("pd"), 1e3),
    ("docs/learning.md", r"the NN on (\d+) of 29", "example_study", _example_passed("nn"), 1.0),
    ("docs/learning.md", r"of 29 \(([\d.]+) mm; the error", "example_study", _example_median("nn"), 1e3),
    (
        "docs/learning.md",
        r"task-space PD on none \(([\d.]+) mm\)",
        "example_study",
        _example_median("taskpd"),
        1e3,
    ),
    (
        "docs/learning.md",
        r"\(to ([\d.]+) and [\d.]+ of their values",
        "example_study",
        _example_convergence("nn"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"\(to [\d.]+ and ([\d.]+) of their values",
        "example_study",
        _example_convergence("pd"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"at ([\d.]+) of the batch's steps per\nsecond on the paper's arm",
        "learning_env",
        _learning("paper-ellipse", "vector_over_batch"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"second on the paper's arm and ([\d.]+) on the Panda",
        "learning_env",
        _learning("panda-ellipse", "vector_over_batch"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"costs ([\d.]+) µs \(paper arm\)",
        "learning_env",
        _learning("paper-ellipse", "single_env_overhead_us"),
        1.0,
    ),
    (
        "docs/learning.md",
        r"and ([\d.]+) µs\n\(Panda\) more",
        "learning_env",
        _learning("panda-ellipse", "single_env_overhead_us"),
        1.0,
    ),
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)
