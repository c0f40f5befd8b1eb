"""``nnrobust identify``: from a robot's log to its identified model (docs/identification.md).

The log is read (:mod:`.logs`), put on a uniform grid and filtered (:mod:`.signals`), split in
time (the first ``fit_share`` fits, the rest is held out), checked for identifiability, fitted by
weighted least squares and then physically (:mod:`.fit`), and audited. The folder it writes:

- ``nominal.json``: the physically consistent model (:mod:`nnrobust.model.identified`), usable as
  ``[nominal] kind = "identified"``, ``file = ".../nominal.json"`` in any experiment.
- ``identification.json``: everything the fit found: the signals' notes, the base parameters with
  the least-squares estimate, its standard errors, its confidence interval and region (its
  covariance, and how it was computed: :mod:`.confidence`) and the physical estimate, each joint's
  residual on the fit and held-out segments (for the URDF, the least-squares and the physical
  model), the physical checks, and the inputs' SHA-256.
- ``parameters.csv``: the base parameters' table.

The folder is written whole, then renamed into place: an interrupted identification leaves no
half folder, and ``--overwrite`` replaces only a folder identify wrote (its marker).
"""

from __future__ import annotations

import csv
import io
import json
import os
import shutil
import tempfile
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ...core.exceptions import LogError, NNRobustError, RunFolderExists
from ...core.folders import check_place, write_new
from ...core.package_version import package_version
from ...model.identified import IdentifiedModel
from ...model.loading import load_robot, locked_joint_names
from ...model.region import region_from_fit
from ...model.regressor import (
    ParameterLayout,
    base_parameters,
    body_problems,
    inertial_vector,
    mass_matrix_audit,
    with_inertial_vector,
)
from ..base.folder import file_sha256
from .confidence import block_length, confidence_region, residual_statistics
from .fit import (
    base_columns,
    base_projector,
    identifiability,
    least_pseudo_inertia_eigenvalues,
    normal_equations,
    physically_consistent,
    unidentifiable_armature,
    weighted_least_squares,
)
from .fit import residuals as fit_residuals
from .logs import JointLog, check_locked, read_log
from .signals import FilterChoice, prepare
from .spool import column_ranges

MARKER = ".nnrobust-identification"
"""The marker of a folder ``identify`` wrote."""

MODELS = ("urdf", "least_squares", "physical")
"""The models whose residuals identification.json holds: the URDF's, least squares, physical."""

OUTPUTS = (
    "nominal.json", "identification.json", "parameters.csv", "report.html", "region.json", "box.toml", MARKER,
)  # fmt: skip
"""Everything an identification folder holds."""


@dataclass(frozen=True)
class IdentifyOptions:
    """The choices of an identification (each a command-line option; docs/identification.md).

    Attributes:
        friction: the friction terms of every joint (:data:`nnrobust.model.regressor.FRICTION_TERMS`).
        armature: whether each joint's rotor inertia is identified.
        filter: the low-pass, and the torque's delay (:class:`.signals.FilterChoice`).
        stick_band: |q'| below which a joint is taken to stick [rad/s] (its rows left out).
        fit_share: the share of the log, from its start, that fits; the rest is held out.
        allow_unexcited: fit even if the log leaves base parameters unexcited (the URDF's values
            then stand for them in the physical model; the least-squares estimate is minimum-norm).
        confidence: 1 - alpha, the level of the parameters' confidence region (:mod:`.confidence`).
        topic: a ROS 2 bag's or MCAP file's JointState topic (None: its only one).

    """

    friction: tuple[str, ...] = ("viscous", "coulomb")
    armature: bool = False
    filter: FilterChoice = field(default_factory=FilterChoice)
    stick_band: float = 0.01
    fit_share: float = 0.7
    allow_unexcited: bool = False
    confidence: float = 0.95
    topic: str | None = None


def identify(
    logs: Sequence[str | Path] | JointLog,
    robot: str,
    out: str | Path | None = None,
    options: IdentifyOptions = IdentifyOptions(),
    locked_joints: list[str] | None = None,
    chain: Sequence[str] | None = None,
    overwrite: bool = False,
    say=lambda text: None,
) -> dict:
    """Identify ``robot`` (a URDF or a robot's name) from ``logs`` (files, or a log already read);
    write the folder ``out`` (if given) and return what ``identification.json`` holds.
    """
    if not 0.5 <= options.confidence < 1:
        raise NNRobustError(f"--confidence must be in [0.5, 1), got {options.confidence}")
    if not 0 < options.fit_share < 1:
        raise NNRobustError(f"--fit-share must be in (0, 1), got {options.fit_share}")
    if out is not None:
        out = Path(out)
        _check_out(out, overwrite)
    started = time.perf_counter()
    arm = load_robot(robot, task="position", locked_joints=locked_joints, chain=chain)
    model = arm.model
    joints = tuple(model.names[1:])
    locked = locked_joint_names(robot, locked_joints, chain)
    log = logs if isinstance(logs, JointLog) else read_log(logs, joints, options.topic, locked)
    say(f"read {log.samples} samples of {len(joints)} joints from {log.source}")
    locked_warnings = check_locked(log)
    _check_limits(log, model)
    states = prepare(log, options.filter)
    layout = ParameterLayout(joints, tuple(options.friction), options.armature)
    base = base_parameters(model, layout.names[: 10 * layout.n])
    columns = base_columns(layout, base)
    columns, held, absorbed = _held_armature(model, base, layout, columns, say)
    names = [*base.names, *(layout.names[c] for c in columns[base.rank :])]
    split = int(options.fit_share * len(states.t))
    _check_segments(log.source, states.t, split)
    fit_rows = normal_equations(model, layout, states, options.stick_band, slice(0, split))
    # every held-out sample is scored, a joint in stick included: a prediction is judged where it is used
    held_rows = normal_equations(model, layout, states, 0.0, slice(split, None), guard=False)
    excitation = identifiability(fit_rows, columns, names)
    say(
        f"{base.rank} base parameters + {layout.size - 10 * layout.n} friction terms; condition number "
        f"{excitation.condition:.4g}"
    )
    if excitation.unexcited and not options.allow_unexcited:
        _refuse_unexcited(log.source, excitation.unexcited)
    least = weighted_least_squares(fit_rows, columns, minimum_norm=bool(excitation.unexcited))
    prior = urdf_parameters(model, layout)
    phi = physically_consistent(fit_rows, layout, least.sigma, prior, held)
    phi_least = np.zeros(layout.size)
    phi_least[columns] = least.beta
    fit_part = (model, layout, states, options.stick_band, slice(0, split))
    sums, whiteness = residual_statistics(*fit_part, phi_least, columns, block_length(states.dt, split))
    region = confidence_region(
        fit_rows, columns, least.beta, least.sigma, sums, whiteness, options.confidence
    )
    low, high = region.intervals()
    identified_model = with_inertial_vector(model, phi)
    armature = phi[layout.armature_slice] if layout.armature else np.zeros(layout.n)
    checks = _physical_checks(log.source, identified_model, phi, layout.n, armature)
    warnings = locked_warnings + _fit_warnings(fit_rows, held_rows, phi, phi_least, least.sigma, joints)
    for line in warnings:
        say(f"warning: {line}")

    # the physical model's value of each fitted column: the base combinations, then the extra terms fitted
    projection = _fitted_projection(layout, base, columns)
    beta_physical = projection @ phi
    box = region_from_fit(
        arm.name, layout, names, region.level, region.method, least.beta, region.covariance, projection, phi
    )
    standard_errors = np.sqrt(np.maximum(np.diag(region.covariance), 0)).tolist()
    friction = {term: phi[layout.friction_slice(term)].tolist() for term in layout.friction}
    files = {str(Path(p).absolute()): file_sha256(p) for p in log.files}
    summary = {
        "format": "nnrobust-identification/1",
        "robot": arm.name,
        "joints": list(joints),
        "log": {"source": log.source, "files": files, **log.notes, **states.notes},
        "options": {
            "friction": list(options.friction),
            "armature": options.armature,
            "stick_band": options.stick_band,
            "fit_share": options.fit_share,
            "allow_unexcited": options.allow_unexcited,
            "confidence": options.confidence,
            **{f"filter_{k}": v for k, v in asdict(options.filter).items()},
        },
        "segments": {
            "fit": [float(states.t[0]), float(states.t[split - 1])],
            "held_out": [float(states.t[split]), float(states.t[-1])],
            "fit_rows": fit_rows.rows.tolist(),
            "held_out_rows": held_rows.rows.tolist(),
        },
        "identifiability": {
            "base_parameters": base.rank,
            "parameters": len(columns),
            "condition_number": excitation.condition,
            "unexcited": excitation.unexcited,
            "armature_held": [joints[j] for j in absorbed],
        },
        "noise_sigma": least.sigma.tolist(),
        "torque_rms": {"fit": fit_rows.torque_rms().tolist(), "held_out": held_rows.torque_rms().tolist()},
        "parameters": [
            {
                "name": name,
                "least_squares": float(b),
                "standard_error": float(s),
                "low": float(lo),
                "high": float(hi),
                "physical": float(p),
            }
            for name, b, s, lo, hi, p in zip(names, least.beta, standard_errors, low, high, beta_physical)
        ],
        "confidence": {
            "level": region.level,
            "method": region.method,
            "region": "ellipsoid (beta - least_squares)^T C^-1 (beta - least_squares) <= radius2",
            "radius2": region.radius2,
            "white": region.white,
            "whiteness_p": region.whiteness_p,
            "long_run_ratio": region.long_run,
            "covariance": region.covariance.tolist(),
            "box_half_width": box.half_width,
            "physical_in_box": bool(np.max(np.abs(box.coordinates(beta_physical))) <= box.half_width),
        },
        "friction": friction,
        "armature": armature.tolist(),
        "residuals": {k: _residuals(fit_rows, held_rows, p) for k, p in zip(MODELS, (prior, phi_least, phi))},
        "checks": checks,
        "warnings": warnings,
        "seconds": time.perf_counter() - started,
        "version": package_version(),
    }
    say(
        "held-out torque residual / torque RMS, per joint: "
        + " ".join(f"{100 * s:.1f}%" for s in summary["residuals"]["physical"]["held_out_share"])
    )
    if out is not None:
        record = {
            "identification": summary["format"],
            "robot": arm.name,
            "log_files": files,
            "version": package_version(),
        }
        identified = _identified(str(robot), joints, identified_model, friction, armature)
        page = _report(model, layout, states, split, phi, summary)
        _write_folder(out, identified.to_dict(record), summary, overwrite, page, box.to_dict(record))
    return summary


def _fitted_projection(layout: ParameterLayout, base, columns: np.ndarray) -> np.ndarray:
    """B: the fitted parameters (the base combinations, then the extra terms fitted) of a full
    parameter vector.
    """
    extra_rows = [base.rank + int(c) - 10 * layout.n for c in columns[base.rank :]]
    return base_projector(layout, base)[[*range(base.rank), *extra_rows]]


def _held_armature(model, base, layout: ParameterLayout, columns: np.ndarray, say):
    """(the fitted columns, the full vector's entries held, their joints): a rotor inertia no log
    can tell from the links' (a first joint's, a second perpendicular to it;
    :func:`.fit.unidentifiable_armature`) is held at the URDF's value, and the links' base
    parameter about that axis holds the sum.
    """
    absorbed = unidentifiable_armature(model, base) if layout.armature else []
    held = [layout.armature_slice.start + j for j in absorbed]
    if absorbed:
        columns = np.array([c for c in columns if c not in held])
        say(
            f"armature of {', '.join(layout.joints[j] for j in absorbed)}: no log separates it from the "
            "links' inertia about the same axis (it moves the torque as that does); held at the URDF's "
            "value, the links' base parameter holds the sum"
        )
    return columns, held, absorbed


def _identified(robot: str, joints, model, friction: dict, armature: np.ndarray) -> IdentifiedModel:
    """The identified model nominal.json holds: the bodies of ``model``, the friction, the armature."""
    zeros = np.zeros(len(joints))
    return IdentifiedModel(
        robot,
        joints,
        tuple(model.inertias[j] for j in range(1, model.njoints)),
        np.asarray(friction.get("viscous", zeros)),
        np.asarray(friction.get("coulomb", zeros)),
        np.asarray(friction.get("offset", zeros)),
        armature,
    )


def _report(model, layout: ParameterLayout, states, split: int, phi: np.ndarray, summary: dict) -> str:
    """report.html: the held-out torque against the physical model's prediction (at most
    :data:`FIGURE_SAMPLES` of its samples, evenly spaced), and the rest.
    """
    from .report import report_html

    held = slice(split, None, max(1, (len(states.t) - split) // FIGURE_SAMPLES))
    residual = fit_residuals(model, layout, states, 0.0, held, phi, guard=False)
    logged = states.whole(held).tau
    fastest = np.max([np.abs(w.dq).max(axis=0) for w in states.windows()], axis=0)  # each joint's
    return report_html(summary, states.t[held], logged, logged - residual, fastest[None, :])


FIGURE_SAMPLES = 20_000
"""The held-out samples report.html's torque figure draws at most (a figure shows no more)."""

LIMIT_MARGIN = 0.1
"""How far past a joint's URDF limits [rad or m] a logged position may go (a stop's give)."""


def _check_limits(log: JointLog, model) -> None:
    """Positions within the URDF's joint limits (and :data:`LIMIT_MARGIN`): a log in degrees, or
    of another robot, is refused before it is fitted.
    """
    low, high = model.lowerPositionLimit, model.upperPositionLimit
    lows, highs = column_ranges(log.q)
    for j in range(model.nv):
        if not (np.isfinite(low[j]) and np.isfinite(high[j])):
            continue
        least, most = float(lows[j]), float(highs[j])
        if least < low[j] - LIMIT_MARGIN or most > high[j] + LIMIT_MARGIN:
            raise LogError(
                f"{log.source}: joint {model.names[j + 1]}'s positions span [{least:.4g}, {most:.4g}], "
                f"outside its URDF limits [{low[j]:.4g}, {high[j]:.4g}]: positions must be in rad (m for a "
                "prismatic joint), of the robot given by --robot"
            )


MIN_SEGMENT_SECONDS = 1.0
"""The fit and the held-out segments are each at least this long [s]."""


def _check_segments(source: str, t: np.ndarray, split: int) -> None:
    """Each segment at least :data:`MIN_SEGMENT_SECONDS` long."""
    for what, (a, b) in (("fit", (0, split - 1)), ("held-out", (split, len(t) - 1))):
        length = float(t[b] - t[a]) if b > a else 0.0
        if length < MIN_SEGMENT_SECONDS:
            raise LogError(
                f"{source}: the {what} segment is {length:.3g} s; each needs {MIN_SEGMENT_SECONDS:g} s at "
                "least (--fit-share, or a longer log)"
            )


def urdf_parameters(model, layout: ParameterLayout) -> np.ndarray:
    """The URDF's own parameters in the layout: its bodies, its <dynamics damping> as viscous and
    friction as Coulomb friction, no offset, no armature (what the physical fit is pulled
    towards where the log does not see, and the residual table's URDF row).
    """
    out = np.zeros(layout.size)
    out[layout.inertial] = inertial_vector(model)
    for term, values in (("viscous", model.damping), ("coulomb", model.friction)):
        if term in layout.friction:
            out[layout.friction_slice(term)] = np.asarray(values, dtype=float)
    return out


def _fit_warnings(fit_rows, held_rows, phi, phi_least, sigma, joints) -> list[str]:
    """What the fit says of the log: a joint the physical model fits far worse than least squares
    does (a torque of the wrong sign or units, a log no physical robot explains), and joints whose
    held-out torque it misses by half or more (a torque the log does not record).
    """
    out = []
    physical, least = fit_rows.rms(phi), fit_rows.rms(phi_least)
    worse = [j for j in range(len(sigma)) if physical[j] > 1.5 * least[j] + sigma[j]]
    if worse:
        shown = ", ".join(f"joint {j + 1} ({physical[j]:.3g} against {least[j]:.3g} N m)" for j in worse)
        out.append(
            f"the physical model fits {shown} far worse than least squares: no physical robot explains "
            "this log (is the torque the joint torque, in N m, of the sign that accelerates q?)"
        )
    blind = [j for j, share in enumerate(held_rows.rms(phi) / held_rows.torque_rms()) if share >= 0.5]
    if blind:
        out.append(
            f"the model misses half or more of the held-out torque of {', '.join(joints[j] for j in blind)}: "
            "a torque the log does not record acts on the arm (a run's plant disturbance, a contact), or "
            "the segments differ"
        )
    return out


def _residuals(fit_rows, held_rows, p: np.ndarray) -> dict:
    """Each joint's residual RMS of the parameters ``p`` on the fit and held-out segments."""
    return {
        "fit_rms": fit_rows.rms(p).tolist(),
        "held_out_rms": held_rows.rms(p).tolist(),
        "held_out_share": (held_rows.rms(p) / held_rows.torque_rms()).tolist(),
    }


def _check_out(out: Path, overwrite: bool) -> None:
    """``--out`` checked before anything is read: a new folder, or one identify wrote."""
    check_place(out)
    if out.exists() and not (out / MARKER).is_file() and (not out.is_dir() or any(out.iterdir())):
        raise NNRobustError(
            f"{out} exists and is not an identification folder (no {MARKER}); choose another --out"
        )
    if out.exists() and (out / MARKER).is_file() and not overwrite:
        raise RunFolderExists(f"{out} holds an identification already; pass --overwrite to replace it")


def _refuse_unexcited(source: str, unexcited: list[str]) -> None:
    named = ", ".join(unexcited[:6]) + (" ..." if len(unexcited) > 6 else "")
    raise LogError(
        f"{source}: the fit segment does not excite {len(unexcited)} of the base parameters: {named}; "
        "log a trajectory that moves every joint both ways at several speeds, or pass "
        "--allow-unexcited to keep the URDF's values for them"
    )


def _physical_checks(source: str, model, phi: np.ndarray, n: int, armature: np.ndarray) -> dict:
    """The identified model's audit: each body's least pseudo-inertia eigenvalue, what is not
    physical, and the least eigenvalue of M(q) over random poses; a model that fails it is an
    error (never a model a run would refuse).
    """
    least_eigenvalue, _ = mass_matrix_audit(model, armature)
    problems = body_problems(model)
    if problems or not least_eigenvalue > 0:
        raise LogError(
            f"{source}: the physically consistent model is not physical after all: "
            f"{'; '.join(problems) or 'M(q) not positive definite'}"
        )
    return {
        "pseudo_inertia_least_eigenvalues": least_pseudo_inertia_eigenvalues(phi, n).tolist(),
        "body_problems": problems,
        "mass_matrix_least_eigenvalue": least_eigenvalue,
        "physical": not problems and least_eigenvalue > 0,
    }


def box_toml(out: Path, box: dict) -> str:
    """box.toml: the sweep table of the identified box whose region file is ``out``/region.json
    (:mod:`nnrobust.model.region`): ``[set]`` the plant keys that make the plant the box's,
    ``[vary]`` each coordinate uniform in [-c, c], ``[claim]`` what the box's confidence means.
    """
    region = (out / "region.json").absolute()
    c, p = box["half_width"], len(box["center"])
    lines = [
        f"# The identified box of {box['robot']}: nnrobust identify wrote it with {region.name}.",
        f"# With confidence {box['level']:g} the robot's {p} fitted parameters are in it:",
        "# beta = center + axes z (region.json), every z_i uniform in [-c, c], and",
        f"# (2 Phi(c) - 1)^p = {box['level']:g} with p = {p}, c = {c:.6g} (to the fit's first order).",
        f"# Use it in a sweep, falsify or study file: box = {json.dumps(str(out.absolute() / 'box.toml'))}",
        "",
        "[claim]",
        f"level = {box['level']!r}",
        f"method = {json.dumps(box['method'])}",
        f"region = {json.dumps(str(region))}",
        "",
        "[set]",
        f'"plant.region" = {json.dumps(str(region))}',
        '"plant.friction" = "urdf"',
        '"plant.friction_scale" = 1.0',
        "",
        "[vary]",
        *(f'"plant.region_coordinates[{i}]" = {{uniform = [{-c!r}, {c!r}]}}' for i in range(p)),
    ]
    return "\n".join(lines) + "\n"


def _write_folder(out: Path, nominal: dict, summary: dict, overwrite: bool, page: str, box: dict) -> None:
    """The folder written whole beside ``out``, then renamed into place (over an earlier
    identification, its files each replaced whole; nothing else in the folder is touched).
    """
    out = out.absolute()
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", dir=out.parent))
    tmp.chmod(0o755)
    try:
        write_new(tmp / "nominal.json", json.dumps(nominal, indent=1) + "\n")
        write_new(tmp / "identification.json", json.dumps(summary, indent=1) + "\n")
        table = io.StringIO()
        writer = csv.writer(table)
        fields = ["name", "least_squares", "standard_error", "low", "high", "physical"]
        writer.writerow(fields)
        for row in summary["parameters"]:
            writer.writerow([row["name"], *(repr(row[f]) for f in fields[1:])])
        write_new(tmp / "parameters.csv", table.getvalue())
        write_new(tmp / "report.html", page)
        write_new(tmp / "region.json", json.dumps(box) + "\n")
        write_new(tmp / "box.toml", box_toml(out, box))
        write_new(
            tmp / MARKER, json.dumps({"format": summary["format"], "version": summary["version"]}) + "\n"
        )
        if out.exists():
            if not overwrite and (out / MARKER).is_file():
                raise RunFolderExists(
                    f"{out} holds an identification already; pass --overwrite to replace it"
                )
            # file by file (each whole), the model last: what else the folder holds stays
            for name in (*(f for f in OUTPUTS if f not in ("nominal.json", MARKER)), MARKER, "nominal.json"):
                os.replace(tmp / name, out / name)
        else:
            os.replace(tmp, out)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
