"""The numbers docs/robots.md quotes: each against its data file, and the reruns behind them."""

from tests.docs_numbers.common import (
    _ratio,
    quoted_figures_test,
)

QUOTES: list[tuple] = [
    ("docs/robots.md", r"the UR5, (\d+)–\d+× better than no-u0", "arm_presets", _ratio("panda-pose"), 1.0),
    ("docs/robots.md", r"the UR5, \d+–(\d+)× better than no-u0", "arm_presets", _ratio("panda-ellipse"), 1.0),
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)
