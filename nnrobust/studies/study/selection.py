"""Which tuned setting a study keeps: every seed's best validated on fresh draws, judged under the
study's constraints there, the least median error among the feasible ones, and whether the
budget converged (the same selection at half the budget).
"""

from __future__ import annotations

import math

from .spec import StudySpec


def half_name(label: str) -> str:
    """The validation entry of a seed's best setting at half the budget."""
    return f"{label}-half"


def validation_runs(frame, label: str) -> list[dict]:
    """The validation rows of one entry, as the tuner judges runs (status and metrics)."""
    return frame[frame["controller"] == label].sort_values("sample").to_dict("records")


def judged(spec: StudySpec, runs: list[dict]) -> tuple[bool, dict, dict]:
    """(feasible, the constraints' values, the mean metrics) of runs under the study's tuning
    constraints (:func:`nnrobust.studies.tune.engine.judge`: RMS torque, saturated share, no runaway, no
    stop hit, every run completed).
    """
    from ..tune.engine import CONSTRAINTS, TuneSpec, judge

    b = spec.budgets  # the constraints the study's tunings ran under
    limits = TuneSpec(
        str(spec.path), ["pd"], 2, max_rms_torque=b["max_rms_torque"], max_saturated=b["max_saturated"]
    )
    _, constraints, mean = judge(limits, runs)
    return all(v <= 0 for v in constraints), dict(zip(CONSTRAINTS, constraints)), mean


def select_kept(spec: StudySpec, frame, setting_of: dict) -> tuple[dict, dict, dict]:
    """Each controller's kept setting: among its seeds *feasible on the validation draws* (the
    study's constraints judged on the draws that rank them, as the tuner judged the training
    draws), the one with the least median RMS error after 2 s (a run that did not complete counts
    as +inf; ties: the lower seed); every seed's validation statistics and feasibility; and, per
    controller with no feasible seed, why ("infeasible on validation", with the numbers).
    """
    import numpy as np

    from ..base.paired import metric_values
    from ..tune.engine import infeasible_text

    limits = {
        "max_rms_torque": spec.budgets["max_rms_torque"],
        "max_saturated": spec.budgets["max_saturated"],
    }
    per_seed: dict[str, list] = {}
    for label, (c, seed, settings, at_bound) in setting_of.items():
        rows = frame[frame["controller"] == label]
        values = np.array(list(metric_values(rows, "rms_error_after_2s").values()))
        feasible, constraints, mean = judged(spec, validation_runs(frame, label))
        per_seed.setdefault(c, []).append(
            {
                "seed": seed,
                "settings": settings,
                "at_bound": at_bound,
                "median_error": float(np.median(values)) if values.size else float("inf"),
                "rows": int(values.size),
                "completed": int(np.isfinite(values).sum()),
                "feasible": feasible,
                "validation": {k: mean.get(k) for k in ("rms_torque", "saturated_fraction", "runaway",
                                                        "max_joint_limit_violation", "status")},
                "why_infeasible": "" if feasible else infeasible_text(limits, mean, constraints),
            }
        )  # fmt: skip
    kept, infeasible = {}, {}
    for c, entries in per_seed.items():
        fit = [e for e in entries if e["feasible"] or e["seed"] is None]  # an untuned law is what it is
        if fit:
            kept[c] = min(fit, key=lambda e: (e["median_error"], e["seed"] if e["seed"] is not None else -1))
        else:
            infeasible[c] = "infeasible on validation: " + "; ".join(
                f"seed {e['seed']}: {e['why_infeasible']}" for e in entries
            )
    return kept, per_seed, infeasible


def convergence(spec: StudySpec, frame, labels: list[str], halves: dict) -> dict:
    """Whether a law's tuning converged at its budget: its kept median m(B) (the least validation
    median of its feasible seeds) against the same at half the budget, m(B/2), from each seed's
    best setting after half its simulations, validated on the same draws. Converged when
    |m(B/2) / m(B) - 1| <= the study's tolerance: doubling the budget from B/2 to B moved the
    kept result by less than the tolerance.
    """
    import numpy as np

    from ..base.paired import metric_values

    def kept_median(names: list[str]) -> float:
        medians = []
        for label in names:
            values = np.array(
                list(metric_values(frame[frame["controller"] == label], "rms_error_after_2s").values())
            )
            if values.size and judged(spec, validation_runs(frame, label))[0]:
                medians.append(float(np.median(values)))
        return min(medians) if medians else float("inf")

    full = kept_median(labels)
    half = kept_median([halves[label] for label in labels if label in halves])
    tolerance = spec.budgets["tolerance"]
    change = half / full - 1 if math.isfinite(half) and math.isfinite(full) and full > 0 else None
    return {
        "budget": spec.budgets["tune"],
        "half_budget": spec.budgets["tune"] // 2,
        "kept_median": full if math.isfinite(full) else None,
        "kept_median_half": half if math.isfinite(half) else None,
        "change": change,
        "tolerance": tolerance,
        "converged": change is not None and abs(change) <= tolerance,
    }
