"""The numbers docs/identification.md quotes: the Panda tables, regenerated from
docs/data/identify_panda.json (benchmarks/identify_panda.py, which needs the log no one here
ships), and the log's and the fit's figures beside them."""

from __future__ import annotations

import json
import re

import pytest
import scipy.stats

from nnrobust.model.loading import load_robot
from tests.docs_numbers.common import ROOT, quoted_figures_test

PAGE = ROOT / "docs" / "identification.md"
DATA = ROOT / "docs" / "data" / "identify_panda.json"
ROWS = (
    "published (Gaz et al. 2019)",
    "published inertias, friction refitted",
    "URDF (example-robot-data, its damping)",
    "nnrobust least squares",
    "nnrobust physical",
)


def table(treatment: dict) -> str:
    """The page's table of one torque treatment, from the benchmark's JSON."""
    lines = ["| model | " + " | ".join(f"joint {j}" for j in range(1, 8)) + " |", "|---" * 8 + "|"]
    lines.append("| torque RMS [N m] | " + " | ".join(f"{x:.3f}" for x in treatment["torque_rms"]) + " |")
    for row in ROWS:
        lines.append(
            f"| {row} | " + " | ".join(f"{100 * x:.1f} %" for x in treatment["residual_share"][row]) + " |"
        )
    return "\n".join(lines)


CALIBRATION = ROOT / "docs" / "data" / "identify_calibration.json"


def calibration_table(data: dict) -> str:
    """The page's calibration table, from benchmarks/identify_calibration.py's JSON."""
    median = sorted(r["distance2"] for r in data["rows"])[len(data["rows"]) // 2] / data["parameters"]
    return "\n".join(
        [
            "| logs | parameters | truth in the 95 % region | truth in the 95 % box | median distance² / p | "
            "physical | worst held-out RMS / noise floor |",
            "|---|---|---|---|---|---|---|",
            f"| {data['logs']} | {data['parameters']} | {100 * data['coverage']:.0f} % | "
            f"{100 * data['box_coverage']:.0f} % | {median:.2f} | "
            f"{100 * data['physical_share']:.0f} % | {data['worst_held_out_over_floor']:.2f} |",
        ]
    )


PLANT = ROOT / "docs" / "data" / "identify_calibration_plant.json"


def plant_table(data: dict) -> str:
    """The page's table of the calibration on the plant's logs (benchmarks/identify_calibration_plant.py)."""
    lines = [
        "| identify's options | truth in the 95 % region | truth in the 95 % box | median distance² / p | "
        "physical |",
        "|---|---|---|---|---|",
    ]
    for name, v in data["variants"].items():
        median = sorted(r["distance2"] for r in v["rows"])[len(v["rows"]) // 2] / v["parameters"]
        options = f"{name}: `--stick-band {v['stick_band']:g} --reversal-guard {v['reversal_guard']:g}`"
        lines.append(
            f"| {options} | {100 * v['coverage']:.0f} % | {100 * v['box_coverage']:.0f} % | {median:.2f} | "
            f"{100 * v['physical_share']:.0f} % |"
        )
    return "\n".join(lines)


def test_the_plant_calibration_table_is_the_benchmarks():
    data = json.loads(PLANT.read_text())
    found = re.search(r"<!-- identify_calibration_plant -->\n(.*?)\n<!-- end -->", PAGE.read_text(), re.S)
    assert found and found.group(1) == plant_table(data), "python -m tests.docs_numbers.test_identification"
    assert data["logs"] == 100


HOUR = ROOT / "docs" / "data" / "identify_hour.json"


def hour_table(data: dict) -> str:
    """The page's long-log table, from benchmarks/identify_hour.py's JSON."""
    lines = [
        "| log | samples | identify [s] | peak memory [MB] |",
        "|---|---|---|---|",
    ]
    for row in data["rows"]:
        lines.append(
            f"| {row['minutes']:g} min | {row['samples']:,} | {row['seconds']:.1f} | {row['peak_mb']:.0f} |"
        )
    return "\n".join(lines)


DESIGN = ROOT / "docs" / "data" / "identify_design.json"

ARMS = {"three_link_planar": "paper arm", "panda": "Panda"}


def design_table(data: dict) -> str:
    """The page's excitation design table, from benchmarks/identify_design.py's JSON."""
    budget = data["evaluations"]
    lines = [
        f"| arm | criterion | condition number, {budget:,} / {2 * budget:,} evaluations | random: "
        "median, best of 20 | standard errors ÷ a random trajectory's | run on the bench: "
        "joint-fourier, task-space law |",
        "|---|---|---|---|---|---|",
    ]
    for row in data["robots"]:
        for criterion, c in row["criteria"].items():
            first, second = (c["budget"][str(b)]["condition"] for b in (budget, 2 * budget))
            random = f"{row['random_condition_median']:.3g}, {row['random_condition_best']:.3g}"
            runs = row["bench_runs"]
            bench = (
                f"{runs['joint-fourier']['condition']:.3g}, {runs['preset']['condition']:.3g}"
                if criterion == "condition"
                else "–"
            )
            lines.append(
                f"| {ARMS[row['robot']]} | {criterion} | {first:.3g} / {second:.3g} | {random} | "
                f"{c['standard_error_ratio_median']:.2f} | {bench} |"
            )
    return "\n".join(lines)


def test_the_design_table_is_the_benchmarks():
    found = re.search(r"<!-- identify_design -->\n(.*?)\n<!-- end -->", PAGE.read_text(), re.S)
    assert found and found.group(1) == design_table(json.loads(DESIGN.read_text())), (
        "python -m tests.docs_numbers.test_identification"
    )


def test_the_design_s_verdicts_are_its_data():
    """What the page says in words: the condition design's standard errors are below a random
    trajectory's on both arms, the D-optimal design's further below on both ("does better"); the
    joint-space law runs the design within 0.01 rad, a task-space law radians away."""
    rows = {r["robot"]: r for r in json.loads(DESIGN.read_text())["robots"]}
    for r in rows.values():
        condition, optimal = (
            r["criteria"][c]["standard_error_ratio_median"] for c in ("condition", "d-optimal")
        )
        assert optimal < condition < 1
    for r in rows.values():
        assert max(r["bench_runs"]["joint-fourier"]["joint_deviation_rms"]) < 0.01
        assert max(r["bench_runs"]["preset"]["joint_deviation_rms"]) > 1.0
        assert all(
            max(c["peaks"]["position"] + c["peaks"]["velocity"]) <= 1.0 for c in r["criteria"].values()
        )


def test_the_long_log_table_is_the_benchmarks():
    found = re.search(r"<!-- identify_hour -->\n(.*?)\n<!-- end -->", PAGE.read_text(), re.S)
    assert found and found.group(1) == hour_table(json.loads(HOUR.read_text())), (
        "python -m tests.docs_numbers.test_identification"
    )


def test_the_calibration_table_is_the_benchmarks():
    data = json.loads(CALIBRATION.read_text())
    found = re.search(r"<!-- identify_calibration -->\n(.*?)\n<!-- end -->", PAGE.read_text(), re.S)
    assert found and found.group(1) == calibration_table(data), (
        "python -m tests.docs_numbers.test_identification"
    )
    assert data["logs"] == 100 and data["physical_share"] == 1.0 and data["worst_held_out_over_floor"] <= 1.2


@pytest.mark.parametrize("treatment", ["filtered", "as logged"])
def test_the_panda_tables_are_the_benchmarks(treatment):
    data = json.loads(DATA.read_text())["treatments"][treatment]
    text = PAGE.read_text()
    found = re.search(rf"<!-- identify_panda {treatment} -->\n(.*?)\n<!-- end -->", text, re.S)
    assert found and found.group(1) == table(data), "python -m tests.docs_numbers.test_identification"


def test_the_physical_model_is_at_or_below_the_published_one_on_every_joint():
    """The page's claim, on both treatments, and the physical checks it quotes."""
    for data in json.loads(DATA.read_text())["treatments"].values():
        ours = data["residual_rms"]["nnrobust physical"]
        for theirs in (data["residual_rms"][ROWS[0]], data["residual_rms"][ROWS[1]]):
            assert all(a <= b for a, b in zip(ours, theirs))
        assert data["physical"] and data["mass_matrix_least_eigenvalue"] > 0 and data["base_parameters"] == 43
        assert not any(data["white"])  # "every joint's residual fails the whiteness test"


def test_the_panda_log_without_the_reversal_guard_is_the_page_s():
    """The page's residuals without the guard, its "up to 0.8 points more" and the same verdict."""
    data = json.loads(DATA.read_text())
    without = data["without_reversal_guard"]["residual_share"]["nnrobust physical"]
    text = PAGE.read_text()
    found = re.search(r"held-out residual is ([\d.,\sand]+) % filtered, under it up to ([\d.]+) points", text)
    assert found
    quoted = [float(x) for x in re.findall(r"[\d.]+", found.group(1))]
    assert quoted == [round(100 * x, 1) for x in without]
    under = data["treatments"]["filtered"]["residual_share"]["nnrobust physical"]
    assert round(100 * max(u - w for u, w in zip(under, without)), 1) == float(found.group(2))
    assert data["without_reversal_guard"]["below_published"] == list(range(1, 8))


def test_no_repeated_row_of_the_panda_log_is_kept():
    """ "none in the Panda log": every row of it that repeats its positions is stale by the count rule."""
    for data in json.loads(DATA.read_text())["treatments"].values():
        assert data["log"]["repeated_positions_kept"] == 0


def test_the_verdict_holds_at_the_other_cut_offs():
    cutoffs = json.loads(DATA.read_text())["cutoffs"]
    assert sorted(cutoffs) == ["20 Hz, as logged", "20 Hz, filtered", "5 Hz, as logged", "5 Hz, filtered"]
    assert all(
        entry["below_published"] == list(range(1, 8)) and entry["physical"] for entry in cutoffs.values()
    )


def test_the_urdfs_link_7_is_the_one_the_page_names():
    model = load_robot("panda", task="position").model
    assert list(model.damping) == [0.003] * 7 and not any(model.friction)  # "its only friction"
    mass = model.inertias[7].mass
    assert round(mass, 2) == 1.50 == round(json.loads(DATA.read_text())["link7_mass"]["urdf"], 2)


def _filtered(*path):
    """The value at ``path`` in the filtered treatment's entry."""

    def value(data):
        out = data["treatments"]["filtered"]
        for key in path:
            out = out[key]
        return float(out)

    return value


def _chi2_median_over_p(data):
    return float(scipy.stats.chi2.median(data["parameters"]) / data["parameters"])


PAGE_NAME = "docs/identification.md"


def _panda_box_half_width(data: dict) -> float:
    """c of the calibration's box: (2 Phi(c) - 1)^p = its level, p its parameters."""
    from nnrobust.model.region import box_half_width

    return box_half_width(data["level"], data["parameters"])


PAPER, PANDA = "three_link_planar", "panda"


def _arm(robot: str, *keys):
    """A selector of docs/data/identify_design.json's row of ``robot``, then ``keys``."""

    def select(data):
        value = next(r for r in data["robots"] if r["robot"] == robot)
        for key in keys:
            value = value[key]
        return value

    return select


def _criterion(robot: str, criterion: str, *keys):
    """A selector of a criterion's design."""
    return _arm(robot, "criteria", criterion, *keys)


def _budget(robot: str, evaluations: str):
    """The condition design's condition number at a budget."""
    return _criterion(robot, "condition", "budget", evaluations, "condition")


def _deviations(end):
    """The least (end = min) or largest (max) joint deviation of the task-space law's runs [rad]."""
    return lambda d: end(end(_arm(r, "bench_runs", "preset", "joint_deviation_rms")(d)) for r in ARMS)


def _doubling(d) -> float:
    """How much the paper arm's condition design moved on doubling its budget [%]."""
    return 100 * abs(1 - _budget(PAPER, "12000")(d) / _budget(PAPER, "6000")(d))


_DESIGN_QUOTES = (
    (
        r"excitation's condition number is ([\d.]+) against a median",
        _criterion(PANDA, "condition", "condition"),
    ),
    (r"against a median of ([\d.]+) for random", _arm(PANDA, "random_condition_median")),
    (
        r"standard errors are ([\d.]+) of a random",
        _criterion(PANDA, "condition", "standard_error_ratio_median"),
    ),
    (r"its condition number is ([\d.]+) against [\d.]+, yet", _criterion(PAPER, "condition", "condition")),
    (r"its condition number is [\d.]+ against ([\d.]+), yet", _arm(PAPER, "random_condition_median")),
    (r"\*\*([\d.]+) times\*\* a\s+random", _criterion(PAPER, "condition", "standard_error_ratio_median")),
    (
        r"on both arms\s+\(([\d.]+) and [\d.]+ of a",
        _criterion(PAPER, "d-optimal", "standard_error_ratio_median"),
    ),
    (
        r"on both arms\s+\([\d.]+ and ([\d.]+) of a",
        _criterion(PANDA, "d-optimal", "standard_error_ratio_median"),
    ),
    (
        r"criterion by\s+([\d.]+) or less",
        lambda d: max(_criterion(r, "d-optimal", "doubling_change")(d) for r in ARMS),
    ),
    (r"and the condition number\s+by ([\d.]+) % on the paper arm", _doubling),
    (r"evaluations\s+\(([\d.]+), then", _budget(PANDA, "6000")),
    (r"then ([\d.]+) at 12 000\)", _budget(PANDA, "12000")),
    (
        r"the condition number is the design's \(([\d.]+) and",
        _arm(PAPER, "bench_runs", "joint-fourier", "condition"),
    ),
    (r"the design's \([\d.]+ and ([\d.]+)\)", _arm(PANDA, "bench_runs", "joint-fourier", "condition")),
    (r"task-space law it is ([\d.]+) and", _arm(PAPER, "bench_runs", "preset", "condition")),
    (r"task-space law it is [\d.]+ and ([\d.]+), the", _arm(PANDA, "bench_runs", "preset", "condition")),
    (r"the joints ([\d.]+) to [\d.]+ rad\s+away", _deviations(min)),
    (r"the joints [\d.]+ to ([\d.]+) rad\s+away", _deviations(max)),
)
"""The excitation design's figures in the page's prose (benchmarks/identify_design.py)."""


def _variant(name: str, key: str, scale: float = 100.0):
    """A figure of one of the plant calibration's variants."""
    return lambda d: scale * d["variants"][name][key]


_PLANT_QUOTES = (
    (r"the region held the truth in (\d+) % of the plant's logs", _variant("no reversal guard", "coverage")),
    (r"and gets (\d+) %; the guard", _variant("no guard, wide stick band", "coverage")),
    (r"by time rather than speed, (\d+) %", _variant("defaults", "coverage")),
    (
        r"median distance² / p at\s+([\d.]+),",
        lambda d: sorted(r["distance2"] for r in d["variants"]["defaults"]["rows"])[50] / 57,
    ),
    (r"holds the truth in (\d+) %\. Every", _variant("defaults", "box_coverage")),
    (
        r"held-out residual is ([\d.]+) times the noise floor",
        _variant("defaults", "worst_held_out_over_floor", 1.0),
    ),
    (r"holds the truth\s+in (\d+) % of the logs at 95 %", _variant("defaults", "coverage")),
)
"""The plant calibration's figures in the page's prose (benchmarks/identify_calibration_plant.py)."""

QUOTES: list[tuple] = [
    *((PAGE_NAME, pattern, "identify_design", where, 1.0) for pattern, where in _DESIGN_QUOTES),
    *((PAGE_NAME, pattern, "identify_calibration_plant", where, 1.0) for pattern, where in _PLANT_QUOTES),
    (
        PAGE_NAME,
        r"rⱼ is between ([\d.]+) and",
        "identify_panda",
        lambda d: min(d["treatments"]["as logged"]["long_run_ratio"]),
        1.0,
    ),
    (
        PAGE_NAME,
        r"rⱼ is between [\d.]+ and ([\d.]+)",
        "identify_panda",
        lambda d: max(d["treatments"]["as logged"]["long_run_ratio"]),
        1.0,
    ),
    (
        PAGE_NAME,
        r"median over p is about ([\d.]+) at p",
        "identify_calibration",
        _chi2_median_over_p,
        1.0,
    ),
    (
        PAGE_NAME,
        r"A one-hour log is identified in ([\d.]+) s",
        "identify_hour",
        lambda d: d["rows"][-1]["seconds"],
        1.0,
    ),
    (
        PAGE_NAME,
        r"the peak grows by (\d+) MB \(to",
        "identify_hour",
        lambda d: d["rows"][-1]["peak_mb"] - d["rows"][0]["peak_mb"],
        1.0,
    ),
    (
        PAGE_NAME,
        r"\(to (\d+) MB\s+for the hour\)",
        "identify_hour",
        lambda d: d["rows"][-1]["peak_mb"],
        1.0,
    ),
    # the walkthrough (benchmarks/identify_walkthrough.py)
    *(
        (PAGE_NAME, pattern, "identify_walkthrough", where, scale)
        for pattern, where, scale in (
            (r"On this log the box has (\d+) coordinates", lambda d: float(d["coordinates"]), 1.0),
            (r"coordinates, each within ±([\d.]+); the", lambda d: d["half_width"], 1.0),
            (r"largest coordinate is ([\d.]+): it is in", lambda d: d["truth_largest_coordinate"], 1.0),
            (
                r"law passes (\d+) of \d+\s+certification",
                lambda d: d["laws"]["nn"]["N"] - d["laws"]["nn"]["failed"],
                1.0,
            ),
            (r"law passes \d+ of (\d+)\s+certification", lambda d: float(d["laws"]["nn"]["N"]), 1.0),
            (r"draws \(P\(fail\) ≤ ([\d.]+) at 0.95", lambda d: d["laws"]["nn"]["p_upper"], 1.0),
            (r"at 0.95; median error ([\d.]+) mm\)", lambda d: d["laws"]["nn"]["median_error_mm"], 1.0),
            (r"passes none \(median error ([\d.]+) mm", lambda d: d["laws"]["pd"]["median_error_mm"], 1.0),
            (
                r"with confidence ≥ ([\d.]+), the robot is in the box and",
                lambda d: d["composed_claim"]["together"],
                1.0,
            ),
            (r"c = ([\d.]+) for p = 13", lambda d: d["half_width"], 1.0),
            (
                r"budget of (\d+) simulations per\s+seed",
                lambda d: d["laws"]["nn"]["convergence"]["budget"],
                1.0,
            ),
            (
                r"kept median moved (\d+) % from half",
                lambda d: d["laws"]["nn"]["convergence"]["change"],
                100.0,
            ),
            (r"study asks at most (\d+) %", lambda d: d["laws"]["nn"]["convergence"]["tolerance"], 100.0),
            (
                r"median error falls to ([\d.]+) mm",
                lambda d: d["doubled_budget"]["laws"]["nn"]["median_error_mm"],
                1.0,
            ),
            (
                r"it passes\s+(\d+) of \d+ certification draws, certified again",
                lambda d: (
                    d["doubled_budget"]["laws"]["nn"]["N"] - d["doubled_budget"]["laws"]["nn"]["failed"]
                ),
                1.0,
            ),
            (
                r"it passes\s+\d+ of (\d+) certification draws, certified again",
                lambda d: d["doubled_budget"]["laws"]["nn"]["N"],
                1.0,
            ),
            (
                r"its kept\s+median moved (\d+) % from 80 to 160",
                lambda d: d["doubled_budget"]["laws"]["nn"]["convergence"]["change"],
                100.0,
            ),
        )
    ),
    (PAGE_NAME, r"([\d.]+) for p = 57 \(the Panda\)", "identify_calibration", _panda_box_half_width, 1.0),
    (PAGE_NAME, r"at p = (\d+)\)", "identify_calibration", lambda d: float(d["parameters"]), 1.0),
    (
        PAGE_NAME,
        r"Of\s+them, (\d+) come with a fresh torque",
        "identify_panda",
        _filtered("log", "stale_with_new_torque"),
        1.0,
    ),
    (
        PAGE_NAME,
        r"The Panda log has ([\d ]+) of its",
        "identify_panda",
        _filtered("log", "stale_samples"),
        1.0,
    ),
    (
        PAGE_NAME,
        r"The Panda log has [\d ]+ of its\s+([\d ]+)\.",
        "identify_panda",
        _filtered("log", "samples"),
        1.0,
    ),
    (
        PAGE_NAME,
        r"stamps range from ([\d.]+) to",
        "identify_panda",
        _filtered("log", "step_range_ms", 0),
        1.0,
    ),
    (
        PAGE_NAME,
        r"stamps range from [\d.]+ to ([\d.]+) ms",
        "identify_panda",
        _filtered("log", "step_range_ms", 1),
        1.0,
    ),
    (PAGE_NAME, r"base regressor is (\d+)\.", "identify_panda", _filtered("condition_number"), 1.0),
    (
        PAGE_NAME,
        r"against the published ([\d.]+) kg",
        "identify_panda",
        lambda d: d["link7_mass"]["published"],
        1.0,
    ),
    (
        PAGE_NAME,
        r"Joint 7's residual \((\d+) % filtered\)",
        "identify_panda",
        _filtered("residual_share", "nnrobust physical", 6),
        100.0,
    ),
]

test_every_quoted_figure_matches_its_data = quoted_figures_test(QUOTES)


if __name__ == "__main__":
    text = PAGE.read_text()
    for name, data in json.loads(DATA.read_text())["treatments"].items():
        text = re.sub(
            rf"(<!-- identify_panda {name} -->\n).*?(\n<!-- end -->)",
            lambda m: m.group(1) + table(data) + m.group(2),
            text,
            flags=re.S,
        )
    pattern = r"(<!-- identify_calibration -->\n).*?(\n?<!-- end -->)"
    table = calibration_table(json.loads(CALIBRATION.read_text()))
    text = re.sub(pattern, lambda m: m.group(1) + table + "\n<!-- end -->", text, flags=re.S)
    pattern = r"(<!-- identify_calibration_plant -->\n).*?(\n?<!-- end -->)"
    table = plant_table(json.loads(PLANT.read_text()))
    text = re.sub(pattern, lambda m: m.group(1) + table + "\n<!-- end -->", text, flags=re.S)
    pattern = r"(<!-- identify_design -->\n).*?(\n?<!-- end -->)"
    table = design_table(json.loads(DESIGN.read_text()))
    text = re.sub(pattern, lambda m: m.group(1) + table + "\n<!-- end -->", text, flags=re.S)
    pattern = r"(<!-- identify_hour -->\n).*?(\n?<!-- end -->)"
    table = hour_table(json.loads(HOUR.read_text()))
    text = re.sub(pattern, lambda m: m.group(1) + table + "\n<!-- end -->", text, flags=re.S)
    PAGE.write_text(text)


def test_the_walkthrough_s_verdicts_are_its_data():
    """What the walkthrough's prose says in words: the truth in its box, the NN law certified and
    the PD not (docs/data/identify_walkthrough.json)."""
    data = json.loads((ROOT / "docs" / "data" / "identify_walkthrough.json").read_text())
    assert data["truth_in_box"] and data["laws"]["nn"]["certified"] and not data["laws"]["pd"]["certified"]
    assert data["laws"]["pd"]["failed"] == data["laws"]["pd"]["N"] and data["composed_claim"]["stated"]
    assert not data["laws"]["nn"]["convergence"]["converged"]  # "did not converge at its budget"
    doubled = data["doubled_budget"]
    assert doubled["tune"] == 2 * data["laws"]["nn"]["convergence"]["budget"]
    assert doubled["laws"]["nn"]["certified"] and doubled["laws"]["nn"]["failed"] == 0  # "certified again"
    assert not doubled["laws"]["nn"]["convergence"]["converged"]  # "has still not converged"
