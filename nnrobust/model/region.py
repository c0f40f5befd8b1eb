"""The uncertainty box of an identified robot: the plants its log leaves possible, at a stated
confidence (``nnrobust identify`` writes it as ``region.json`` and ``box.toml``;
docs/identification.md, "The box").

identify's confidence region is the ellipsoid (beta - beta_hat)^T C^-1 (beta - beta_hat) <=
chi2_p(1 - alpha) over the p fitted parameters beta (the base inertial combinations, then the
friction terms and rotor inertias fitted). In its principal coordinates z,

    beta = beta_hat + A z,   A = V diag(sqrt(lambda)),   C = V diag(lambda) V^T,

the estimate's error is z ~ N(0, I_p) to the first order of the fit, its coordinates independent;
so the cube |z_i| <= c holds the truth with probability (2 Phi(c) - 1)^p, and c is chosen to make
that 1 - alpha exactly (:func:`box_half_width`). The cube is the box: a sweep's ``[vary]`` over
``plant.region_coordinates[i]``, each uniform in [-c, c].

A point z is a plant. The torque depends on the full parameters phi (every body's ten, the
friction, the armature) only through beta = B phi, so every phi with B phi = beta(z) is the same
plant; :meth:`IdentifiedRegion.parameters` takes the one nearest the physically consistent
estimate phi_0 (nominal.json's), phi_0 + D (B D)^+ (beta(z) - B phi_0) with D the parameters'
typical sizes: beta(z) exactly. Its bodies need not each be physical (a log sees beta, not the
bodies; an arm whose links are point masses has its truth on the physical set's boundary, and
half of any box about it outside), but a plant must be one a simulation can integrate:
:meth:`IdentifiedRegion.plant_problems` names what is not (a mass matrix not positive definite
over sampled poses, friction or armature below zero), and the plant refuses that point (a run that
fails to build fails every property of a certificate: the box's non-plants count against a law).
"""

from __future__ import annotations

import functools
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.stats

from ..core.exceptions import ConfigError
from .identified import identify_file
from .regressor import ParameterLayout, mass_matrix_audit, typical_sizes

REGION_FORMAT = "nnrobust-identified-region/1"
"""The ``format`` of a region's file."""

AUDIT_POSES = 200
"""Random poses over which a point's mass matrix must be positive definite."""


def box_half_width(level: float, p: int) -> float:
    """The half-width c with (2 Phi(c) - 1)^p = ``level``: the cube |z_i| <= c of p independent
    standard normal coordinates holds them with probability ``level`` exactly.
    """
    if not 0 < level < 1 or p < 1:
        raise ValueError(f"a level in (0, 1) and p >= 1, got {level}, {p}")
    each = level ** (1 / p)  # every coordinate's own two-sided level
    return float(scipy.stats.norm.ppf(0.5 + each / 2))


@dataclass(frozen=True)
class IdentifiedRegion:
    """An identified robot's uncertainty box (module docstring), as ``region.json`` holds it.

    Attributes:
        robot: the robot source it was identified on.
        joints: the joints' names, in order.
        layout: the full parameter vector's layout (friction terms, armature).
        names: the p fitted parameters' names.
        level: 1 - alpha, the box's confidence.
        method: how the covariance was computed (the confidence region's method).
        center: beta_hat, the least-squares estimate (p).
        axes: A (p x p): beta = center + A z.
        half_width: c, the box's half-width in every coordinate.
        projection: B (p x the layout's size): beta = B phi.
        physical: phi_0, the physically consistent estimate (the layout's size).

    """

    robot: str
    joints: tuple[str, ...]
    layout: ParameterLayout
    names: tuple[str, ...]
    level: float
    method: str
    center: np.ndarray
    axes: np.ndarray
    half_width: float
    projection: np.ndarray
    physical: np.ndarray

    @property
    def dimension(self) -> int:
        """p, the box's coordinates."""
        return len(self.center)

    def coordinates(self, beta: np.ndarray) -> np.ndarray:
        """The coordinates z of the fitted parameters ``beta``: beta is in the box when max |z_i| <= c."""
        return np.linalg.lstsq(self.axes, np.asarray(beta, dtype=float) - self.center, rcond=None)[0]

    def beta(self, z: np.ndarray) -> np.ndarray:
        """The fitted parameters at the box's point ``z``."""
        return self.center + self.axes @ np.asarray(z, dtype=float)

    def parameters(self, z: np.ndarray, where: str = "plant.region_coordinates") -> np.ndarray:
        """The full parameters of the plant at ``z``: B phi = beta(z), nearest phi_0 (module
        docstring).
        """
        z = np.asarray(z, dtype=float)
        if z.shape != (self.dimension,) or not np.all(np.isfinite(z)):
            raise ConfigError(where, f"needs {self.dimension} finite numbers (the box's coordinates)")
        D = typical_sizes(self.layout)
        gap = self.beta(z) - self.projection @ self.physical
        return self.physical + D * np.linalg.lstsq(self.projection * D, gap, rcond=None)[0]

    def plant_problems(self, phi: np.ndarray, model) -> list[str]:
        """Why ``phi`` is no plant to simulate (empty: it is one): friction or armature below zero,
        or the mass matrix of ``model`` (the robot with phi's bodies and armature) not positive
        definite over :data:`AUDIT_POSES` random poses.
        """
        out = []
        for term in self.layout.friction:
            low = phi[self.layout.friction_slice(term)]
            if term != "offset" and np.any(low < 0):
                out.append(f"{term} friction {np.round(low, 6).tolist()} below zero")
        if self.layout.armature and np.any(phi[self.layout.armature_slice] < 0):
            out.append("armature below zero")
        least, _ = mass_matrix_audit(model, poses=AUDIT_POSES)  # crba counts model.armature
        if not least > 0:
            out.append(f"its mass matrix is not positive definite (least eigenvalue {least:.3g})")
        return out

    def friction(self, phi: np.ndarray, term: str) -> np.ndarray:
        """Each joint's ``term`` coefficient in ``phi`` (zero where the layout has no such term)."""
        if term not in self.layout.friction:
            return np.zeros(self.layout.n)
        return np.asarray(phi[self.layout.friction_slice(term)], dtype=float)

    def armature(self, phi: np.ndarray) -> np.ndarray | None:
        """Each joint's rotor inertia in ``phi``, or None where the layout has none."""
        return np.asarray(phi[self.layout.armature_slice]) if self.layout.armature else None

    def to_dict(self, record: dict | None = None) -> dict:
        """The file's content, with ``record`` (how it was computed)."""
        return {
            "format": REGION_FORMAT,
            "robot": self.robot,
            "joints": list(self.joints),
            "layout": {"friction": list(self.layout.friction), "armature": self.layout.armature},
            "names": list(self.names),
            "level": self.level,
            "method": self.method,
            "box": "beta = center + axes z, every |z_i| <= half_width; P(truth inside) = "
            "(2 Phi(half_width) - 1)^p = level",
            "center": self.center.tolist(),
            "axes": self.axes.tolist(),
            "half_width": self.half_width,
            "projection": self.projection.tolist(),
            "physical": self.physical.tolist(),
            "record": record or {},
        }


def region_from_fit(
    robot: str,
    layout: ParameterLayout,
    names: list[str],
    level: float,
    method: str,
    center: np.ndarray,
    covariance: np.ndarray,
    projection: np.ndarray,
    physical: np.ndarray,
) -> IdentifiedRegion:
    """The box of a fit: its estimate, covariance, map B and physical estimate (module docstring)."""
    values, vectors = np.linalg.eigh((covariance + covariance.T) / 2)
    order = np.argsort(values)[::-1]  # the widest axis first
    axes = vectors[:, order] * np.sqrt(np.maximum(values[order], 0.0))
    return IdentifiedRegion(
        robot,
        tuple(layout.joints),
        layout,
        tuple(names),
        float(level),
        method,
        np.asarray(center, dtype=float),
        axes,
        box_half_width(level, len(center)),
        np.asarray(projection, dtype=float),
        np.asarray(physical, dtype=float),
    )


def read_region(path: str | Path, where: str = "plant.region") -> IdentifiedRegion:
    """The region in ``path``; a file that is not one is one error naming the field."""
    path = Path(path)
    return _read_region(str(path.absolute()), where, *_stamp(path, where))


def region_sha256(path: str | Path) -> str:
    """The SHA-256 of a region's file (what a box's claim names)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _stamp(path: Path, where: str) -> tuple[int, int]:
    try:
        status = path.stat()
    except OSError as err:
        raise ConfigError(f"{where} {path}", f"cannot be read ({type(err).__name__}: {err})") from err
    return status.st_mtime_ns, status.st_size


@functools.lru_cache(maxsize=8)
def _read_region(path: str, where: str, mtime: int, size: int) -> IdentifiedRegion:
    """A region read once per content stamp (a sweep's runs share the file)."""
    where = f"{where} {path}"
    data = identify_file(Path(path), where, REGION_FORMAT, "an identified region")
    try:
        joints = tuple(str(j) for j in data["joints"])
        friction = tuple(str(t) for t in data["layout"]["friction"])
        layout = ParameterLayout(joints, friction, bool(data["layout"]["armature"]))
        center = np.asarray(data["center"], dtype=float)
        axes = np.asarray(data["axes"], dtype=float)
        projection = np.asarray(data["projection"], dtype=float)
        physical = np.asarray(data["physical"], dtype=float)
        level, half_width = float(data["level"]), float(data["half_width"])
        names = tuple(str(n) for n in data["names"])
    except (KeyError, TypeError, ValueError) as err:
        raise ConfigError(
            where, f"is missing or has a malformed field ({type(err).__name__}: {err})"
        ) from err
    p = len(center)
    shapes = {
        "axes": (axes.shape, (p, p)),
        "projection": (projection.shape, (p, layout.size)),
        "physical": (physical.shape, (layout.size,)),
        "names": ((len(names),), (p,)),
    }
    for field_name, (shape, expected) in shapes.items():
        if shape != expected:
            raise ConfigError(where, f"{field_name} has shape {shape}; expected {expected}")
    if not all(np.all(np.isfinite(a)) for a in (center, axes, projection, physical)):
        raise ConfigError(where, "every value must be a finite number")
    if not 0 < level < 1 or not math.isclose(half_width, box_half_width(level, p), rel_tol=1e-9):
        raise ConfigError(
            where, f"half_width {half_width} is not the box's of level {level} over {p} coordinates"
        )
    return IdentifiedRegion(
        str(data.get("robot", "")), joints, layout, names, level, str(data.get("method", "")), center, axes,
        half_width, projection, physical,
    )  # fmt: skip
