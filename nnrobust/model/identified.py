"""An identified model: the robot's URDF kinematics with the bodies, friction and armature a log
gave (``nnrobust identify``; docs/identification.md). Written as ``nominal.json`` and read back
as a controller's nominal model (``[nominal] kind = "identified"``, ``file = ...``).

The file (JSON): ``format`` (:data:`IDENTIFIED_FORMAT`), ``robot`` (the source it was identified
on), ``joints`` (names, in order), ``bodies`` (per joint: ``mass`` [kg], ``lever`` [m], the centre of
mass in the joint frame, ``inertia`` [kg m^2], 3 x 3 about the centre of mass), ``friction``
(``viscous`` [N m s/rad], ``coulomb`` [N m], ``offset`` [N m], one per joint, zero where not
identified), ``armature`` [kg m^2] per joint, and ``record`` (how it was computed).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..core.exceptions import ConfigError
from .perturbation import rotational_inertia_problem

IDENTIFIED_FORMAT = "nnrobust-identified-model/1"
"""The ``format`` of an identified model's file."""


@dataclass(frozen=True)
class IdentifiedModel:
    """An identified model as its file holds it.

    Attributes:
        robot: the robot source it was identified on.
        joints: the joints' names, in order.
        inertias: each joint's body.
        viscous, coulomb, offset, armature: per joint.

    """

    robot: str
    joints: tuple[str, ...]
    inertias: tuple[pin.Inertia, ...]
    viscous: np.ndarray
    coulomb: np.ndarray
    offset: np.ndarray
    armature: np.ndarray

    def pinocchio(self, model: pin.Model, source: str = "the robot") -> pin.Model:
        """A copy of ``model`` (the robot's kinematics) with these bodies and armature; its joints
        must be the file's, in order.
        """
        names = tuple(model.names[1:])
        if names != self.joints:
            raise ConfigError(
                "nominal.file",
                f"the identified model's joints {list(self.joints)} are not {source}'s {list(names)}: "
                "identify it on the same robot (robot.source, locked_joints, chain)",
            )
        out = pin.Model(model)
        for j, body in enumerate(self.inertias, start=1):
            out.inertias[j] = body.copy()
        out.armature = np.asarray(self.armature, dtype=float).copy()
        return out

    def to_dict(self, record: dict | None = None) -> dict:
        """The file's content (module docstring), with ``record`` (how it was computed)."""
        return {
            "format": IDENTIFIED_FORMAT,
            "robot": self.robot,
            "joints": list(self.joints),
            "bodies": [
                {
                    "joint": name,
                    "mass": float(body.mass),
                    "lever": np.asarray(body.lever).tolist(),
                    "inertia": np.asarray(body.inertia).tolist(),
                }
                for name, body in zip(self.joints, self.inertias)
            ],
            "friction": {
                "viscous": self.viscous.tolist(),
                "coulomb": self.coulomb.tolist(),
                "offset": self.offset.tolist(),
            },
            "armature": self.armature.tolist(),
            "record": record or {},
        }


def identify_file(path: Path, where: str, format: str, what: str) -> dict:
    """The JSON object of a file ``nnrobust identify`` wrote, of ``format``: one error naming
    ``where`` when it cannot be read, is not JSON or is another file.
    """
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError(where, f"cannot be read ({type(err).__name__}: {err})") from err
    except ValueError as err:
        raise ConfigError(where, f"is not JSON ({err})") from err
    if not isinstance(data, dict) or data.get("format") != format:
        raise ConfigError(
            where, f"is not {what} (its format must be {format!r}; nnrobust identify writes one)"
        )
    return data


def read_identified(path: str | Path) -> IdentifiedModel:
    """The identified model in ``path``; a file that is not one is one error naming the field."""
    path = Path(path)
    where = f"nominal.file {path}"
    data = identify_file(path, where, IDENTIFIED_FORMAT, "an identified model")
    joints = data.get("joints")
    if not isinstance(joints, list) or not joints or not all(isinstance(j, str) for j in joints):
        raise ConfigError(where, "needs 'joints', a list of joint names")
    n = len(joints)
    bodies = data.get("bodies")
    if not isinstance(bodies, list) or len(bodies) != n:
        raise ConfigError(where, f"needs 'bodies', one per joint ({n})")
    inertias = []
    for name, body in zip(joints, bodies):
        try:
            mass = float(body["mass"])
            lever = np.asarray(body["lever"], dtype=float).reshape(3)
            inertia = np.asarray(body["inertia"], dtype=float).reshape(3, 3)
        except (KeyError, TypeError, ValueError) as err:
            raise ConfigError(
                where, f"body of {name}: needs mass, lever (3) and inertia (3 x 3) numbers ({err})"
            ) from err
        if not (np.isfinite(mass) and np.all(np.isfinite(lever)) and np.all(np.isfinite(inertia))):
            raise ConfigError(where, f"body of {name}: every value must be a finite number")
        why = rotational_inertia_problem(inertia, 1e-9, point_mass=True) if mass > 0 else f"mass {mass} kg"
        if why or not np.allclose(inertia, inertia.T, atol=1e-12):
            raise ConfigError(
                where, f"body of {name} is not physical: {why or 'an inertia that is not symmetric'}"
            )
        inertias.append(pin.Inertia(mass, lever, inertia))
    friction = data.get("friction", {})
    vectors = {}
    for key, values in (
        *(("friction." + k, friction.get(k)) for k in ("viscous", "coulomb", "offset")),
        ("armature", data.get("armature")),
    ):
        array = np.zeros(n) if values is None else np.asarray(values, dtype=float)
        if (
            array.shape != (n,)
            or not np.all(np.isfinite(array))
            or (key != "friction.offset" and np.any(array < 0))
        ):
            raise ConfigError(
                where,
                f"{key}: needs {n} finite numbers" + ("" if key == "friction.offset" else ", none negative"),
            )
        vectors[key] = array
    return IdentifiedModel(
        str(data.get("robot", "")),
        tuple(joints),
        tuple(inertias),
        vectors["friction.viscous"],
        vectors["friction.coulomb"],
        vectors["friction.offset"],
        vectors["armature"],
    )
