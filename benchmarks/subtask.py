"""The null-space subtask under uncertainty: h of eq. (19) at the start and end of case (b).

    python benchmarks/subtask.py --json docs/data/subtask.json [--workers 2]

The NN compensator acts through J+ on the task error only (eq. 13 is the task-space error), so a
model error's null-space part disturbs the self-motion unopposed. The rows separate the causes
(model error, friction, disturbance) and show what the self-motion gain k does.
"""

from __future__ import annotations

from _common import mm, number, parser, report

NO_FRICTION = {"viscous_friction": [0.0] * 3, "coulomb_friction": [0.0] * 3}

VARIANTS = {
    "NN, the paper's uncertainty (defaults)": {},
    "NN, no disturbance": {"plant": {"disturbance": "none"}},
    "NN, true model, true viscous friction, no Coulomb, no disturbance": {
        "nominal": {"kind": "urdf", "viscous_friction": [4.3, 1.4, 0.4]},
        "plant": {"disturbance": "none", "coulomb_friction": [0.0] * 3},
    },
    "NN, true model, no friction, no disturbance": {
        "nominal": {"kind": "urdf", "viscous_friction": [0.0] * 3},
        "plant": {"disturbance": "none", **NO_FRICTION},
    },
    "computed-torque (true model and friction)": {"controller": {"kind": "computed-torque"}},
    "NN, k = 30": {"controller": {"k": 30.0}},
    "NN, k = 100": {"controller": {"k": 100.0}},
    "no-u0 baseline": {"controller": {"kind": "no-u0"}},
}


COLUMNS = [
    ("variant", 66, lambda r: r["variant"]),
    ("h(0)", 8, number("h_start", ".4f")),
    ("h(20 s)", 8, number("h_end", ".4f")),
    ("rms e [mm]", 10, mm("rms_error_after_2s")),
    ("rms tau", 8, number("rms_torque")),
]


def main() -> None:
    jobs = [
        {"variant": name, "preset": "paper-ellipse", "changes": changes} for name, changes in VARIANTS.items()
    ]
    report(parser(__doc__).parse_args(), jobs, COLUMNS)


if __name__ == "__main__":
    main()
