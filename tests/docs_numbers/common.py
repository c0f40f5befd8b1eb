"""What the docs-number tests share: the data files, their readers, and the figures' selectors."""

import json
import re
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "docs"))

import _common  # noqa: E402, F401 (the page tests rerun the benchmarks' rows with it)
import render_tables  # noqa: E402

DATA_FILES = ["paper_reproduction", "nn_options", "subtask", "arm_presets", "torque_speed"]
"""Rows of benchmarks/_common.py jobs (preset and changes)."""
STUDIES = ["paper_robustness", "panda_robustness"]
"""Reports of the shipped robustness studies (their report.json)."""


OTHERS = [
    "friction_compensation",
    "plant_convergence",
    "tuned_paper",
    "tuned_panda",
    "falsify_paper",
    "falsify_panda",
    "falsify_paper_tuned",
    "falsify_panda_tuned",
    "engine_gap",
    "adaptive_step",
    "tune_noisy_case_b",
    "example_study",
    "interval_coverage",
    "worst_plant_loops",
    "identify_panda",
    "identify_calibration",
    "identify_calibration_plant",
    "identify_design",
    "identify_walkthrough",
]
"""Data files with a re-run test of their own below (worst_plant_loops: its compiled loop), or
whose tables a page's test regenerates from them (identify_panda, whose log no one here ships,
identify_calibration, identify_calibration_plant and identify_design:
tests/docs_numbers/test_identification.py; identify_walkthrough: the
commands tests/studies/identify/test_walkthrough.py runs, its budgets cut)."""


TIMINGS = ["learning_env", "study_overhead", "study_overhead_falsify_panda", "serve_misses", "fresh_clone",
           "loop_profile", "closed_loop", "identify_rows", "identify_hour"]  # fmt: skip
"""Timings of this machine quoted in prose or drawn in a table (loop_profile: docs/compiled.md's
breakdown; closed_loop: its timings and README's): QUOTED_FIGURES checks each quote against its
file, render_tables each table (a rerun measures the machine it runs on: it gives other numbers,
not the same)."""


def _quickest_row(rows):
    """The first row of the shortest runs (on the 3-link arm where there is a choice)."""

    def cost(row):
        return (row["changes"].get("simulation", {}).get("duration", 20.0), "panda" in row["preset"])

    return min(rows, key=cost)


def _rerun(job: dict) -> dict:
    from nnrobust.config.presets import load_preset
    from nnrobust.run.experiment import run_experiment

    return run_experiment(load_preset(job["preset"]).replace(**job["changes"])).metrics()


def _rerun_best(summary: dict, controllers: list[str], name: str) -> None:
    """A tuning's best setting of ``name``, rerun on its training sample, gives its metrics."""
    from nnrobust.config import apply_overrides
    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.base.plan import base_config, draw, experiment
    from nnrobust.studies.tune import TuneSpec
    from nnrobust.studies.tune.engine import sweep_of

    spec = TuneSpec(
        summary["target"],
        controllers,
        summary["budget"],
        len(summary["train_samples"]),
        len(summary["validation_samples"]),
        seed=summary["seed"],
    )
    sweep = sweep_of(spec)
    best = summary["controllers"][name]["best"]
    runs = [
        run_experiment(
            apply_overrides(
                experiment(sweep, base_config(sweep), draw(sweep, t["sample"]), name), best["params"]
            )
        ).metrics()
        for t in summary["train_samples"]
    ]
    for key in ("rms_error_after_2s", "rms_torque", "torque_chatter"):  # the mean over the training samples
        assert np.mean([r[key] for r in runs]) == pytest.approx(best["train"][key], rel=1e-9), key


def _rerun_validation(study: str, case_name: str, controller: str) -> tuple[float, float]:
    """A tuned study's kept setting of ``controller`` in ``case_name``, rerun on the validation
    draws (rebuilt from the study file, as the study's validate stage draws them): (the median of
    their RMS errors after 2 s, the median report.json gives)."""
    from statistics import median

    from nnrobust.run.experiment import run_experiment
    from nnrobust.studies.base.plan import base_config, draw, experiment
    from nnrobust.studies.base.tuned import tuned_entry
    from nnrobust.studies.study import load_study
    from nnrobust.studies.study.stages import VALIDATION_SEED, seed_name, sweep_of

    spec = load_study(ROOT / "benchmarks" / "studies" / f"{study}.toml")
    report = json.loads((render_tables.DATA / f"{study.replace('-', '_')}.json").read_text())
    case = next(c for c in spec.cases if spec.case_name(c) == case_name)
    tuned = report["cases"][case_name]["controllers"][controller]["tuned"]
    label = seed_name(controller, tuned["kept_seed"])
    entries = {label: tuned_entry(controller, tuned["settings"], spec.entries)}
    n = spec.budgets["validation"]
    sweep = sweep_of(spec, case, [label], entries, n, spec.seed + VALIDATION_SEED)
    base = base_config(sweep)
    errors = [
        run_experiment(experiment(sweep, base, draw(sweep, i), label)).metrics()["rms_error_after_2s"]
        for i in range(n)
    ]
    kept = next(s for s in tuned["seeds"] if s["seed"] == tuned["kept_seed"])
    return median(errors), kept["median_error"]


def _read(name: str):
    """A data file's content (docs/data/NAME.json). ``NAME:falsification`` reads a falsification
    study's report as its falsification stage: ``properties`` (the study's require),
    ``controllers`` (each law's ``falsification`` entry) and ``margin`` (each law's margin)."""
    name, _, view = name.partition(":")
    data = json.loads((render_tables.DATA / f"{name}.json").read_text())
    if not view:
        return data
    (case,) = data["cases"].values()
    laws = case["controllers"]
    return {
        "properties": data["require"],
        "controllers": {c: e["falsification"] for c, e in laws.items()},
        "margin": {c: e["margin"] for c, e in laws.items() if e.get("margin")},
    }


def _at(data, path):
    for key in path:
        data = data[key]
    return data


PAPER, PANDA, TUNED = "paper_robustness", "panda_robustness", "tuned_paper"
"""TUNED: the checks below read both tuned studies' reports (render_tables.tuned_cases)."""


def _falsified(controller, search=None):
    """The worst RMS error after 2 s a falsification found (or its random baseline)."""

    def get(data):
        entry = data["controllers"][controller]
        entry = entry[search] if search else entry
        return entry["worst"]["metrics"]["rms_error_after_2s"]

    return get


def _tuned_case(case: str, sensing: str) -> dict:
    """A case of the tuned studies by its table label, e.g. ("case (a) line", "noisy")."""
    return next(c for c in render_tables.tuned_cases() if c["label"] == f"{case}, {sensing}")


def _held(case, controller, sensing="noisy"):
    """The median over the optimiser seeds of a controller's validation error in the tuned
    studies (what the headline table prints)."""
    from statistics import median

    return lambda _: median(render_tables.tuned_seed_errors(_tuned_case(case, sensing)["case"], controller))


def _row(case, variant):
    """A paper_reproduction.json row's RMS error."""
    return lambda data: next(
        r["rms_error_after_2s"] for r in data["rows"] if r["case"] == case and r["variant"] == variant
    )


def _ratio(preset):
    """no-u0's RMS error over the NN's on a real-arm preset (arm_presets.json)."""

    def get(data):
        error = {r["controller"]: r["rms_error_after_2s"] for r in data["rows"] if r["preset"] == preset}
        return error["no-u0"] / error["nn"]

    return get


def _error(row, variant):
    return row[variant]["rms_error_after_2s"]


def _gaps(part, controller=None, exclude=(), variant="mujoco", reference="pinocchio", only=None):
    """|error on ``variant`` / error on ``reference`` - 1| in % for each row of engine_gap.json;
    ``exclude``: presets, or (case, controller, sensing) of tuned rows, left out; ``only``: the
    (case, controller, sensing) of the tuned rows kept."""

    def get(data):
        def which(r):
            return (r.get("case"), r["controller"], r.get("sensing"))

        return [
            100 * abs(_error(r, variant) / _error(r, reference) - 1)
            for r in data[part]
            if controller in (None, r["controller"])
            and r.get("preset") not in exclude
            and which(r) not in exclude
            and only in (None, which(r))
        ]

    return get


RBF_IDEAL = (("paper-line", "rbf-nn", "ideal"), ("paper-ellipse", "rbf-nn", "ideal"))
"""The tuned rows the engines' text names apart: the RBF network's hundredths of a micrometre."""


def _gap_stat(stat, *args, **kwargs):
    return lambda data: float(stat(_gaps(*args, **kwargs)(data)))


GAP_REST = _gap_stat(max, "tuned", exclude=RBF_IDEAL)


GAP_RBF_A = _gap_stat(max, "tuned", only=RBF_IDEAL[0])


GAP_RBF_B = _gap_stat(max, "tuned", only=RBF_IDEAL[1])
"""The quoted engine gaps: every tuned row but RBF_IDEAL's (max), the RBF network's on case (a)
and on case (b)."""


def _gap_error(preset, controller, variant):
    return lambda data: next(
        _error(r, variant) for r in data["presets"] if r["preset"] == preset and r["controller"] == controller
    )


def _failing(variant, factor=2.0, sensing="ideal"):
    """Tuned rows of a sensing whose error on ``variant`` is over ``factor`` times Pinocchio's."""
    return lambda data: sum(
        _error(r, variant) > factor * _error(r, "pinocchio") for r in data["tuned"] if r["sensing"] == sensing
    )


CASE_A, CASE_B, PANDA_ARM = "case (a) line", "case (b) ellipse", "Panda ellipse"


GAP = "engine_gap"


PRINTED = ("paper-ellipse-paper-law",)


FALSIFIED = "falsify_paper:falsification"


def _best(controller: str):
    """The held-out RMS error of a controller's best setting in a tuning's summary."""
    return lambda data: data["controllers"][controller]["best"]["validation"]["rms_error_after_2s"]


def _drift_ratio(coarse: float, fine: float):
    def ratio(data):
        drift = {r["max_step_rotation"]: r["energy_drift"] for r in data["rows"]}
        return drift[coarse] / drift[fine]

    return ratio


def _convergence(preset: str, key: str, controller: str = "computed-torque"):
    return lambda data: next(
        r[key] for r in data["rows"] if r["preset"] == preset and r["controller"] == controller
    )


def _random_failures(controller):
    """How many of a falsification's random-baseline plants fail (the certificate's k)."""
    return lambda data: data["controllers"][controller]["certificate"]["certificates"][0]["k"]


def _certified(controller):
    """The random baseline's Clopper-Pearson bound on P(fail) of a falsification's controller."""
    return lambda data: data["controllers"][controller]["certificate"]["certificates"][0]["p_upper"]


def _margin(controller):
    """Where a falsification's margin search found no violation (holds_up_to, × the box)."""
    return lambda data: data["margin"][controller]["holds_up_to"]


def _seed_spread(rank):
    """The rank-th largest (0: the largest) ratio of a cell's worst seed to its median in the
    tuned studies."""
    from statistics import median

    def get(_):
        ratios = sorted(
            (
                max(e) / median(e)
                for c in render_tables.tuned_cases()
                for n in c["controllers"]
                if (e := render_tables.tuned_seed_errors(c["case"], n))
            ),
            reverse=True,
        )
        return ratios[rank]

    return get


def _nn_gain(pick):
    """The least or greatest adaptation gain F of the NN's best settings over every case and seed."""
    return lambda _: pick(
        s["settings"]["nn.F"]
        for c in render_tables.tuned_cases()
        if (entry := c["case"]["controllers"].get("nn")) is not None and entry["tuned"]
        for s in entry["tuned"]["seeds"]
    )


def _seed_extreme(case, controller, pick, sensing="noisy"):
    """The least or greatest of a controller's seeds' validation errors in the tuned studies."""
    return lambda _: pick(render_tables.tuned_seed_errors(_tuned_case(case, sensing)["case"], controller))


def _paired_better(case, a, b, sensing="noisy"):
    """On how many certification draws ``a``'s kept setting beats ``b``'s (the paired comparison)."""
    return lambda _: render_tables._paired(_tuned_case(case, sensing)["case"], a, b)["a_better"]


def _paired_p(case, a, b, sensing="noisy", key="sign_p"):
    """The sign test's p-value of the paired comparison of ``a`` and ``b`` (``holm_p``: after
    Holm's correction over the case's pairs)."""
    return lambda _: render_tables._paired(_tuned_case(case, sensing)["case"], a, b)[key]


def _pairs(case, sensing="noisy"):
    """How many pairs a tuned case compares (Holm's correction is over them)."""
    return lambda _: len(_tuned_case(case, sensing)["case"]["paired"])


def _unconverged(_):
    """How many tunings of the tuned studies had not converged at their budget."""
    return sum(
        len(render_tables._not_converged(c["case"], c["controllers"])) for c in render_tables.tuned_cases()
    )


def _lead(case, sensing="noisy"):
    """The least median over the next law's in a tuned case (how far the winner leads)."""
    from statistics import median

    def get(_):
        c = _tuned_case(case, sensing)
        medians = sorted(
            median(e) for n in c["controllers"] if (e := render_tables.tuned_seed_errors(c["case"], n))
        )
        return medians[1] / medians[0]

    return get


def _half_budget_ratio(controller, pick):
    """The least or greatest, over the tuned cases, of a controller's kept validation median at
    half its tuning budget over that at the whole (1 + the convergence record's change)."""

    def get(_):
        return pick(
            conv["kept_median_half"] / conv["kept_median"]
            for c in render_tables.tuned_cases()
            if (conv := render_tables.tuned_convergence(c["case"], controller))
        )

    return get


def _ratio_to(case, controller, other, sensing="noisy"):
    """A controller's median validation error over another's."""
    return lambda data: _held(case, controller, sensing)(data) / _held(case, other, sensing)(data)


def _nn_ideal_ratio(pick):
    """The least or greatest, over the three ideal-sensing cases, of the NN's median over the best
    other eq. (9) law's (no-u0, the sliding mode)."""
    from statistics import median

    def ratio(case):
        nn = median(render_tables.tuned_seed_errors(case, "nn"))
        return nn / min(median(render_tables.tuned_seed_errors(case, n)) for n in ("no-u0", "sliding-mode"))

    cases = render_tables.tuned_cases
    return lambda _: pick(ratio(c["case"]) for c in cases() if c["label"].endswith("ideal"))


PF = "falsify_panda:falsification"


def _example_median(controller: str):
    """A controller's median RMS error (t >= 2 s) in the example study's report [m]."""
    return lambda d: d["cases"]["paper-ellipse-noisy"]["controllers"][controller]["statistics"][
        "rms_error_after_2s"
    ]["median"]


def _example_passed(controller: str):
    """How many of the example study's certification draws met a controller's whole requirement."""

    def passed(d):
        whole = d["cases"]["paper-ellipse-noisy"]["controllers"][controller]["certificates"][0]
        return whole["N"] - whole["k"]

    return passed


def _example_convergence(controller: str):
    """A tuned controller's kept median at the budget over that at half of it (example study)."""

    def ratio(d):
        c = d["cases"]["paper-ellipse-noisy"]["controllers"][controller]["tuned"]["convergence"]
        return c["kept_median"] / c["kept_median_half"]

    return ratio


PT = "falsify_panda_tuned:falsification"


def _learning(preset: str, key: str):
    """``key`` of the row of learning_env.json for this preset."""

    def pick(d):
        (row,) = [r for r in d["rows"] if r["preset"] == preset]
        return row[key]

    return pick


def _serve(arm: str, load: str, fifo: bool, value):
    """``value`` of the row of serve_misses.json for this arm, load and scheduling."""

    def pick(d):
        (row,) = [
            r for r in d["rows"] if (r["arm"], r["load"], "FIFO" in r["scheduling"]) == (arm, load, fifo)
        ]
        return value(row)

    return pick


def _stage_wall(words: str):
    """The wall seconds of the study stages whose line holds ``words`` (study_overhead.json)."""
    return lambda d: sum(seconds for line, seconds in d["stage_wall_seconds"] if words in line)


def _simulated(*stages: str):
    """The worker seconds of simulation of a study's ``stages``, all of them if none is named
    (study_overhead.json)."""
    return lambda d: sum(
        v
        for k, v in d["simulation_seconds"].items()
        if k in stages or (not stages and k != "runs_without_their_own_time")
    )


def _busy(words: str, *stages: str):
    """The share of the workers' time that ``stages`` simulated while the stage line holding
    ``words`` ran (study_overhead.json)."""
    return lambda d: _simulated(*stages)(d) / (d["workers"] * _stage_wall(words)(d))


def _pick_certificate(certificates: list[dict], metric: str | None) -> dict:
    """Of a controller's certificates, the whole requirement's (the first: every property at
    once), or with ``metric`` that of the property on it."""
    if metric is None:
        assert certificates[0]["property"].startswith("all of: ")
        return certificates[0]
    (certificate,) = [c for c in certificates[1:] if re.match(rf"{metric}\s*(<|>|=)", c["property"])]
    return certificate


def _box_certified(controller: str, key: str, metric: str | None = None):
    """``key`` of a controller's certificate in a one-case study's report (a falsify study's):
    the whole requirement's, or with ``metric`` that of the property on it."""

    def get(d):
        (case,) = d["cases"].values()
        return _pick_certificate(case["controllers"][controller]["certificates"], metric)[key]

    return get


def _panda_noisy_kept(stat):
    """``stat`` of the kept validation medians of the six shipped laws, tuned-panda's noisy case."""

    def get(d):
        laws = d["cases"]["panda-ellipse-noisy"]["controllers"]
        return stat(
            next(s["median_error"] for s in e["tuned"]["seeds"] if s["seed"] == e["tuned"]["kept_seed"])
            for c, e in laws.items()
            if c != "taskpd-cpp"
        )

    return get


FT = "falsify_paper_tuned:falsification"


def _ideal_median(controller: str, stat, sensing: str = "ideal"):
    """``stat`` over the cases of both tuned studies with that sensing of a controller's median
    of its seeds' validation medians (the headline table's cells)."""
    from statistics import median

    return lambda _: stat(
        median(render_tables.tuned_seed_errors(c["case"], controller))
        for c in render_tables.tuned_cases()
        if c["label"].endswith(sensing)
    )


def _case(case: str, controller: str, statistic: str):
    """A statistic of a controller's RMS error after 2 s on one case's certification draws (a
    robustness study's report)."""
    return lambda d: d["cases"][case]["controllers"][controller]["statistics"]["rms_error_after_2s"][
        statistic
    ]


def _worst_draw(controller: str):
    """A controller's worst RMS error after 2 s over every case of a robustness study."""
    return lambda d: max(
        c["controllers"][controller]["statistics"]["rms_error_after_2s"]["max"] for c in d["cases"].values()
    )


def _case_failing(case: str, controller: str, metric: str | None = "rms_error_after_2s"):
    """How many of a case's certification draws fail one property (the certificate of the
    property on ``metric``), or with ``metric`` None the whole requirement (the first
    certificate: every property at once)."""

    return lambda d: _pick_certificate(d["cases"][case]["controllers"][controller]["certificates"], metric)[
        "k"
    ]


def _tuned_draws_failing(stat):
    """``stat`` of the certification draws failing each model-based law of falsify-paper-tuned
    (every law but the PD)."""
    return lambda d: stat(
        e["certificates"][0]["k"]
        for c, e in d["cases"]["paper-ellipse-noisy"]["controllers"].items()
        if c != "pd-tuned"
    )


def _paper_noisy_kept(controller):
    """A law's kept validation median in the tuned-paper study's noisy case (b) [m]."""

    def get(d):
        tuned = d["cases"]["paper-ellipse-noisy"]["controllers"][controller]["tuned"]
        return next(s["median_error"] for s in tuned["seeds"] if s["seed"] == tuned["kept_seed"])

    return get


_worst_config = _common.worst_config
"""The experiment of a printed rerun command (benchmarks/_common.py, which its benchmarks use)."""


CHAOS_PROBE, CHAOS_SPREAD = 1e-6, 0.01
"""A run is chaotic when scaling its disturbance (or friction) by 1 +- CHAOS_PROBE moves its RMS
error by more than CHAOS_SPREAD of it (benchmarks/_common.py's probe)."""


def _reproduces_or_is_chaotic(config, published: float, what: str, limit: float | None = None) -> float:
    """The RMS error (t >= 2 s) of ``config`` [m]: equal to ``published`` to 1e-9, or else a
    chaotic run (its probes spread by more than CHAOS_SPREAD: the digits depend on the machine's
    rounding, its BLAS and compiler) that still exceeds ``limit`` on every probe, so the verdict
    the docs draw from it holds wherever it is rerun."""
    from nnrobust.run.experiment import run_experiment

    value = run_experiment(config).metrics()["rms_error_after_2s"]
    if value == pytest.approx(published, rel=1e-9, abs=1e-15):
        return value
    key = "disturbance_scale" if config.plant.disturbance != "none" else "friction_scale"
    scale = getattr(config.plant, key)
    probes = [value] + [
        run_experiment(config.replace(plant={key: scale * (1 + d)})).metrics()["rms_error_after_2s"]
        for d in (CHAOS_PROBE, -CHAOS_PROBE)
    ]
    assert max(probes) - min(probes) > CHAOS_SPREAD * max(probes), (what, value, published, probes)
    if limit is not None:
        assert min(probes) > limit, (what, probes, limit)
    return value


def _docs_data_commands() -> list[list[str]]:
    """The commands of `make docs-data`, each as its arguments, with the Makefile's variables
    given their default values and the options that only choose how it runs (--quiet,
    --overwrite) left out."""
    import shlex

    text = (ROOT / "Makefile").read_text()
    recipe = text[text.index("docs-data:") :].split("\n\n")[0].replace("\\\n", " ")
    out = []
    for line in recipe.splitlines()[1:]:
        line = line.strip().replace("$(BIN)/", "").replace("$(DATA)", "docs/data").replace("$(OUT)", "out")
        out.append([word for word in shlex.split(line) if word not in ("--quiet", "--overwrite")])
    return out


def check_quote(document: str, pattern: str, name, where, scale: float) -> None:
    """One figure a page quotes (``pattern``'s group 1 in ``document``) is its data file's value
    (``where`` in docs/data/NAME.json, times ``scale``) rounded to the printed digits; with
    ``name`` None, only that the text is there."""

    text = (ROOT / document).read_text()
    match = re.search(pattern, text)
    assert match, f"{document}: no text matches {pattern!r}"
    if name is None:
        return
    data = _read(name)
    value = where(data) if callable(where) else _at(data, where)
    quoted = float(match.group(1).replace(" ", "").replace(",", ""))  # 20 544 and 1,255 too
    # the quoted figure is the data rounded to its printed digits: within half a unit of the last
    digits = match.group(1).split(".")[1] if "." in match.group(1) else ""
    half = 0.5 * 10 ** -len(digits) if digits else 0.5
    bound = max(half, 0.02 * abs(scale * value))
    assert abs(quoted - scale * value) <= bound, (document, pattern, scale * value)


def quoted_figures_test(quotes: list[tuple]):
    """A page's test of the figures it quotes: one case per figure (:func:`check_quote`), so a
    failing number names its page's file and the start of its text."""

    @pytest.mark.parametrize("quote", quotes, ids=lambda quote: quote[1][:40])
    def test(quote):
        check_quote(*quote)

    return test
