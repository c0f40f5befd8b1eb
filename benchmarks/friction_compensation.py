"""Coulomb friction compensated from sampled velocities: computed torque (the true model and
friction as the controller's model) on case (b) without disturbance, at K_p = 100, K_v = 20.

    python benchmarks/friction_compensation.py --json docs/data/friction_compensation.json [--workers 2]

Variants: the self-motion gain k = 10 (the preset's) and k = 0; the plant without Coulomb
friction (what the sampled sign costs); the controller's sgn replaced by sat(q' / v_s) at
v_s = 0.01 and 0.05 rad/s. A discontinuous law makes a run sensitive, so each variant also runs
with the plant's friction scaled by 1 +- 1e-6 and its metrics are given as the median and range
of the three.
"""

from __future__ import annotations

import numpy as np
from _common import parser, run_rows

from nnrobust.run.results import write_json_atomic

BASE = {
    "controller": {"kind": "computed-torque", "Kp": [100.0], "Kv": [20.0]},
    "plant": {"disturbance": "none"},
}
VARIANTS = {
    "k = 10 (self-motion on)": {},
    "k = 0 (no self-motion)": {"controller": {"k": 0.0}},
    "no Coulomb friction in the plant": {"plant": {"coulomb_friction": [0.0, 0.0, 0.0]}},
    "sgn -> sat(q' / 0.01 rad/s)": {"controller": {"coulomb_smoothing": 0.01}},
    "sgn -> sat(q' / 0.05 rad/s)": {"controller": {"coulomb_smoothing": 0.05}},
}
PROBES = {"as is": 1.0, "friction x (1 + 1e-6)": 1 + 1e-6, "friction x (1 - 1e-6)": 1 - 1e-6}
METRICS = ("rms_error_after_2s", "rms_torque", "torque_chatter")


def _merge(*parts: dict) -> dict:
    out: dict = {}
    for part in parts:
        for section, values in part.items():
            out[section] = {**out.get(section, {}), **values}
    return out


def jobs() -> list[dict]:
    """Every variant under every probe."""
    return [
        {
            "variant": name,
            "probe": probe,
            "preset": "paper-ellipse",
            "changes": _merge(BASE, changes, {"plant": {"friction_scale": scale}}),
        }
        for name, changes in VARIANTS.items()
        for probe, scale in PROBES.items()
    ]


def summary(runs: list[dict]) -> list[dict]:
    """Per variant: median, min and max of each metric over the probes."""
    out = []
    for name in VARIANTS:
        group = [r for r in runs if r["variant"] == name]
        row = {"variant": name, "status": sorted({r["status"] for r in group})}
        for key in METRICS:
            values = np.array([r[key] for r in group], dtype=float)
            row[key] = float(np.median(values))
            row[f"{key}_min"], row[f"{key}_max"] = float(values.min()), float(values.max())
        out.append(row)
    return out


def main() -> None:
    args = parser(__doc__).parse_args()
    runs = run_rows(jobs(), args.workers)
    rows = summary(runs)
    print(f"{'variant':36s} {'RMS e [mm] median (range)':>30s} {'RMS tau':>8s} {'chatter':>8s}")
    for r in rows:
        e = (
            f"{1e3 * r['rms_error_after_2s']:.4g} ({1e3 * r['rms_error_after_2s_min']:.4g}-"
            f"{1e3 * r['rms_error_after_2s_max']:.4g})"
        )
        print(f"{r['variant']:36s} {e:>30s} {r['rms_torque']:8.3f} {r['torque_chatter']:8.4f}")
    if args.json:
        write_json_atomic(args.json, {"rows": rows, "runs": runs})


if __name__ == "__main__":
    main()
