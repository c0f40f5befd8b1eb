"""Experiment files in and out: TOML text to a typed configuration (types checked, then
:func:`~.checks.validate`), a configuration to TOML text with its provenance header, the files a
configuration names (a base preset, user classes) and their digests, and ``--set`` overrides.
"""

from __future__ import annotations

import copy
import dataclasses
import datetime
import difflib
import functools
import math
import os
import re
import sys
import tomllib
import types
import typing
import warnings
from importlib import metadata
from pathlib import Path

from ..core.exceptions import ConfigError
from ..core.package_version import package_version
from ..model.loading import urdf_digest
from ..plugins.native_law import compiled_inputs, is_source
from ..plugins.user_code import class_file, file_digest
from .checks import FILLED_LISTS, INDEXED, validate
from .resolve import resolve
from .schema import KEY_ALIASES, USER_PARTS, ExperimentConfig, _field_names, _user_part
from .shipped import preset_path


def _suggest(key: str, valid: list[str], prefix: str = "") -> str:
    """'unknown key; did you mean X?' and the valid keys (``prefix`` + each name; the names alone
    are compared, so that a shared prefix does not make every key look close).
    """
    close = [prefix + c for c in difflib.get_close_matches(key, valid, n=1)]
    valid = [prefix + v for v in valid]
    hint = f"; did you mean {close[0]!r}?" if close else "."
    return f"unknown key{hint} Valid keys: {', '.join(valid)}"


_TYPE_WORDS = {str: "string", float: "number", int: "integer", bool: "boolean"}


def _check_type(path: str, value, annotation):
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1:
            return _check_type(path, value, inner[0])
        for alternative in inner:  # e.g. str | list[float]: the first that takes the value
            if (typing.get_origin(alternative) or alternative) is type(value):
                return _check_type(path, value, alternative)
        kinds = " or ".join(
            "a list" if typing.get_origin(a) is list else f"a {_TYPE_WORDS[a]}" for a in inner
        )
        raise ConfigError(path, f"expected {kinds}, got {type(value).__name__} {value!r}")
    if origin is list:
        if not isinstance(value, list):
            raise ConfigError(path, f"expected a list, got {type(value).__name__} {value!r}")
        return [_check_type(f"{path}[{i}]", v, args[0]) for i, v in enumerate(value)]
    if annotation is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(path, f"expected a number, got {type(value).__name__} {value!r}")
        if isinstance(value, int) and abs(value) >= 2**63:
            raise ConfigError(
                path,
                f"expected a finite number of sensible size, got an integer of {len(str(abs(value)))} digits",
            )
        if not math.isfinite(value):
            raise ConfigError(path, f"expected a finite number, got {value!r}")
        return float(value)
    if annotation is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(path, f"expected an integer, got {type(value).__name__} {value!r}")
        if abs(value) >= 2**63:
            raise ConfigError(
                path, f"expected an integer in (-2^63, 2^63), got one of {len(str(abs(value)))} digits"
            )
        return value
    if annotation is bool:
        if not isinstance(value, bool):
            raise ConfigError(path, f"expected true or false, got {value!r}")
        return value
    if annotation is dict:  # free keyword arguments (controller.params): names checked, values kept
        if not isinstance(value, dict):
            raise ConfigError(path, f"expected a table, got {type(value).__name__} {value!r}")
        refuse_dates(value, path)
        for key in value:
            if not key.isidentifier():
                raise ConfigError(
                    f"{path}.{key}", "is not a valid Python identifier (a keyword argument name)"
                )
        return dict(value)
    if annotation is str:
        if not isinstance(value, str):
            raise ConfigError(path, f"expected a string, got {type(value).__name__} {value!r}")
        return value
    raise TypeError(f"unsupported annotation {annotation!r} at {path}")  # pragma: no cover


@functools.cache
def _type_hints(cls) -> dict:
    """The annotations of a config dataclass, resolved once (every sample of a sweep parses one)."""
    return typing.get_type_hints(cls)


def _declared_keys(cls) -> dict:
    """The keys a section's kinds declare beyond its fields (a ``DeclaredKeys`` section's), or {}."""
    return cls.declared_keys() if hasattr(cls, "declared_keys") else {}


def _section_from_dict(cls, data: dict, path: str):
    if not isinstance(data, dict):
        raise ConfigError(path, f"expected a table, got {type(data).__name__}")
    hints = _type_hints(cls)
    names = _field_names(cls)
    declared = _declared_keys(cls)
    values: dict = {}
    shown = [next((a for a, f in KEY_ALIASES.items() if f == n), n) for n in names] + sorted(declared)
    for key, value in data.items():
        full = f"{path}.{key}" if path else key
        key = KEY_ALIASES.get(key, key)
        if key in declared:  # checked against its declaration with the section's rules
            values.setdefault("extra", {})[key] = _declared_value(full, value)
            continue
        if key not in names:
            raise ConfigError(full, _suggest(key, shown))
        annotation = hints[key]
        if dataclasses.is_dataclass(annotation):
            values[key] = _section_from_dict(annotation, value, full)
        else:
            values[key] = _check_type(full, value, annotation)
    return cls(**values)


def _declared_value(path: str, value):
    """A value of a key a kind declares: a number, text, true/false or a list of numbers (its
    range and size are its declaration's, checked with the section's rules).
    """
    numbers = isinstance(value, list) and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
    )
    if isinstance(value, (bool, int, float, str)) or numbers:
        return value
    raise ConfigError(path, f"expected a number, a text, true or false or a list of numbers, got {value!r}")


def from_dict(data: dict) -> ExperimentConfig:
    """A configuration from nested dicts (as read from TOML): built, validated and resolved
    (:func:`.resolve.resolve`).
    """
    config = _section_from_dict(ExperimentConfig, data, "")
    validate(config)
    return resolve(config)


MAX_TOML_BYTES = 1_000_000
"""Largest experiment or sweep file read (an experiment file is a few kB)."""


def read_text_file(path: str | Path, limit: int = MAX_TOML_BYTES, what: str = "file") -> str:
    """The text of a regular file of at most ``limit`` bytes; a device, FIFO, folder, larger or
    non-UTF-8 file is one clear error (never an endless read or a hang).
    """
    path = Path(path)
    try:
        if path.exists() and not path.is_file():
            raise ConfigError(str(path), f"not a regular file; give a TOML {what}")
        with open(path, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as err:
        raise ConfigError(str(path), f"cannot read the file: {err.strerror or err}") from err
    if len(data) > limit:
        article = "an" if what[0] in "aeiou" else "a"
        raise ConfigError(str(path), f"larger than {limit // 1000} kB, the most read for {article} {what}")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ConfigError(str(path), "not a UTF-8 text file") from err


def _too_long(err: ValueError) -> str:
    """The error of tomllib for an integer Python will not read (more than 4300 digits), in words."""
    digits = re.search(r"value has (\d+) digits", str(err))
    if not digits:
        return f"{type(err).__name__}: {err}"
    return (
        f"an integer of {digits.group(1)} digits (at most {sys.get_int_max_str_digits()} are "
        "read, and no key takes one of more than 19)"
    )


def parse_toml(text: str, where: str) -> dict:
    """tomllib.loads with one-line errors (also for tables nested too deep to parse), refusing
    TOML dates and times (:func:`refuse_dates`). A UTF-8 byte-order mark at the start (as some
    editors on Windows write one) is read as nothing.
    """
    try:
        data = tomllib.loads(text.removeprefix("\ufeff"))
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(where, f"invalid TOML: {err}") from err
    except RecursionError as err:
        raise ConfigError(where, "invalid TOML: nested too deeply") from err
    except ValueError as err:  # Python refuses to read an integer of more than 4300 digits
        raise ConfigError(where, f"invalid TOML: {_too_long(err)}") from err
    refuse_dates(data, "", f"{where}: ")
    return data


TOML_DATES = {datetime.datetime: "date-time", datetime.date: "date", datetime.time: "time"}
"""TOML's date and time values (tomllib's types), which no key of an experiment, a sweep or a
tuning takes."""


def refuse_dates(value, path: str, where: str = "") -> None:
    """Refuse a TOML date, time or date-time anywhere in ``value`` (tables and arrays), naming its
    key ``path`` (after ``where``: a file, ``--set``): no key takes one, and a free table
    (``controller.params``) that kept it would run, then lose the run when config.toml is written.
    """
    kind = TOML_DATES.get(type(value))
    if kind is not None:
        text = value.isoformat()
        raise ConfigError(
            f"{where}{path or 'value'}",
            f'is a TOML {kind} ({text}), which no key takes; to pass text, quote it: "{text}"',
        )
    try:
        if isinstance(value, dict):
            for key, item in value.items():
                refuse_dates(item, f"{path}.{key}" if path else str(key), where)
        elif isinstance(value, list):
            for i, item in enumerate(value):
                refuse_dates(item, f"{path}[{i}]", where)
    except RecursionError as err:
        raise ConfigError(f"{where}{path or 'value'}", "nested too deeply") from err


def load_config(path: str | Path, overrides: dict | None = None) -> ExperimentConfig:
    """Read and validate a TOML experiment file. A relative URDF path in ``robot.source`` is read
    from the file's folder; a run folder's config.toml that recorded its URDF's SHA-256
    (:func:`provenance_header`) warns when that URDF has changed since.

    ``overrides`` (dotted keys, as ``run --set`` gives them) are set in the file's own values,
    before one-value gains are written out in full (:func:`.resolve.resolve`): the configuration is
    the one the file would give edited so (``robot.task = "pose"`` on a file with ``Kp = [25.0]``
    gives six gains of 25). An error is said to be the file's only when the file alone has it.
    """
    path = Path(path)
    text = read_text_file(path, what="experiment file")
    data = _file_data(path, text)
    edited = copy.deepcopy(data) if overrides else data
    for key, value in (overrides or {}).items():
        set_dotted(edited, key, value)
    try:
        config = from_dict(edited)
    except ConfigError as err:
        own = _error_of(data) if overrides else err
        if own is None:  # the file alone is sound: the overrides made the error
            raise
        raise ConfigError(f"{path}: {own.key}", str(own).split(": ", 1)[1]) from own

    checks = [("robot's URDF", RECORDED_DIGEST, config.robot.source, urdf_digest)]
    for part, source in user_files(config).items():
        pattern = re.compile(rf"^# {part} sha256: ([0-9a-f]{{64}})$", re.MULTILINE)
        checks.append((f"{part} file", pattern, source, _file_digest))
        included = re.compile(rf"^# {part} includes (.+) sha256: ([0-9a-f]{{64}})$", re.MULTILINE)
        for match in included.finditer(text):  # the headers a law in C++ included
            header = str(Path(source).parent / match.group(1))
            pattern = re.compile(
                rf"^# {part} includes {re.escape(match.group(1))} sha256: ([0-9a-f]{{64}})$", re.M
            )
            checks.append((f"{part} file's header {match.group(1)}", pattern, header, _file_digest))
    for what, pattern, source, digest in checks:
        recorded = pattern.search(text)
        if not recorded or not source:
            continue
        try:
            now = digest(source)
        except OSError:
            now = ""
        if now and now != recorded.group(1):
            warnings.warn(
                f"{path}: the {what} ({source}) has changed since this run was written "
                f"(SHA-256 {recorded.group(1)[:12]}... then, {now[:12]}... now)",
                stacklevel=2,
            )
    return config


def _error_of(data: dict) -> ConfigError | None:
    """The error an experiment's tables give, or None."""
    try:
        from_dict(data)
    except ConfigError as err:
        return err
    return None


RECORDED_DIGEST = re.compile(r"^# urdf sha256: ([0-9a-f]{64})$", re.MULTILINE)


MAX_BASE_DEPTH = 8
"""Experiment files that start from one another (``base = "file.toml"``), at most this deep."""


def file_values(path: str | Path, read: list[Path] | None = None) -> dict:
    """An experiment file's own values, not yet validated nor resolved: its tables merged over its
    ``base`` chain, relative paths made absolute (what ``load_config(path, overrides)`` sets its
    keys in). ``read``, if given, gets every file read: the file, then its bases.
    """
    path = Path(path)
    return _file_data(path, read_text_file(path, what="experiment file"), read=read)


DATA_FILE_KEYS = (("nominal", "file"), ("plant", "region"))
"""(section, key) of the keys that name a data file (an identified model, an identified box): a
relative path is read from the folder of the file that gives it."""


def _file_data(path: Path, text: str, depth: int = 0, read: list[Path] | None = None) -> dict:
    """An experiment file's table with its relative paths (robot.source, robot.mesh_folders, the
    classes of :data:`USER_PARTS`) made absolute from the file's folder, merged over its ``base``
    (a preset name or an experiment file): the file's keys win, section by section. Each file
    read is appended to ``read`` (if given).
    """
    if read is not None:
        read.append(path.resolve())
    data = parse_toml(text, str(path))
    folder = path.resolve().parent
    robot = data.get("robot")
    if (
        isinstance(robot, dict)
        and isinstance(robot.get("source"), str)
        and _is_relative_urdf_path(robot["source"])
    ):
        resolved = (folder / robot["source"]).resolve()
        if not resolved.is_file():
            raise ConfigError(
                f"{path}: robot.source",
                f"{robot['source']!r} is not a file in {folder} (a "
                "relative path in an experiment file is read from the file's folder)",
            )
        robot["source"] = str(resolved)
    if isinstance(robot, dict) and isinstance(robot.get("mesh_folders"), list):
        robot["mesh_folders"] = [
            str((folder / entry).resolve()) if isinstance(entry, str) and entry.strip() else entry
            for entry in robot["mesh_folders"]
        ]

    for section, key in DATA_FILE_KEYS:  # an identified model or box, read from the file's folder
        table = data.get(section)
        if isinstance(table, dict) and isinstance(table.get(key), str) and table[key].strip():
            if not Path(table[key]).is_absolute():
                table[key] = str((folder / table[key]).resolve())
    controller = data.get("controller")
    if isinstance(controller, dict):  # a law's data file (a policy's ONNX file), read from the file's folder
        data_file = law_file(controller.get("kind"), controller.get("params"))
        if data_file is not None and not Path(data_file).is_absolute():
            controller["params"]["file"] = str((folder / data_file).resolve())
    for section, key, _, _ in USER_PARTS.values():
        table = data.get(section)
        if isinstance(table, dict) and isinstance(table.get(key), str):
            where, name = class_file(table[key]), table[key].rpartition(":")[2]
            if where is not None and not where.is_absolute():
                table[key] = f"{(folder / where).resolve()}:{name}"
    if "base" not in data:
        return data
    base = data.pop("base")
    if not isinstance(base, str):
        raise ConfigError(f"{path}: base", f"expected a preset name or an experiment file, got {base!r}")
    if depth >= MAX_BASE_DEPTH:
        raise ConfigError(
            f"{path}: base",
            f"experiment files start from one another more than {MAX_BASE_DEPTH} deep (a cycle?)",
        )
    if base.endswith(".toml"):
        base_path = (folder / base).resolve()
        if not base_path.is_file():
            raise ConfigError(f"{path}: base", f"{base!r} is not a file in {folder}")
    else:
        try:
            base_path = preset_path(base)
        except ConfigError as err:
            raise ConfigError(f"{path}: base", str(err).split(": ", 1)[1]) from err
    merged = _file_data(base_path, read_text_file(base_path, what="experiment file"), depth + 1, read)
    for key, value in data.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return merged


def user_classes(config: ExperimentConfig) -> dict[str, str]:
    """The user classes the experiment uses: part (controller, trajectory, disturbance,
    criterion) -> its ``"file.py:Class"`` or ``"package.module:Class"``.
    """
    parts = {part: _user_part(config, part) for part in USER_PARTS}
    return {part: spec for part, (spec, _, chosen, _) in parts.items() if chosen and spec}


def user_files(config: ExperimentConfig) -> dict[str, str]:
    """The files of the user classes the experiment uses (part -> path; module paths left out)."""
    paths = {part: class_file(spec) for part, spec in user_classes(config).items()}
    out = {part: str(path) for part, path in paths.items() if path is not None}
    data_file = law_file(config.controller.kind, config.controller.params)
    if data_file is not None:
        out["policy" if config.controller.kind == "policy" else f"{config.controller.kind} file"] = data_file
    if config.nominal.kind == "identified" and config.nominal.file:
        out["identified model"] = config.nominal.file
    if config.plant.region:
        out["identified box"] = config.plant.region
    return out


def law_file(kind, params) -> str | None:
    """The data file of a registered law, its ``controller.params.file`` (a policy's ONNX file, a
    designed excitation's record: the law declares it a path), or None.
    """
    if not isinstance(kind, str) or not isinstance(params, dict) or not isinstance(params.get("file"), str):
        return None
    from ..controllers.registry import registered_law  # here: the registry imports the laws

    law = registered_law(kind)
    declared = law.param("file") if law is not None else None
    return params["file"] if declared is not None and declared.path else None


def _file_digest(source: str) -> str:

    return file_digest(source)


def _is_relative_urdf_path(source: str) -> bool:
    """Whether robot.source names a URDF file by a relative path (not a robot name, not URDF text)."""
    if source.lstrip().startswith("<") or Path(source).is_absolute():
        return False
    return source.lower().endswith(".urdf") or "/" in source or os.sep in source


@functools.cache
def _package_version(package: str) -> str:
    """An installed package's version, or "?" (read once per process)."""
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "?"


def provenance_header(config: ExperimentConfig) -> str:
    """Comment lines for a run's config.toml: the versions that ran it and the SHA-256 of the
    robot's URDF and of every user class's file, so that a run can be repeated, and checked,
    from anywhere.
    """
    lines = [
        f"# written by nnrobust {package_version()} (pin {_package_version('pin')}, example-robot-data "
        f"{_package_version('example-robot-data')})"
    ]
    digest = urdf_digest(config.robot.source)
    if digest:
        lines.append(f"# urdf sha256: {digest}")
    for part, source in user_files(config).items():
        if Path(source).is_file():
            lines.append(f"# {part} sha256: {_file_digest(source)}")
            lines += _native_lines(part, source)
    return "\n".join(lines) + "\n"


def _native_lines(part: str, source: str) -> list[str]:
    """For a law in C++: the SHA-256 of each header its file includes and of all its library's
    inputs (nnrobust.plugins.native_law.Library: the file, its headers, the toolchain).
    """
    library = compiled_inputs(Path(source)) if is_source(source) else None
    if library is None:
        return []
    lines = [
        f"# {part} includes {_path_text(name)} sha256: {digest}" for name, digest in library.dependencies
    ]
    return [*lines, f"# {part} inputs sha256: {library.digest}"]


def _path_text(name: str) -> str:
    """A header's relative path on one comment line (control characters escaped)."""
    return name.encode("unicode_escape").decode("ascii")


# ---- TOML output -------------------------------------------------------------------------


_TOML_ESCAPES = {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\t": "\\t", "\r": "\\r"}


_TOML_ESCAPED = re.compile(r'[\\"\x00-\x1f\x7f]')


def _toml_string(value: str) -> str:
    """A TOML basic string: quotes, backslashes and every control character escaped."""

    def escape(match: re.Match) -> str:
        c = match.group()
        return _TOML_ESCAPES.get(c) or f"\\u{ord(c):04x}"

    return '"' + _TOML_ESCAPED.sub(escape, value) + '"'


def _toml_key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else _toml_string(key)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):  # an inline table (controller.params)
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {type(value).__name__} to TOML")


def dump_toml(data: dict) -> str:
    """TOML text of a dict whose values are scalars, lists or one level of sub-tables."""
    lines = [f"{k} = {_toml_value(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for key, table in data.items():
        if isinstance(table, dict):
            lines += ["", f"[{key}]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


def check_dotted_key(key: str) -> None:
    """Refuse a dotted key that names no field of the experiment schema (``section.field``, or a
    top-level ``name`` / ``description``, or ``section.field[i]`` of a list field), with a
    suggestion.
    """
    indexed = INDEXED.match(key)
    if indexed:
        section, field_name, _ = indexed.groups()
        check_dotted_key(f"{section}.{field_name}")
        cls = _type_hints(ExperimentConfig)[section]
        declared = _declared_keys(cls).get(field_name)
        annotation = (
            "list" if declared is not None and declared.size != "1" else _type_hints(cls).get(field_name)
        )
        if "list" not in str(annotation):
            raise ConfigError(key, f"{section}.{field_name} is not a list; index only list keys")
        return
    parts = key.split(".")
    top = _field_names(ExperimentConfig)
    hints = _type_hints(ExperimentConfig)
    if len(parts) == 1:
        if parts[0] not in top or dataclasses.is_dataclass(hints.get(parts[0])):
            raise ConfigError(
                key, "not a key of the experiment schema; use section.field, e.g. simulation.duration"
            )
        return
    section, field_name = parts[0], ".".join(parts[1:])
    if section not in top or not dataclasses.is_dataclass(hints[section]):
        raise ConfigError(key, _suggest(section, [t for t in top if dataclasses.is_dataclass(hints[t])]))
    names = [next((a for a, f in KEY_ALIASES.items() if f == n), n) for n in _field_names(hints[section])]
    names += sorted(_declared_keys(hints[section]))
    if len(parts) == 3 and section == "controller" and parts[1] == "params":  # one keyword argument
        if not parts[2].isidentifier():
            raise ConfigError(key, f"{parts[2]!r} is not a valid Python identifier (a keyword argument name)")
        return
    if len(parts) != 2 or field_name not in names:
        raise ConfigError(key, _suggest(field_name, names, prefix=f"{section}."))


def apply_overrides(config: ExperimentConfig, overrides: dict) -> ExperimentConfig:
    """A copy of ``config`` with dotted keys set (``{"simulation.duration": 20.0}``), validated like
    an experiment file.

    The keys are set in the resolved configuration, whose one-value gains already have one entry
    per task coordinate: to change the task's size m (``robot.task``, the path's dimension) and
    keep a gain given once, set the keys in the file's values instead
    (``load_config(path, overrides)``).
    """
    data = config.to_dict()
    for key, value in overrides.items():
        set_dotted(data, key, value)
    return from_dict(data)


def set_dotted(data: dict, key: str, value) -> None:
    """Set a dotted key (``section.field``, ``section.field[i]``, ``controller.params.NAME`` or a
    top-level ``name``) in an experiment's nested tables, checked against the schema first.
    """
    check_dotted_key(key)
    parts = key.split(".")
    indexed = INDEXED.match(key)
    if indexed:
        section, field_name, index = indexed.groups()
        _set_entry(data.setdefault(section, {}), section, field_name, int(index), value)
    elif len(parts) == 1:
        data[parts[0]] = value
    elif len(parts) == 3:  # controller.params.NAME
        table = data.setdefault(parts[0], {})
        table[parts[1]] = {**(table.get(parts[1]) or {}), parts[2]: value}
    else:
        data.setdefault(parts[0], {})[parts[1]] = value


def _set_entry(table: dict, section: str, field_name: str, index: int, value) -> None:
    """``section.field[index] = value`` in a section's table: a list key given in full, or one
    whose missing entries are known (:data:`FILLED_LISTS`).
    """
    current = table.get(field_name)
    fill = FILLED_LISTS.get((section, field_name))
    if current is None and fill is None:
        raise ConfigError(
            f"{section}.{field_name}[{index}]",
            f"{section}.{field_name} is not set: give the whole list first (in [set]), then vary its entries",
        )
    entries = list(current) if current is not None else []
    if index >= len(entries):
        if fill is None:
            raise ConfigError(
                f"{section}.{field_name}[{index}]", f"{section}.{field_name} has {len(entries)} entries"
            )
        entries += [fill] * (index + 1 - len(entries))
    entries[index] = value
    table[field_name] = entries


def parse_override(
    text: str, option: str = "--set", example: str = "simulation.duration=20"
) -> tuple[str, object]:
    """``key=value`` with a TOML value (``simulation.duration=20``, ``nn.sigma=0.5``,
    ``controller.Kp=[100.0]``); a value that is not TOML is taken as a string. The key is an
    experiment's dotted key for ``--set``; another ``option`` (``--hyper``: a trainer's
    hyper-parameter, ``example``) names itself in its errors and leaves the key to its reader.
    """
    key, sep, raw = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise ConfigError(option, f"{text!r} is not key=value (e.g. {example})")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    except RecursionError as err:
        raise ConfigError(f"{option} {key}", "the value is nested too deeply") from err
    except ValueError as err:
        raise ConfigError(f"{option} {key}", _too_long(err)) from err
    refuse_dates(value, key, f"{option} ")
    if option == "--set":
        check_dotted_key(key)
    return key, value
