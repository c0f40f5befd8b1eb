"""Bad inputs: falsification: boxes, tuned entries, damaged folders."""

from __future__ import annotations

from pathlib import Path

from nnrobust.core import exceptions as ex

from .common import (
    Case,
    _file,
)
from .tune import (
    LAWS,
)


def _falsify(**changes):
    def check():
        from nnrobust.studies.falsify import FalsifySpec

        return FalsifySpec(
            **{
                "target": "s.toml",
                "controllers": ["nn"],
                "require": ["rms_error<=0.05"],
                "budget": 100,
                **changes,
            }
        )

    return check


def _box(folder: Path, vary: str):
    def check():
        from nnrobust.studies.falsify import box_of
        from nnrobust.studies.sweep import load_sweep

        return box_of(
            load_sweep(
                _file(
                    folder,
                    "s.toml",
                    f'name = "s"\nbase = "paper-ellipse"\ncontrollers = ["nn"]\n[vary]\n{vary}',
                )
            )
        )

    return check


def _entry_sweep(folder: Path, entry: str, tables: str = ""):
    def check():
        from nnrobust.studies.sweep import load_sweep

        text = f'name = "s"\nbase = "paper-ellipse"\ncontrollers = ["nn", {entry}]\n{tables}'
        return load_sweep(_file(folder, "s.toml", text))

    return check


def _tuned(folder: Path, summary: str, names: list[str], varied=()):
    def check():
        from nnrobust.studies.base.tuned import tuned_settings

        return tuned_settings(_file(folder, "summary.json", summary), names, varied)

    return check


def _damaged_parts(folder: Path, damage: str):
    def check():
        from nnrobust.studies.base.folder import parts_folder, read_parts

        study = folder / f"study-{damage}"
        study.mkdir(exist_ok=True)
        if damage == "file":
            (study / "results").write_text("not a folder")
        else:
            (study / "results").mkdir(exist_ok=True)
            (study / "results" / "part-0123456789ab.parquet").write_text("garbage")
        return read_parts(parts_folder(study, "results"))

    return check


def _cannot_run(folder: Path, command: str, entry: str):
    """A sweep or a search of a controller that can never run (refused before anything runs)."""

    def run():
        from nnrobust.studies.falsify import FalsifySpec, run_falsify
        from nnrobust.studies.sweep import load_sweep, run_sweep

        (folder / "laws.py").write_text(LAWS.read_text())
        path = _file(
            folder,
            "s.toml",
            f'name = "s"\nbase = "paper-ellipse"\ncontrollers = [{{name = "mine", {entry}}}]\n'
            '[set]\n"simulation.duration" = 0.2\n'
            '[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n',
        )
        if command == "sweep":
            return run_sweep(load_sweep(path), folder / "out", workers=1)
        return run_falsify(
            FalsifySpec(str(path), ["mine"], ["rms_error<=0.05"], 4), folder / "out", workers=1
        )

    return run


def _study_cannot_run(folder: Path):
    """A study with a law whose constructor raises: refused before any stage, its name said once
    (it was "controllers: mine: mine: cannot run")."""

    def check():
        from nnrobust.studies.study import load_study
        from nnrobust.studies.study.engine import _check_controllers

        (folder / "laws.py").write_text(LAWS.read_text())
        path = _file(
            folder,
            "study.toml",
            'name = "x"\ncases = ["paper-ellipse"]\nrequire = ["rms_error<=0.05"]\n'
            'controllers = ["pd", {name = "mine", class = "laws.py:NeedsGain", params = {gain = -1.0}, '
            "tune = false}]\n"
            '[set]\n"simulation.duration" = 0.2\n[vary]\n"plant.disturbance_scale" = {uniform = [0.5, 2.0]}\n'
            "[budgets]\ntune = 4\nseeds = 1\ntrain_samples = 1\nvalidation = 2\nepsilon = 0.5\nbeta = 0.2\n"
            "falsify = 4\n",
        )
        return _check_controllers(load_study(path))

    return check


def _resumed(folder: Path, change: str):
    """A sweep folder prepared for its inputs with one part of rows, then resumed after ``change``:
    its base experiment edited, or its part changed after it was written."""

    def check():
        import pyarrow as pa
        import pyarrow.parquet as pq

        from nnrobust.studies.base.folder import prepare, read_parts, write_part
        from nnrobust.studies.base.plan import study_inputs
        from nnrobust.studies.sweep import load_sweep

        base = _file(folder, "base.toml", 'base = "paper-ellipse"\n[simulation]\nduration = 0.3\n')
        sweep = _file(folder, "s.toml", 'name = "s"\nbase = "base.toml"\ncontrollers = ["nn"]\n')
        study = folder / f"resumed-{change}"
        names = ("results", "sweep.toml")
        inputs = study_inputs(load_sweep(sweep))
        prepare(study, "sweep", "", names, False, "sweep", *names, inputs)
        rows = pa.table({"sample": [0], "controller": ["nn"], "rms_error": [0.1]})
        part = write_part(study / "results", rows, inputs.key)
        if change == "base":
            base.write_text(base.read_text().replace("0.3", "0.4"))
            return prepare(study, "sweep", "", names, False, "sweep", *names, study_inputs(load_sweep(sweep)))
        part.unlink()  # its bytes changed in place: the SHA-256 its name records no longer holds
        pq.write_table(
            rows.set_column(2, "rms_error", pa.array([0.0])),
            part.with_name(f"part-{'0' * 12}-{'0' * 32}.parquet"),
        )
        return read_parts(study / "results", key=inputs.key, ids=("sample", "controller"))

    return check


FALSIFY_CASES = [
    Case(
        "resume: a Parquet part damaged after it was written (sweep, tune, falsify)",
        lambda d: _damaged_parts(d, "part"),
        ex.NNRobustError,
        "is not a readable Parquet part (ArrowInvalid); it was changed after it was written",
    ),
    Case(
        "resume: a file where the rows folder was (sweep, tune, falsify)",
        lambda d: _damaged_parts(d, "file"),
        ex.NNRobustError,
        "results is not a folder: a study keeps its rows there",
    ),
    Case(
        "sweep file: a controllers entry of an unknown kind",
        lambda d: _entry_sweep(d, '{name = "fast", kind = "lqr"}'),
        ex.ConfigError,
        "controllers[1].kind: 'lqr' is not one of nn",
    ),
    Case(
        "sweep file: a controllers entry that sets the plant",
        lambda d: _entry_sweep(d, '{name = "fast", kind = "nn", set = {"plant.payload" = 1.0}}'),
        ex.ConfigError,
        "controllers[1].set.plant.payload: an entry's settings are the law's own",
    ),
    Case(
        "sweep file: [set] and a controllers entry set the same key",
        lambda d: _entry_sweep(
            d, '{name = "fast", kind = "nn", set = {"nn.F" = 0.5}}', '[set]\n"nn.F" = 5.0\n'
        ),
        ex.ConfigError,
        "set.nn.F: is also set by the controllers entry 'fast', whose own value would win",
    ),
    Case(
        "sweep file: a TOML date in a law's params",
        lambda d: _entry_sweep(d, '{name = "mine", class = "laws.py:Eq9", params = {when = 1979-05-27}}'),
        ex.ConfigError,
        "s.toml: controllers[1].params.when: is a TOML date (1979-05-27), which no key takes",
    ),
    Case(
        "sweep file: a controllers entry with a class and a kind",
        lambda d: _entry_sweep(d, '{name = "fast", kind = "nn", class = "a.py:B"}'),
        ex.ConfigError,
        "controllers[1]: a table entry is",
    ),
    Case(
        "falsify --tuned: a law the tuning has no best setting for",
        lambda d: _tuned(d, '{"controllers": {"nn": {"best": null}}}', ["nn"]),
        ex.ConfigError,
        "--tuned: ",
    ),
    Case(
        "falsify --tuned: a setting of the plant, not of the law",
        lambda d: _tuned(
            d, '{"controllers": {"pd": {"best": {"params": {"plant.disturbance_scale": 0.0}}}}}', ["pd"]
        ),
        ex.ConfigError,
        "summary.json sets 'plant.disturbance_scale' for pd, which is not a key pd reads itself",
    ),
    Case(
        "falsify --tuned: a key the box varies",
        lambda d: _tuned(
            d,
            '{"controllers": {"pd": {"best": {"params": {"controller.pd_Kp": [900.0]}}}}}',
            ["pd"],
            ["controller.pd_Kp"],
        ),
        ex.ConfigError,
        "summary.json sets 'controller.pd_Kp' for pd, which the box varies",
    ),
    Case(
        "falsify --tuned: a file that is not a tuning's summary",
        lambda d: _tuned(d, "[1, 2]", ["nn"]),
        ex.ConfigError,
        "is not a tuning's summary.json",
    ),
    Case(
        "falsify: a budget of 0",
        lambda d: _falsify(budget=0),
        ex.ConfigError,
        "--budget: must be an integer in [4, 100000], got 0",
    ),
    Case(
        "falsify: a budget of 10^9",
        lambda d: _falsify(budget=10**9),
        ex.ConfigError,
        "--budget: must be an integer in [4, 100000]",
    ),
    Case(
        "falsify: no property",
        lambda d: _falsify(require=[]),
        ex.ConfigError,
        "--require: falsify needs at least one property to falsify",
    ),
    Case(
        "sweep file: a uniform range of [-1e308, 1e308] (numpy overflowed)",
        lambda d: _box(d, '"plant.disturbance_scale" = {uniform = [-1e308, 1e308]}\n'),
        ex.ConfigError,
        "vary.plant.disturbance_scale.uniform: [-1e+308, 1e+308] is wider than a double holds "
        "(b - a overflows)",
    ),
    Case(
        "sweep file: a uniform range ending at a 400-digit integer (math.isfinite overflowed)",
        lambda d: _box(d, f'"plant.disturbance_scale" = {{uniform = [0.5, {"9" * 400}]}}\n'),
        ex.ConfigError,
        "vary.plant.disturbance_scale.uniform: expected a finite number of sensible size, got an "
        "integer of 400 digits",
    ),
    Case(
        "sweep file: samples = a 300-digit integer (echoed as %.6g)",
        lambda d: (
            lambda: __import__("nnrobust.studies.sweep", fromlist=["load_sweep"]).load_sweep(
                _file(
                    d,
                    "s.toml",
                    f'name = "s"\nbase = "paper-ellipse"\ncontrollers = ["nn"]\nsamples = {"9" * 300}\n',
                )
            )
        ),
        ex.ConfigError,
        "s.toml: samples: expected an integer >= 1, got 1e+300",
    ),
    Case(
        "sweep file: a normal of standard deviation 1e307",
        lambda d: _box(d, '"plant.disturbance_scale" = {normal = [1.0, 1e307]}\n'),
        ex.ConfigError,
        "vary.plant.disturbance_scale.normal: [1, 1e+307]: draws 40 standard deviations out would "
        "overflow a double",
    ),
    Case(
        "falsify: an empty box",
        lambda d: _box(d, ""),
        ex.ConfigError,
        "vary: the sweep file varies nothing: falsify needs a box of uniform or loguniform ranges",
    ),
    Case(
        "falsify: a normal distribution (no box)",
        lambda d: _box(d, '"nn.sigma" = {normal = [0.1, 0.02]}\n'),
        ex.ConfigError,
        "vary.nn.sigma: falsify searches uniform and loguniform ranges, not normal",
    ),
    Case(
        "resume (sweep, tune, falsify): an input edited since the rows were computed",
        lambda d: _resumed(d, "base"),
        ex.NNRobustError,
        "resumed-base holds a different sweep: the base experiment, ",
    ),
    Case(
        "resume (sweep, tune, falsify): a part changed after it was written",
        lambda d: _resumed(d, "part"),
        ex.NNRobustError,
        "was changed after it was written, or not written by this study",
    ),
    Case(
        "sweep: a controller whose first torque has the wrong shape",
        lambda d: _cannot_run(d, "sweep", 'class = "laws.py:WrongShape"'),
        ex.ConfigError,
        "controllers: mine: cannot run: WrongShape.compute returned a torque of shape (4,) at t = 0 s",
    ),
    Case(
        "falsify: a controller whose constructor raises",
        lambda d: _cannot_run(d, "falsify", 'class = "laws.py:NeedsGain", params = {gain = -1.0}'),
        ex.ConfigError,
        "controllers: mine: cannot run: controller.params: NeedsGain(context, **params) raised ValueError",
    ),
    Case(
        "study: a controller whose constructor raises (its name once)",
        _study_cannot_run,
        ex.ConfigError,
        "study.toml: case paper-ellipse: controllers: mine: cannot run: controller.params: "
        "NeedsGain(context, **params) raised ValueError",
    ),
]

SMALL_STUDY = (
    'name = "s"\ncases = [{cases}]\ncontrollers = [{controllers}]\nrequire = ["rms_error_after_2s<=0.005"]\n'
    "{top}"
    '[set]\n"simulation.duration" = 2.2\n[vary]\n"plant.friction_scale" = {{uniform = [0.5, 2.0]}}\n'
    "[budgets]\nvalidation = 2\ncertify = 3\nfalsify = 0\n{budgets}"
)
"""The issue's smallest study S: one case, the PD untuned, a friction box, 2 + 3 draws."""
