"""The numbers docs/robots.md quotes: each against its data file, and the reruns behind them."""

import pytest

from tests.docs_numbers.common import (
    _ratio,
    check_quote,
)

QUOTES: list[tuple] = [
    ("docs/robots.md", r"the UR5, (\d+)–\d+× better than no-u0", "arm_presets", _ratio("panda-pose"), 1.0),
    ("docs/robots.md", r"the UR5, \d+–(\d+)× better than no-u0", "arm_presets", _ratio("panda-ellipse"), 1.0),
]


@pytest.mark.parametrize("quote", QUOTES, ids=lambda quote: quote[1][:40])
def test_every_quoted_figure_matches_its_data(quote):
    """Each figure docs/robots.md quotes, against its data file."""
    check_quote(*quote)
