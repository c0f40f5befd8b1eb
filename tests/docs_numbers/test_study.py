"""The numbers docs/study.md quotes: each against its data file, and the reruns behind them."""

from tests.docs_numbers.common import (
    _busy,
    _simulated,
    _stage_wall,
    quoted_figures_test,
)

QUOTES: list[tuple] = [
    (
        "docs/study.md",
        r"the study took ([\d.]+) s of wall time",
        "study_overhead",
        lambda d: d["wall_seconds"],
        1.0,
    ),
    (
        "docs/study.md",
        r"its\nsimulations (\d+) worker-seconds",
        "study_overhead",
        _simulated(),
        1.0,
    ),
    (
        "docs/study.md",
        r"so its cost beyond its simulations is\n([\d.]+) %",
        "study_overhead",
        lambda d: d["overhead"],
        100.0,
    ),
    (
        "docs/study.md",
        r"writes\nits report in ([\d.]+) s",
        "study_overhead",
        lambda d: d["rerun_seconds"],
        1.0,
    ),
    (
        "docs/study.md",
        r"the MuJoCo draws \((\d+) s of wall time for \d+ worker",
        "study_overhead",
        _stage_wall("certify, falsify"),
        1.0,
    ),
    (
        "docs/study.md",
        r"the MuJoCo draws \(\d+ s of wall time for (\d+) worker",
        "study_overhead",
        _simulated("certify", "falsify", "certify-mujoco"),
        1.0,
    ),
    (
        "docs/study.md",
        r"both workers busy (\d+) % of it\)",
        "study_overhead",
        _busy("certify, falsify", "certify", "falsify", "certify-mujoco"),
        100.0,
    ),
    (
        "docs/study.md",
        r"took (\d+) s\nof wall time for \d+ worker-seconds",
        "study_overhead_falsify_panda",
        lambda d: d["wall_seconds"],
        1.0,
    ),
    (
        "docs/study.md",
        r"of wall time for (\d+) worker-seconds of simulation, a cost",
        "study_overhead_falsify_panda",
        _simulated(),
        1.0,
    ),
    (
        "docs/study.md",
        r"a cost beyond its simulations of ([\d.]+) %",
        "study_overhead_falsify_panda",
        lambda d: d["overhead"],
        100.0,
    ),
    (
        "docs/study.md",
        r"kept both workers busy (\d+) % of their",
        "study_overhead_falsify_panda",
        _busy("certify, falsify", "certify", "falsify"),
        100.0,
    ),
    (
        "docs/study.md",
        r"busy \d+ % of their (\d+) s\.",
        "study_overhead_falsify_panda",
        _stage_wall("certify, falsify"),
        1.0,
    ),
    (
        "docs/study.md",
        r"starting the\s+cluster and checking\s+every controller \(([\d.]+) s\)",
        "study_overhead",
        _stage_wall("checks, the cluster"),
        1.0,
    ),
    ("docs/study.md", r"seeds' tunings \((\d+) s of\s+wall", "study_overhead", _stage_wall("tune"), 1.0),
    (
        "docs/study.md",
        r"seeds' tunings \(\d+ s of\s+wall time for (\d+) worker",
        "study_overhead",
        _simulated("tune"),
        1.0,
    ),
    (
        "docs/study.md",
        r"the\s+realtime stage, alone on\s+the machine by design\) takes (\d+) s",
        "study_overhead",
        _stage_wall("export the kept laws"),
        1.0,
    ),
]


test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)
