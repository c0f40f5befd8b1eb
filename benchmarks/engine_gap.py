"""The sim-to-sim gap: every preset and controller, and every tuned setting of the fair
comparison, run on both true plants, Pinocchio's and MuJoCo's (plant.engine; docs/engines.md).

    python benchmarks/engine_gap.py --json docs/data/engine_gap.json [--tuned tuned-paper,tuned-panda]

Part 1 runs each preset with each controller at the preset's settings. Part 2 takes the kept
setting of each controller in each case of the tuned studies (benchmarks/studies/tuned-*.toml,
their reports docs/data/tuned_*.json: every law tuned at equal budget) and runs it on the case's
first two validation draws. Each row is one experiment run
on Pinocchio's plant and on MuJoCo (frictionloss, limit constraints), MuJoCo with
its RK4 (the default) and its implicitfast, each at the experiment's plant step and at 4x more
steps (their convergence), with the verdicts of the tuning's constraints (RMS torque, <= 1 %
saturated, no runaway, no stop hit) and the run's warnings in each.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

from nnrobust.config import CONTROLLER_KINDS
from nnrobust.config.presets import load_preset, preset_names
from nnrobust.core.exceptions import NNRobustError
from nnrobust.outputs.run_deltas import verdicts
from nnrobust.run.experiment import run_experiment
from nnrobust.run.properties import run_properties
from nnrobust.run.results import write_json_atomic

HERE = Path(__file__).resolve().parent
KEEP = (
    "status",
    "rms_error_after_2s",
    "max_error",
    "rms_torque",
    "torque_chatter",
    "saturated_fraction",
    "max_joint_limit_violation",
    "runaway",
    "friction_events",
    "realtime_factor",
    "warnings",
    "engine_audit",
)
FINE = 4
"""Times more plant steps of the convergence runs."""
HELD_OUT = 2
"""Held-out samples of each tuning that part 2 runs (of the four the tuning checked)."""


VARIANTS = {
    "pinocchio": {"plant": {"engine": "pinocchio"}},
    "mujoco": {"plant": {"engine": "mujoco"}},
    "mujoco_fine": {"plant": {"engine": "mujoco"}, "substeps": FINE},
    "implicitfast": {"plant": {"engine": "mujoco", "mujoco_integrator": "implicitfast"}},
    "implicitfast_fine": {
        "plant": {"engine": "mujoco", "mujoco_integrator": "implicitfast"},
        "substeps": FINE,
    },
}
"""Each experiment's runs: Pinocchio's plant; MuJoCo (RK4, the default) at the plant step and at
FINE times more steps (its convergence); MuJoCo's implicitfast likewise."""


def both_engines(config) -> dict:
    """The runs of ``config`` in every variant: the kept metrics of each."""
    from nnrobust.run.experiment import build

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        substeps = build(config).substeps  # the plant step the experiment chose
    out = {}
    for name, change in VARIANTS.items():
        variant = config.replace(plant=change["plant"])
        if "substeps" in change:
            variant = variant.replace(simulation={"substeps": substeps * change["substeps"]})
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                metrics = run_experiment(variant).metrics()
            except NNRobustError as err:
                out[name] = {"status": "refused", "message": str(err)[:300]}
                continue
        out[name] = {k: metrics.get(k) for k in KEEP}
    return out


def with_verdicts(row: dict, torque_limit: float) -> dict:
    """Add each engine's verdicts: the run's warnings and the tuning's constraints."""
    constraints = run_properties(
        [
            f"rms_torque<={torque_limit:g}",
            "saturated_fraction<=0.01",
            "runaway==false",
            "max_joint_limit_violation<=0",
        ]
    )
    row["verdicts"] = {
        name: verdicts(row[name], constraints) if "rms_torque" in row[name] else {} for name in VARIANTS
    }
    return row


def presets_part() -> list[dict]:
    rows = []
    for preset in preset_names():
        for controller in CONTROLLER_KINDS:
            config = load_preset(preset).replace(controller={"kind": controller})
            row = with_verdicts(
                {"preset": preset, "controller": controller, **both_engines(config)},
                35.0 if preset.startswith("panda") else 10.0,
            )
            rows.append(row)
            print_row(f"{preset} {controller}", row)
    return rows


def tuned_part(studies: list[str]) -> list[dict]:
    """Each kept setting of the tuned studies (benchmarks/studies/NAME.toml, their reports in
    docs/data/NAME.json) on the first HELD_OUT of its case's validation draws, as the study's
    validate stage drew them."""
    from nnrobust.studies.base.plan import base_config, draw, experiment
    from nnrobust.studies.base.tuned import tuned_entry
    from nnrobust.studies.study import load_study
    from nnrobust.studies.study.stages import VALIDATION_SEED, sweep_of

    rows = []
    for study in studies:
        spec = load_study(HERE / "studies" / f"{study}.toml")
        report = json.loads((HERE.parent / "docs" / "data" / f"{study.replace('-', '_')}.json").read_text())
        torque = report["budgets"]["max_rms_torque"]
        for case in spec.cases:
            name = spec.case_name(case)
            for controller, entry in report["cases"][name]["controllers"].items():
                label = f"{controller}-kept"
                entries = {label: tuned_entry(controller, entry["tuned"]["settings"], spec.entries)}
                sweep = sweep_of(spec, case, [label], entries, HELD_OUT, spec.seed + VALIDATION_SEED)
                base = base_config(sweep)
                for sample in range(HELD_OUT):
                    row = with_verdicts(
                        {
                            "case": name.removesuffix("-noisy"),
                            "sensing": "noisy" if name.endswith("-noisy") else "ideal",
                            "controller": controller,
                            "sample": sample,
                            **both_engines(experiment(sweep, base, draw(sweep, sample), label)),
                        },
                        torque,
                    )
                    rows.append(row)
                    print_row(f"{name} {controller} #{sample}", row)
    return rows


def print_row(label: str, row: dict) -> None:
    error = [row[name].get("rms_error_after_2s") for name in VARIANTS]
    pin, mj = row["verdicts"]["pinocchio"], row["verdicts"]["mujoco"]
    changed = sorted(k for k in set(pin) | set(mj) if pin.get(k, "no") != mj.get(k, "no"))
    cells = " ".join(f"{1e3 * e:10.4g}" if e is not None else f"{'-':>10s}" for e in error)
    print(f"{label:44s} {cells}  {'; '.join(changed)}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the rows to this file")
    parser.add_argument(
        "--tuned",
        default="tuned-paper,tuned-panda",
        help="the tuned studies whose kept settings part 2 runs (benchmarks/studies/NAME.toml)",
    )
    args = parser.parse_args()
    import mujoco

    start = time.perf_counter()
    print("RMS error t >= 2 s [mm] of each variant, and the verdicts that change from pinocchio to mujoco")
    print(f"{'experiment':44s} " + " ".join(f"{name[:10]:>10s}" for name in VARIANTS))
    presets = presets_part()
    tuned = tuned_part(args.tuned.split(","))
    if args.json:
        write_json_atomic(
            args.json,
            {
                "mujoco": mujoco.__version__,
                "held_out": HELD_OUT,
                "fine": FINE,
                "presets": presets,
                "tuned": tuned,
                "wall_seconds": time.perf_counter() - start,
            },
        )


if __name__ == "__main__":
    main()
