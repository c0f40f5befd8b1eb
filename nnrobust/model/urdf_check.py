"""Check a URDF before Pinocchio sees it.

Pinocchio returns an empty model for a kinematic cycle and the XML parsers behind URDF readers
repair broken files silently, so nnrobust reads the XML itself first, with hard limits, and
refuses with one clear message per kind of problem (exceptions in :mod:`nnrobust.exceptions`).
"""

from __future__ import annotations

import math
import os
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..exceptions import (
    InvalidInertia,
    KinematicCycle,
    UnsafePath,
    UrdfRefused,
    UrdfStructureError,
    UrdfSyntaxError,
)
from .perturbation import rotational_inertia_problem

MAX_URDF_BYTES = 20_000_000
"""Largest URDF read [bytes]; real arms are well under 1 MB."""

MAX_ELEMENTS = 200_000
"""Most XML elements in a URDF."""


class MissingMeshWarning(UserWarning):
    """A visual mesh file does not exist: the robot simulates, the viewer leaves the part out."""


def read_urdf_file(path: str | Path) -> str:
    """The text of a URDF file, refused when it is too large or not UTF-8."""
    path = Path(path)
    size = path.stat().st_size
    if size > MAX_URDF_BYTES:
        raise UrdfRefused(str(path), f"{size / 1e6:.1f} MB is larger than the {MAX_URDF_BYTES / 1e6:g} MB "
                          "a URDF may have")
    try:
        return path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as err:
        raise UrdfSyntaxError(str(path), f"not UTF-8 text (byte {err.start})") from err


def _number_list(text: str | None, count: int, where: str, source: str) -> list[float]:
    values = (text or "").split()
    expected = "a finite number" if count == 1 else f"{count} finite numbers"
    try:
        numbers = [float(v) for v in values]
    except ValueError as err:
        raise UrdfStructureError(source, f"{where}: {text!r} is not {expected}") from err
    if len(numbers) != count or not all(math.isfinite(v) for v in numbers):
        raise UrdfStructureError(source, f"{where}: {text!r} is not {expected}")
    return numbers


def _check_inertial(link: ET.Element, name: str, source: str) -> None:
    inertial = link.find("inertial")
    if inertial is None:
        return
    mass_el = inertial.find("mass")
    inertia_el = inertial.find("inertia")
    if mass_el is None or inertia_el is None:
        raise InvalidInertia(source, f"link {name!r}: <inertial> needs <mass> and <inertia>")
    (mass,) = _number_list(mass_el.get("value"), 1, f"link {name!r} mass", source)
    if mass <= 0:
        raise InvalidInertia(source, f"link {name!r}: mass {mass:g} kg must be positive (remove "
                             "<inertial> for a massless link)")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    values = {}
    for key in keys:
        (values[key],) = _number_list(inertia_el.get(key, "0"), 1, f"link {name!r} {key}", source)
    I = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                  [values["ixy"], values["iyy"], values["iyz"]],
                  [values["ixz"], values["iyz"], values["izz"]]])
    problem = rotational_inertia_problem(I, rel_tol=1e-9)
    if problem:
        raise InvalidInertia(source, f"link {name!r}: {problem}")


def mesh_roots(base: Path) -> list[Path]:
    """Folders a URDF in ``base`` may take meshes from: its own and the one above it.

    ``package://<pkg>/meshes/x.stl`` then finds ``<pkg>/meshes/x.stl`` for
    ``<pkg>/urdf/robot.urdf``. The filesystem root is never one of them.
    """
    base = base.resolve()
    return [p for p in (base, base.parent) if p != Path(p.anchor)]


def _resolve_mesh(uri: str, base: Path | None, roots: list[Path], source: str) -> Path | None:
    """The file a mesh URI names (maybe missing), or None when it cannot be located at all."""
    if uri.startswith("package://"):
        relative = uri[len("package://"):]
        tail = relative.split("/", 1)[1] if "/" in relative else relative
        candidates = [root / rel for root in roots for rel in (relative, tail)]
    elif uri.startswith("file://"):
        candidates = [Path(uri[len("file://"):])]
    elif "://" in uri:
        raise UnsafePath(source, f"mesh {uri!r}: only package:// and file paths are read")
    elif os.path.isabs(uri):
        candidates = [Path(uri)]
    else:
        candidates = [base / uri] if base is not None else []
    if not candidates or not roots:
        return None  # a URDF string: nothing to resolve against
    allowed = [r.resolve() for r in roots]
    found = None
    for candidate in candidates:
        real = candidate.resolve()
        if not any(real == r or r in real.parents for r in allowed):
            raise UnsafePath(source, f"mesh {uri!r} resolves to {real}, outside the allowed folders "
                             f"{[str(r) for r in allowed]}")
        if found is None and real.is_file():
            found = real
    return found or candidates[0].resolve()


def check_urdf(text: str, source: str, base: Path | None = None,
               roots: list[Path] | None = None) -> None:
    """Refuse a URDF that Pinocchio would mis-read; warn about missing visual meshes.

    Args:
        text: the URDF XML.
        source: file name or ``<urdf string>``, for messages.
        base: folder of the URDF file (None for a string).
        roots: folders mesh paths may resolve into (default: :func:`mesh_roots` of ``base``).

    """
    if len(text) > MAX_URDF_BYTES:
        raise UrdfRefused(source, f"{len(text) / 1e6:.1f} MB is larger than the "
                          f"{MAX_URDF_BYTES / 1e6:g} MB a URDF may have")
    if "<!DOCTYPE" in text or "<!ENTITY" in text:
        raise UrdfRefused(source, "DTD or entity declarations (<!DOCTYPE, <!ENTITY) are not "
                          "allowed in a URDF; they are never needed and can expand without bound")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as err:
        line, column = err.position
        raise UrdfSyntaxError(source, f"malformed XML at line {line}, column {column + 1}: "
                              f"{str(err).split(':')[0]}") from err
    if sum(1 for _ in root.iter()) > MAX_ELEMENTS:
        raise UrdfRefused(source, f"more than {MAX_ELEMENTS} XML elements")
    if root.tag != "robot":
        raise UrdfStructureError(source, f"the root element is <{root.tag}>, a URDF needs <robot>")

    links = _by_name(root, "link", source)
    if not links:
        raise UrdfStructureError(source, "no <link> at all")

    parent_of: dict[str, tuple[str, str]] = {}  # child link -> (parent link, joint)
    for name, joint in _by_name(root, "joint", source).items():
        parent_el, child_el = joint.find("parent"), joint.find("child")
        if parent_el is None or child_el is None:
            raise UrdfStructureError(source, f"joint {name!r} needs <parent link=...> and <child link=...>")
        parent, child = parent_el.get("link"), child_el.get("link")
        for role, link in (("parent", parent), ("child", child)):
            if link not in links:
                raise UrdfStructureError(source, f"joint {name!r}: {role} link {link!r} is not defined "
                                         f"(links: {', '.join(sorted(links))})")
        if child in parent_of:
            raise UrdfStructureError(source, f"link {child!r} is the child of two joints "
                                     f"({parent_of[child][1]!r} and {name!r})")
        parent_of[child] = (parent, name)

    _refuse_cycles(parent_of, source)
    roots_found = [name for name in links if name not in parent_of]
    if len(roots_found) != 1:
        raise UrdfStructureError(source, f"links {sorted(roots_found)} have no parent joint: the "
                                 "links do not form one tree (every link but the root needs one)")

    for name, link in links.items():
        _check_inertial(link, name, source)

    visual_meshes = {id(m) for visual in root.iter("visual") for m in visual.iter("mesh")}
    allowed = roots if roots is not None else (mesh_roots(base) if base is not None else [])
    for mesh in root.iter("mesh"):
        uri = mesh.get("filename", "")
        path = _resolve_mesh(uri, base, allowed, source)
        if path is not None and not path.is_file():
            where = "visual" if id(mesh) in visual_meshes else "collision"
            warnings.warn(f"{source}: {where} mesh {uri!r} not found ({path}); the robot simulates, "
                          "the viewer leaves that part out", MissingMeshWarning, stacklevel=3)


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
        walk, on_walk, link = [], set(), start
        while link in parent_of and link not in done:
            if link in on_walk:
                loop = walk[walk.index(link):] + [link]
                joints = [parent_of[x][1] for x in loop[:-1]]
                raise KinematicCycle(source, f"the joints {joints} form a closed loop through links "
                                     f"{loop}; Pinocchio models trees only")
            walk.append(link)
            on_walk.add(link)
            link = parent_of[link][0]
        done.update(walk)
