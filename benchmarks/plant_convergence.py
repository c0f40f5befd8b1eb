"""Is the plant step converged? Every preset x controller at the default plant step against a finer
one; runs that are chaotic are compared as distributions over probes.

    python benchmarks/plant_convergence.py --json docs/data/plant_convergence.json [--fine 64] [--workers 2]

For each preset and controller the run at the default step (one RK4 step per control period, cut
where a joint is fast: simulation.max_step_rotation) is compared with the same run at ``--fine``
steps per period: RMS error after 2 s and RMS torque must agree within 2 %, chatter within 10 %
(TOLERANCES). A chaotic run moves by more than that when the plant moves by a millionth, whatever
the step: its metrics are a distribution, not a number. Eight probe runs at the default step scale
the disturbance or the friction by 1 +- 1e-6 or 1 +- 2e-6 (a change injected at every step, as the
step's own truncation error is); where their spread exceeds a tolerance the run is chaotic. A
chaotic run is run with the same probes at the fine step too, and the two samples of nine are
compared: converged when, for every metric, its values (completed runs) do not differ between the
steps by a two-sided Mann-Whitney test at ALPHA or their medians agree within the tolerance, and the
number of runs that diverged does not differ either (Fisher's exact test). Runs that diverge at both
steps agree on the verdict. Each row also counts the stick-slip events the plant located, the steps
it could not resolve and the control periods whose step was cut for speed.
"""

from __future__ import annotations

import itertools

import numpy as np
from _common import parser, run_rows
from scipy.stats import fisher_exact, mannwhitneyu

from nnrobust.config import CONTROLLER_KINDS
from nnrobust.config.presets import load_preset, preset_names
from nnrobust.run.results import write_json_atomic

TOLERANCES = {"rms_error_after_2s": 0.02, "rms_torque": 0.02, "torque_chatter": 0.10}
"""Largest relative difference from the fine plant step that counts as converged."""

PROBE = 1e-6
"""Relative change of the disturbance or the friction in the probe runs that measure chaos."""

PROBES = {
    f"{key} x (1 {sign} {k}e-6)": {f"{key}_scale": 1 + (1 if sign == "+" else -1) * k * PROBE}
    for key in ("disturbance", "friction")
    for k in (1, 2)
    for sign in "+-"
}

ALPHA = 0.01
"""A chaotic run is not converged when its two steps' samples differ at this level."""


def _job(preset: str, kind: str, run: str, substeps: int, probe: dict | None = None) -> dict:
    changes = {"controller": {"kind": kind}, "simulation": {"substeps": substeps}}
    if probe:
        plant = load_preset(preset).plant
        changes["plant"] = {k: v * getattr(plant, k) for k, v in probe.items()}
    return {"preset": preset, "controller": kind, "run": run, "changes": changes}


def jobs(fine: int) -> list[dict]:
    """Per preset and controller: the default step, the fine step, and the probes at the default step."""
    out = []
    for preset, kind in itertools.product(preset_names(), CONTROLLER_KINDS):
        out += [_job(preset, kind, "default", 1), _job(preset, kind, "fine", fine)]
        out += [_job(preset, kind, name, 1, probe) for name, probe in PROBES.items()]
    return out


def fine_probe_jobs(preset: str, kind: str, fine: int) -> list[dict]:
    """The probes of a chaotic run at the fine step."""
    return [_job(preset, kind, f"fine {name}", fine, probe) for name, probe in PROBES.items()]


def _distributions(out: dict, coarse: list[dict], fine: list[dict]) -> bool:
    """Compare the two steps' samples of a chaotic run (written into ``out``); True if they agree:
    per metric, the Mann-Whitney test finds no difference at ALPHA or the medians differ by less
    than the metric's tolerance (a real difference smaller than the tolerance is convergence)."""
    diverged = [sum(r["status"] == "diverged" for r in runs) for runs in (coarse, fine)]
    p = fisher_exact([[diverged[0], len(coarse) - diverged[0]], [diverged[1], len(fine) - diverged[1]]])[1]
    out["diverged_runs"], out["fine_diverged_runs"], out["diverged_p"] = diverged[0], diverged[1], float(p)
    agree = p >= ALPHA
    for key, tol in TOLERANCES.items():
        a = [r[key] for r in coarse if r["status"] == "completed"]
        b = [r[key] for r in fine if r["status"] == "completed"]
        if len(a) >= 3 and len(b) >= 3:
            p = float(mannwhitneyu(a, b, alternative="two-sided").pvalue)
            ma, mb = float(np.median(a)), float(np.median(b))
            out[f"{key}_median"], out[f"fine_{key}_median"] = ma, mb
            out[f"{key}_median_difference"] = abs(ma - mb) / abs(mb) if mb else float(ma != mb)
            ok = p >= ALPHA or out[f"{key}_median_difference"] <= tol
        else:  # too few completed runs at one step to compare: the divergence counts decide
            p, ok = 1.0, True
        out[f"{key}_p"] = p
        agree = agree and ok
    return agree


def verdict(runs: list[dict]) -> dict:
    """The comparison of one preset x controller's runs (default, fine, probes at both)."""
    by = {r["run"]: r for r in runs}
    default, fine = by["default"], by["fine"]
    coarse = [r for r in runs if not r["run"].startswith("fine")]  # the default step and its probes
    fines = [r for r in runs if r["run"].startswith("fine")]
    out = {
        "preset": default["preset"],
        "controller": default["controller"],
        "status": default["status"],
        "fine_status": fine["status"],
        "friction_events": default["friction_events"],
        "unresolved_events": default["unresolved_events"],
        "fine_unresolved_events": fine["unresolved_events"],
        "refined_periods": default["refined_periods"],
    }
    both_diverged = default["status"] == fine["status"] == "diverged"
    out["both_diverged"] = both_diverged
    chaotic, close = False, default["status"] == fine["status"]
    for key, tol in TOLERANCES.items():
        a, b = default[key], fine[key]
        values = [r[key] for r in coarse]
        spread = float(max(values) - min(values))
        relative = abs(a - b) / abs(b) if b else (0.0 if a == b else float("inf"))
        out[key], out[f"fine_{key}"] = a, b
        out[f"{key}_relative_difference"], out[f"{key}_spread"] = relative, spread
        if both_diverged:  # what a run computes after it diverged measures nothing
            continue
        chaotic = chaotic or spread > tol * abs(b)
        close = close and relative <= tol
    out["chaotic"] = chaotic
    if chaotic:
        converged = _distributions(out, coarse, fines) if len(fines) > 1 else False
    else:
        converged = close or both_diverged
    out["converged"] = bool(converged and default["unresolved_events"] == 0)
    return out


def _collect_extra(row_job):
    """run_rows keeps only _common.ROW_METRICS; the event counts come from the metrics too."""
    from nnrobust.run.experiment import run_experiment

    metrics = run_experiment(load_preset(row_job["preset"]).replace(**row_job["changes"])).metrics()
    keep = ("status", *TOLERANCES, "friction_events", "unresolved_events", "refined_periods")
    return {**row_job, **{k: metrics.get(k) for k in keep}}


def main() -> None:
    p = parser(__doc__)
    p.add_argument("--fine", type=int, default=64, help="plant steps per control period of the reference")
    args = p.parse_args()
    all_jobs = jobs(args.fine)
    done = itertools.count(1)

    def progress(row):
        print(
            f"  [{next(done)}/{len(all_jobs)}] {row['preset']} {row['controller']} {row['run']}: "
            f"{row['status']}",
            flush=True,
        )

    rows = run_rows(all_jobs, args.workers, echo=progress, runner=_collect_extra)

    def key(r):
        return r["preset"], r["controller"]

    chaotic = [k for k, g in itertools.groupby(rows, key=key) if verdict(list(g))["chaotic"]]
    more = [job for preset, kind in chaotic for job in fine_probe_jobs(preset, kind, args.fine)]
    all_jobs += more
    rows += run_rows(more, args.workers, echo=progress, runner=_collect_extra)
    rows.sort(key=key)  # stable: each group keeps its order
    verdicts = [verdict(list(g)) for _, g in itertools.groupby(rows, key=key)]
    header = (
        f"{'preset':24s} {'controller':16s} {'rms e [mm]':>11s} {'d%':>6s} {'rms tau':>8s} {'d%':>6s} "
        f"{'chatter':>8s} {'d%':>6s} {'events':>7s} {'verdict':>10s}"
    )
    print(header)
    for v in verdicts:

        def pct(key):
            return f"{100 * v[f'{key}_relative_difference']:.2f}"

        label = ("converged" if v["converged"] else "NOT") + (
            " (diverged)" if v["both_diverged"] else " (chaotic)" if v["chaotic"] else ""
        )
        print(
            f"{v['preset']:24s} {v['controller']:16s} {1e3 * v['rms_error_after_2s']:11.4f} "
            f"{pct('rms_error_after_2s'):>6s} {v['rms_torque']:8.3f} {pct('rms_torque'):>6s} "
            f"{v['torque_chatter']:8.4f} {pct('torque_chatter'):>6s} {v['friction_events']:7d} "
            f"{label:>10s}"
        )
    print(
        f"{sum(v['converged'] for v in verdicts)} of {len(verdicts)} converged at one plant step per "
        f"period (reference: {args.fine})"
    )
    if args.json:
        write_json_atomic(
            args.json,
            {
                "fine": args.fine,
                "probe": PROBE,
                "probes": list(PROBES),
                "alpha": ALPHA,
                "tolerances": TOLERANCES,
                "rows": verdicts,
                "runs": rows,
            },
        )


if __name__ == "__main__":
    main()
