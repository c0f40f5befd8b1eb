"""The controller's nominal model: the true URDF model with perturbed inertial parameters."""

from __future__ import annotations

import numpy as np
import pinocchio as pin


def rotational_inertia_problem(I: np.ndarray, rel_tol: float = 0.0, point_mass: bool = False) -> str | None:
    """Why a 3 x 3 inertia about the centre of mass is not physical, or None when it is.

    It must be positive definite (semi-definite with ``point_mass``: a point or a thin rod,
    within ``rel_tol`` of the largest moment) and its principal moments must satisfy the
    triangle inequality I1 + I2 >= I3 (within ``rel_tol`` of I3).
    """
    moments = np.linalg.eigvalsh(np.asarray(I, dtype=float))
    shown = np.round(moments, 9).tolist()
    if point_mass:
        positive, what = moments[0] >= -(rel_tol * abs(moments[2]) + 1e-15), "positive semi-definite"
    else:
        positive, what = moments[0] > 0, "positive definite"
    if not positive:
        return f"the inertia is not {what} (principal moments {shown} kg m^2)"
    if moments[0] + moments[1] < moments[2] * (1 - rel_tol):
        return (
            f"principal moments {shown} break the triangle inequality I1 + I2 >= I3 (no rigid body has them)"
        )
    return None


def is_physical(inertia: pin.Inertia) -> bool:
    """Mass > 0 and a physical rotational inertia (:func:`rotational_inertia_problem`)."""
    return bool(inertia.mass > 0) and rotational_inertia_problem(inertia.inertia) is None


def bodies_with_mass(model: pin.Model) -> list[int]:
    """The joints whose bodies have mass, in order: the bodies a model error perturbs
    (:func:`perturb_inertias`, ``nominal.factors``).
    """
    return [j for j in range(1, model.njoints) if model.inertias[j].mass > 0]


def perturb_inertias(
    model: pin.Model,
    mass_scale: float = 1.0,
    inertia_scale: float = 1.0,
    relative_error: float = 0.0,
    com_error: float = 0.0,
    seed: int = 0,
) -> pin.Model:
    """A copy of ``model`` whose bodies have wrong masses, centres of mass and inertias.

    For each body with mass: m' = m * mass_scale * (1 + u_m), I_c' = I_c * inertia_scale *
    (1 + u_I) with u_m, u_I uniform in [-relative_error, relative_error], and the centre of mass
    moved by a random vector of length up to ``com_error`` [m]. The rotational inertia is scaled
    about the (moved) centre of mass, so every perturbed body stays physically valid: positive
    mass, positive definite inertia, triangle inequalities. Kinematics and gravity are unchanged.
    The same seed gives the same model.

    Raises:
        ValueError: scales not positive, relative_error outside [0, 1), com_error negative.

    """
    if not (mass_scale > 0 and inertia_scale > 0):
        raise ValueError(f"mass_scale {mass_scale} and inertia_scale {inertia_scale} must be positive")
    if not 0 <= relative_error < 1:
        raise ValueError(f"relative_error {relative_error} must be in [0, 1) so that masses stay positive")
    if not com_error >= 0:
        raise ValueError(f"com_error {com_error} must be >= 0 [m]")
    rng = np.random.default_rng(seed)
    out = pin.Model(model)
    for j in range(1, model.njoints):
        body = model.inertias[j]
        u_m, u_I = rng.uniform(-relative_error, relative_error, 2)
        direction = rng.normal(size=3)
        shift = com_error * rng.uniform() * direction / np.linalg.norm(direction)
        if body.mass <= 0:
            continue
        out.inertias[j] = pin.Inertia(
            body.mass * mass_scale * (1 + u_m),
            np.asarray(body.lever) + shift,
            np.asarray(body.inertia) * inertia_scale * (1 + u_I),
        )
    return out
