"""What the NN compensator's options do to error and torque on the paper's case (b).

    python benchmarks/nn_options.py --json docs/data/nn_options.json [--workers 2]

Runs the paper-ellipse preset (20 s, the URDF's effort limits) with the no-u0 baseline and with the
NN compensator under several settings, each one change from the defaults.
"""

from __future__ import annotations

from _common import mm, number, parser, report

VARIANTS = {
    "no-u0 baseline": {"controller": {"kind": "no-u0"}},
    "nn, defaults (sigma 0.05, eps = 1)": {},
    "nn, paper's law (sigma 0, eps -> 0)": {"nn": {"sigma": 0.0, "eps_min": 0.0}},
    "nn, printed eq. (15)": {"nn": {"law": "printed"}},
    "nn, eps floor 0.05": {"nn": {"eps_min": 0.05}},
    "nn, no leakage (sigma 0)": {"nn": {"sigma": 0.0}},
    "nn, sigma 0.5": {"nn": {"sigma": 0.5}},
    "nn, F = 1": {"nn": {"F": 1.0}},
    "nn, F = 20": {"nn": {"F": 20.0}},
    "nn, basis s = [e, e']": {"nn": {"basis_input": "error"}},
    "nn, constant unit only": {"nn": {"centers": 1, "width": 1e-6}},
}


COLUMNS = [
    ("variant", 36, lambda r: r["variant"]),
    ("rms e t>=2s [mm]", 17, mm("rms_error_after_2s")),
    ("max e [mm]", 11, mm("max_error")),
    ("rms tau [N m]", 14, number("rms_torque")),
    ("chatter [N m]", 14, number("torque_chatter")),
    ("sat %", 6, number("saturated_fraction", ".2f", 100)),
    ("rho-hat end", 12, number("final_rho_hat", ".3g")),
]


def main() -> None:
    p = parser(__doc__)
    p.add_argument("--preset", default="paper-ellipse")
    args = p.parse_args()
    jobs = [
        {"variant": name, "preset": args.preset, "changes": changes} for name, changes in VARIANTS.items()
    ]
    report(args, jobs, COLUMNS, preset=args.preset)


if __name__ == "__main__":
    main()
