"""Bad inputs: identification: logs that no fit can use, and identified models that are not one."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from nnrobust.core import exceptions as ex

from .common import Case, _build, _file

JOINTS = ("joint1", "joint2", "joint3")
"""The paper's arm, the robot these logs are of."""


def _csv(folder: Path, edit=None, name: str = "log.csv") -> Path:
    """A valid 4 s, 1 kHz CSV log of the paper's arm (a slow sinusoid), then ``edit(columns)``."""
    t = np.arange(4000) / 1000.0
    columns = {"time": t}
    for i in range(3):
        columns[f"q{i}"] = 0.3 * np.sin(2 * np.pi * 0.5 * t + i)
        columns[f"dq{i}"] = 0.3 * np.pi * np.cos(2 * np.pi * 0.5 * t + i)
        columns[f"tau{i}"] = np.sin(t + i)
    if edit is not None:
        edit(columns)
    names = list(columns)
    rows = np.column_stack([columns[c] for c in names])
    lines = [",".join(names)] + [",".join(repr(float(x)) for x in row) for row in rows]
    return _file(folder, name, "\n".join(lines) + "\n")


def _identify(folder: Path, log, **options):
    def run():
        from nnrobust.studies.identify import IdentifyOptions, identify

        return identify([log(folder)], "three_link_planar", folder / "identified", IdentifyOptions(**options))

    return run


def _set(name: str, index: int, value: float):
    def edit(columns):
        columns[name] = columns[name].copy()
        columns[name][index] = value

    return edit


def _swap_times(columns):
    columns["time"] = columns["time"].copy()
    columns["time"][[100, 101]] = columns["time"][[101, 100]]


def _repeat_time(columns):
    columns["time"] = columns["time"].copy()
    columns["time"][201] = columns["time"][200]


def _joint_named(columns):
    for i, j in enumerate(("shoulder", "elbow", "wrist")):
        for s in ("q", "dq", "tau"):
            columns[f"{s}.{j}"] = columns.pop(f"{s}{i}")


def _degrees(columns):
    for i in range(3):
        columns[f"q{i}"] = columns[f"q{i}"] * 180 / np.pi * 20  # degrees, and a swing past the limits


def _gap(columns):
    for name in list(columns):
        columns[name] = np.delete(columns[name], np.arange(2000, 2400))


def _fourth_joint(columns):
    columns["q3"] = columns["q0"].copy()


def _twice(folder: Path) -> Path:
    path = _csv(folder)
    lines = path.read_text().splitlines()
    lines[0] = lines[0].replace("dq1", "dq2", 1)
    path.write_text("\n".join(lines) + "\n")
    return path


def _still_joint(columns):
    for s, value in (("q", 0.2), ("dq", 0.0)):
        columns[f"{s}2"] = np.full_like(columns["time"], value)


def _text_log(folder: Path, torque_lines: int) -> list[Path]:
    t = np.arange(3000) / 1000.0
    q = 0.3 * np.sin(np.outer(t, [1.0, 2.0, 3.0]))
    files = [_file(folder, "traj_time.txt", "\n".join(str(float(x)) for x in t) + "\n")]
    files.append(_file(folder, "traj_positions.txt", "\n".join(str(float(x)) for x in q.ravel()) + "\n"))
    files.append(
        _file(folder, "traj_torques.txt", "\n".join(str(float(x)) for x in q.ravel()[:torque_lines]) + "\n")
    )
    return files


def _identify_text(folder: Path, torque_lines: int):
    def run():
        from nnrobust.studies.identify import identify

        return identify(_text_log(folder, torque_lines), "three_link_planar", folder / "identified")

    return run


def _identified_file(folder: Path, edit) -> Path:
    from nnrobust.model.identified import IDENTIFIED_FORMAT

    body = {"mass": 1.0, "lever": [0.2, 0, 0], "inertia": [[0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.01]]}
    data = {
        "format": IDENTIFIED_FORMAT,
        "robot": "three_link_planar",
        "joints": list(JOINTS),
        "bodies": [dict(body, joint=j) for j in JOINTS],
        "friction": {"viscous": [0, 0, 0], "coulomb": [0, 0, 0], "offset": [0, 0, 0]},
        "armature": [0, 0, 0],
    }
    edit(data)
    return _file(folder, "nominal.json", json.dumps(data))


def _run_identified(edit):
    def make(folder: Path):
        path = _identified_file(folder, edit)
        return _build(nominal={"kind": "identified", "file": str(path)})

    return make


def _breaks_triangle(data):
    data["bodies"][1]["inertia"] = [[0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.05]]


IDENTIFY_CASES = [
    Case(
        "identify: a NaN in a torque column",
        lambda d: _identify(d, lambda f: _csv(f, _set("tau1", 1234, float("nan")))),
        ex.LogError,
        "log.csv: tau0..tau2 (joint joint2) is nan at sample 1234; every value must be a finite number",
    ),
    Case(
        "identify: times out of order",
        lambda d: _identify(d, lambda f: _csv(f, _swap_times)),
        ex.LogError,
        "log.csv: time goes back at sample 101 (0.101 s then 0.1 s); sort the log by time",
    ),
    Case(
        "identify: a time twice",
        lambda d: _identify(d, lambda f: _csv(f, _repeat_time)),
        ex.LogError,
        "log.csv: time repeats 0.2 s at samples 200 and 201; each sample needs its own time",
    ),
    Case(
        "identify: columns named for other joints",
        lambda d: _identify(d, lambda f: _csv(f, _joint_named)),
        ex.LogError,
        "log.csv: no q columns for the robot's 3 joints (e.g. q0...q2 or q.joint1); its columns: time, "
        "q.shoulder",
    ),
    Case(
        "identify: a torque file of the wrong length",
        lambda d: _identify_text(d, 8000),
        ex.LogError,
        "traj_torques.txt: 8000 numbers, not a whole number of samples of 3 joints",
    ),
    Case(
        "identify: a joint the log never moves",
        lambda d: _identify(d, lambda f: _csv(f, _still_joint)),
        ex.LogError,
        "log.csv: the fit segment does not excite 2 of the base parameters: viscous@joint3, coulomb@joint3; ",
    ),
    Case(
        "identify: a cut-off above the log's Nyquist frequency",
        lambda d: _identify(d, lambda f: _csv(f), filter=_filter(cutoff=600.0)),
        ex.LogError,
        "log.csv: the filter's cut-off 600 Hz must be positive and below 80 % of the log's Nyquist "
        "frequency 500 Hz",
    ),
    Case(
        "identify: a column name twice",
        lambda d: _identify(d, _twice),
        ex.LogError,
        "log.csv: the columns dq2 appear twice; each signal of each joint once",
    ),
    Case(
        "identify: a column of a joint the robot does not have",
        lambda d: _identify(d, lambda f: _csv(f, _fourth_joint)),
        ex.LogError,
        "log.csv: a column q3: the log has more joints than the robot's 3 (joint1, joint2, joint3)",
    ),
    Case(
        "identify: positions in degrees",
        lambda d: _identify(d, lambda f: _csv(f, _degrees)),
        ex.LogError,
        "outside its URDF limits [-3.142, 3.142]: positions must be in rad",
    ),
    Case(
        "identify: 0.4 s without a sample",
        lambda d: _identify(d, lambda f: _csv(f, _gap)),
        ex.LogError,
        "log.csv: no sample between 1.999 s and 2.4 s; a gap over 0.5 cut-off period (50 ms) would be filled",
    ),
    Case(
        "identify: an MCAP file that is not one",
        lambda d: _identify(d, lambda f: _file(f, "log.mcap", "not a recording\n")),
        ex.LogError,
        "log.mcap: not a readable MCAP file (",
    ),
    Case(
        "nominal: an identified model for another robot",
        _run_identified(lambda data: data.update(joints=["a", "b", "c"])),
        ex.ConfigError,
        "nominal.file: the identified model's joints ['a', 'b', 'c'] are not",
    ),
    Case(
        "nominal: an identified body that breaks the triangle inequality",
        _run_identified(_breaks_triangle),
        ex.ConfigError,
        "body of joint2 is not physical: principal moments [0.01, 0.01, 0.05] break the triangle inequality",
    ),
    Case(
        "nominal: an identified model with negative friction",
        _run_identified(lambda data: data["friction"].update(viscous=[0.1, -0.2, 0])),
        ex.ConfigError,
        "friction.viscous: needs 3 finite numbers, none negative",
    ),
]


def _filter(**kwargs):
    from nnrobust.studies.identify.signals import FilterChoice

    return FilterChoice(**kwargs)
