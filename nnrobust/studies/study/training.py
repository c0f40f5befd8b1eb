"""The train stage of a study's case (:mod:`.stages`' table): each policy entry with a ``train``
table trained with Stable-Baselines3 (each seed a task on the study's cluster, on the kept setting
of the law the study tunes as its base), its seeds validated on the case's validation draws and
the best feasible one kept, as a tuned law's seeds are (docs/study.md#trained-policies).
"""

from __future__ import annotations

from pathlib import Path

from ...controllers.laws.policy import policy_params
from ...core.exceptions import ConfigError, NNRobustError
from .case_run import TRAIN_SEED, VALIDATION_SEED, CaseRun, seed_name, sweep_of
from .selection import select_kept
from .spec import StudySpec

# ---- 3. train: the learned policies, on the kept settings of their base laws --------------------


def policy_path(run: CaseRun, controller: str, seed: int) -> Path:
    """The policy file a trained controller's seed writes (with its record beside it)."""
    return run.here / "train" / seed_name(controller, seed) / "policy.onnx"


def _base_kept(run: CaseRun, controller: str) -> tuple[Path | None, dict]:
    """(the file that gives a trained policy's base law its kept setting, that setting): the base
    law's kept setting when the study tunes it (a residual learns on the best model-based law the
    study found), else (None, {}): the base at the case's own settings.
    """
    from ...run.results import write_json_atomic

    base = run.spec.trained[controller].get("base")
    if base is None:
        return None, {}
    kept = run.out["kept"].get(base)
    if kept is None:
        raise NNRobustError(
            f"{run.name}: {controller} learns on {base}'s kept setting, and {base} has none "
            f"({run.out['not_kept'].get(base, 'not kept')})"
        )
    settings = dict(kept["settings"])
    file = run.here / "train" / f"{controller}-base.json"
    file.parent.mkdir(parents=True, exist_ok=True)
    write_json_atomic(file, {"controllers": {base: {"best": {"params": settings}}}})
    return file, settings


def train_seed(case_file: str, out: str, options: dict) -> dict:
    """One seed of a trained policy (:func:`nnrobust.studies.learning.rl.train`), on a worker."""
    from ..learning.rl import train as train_policy

    return train_policy(case_file, out, progress=None, **options)


def train(run: CaseRun):
    """Each trained policy's seeds (PPO or SAC, on the case's box, at its entry's budget of
    simulated seconds; ``train/NAME-seedS/``), side by side on the study's cluster; a seed whose
    record is the same training is kept (a rerun computes nothing). Then every seed's policy is
    validated on the validation draws (``validate-train/``) and the best feasible one kept, as a
    tuned law's seeds are.
    """
    from ..base.cluster import cluster_client, run_tasks
    from ..base.plan import load_sweep
    from ..base.tuned import tuned_entry
    from ..learning.rl import experiment_sha256, hyper_settings, stored_training

    spec, b, trained = run.spec, run.spec.budgets, run.spec.trained
    if not trained:
        return "skipped: no policy to train (no entry with a train table)"
    jobs, kept_base, records = [], {}, {}
    for c, table in trained.items():
        params = policy_params(spec.entries[c].get("params"))
        action, base = params["action"], params["base"]
        tuned_file, settings = _base_kept(run, c)
        kept_base[c] = settings
        # the episodes: the case's experiment and box, its base law's row (the observation's model)
        episodes = run.here / "train" / f"{c}.toml"
        episodes.parent.mkdir(parents=True, exist_ok=True)
        run.stage_file(episodes, sweep_of(spec, run.case, [base], {}, 1, spec.seed + TRAIN_SEED).to_toml())
        sha = experiment_sha256(episodes)
        for s in range(table["seeds"]):
            path = policy_path(run, c, s)
            path.parent.mkdir(parents=True, exist_ok=True)
            options = {"algorithm": table["algorithm"], "budget": table["budget"], "action": action,
                       "controller": base, "seed": spec.seed + TRAIN_SEED + s,
                       "num_envs": table["num_envs"], "validation_episodes": table["curve_episodes"],
                       "eval_every": table["budget"] / table["curve_points"],
                       "hyper": table["hyper"] or None,
                       "residual_scale": params["residual_scale"], "gain_range": params["gain_range"],
                       "tuned": str(tuned_file) if tuned_file else None}  # fmt: skip
            wanted = {"experiment_sha256": sha, "algorithm": table["algorithm"],
                      "budget_seconds": table["budget"], "action": action, "tuned_file": options["tuned"],
                      "hyper": hyper_settings(table["algorithm"], table["hyper"]), "controller": base,
                      **({"tuned_settings": settings} if tuned_file else {})}  # fmt: skip
            try:
                stored = stored_training(path, wanted, where=f"{run.name}: train")
            except ConfigError:
                if not run.overwrite:
                    raise
                stored = None
            if stored is not None:
                records[(c, s)] = stored
            else:
                jobs.append(((c, s), (train_seed, str(episodes), str(path), options)))
    said = [
        f"{c} ({t['algorithm']}, {t['seeds']} seed{'s' * (t['seeds'] != 1)}, {t['budget']:g} simulated s)"
        for c, t in trained.items()
    ]
    before = f"; {len(records)} seed{'s' if len(records) != 1 else ''} trained before" if records else ""
    run.say(f"{run.name}: train {', '.join(said)}{before}")

    def crashed(reason):
        raise NNRobustError(f"{run.name}: a policy's training ended its worker: {reason}")

    def work():
        if jobs:
            if run.progress:
                run.progress(len(records), len(records) + len(jobs))
            with cluster_client(None, run.address) as client:
                done = run_tasks(client, [task for _, task in jobs], crashed)
            records.update(zip([key for key, _ in jobs], done))
        names, entries, setting_of = [], {}, {}
        for (c, s), record in sorted(records.items()):
            label = seed_name(c, s)
            settings = {**kept_base[c], "controller.params.file": str(policy_path(run, c, s))}
            names.append(label)
            entries[label] = tuned_entry(c, settings, spec.entries)
            setting_of[label] = (c, s, settings, [])
        sweep = sweep_of(spec, run.case, names, entries, b["validation"], spec.seed + VALIDATION_SEED)
        file = run.here / "validate-train.toml"
        run.stage_file(file, sweep.to_toml())
        validate_spec = load_sweep(file)
        run.say(
            f"{run.name}: validate {len(names)} trained policies on the {b['validation']} validation draws"
        )
        rows = validated(validate_spec, run, run.here / "validate-train")
        return records, setting_of, validate_spec, rows

    return work


def validated(sweep, run: CaseRun, folder: Path):
    """The rows of ``sweep`` run into ``folder`` on the study's cluster."""
    from ..sweep.engine import read_results, run_sweep

    run_sweep(sweep, folder, scheduler=run.address, overwrite=run.overwrite, progress=run.progress,
              ship_files=run.ship)  # fmt: skip
    return read_results(folder)


def trained_report(run: CaseRun, result) -> None:
    """The trained policies' kept seeds (beside the tuned laws'), their records and curves."""
    from ..learning.rl import write_curves
    from ..sweep.summary import summarize, write_summary

    records, setting_of, validate_spec, frame = result
    spec, out = run.spec, run.out
    write_summary(run.here / "validate-train", summarize(validate_spec, frame))
    kept, per_seed, infeasible = select_kept(spec, frame, setting_of)
    for c, reason in infeasible.items():
        out["not_kept"][c] = reason
        run.say(f"{run.name}: {c} is not kept: {reason}")
    if not out["kept"] and not kept:
        raise NNRobustError(
            f"{run.name}: no controller is feasible on the validation draws "
            f"({'; '.join(infeasible.values())})"
        )
    out["kept"].update(kept)
    out["per_seed"].update(per_seed)
    out.setdefault("trained", {})
    for c, table in spec.trained.items():
        mine = [records[key] for key in sorted(records) if key[0] == c]
        tuned = {law: seconds for law, seconds in out.get("training", {}).items() if law not in spec.trained}
        write_curves(run.here / "train" / c, mine, tuned, seed_offset=spec.seed + TRAIN_SEED)
        out["trained"][c] = {
            **{
                k: table[k]
                for k in ("algorithm", "budget", "seeds", "num_envs", "curve_points", "curve_episodes")
            },
            "base_settings": next((r["tuned"]["settings"] for r in mine if r.get("tuned")), None),
            "simulated_seconds": sum(r["simulated_seconds"] for r in mine),
            "wall_seconds": sum(r["wall_seconds"] for r in mine),
            "curves": {int(r["seed"]) - spec.seed - TRAIN_SEED: r["curve"] for r in mine},
            "convergence": learning_convergence(spec, mine),
            "records": [str(policy_path(run, c, s)) + ".json" for s in range(table["seeds"])],
        }
        out.setdefault("training", {})[c] = out["trained"][c]["simulated_seconds"]
        if c in kept:
            out.setdefault("convergence", {})[c] = out["trained"][c]["convergence"]


def learning_convergence(spec: StudySpec, records: list[dict]) -> dict:
    """Whether a policy's training converged at its budget, judged as a tuning's is.

    The least final validation error of its seeds' learning curves, m(B), against the same at the
    curve's point nearest half the budget, m(B/2); converged when |m(B/2) / m(B) - 1| <= the
    tolerance (on the curve's own validation episodes, not the study's draws).
    """
    import math

    def at(record: dict, seconds: float) -> float:
        point = min(record["curve"], key=lambda p: abs(p["simulated_seconds"] - seconds))
        value = point["median_rms_error_after_2s"]
        return value if math.isfinite(value) else math.inf

    budget = records[0]["budget_seconds"] if records else 0.0
    full = min((at(r, r["simulated_seconds"]) for r in records), default=math.inf)
    half = min((at(r, r["simulated_seconds"] / 2) for r in records), default=math.inf)
    tolerance = spec.budgets["tolerance"]
    change = half / full - 1 if math.isfinite(half) and math.isfinite(full) and full > 0 else None
    return {
        "budget": budget,
        "half_budget": budget / 2,
        "unit": "simulated seconds",
        "kept_median": full if math.isfinite(full) else None,
        "kept_median_half": half if math.isfinite(half) else None,
        "change": change,
        "tolerance": tolerance,
        "converged": change is not None and abs(change) <= tolerance,
        "judged_on": "each seed's learning curve (its own validation episodes)",
    }
