"""The timings docs/compiled.md, docs/benchmarks.md, docs/plant.md, docs/identification.md and
README quote in prose: each against docs/data/closed_loop.json (benchmarks/closed_loop.py),
docs/data/loop_profile.json (benchmarks/loop_profile.py) or docs/data/identify_rows.json
(benchmarks/identify_rows.py), the runs its tables are rendered from."""

from tests.docs_numbers.common import quoted_figures_test

CM, BM, PM = "docs/compiled.md", "docs/benchmarks.md", "docs/plant.md"


def _us(preset, contender):
    """µs per step of one contender of closed_loop.json."""
    return lambda d: (
        1e6
        * next(r["step_seconds"] for r in d["rows"] if r["preset"] == preset and r["contender"] == contender)
    )


def _ratio(preset, a, b):
    """a's step over b's, one preset of closed_loop.json."""
    return lambda d: _us(preset, a)(d) / _us(preset, b)(d)


def _realtime(preset, contender):
    return lambda d: 1e3 / _us(preset, contender)(d)


def _hybrid_overhead(preset):
    return lambda d: _us(preset, "TaskPD, hybrid loop")(d) - _us(preset, "TaskPD, compute alone")(d)


def _part(preset, law, part):
    """µs per step of one part of loop_profile.json."""
    return lambda d: next(
        r["us_per_step"] for r in d["rows"] if (r["preset"], r["law"], r["part"]) == (preset, law, part)
    )


def _floor_step(preset):
    return _us(preset, "floor, C++")


P, Q = "paper-ellipse", "panda-ellipse"
CL, FL, PY, SL = "nnrobust, compiled loop", "floor, C++", "nnrobust, Python loop", "slotine-li, compiled loop"
MJ, HY, TP = "nnrobust, compiled, MuJoCo", "TaskPD, hybrid loop", "TaskPD, Python loop"

QUOTES: list[tuple] = [
    (CM, r"runs the paper's case \(b\) at (\d+)× real time", "closed_loop", _realtime(P, CL), 1.0),
    (CM, r"basis\) at (\d+)×: ", "closed_loop", _realtime(Q, CL), 1.0),
    (CM, r"basis\) at \d+×: ([\d.]+) times its C\+\+ floor", "closed_loop", _ratio(P, CL, FL), 1.0),
    (CM, r"basis\) at \d+×: ([\d.]+) times its C\+\+ floor", "closed_loop", _ratio(Q, CL, FL), 1.0),
    (CM, r"and (\d+) and \d+ times faster than the Python\s+loop", "closed_loop", _ratio(P, PY, CL), 1.0),
    (CM, r"and \d+ and (\d+) times faster than the Python\s+loop", "closed_loop", _ratio(Q, PY, CL), 1.0),
    (CM, r"Slotine–Li is ([\d.]+) and [\d.]+ times the floor", "closed_loop", _ratio(P, SL, FL), 1.0),
    (CM, r"Slotine–Li is [\d.]+ and ([\d.]+) times the floor", "closed_loop", _ratio(Q, SL, FL), 1.0),
    (CM, r"its law alone \(([\d.]+) µs", "loop_profile", _part(Q, "slotine-li", "law"), 1.0),
    (CM, r"the floor's whole\s+step \(([\d.]+) µs\)", "closed_loop", _floor_step(Q), 1.0),
    (CM, r"mj_step` and runs at (\d+)× and \d+× real time", "closed_loop", _realtime(P, MJ), 1.0),
    (CM, r"mj_step` and runs at \d+× and (\d+)× real time", "closed_loop", _realtime(Q, MJ), 1.0),
    (
        CM,
        r"plant: ([\d.]+)× \(paper arm\) and [\d.]+× \(Panda\) faster",
        "closed_loop",
        _ratio(P, TP, HY),
        1.0,
    ),
    (
        CM,
        r"plant: [\d.]+× \(paper arm\) and ([\d.]+)× \(Panda\) faster",
        "closed_loop",
        _ratio(Q, TP, HY),
        1.0,
    ),
    (
        CM,
        r"takes ([\d.]+) and [\d.]+ µs per step \(the closed-form",
        "closed_loop",
        _us(P, "TaskPD, compute alone"),
        1.0,
    ),  # fmt: skip
    (
        CM,
        r"takes [\d.]+ and ([\d.]+) µs per step \(the closed-form",
        "closed_loop",
        _us(Q, "TaskPD, compute alone"),
        1.0,
    ),  # fmt: skip
    (CM, r"beyond the controller: ([\d.]+) and", "closed_loop", _us(P, "hybrid loop, law replayed"), 1.0),
    (
        CM,
        r"beyond the controller: [\d.]+ and ([\d.]+) µs",
        "closed_loop",
        _us(Q, "hybrid loop, law replayed"),
        1.0,
    ),
    (CM, r"its compute plus ([\d.]+) and", "closed_loop", _hybrid_overhead(P), 1.0),
    (CM, r"its compute plus [\d.]+ and ([\d.]+) µs", "closed_loop", _hybrid_overhead(Q), 1.0),
    (CM, r"the Panda's plant alone is ([\d.]+) µs", "loop_profile", _part(Q, "nn", "plant"), 1.0),
    (BM, r"Python loop of nnrobust is (\d+)× \(paper arm\)", "closed_loop", _ratio(P, PY, FL), 1.0),
    (BM, r"\(paper arm\) and\s+(\d+)× \(Panda\) slower", "closed_loop", _ratio(Q, PY, FL), 1.0),
    (BM, r"The compiled loop is ([\d.]+)× its floor on both arms", "closed_loop", _ratio(P, CL, FL), 1.0),
    (BM, r"The compiled loop is ([\d.]+)× its floor on both arms", "closed_loop", _ratio(Q, CL, FL), 1.0),
    (BM, r"Slotine–Li on it ([\d.]+)× and", "closed_loop", _ratio(P, SL, FL), 1.0),
    (BM, r"Slotine–Li on it [\d.]+× and ([\d.]+)×", "closed_loop", _ratio(Q, SL, FL), 1.0),
    (
        BM,
        r"runs ([\d.]+)× \(paper arm\) and [\d.]+× \(Panda\) faster on the",
        "closed_loop",
        _ratio(P, TP, HY),
        1.0,
    ),
    (
        BM,
        r"runs [\d.]+× \(paper arm\) and ([\d.]+)× \(Panda\) faster on the",
        "closed_loop",
        _ratio(Q, TP, HY),
        1.0,
    ),
    (BM, r"most of the step \(([\d.]+) and", "closed_loop", _us(P, "TaskPD, compute alone"), 1.0),
    (
        BM,
        r"most of the step \([\d.]+ and\s+([\d.]+) µs\)",
        "closed_loop",
        _us(Q, "TaskPD, compute alone"),
        1.0,
    ),
    (
        BM,
        r"costs ([\d.]+) and\s+[\d.]+ µs\. With MuJoCo",
        "closed_loop",
        _us(P, "hybrid loop, law replayed"),
        1.0,
    ),
    (
        BM,
        r"costs [\d.]+ and\s+([\d.]+) µs\. With MuJoCo",
        "closed_loop",
        _us(Q, "hybrid loop, law replayed"),
        1.0,
    ),
    (BM, r"takes ([\d.]+) and [\d.]+ µs per step, \d+×", "closed_loop", _us(P, MJ), 1.0),
    (BM, r"takes [\d.]+ and ([\d.]+) µs per step, \d+×", "closed_loop", _us(Q, MJ), 1.0),
    (BM, r"µs per step, (\d+)× and \d+× real time", "closed_loop", _realtime(P, MJ), 1.0),
    (BM, r"µs per step, \d+× and (\d+)× real time", "closed_loop", _realtime(Q, MJ), 1.0),
    (PM, r"paper-ellipse costs ([\d.]+) µs per step", "closed_loop", _us(P, CL), 1.0),
    (PM, r"per step \((\d+)× real time\) and panda-ellipse", "closed_loop", _realtime(P, CL), 1.0),
    (PM, r"and panda-ellipse ([\d.]+) µs \(\d+×\)", "closed_loop", _us(Q, CL), 1.0),
    (PM, r"and panda-ellipse [\d.]+ µs \((\d+)×\)", "closed_loop", _realtime(Q, CL), 1.0),
    (PM, r"both ([\d.]+)×\s+their bare C\+\+ floor", "closed_loop", _ratio(P, CL, FL), 1.0),
    (PM, r"both ([\d.]+)×\s+their bare C\+\+ floor", "closed_loop", _ratio(Q, CL, FL), 1.0),
    (PM, r"the plant's integration ([\d.]+) and", "loop_profile", _part(P, "nn", "plant"), 1.0),
    (PM, r"the plant's integration [\d.]+ and ([\d.]+) µs", "loop_profile", _part(Q, "nn", "plant"), 1.0),
    ("README.md", r"compiled loop runs at (\d+)× \(paper arm\)", "closed_loop", _realtime(P, MJ), 1.0),
    ("README.md", r"\(paper arm\) and (\d+)× \(Panda\) real time", "closed_loop", _realtime(Q, MJ), 1.0),
]


def _rows(contender, scale=1.0):
    """µs per sample of one contender of identify_rows.json, times ``scale``."""
    return lambda d: (
        scale * next(r["us_per_sample"] for r in d["rows"] if r["contender"].startswith(contender))
    )


ID = "docs/identification.md"
QUOTES += [
    (ID, r"interleaved: ([\d.]+) µs per sample\s+in C\+\+", "identify_rows", _rows("C++"), 1.0),
    (ID, r"in C\+\+ against ([\d.]+) µs from Python", "identify_rows", _rows("Python"), 1.0),
    (ID, r"log's rows take ([\d.]+) s where", "identify_rows", _rows("C++", 3.6), 1.0),
    (ID, r"where they took\s+([\d.]+) s", "identify_rows", _rows("Python", 3.6), 1.0),
]

test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)
