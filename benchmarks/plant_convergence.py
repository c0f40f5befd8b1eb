"""Is the plant step converged? Every preset x controller at the default plant step against a
finer one, with the spread under a millionth of a perturbation for runs that are chaotic.

    python benchmarks/plant_convergence.py --json docs/data/plant_convergence.json [--fine 64] [--workers 2]

For each preset and controller the run at the default step (one RK4 step per control period) is
compared with the same run at ``--fine`` steps per period: RMS error after 2 s and RMS torque
must agree within 2 %, chatter within 10 % (TOLERANCES). A chaotic run moves by more than that
when the plant moves by a millionth, whatever the step: its metrics are a spread, not a number.
Four probe runs at the default step scale the disturbance or the friction by 1 +- 1e-6 (a change
injected at every step, as the step's own truncation error is); where their spread exceeds a
tolerance the run is marked chaotic and the fine run must lie within the spread (plus the
tolerance). Runs that diverge at both steps agree on the verdict. Each row also counts the
stick-slip events the plant located and the steps it could not resolve.
"""

from __future__ import annotations

import itertools

from _common import parser, run_rows

from nnrobust.config import CONTROLLER_KINDS
from nnrobust.presets import load_preset, preset_names
from nnrobust.results import write_json_atomic

TOLERANCES = {"rms_error_after_2s": 0.02, "rms_torque": 0.02, "torque_chatter": 0.10}
"""Largest relative difference from the fine plant step that counts as converged."""

PROBE = 1e-6
"""Relative change of the disturbance or the friction in the probe runs that measure chaos."""

PROBES = {"disturbance x (1 + 1e-6)": {"disturbance_scale": 1 + PROBE},
          "disturbance x (1 - 1e-6)": {"disturbance_scale": 1 - PROBE},
          "friction x (1 + 1e-6)": {"friction_scale": 1 + PROBE},
          "friction x (1 - 1e-6)": {"friction_scale": 1 - PROBE}}


def jobs(fine: int) -> list[dict]:
    """Per preset and controller: the default step, the fine step, and the probes."""
    out = []
    for preset, kind in itertools.product(preset_names(), CONTROLLER_KINDS):
        base = {"preset": preset, "controller": kind}
        changes = {"controller": {"kind": kind}}
        out.append({**base, "run": "default", "changes": {**changes, "simulation": {"substeps": 1}}})
        out.append({**base, "run": "fine", "changes": {**changes, "simulation": {"substeps": fine}}})
        plant = load_preset(preset).plant
        for name, probe in PROBES.items():
            scaled = {k: v * getattr(plant, k) for k, v in probe.items()}
            out.append({**base, "run": name, "changes": {**changes, "plant": scaled,
                                                         "simulation": {"substeps": 1}}})
    return out


def verdict(runs: list[dict]) -> dict:
    """The comparison of one preset x controller's runs (default, fine, offsets)."""
    by = {r["run"]: r for r in runs}
    default, fine = by["default"], by["fine"]
    spread_runs = [r for r in runs if r["run"] != "fine"]  # the default step and its probes
    out = {"preset": default["preset"], "controller": default["controller"],
           "status": default["status"], "fine_status": fine["status"],
           "friction_events": default["friction_events"], "unresolved_events": default["unresolved_events"],
           "fine_unresolved_events": fine["unresolved_events"]}
    converged, chaotic = default["status"] == fine["status"], False
    both_diverged = default["status"] == fine["status"] == "diverged"
    out["both_diverged"] = both_diverged
    for key, tol in TOLERANCES.items():
        a, b = default[key], fine[key]
        values = [r[key] for r in spread_runs]
        spread = float(max(values) - min(values))
        relative = abs(a - b) / abs(b) if b else (0.0 if a == b else float("inf"))
        out[key] = a
        out[f"fine_{key}"] = b
        out[f"{key}_relative_difference"] = relative
        out[f"{key}_spread"] = spread
        if both_diverged:  # what a run computes after it diverged measures nothing
            continue
        if spread > tol * abs(b):
            chaotic = True
            ok = min(values) - tol * abs(b) <= b <= max(values) + tol * abs(b)
        else:
            ok = relative <= tol
        converged = converged and ok
    out["chaotic"] = chaotic
    out["converged"] = bool(converged and default["unresolved_events"] == 0)
    return out


def _collect_extra(row_job):
    """run_rows keeps only _common.ROW_METRICS; the event counts come from the metrics too."""
    from nnrobust.experiment import run_experiment

    metrics = run_experiment(load_preset(row_job["preset"]).replace(**row_job["changes"])).metrics()
    keep = ("status", *TOLERANCES, "friction_events", "unresolved_events")
    return {**row_job, **{k: metrics.get(k) for k in keep}}


def main() -> None:
    p = parser(__doc__)
    p.add_argument("--fine", type=int, default=64, help="plant steps per control period of the reference")
    args = p.parse_args()
    all_jobs = jobs(args.fine)
    done = iter(range(1, len(all_jobs) + 1))

    def progress(row):
        print(f"  [{next(done)}/{len(all_jobs)}] {row['preset']} {row['controller']} {row['run']}: "
              f"{row['status']}", flush=True)

    rows = run_rows(all_jobs, args.workers, echo=progress, runner=_collect_extra)
    groups = itertools.groupby(rows, key=lambda r: (r["preset"], r["controller"]))
    verdicts = [verdict(list(g)) for _, g in groups]
    header = (f"{'preset':24s} {'controller':16s} {'rms e [mm]':>11s} {'d%':>6s} {'rms tau':>8s} {'d%':>6s} "
              f"{'chatter':>8s} {'d%':>6s} {'events':>7s} {'verdict':>10s}")
    print(header)
    for v in verdicts:
        def pct(key):
            return f"{100 * v[f'{key}_relative_difference']:.2f}"

        label = ("converged" if v["converged"] else "NOT") + (
            " (diverged)" if v["both_diverged"] else " (chaotic)" if v["chaotic"] else "")
        print(f"{v['preset']:24s} {v['controller']:16s} {1e3 * v['rms_error_after_2s']:11.4f} "
              f"{pct('rms_error_after_2s'):>6s} {v['rms_torque']:8.3f} {pct('rms_torque'):>6s} "
              f"{v['torque_chatter']:8.4f} {pct('torque_chatter'):>6s} {v['friction_events']:7d} "
              f"{label:>10s}")
    print(f"{sum(v['converged'] for v in verdicts)} of {len(verdicts)} converged at one plant step per "
          f"period (reference: {args.fine})")
    if args.json:
        write_json_atomic(args.json, {"fine": args.fine, "probe": PROBE, "tolerances": TOLERANCES,
                                      "rows": verdicts, "runs": rows})


if __name__ == "__main__":
    main()
