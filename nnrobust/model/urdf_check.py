"""Check a URDF before Pinocchio sees it.

Pinocchio returns an empty model for a kinematic cycle and the XML parsers behind URDF readers
repair broken files silently, so nnrobust reads the XML itself first, with hard limits, and
refuses with one clear message per kind of problem (exceptions in :mod:`nnrobust.core.exceptions`).
"""

from __future__ import annotations

import math
import os
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from xml.parsers import expat

import numpy as np

from ..core.exceptions import (
    InvalidInertia,
    KinematicCycle,
    UrdfRefused,
    UrdfStructureError,
    UrdfSyntaxError,
)
from ..core.shipped_files import local

MAX_URDF_BYTES = 20_000_000
"""Largest URDF read [bytes]; real arms are well under 1 MB."""

MAX_ELEMENTS = 200_000
"""Most XML elements in a URDF."""


class MissingMeshWarning(UserWarning):
    """A visual mesh file does not exist: the robot simulates, the viewer leaves the part out."""


class MeshOutsideFoldersWarning(UserWarning):
    """A visual mesh lies outside the folders meshes are read from: the viewer leaves it out."""


class UndeclaredPrefixWarning(UserWarning):
    """A URDF uses XML namespace prefixes it never declares (``drake:``, ``gazebo:``): their
    elements and attributes are read as foreign extensions, which a URDF reader ignores.
    """


UNDECLARED_NAMESPACE = "urn:nnrobust:undeclared:"
"""Namespace given to an undeclared prefix P (``urn:nnrobust:undeclared:P``)."""


def read_urdf_file(path: str | Path) -> str:
    """The text of a URDF file, refused when it is too large or not UTF-8; read from its copy when
    the running task brought it with it (:func:`nnrobust.core.shipped_files.local`).
    """
    path = Path(path)
    source = local(path)
    size = source.stat().st_size
    if size > MAX_URDF_BYTES:
        raise UrdfRefused(
            str(path), f"{size / 1e6:.1f} MB is larger than the {MAX_URDF_BYTES / 1e6:g} MB a URDF may have"
        )
    try:
        return source.read_bytes().decode("utf-8")
    except UnicodeDecodeError as err:
        raise UrdfSyntaxError(str(path), f"not UTF-8 text (byte {err.start})") from err


def _malformed(source: str, line: int, column: int, reason: str) -> UrdfSyntaxError:
    """The one error of XML that is not well-formed (``column`` counted from 0, as expat does)."""
    return UrdfSyntaxError(source, f"malformed XML at line {line}, column {column + 1}: {reason}")


def _undeclared_prefixes(data: bytes, source: str) -> tuple[list[str], int]:
    """The namespace prefixes that element and attribute names use where no ``xmlns:`` declares
    them, in order of first use, and the byte offset just after the root element's name. Read by
    expat without namespace processing (an ExpatError when the XML is malformed otherwise too).
    """
    parser = expat.ParserCreate("utf-8")
    scopes: list[frozenset[str]] = [frozenset({"xml"})]
    found: dict[str, None] = {}
    root_name_end, elements = [-1], [0]

    def start(name: str, attributes: dict[str, str]) -> None:
        if len(scopes) == 1:
            root_name_end[0] = parser.CurrentByteIndex + 1 + len(name.encode("utf-8"))
        elements[0] += 1
        if elements[0] > MAX_ELEMENTS:
            raise UrdfRefused(source, f"more than {MAX_ELEMENTS} XML elements")
        scope = scopes[-1] | {key[len("xmlns:") :] for key in attributes if key.startswith("xmlns:")}
        scopes.append(scope)
        for qualified in (name, *attributes):
            prefix, colon, _ = qualified.partition(":")
            if colon and prefix != "xmlns" and prefix not in scope:
                found.setdefault(prefix)

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda name: scopes.pop()
    parser.Parse(data, True)
    return list(found), root_name_end[0]


def parse_urdf_xml(text: str, source: str) -> tuple[ET.Element, str, list[str]]:
    """The parsed XML of a URDF, the text parsed and the undeclared namespace prefixes it uses.

    Projects publish URDFs with foreign attributes and elements whose prefix no ``xmlns:``
    declares (``<limit drake:acceleration="2.5" .../>``, ``<gazebo:plugin>``, ``xacro:``
    leftovers); Pinocchio, ROS and Drake read them and skip what they do not know. Such a text
    is parsed again with each of these prefixes declared on the root element
    (``xmlns:drake="urn:nnrobust:undeclared:drake"``, on the root's own line: line numbers stay),
    and that text is returned; anything else that is not well-formed is refused, naming the
    first place that is. DTD and entity declarations are refused before any parse.
    """
    if "<!DOCTYPE" in text or "<!ENTITY" in text:
        raise UrdfRefused(
            source,
            "DTD or entity declarations (<!DOCTYPE, <!ENTITY) are not "
            "allowed in a URDF; they are never needed and can expand without bound",
        )
    try:
        return ET.fromstring(text), text, []
    except ET.ParseError as err:
        line, column = err.position
        first = _malformed(source, line, column, str(err).split(":")[0])
        if err.code != expat.errors.codes[expat.errors.XML_ERROR_UNBOUND_PREFIX]:
            raise first from err
    data = text.encode("utf-8")
    try:
        prefixes, at = _undeclared_prefixes(data, source)
    except expat.ExpatError as err:  # malformed further on, whatever the prefixes
        raise _malformed(source, err.lineno, err.offset, expat.ErrorString(err.code)) from err
    if not prefixes or at < 0:
        raise first
    declarations = "".join(f' xmlns:{p}="{UNDECLARED_NAMESPACE}{p}"' for p in prefixes)
    declared = (data[:at] + declarations.encode("utf-8") + data[at:]).decode("utf-8")
    try:
        return ET.fromstring(declared), declared, prefixes
    except ET.ParseError as err:
        line, column = err.position
        raise _malformed(source, line, column, str(err).split(":")[0]) from err


def _shown(tag: str) -> str:
    """An element's name as written in the file (``{urn:nnrobust:undeclared:P}x`` is ``P:x``)."""
    if tag.startswith("{" + UNDECLARED_NAMESPACE):
        prefix, _, name = tag[len(UNDECLARED_NAMESPACE) + 1 :].partition("}")
        return f"{prefix}:{name}"
    return tag


def _number_list(text: str | None, count: int, where: str, source: str) -> list[float]:
    if text is None:
        raise UrdfStructureError(source, f"{where}: the attribute is missing")
    values = text.split()
    expected = "a finite number" if count == 1 else f"{count} finite numbers"
    try:
        numbers = [float(v) for v in values]
    except ValueError as err:
        raise UrdfStructureError(source, f"{where}: {text!r} is not {expected}") from err
    if len(numbers) != count or not all(math.isfinite(v) for v in numbers):
        raise UrdfStructureError(source, f"{where}: {text!r} is not {expected}")
    return numbers


MAX_MASS = 1e5
"""Heaviest link accepted [kg] (a large industrial arm's links weigh hundreds of kg)."""
MAX_INERTIA = 1e5
"""Largest principal moment of inertia accepted [kg m^2]."""
MAX_LENGTH = 1e3
"""Largest offset of an origin accepted [m]."""
MAX_EFFORT = 1e7
"""Largest effort limit accepted [N m or N]."""
MAX_VELOCITY = 1e4
"""Largest velocity limit accepted [rad/s or m/s]."""

_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_MOVING = ("revolute", "continuous", "prismatic")


def _attribute(
    element: ET.Element,
    key: str,
    where: str,
    source: str,
    default: str | None = None,
    count: int = 1,
    low: float = -math.inf,
    high: float = math.inf,
) -> list[float]:
    """Numbers of one attribute, finite and within [low, high]; missing is an error unless a
    default is given (what the URDF specification defaults it to).
    """
    text = element.get(key, default)
    if text is None:
        raise UrdfStructureError(source, f"{where}: the attribute {key!r} is missing")
    numbers = _number_list(text, count, f"{where} {key}", source)
    for value in numbers:
        if not low <= value <= high:
            raise UrdfStructureError(source, f"{where} {key}: {value:g} is outside [{low:g}, {high:g}]")
    return numbers


def _check_origin(element: ET.Element, where: str, source: str) -> None:
    origin = element.find("origin")
    if origin is not None:
        _attribute(origin, "xyz", f"{where} <origin>", source, "0 0 0", 3, -MAX_LENGTH, MAX_LENGTH)
        _attribute(origin, "rpy", f"{where} <origin>", source, "0 0 0", 3, -1e3, 1e3)


TRIANGLE_TOLERANCE = 0.01
"""Relative violation of the triangle inequality I1 + I2 >= I3 accepted as rounding: an inertia
written to 3 significant digits has each principal moment off by up to 0.5 %, so I1 + I2 - I3 off
by up to 1 % of I3. A thin plate sits exactly on the inequality, so real links reach it."""


class InertiaAssumptionWarning(UserWarning):
    """A URDF's inertial data was read with an assumption (a convention of exporters, rounding)."""


def _read_inertial(link: ET.Element, name: str, source: str) -> tuple[float, np.ndarray | None]:
    """(mass, inertia about the centre of mass) of a link's <inertial>, refusing what no reading
    makes usable: missing entries, a negative or absurd mass or inertia ((0, None) without one).
    """
    inertial = link.find("inertial")
    if inertial is None:
        return 0.0, None
    where = f"link {name!r}"
    mass_el = inertial.find("mass")
    inertia_el = inertial.find("inertia")
    if mass_el is None or inertia_el is None:
        raise InvalidInertia(source, f"{where}: <inertial> needs <mass> and <inertia>")
    _check_origin(inertial, where, source)
    (mass,) = _number_list(mass_el.get("value"), 1, f"{where} mass", source)
    if mass < 0:
        raise InvalidInertia(source, f"{where}: mass {mass:g} kg must not be negative")
    if mass > MAX_MASS:
        raise InvalidInertia(
            source, f"{where}: mass {mass:g} kg is beyond any robot link (at most {MAX_MASS:g} kg)"
        )
    missing = [key for key in _INERTIA_KEYS if inertia_el.get(key) is None]
    if missing:
        raise InvalidInertia(
            source,
            f"{where}: <inertia> needs all six of {', '.join(_INERTIA_KEYS)} "
            f"(missing {', '.join(missing)}; write 0 for a zero product of inertia)",
        )
    values = {key: _number_list(inertia_el.get(key), 1, f"{where} {key}", source)[0] for key in _INERTIA_KEYS}
    I = np.array(
        [
            [values["ixx"], values["ixy"], values["ixz"]],
            [values["ixy"], values["iyy"], values["iyz"]],
            [values["ixz"], values["iyz"], values["izz"]],
        ]
    )
    if np.abs(I).max() > MAX_INERTIA:
        raise InvalidInertia(
            source,
            f"{where}: an inertia of {np.abs(I).max():g} kg m^2 is beyond any robot "
            f"link (at most {MAX_INERTIA:g} kg m^2)",
        )
    return mass, I


def _triangle_excess(I: np.ndarray) -> float:
    """(I3 - I1 - I2) / I3 of the principal moments: > 0 where the triangle inequality breaks."""
    moments = np.linalg.eigvalsh(I)
    return float((moments[2] - moments[0] - moments[1]) / moments[2]) if moments[2] > 0 else 0.0


def _opposite_products(I: np.ndarray) -> np.ndarray:
    """The inertia with its products of inertia of the opposite sign (+integral of x y dm, the
    CAD convention, where URDF's ixy is -integral of x y dm).
    """
    return np.where(np.eye(3, dtype=bool), I, -I)


def _check_inertias(
    links: dict[str, ET.Element], parent_of: dict[str, tuple[str, str]], source: str
) -> tuple[dict[str, float], list[str], bool]:
    """Every moving link's mass and inertia, told into three kinds (docs/robots.md, "Inertial
    data"): impossible (refused, every such link named at once), conventions of real exports
    (read as such, with one warning) and data as given.

    - A massless link with an inertia (a frame link such as a flange) is read with no inertia: a
      rotational inertia without mass is no body.
    - When some link breaks the triangle inequality as written but every link keeps it with the
      products of inertia of the opposite sign, the file is read with that sign (its exporter
      wrote +integral of x y dm): an exporter uses one convention for all its links.
    - A triangle inequality broken by at most :data:`TRIANGLE_TOLERANCE` is rounding.

    Returns (mass per link, massless links whose inertia is dropped, whether the products are
    read with the opposite sign).
    """
    masses: dict[str, float] = {}
    bodies: dict[str, np.ndarray] = {}
    massless: list[str] = []
    impossible: list[str] = []
    for name, link in links.items():
        if name not in parent_of:  # the root is welded to the world: its inertia never enters the dynamics
            masses[name] = 0.0
            continue
        mass, I = _read_inertial(link, name, source)
        masses[name] = mass
        if I is None:
            continue
        if mass == 0:
            if np.any(I != 0):
                massless.append(name)
            continue
        moments = np.linalg.eigvalsh(I)
        if not moments[0] >= -(1e-9 * abs(moments[2]) + 1e-15):
            impossible.append(
                f"{name!r}: the inertia is not positive semi-definite (principal moments "
                f"{np.round(moments, 9).tolist()} kg m^2)"
            )
            continue
        bodies[name] = I
    broken = [name for name, I in bodies.items() if _triangle_excess(I) > 1e-9]
    flipped = bool(broken) and all(_triangle_excess(_opposite_products(I)) <= 1e-9 for I in bodies.values())
    rounded: list[str] = []
    for name in broken if not flipped else []:
        excess = _triangle_excess(bodies[name])
        if excess <= TRIANGLE_TOLERANCE:
            rounded.append(name)
        else:
            moments = np.round(np.linalg.eigvalsh(bodies[name]), 9).tolist()
            impossible.append(
                f"{name!r}: principal moments {moments} break the triangle inequality "
                f"I1 + I2 >= I3 by {100 * excess:.3g} % of I3 (no rigid body has them; "
                f"{100 * TRIANGLE_TOLERANCE:g} % is taken as rounding)"
            )
    if impossible:
        raise InvalidInertia(
            source,
            f"{len(impossible)} link{'s' if len(impossible) > 1 else ''} with "
            f"impossible inertial data: {'; '.join(impossible)}",
        )
    assumed = []
    if massless:
        assumed.append(
            f"massless link{'s' if len(massless) > 1 else ''} {', '.join(massless)} read with no "
            "inertia (a rotational inertia without mass is no body: a frame link)"
        )
    if flipped:
        assumed.append(
            f"products of inertia read with the opposite sign (+integral of x y dm, the CAD "
            f"convention; URDF's ixy is -integral of x y dm): as written, link"
            f"{'s' if len(broken) > 1 else ''} {', '.join(broken)} break the triangle inequality, "
            "read so every link keeps it"
        )
    if rounded:
        assumed.append(
            f"link{'s' if len(rounded) > 1 else ''} {', '.join(rounded)} break the triangle "
            f"inequality by at most {100 * TRIANGLE_TOLERANCE:g} % (rounding), taken as given"
        )
    if assumed:
        warnings.warn(
            f"{source}: inertial data read with assumptions: {'; '.join(assumed)}",
            InertiaAssumptionWarning,
            stacklevel=4,
        )
    return masses, massless, flipped


def _repaired(root: ET.Element, massless: list[str], flipped: bool) -> str | None:
    """The URDF text with the assumptions of :func:`_check_inertias` written in, or None."""
    if not massless and not flipped:
        return None
    for link in root.iter("link"):
        inertia = link.find("inertial/inertia")
        if inertia is None:
            continue
        if link.get("name") in massless:
            for key in _INERTIA_KEYS:
                inertia.set(key, "0")
        elif flipped:
            for key in ("ixy", "ixz", "iyz"):
                value = float(inertia.get(key, "0"))
                inertia.set(key, repr(-value) if value else "0")
    return ET.tostring(root, encoding="unicode")


def _check_joint(joint: ET.Element, name: str, source: str, locked: frozenset[str]) -> None:
    """Refuse joint values the parser would read wrongly or silently change."""
    kind = joint.get("type")
    where = f"joint {name!r}"
    valid = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
    if kind not in valid:
        raise UrdfStructureError(source, f"{where}: type {kind!r} is not one of {', '.join(valid)}")
    _check_origin(joint, where, source)
    if kind in _MOVING:
        axis = joint.find("axis")
        if axis is not None:
            xyz = _attribute(axis, "xyz", f"{where} <axis>", source, "1 0 0", 3)
            if math.hypot(*xyz) < 1e-9:
                raise UrdfStructureError(
                    source, f"{where} <axis>: xyz = {axis.get('xyz')!r} is zero; an axis needs a direction"
                )
    limit = joint.find("limit")
    if kind in ("revolute", "prismatic") and limit is None:
        raise UrdfStructureError(source, f"{where}: a {kind} joint needs <limit lower upper effort velocity>")
    if limit is not None and kind in _MOVING:
        lower, upper = (
            _attribute(limit, key, f"{where} <limit>", source, "0")[0] for key in ("lower", "upper")
        )
        if kind != "continuous" and lower > upper:
            raise UrdfStructureError(source, f"{where} <limit>: lower = {lower:g} is above upper = {upper:g}")
        _attribute(limit, "effort", f"{where} <limit>", source, None, 1, 0, MAX_EFFORT)
        _attribute(limit, "velocity", f"{where} <limit>", source, None, 1, 0, MAX_VELOCITY)
    dynamics = joint.find("dynamics")
    if dynamics is not None:
        for key in ("damping", "friction"):
            _attribute(dynamics, key, f"{where} <dynamics>", source, "0", 1, 0, MAX_EFFORT)
    mimic = joint.find("mimic")
    if mimic is not None and name not in locked:
        raise UrdfStructureError(
            source,
            f"{where} mimics joint {mimic.get('joint')!r}: nnrobust does not "
            "model mimic joints (the parser would make it an independent joint); "
            f"lock it with robot.locked_joints = [{name!r}] or remove <mimic>",
        )


def mimic_joints(text: str) -> frozenset[str]:
    """Names of the joints that carry a <mimic> (none when the text is not XML: the check says why)."""
    try:
        root = parse_urdf_xml(text, "")[0]
    except (UrdfSyntaxError, UrdfRefused):
        return frozenset()
    return frozenset(
        j.get("name", "") for j in root.iter("joint") if j.find("mimic") is not None and j.get("name")
    )


def _check_origin_of_root(link: ET.Element, name: str, source: str) -> None:
    """The root's <inertial> does not matter, but its numbers must still be numbers."""
    inertial = link.find("inertial")
    if inertial is not None:
        _check_origin(inertial, f"link {name!r}", source)


def _check_mass_moves(
    joints: dict[str, ET.Element],
    parent_of: dict[str, tuple[str, str]],
    masses: dict[str, float],
    source: str,
) -> None:
    """Every moving joint must move some mass, or M(q) is singular (O(links))."""
    below = dict(masses)  # link -> mass of its subtree
    children: dict[str, list[str]] = {}
    for child, (parent, _) in parent_of.items():
        children.setdefault(parent, []).append(child)
    order, stack = [], [name for name in masses if name not in parent_of]
    while stack:
        link = stack.pop()
        order.append(link)
        stack.extend(children.get(link, []))
    for link in reversed(order):
        if link in parent_of:
            below[parent_of[link][0]] += below[link]
    for child, (_, joint) in parent_of.items():
        if joints[joint].get("type") in _MOVING and below[child] <= 0:
            raise InvalidInertia(
                source,
                f"joint {joint!r} moves no mass (link {child!r} and the links after "
                "it have no <inertial>): M(q) would be singular; give them masses or "
                "make the joint fixed",
            )


def mesh_roots(base: Path | None, folders: Sequence[str | Path] = ()) -> list[Path]:
    """Folders a URDF's visual meshes may be read from (docs/robots.md, "Meshes").

    A URDF file in ``base``: its own folder and the one above it, so that
    ``package://<pkg>/meshes/x.stl`` finds ``<pkg>/meshes/x.stl`` for ``<pkg>/urdf/robot.urdf``.
    A URDF given as text (``base`` None): the working folder. In both cases also every folder of
    ``ROS_PACKAGE_PATH`` (``package://<pkg>/...`` is ``<folder>/<pkg>/...``) and every folder of
    ``folders`` (``robot.mesh_folders``, relative ones from the working folder). The filesystem
    root is never one of them.
    """
    own = [Path.cwd().resolve()] if base is None else [Path(base).resolve(), Path(base).resolve().parent]
    ros = [Path(p).resolve() for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    return [p for p in dict.fromkeys(own + ros + listed_mesh_folders(folders)) if p != Path(p.anchor)]


def listed_mesh_folders(folders: Sequence[str | Path]) -> list[Path]:
    """The folders of ``robot.mesh_folders``, resolved (relative ones from the working folder),
    without the filesystem root.
    """
    resolved = [Path(f).resolve() for f in folders if str(f)]
    return [p for p in resolved if p != Path(p.anchor)]


def _inside(path: Path, roots: list[Path]) -> bool:
    return any(path == r or r in path.parents for r in roots)


def _resolve_mesh(uri: str, base: Path | None, roots: list[Path]) -> tuple[Path | None, str]:
    """Where a mesh URI leads: (the file inside ``roots``, maybe missing, ""), or (None, why it
    is not read: a URL, or a path outside ``roots``). Nothing outside ``roots`` is opened: a
    candidate is placed by its text first (``..`` folded), and only one inside a root is
    resolved on disk, where a symbolic link may still lead out.
    """
    if uri.startswith("package://"):
        relative = uri[len("package://") :].lstrip("/")  # package:///pkg/... as Pinocchio reads it
        tail = relative.split("/", 1)[1] if "/" in relative else relative
        candidates = [root / rel for root in roots for rel in (relative, tail)]
    elif uri.startswith("file://"):
        candidates = [Path(uri[len("file://") :])]
    elif "://" in uri:
        return None, "a URL: only package:// and file paths are read"
    elif os.path.isabs(uri):
        candidates = [Path(uri)]
    else:
        candidates = [(base if base is not None else Path.cwd()) / uri]
    inside = []
    for candidate in candidates:
        if _inside(Path(os.path.normpath(os.path.abspath(candidate))), roots):
            real = candidate.resolve()
            if _inside(real, roots):
                inside.append(real)
    if not inside:
        return None, ""
    return next((path for path in inside if path.is_file()), inside[0]), ""


def check_urdf(text: str, source: str, locked: frozenset[str] = frozenset()) -> str:
    """Refuse a URDF that Pinocchio would mis-read; return the text to parse: the URDF itself,
    with its undeclared namespace prefixes declared (:func:`parse_urdf_xml`) and the inertial
    assumptions of real exports written in (:func:`_check_inertias`), each said in one warning.
    Meshes are not looked at: the dynamics never need them (:func:`resolved_visuals` does, for
    the viewer).

    Args:
        text: the URDF XML.
        source: file name or ``<urdf string>``, for messages.
        locked: joints that will be locked (a mimic joint must be one of them).

    """
    if len(text) > MAX_URDF_BYTES:
        raise UrdfRefused(
            source, f"{len(text) / 1e6:.1f} MB is larger than the {MAX_URDF_BYTES / 1e6:g} MB a URDF may have"
        )
    root, text, prefixes = parse_urdf_xml(text, source)
    if sum(1 for _ in root.iter()) > MAX_ELEMENTS:
        raise UrdfRefused(source, f"more than {MAX_ELEMENTS} XML elements")
    if root.tag != "robot":
        raise UrdfStructureError(source, f"the root element is <{_shown(root.tag)}>, a URDF needs <robot>")
    if prefixes:
        several = len(prefixes) > 1
        warnings.warn(
            f"{source}: undeclared XML namespace prefix{'es' if several else ''} {', '.join(prefixes)}: "
            f"{'their' if several else 'its'} elements and attributes are ignored",
            UndeclaredPrefixWarning,
            stacklevel=3,
        )

    links = _by_name(root, "link", source)
    if not links:
        raise UrdfStructureError(source, "no <link> at all")

    parent_of: dict[str, tuple[str, str]] = {}  # child link -> (parent link, joint)
    joints = _by_name(root, "joint", source)
    for name, joint in joints.items():
        parent_el, child_el = joint.find("parent"), joint.find("child")
        if parent_el is None or child_el is None:
            raise UrdfStructureError(source, f"joint {name!r} needs <parent link=...> and <child link=...>")
        parent, child = parent_el.get("link", ""), child_el.get("link", "")
        for role, link in (("parent", parent), ("child", child)):
            if link not in links:
                raise UrdfStructureError(
                    source,
                    f"joint {name!r}: {role} link {link!r} is not defined "
                    f"(links: {', '.join(sorted(links))})",
                )
        if child in parent_of:
            raise UrdfStructureError(
                source, f"link {child!r} is the child of two joints ({parent_of[child][1]!r} and {name!r})"
            )
        parent_of[child] = (parent, name)

    _refuse_cycles(parent_of, source)
    roots_found = [name for name in links if name not in parent_of]
    if len(roots_found) != 1:
        raise UrdfStructureError(
            source,
            f"links {sorted(roots_found)} have no parent joint: the "
            "links do not form one tree (every link but the root needs one)",
        )
    _check_origin_of_root(links[roots_found[0]], roots_found[0], source)

    masses, massless, flipped = _check_inertias(links, parent_of, source)
    for name, joint in joints.items():
        _check_joint(joint, name, source, locked)
    _check_mass_moves(joints, parent_of, masses, source)
    return _repaired(root, massless, flipped) or text


def resolved_visuals(
    text: str, source: str, base: Path | None = None, roots: list[Path] | None = None
) -> str:
    """The URDF with every visual mesh's filename replaced by the file it resolves to inside the
    folders meshes are read from (:func:`mesh_roots`, or ``roots``), and every other visual
    removed (its mesh outside them, a URL, or missing), so that the geometry parser and the
    viewer read no other file and such a mesh costs only its own part. One warning says how
    many lie outside, one how many are missing.
    """
    root = parse_urdf_xml(text, source)[0]
    roots = mesh_roots(base) if roots is None else roots
    outside: list[tuple[str, str]] = []  # (URI, why not read)
    missing: list[tuple[str, Path]] = []  # (URI, the file it names)
    for link in root.iter("link"):
        for visual in list(link.findall("visual")):
            for mesh in visual.iter("mesh"):
                uri = mesh.get("filename", "")
                path, why = _resolve_mesh(uri, base, roots)
                if path is None or not path.is_file():
                    if path is None:
                        outside.append((uri, why))
                    else:
                        missing.append((uri, path))
                    link.remove(visual)
                    break
                mesh.set("filename", str(path))
    if outside:
        n, (uri, why) = len(outside), outside[0]
        folders = "the URDF's folder, the one above it" if base is not None else "the working folder"
        warnings.warn(
            f"{source}: {n} visual mesh{'es lie' if n > 1 else ' lies'} outside the folders meshes "
            f"are read from (first: {uri!r}{'; ' + why if why else ''}); the run's dynamics do not "
            f"need {'them' if n > 1 else 'it'}; the viewer draws {'them' if n > 1 else 'it'} only "
            f"from folders listed in robot.mesh_folders (besides {folders} and ROS_PACKAGE_PATH)",
            MeshOutsideFoldersWarning,
            stacklevel=3,
        )
    if missing:
        n, (uri, path) = len(missing), missing[0]
        what = (
            f"visual mesh {uri!r} not found ({path}); the robot simulates, the viewer leaves that part out"
            if n == 1
            else f"{n} visual meshes not found (first: {uri!r}, {path}); the robot simulates, the "
            "viewer leaves those parts out"
        )
        warnings.warn(f"{source}: {what}", MissingMeshWarning, stacklevel=3)
    return ET.tostring(root, encoding="unicode")


def visual_meshes_set_aside(text: str) -> tuple[str, dict[str, tuple[str, list[float]]]]:
    """The URDF with every visual mesh replaced by a point (a sphere of radius 0), and the meshes:
    {geometry object name: (file, scale)}, named as Pinocchio's parser names visuals
    (``<link>_<index of the visual in the link>``). A viewer reads mesh files itself; parsing
    them into collision structures (about 0.5 s for the Panda) is then skipped.
    """
    root = ET.fromstring(text)
    meshes = {}
    for link in root.iter("link"):
        for index, visual in enumerate(link.findall("visual")):
            geometry = visual.find("geometry")
            mesh = None if geometry is None else geometry.find("mesh")
            if geometry is None or mesh is None:
                continue
            scale = [float(v) for v in mesh.get("scale", "1 1 1").split()]
            meshes[f"{link.get('name')}_{index}"] = (mesh.get("filename", ""), scale)
            geometry.remove(mesh)
            ET.SubElement(geometry, "sphere", radius="0")
    return ET.tostring(root, encoding="unicode"), meshes


def _by_name(root: ET.Element, tag: str, source: str) -> dict[str, ET.Element]:
    """The <link> or <joint> elements by name; every one named, no name twice."""
    found: dict[str, ET.Element] = {}
    for element in root.findall(tag):
        name = element.get("name")
        if not name:
            raise UrdfStructureError(source, f"a <{tag}> has no name")
        if name in found:
            raise UrdfStructureError(source, f"two {tag}s are named {name!r}")
        found[name] = element
    return found


def _refuse_cycles(parent_of: dict[str, tuple[str, str]], source: str) -> None:
    """Follow parent links from every link once (O(links)); a link met twice on one walk closes
    a loop.
    """
    done: set[str] = set()  # links whose walk ended at a root
    for start in parent_of:
        walk: list[str] = []
        on_walk: set[str] = set()
        link = start
        while link in parent_of and link not in done:
            if link in on_walk:
                loop = walk[walk.index(link) :] + [link]
                joints = [parent_of[x][1] for x in loop[:-1]]
                raise KinematicCycle(
                    source,
                    f"the joints {joints} form a closed loop through links "
                    f"{loop}; Pinocchio models trees only",
                )
            walk.append(link)
            on_walk.add(link)
            link = parent_of[link][0]
        done.update(walk)
