"""What the torque-speed envelope (plant.torque_speed = "urdf") does to the shipped presets.

    python benchmarks/torque_speed.py --json docs/data/torque_speed.json [--workers 2]

Each preset as shipped (its controller, gains and duration), without the envelope (the default),
with it at the default knee (0.5) and with a DC motor's straight line (knee 0): the error, the
saturated steps, the peak joint speed over its limit and the warnings (docs/plant.md).
"""

from __future__ import annotations

import itertools

from _common import mm, number, parser, report, run_row

PRESETS = ("paper-ellipse", "paper-line", "panda-ellipse", "panda-pose", "ur5-ellipse", "planar7-ellipse")
ENVELOPES = (("none", {"torque_speed": "none"}), ("knee 0.5", {"torque_speed": "urdf"}),
             ("knee 0", {"torque_speed": "urdf", "torque_speed_knee": 0.0}))  # fmt: skip
COLUMNS = [
    ("preset", 16, lambda r: r["preset"]),
    ("envelope", 9, lambda r: r["envelope"]),
    ("rms e [mm]", 10, mm("rms_error_after_2s")),
    ("sat %", 6, number("saturated_fraction", ".2f", 100)),
    ("speed/limit", 11, number("max_speed_ratio", ".3g")),
    ("warnings", 9, lambda r: str(len(r["warnings"]))),
]


def main() -> None:
    args = parser(__doc__).parse_args()
    jobs = [
        {"preset": preset, "envelope": label, "changes": {"plant": plant}}
        for preset, (label, plant) in itertools.product(PRESETS, ENVELOPES)
    ]
    report(args, jobs, COLUMNS, runner=run_row)


if __name__ == "__main__":
    main()
