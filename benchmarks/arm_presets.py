"""Every controller on the real-arm presets (Panda, UR5, a 7-link planar chain), 10 s each.

    python benchmarks/arm_presets.py --json docs/data/arm_presets.json [--workers 2]

Each preset has a +-20 % inertial model error, unmodelled scaled friction, a scaled disturbance,
the URDF's effort limits and joint stops; every controller runs with the preset's gains.
"""

from __future__ import annotations

import itertools

from _common import mm, number, parser, report

PRESETS = ("panda-ellipse", "panda-pose", "ur5-ellipse", "planar7-ellipse")
CONTROLLERS = ("nn", "no-u0", "sliding-mode", "computed-torque", "pd")
COLUMNS = [
    ("preset", 16, lambda r: r["preset"]),
    ("controller", 16, lambda r: r["controller"]),
    ("rms e [mm]", 10, mm("rms_error_after_2s")),
    ("rms rot [mrad]", 14, number("rms_orientation_error_after_2s", ".3g", 1e3)),
    ("rms tau", 8, number("rms_torque")),
    ("chatter", 8, number("torque_chatter")),
    ("sat %", 6, number("saturated_fraction", ".2f", 100)),
]


def main() -> None:
    args = parser(__doc__).parse_args()
    jobs = [
        {"preset": preset, "controller": kind, "changes": {"controller": {"kind": kind}}}
        for preset, kind in itertools.product(PRESETS, CONTROLLERS)
    ]
    report(args, jobs, COLUMNS)


if __name__ == "__main__":
    main()
