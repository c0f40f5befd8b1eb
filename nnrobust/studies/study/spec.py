"""Study files: the cases, controllers, uncertainty set, required properties and budgets of one
study (docs/study.md), checked before any stage runs.

A study file is TOML::

    name = "small"
    cases = ["paper-ellipse-noisy"]       # presets or experiment files (from the study's folder)
    controllers = ["nn", "pd", {name = "taskpd", class = "laws.py:TaskPD"}]
    require = ["rms_error_after_2s<=0.005"]
    seed = 0
    [set]                                 # fixed overrides, every case
    "simulation.duration" = 3.0
    [vary]                                # the uncertainty set: distributions
    "plant.disturbance_scale" = {uniform = [0.5, 2.0]}
    [budgets]
    tune = 12          # simulations per controller, case and seed (training)
    seeds = 2          # optimiser seeds
    ...

Each case becomes a sweep file (its ``[set]`` and ``[vary]`` the study's), so every stage is the
existing command's own engine on that file.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

from ...config import parse_toml, read_text_file
from ...controllers.laws.policy import base_laws, policy_params
from ...core.exceptions import ConfigError
from ..base.plan import NAME, SweepSpec, parse_sweep, resolve_entry_files, with_box
from ..learning.rl import ALGORITHMS, hyper_settings

KEYS = (
    "name", "description", "cases", "controllers", "tuned", "require", "waive", "seed", "set", "vary",
    "budgets", "box",
)  # fmt: skip

DESIGN = {
    "torque": "RMS torque <= budgets.max_rms_torque (where set)",
    "saturation": "saturated share of the steps <= budgets.max_saturated (where set)",
    "stops": "no joint stop hit (max_joint_limit_violation <= 0)",
    "runaway": "the error does not run away (runaway == false)",
    "tracking": "the path is not lost (tracking_error_ratio <= the tracking-lost threshold)",
}
"""The design's own requirement, certified beside ``require`` unless the study file waives one
(``waive = ["stops"]``): the tuning's constraints and the verdicts that mean a failed design."""

BUDGET_KEYS = {
    "tune": "simulations per controller, case and optimiser seed (training)",
    "seeds": "optimiser seeds per controller and case",
    "train_samples": "draws of the uncertainty set each tuning setting runs on",
    "validation": "fresh draws each (controller, seed) is validated on (selects the seed)",
    "epsilon": "the certified claim: P(a property fails) <= epsilon ...",
    "beta": "... with confidence 1 - beta (Clopper-Pearson, on draws the selection never saw)",
    "certify": "certification draws per case (default: the fewest that prove the claim with no failure)",
    "falsify": "falsification budget per controller and case (and as many random draws); 0: no search",
    "margin": "search how far the box may grow before a property fails (true/false)",
    "max_rms_torque": "tuning constraint: RMS torque <= this [N m]",
    "max_saturated": "tuning constraint: saturated fraction of the steps <= this",
    "second_engine": "run the certification draws again with MuJoCo as the plant (true/false)",
    "tolerance": "convergence: the kept median may move by at most this share from half the budget",
    "realtime": "export each kept law and time its step out of Python (true/false)",
}
"""The keys of [budgets], each with what it means."""

DEFAULT_BUDGETS = {
    "tune": 40,
    "seeds": 3,
    "train_samples": 2,
    "validation": 20,
    "epsilon": 0.1,
    "beta": 0.05,
    "certify": 0,
    "falsify": 40,
    "margin": False,
    "max_rms_torque": math.inf,
    "max_saturated": 1.0,
    "second_engine": False,
    "realtime": False,
    "tolerance": 0.1,
}


def kept_name(controller: str) -> str:
    """The certification and falsification entry of a controller's kept setting (and of a
    setting ``tuned =`` takes from another study).
    """
    return f"{controller}-tuned"


MAX_CASES = 100
"""The most cases a study may have: each is tuned, validated, certified and falsified apart (a
study of more is many studies; split it)."""

CASE_KEYS = ("name", "base", "set")
"""The keys of a case given as a table: its name, its experiment and its own overrides."""


@dataclass
class StudyCase:
    """One case of a study: a preset or an experiment file, with overrides of its own (a case
    table's ``set``, over the study's ``[set]``): the same experiment at three disturbance
    scales is three cases, each certified on its own draws.
    """

    name: str
    base: str
    set: dict = field(default_factory=dict)


ENTRY_TUNE = "tune"
"""The key of a controllers entry that, set to false, runs it at its own settings untuned."""

ENTRY_TRAIN = "train"
"""The key of a policy entry (``kind = "policy"``, no ``file``) that the study trains as a stage:
``train = {algorithm = "ppo", budget = 60.0, seeds = 3}`` (:data:`TRAIN_KEYS`)."""

TRAIN_KEYS = {
    "algorithm": "ppo or sac (Stable-Baselines3: the rl extra)",
    "budget": "simulated seconds of training per seed (> 0)",
    "seeds": "training seeds (1-20, default 1); the study keeps the best on its validation draws",
    "num_envs": "episodes run side by side (the vector environment, default 8)",
    "curve_points": "points of the learning curve after its start (default 10, one per tenth of the budget)",
    "curve_episodes": "validation episodes of each point of the learning curve (default 8)",
    "hyper": "the algorithm's hyper-parameters, over its defaults (docs/learning.md)",
}
"""The keys of a policy entry's ``train`` table, each with what it means."""

ENTRY_CASES = "cases"
"""The key of a controllers entry that runs it on the cases it lists only (by name): two entries
of one name whose lists do not share a case are one law, with its own settings on each (a
learned policy of each arm, whose observation sizes differ)."""


@dataclass
class StudySpec:
    """A parsed, validated study file.

    Attributes:
        name: the study's name (1-40 letters, digits, '_' or '-').
        path: the study file.
        cases: the cases (:class:`StudyCase`): a preset or an experiment file (absolute), with
            overrides of its own.
        controllers: the controllers' names (a built-in kind or registered law, or a table entry's
            name), in the study's order.
        entries: table entries by name, as a sweep file's (``tune = false`` removed).
        fixed: names run at their own settings, untuned.
        require: the ``--require`` properties of the certification and the falsification.
        seed: the study's seed (tuning seeds, validation, certification draws derive from it).
        set, vary: the fixed overrides and the uncertainty set (distributions).
        budgets: :data:`BUDGET_KEYS` with their values.
        tuned: the tuning whose kept settings every controller runs at, as NAME-tuned and untuned
            here (``tuned = "FILE#CASE"``, absolute), or "" (none).
        box: the identified box the file names (``box = "box.toml"``; its [set] and [vary] are in
            ``set`` and ``vary``): its file, SHA-256 and [claim] (:func:`~..base.plan.with_box`),
            or empty.

    """

    name: str
    path: Path
    cases: list[StudyCase]
    controllers: list[str]
    entries: dict
    fixed: list[str]
    require: list[str]
    seed: int = 0
    set: dict = field(default_factory=dict)
    vary: dict = field(default_factory=dict)
    budgets: dict = field(default_factory=lambda: dict(DEFAULT_BUDGETS))
    description: str = ""
    tuned: str = ""
    waive: list[str] = field(default_factory=list)
    case_controllers: dict = field(default_factory=dict)
    """case name -> (controllers, entries) where entries name the cases they run on."""
    trained: dict = field(default_factory=dict)
    """The learned policies the study trains (name -> its checked ``train`` table); neither
    fixed nor tuned: the train stage gives each seed's policy file, the validation keeps one."""
    box: dict = field(default_factory=dict)

    @property
    def searched(self) -> list[str]:
        """The controllers the study's tunings search: neither fixed nor trained."""
        return [c for c in self.controllers if c not in self.fixed and c not in self.trained]

    def for_case(self, case: StudyCase) -> StudySpec:
        """The study as one case sees it: the controllers that run there, with that case's entries."""
        if case.name not in self.case_controllers:
            return self
        names, entries = self.case_controllers[case.name]
        fixed = [f for f in self.fixed if f in names]
        trained = {c: t for c, t in self.trained.items() if c in names}
        return replace(
            self,
            controllers=list(names),
            entries=dict(entries),
            fixed=fixed,
            case_controllers={},
            trained=trained,
        )

    def design_requirement(self) -> dict[str, str]:
        """The design's requirement (:data:`DESIGN`) as properties by name, those the file waives
        left out: the tuning's constraints where set, no joint stop hit, no runaway, the path kept.
        """
        from ...run.verdicts import TRACKING_LOST

        b = self.budgets
        texts = {
            "torque": f"rms_torque<={b['max_rms_torque']:g}" if math.isfinite(b["max_rms_torque"]) else "",
            "saturation": f"saturated_fraction<={b['max_saturated']:g}" if b["max_saturated"] < 1 else "",
            "stops": "max_joint_limit_violation<=0",
            "runaway": "runaway==false",
            "tracking": f"tracking_error_ratio<={TRACKING_LOST:g}",
        }
        return {name: text for name, text in texts.items() if text and name not in self.waive}

    def design_properties(self) -> list[str]:
        """The design's requirement as properties (:meth:`design_requirement`'s, in order)."""
        return list(self.design_requirement().values())

    def certified_properties(self) -> list[str]:
        """What the certification certifies: ``require``, then the design's own requirement."""
        return [*self.require, *(p for p in self.design_properties() if p not in self.require)]

    def case_name(self, case: StudyCase) -> str:
        """A case's folder name: its table's name, the preset, or the experiment file's stem."""
        return case.name

    def case_set(self, case: StudyCase) -> dict:
        """The overrides every run of the case takes: the study's [set], then the case's own."""
        return {**self.set, **case.set}

    def case_sweep(self, case: StudyCase) -> SweepSpec:
        """The case as a sweep (its controllers, its overrides and the study's [vary])."""
        view = self.for_case(case)
        return SweepSpec(
            name=f"{self.name}-{self.case_name(case)}",
            base=case.base,
            controllers=list(view.controllers),
            samples=1,
            seed=self.seed,
            set=self.case_set(case),
            vary=dict(self.vary),
            entries={k: dict(v) for k, v in view.entries.items()},
            box=dict(self.box),
        )


def _suggest(key: str, valid) -> str:
    close = difflib.get_close_matches(key, list(valid), n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


def _budgets(data, where: str) -> dict:
    if not isinstance(data, dict):
        raise ConfigError(f"{where}: budgets", "expected a table")
    out: dict = dict(DEFAULT_BUDGETS)
    for key, value in data.items():
        if key not in BUDGET_KEYS:
            raise ConfigError(
                f"{where}: budgets.{key}",
                f"unknown key{_suggest(key, BUDGET_KEYS)} Valid: {', '.join(BUDGET_KEYS)}",
            )
        out[key] = value
    whole = {"tune": (2, 100_000), "seeds": (1, 20), "train_samples": (1, 1000), "validation": (2, 10_000),
             "certify": (0, 100_000), "falsify": (0, 100_000)}  # fmt: skip
    for key, (low, high) in whole.items():
        value = out[key]
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise ConfigError(
                f"{where}: budgets.{key}", f"expected an integer in [{low}, {high}], got {value!r}"
            )
    for key in ("epsilon", "beta"):
        value = out[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < 1:
            raise ConfigError(f"{where}: budgets.{key}", f"expected a number in (0, 1), got {value!r}")
    for key in ("margin", "second_engine", "realtime"):
        if not isinstance(out[key], bool):
            raise ConfigError(f"{where}: budgets.{key}", f"expected true or false, got {out[key]!r}")
    for key in ("max_rms_torque", "max_saturated", "tolerance"):
        value = out[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
            raise ConfigError(f"{where}: budgets.{key}", f"expected a number > 0, got {value!r}")
    from ...run.properties import check_claim

    check_claim(
        out["epsilon"], out["beta"], names=(f"{where}: budgets.epsilon", f"{where}: budgets.beta", "")
    )
    if 0 < out["falsify"] < 4:
        raise ConfigError(
            f"{where}: budgets.falsify", f"expected 0 (no search) or at least 4, got {out['falsify']}"
        )
    if out["certify"]:
        from ...run.properties import samples_needed

        needed = samples_needed(out["epsilon"], out["beta"])
        if out["certify"] < needed:
            raise ConfigError(
                f"{where}: budgets.certify",
                f"{out['certify']} draws cannot prove P(fail) <= {out['epsilon']:g} with confidence "
                f"1 - {out['beta']:g}; it needs at least {needed} (or leave certify out)",
            )
    if out["max_saturated"] > 1:
        raise ConfigError(
            f"{where}: budgets.max_saturated", f"expected a fraction in (0, 1], got {out['max_saturated']!r}"
        )
    return out


def _cases(cases, path: Path) -> list[StudyCase]:
    """The ``cases`` list: presets or experiment files (read from the study's folder), or tables
    ``{name, base, set}`` (a case with overrides of its own); names unique.
    """
    where = str(path)
    if not isinstance(cases, list) or not cases:
        raise ConfigError(f"{where}: cases", f"expected a list of presets or experiment files, got {cases!r}")
    if len(cases) > MAX_CASES:
        raise ConfigError(
            f"{where}: cases",
            f"{len(cases)} cases: a study has at most {MAX_CASES} (each is tuned, validated, certified "
            "and falsified on its own draws); split it into several studies",
        )
    out = []
    for i, case in enumerate(cases):
        table = case if isinstance(case, dict) else None
        if table is not None:
            for key in table:
                if key not in CASE_KEYS:
                    raise ConfigError(
                        f"{where}: cases[{i}].{key}",
                        f"unknown key{_suggest(key, CASE_KEYS)} Valid: {', '.join(CASE_KEYS)}",
                    )
            for key in ("name", "base"):
                if not isinstance(table.get(key), str):
                    raise ConfigError(f"{where}: cases[{i}].{key}", "missing (a string)")
            if not NAME.fullmatch(table["name"]):
                raise ConfigError(
                    f"{where}: cases[{i}].name",
                    f"must be 1-40 letters, digits, '_' or '-', got {table['name']!r}",
                )
            if not isinstance(table.get("set", {}), dict):
                raise ConfigError(f"{where}: cases[{i}].set", "expected a table of overrides")
            case = table["base"]
        elif not isinstance(case, str):
            raise ConfigError(
                f"{where}: cases",
                f"expected presets, experiment files or {{name, base, set}} tables, got {case!r}",
            )
        if case.endswith(".toml"):
            file = (path.parent / case).resolve()
            if not file.is_file():
                raise ConfigError(f"{where}: cases", f"{case!r} is not a file (read from {path.parent})")
            case = str(file)
        name = table["name"] if table else (Path(case).stem if case.endswith(".toml") else case)
        if not table and not NAME.fullmatch(name):  # it names the case's folder and its rows
            raise ConfigError(
                f"{where}: cases[{i}]",
                f"the case file {Path(case).name!r} gives the case the name {name!r}, which must be "
                "1-40 letters, digits, '_' or '-' (it names the case's folder and table rows): "
                "rename the file, or give the case as a table {name = ..., base = ...}",
            )
        out.append(StudyCase(name, case, dict(table.get("set", {})) if table else {}))
    names = [c.name for c in out]
    if len(set(names)) != len(names):
        raise ConfigError(f"{where}: cases", f"names a case twice: {', '.join(names)}")
    return out


def parse_study(data: dict, path: Path) -> StudySpec:
    """Validate a study table (as read from TOML); every error names the file and its key."""
    where = str(path)
    for key in data:
        if key not in KEYS:
            raise ConfigError(f"{where}: {key}", f"unknown key{_suggest(key, KEYS)} Valid: {', '.join(KEYS)}")
    data, box = with_box(data, path.parent, where)  # its [set] and [vary] merged in
    for key in ("name", "cases", "controllers"):
        if key not in data:
            raise ConfigError(f"{where}: {key}", "missing")
    name = data["name"]
    if not isinstance(name, str) or not NAME.fullmatch(name):
        raise ConfigError(f"{where}: name", f"must be 1-40 letters, digits, '_' or '-', got {name!r}")
    cases = _cases(data["cases"], path)
    fixed: list[str] = []
    trained: dict[str, dict] = {}
    controllers = data["controllers"]
    if isinstance(controllers, list):
        from ..base.plan import ENTRY_KEYS

        controllers = [dict(c) if isinstance(c, dict) else c for c in controllers]
        for i, c in enumerate(controllers):
            for key in c if isinstance(c, dict) else ():
                if key not in (*ENTRY_KEYS, ENTRY_TUNE, ENTRY_CASES, ENTRY_TRAIN):
                    valid = (*ENTRY_KEYS, ENTRY_TUNE, ENTRY_CASES, ENTRY_TRAIN)
                    raise ConfigError(
                        f"{where}: controllers[{i}].{key}",
                        f"unknown key{_suggest(key, valid)} Valid: {', '.join(valid)}",
                    )
            if isinstance(c, dict) and ENTRY_TRAIN in c:
                trained[str(c.get("name"))] = _train_table(c, f"{where}: controllers[{i}]")
            if isinstance(c, dict) and ENTRY_TUNE in c:
                if not isinstance(c[ENTRY_TUNE], bool):
                    raise ConfigError(f"{where}: controllers", f"an entry's tune is true or false, got {c!r}")
                if not c.pop(ENTRY_TUNE):
                    fixed.append(str(c.get("name")))
                if list(c) == ["name"]:  # {name = "nn", tune = false}: a kind at its own settings
                    controllers[i] = c["name"]
        controllers, per_case = _per_case(controllers, cases, fixed, where)
    else:
        per_case = {}
    require = data.get("require", [])
    if not isinstance(require, list) or not require or not all(isinstance(r, str) for r in require):
        raise ConfigError(
            f"{where}: require",
            f"expected a list of properties, e.g. ['rms_error_after_2s<=0.005'], got {require!r}",
        )
    from ...run.properties import run_properties

    try:
        run_properties(require)
    except ConfigError as err:
        raise ConfigError(f"{where}: require", str(err)) from err
    vary = data.get("vary", {})
    if isinstance(vary, dict):
        grid = [k for k, v in vary.items() if isinstance(v, list)]
        if grid:
            raise ConfigError(
                f"{where}: vary.{grid[0]}",
                "a study's uncertainty set is distributions (the draws of tuning, validation and "
                "certification); give {uniform = [a, b]}, {loguniform = ...}, {normal = ...} or "
                "{choice = [...]}",
            )
    seed = data.get("seed", 0)
    if isinstance(seed, int) and not isinstance(seed, bool) and not 0 <= seed < 2**62:
        raise ConfigError(  # its stages' seeds are seed + offsets, each a sweep's seed (< 2^63)
            f"{where}: seed",
            f"expected an integer in [0, 2^62) (the stages' seeds derive from it), got {seed}",
        )
    # the sweep file's own checks: controllers, [set], [vary], seed
    sweep = parse_sweep(
        {
            "name": name,
            "base": cases[0].base,
            "controllers": controllers,
            "seed": data.get("seed", 0),
            **({"set": data["set"]} if "set" in data else {}),
            **({"vary": vary} if "vary" in data else {}),
        },
        *(where, path.parent),
    )
    resolve_entry_files(sweep.entries, path.parent)  # class and policy files: from the study's folder
    case_controllers = {}
    for case_name, listed in per_case.items():  # each case's own list, checked as a sweep file's
        own = parse_sweep({"name": name, "base": cases[0].base, "controllers": listed, "seed": 0}, where)
        resolve_entry_files(own.entries, path.parent)
        case_controllers[case_name] = (own.controllers, own.entries)
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ConfigError(f"{where}: description", "expected a string")
    waive = data.get("waive", [])
    if not isinstance(waive, list) or not all(isinstance(w, str) for w in waive):
        raise ConfigError(
            f"{where}: waive", f"expected a list of names among {', '.join(DESIGN)}, got {waive!r}"
        )
    for w in waive:
        if w not in DESIGN:
            raise ConfigError(
                f"{where}: waive",
                f"{w!r} is not part of the design's requirement{_suggest(w, DESIGN)} "
                f"Valid: {', '.join(DESIGN)}",
            )
    names, entries, tuned = sweep.controllers, sweep.entries, ""
    if "tuned" in data:
        _no_training_at_kept_settings(trained, where)
        names, entries, fixed, tuned = _tuned_elsewhere(data["tuned"], sweep, path)
    for c, table in trained.items():  # a residual on a law the study tunes learns on its kept setting
        table["base"] = _trained_base(entries[c], names, fixed, trained)
    for c in names:  # a tuned law's kept setting is certified as NAME-tuned
        if c not in fixed and kept_name(c) in names:
            raise ConfigError(
                f"{where}: controllers",
                f"{kept_name(c)!r} is the name the study gives the kept setting of {c!r}, which is "
                "tuned here: rename one of them",
            )
    for case in cases:  # each case's own overrides: the keys a sweep file's [set] takes
        if case.set:
            try:
                only_set = {"name": name, "base": case.base, "controllers": ["pd"], "set": case.set}
                parse_sweep(only_set, where)  # "pd" stands for any law: the set alone is checked
            except ConfigError as err:
                raise ConfigError(
                    f"{where}: cases.{case.name}.{err.key.split(': ')[-1]}", err.message
                ) from err
            clash = sorted(set(case.set) & (set(sweep.vary) | set(box.get("keys", []))))
            if clash:
                raise ConfigError(
                    f"{where}: cases.{case.name}.set",
                    f"sets {clash[0]!r}, which [vary] draws or the box file gives: a case may not change "
                    "the box",
                )
    return StudySpec(
        name,
        path,
        cases,
        names,
        entries,
        fixed,
        list(require),
        sweep.seed,
        sweep.set,
        sweep.vary,
        _budgets(data.get("budgets", {}), where),
        description,
        tuned,
        list(dict.fromkeys(waive)),
        case_controllers,
        trained,
        box,
    )


def _no_training_at_kept_settings(trained: dict, where: str) -> None:
    if trained:
        raise ConfigError(
            f"{where}: tuned",
            f"the study trains {', '.join(trained)}: a study whose laws run at another study's kept "
            "settings trains no policy (train it in that study, or give its file with tune = false)",
        )


def _trained_base(entry: dict, names: list[str], fixed: list[str], trained: dict) -> str | None:
    """The law a trained residual or gains policy learns on the kept setting of: its base, where
    the study tunes it; else None (the base at the case's own settings, or a torque policy).
    """
    params = policy_params(entry.get("params"))
    base = params["base"] if params["action"] != "torque" else None
    return base if base in names and base not in fixed and base not in trained else None


def _train_table(entry: dict, where: str) -> dict:
    """A policy entry's ``train`` table, checked (:data:`TRAIN_KEYS`); the entry loses its
    ``train`` key (the sweeps run the trained file) and may not also be tuned or fixed.
    """
    table = entry.pop(ENTRY_TRAIN)
    if entry.get("kind") != "policy" or "class" in entry:
        raise ConfigError(
            f"{where}.train", f'only a policy entry (kind = "policy") is trained, not {entry.get("name")!r}'
        )
    if ENTRY_TUNE in entry:
        raise ConfigError(f"{where}.tune", "a trained policy is neither tuned nor fixed: drop tune")
    if "file" in (entry.get("params") or {}):
        raise ConfigError(
            f"{where}.params.file",
            "the train stage writes a trained policy's file: drop file, or drop train (and give "
            "tune = false) to run a policy trained before",
        )
    if not isinstance(table, dict):
        raise ConfigError(
            f"{where}.train", f'expected a table such as {{algorithm = "ppo", budget = 60.0}}, got {table!r}'
        )
    for key in table:
        if key not in TRAIN_KEYS:
            raise ConfigError(
                f"{where}.train.{key}",
                f"unknown key{_suggest(key, TRAIN_KEYS)} Valid: {', '.join(TRAIN_KEYS)}",
            )
    algorithm = table.get("algorithm")
    if algorithm not in ALGORITHMS:
        raise ConfigError(
            f"{where}.train.algorithm", f"expected one of {', '.join(ALGORITHMS)}, got {algorithm!r}"
        )
    budget = table.get("budget")
    if isinstance(budget, bool) or not isinstance(budget, int | float) or not 0 < budget < math.inf:
        raise ConfigError(
            f"{where}.train.budget", f"expected simulated seconds of training > 0, got {budget!r}"
        )
    checked = {"algorithm": algorithm, "budget": float(budget)}
    counts = (("seeds", 1, 1, 20), ("num_envs", 8, 1, 256), ("curve_points", 10, 1, 1000),
              ("curve_episodes", 8, 1, 1000))  # fmt: skip
    for key, default, low, high in counts:
        value = table.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
            raise ConfigError(
                f"{where}.train.{key}", f"expected an integer in [{low}, {high}], got {value!r}"
            )
        checked[key] = value
    hyper = table.get("hyper", {})
    if not isinstance(hyper, dict):
        raise ConfigError(f"{where}.train.hyper", f"expected a table of hyper-parameters, got {hyper!r}")
    try:
        hyper_settings(algorithm, hyper)  # the trainer's own check, before any stage runs
    except ConfigError as err:
        raise ConfigError(f"{where}.train.{err.key}", err.message) from err
    checked["hyper"] = dict(hyper)
    params = policy_params(entry.get("params"))
    if params["action"] != "torque" and params["base"] not in base_laws():
        raise ConfigError(
            f"{where}.params.base",
            f"{params['base']!r}: a trained policy's base law runs on the compiled loop, so it is one of "
            f"{', '.join(base_laws())}{_suggest(str(params['base']), base_laws())}",
        )
    return checked


def _per_case(controllers: list, cases: list[StudyCase], fixed: list[str], where: str):
    """The controllers list with ``cases = [...]`` taken out of its entries: (the list a sweep
    file's checks read, one entry per name, the first; case name -> that case's own list) where
    some entry names its cases, else (the list, {}). Two entries of one name must each list
    their cases, none twice, and agree on being tuned.
    """
    known = [c.name for c in cases]
    listed: dict[int, list[str]] = {}
    for i, c in enumerate(controllers):
        if isinstance(c, dict) and ENTRY_CASES in c:
            names = c.pop(ENTRY_CASES)
            if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
                raise ConfigError(
                    f"{where}: controllers[{i}].cases", f"expected a list of case names, got {names!r}"
                )
            unknown = [n for n in names if n not in known]
            if unknown:
                raise ConfigError(
                    f"{where}: controllers[{i}].cases",
                    f"{unknown[0]!r} is not a case of the study{_suggest(unknown[0], known)} "
                    f"Cases: {', '.join(known)}",
                )
            listed[i] = names
    if not listed:
        return controllers, {}
    by_name: dict[str, list[int]] = {}
    for i, c in enumerate(controllers):
        by_name.setdefault(str(c.get("name")) if isinstance(c, dict) else str(c), []).append(i)
    for law, places in by_name.items():
        if len(places) == 1:
            continue
        if any(i not in listed for i in places):
            raise ConfigError(
                f"{where}: controllers",
                f"{law!r} has {len(places)} entries: each must list the cases it runs on (cases = [...])",
            )
        seen: set[str] = set()
        for i in places:
            twice = seen & set(listed[i])
            if twice:
                raise ConfigError(
                    f"{where}: controllers", f"{law!r} has two entries for the case {sorted(twice)[0]!r}"
                )
            seen |= set(listed[i])
    first = [controllers[places[0]] for places in by_name.values()]
    per_case = {
        case: [c for i, c in enumerate(controllers) if i not in listed or case in listed[i]] for case in known
    }
    return first, per_case


def _tuned_elsewhere(value, sweep: SweepSpec, path: Path) -> tuple[list[str], dict, list[str], str]:
    """``tuned = "FILE#CASE"``: every controller at the kept setting another tuning found (a
    study's report.json with one of its cases, its cases/CASE/kept.json, or ``nnrobust tune``'s
    DIR or summary.json; read from the study's folder), as ``nnrobust falsify --tuned`` runs it:
    NAME-tuned, an entry with the setting, untuned here (a controller that tuning ran at its own
    settings keeps its name and entry). Returns (names, entries, fixed, the source, absolute).
    """
    from ..base.tuned import tuned_entry, tuned_settings

    where = f"{path}: tuned"
    if not isinstance(value, str) or not value.split("#")[0]:
        raise ConfigError(
            where, f"expected a study's report as 'REPORT.json#CASE' or a tuning's folder, got {value!r}"
        )
    text, sep, case = value.partition("#")
    file = (path.parent / text).resolve()
    source = str(file) + sep + case
    if not file.exists():
        raise ConfigError(where, f"{text!r} does not exist (read from {path.parent})")
    if file.is_dir() and (file / "report.json").is_file():
        said = f"{text!r} is a study's folder: name its report and a case, '{text}/report.json#CASE'"
        raise ConfigError(where, said)
    try:
        settings = tuned_settings(source, sweep.controllers, list(sweep.vary), sweep.entries)
    except ConfigError as err:  # a file's own key (its path) kept: "cannot read ..." names it
        said = err.message if err.key == "--tuned" else f"{err.key}: {err.message}"
        raise ConfigError(where, said) from err
    names, entries = [], {}
    for c in sweep.controllers:
        if c in settings:
            label = kept_name(c)
            entries[label] = tuned_entry(c, settings[c], sweep.entries)
        else:
            label = c
            if c in sweep.entries:
                entries[c] = sweep.entries[c]
        names.append(label)
    return names, entries, list(names), source


def load_study(path: str | Path) -> StudySpec:
    """Read and validate a study file."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(str(path), "is not a file (a study file, TOML: docs/study.md)")
    data = parse_toml(read_text_file(path, what="study file"), str(path))
    return parse_study(data, path.resolve())
