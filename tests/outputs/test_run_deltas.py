"""nnrobust compare's changes: metric deltas against the first run and the verdicts that flip."""

from nnrobust.outputs.run_deltas import delta_table, verdict_changes
from nnrobust.run.properties import run_properties


def metrics(error, torque, warnings=(), status="completed"):
    return {
        "status": status,
        "rms_error": error,
        "rms_error_after_2s": error,
        "rms_torque": torque,
        "saturated_fraction": 0.0,
        "warnings": list(warnings),
    }


def test_deltas_are_against_the_first_run_in_display_units():
    rows = [("a", metrics(0.002, 4.0)), ("b", metrics(0.003, 4.0)), ("c", metrics(0.001, 5.0))]
    table = delta_table(rows).splitlines()
    error = next(line for line in table if line.startswith("RMS error [mm]"))
    assert "3 (+1, +50 %)" in error and "1 (-1, -50 %)" in error
    torque = next(line for line in table if line.startswith("RMS torque"))
    assert "4 (=)" in torque and "5 (+1, +25 %)" in torque
    assert not any(line.startswith("max torque") for line in table)  # in no run: no row


def test_only_the_verdicts_that_differ_are_listed():
    props = run_properties(["rms_error_after_2s<=0.0025", "rms_torque<=10"])
    rows = [
        ("pin", metrics(0.002, 4.0)),
        ("mj", metrics(0.003, 4.0, ["torque saturation: the command exceeded ..."])),
        ("cut", metrics(0.001, 4.0, status="diverged")),
    ]
    changes = verdict_changes(rows, props)
    assert "status: pin: completed; mj: completed; cut: diverged" in changes
    assert "rms_error_after_2s<=0.0025: pin: holds; mj: fails; cut: fails" in changes  # a diverged run fails
    assert "torque saturation: pin: no; mj: yes; cut: no" in changes
    assert "rms_torque<=10: pin: holds; mj: holds; cut: fails" in changes
    assert verdict_changes(rows[:1] * 2, props) == []
