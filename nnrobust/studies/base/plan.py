"""Sweep files: one experiment over many samples of the uncertainty set (docs/robustness.md).

A sweep file names a base experiment (a preset or an experiment file), the controllers every
sample runs with (common random numbers), fixed overrides (``[set]``) and varied keys
(``[vary]``): a list is a grid; a table draws ``samples`` values per grid point from a
distribution. Everything is checked against the experiment schema before anything runs.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...config import (
    ExperimentConfig,
    check_dotted_key,
    dump_toml,
    parse_toml,
    read_text_file,
    shipped_laws,
)
from ...config.toml_io import DATA_FILE_KEYS, law_file
from ...controllers.registry import registered_law
from ...core.exceptions import ConfigError, NNRobustError
from ...core.numeric_limits import finite_number

DISTRIBUTIONS = ("uniform", "normal", "loguniform", "choice")
"""The tables a [vary] key may hold: {uniform = [a, b]}, {normal = [mu, sd]},
{loguniform = [a, b]} (0 < a < b) or {choice = [...]}."""

KEYS = ("name", "base", "controllers", "samples", "seed", "set", "vary", "description", "box")
MAX_ROWS = 1_000_000
"""Samples x controllers above which a sweep is refused."""


@dataclass
class SweepSpec:
    """A parsed, validated sweep file.

    Attributes:
        name: the sweep's name.
        base: a preset name or an experiment file (relative paths from the sweep file's folder).
        controllers: the names of the controllers every sample runs with: built-in kinds, and
            the names of table entries.
        box: an identified box the file names (``box = "box.toml"``, :func:`with_box`): its file,
            SHA-256 and ``[claim]``; its ``[set]`` and ``[vary]`` are in ``set`` and ``vary``
            (empty: no box file).
        entries: per name of a table in the controllers list, ``{"class": ..., "params": {...}}``
            (a custom law) or ``{"kind": ..., "set": {...}}`` (a built-in law with its own
            settings).
        samples: random draws per grid point.
        seed: seed of the draws (each sample's own seed derives from it and the sample id).
        set: fixed overrides, dotted keys.
        vary: varied keys: a list (grid) or {distribution = parameters}.
        description: free text.

    """

    name: str
    base: str
    controllers: list[str]
    samples: int = 1
    seed: int = 0
    set: dict = field(default_factory=dict)
    vary: dict = field(default_factory=dict)
    description: str = ""
    entries: dict = field(default_factory=dict)
    box: dict = field(default_factory=dict)

    @property
    def grid_keys(self) -> list[str]:
        """Varied keys given as lists (the grid)."""
        return [k for k, v in self.vary.items() if isinstance(v, list)]

    @property
    def random_keys(self) -> list[str]:
        """Varied keys drawn from a distribution."""
        return [k for k, v in self.vary.items() if isinstance(v, dict)]

    def grid_point(self, index: int) -> tuple:
        """Point ``index`` of the grid the list-valued keys form, in itertools.product order (the
        last key varies fastest); the grid itself is never built, however large.
        """
        point = []
        for key in reversed(self.grid_keys):
            index, position = divmod(index, len(self.vary[key]))
            point.append(self.vary[key][position])
        return tuple(reversed(point))

    @property
    def size(self) -> int:
        """Number of samples: draws x grid points."""
        return self.samples * math.prod(len(self.vary[k]) for k in self.grid_keys)

    def to_toml(self) -> str:
        """The resolved sweep file (what DIR/sweep.toml holds)."""
        entries = [{"name": c, **self.entries[c]} if c in self.entries else c for c in self.controllers]
        head = {
            "name": self.name,
            "description": self.description,
            "base": self.base,
            "controllers": entries,
            "samples": self.samples,
            "seed": self.seed,
        }
        lines = [dump_toml(head).rstrip("\n")]
        if self.box:  # merged below; named for the reader
            lines.append(f"# box: {self.box['file']} (sha256 {self.box['sha256']}): its [set], [vary] below")
        for table in ("set", "vary"):
            lines += ["", f"[{table}]"]
            lines += [f'"{k}" = {_inline(v)}' for k, v in getattr(self, table).items()]
        return "\n".join(lines) + "\n"

    def digest(self) -> str:
        """A hash of the resolved sweep (a changed sweep into an existing folder is refused)."""
        return hashlib.sha256(self.to_toml().encode()).hexdigest()[:16]


def _inline(value) -> str:
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_inline(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ", ".join(_inline(v) for v in value) + "]"
    return dump_toml({"v": value}).split(" = ", 1)[1].strip()


@dataclass(frozen=True)
class Sample:
    """One point of the uncertainty set: its id, the varied values (dotted keys) and its seed."""

    id: int
    values: dict
    seed: int


def _number(path: str, value) -> float:
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 2**63:
        digits = len(str(abs(value)))
        raise ConfigError(
            path, f"expected a finite number of sensible size, got an integer of {digits} digits"
        )
    if not (isinstance(value, (int, float)) and finite_number(value)):
        raise ConfigError(path, f"expected a finite number, got {value!r}")
    return float(value)


def _check_distribution(key: str, table: dict) -> None:
    if len(table) != 1:
        raise ConfigError(
            f"vary.{key}", f"needs exactly one of {', '.join(DISTRIBUTIONS)}, got {sorted(table)}"
        )
    ((kind, params),) = table.items()
    path = f"vary.{key}.{kind}"
    if kind not in DISTRIBUTIONS:
        raise ConfigError(path, f"unknown distribution; valid: {', '.join(DISTRIBUTIONS)}")
    if not isinstance(params, list) or not params:
        raise ConfigError(path, f"expected a list of parameters, got {params!r}")
    if kind == "choice":
        return
    if len(params) != 2:
        raise ConfigError(path, f"needs two numbers, got {params!r}")
    a, b = (_number(path, p) for p in params)
    if kind in ("uniform", "loguniform") and not a < b:
        raise ConfigError(path, f"needs a < b, got [{a:g}, {b:g}]")
    if kind == "loguniform" and a <= 0:
        raise ConfigError(path, f"needs 0 < a, got {a:g}")
    if kind == "normal" and b < 0:
        raise ConfigError(path, f"needs a standard deviation >= 0, got {b:g}")
    if kind == "uniform" and not math.isfinite(b - a):
        raise ConfigError(path, f"[{a:.6g}, {b:.6g}] is wider than a double holds (b - a overflows)")
    if kind == "normal" and not math.isfinite(abs(a) + 40.0 * b):
        raise ConfigError(
            path, f"[{a:.6g}, {b:.6g}]: draws 40 standard deviations out would overflow a double"
        )


ENTRY_KEYS = ("name", "class", "params", "kind", "set")
"""The keys of a table in a sweep's controllers list."""

ENTRY_FORMS = (
    '{name = "...", class = "file.py:Class", params = {...}} (a custom law) or '
    '{name = "...", kind = "nn", set = {"nn.F" = 0.5, ...}} (a built-in law with settings of its own; '
    "a registered law such as slotine-li takes params = {...} too)"
)

SETTING_ROOTS = ("controller", "nn")
"""The sections a named entry's ``set`` may change: the controller's own settings."""


def _entry(entry: dict, key: str) -> dict:
    """A controllers table checked: ``{class, params}`` of a custom law, or ``{kind, set}``."""
    shape = (
        not [k for k in entry if k not in ENTRY_KEYS]
        and isinstance(entry.get("name"), str)
        and (
            (isinstance(entry.get("class"), str) and "kind" not in entry and "set" not in entry)
            or (
                isinstance(entry.get("kind"), str)
                and "class" not in entry
                and ("params" not in entry or registered_law(entry["kind"]) is not None)
            )
        )
    )
    if not shape:
        raise ConfigError(key, f"a table entry is {ENTRY_FORMS}, got {entry!r}")
    if not NAME.fullmatch(entry["name"]) or entry["name"] in shipped_laws():
        raise ConfigError(
            f"{key}.name",
            f"{entry['name']!r} must be 1-40 letters, digits, '_' or '-' and not a built-in kind",
        )
    if "class" in entry:
        return {"class": entry["class"], "params": dict(entry.get("params") or {})}
    if entry["kind"] not in shipped_laws():
        raise ConfigError(f"{key}.kind", f"{entry['kind']!r} is not one of {', '.join(shipped_laws())}")
    settings = entry.get("set") or {}
    if not isinstance(settings, dict):
        raise ConfigError(f"{key}.set", f"expected a table of dotted keys, got {settings!r}")
    for dotted in settings:
        root = str(dotted).split(".")[0]
        if root not in SETTING_ROOTS or str(dotted).split(".")[:2] in (
            ["controller", "kind"],
            ["controller", "class"],
            ["controller", "params"],
        ):
            raise ConfigError(
                f"{key}.set.{dotted}",
                "an entry's settings are the law's own: controller.* (but kind, class, params) and nn.*",
            )
        try:
            check_dotted_key(dotted)
        except ConfigError as err:
            raise ConfigError(f"{key}.set.{err.key}", str(err).split(": ", 1)[1]) from err
    params = entry.get("params")
    if params is not None and not isinstance(params, dict):
        raise ConfigError(f"{key}.params", f"expected a table of the law's parameters, got {params!r}")
    return {"kind": entry["kind"], "set": dict(settings), **({"params": dict(params)} if params else {})}


def _controllers(entries, where: str) -> tuple[list[str], dict]:
    """(names, table entries by name) of a sweep's controllers list: built-in kinds, and tables
    naming a custom law or a built-in law with settings of its own (:data:`ENTRY_FORMS`).
    """
    key = f"{where}: controllers"
    if not isinstance(entries, list) or not entries:
        raise ConfigError(
            key, f"needs a list of {', '.join(shipped_laws())} or tables {ENTRY_FORMS}, got {entries!r}"
        )
    names, tables = [], {}
    for i, entry in enumerate(entries):
        if isinstance(entry, dict):
            tables[entry.get("name")] = _entry(entry, f"{key}[{i}]")
            names.append(entry["name"])
        elif entry in shipped_laws():
            names.append(entry)
        else:
            raise ConfigError(
                f"{key}[{i}]",
                f"{entry!r} is not one of {', '.join(shipped_laws())} nor a table {ENTRY_FORMS}",
            )
    if len(set(names)) != len(names):
        raise ConfigError(key, f"lists a controller twice: {names}")
    return names, tables


NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]{0,39}")
"""A controllers table's name in a sweep: it names rows, columns and folders."""


BOX_TABLES = ("claim", "set", "vary")
"""The tables of a box file (box.toml, which ``nnrobust identify`` writes)."""


def with_box(data: dict, folder: Path, where: str) -> tuple[dict, dict]:
    """(``data`` with the ``[set]`` and ``[vary]`` of the box file its ``box`` key names merged in,
    the box's record: its file, SHA-256 and ``[claim]``); ``data`` unchanged without a ``box``.
    A key both the file and the box give is refused: the box's plant is what its claim is about.
    A relative path is read from ``folder`` (the sweep or study file's).
    """
    if "box" not in data:
        return data, {}
    from .folder import file_sha256

    given = data["box"]
    if not isinstance(given, str) or not given.strip():
        raise ConfigError(f"{where}: box", f"expected the path of a box file (box.toml), got {given!r}")
    path = Path(given) if Path(given).is_absolute() else (folder / given).resolve()
    if not path.is_file():
        raise ConfigError(f"{where}: box", f"{path} is not a file (nnrobust identify writes DIR/box.toml)")
    box = parse_toml(read_text_file(path, what="box file"), str(path))
    unknown = [k for k in box if k not in BOX_TABLES]
    if unknown or not all(isinstance(box.get(t, {}), dict) for t in BOX_TABLES):
        raise ConfigError(
            f"{path}: {unknown[0] if unknown else 'tables'}",
            f"a box file holds the tables {', '.join(BOX_TABLES)} (nnrobust identify writes one)",
        )
    out = {k: v for k, v in data.items() if k != "box"}
    for table in ("set", "vary"):
        own = out.get(table, {})
        if not isinstance(own, dict):
            continue  # parse_sweep says so
        both = sorted(set(own) & (set(box.get("set", {})) | set(box.get("vary", {}))))
        if both:
            raise ConfigError(
                f"{where}: {table}.{both[0]}",
                f"is also given by the box {path}: the box's plant is what its claim is about; leave the "
                "key to the box, or drop the box",
            )
        out[table] = {**box.get(table, {}), **own}
    claim = dict(box.get("claim", {}))
    keys = [*box.get("set", {}), *box.get("vary", {})]
    return out, {"file": str(path), "sha256": file_sha256(path), "claim": claim, "keys": keys}


FILE_KEYS = tuple(f"{section}.{key}" for section, key in DATA_FILE_KEYS)
"""[set] keys that name a data file: a relative path is read from the sweep or study file's folder,
as in an experiment file (:data:`nnrobust.config.toml_io.DATA_FILE_KEYS`)."""


def _files_from(data: dict, folder: Path | None) -> dict:
    """``data`` with the relative paths of its [set]'s :data:`FILE_KEYS` made absolute from ``folder``."""
    given = data.get("set")
    if folder is None or not isinstance(given, dict):
        return data
    fixed = {
        k: str((folder / v).resolve())
        if k in FILE_KEYS and isinstance(v, str) and v and not Path(v).is_absolute()
        else v
        for k, v in given.items()
    }
    return {**data, "set": fixed}


def parse_sweep(data: dict, where: str = "sweep", folder: Path | None = None) -> SweepSpec:
    """Validate a sweep table (as read from TOML); every error names its key. A ``box`` key is
    merged in (:func:`with_box`; relative to ``folder``, default the working folder).
    """
    data, box = with_box(data, folder or Path.cwd(), where)
    data = _files_from(data, folder)
    unknown = [k for k in data if k not in KEYS]
    if unknown:
        raise ConfigError(f"{where}: {unknown[0]}", f"unknown key; valid keys: {', '.join(KEYS)}")
    for key in ("name", "base", "controllers"):
        if key not in data:
            raise ConfigError(f"{where}: {key}", "missing")
    if not isinstance(data["name"], str) or not isinstance(data["base"], str):
        raise ConfigError(f"{where}: name", "name and base must be strings")
    controllers, entries = _controllers(data["controllers"], where)
    for table in ("set", "vary"):
        chosen = [
            k
            for k in data.get(table, {})
            if isinstance(k, str)
            and k.split(".")[:2]
            in (["controller", "kind"], ["controller", "class"], ["controller", "params"])
        ]
        if chosen:
            raise ConfigError(
                f"{where}: {table}.{chosen[0]}",
                "the controllers list chooses each row's "
                "controller; give a custom law's parameters in its entry: {name = ..., class = "
                "..., params = {...}}",
            )
    for name, entry in entries.items():  # an entry's own settings win over [set] and [vary]: refuse both
        for table in ("set", "vary"):
            table_keys = data.get(table, {}) if isinstance(data.get(table, {}), dict) else {}
            both = [k for k in (entry.get("set") or {}) if k in table_keys]
            if both:
                raise ConfigError(
                    f"{where}: {table}.{both[0]}",
                    f"is also set by the controllers entry {name!r}, whose own value would win for "
                    "its rows; give it in one place",
                )
    for key, low in (("samples", 1), ("seed", 0)):
        value = data.get(key, low)
        if isinstance(value, bool) or not isinstance(value, int) or not low <= value < 2**63:
            raise ConfigError(f"{where}: {key}", f"expected an integer >= {low}, got {value!r}")
    for table in ("set", "vary"):
        if not isinstance(data.get(table, {}), dict):
            raise ConfigError(f"{where}: {table}", "expected a table of dotted keys")
    vary = data.get("vary", {})
    for key, value in vary.items():
        try:
            check_dotted_key(key)
        except ConfigError as err:
            raise ConfigError(f"{where}: vary.{err.key}", str(err).split(": ", 1)[1]) from err
        if key in data.get("set", {}):
            raise ConfigError(f"{where}: vary.{key}", "is also in [set]")
        if isinstance(value, dict):
            _check_distribution(key, value)
        elif not isinstance(value, list) or not value:
            raise ConfigError(
                f"{where}: vary.{key}",
                f"expected a non-empty list (grid) or a distribution table, got {value!r}",
            )
    spec = SweepSpec(
        data["name"],
        data["base"],
        list(controllers),
        data.get("samples", 1),
        data.get("seed", 0),
        dict(data.get("set", {})),
        dict(vary),
        data.get("description", ""),
        entries,
        box,
    )
    if spec.size * len(controllers) > MAX_ROWS:
        raise ConfigError(
            f"{where}: samples",
            f"{spec.size} samples x {len(controllers)} controllers exceed {MAX_ROWS} rows",
        )
    return spec


SWEEP_DIR = Path(__file__).resolve().parents[2] / "sweep_files"
"""The shipped sweep files (``nnrobust sweep paper-robustness``)."""


def shipped_sweeps() -> list[str]:
    """Names of the shipped sweep files."""
    return sorted(p.stem for p in SWEEP_DIR.glob("*.toml"))


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and validate a sweep file, or a shipped sweep file by name; a relative ``base`` file
    resolves from the file's folder.
    """
    path = Path(path)
    if not path.exists() and str(path) in shipped_sweeps():
        path = SWEEP_DIR / f"{path}.toml"
    if not path.exists():
        raise ConfigError(str(path), f"not a file nor a shipped sweep file ({', '.join(shipped_sweeps())})")
    data = parse_toml(read_text_file(path, what="sweep file"), str(path))
    spec = parse_sweep(data, str(path), path.parent)
    base = Path(spec.base)
    if base.suffix == ".toml" and not base.is_absolute():
        spec.base = str((path.parent / base).resolve())

    resolve_entry_files(spec.entries, path.parent)
    return spec


def resolve_entry_files(entries: dict, folder: Path) -> None:
    """A controllers entry's class file and law's data file, given by relative paths, are read from
    ``folder`` (the sweep or study file's).
    """
    from ...plugins.user_code import class_file

    for entry in entries.values():
        data_file = law_file(entry.get("kind"), entry.get("params"))
        if data_file is not None and not Path(data_file).is_absolute():
            entry["params"]["file"] = str((folder / data_file).resolve())
        if "class" not in entry:
            continue
        where, name = class_file(entry["class"]), entry["class"].rpartition(":")[2]
        if where is not None and not where.is_absolute():
            entry["class"] = f"{(folder / where).resolve()}:{name}"


def base_path(spec: SweepSpec) -> Path:
    """The file of the sweep's base: an experiment file, or a preset's file."""
    from ...config.presets import preset_names, preset_path, presets_hint

    if spec.base.endswith(".toml"):
        return Path(spec.base)
    if spec.base in preset_names():
        return preset_path(spec.base)
    raise ConfigError(
        "base", f"{spec.base!r} is neither an experiment file (.toml) nor a preset; {presets_hint(spec.base)}"
    )


def base_config(spec: SweepSpec) -> ExperimentConfig:
    """The base experiment with the fixed overrides of [set]: the configuration the base file
    edited so gives (``load_config(path, set)``: the keys set in the file's own values, before a
    gain given once is written out m times).
    """
    from ...config import load_config

    path = base_path(spec)
    try:
        return load_config(path, spec.set)
    except ConfigError as err:
        if err.key.startswith(f"{path}: "):  # the base file's own error
            raise
        raise ConfigError(f"set: {err.key}", str(err).split(": ", 1)[1]) from err


def base_values(spec: SweepSpec) -> dict:
    """The base file's own values with [set]'s keys set in them, not yet validated nor resolved:
    what each row's keys are set in (:func:`experiment`), as an edit of the file would set them.
    A plain dict, sent to the workers (which need no file of the client's but the classes and
    URDFs it names).
    """
    from ...config.toml_io import file_values, set_dotted

    data = file_values(base_path(spec))
    for key, value in spec.set.items():
        set_dotted(data, key, value)
    return data


def study_inputs(spec: SweepSpec, options: dict[str, str] | None = None):
    """What a study of this sweep computes its rows from (:class:`nnrobust.studies.base.folder.Inputs`):
    the sweep's values (a preset base, the controllers with their entries, samples, seed, [set]
    and [vary]) and the command's ``options``, with the SHA-256 of every file they read: the base
    experiment and the files it starts from, the robot's URDF, the user classes of the base and
    of the controllers entries, and the files a [vary] value names. Paths are never part of it:
    a class entry is recorded by its class, its file by digest.
    """
    from ...config import user_files
    from ...config.toml_io import file_values
    from ...core.package_version import package_version
    from ...model.loading import urdf_digest
    from ...plugins.user_code import class_file
    from .folder import Inputs, file_sha256

    entries = []
    for name in spec.controllers:
        entry = dict(spec.entries.get(name, {}))
        if "class" in entry:
            entry["class"] = entry["class"].rpartition(":")[2]
        entries.append({"name": name, **entry} if entry else name)
    values = {"base": spec.base} if not spec.base.endswith(".toml") else {}
    values.update(controllers=_inline(entries), samples=str(spec.samples), seed=str(spec.seed))
    values.update({f"[set] {k}": _inline(v) for k, v in spec.set.items()})
    values.update({f"[vary] {k}": _inline(v) for k, v in spec.vary.items()})
    values.update(options or {})
    read: list[Path] = []
    file_values(base_path(spec), read)
    files: dict[str, tuple[str, str]] = {}
    for level, path in enumerate(read):
        role = "the base experiment" if level == 0 else f"the experiment file the base starts from ({level})"
        files[role] = (str(path), file_sha256(path))
    config = base_config(spec)
    source = config.robot.source
    digest = urdf_digest(source)
    if digest:
        files["the robot's URDF"] = (source if not source.lstrip().startswith("<") else "(inline)", digest)
    for part, class_path in user_files(config).items():
        if part in ("identified model", "identified box"):  # data files, no class and no headers
            files[f"the {part}"] = (class_path, file_sha256(class_path))
            continue
        files[f"the {part} class file"] = (class_path, file_sha256(class_path))
        files.update(_included(Path(class_path), f"the {part} class file", f"{part}.class"))
    for name, entry in spec.entries.items():
        where = class_file(entry["class"]) if "class" in entry else None
        if where is not None:
            files[f"the class file of controller {name}"] = (str(where), file_sha256(where))
            files.update(_included(where, f"the class file of controller {name}", f"controllers: {name}"))
        data_file = law_file(entry.get("kind"), entry.get("params"))
        if data_file is not None and Path(data_file).is_file():
            what = "policy file" if entry.get("kind") == "policy" else "file"
            files[f"the {what} of controller {name}"] = (data_file, file_sha256(data_file))
    if spec.box:
        files["the box file"] = (spec.box["file"], spec.box["sha256"])
    for key, value in spec.vary.items():
        choices = value if isinstance(value, list) else value.get("choice", [])
        for text in (v for v in choices if isinstance(v, str)):
            where = class_file(text) if ":" in text else Path(text)
            if where is not None and where.is_file():
                files[f"the file of [vary] {key} = {text}"] = (str(where), file_sha256(where))
    return Inputs(values, files, package_version())


def _included(path: Path, role: str, key: str) -> dict[str, tuple[str, str]]:
    """The headers a law in C++ includes (nnrobust.plugins.native_law.dependencies: compiled now unless
    cached), by role: what the study's rows are computed from, and sent with its file to workers
    that do not see the client's files. A file that does not compile records the compiler's
    message instead, so that a fix in one of its headers is a change of inputs too.
    """
    from ...core.shipped_files import local
    from ...plugins.native_law import dependencies, is_source

    if not is_source(path) or not local(path).is_file():
        return {}
    try:
        headers = dependencies(local(path), key)
    except NNRobustError as err:  # a compile error, no compiler here
        said = hashlib.sha256(str(err).encode()).hexdigest()
        return {f"the compiler's message on {role}": (str(path), said)}
    folder = Path(os.path.abspath(path)).parent
    return {
        f"the header {os.path.relpath(header, folder)} that {role} includes": (header, digest)
        for header, digest in headers
    }


def sample_seed(seed: int, sample_id: int) -> int:
    """The seed of one sample: independent of how samples are chunked or resumed."""
    return int(np.random.default_rng([seed, sample_id]).integers(2**62))


def draw(spec: SweepSpec, sample_id: int) -> Sample:
    """Sample ``sample_id``: grid point ``id // samples``, draw ``id % samples``."""
    point = spec.grid_point(sample_id // spec.samples)
    values = dict(zip(spec.grid_keys, point))
    seed = sample_seed(spec.seed, sample_id)
    rng = np.random.default_rng(seed)
    for key in spec.random_keys:
        ((kind, params),) = spec.vary[key].items()
        if kind == "uniform":
            value = float(rng.uniform(*params))
        elif kind == "normal":
            value = float(rng.normal(*params))
        elif kind == "loguniform":
            value = float(np.exp(rng.uniform(np.log(params[0]), np.log(params[1]))))
        else:
            value = params[int(rng.integers(len(params)))]
        values[key] = value
    return Sample(sample_id, values, seed)


SEEDED_KEYS = ("nominal.seed", "sensing.seed")
"""Keys that take the sample's seed unless the sweep sets or varies them: each sample gets its own
model error draw and sensor noise, the same for every controller (common random numbers)."""


def experiment(
    spec: SweepSpec,
    base: dict | ExperimentConfig,
    sample: Sample,
    controller: str,
    settings: dict | None = None,
) -> ExperimentConfig:
    """The experiment of one (sample, controller) row, validated: the sample's seeds and values,
    the controller's keys and ``settings`` (a tuner's, dotted keys) set in ``base``, the base's own
    values (:func:`base_values`), then validated and resolved once: the configuration the base
    file edited so gives. A ``base`` given as a configuration takes them in its resolved values,
    where a gain given once already has an entry per task coordinate.
    """
    import copy

    from ...config import from_dict
    from ...config.toml_io import set_dotted

    overrides = {
        key: sample.seed % 2**31 for key in SEEDED_KEYS if key not in spec.set and key not in spec.vary
    }
    overrides.update(sample.values)
    overrides.update(controller_overrides(spec, controller))
    overrides.update(settings or {})
    data = copy.deepcopy(base) if isinstance(base, dict) else base.to_dict()
    try:
        for key, value in overrides.items():
            set_dotted(data, key, value)
        return from_dict(data)
    except ConfigError as err:
        values = ", ".join(f"{k} = {v!r}" for k, v in sample.values.items())
        raise ConfigError(
            f"vary: {err.key}",
            f"{str(err).split(': ', 1)[1]} (sample {sample.id}: {values or 'no varied values'})",
        ) from err


def controller_overrides(spec: SweepSpec, controller: str) -> dict:
    """The dotted keys that choose a row's controller: a built-in kind (with an entry's settings),
    or a custom class and params.
    """
    if controller not in spec.entries:
        return {"controller.kind": controller}
    entry = spec.entries[controller]
    if "kind" in entry:
        params = {"controller.params": entry["params"]} if entry.get("params") else {}
        return {"controller.kind": entry["kind"], **params, **entry["set"]}
    return {
        "controller.kind": "custom",
        "controller.class": entry["class"],
        "controller.params": entry["params"] or None,
    }


def rerun_command(spec: SweepSpec, sample: Sample, controller: str) -> str:
    """The one-line command that reruns a sample as a normal run, every argument shell-quoted."""
    import shlex

    values = {
        **spec.set,
        **{key: sample.seed % 2**31 for key in SEEDED_KEYS if key not in spec.set and key not in spec.vary},
        **sample.values,
    }
    entry = spec.entries.get(controller, {"kind": controller, "set": {}})
    values.update(entry.get("set") or {})
    values.update({f"controller.params.{k}": v for k, v in (entry.get("params") or {}).items()})
    chosen = entry.get("class") or entry["kind"]
    words = ["nnrobust", "run", spec.base, "--controller", chosen]
    for key, value in values.items():
        words += ["--set", f"{key}={_inline(value)}"]
    return shlex.join(words)


def first_step(config: ExperimentConfig):
    """The experiment built (:func:`nnrobust.run.experiment.build`) and its controller's first control
    step run at q(0), v(0), its output checked as the loop checks it (a torque per joint, declared
    signals, a state of z's size); returns the Setup. What fails is the builder's or the loop's
    one-line error, as a run would raise it (a user's exception located in their file).
    """
    import numpy as np

    from ...controllers.custom import checked_output, failed
    from ...run.experiment import build

    setup = build(config)
    controller = setup.controller
    if getattr(type(controller), "native", None):  # a law in C++: its first step on the compiled loop
        from ...run.compiled import simulate_compiled

        try:
            simulate_compiled(setup, setup.config.simulation.control_period)
        except NNRobustError:
            raise
        except Exception as err:
            raise failed(controller, err, 0.0) from err
        return setup
    try:
        z = np.asarray(controller.initial_state(), dtype=float)
        out = controller.compute(
            0.0, setup.q0.copy(), setup.v0.copy(), z, setup.config.simulation.control_period
        )
    except NNRobustError:
        raise
    except Exception as err:
        raise failed(controller, err, 0.0) from err
    checked_output(controller, out, setup.robot.nq, z.size, 0.0)
    return setup


REFERENCE = "no-u0"
"""The shipped law a controller that cannot run is compared with: if it runs on the same
experiment, the controller is at fault (:func:`check_controllers`)."""


def check_controllers(spec: SweepSpec, base: dict, values: dict | None = None) -> None:
    """Refuse, before any sample runs, a controller that can never run: each is built on the base
    experiment (with ``values``, falsify's centre of the box) and its first control step run
    (:func:`first_step`). A missing class file, a constructor that raises or a torque of the wrong
    shape is one line naming the controller, with the builder's message. Where the shipped
    :data:`REFERENCE` law fails there too, the experiment is at fault, not the controller, and its
    rows say why (a base that only the samples make valid, say).
    """
    from ..base.plan import Sample, sample_seed

    sample = Sample(-1, dict(values or {}), sample_seed(spec.seed, 0))
    for name in spec.controllers:
        try:
            first_step(experiment(spec, base, sample, name))
        except NNRobustError as err:
            try:
                first_step(experiment(spec, base, sample, REFERENCE))
            except NNRobustError as fault:
                key = fault.key.split(" ")[0] if isinstance(fault, ConfigError) else ""
                if isinstance(fault, ConfigError) and key in spec.set and key not in spec.vary:
                    # no draw changes it: every row would fail
                    raise ConfigError(
                        f"set: {fault.key}", f"fails every run, whatever is drawn: {fault.message}"
                    ) from fault
                continue  # the experiment itself fails where the samples may not: every row will say so
            raise ConfigError(f"controllers: {name}", f"cannot run: {err}") from err
