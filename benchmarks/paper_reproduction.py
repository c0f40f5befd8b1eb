"""The paper's two cases at the paper's gains: the reproduction table of the README, and the
control-quality check of a tuned NN setting over 120 s.

    python benchmarks/paper_reproduction.py --json docs/data/paper_reproduction.json [--workers 2]

Rows (20 s runs unless said): the NN controller with the library's defaults and the no-u0
baseline, both with the URDF's effort limits; the paper's own adaptive law on the paper's
idealised robot (no limits, as the paper has it) and on the robot with limits; and the tuned NN
setting (Kp = 400, Kv = 40, sigma = 0.5) run for 120 s, which must reach an RMS error <= 1 mm
over t >= 2 s at an RMS torque <= 10 N m and stay bounded (last 20 s at most 2x the RMS over
2-20 s).
"""

from __future__ import annotations

import itertools

from _common import mm, number, parser, report

CASES = {"case (a) line": "paper-line", "case (b) ellipse": "paper-ellipse"}
PAPER_LAW = {"nn": {"sigma": 0.0, "eps_min": 0.0}}
IDEAL_ROBOT = {"torque_limits": "none", "joint_stops": False}
TUNED = {"controller": {"kind": "nn", "Kp": [400.0], "Kv": [40.0]}, "nn": {"sigma": 0.5}}

VARIANTS = {
    "NN, defaults": {"controller": {"kind": "nn"}},
    "no-u0 baseline": {"controller": {"kind": "no-u0"}},
    "NN, paper's law, ideal actuators": {"controller": {"kind": "nn"}, **PAPER_LAW, "plant": IDEAL_ROBOT},
    "NN, paper's law, effort limits": {"controller": {"kind": "nn"}, **PAPER_LAW},
    "NN, tuned (Kp 400, Kv 40, sigma 0.5), 120 s": {**TUNED, "simulation": {"duration": 120.0}},
}


def jobs() -> list[dict]:
    """One job per case and variant."""
    return [
        {"case": case, "variant": name, "preset": preset, "changes": changes}
        for (case, preset), (name, changes) in itertools.product(CASES.items(), VARIANTS.items())
    ]


COLUMNS = [
    ("case", 17, lambda r: r["case"]),
    ("variant", 44, lambda r: r["variant"]),
    ("rms e [mm]", 10, mm("rms_error_after_2s")),
    ("rms tau", 8, number("rms_torque")),
    ("chatter", 8, number("torque_chatter")),
    ("sat %", 6, number("saturated_fraction", ".2f", 100)),
    ("warnings", 9, lambda r: str(len(r["warnings"]))),
]


def main() -> None:
    report(parser(__doc__).parse_args(), jobs(), COLUMNS)


if __name__ == "__main__":
    main()
