"""What changes between runs (``nnrobust compare``): each metric against the first run, and the
verdicts that flip. Run on the same experiment with ``plant.engine`` pinocchio and mujoco, it is
the sim-to-sim gap (docs/engines.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ..run.properties import Property

DELTA_METRICS = (
    ("rms_error", "RMS error [mm]", 1e3),
    ("rms_error_after_2s", "RMS error t>=2s [mm]", 1e3),
    ("max_error", "max error [mm]", 1e3),
    ("final_error", "final error [mm]", 1e3),
    ("rms_orientation_error_after_2s", "RMS rot t>=2s [mrad]", 1e3),
    ("rms_torque", "RMS torque norm [N m]", 1.0),
    ("max_torque", "largest joint torque [N m]", 1.0),
    ("torque_chatter", "chatter [N m]", 1.0),
    ("saturated_fraction", "saturated [%]", 100.0),
    ("max_joint_limit_violation", "past a limit [rad]", 1.0),
    ("max_joint_speed", "max speed [rad/s]", 1.0),
    ("max_speed_ratio", "max speed / limit", 1.0),
    ("rms_torque_ratio", "RMS torque / limit, worst joint", 1.0),
)
"""(metric, label with unit, scale) of the delta table."""


def verdicts(metrics: dict, properties: Sequence[Property] = ()) -> dict[str, str]:
    """A run's verdicts: its status, each kind of warning (``yes``), each ``--require``
    property (``holds`` / ``fails``).
    """
    out = {"status": str(metrics.get("status", "completed"))}
    for warning in metrics.get("warnings", []):
        out[str(warning).split(":")[0]] = "yes"
    for prop in properties:
        out[prop.text] = "holds" if prop.holds(metrics) else "fails"
    return out


def _change(reference: float, value: float) -> str:
    if reference == value:
        return "="
    delta = value - reference
    relative = f", {100 * delta / abs(reference):+.3g} %" if reference else ""
    return f"{delta:+.3g}{relative}"


def delta_table(rows: list[tuple[str, dict]]) -> str:
    """Each metric of every run with its change from the first run's (absolute, then relative)."""
    cells = [["metric", rows[0][0]] + [f"{label} (change)" for label, _ in rows[1:]]]
    for key, label, scale in DELTA_METRICS:
        values = [metrics.get(key) for _, metrics in rows]
        if all(v is None for v in values):
            continue
        ref = values[0]
        row = [label, "-" if ref is None else f"{scale * ref:.4g}"]
        for value in values[1:]:
            if value is None or ref is None or not (math.isfinite(ref) and math.isfinite(value)):
                row.append("-" if value is None else f"{scale * value:.4g}")
            else:
                row.append(f"{scale * value:.4g} ({_change(scale * ref, scale * value)})")
        cells.append(row)
    widths = [max(len(r[i]) for r in cells) for i in range(len(cells[0]))]
    lines = [
        "  ".join(c.rjust(w) if i else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths))) for r in cells
    ]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def verdict_changes(rows: list[tuple[str, dict]], properties: Sequence[Property] = ()) -> list[str]:
    """One line per verdict that is not the same in every run: ``what: run a: x; run b: y``."""
    each = [(label, verdicts(metrics, properties)) for label, metrics in rows]
    keys = list(dict.fromkeys(k for _, v in each for k in v))
    lines = []
    for key in keys:
        seen = [v.get(key, "no") for _, v in each]
        if len(set(seen)) > 1:
            lines.append(f"{key}: " + "; ".join(f"{label}: {value}" for (label, _), value in zip(each, seen)))
    return lines
