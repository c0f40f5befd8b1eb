"""Many runs on dask.distributed: sweep, falsify, study, tune."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..core.exceptions import ConfigError, one_line
from ..studies.study.stage_table import study_description
from .common import (
    Command,
    keep_count,
    resumable,
)
from .console import (
    BAR_OPEN,
    bar,
)


def cmd_sweep(args) -> int:
    """Run or resume a robustness sweep on dask.distributed."""
    import time

    from ..studies.sweep import load_sweep, read_results, run_sweep
    from ..studies.sweep.summary import format_summary, keep_worst, plot_sweep, summarize, write_summary

    spec = load_sweep(args.sweep)
    if args.tuned:  # each controller at its best setting of a tuning, as NAME-tuned
        from ..studies.base.tuned import check_tuned_values, tuned_settings, with_controllers

        tuned = tuned_settings(args.tuned, spec.controllers, spec.vary, spec.entries)
        spec = with_controllers(spec, spec.controllers, tuned)
        check_tuned_values(spec, tuned)
    out = Path(args.out)
    properties, claim = _sweep_claim(args, spec)

    def progress(done, total):
        if args.quiet:
            return
        if not started:  # the sweep validated and its cluster is up
            started.append(time.monotonic())
            where = args.scheduler or f"a local cluster of {args.workers or 'one worker per core'}"
            print(
                f"sweep {spec.name}: {spec.size} samples x {len(spec.controllers)} controllers on "
                f"{where}; {done} of {total} rows already done",
                file=sys.stderr,
            )
        if len(started) == 1:
            started.append(done)  # rows already there when the sweep started
        elapsed = time.monotonic() - started[0]
        rate = (done - started[1]) / elapsed if elapsed > 0 else 0.0
        eta = f"{(total - done) / rate:.0f} s" if rate > 0 else "?"
        bar(done, total, f"rows, {rate:.2f}/s, ETA {eta}")

    started: list[float] = []
    checking_since = time.monotonic()
    checking_shown: list[bool] = []

    def checking(done, total):  # 10^6 rows take minutes to validate: said after a second
        if args.quiet:
            return
        elapsed = time.monotonic() - checking_since
        if not checking_shown and (elapsed < 1.0 or done == total):  # quick: nothing to show
            return
        if not checking_shown:
            checking_shown.append(True)
            print(
                f"sweep {spec.name}: checking the experiments of {total} rows before any of them runs",
                file=sys.stderr,
            )
        eta = f"{elapsed * (total - done) / done:.0f} s" if done else "?"
        bar(done, total, f"rows checked, ETA {eta}")
        if done == total:
            print(file=sys.stderr)

    stop = None
    if args.stop_early:
        from ..core.exceptions import ConfigError
        from ..run.properties import refuted_groups

        if not claim:
            raise ConfigError(
                "--stop-early", "stops once a claim is refuted: give --require, --epsilon and --beta"
            )
        stop = lambda records: refuted_groups(spec, records, properties, *claim)  # noqa: E731
    counts = resumable(
        lambda: run_sweep(
            spec, out, args.workers, args.scheduler, args.overwrite, progress, stop=stop, checking=checking
        ),
        lambda: (
            f"sweep interrupted; the rows written so far are in {out}/results"
            if (out / "results").is_dir()
            else "sweep interrupted before any row was written"
        ),
    )
    if counts is None:
        return 130
    if started:
        print(file=sys.stderr)
    frame = read_results(out)
    summary = summarize(spec, frame)
    certified = {}
    if properties and claim:
        from ..run.properties import certify

        certified = certify(spec, frame, properties, *claim, stopped_early=bool(counts.get("stopped")))
        for controller, entry in certified.items():
            summary["controllers"][controller].update(entry)
    write_summary(out, summary)
    plot_sweep(spec, frame, out)
    if args.keep_worst:
        kept = keep_worst(spec, frame, out, args.keep_worst)
        if not args.quiet:
            print(f"run folders of the worst samples: {', '.join(str(p) for p in kept)}", file=sys.stderr)
    if not args.quiet:
        print(format_summary(summary))
        if certified:
            from ..run.properties import format_certificates

            print("\n".join(format_certificates(certified)))
        for controller, entry in summary["controllers"].items():
            if "worst" in entry:
                print(f"worst {controller}: sample {entry['worst']['sample']}: {entry['worst']['command']}")
        stopped = f", {counts['stopped']} not run (claim already refuted)" if counts.get("stopped") else ""
        print(
            f"{counts['computed']} rows computed, {counts['skipped']} already there{stopped}; results in "
            f"{out}/results (pandas.read_parquet), summary in {out}/summary.json",
            file=sys.stderr,
        )
    return _broken_rows(frame)


def _broken_rows(frame) -> int:
    """1 (and a line on stderr) when a row ended with status ``crashed`` (its worker died) or
    ``error`` (a defect): such a sweep is not a result to cite; 0 otherwise.
    """
    broken = frame[frame["status"].isin(["crashed", "error"])]
    if not len(broken):
        return 0
    first = broken.iloc[0]
    print(
        f"nnrobust: {len(broken)} rows ended without a result ({', '.join(sorted(set(broken['status'])))}); "
        f"first: sample {first['sample']}, {first['controller']}: {one_line(str(first['message']))}",
        file=sys.stderr,
    )
    return 1


def _sweep_claim(args, spec) -> tuple[list, tuple[float, float] | None]:
    """(the properties of --require, (epsilon, beta) or None), the sweep's size checked against
    the claim before anything runs.
    """
    from ..run.properties import check_claim, confidence_text, run_properties, samples_needed

    properties = run_properties(args.require)
    if (args.epsilon is None) != (args.beta is None):
        raise ConfigError("--epsilon", "give --epsilon and --beta together (the claim and its confidence)")
    if args.epsilon is None:
        if properties:
            raise ConfigError(
                "--require",
                "needs --epsilon and --beta: the claim P(fail) <= EPSILON with "
                "confidence 1 - BETA that the sweep certifies",
            )
        return properties, None
    if not properties:
        raise ConfigError("--epsilon", "certifies the properties of --require; give at least one")
    check_claim(args.epsilon, args.beta, args.failures)
    needed = samples_needed(args.epsilon, args.beta, args.failures)
    if spec.samples < needed and not args.allow_small:
        cell = " per grid point" if spec.grid_keys else ""
        raise ConfigError(
            "samples",
            f"P(fail) <= {args.epsilon:g} with confidence {confidence_text(args.beta)} needs "
            f"N >= {needed} samples{cell} with at most {args.failures} failures; the sweep "
            f"draws {spec.samples}: raise samples, or --allow-small to report the bound anyway",
        )
    return properties, (args.epsilon, args.beta)


def simulations_bar(quiet: bool, first_line):
    """(progress(done, total), started): a bar of simulations, after one line ``first_line(done,
    total)`` says what runs; ``started`` holds the start time once it has.
    """
    import time

    started: list[float] = []

    def progress(done, total):
        if quiet:
            return
        if not started:
            started.append(time.monotonic())
            print(first_line(done, total), file=sys.stderr)
        bar(done, total, f"simulations, {time.monotonic() - started[0]:.0f} s")

    return progress, started


def cmd_study(args) -> int:
    """Run (or resume) a study: tune, validate, certify and falsify every case, then the report."""
    import time

    from ..studies.study import load_study, run_study
    from ..studies.study.tables import console_line, table_rows

    spec = load_study(args.study)
    start = time.monotonic()

    def say(line: str) -> None:
        if not args.quiet:
            print(f"\rstudy {spec.name} [{time.monotonic() - start:.0f} s] {line}".ljust(60), file=sys.stderr)
            BAR_OPEN[0] = False

    def progress(done: int, total: int) -> None:
        if not args.quiet:
            bar(done, total, f"of the stages now running, {time.monotonic() - start:.0f} s in all")

    report = resumable(
        lambda: run_study(spec, args.out, args.workers, args.scheduler, args.overwrite, say, progress),
        f"study interrupted; each stage keeps what it computed under {args.out}/cases",
    )
    if report is None:
        return 130
    if not args.quiet:
        print(file=sys.stderr)
        for row in table_rows(report):
            print(console_line(row))
        for name, case in report["cases"].items():
            for controller, reason in case["not_kept"].items():
                print(f"{name:24s} {controller:18s} not kept: {reason}")
        if report.get("composed_claim"):
            from ..studies.study.html import composed_text

            print(f"composed claim: {composed_text(report['composed_claim'])}")
        for warning in report.get("warnings", []):
            print(f"warning: {warning}", file=sys.stderr)
        print(f"report in {args.out}/report.html and {args.out}/report.json", file=sys.stderr)
    return 0


def cmd_falsify(args) -> int:
    """Search each controller's worst plant in the sweep file's box, at one budget."""
    from ..studies.falsify import FalsifySpec, run_falsify
    from ..studies.falsify.summary import replayed_worst

    controllers = [c.strip() for c in args.controllers.split(",") if c.strip()]
    tuned = None
    if args.tuned:
        from ..studies.base.tuned import tuned_settings
        from ..studies.sweep import load_sweep

        box = load_sweep(args.sweep)
        tuned = tuned_settings(args.tuned, controllers, box.vary, box.entries)
    spec = FalsifySpec(args.sweep, controllers, args.require, args.budget, args.seed, args.margin, tuned)
    progress, started = simulations_bar(
        args.quiet,
        lambda done, total: (
            f"falsify {args.sweep}: {', '.join(spec.controllers)}, {spec.budget} simulations each and as "
            f"many for random search; {done} of {total} already done"
        ),
    )

    out = Path(args.out)
    summary = resumable(
        lambda: run_falsify(
            spec, out, args.workers, args.scheduler, args.overwrite, progress, (args.epsilon, args.beta)
        ),
        f"search interrupted; the plants simulated so far are in {out}/history",
    )
    if summary is None:
        return 130
    if started:
        print(file=sys.stderr)
    if not args.quiet:
        for name, entry in summary["controllers"].items():
            baseline = entry["random_baseline"]
            worst, found_by = replayed_worst(entry)
            verdict = "FALSIFIED" if entry["falsified"] else "not falsified"
            if found_by == "random":
                verdict = "FALSIFIED by random search only (the search found none)"
            status = worst["metrics"].get("status", "completed")
            ended = (
                f" (the run ended {status}: {one_line(str(worst['metrics'].get('message', '')))})"
                if status != "completed"
                else ""
            )
            print(
                f"{name}: {verdict} in {entry['simulations']} simulations; least margin "
                f"{worst['margin']:.4g}{ended} (random search: {baseline['worst']['margin']:.4g}); "
                f"worst plant: {worst['command']}"
            )
        if summary.get("searched_as"):
            print(f"searched: {summary['searched_as']}")
        for name, margin in summary.get("margin", {}).items():
            print(format_margin(name, margin))
        from ..run.properties import format_certificates

        certified = {name: entry["certificate"] for name, entry in summary["controllers"].items()}
        print("from the random baseline (independent draws of the box):")
        print("\n".join(f"  {line}" for line in format_certificates(certified)))
        print(
            f"summary in {out}/summary.json, history in {out}/history, {out}/falsification.csv",
            file=sys.stderr,
        )
    if args.keep_worst:
        from ..studies.falsify import keep_worst

        for folder in keep_worst(spec, summary, out, args.keep_worst):
            if not args.quiet:
                print(f"worst plant kept: {folder}/ (nnrobust view {folder})", file=sys.stderr)
    return 0


def format_margin(name: str, margin: dict) -> str:
    """One controller's robustness margin in a line: the largest scale of the box searched without
    a violation, and the scale and plant that violated.
    """
    plant, low, high = margin["violating_plant"], margin["holds_up_to"], margin["violated_at"]
    if high == 0.0:
        return f"{name}: margin 0 (the nominal plant, the centre of the box, fails: {plant['command']})"
    held = f"no violation found up to {low:.3g} x the box with {margin['simulations']} simulations"
    if high is None:
        return f"{name}: margin >= {low:.3g} ({held}, the largest scale tried)"
    return f"{name}: margin {low:.3g} ({held}; violated at {high:.3g} x by {plant['command']})"


def format_tuning(summary: dict) -> str:
    """Each controller's best setting under the constraints: errors on the training and the
    held-out samples, torque, chatter, the bounds it sits on, and the keys it does not search
    with why.
    """
    from ..studies.tune.engine import infeasible_text
    from ..studies.tune.space import fixed_text

    lines = [
        f"{'':14s} {'training draws':^29s}   {'held-out draws':^29s}",
        f"{'controller':14s} {'e [mm]':>10s} {'tau [N m]':>9s} {'chatter':>8s}   {'e [mm]':>10s} "
        f"{'tau [N m]':>9s} {'feasible':>8s}  setting",
    ]
    for name, entry in summary["controllers"].items():
        best = entry["best"]
        fixed = [f"{'':14s} not searched, {line}" for line in fixed_text(entry.get("fixed", {}).items())]
        if best is None:
            lines += [f"{name:14s} {entry['note']}", *fixed]
            continue
        held = best["validation"]
        feasible = best.get("validation_feasible")
        settings = ", ".join(
            f"{k} = {v[0] if isinstance(v, list) else v:.4g}" for k, v in best["params"].items()
        )

        def number(value, scale=1.0, width=10, digits=4):
            return f"{'-' if value is None else f'{scale * value:.{digits}g}':>{width}s}"

        train = best["train"]
        lines.append(
            f"{name:14s} {number(train['rms_error_after_2s'], 1e3)} "
            f"{number(train['rms_torque'], width=9)} {number(train['torque_chatter'], width=8)}"
            f"   {number(held.get('rms_error_after_2s'), 1e3)} {number(held.get('rms_torque'), width=9)} "
            f"{'-' if feasible is None else 'yes' if feasible else 'NO':>8s}  {settings}"
        )
        if feasible is False:
            why = infeasible_text(summary["constraints"], held, best["validation_constraints"])
            lines.append(f"{'':14s} infeasible on validation: {why}")
        for b in best["at_bound"]:
            lines.append(
                f"{'':14s} at the {b['side']} bound of {b['param']} ({b['bound']:.4g})"
                + (f": {b['physical']}" if b["physical"] else "")
            )
        lines += fixed
    return "\n".join(lines)


def cmd_tune(args) -> int:
    """Tune every controller by one optimiser at one budget; validate on held-out samples."""
    import math

    from ..config import parse_override
    from ..studies.tune import TuneSpec, run_tune

    spec = TuneSpec(
        args.target,
        [c.strip() for c in args.controllers.split(",") if c.strip()],
        args.budget,
        args.train_samples,
        args.validation,
        math.inf if args.max_rms_torque is None else args.max_rms_torque,
        1.0 if args.max_saturated is None else args.max_saturated,
        args.seed,
        dict(parse_override(item) for item in args.set or ()),
    )
    progress, started = simulations_bar(
        args.quiet,
        lambda done, total: (
            f"tune {args.target}: {', '.join(spec.controllers)}, {spec.budget} simulations each "
            f"({spec.trials} settings x {spec.train_samples} samples); {done} of {total} already done"
        ),
    )

    out = Path(args.out)
    summary = resumable(
        lambda: run_tune(spec, out, args.workers, args.scheduler, args.overwrite, progress),
        f"tuning interrupted; the settings tried so far are in {out}/trials",
    )
    if summary is None:
        return 130
    if started:
        print(file=sys.stderr)
    if not args.quiet:
        print(format_tuning(summary))
        print(
            f"summary in {out}/summary.json, settings in {out}/trials (pandas.read_parquet), Pareto fronts "
            f"in {out}/pareto.png",
            file=sys.stderr,
        )
    never = [
        name
        for name, entry in summary["controllers"].items()
        if entry["simulations"] and entry.get("runs_without_result") == entry["simulations"]
    ]
    if never:  # as a sweep whose rows ended without a result: the command did not do its work
        first = summary["controllers"][never[0]].get("note", "").partition("(first: ")[2].removesuffix(")")
        print(
            one_line(
                f"nnrobust: {', '.join(never)}: every run ended without a result (refused, raised or "
                f"crashed{'; first: ' + first if first else ''}): see {out}/summary.json"
            ),
            file=sys.stderr,
        )
        return 1
    return 0


def sweep_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust sweep``."""
    from ..studies.base.plan import shipped_sweeps

    parser.add_argument(
        "sweep", help=f"sweep file (TOML), or a shipped sweep file by name: {', '.join(shipped_sweeps())}"
    )
    parser.add_argument("--out", required=True, help="sweep folder (results/, sweep.toml, summary.json)")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the results of a different sweep in --out"
    )
    parser.add_argument(
        "--keep-worst",
        type=keep_count,
        default=0,
        metavar="K",
        help="write full run folders (with animation) of the K worst samples of each "
        "controller into DIR/worst/",
    )
    parser.add_argument(
        "--tuned",
        metavar="DIR",
        help="run each controller at its best setting in this tuning (nnrobust tune's DIR or its "
        "summary.json, a study's cases/CASE/kept.json, or REPORT.json#CASE of a study's report), as "
        "NAME-tuned; every law takes them: shipped, registered, custom entries",
    )
    parser.add_argument(
        "--require",
        action="append",
        metavar="EXPR",
        default=[],
        help="a property every run should have, METRIC OP VALUE (repeatable), e.g. "
        "'rms_error_after_2s<=0.05', 'runaway==false'; with --epsilon and --beta, "
        "summary.json gets a certificate per controller (docs/robustness.md)",
    )
    parser.add_argument("--epsilon", type=float, help="claim P(a property fails) <= EPSILON ...")
    parser.add_argument("--beta", type=float, help="... with confidence 1 - BETA (one-sided Clopper-Pearson)")
    parser.add_argument(
        "--failures",
        type=int,
        default=0,
        metavar="K",
        help="plan the sample size for up to K failures (default 0)",
    )
    parser.add_argument(
        "--allow-small",
        action="store_true",
        help="run a sweep too small to prove the claim, and report its bound anyway",
    )
    parser.add_argument(
        "--stop-early",
        action="store_true",
        help="sequential stopping: stop a controller's rows (per grid cell) once its claim is "
        "refuted whatever the rest give; a claim is proved only by all its rows",
    )


SWEEP = Command(
    "sweep",
    help="run a robustness sweep (Monte Carlo over the uncertainty set)",
    description="Run one experiment over many samples of model error, friction, "
    "disturbance, gains or seeds with several controllers, on dask.distributed: "
    "a local cluster on 127.0.0.1 by default, or an existing scheduler. Re-running "
    "the same command into the same folder computes only the missing rows "
    "(docs/robustness.md).",
    arguments=sweep_arguments,
    run=cmd_sweep,
    many_runs=True,
)


def falsify_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust falsify``."""
    parser.add_argument(
        "sweep", help="sweep file (TOML) or shipped sweep file by name whose [vary] ranges are the box"
    )
    parser.add_argument(
        "--controllers",
        required=True,
        help="comma-separated controller kinds, custom "
        "classes as file.py:Class, or the sweep file's custom entries",
    )
    parser.add_argument(
        "--require",
        action="append",
        required=True,
        metavar="EXPR",
        help="a property to falsify, METRIC OP VALUE (repeatable), e.g. 'rms_error_after_2s<=0.05'",
    )
    parser.add_argument(
        "--budget",
        type=int,
        required=True,
        help="simulations per controller (and as many for its random baseline)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the search (default 0)")
    parser.add_argument(
        "--tuned",
        metavar="DIR",
        help="run each listed law at its best setting in this tuning (nnrobust tune's DIR or its "
        "summary.json, a study's cases/CASE/kept.json, or one case of a study's report as "
        "REPORT.json#CASE, e.g. 'docs/data/tuned_panda.json#panda-ellipse-noisy'), as NAME-tuned; "
        "every law takes them: shipped, registered, file.py:Class, a sweep file's entries",
    )
    parser.add_argument(
        "--out",
        required=True,
        help="folder (falsify.toml, history/, summary.json, falsification.csv, convergence.png)",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace a different search in --out")
    parser.add_argument(
        "--keep-worst",
        type=keep_count,
        nargs="?",
        const=1,
        default=0,
        metavar="K",
        help="rerun each controller's K worst distinct plants (1 without K) into "
        "OUT/worst/CONTROLLER, CONTROLLER-2, ... as full run folders (arrays, metrics, plots, "
        "animation)",
    )
    parser.add_argument(
        "--margin",
        action="store_true",
        help="also find each controller's robustness margin: the largest scale s of the box "
        "about its centre with no violation found, by doubling then bisection on s, each "
        "scale searched at a quarter of the budget (docs/falsification.md)",
    )
    parser.add_argument(
        "--epsilon",
        type=float,
        default=0.05,
        help="the random baseline's runs, independent draws of the box, certify P(a property fails) "
        "<= EPSILON (default 0.05) ...",
    )
    parser.add_argument(
        "--beta",
        type=float,
        default=0.05,
        help="... with confidence 1 - BETA (default 0.05; one-sided Clopper-Pearson)",
    )


FALSIFY = Command(
    "falsify",
    help="search the worst plant of an uncertainty box",
    description="Search the sweep file's [vary] box (uniform and loguniform ranges) "
    "for the plant on which each controller most violates the --require properties: "
    "a Sobol start, then CMA-ES with restarts, at one budget of simulations per "
    "controller on dask.distributed, with uniform random search at the same budget "
    "as the baseline. Re-running the same command into the same folder resumes "
    "(docs/falsification.md).",
    arguments=falsify_arguments,
    run=cmd_falsify,
    many_runs=True,
)


def study_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust study``."""
    parser.add_argument("study", help="study file (TOML)")
    parser.add_argument("--out", required=True, help="study folder (cases/, report.json, report.html)")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace what a different study wrote in --out"
    )


STUDY = Command(
    "study",
    help="one study file -> one report: tune, validate, certify, falsify",
    description=study_description(),
    arguments=study_arguments,
    run=cmd_study,
    many_runs=True,
)


def tune_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``nnrobust tune``."""
    parser.add_argument(
        "target",
        help="a preset, an experiment file, or a sweep file whose [vary] "
        "distributions are the uncertainty the settings are tuned over",
    )
    parser.add_argument(
        "--controllers",
        required=True,
        help="comma-separated controller kinds, e.g. "
        "nn,no-u0,pd,sliding-mode; a custom class as file.py:Class (it declares its "
        "search_space); or the names of a sweep file's custom entries",
    )
    parser.add_argument("--budget", type=int, required=True, help="simulations per controller (training)")
    parser.add_argument(
        "--out", required=True, help="tuning folder (tune.toml, trials/, summary.json, pareto.png)"
    )
    parser.add_argument("--max-rms-torque", type=float, metavar="X", help="constraint: RMS torque <= X [N m]")
    parser.add_argument(
        "--max-saturated",
        type=float,
        metavar="F",
        help="constraint: at most this fraction of steps saturated (0 to 1)",
    )
    parser.add_argument(
        "--train-samples",
        type=int,
        default=1,
        metavar="S",
        help="samples (noise seeds, uncertainty draws) each setting runs on (default 1)",
    )
    parser.add_argument(
        "--validation",
        type=int,
        default=4,
        metavar="K",
        help="held-out samples each best setting is checked on (default 4)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the optimiser and the samples")
    parser.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="set one key of the target's experiment for every run (dotted, TOML value; as a sweep "
        "file's [set]); repeatable",
    )
    parser.add_argument("--overwrite", action="store_true", help="replace a different tuning in --out")


TUNE = Command(
    "tune",
    help="tune controllers at an equal budget of simulations",
    description="Tune each controller with the same optimiser (Optuna's TPE, "
    "minimising the RMS error after 2 s under the constraints; torque and chatter are "
    "recorded for the Pareto fronts) over a search space derived from the arm, at the "
    "same budget of simulations, on the same samples, under the same constraints; "
    "then check each best setting on held-out samples. Re-running the same command "
    "into the same folder resumes (docs/tuning.md).",
    arguments=tune_arguments,
    run=cmd_tune,
    many_runs=True,
)
