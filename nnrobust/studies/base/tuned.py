"""Tuned settings, as every study command reads them: a tuning's best setting of each law or a
study's kept setting of one case (``--tuned DIR|summary.json|REPORT.json#CASE``), checked to set
only keys the law reads itself and none the box varies; the sweep entry that runs a law at such a
setting; and the laws a tuner can search with the keys each reads (its own keys, docs/tuning.md).
"""

from __future__ import annotations

import json
from pathlib import Path

from ...config import CLASS_PATTERN
from ...core.exceptions import ConfigError
from .plan import NAME

TUNED_FILE_BYTES = 50_000_000
"""The largest tuning summary or study report --tuned reads (the shipped reports are under 0.3 MB)."""


def law_of(name: str, entries: dict | None = None) -> str:
    """The law a controller name runs, as :func:`.space.own_keys` knows it: a shipped kind or
    registered law by its name, a sweep file's entry by its kind (or ``custom``), a class given as
    file.py:Class as ``custom``.
    """
    entry = (entries or {}).get(name)
    if entry is not None:
        return entry.get("kind", "custom")
    return "custom" if CLASS_PATTERN.fullmatch(name) else name


def summary_name(name: str) -> str:
    """The name a controller has in a tuning's summary: a class given as NAME=file.py:Class by
    NAME, as file.py:Class by its class name, any other by the name given (:func:`with_controllers`).
    """
    label, equals, spec = name.partition("=")
    if equals and CLASS_PATTERN.fullmatch(spec):
        return label
    return name.rpartition(":")[2] if CLASS_PATTERN.fullmatch(name) else name


def check_tuned(
    tuned: dict[str, dict], varied=(), where: str = "--tuned", entries: dict | None = None
) -> None:
    """Refuse a tuned setting (controller name -> dotted-key settings) that sets a key the law
    does not read itself (:func:`.space.own_keys`: a plant's, the controller's kind, another
    law's; a custom law's are its ``controller.params.*``), or a key the box varies (``varied``,
    dotted keys): it would run every point of the box at that value while the summary claims the
    box. ``where`` names the settings' file in the message; ``entries``: the sweep file's table
    entries, by name. A residual or gains policy reads its base law's keys too (it runs that law:
    a policy trained on a tuned law carries its setting).
    """
    import re

    box = {re.sub(r"\[\d+\]$", "", str(k)) for k in varied}
    for name, settings in tuned.items():
        keys, prefixes = own_keys(law_of(name, entries))
        params = ((entries or {}).get(name) or {}).get("params") or {}
        if law_of(name, entries) == "policy" and params.get("action", "torque") != "torque":
            base_keys, base_prefixes = own_keys(str(params.get("base", "pd")))  # the base law it runs
            keys, prefixes = keys | base_keys, prefixes + base_prefixes
        for key in settings:
            plain = re.sub(r"\[\d+\]$", "", str(key))
            if plain not in keys and not plain.startswith(prefixes):
                own = ", ".join([*sorted(keys), *(f"{p}*" for p in prefixes)])
                raise ConfigError(
                    "--tuned",
                    f"{where} sets {key!r} for {name}, which is not a key {name} reads itself; a tuned "
                    f"setting may set only the law's own keys ({own})",
                )
            if plain in box:
                raise ConfigError(
                    "--tuned",
                    f"{where} sets {key!r} for {name}, which the box varies: a tuned setting may not "
                    "fix a coordinate of the box (drop it from [vary], or tune without it)",
                )


STUDY_REPORT = "nnrobust-study-report/"
"""The schema of a study's report.json, whose kept settings ``--tuned FILE#CASE`` reads."""


def _study_kept(report: dict, file: Path, case: str) -> dict:
    """One case's kept settings of a study's report.json, as its ``cases/CASE/kept.json`` holds
    them: each tuned controller's kept setting as its best, an untuned one as fixed.
    """
    cases = report.get("cases")
    if not isinstance(cases, dict):
        cases = {}
    if case not in cases or not isinstance(cases[case], dict):
        raise ConfigError(
            "--tuned",
            f"{file} is a study's report: name one of its cases as {file}#CASE, one of "
            f"{', '.join(repr(k) for k in cases)}" + (f" (not {case!r})" if case else ""),
        )
    controllers = cases[case].get("controllers")
    if not isinstance(controllers, dict):
        raise ConfigError("--tuned", f"{file}: case {case!r} has no controllers table")
    kept: dict = {}
    for name, entry in controllers.items():
        tuned = entry.get("tuned") if isinstance(entry, dict) else None
        settings = tuned.get("settings") if isinstance(tuned, dict) else None
        kept[name] = {"fixed": True} if tuned is None else {"best": {"params": settings}}
    return {"controllers": kept}


def study_report(path: str | Path) -> tuple[dict | None, str]:
    """(a study's report.json, the case named after ``#``) of ``REPORT.json#CASE``; None for the
    report where the file is not a study's report, cannot be read or is over TUNED_FILE_BYTES.
    """
    file, case = tuned_file(path)
    try:
        report = (
            json.loads(file.read_text()) if file.is_file() and file.stat().st_size < TUNED_FILE_BYTES else {}
        )
    except (OSError, ValueError, RecursionError):
        return None, case
    if not isinstance(report, dict) or not str(report.get("schema", "")).startswith(STUDY_REPORT):
        return None, case
    return report, case


def kept_entry(path: str | Path, name: str) -> dict | None:
    """The controllers entry a study certified as ``name`` (the name the study gave the law, its
    kept setting's ``NAME-tuned`` label, or the class name of a file.py:Class) in one case of its
    report (``REPORT.json#CASE``): its kind or class and the params and settings it ran with; None
    where the source is not a study's report or has no such law.
    """
    report, case = study_report(path)
    if report is None:
        return None
    controllers = ((report.get("cases") or {}).get(case) or {}).get("controllers") or {}
    wanted = summary_name(name)
    for law, entry in controllers.items():
        if (
            isinstance(entry, dict)
            and wanted in (law, entry.get("label"))
            and isinstance(entry.get("entry"), dict)
        ):
            return entry["entry"]
    return None


def tuned_file(path: str | Path) -> tuple[Path, str]:
    """(the file ``--tuned`` reads, the case named after ``#``): a tuning's DIR is its
    summary.json; ``FILE#CASE`` names one case of a study's report.
    """
    text, _, case = str(path).partition("#")
    return (Path(text) / "summary.json" if Path(text).is_dir() else Path(text)), case


def tuned_settings(
    path: str | Path, names: list[str], varied=(), entries: dict | None = None
) -> dict[str, dict]:
    """Each named controller's best setting in a tuning's summary (``DIR`` or its summary.json), or
    a study's kept settings of one case (its ``cases/CASE/kept.json``, or its report.json named as
    ``FILE#CASE``): name -> its dotted-key overrides, each a key the law reads itself and none of
    ``varied``, the box's keys (:func:`check_tuned`). Every law takes them: a shipped kind, a
    registered law, a class as file.py:Class (found under its class name) and a sweep file's
    entry (``entries``, by name).
    """
    from ...config import read_text_file

    file, case = tuned_file(path)
    try:
        summary = json.loads(read_text_file(file, limit=TUNED_FILE_BYTES, what="tuning summary"))
    except ValueError as err:
        raise ConfigError("--tuned", f"{file} is not JSON ({err})") from err
    except RecursionError as err:
        raise ConfigError("--tuned", f"{file} nests too deeply to be a tuning's summary") from err
    if isinstance(summary, dict) and str(summary.get("schema", "")).startswith(STUDY_REPORT):
        summary = _study_kept(summary, file, case)
    elif case:
        raise ConfigError("--tuned", f"{file} is one tuning, not a study's report: drop #{case}")
    tuned = summary.get("controllers") if isinstance(summary, dict) else None
    if not isinstance(tuned, dict) or not all(isinstance(e, dict) for e in tuned.values()):
        raise ConfigError(
            "--tuned",
            f"{file} is not a tuning's summary.json (no controllers table; nnrobust tune writes one)",
        )
    out = {}
    for name in names:
        if (tuned.get(summary_name(name)) or {}).get("fixed") is True:  # a study's untuned controller
            continue
        best = (tuned.get(summary_name(name)) or {}).get("best")
        if not best:
            raise ConfigError(
                "--tuned",
                f"{file} has no best setting for {summary_name(name)!r} (it tuned "
                f"{', '.join(tuned) or 'nothing'})",
            )
        if not isinstance(best, dict) or not isinstance(best.get("params"), dict):
            raise ConfigError("--tuned", f"{file}: the best setting of {name!r} has no table of params")
        out[name] = dict(best["params"])
    check_tuned(out, varied, str(file), entries)
    return out


def tuned_target(path: str | Path) -> str:
    """The experiment a tuning tuned on (its summary's ``target``; a study report's case, by
    name), "" when the file does not say (read after :func:`tuned_settings` accepted it).
    """
    from ...config import read_text_file

    file, case = tuned_file(path)
    try:
        summary = json.loads(read_text_file(file, limit=TUNED_FILE_BYTES, what="tuning summary"))
    except (ValueError, RecursionError, ConfigError):
        return ""
    if isinstance(summary, dict) and str(summary.get("schema", "")).startswith(STUDY_REPORT):
        cases = summary.get("cases")  # a case's name: the preset, or the experiment file's stem
        return case if isinstance(cases, dict) and case in cases else ""
    target = summary.get("target") if isinstance(summary, dict) else None
    return target if isinstance(target, str) else ""


def tuned_entry(name: str, settings: dict, entries: dict) -> dict:
    """The sweep entry that runs controller ``name`` at its tuned dotted-key ``settings``, as a
    sweep file would write it: a shipped kind as ``{kind, set}``, a registered law's
    ``controller.params.*`` as its ``params``; a custom law (file.py:Class, or a sweep entry of a
    class) as ``{class, params}`` with the settings' ``controller.params.*`` over its own params; a
    sweep entry of a kind with the settings over its own.
    """
    from ...plugins.user_code import class_file

    entry = entries.get(name)
    if entry is None and CLASS_PATTERN.fullmatch(name):
        path = class_file(name)
        entry = {
            "class": f"{path.resolve()}:{summary_name(name)}" if path is not None else name,
            "params": {},
        }
    prefix = "controller.params."
    params = {k[len(prefix) :]: v for k, v in settings.items() if k.startswith(prefix)}
    rest = {k: v for k, v in settings.items() if not k.startswith(prefix)}
    if entry is None:
        entry = {"kind": name, "set": {}}
    if "class" in entry:
        return {"class": entry["class"], "params": {**(entry.get("params") or {}), **params}}
    own = {**(entry.get("params") or {}), **params}
    return {**entry, "set": {**(entry.get("set") or {}), **rest}, **({"params": own} if own else {})}


def check_tuned_values(sweep, tuned: dict, where: str = "--tuned") -> None:
    """Each tuned setting's values checked as the experiment reads them (on the sweep's first
    sample), a refusal naming --tuned, the law and the key, not a sample of the box.
    """
    from ..base.plan import base_values, draw, experiment

    base = base_values(sweep)
    for name in tuned:
        try:
            experiment(sweep, base, draw(sweep, 0), f"{summary_name(name)}-tuned")
        except ConfigError as err:
            said = str(err).removeprefix("vary: ").split(" (sample ")[0]
            raise ConfigError(where, f"the tuned setting of {name}: {said}") from err


def with_controllers(sweep, names: list[str], tuned: dict | None = None):
    """The sweep with the tuning's controllers: built-in kinds, the sweep file's table entries by
    name, and classes given as file.py:Class (named by the class, the file read from the working
    folder). A built-in law in ``tuned`` (name -> dotted-key settings) runs at those settings as
    the entry ``NAME-tuned``.
    """
    from ...plugins.user_code import class_file

    entries, controllers = {}, []
    for name in names:
        if tuned and name in tuned:
            tuned_name = f"{summary_name(name)}-tuned"
            entries[tuned_name] = tuned_entry(name, tuned[name], sweep.entries)
            controllers.append(tuned_name)
        elif name in tunable():
            controllers.append(name)
        elif name in sweep.entries:
            entries[name] = sweep.entries[name]
            controllers.append(name)
        elif CLASS_PATTERN.fullmatch(name.partition("=")[2] if "=" in name else name):
            label, _, spec = name.rpartition("=")  # NAME=file.py:Class names the entry itself
            path, cls = class_file(spec), spec.rpartition(":")[2]
            label = label or cls
            if not NAME.fullmatch(label):
                raise ConfigError("--controllers", f"{label!r} must be 1-40 letters, digits, '_' or '-'")
            entries[label] = {"class": f"{path.resolve()}:{cls}" if path is not None else spec, "params": {}}
            controllers.append(label)
        else:
            raise ConfigError(
                "--controllers",
                f"{name!r} is not one of {', '.join(tunable())}, a class as "
                f"file.py:Class, nor a custom entry of the sweep file "
                f"({', '.join(sweep.entries) or 'it has none'})",
            )
    if len(set(controllers)) != len(controllers):
        raise ConfigError(
            "--controllers",
            f"names a controller twice: {', '.join(controllers)} (two files with one class name: name "
            "each, NAME=file.py:Class)",
        )
    sweep.controllers, sweep.entries = controllers, entries
    return sweep


def tunable() -> tuple[str, ...]:
    """The shipped laws with a search space: the paper's kinds (their gains, and their robust
    terms' declared coordinates) and the registered laws that declare search bounds
    (nnrobust/controllers/laws/).
    """
    from ...controllers.registry import LAWS, law_names, paper_kinds

    return (*paper_kinds(), *(n for n in law_names() if any(p.search for p in LAWS[n].params)))


def own_keys(name: str) -> tuple[frozenset[str], tuple[str, ...]]:
    """The configuration keys the shipped law ``name`` reads itself, as its declaration gives them:
    (keys, prefixes). A paper kind's: eq. (9)'s shared gains where it is eq. (9), and its own
    keys (``section.field``, or ``section.`` for a whole section, a prefix); a registered law's:
    ``controller.params.NAME`` of each parameter it declares; ``custom`` (a user's class): every
    ``controller.params.`` key, a prefix. What a tuned setting of the law may
    set (``falsify --tuned``); its search coordinates (:func:`search_space`) are among them.
    """
    from ...controllers.registry import SHARED_KEYS, paper_kind, registered_law

    if name == "custom":  # a user's class: the parameters its constructor takes
        return frozenset(), ("controller.params.",)
    law = registered_law(name)
    if law is not None:
        return frozenset(f"controller.params.{p.name}" for p in law.params), ()
    kind = paper_kind(name)
    if kind is None:
        return frozenset(), ()
    keys = {p.name for p in kind.params} | {k for k in kind.keys if not k.endswith(".")}
    if kind.eq9:  # eq. (9)'s gains: the shared keys whose readers are the kinds of eq. (9)
        keys |= {p.name for shared in SHARED_KEYS if shared.readers is None for p in shared.params}
    return frozenset(keys), tuple(k for k in kind.keys if k.endswith("."))
