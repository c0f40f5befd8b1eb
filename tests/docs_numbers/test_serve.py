"""The numbers docs/serve.md quotes: each against its data file, and the reruns behind them."""

from tests.docs_numbers.common import (
    _serve,
    quoted_figures_test,
)

QUOTES: list[tuple] = [
    (
        "docs/serve.md",
        r"with (\d+) missed periods of\s+60 000",
        "serve_misses",
        _serve("paper-ellipse", "loaded", False, lambda r: r["misses"]),
        1.0,
    ),
    (
        "docs/serve.md",
        r"The Panda's tracking moved most where it missed least: (\d+) misses",
        "serve_misses",
        _serve("panda-ellipse", "loaded", True, lambda r: r["misses"]),
        1.0,
    ),
    (
        "docs/serve.md",
        r"both cores busy gave ([\d.]+) % more RMS error",
        "serve_misses",
        _serve("panda-ellipse", "loaded", True, lambda r: r["tracking"] - 1),
        100.0,
    ),
    (
        "docs/serve.md",
        r"while (\d+) misses without it",
        "serve_misses",
        _serve("panda-ellipse", "loaded", False, lambda r: r["misses"]),
        1.0,
    ),
    (
        "docs/serve.md",
        r"gave ([\d.]+) % less\.",
        "serve_misses",
        _serve("panda-ellipse", "loaded", False, lambda r: 1 - r["tracking"]),
        100.0,
    ),
    (
        "docs/serve.md",
        r"cut the misses from \d+ to (\d+) \(paper arm\)",
        "serve_misses",
        _serve("paper-ellipse", "loaded", True, lambda r: r["misses"]),
        1.0,
    ),
    (
        "docs/serve.md",
        r"p99 from ([\d.]+) and [\d.]+ ms",
        "serve_misses",
        _serve("paper-ellipse", "loaded", False, lambda r: r["latency_us"]["p99"]),
        1e-3,
    ),
    (
        "docs/serve.md",
        r"p99 from [\d.]+ and ([\d.]+) ms",
        "serve_misses",
        _serve("panda-ellipse", "loaded", False, lambda r: r["latency_us"]["p99"]),
        1e-3,
    ),
    (
        "docs/serve.md",
        r"ms to ([\d.]+) and [\d.]+ ms\.",
        "serve_misses",
        _serve("paper-ellipse", "loaded", True, lambda r: r["latency_us"]["p99"]),
        1e-3,
    ),
    (
        "docs/serve.md",
        r"ms to [\d.]+ and ([\d.]+) ms\.",
        "serve_misses",
        _serve("panda-ellipse", "loaded", True, lambda r: r["latency_us"]["p99"]),
        1e-3,
    ),
    (
        "docs/serve.md",
        r"\((\d+) to \d+ misses on\s+the paper arm",
        "serve_misses",
        _serve("paper-ellipse", "idle", False, lambda r: r["misses"]),
        1.0,
    ),
    (
        "docs/serve.md",
        r"\(\d+ to (\d+) misses on\s+the paper arm",
        "serve_misses",
        _serve("paper-ellipse", "idle", True, lambda r: r["misses"]),
        1.0,
    ),
    (
        "docs/serve.md",
        r"the paper arm, (\d+) to \d+ on the Panda\)",
        "serve_misses",
        _serve("panda-ellipse", "idle", False, lambda r: r["misses"]),
        1.0,
    ),
    (
        "docs/serve.md",
        r"the paper arm, \d+ to (\d+) on the Panda\)",
        "serve_misses",
        _serve("panda-ellipse", "idle", True, lambda r: r["misses"]),
        1.0,
    ),
    (
        "docs/serve.md",
        r"lateness p99 \(STATE k sent\s+after t_k\) is ([\d.]+) to",
        "serve_misses",
        lambda d: min(r["lateness_us"]["p99"] for r in d["rows"]),
        1e-3,
    ),
    (
        "docs/serve.md",
        r"after t_k\) is [\d.]+ to ([\d.]+) ms",
        "serve_misses",
        lambda d: max(r["lateness_us"]["p99"] for r in d["rows"]),
        1e-3,
    ),
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)
