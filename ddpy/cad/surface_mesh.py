"""Tool surface meshes from files: STL (ASCII and binary), Abaqus/CalculiX input (.inp), Gmsh
(.msh) and what meshio reads besides; merged, checked and oriented for Nagata patches.

:func:`read_surface_mesh` reads the triangles and quadrilaterals of a file (STL and .inp by
readers of our own, which name the line of a defect; the others through meshio), each face
with the line it came from where the format has lines and a group tag (an STL solid, an
Abaqus element block or *SURFACE, a Gmsh physical group). :func:`prepare_surface_mesh` then
merges duplicate vertices (an STL file repeats each vertex in every facet) within a tolerance
relative to the mesh size, refuses degenerate and repeated faces and non-manifold edges,
orients the faces consistently and each connected part towards the blank.

Every refusal is a :class:`MeshFileError` whose message starts with the file (and line).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy._validate import (
    MAX_LENGTH,
    NUMBER_PATTERN,
    TOOL_LIMIT,
    InputFileError,
    check_input_file,
    read_input_file,
)
from ddpy.cad.mesh import point_text
from ddpy.cad.read import CadError
from ddpy.io.case import DeckError
from ddpy.io.gmsh import GmshFileError, check_gmsh
from ddpy.io.inp_mesh import read_inp_mesh

__all__ = ["DEFAULT_MERGE_TOL", "MESH_FORMATS", "MeshFileError", "SurfaceMesh",
           "prepare_surface_mesh", "read_surface_mesh"]

#: Vertices closer than this many times the median edge length are one vertex.
DEFAULT_MERGE_TOL = 1.0e-4
#: A part whose normals point towards the blank by less than this on average (the mean of
#: n . d over its area) is edge-on to it; a crease-bounded region below minus this, away.
AWAY_TOL = 1.0e-3
#: Smallest extent of a tool mesh (mm): a tool smaller than a micrometre across is a mesh in
#: another unit or a damaged file. The largest coordinate is the decks' MAX_LENGTH.
MIN_TOOL_SIZE = 1.0e-3
#: What the readers take, for messages.
MESH_FORMATS = "STL (.stl), Abaqus/CalculiX (.inp), Gmsh (.msh) or a format meshio reads " \
    "(.obj, .off, .ply, .vtk, .vtu, ...)"
#: Abaqus element types that are surfaces themselves: rigid, shell, membrane, surface.
_SURFACE_TYPES = re.compile(r"^(R3D[34]|S[34]|S[34]R.*|S[34]RS|STRI3|S8R.*|S9R5|STRI65|S6|"
                            r"M3D[34].*|M3D[689].*|SFM3D[34].*|SFM3D[68].*|DS[34]|SFM3D8R?)$")
#: Faces of Abaqus solid elements by corner count, S1, S2, ... (corner nodes, from 1).
_SOLID_FACES = {
    4: ((1, 2, 3), (1, 4, 2), (2, 4, 3), (3, 4, 1)),
    6: ((1, 2, 3), (4, 6, 5), (1, 4, 5, 2), (2, 5, 6, 3), (3, 6, 4, 1)),
    8: ((1, 2, 3, 4), (5, 8, 7, 6), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 8, 4), (4, 8, 5, 1)),
}
_SOLID_CORNERS = {"C3D4": 4, "C3D10": 4, "C3D6": 6, "C3D15": 6, "C3D8": 8, "C3D20": 8,
                  "SC6R": 6, "SC8R": 8, "DC3D4": 4, "DC3D8": 8, "DC3D6": 6, "DC3D10": 4,
                  "DC3D20": 8, "DC3D15": 6}


class MeshFileError(CadError):
    """A tool mesh that cannot become a tool model; the message names the file (and line)."""


@dataclass
class SurfaceMesh:
    """Triangles and quadrilaterals of a file: ``faces`` (m, 4) vertex indices, -1 last for a
    triangle; ``groups`` (m,) a tag per face (``group_names``: tag -> name); ``lines`` (m,)
    the line of each face in the file (0 where the format has none)."""

    path: Path
    kind: str
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    groups: NDArray[np.int64]
    lines: NDArray[np.int64]
    group_names: dict[int, str] = field(default_factory=dict)
    #: Filled by prepare_surface_mesh: faces turned over to agree with their neighbours or to
    #: face the blank, and vertices merged.
    flipped: int = 0
    merged: int = 0

    def where(self, face: int) -> str:
        """'file:line' of a face, or 'file' with the face's centre."""
        line = int(self.lines[face]) if len(self.lines) else 0
        corners = self.faces[face][self.faces[face] >= 0]
        centre = point_text(self.vertices[corners].mean(axis=0))
        return f"{self.path}:{line}: face at {centre}" if line else \
            f"{self.path}: face {face + 1} at {centre}"

    def label(self, face: int) -> str:
        """'on line N' or 'number N' (in the file's order)."""
        line = int(self.lines[face]) if len(self.lines) else 0
        return f"on line {line}" if line else f"number {face + 1}"

    def error(self, face: int | None, message: str) -> MeshFileError:
        return MeshFileError(f"{self.where(face) if face is not None else self.path}: {message}")


def _corners(faces: NDArray[np.int64]) -> NDArray[np.int64]:
    return np.where(faces < 0, faces[:, :1], faces)


# ----------------------------------------------------------------------------------- reading


def read_surface_mesh(path: str | Path, groups: Sequence[str] | None = None) -> SurfaceMesh:
    """The triangles and quadrilaterals of a mesh file, as they are in it (not merged nor
    oriented); ``groups`` keeps the named ones only (STL solids, Abaqus *SURFACE or ELSET
    names, Gmsh physical names)."""
    path = Path(path)
    if not path.exists():
        raise MeshFileError(f"{path}: no such mesh file")
    suffix = path.suffix.lower()
    try:
        check_input_file(path, "a tool mesh", TOOL_LIMIT)
        if suffix == ".stl":
            mesh = _read_stl(path)
        elif suffix == ".inp":
            mesh = _read_inp(path, groups)
        else:
            mesh = _read_meshio(path)
    except InputFileError as error:
        raise MeshFileError(str(error)) from None
    except OSError as error:
        raise MeshFileError(f"{path}: cannot read the mesh file: {error.strerror or error}") \
            from None
    _check_size(mesh)
    if groups and suffix != ".inp":
        mesh = _select(mesh, groups)
    if len(mesh.faces) == 0:
        raise MeshFileError(f"{path}: the {mesh.kind} file holds no triangles or "
                            "quadrilaterals: nothing to model")
    return mesh


def _within_limits(x: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Per point (or per number of a 1-D array): all coordinates finite and within
    +-MAX_LENGTH mm (beyond, squares of distances overflow and the mesh is not in mm)."""
    with np.errstate(invalid="ignore"):
        inside = np.abs(x) <= MAX_LENGTH
    return inside.all(axis=-1) if x.ndim > 1 else inside


def _check_size(mesh: SurfaceMesh) -> None:
    """Refuse a mesh smaller than MIN_TOOL_SIZE across (a unit mistake)."""
    used = mesh.faces[mesh.faces >= 0]
    if not used.size:
        return
    extent = float(np.ptp(mesh.vertices[np.unique(used)], axis=0).max())
    if extent < MIN_TOOL_SIZE:
        raise MeshFileError(f"{mesh.path}: the mesh is {extent:.3g} mm across: a tool mesh is "
                            f"in mm and at least {MIN_TOOL_SIZE:g} mm across (is it in another "
                            "unit?)")


def _select(mesh: SurfaceMesh, groups: Sequence[str]) -> SurfaceMesh:
    by_name = {name: tag for tag, name in mesh.group_names.items()}
    missing = [g for g in groups if g not in by_name]
    if missing:
        known = ", ".join(sorted(by_name)) or "none"
        raise MeshFileError(f"{mesh.path}: no group named '{missing[0]}' (groups: {known})")
    keep = np.isin(mesh.groups, [by_name[g] for g in groups])
    return replace(mesh, faces=mesh.faces[keep], groups=mesh.groups[keep],
                   lines=mesh.lines[keep])


def _read_stl(path: Path) -> SurfaceMesh:
    data = read_input_file(path, "a tool mesh", TOOL_LIMIT)
    if len(data) >= 84:
        count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
        if len(data) == 84 + 50 * count:
            return _stl_binary(path, data, count)
    if not data.lstrip()[:5].lower() == b"solid":
        size = f"{len(data)} bytes"
        raise MeshFileError(f"{path}: not an STL file: an ASCII STL starts with 'solid', and "
                            f"a binary one of {size} would hold "
                            f"{(len(data) - 84) / 50:g} triangles of 50 bytes after its 84-byte"
                            " header")
    return _stl_ascii(path, data)


def _stl_binary(path: Path, data: bytes, count: int) -> SurfaceMesh:
    record = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attribute", "<u2")])
    triangles = np.frombuffer(data, dtype=record, count=count, offset=84)
    x = triangles["v"].astype(np.float64).reshape(-1, 3)
    inside = _within_limits(x)
    if not inside.all():
        k = int(np.argmin(inside)) // 3
        raise MeshFileError(f"{path}: triangle {k + 1} has a coordinate that is not a finite "
                            f"number within +-{MAX_LENGTH:g} mm")
    faces = np.column_stack([np.arange(3 * count).reshape(-1, 3), np.full(count, -1)])
    return SurfaceMesh(path, "STL (binary)", x, faces.astype(np.int64),
                       np.ones(count, dtype=np.int64), np.zeros(count, dtype=np.int64), {1: "1"})


def _stl_ascii(path: Path, data: bytes) -> SurfaceMesh:
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as error:
        line = data[:error.start].count(b"\n") + 1
        raise MeshFileError(f"{path}:{line}: not an ASCII STL file: a byte that is not ASCII "
                            f"(a binary STL whose size does not match its triangle count?)"
                            ) from None
    points: list[list[float]] = []
    lines: list[int] = []
    groups: list[int] = []
    names: dict[int, str] = {}
    state, solid, facet_line, count = "outside", 0, 0, 0
    last = 0
    for number, raw in enumerate(text.replace("\r\n", "\n").replace("\r", "\n").split("\n"),
                                 start=1):
        words = raw.split()
        if not words:
            continue
        last = number
        key = words[0].lower()

        def expect(what: str, number: int = number, raw: str = raw) -> MeshFileError:
            return MeshFileError(f"{path}:{number}: expected {what}, got '{raw.strip()[:60]}'")

        if state == "outside":
            if key != "solid":
                raise expect("'solid <name>'")
            solid += 1
            names[solid] = " ".join(words[1:]) or str(solid)
            state = "solid"
        elif state == "solid":
            if key == "endsolid":
                state = "outside"
            elif key == "facet":
                facet_line, count = number, 0
                state = "facet"
            else:
                raise expect("'facet normal <nx> <ny> <nz>' or 'endsolid'")
        elif state == "facet":
            if key != "outer" or len(words) < 2 or words[1].lower() != "loop":
                raise expect("'outer loop'")
            state = "loop"
        elif state == "loop":
            if key == "vertex":
                if len(words) != 4:
                    raise MeshFileError(f"{path}:{number}: expected 'vertex <x> <y> <z>' (3 "
                                        f"numbers), got {len(words) - 1}")
                if not all(NUMBER_PATTERN.fullmatch(w) for w in words[1:]):
                    raise expect("'vertex <x> <y> <z>' with numbers")
                xyz = [float(w) for w in words[1:]]
                if not _within_limits(np.array(xyz)).all():
                    raise MeshFileError(f"{path}:{number}: expected finite coordinates within "
                                        f"+-{MAX_LENGTH:g} mm, got '{' '.join(words[1:])}' (in "
                                        f"the facet of line {facet_line})")
                points.append(xyz)
                count += 1
            elif key == "endloop":
                if count != 3:
                    raise MeshFileError(f"{path}:{facet_line}: the facet has {count} vertices: "
                                        "an STL facet is a triangle (3)")
                lines.append(facet_line)
                groups.append(solid)
                state = "endfacet"
            else:
                raise expect("'vertex <x> <y> <z>' or 'endloop'")
        elif state == "endfacet":
            if key != "endfacet":
                raise expect("'endfacet'")
            state = "solid"
    if state != "outside":
        raise MeshFileError(f"{path}:{last}: the file ends inside a "
                            f"{'solid' if state == 'solid' else 'facet'}: expected "
                            f"'{'endsolid' if state == 'solid' else 'endfacet'}'")
    n = len(lines)
    faces = np.column_stack([np.arange(3 * n).reshape(-1, 3), np.full(n, -1)])
    return SurfaceMesh(path, "STL (ASCII)", np.array(points, dtype=np.float64).reshape(-1, 3),
                       faces.astype(np.int64), np.array(groups, dtype=np.int64),
                       np.array(lines, dtype=np.int64), names)


# ------------------------------------------------------------------------------ Abaqus input


@dataclass
class _Element:
    kind: str
    nodes: list[int]
    line: int
    block: int


def _read_inp(path: Path, groups: Sequence[str] | None) -> SurfaceMesh:
    """The faces of an input file, read by ddpy's .inp reader (:mod:`ddpy.io.inp_mesh`, the
    one of ``ddpy convert``: includes followed, an assembly made flat, Abaqus ids kept)."""
    try:
        mesh = read_inp_mesh(path)
    except DeckError as error:
        raise MeshFileError(str(error.errors[0])) from None
    nodes: dict[int, tuple[list[float], int]] = {}
    for ident, (xyz, line) in mesh.nodes.items():
        if not _within_limits(np.array(xyz)).all():
            raise MeshFileError(f"{line.where}: expected 2 or 3 finite coordinates within "
                                f"+-{MAX_LENGTH:g} mm for node {ident}")
        nodes[ident] = (list(xyz), line.number)
    elements = {ident: _Element(kind, ids, line.number, mesh.blocks[ident])
                for ident, (kind, ids, line) in mesh.elements.items()}
    elsets = {name: [(item, at.number) for item, at in items]
              for name, items in mesh.elsets.items()}
    surfaces = {name: ([(item, face or "SPOS", at.number) for item, face, at in items],
                       card.number) for name, (items, card) in mesh.surfaces.items()}
    return _inp_faces(path, nodes, elements, elsets, surfaces, groups)


def _inp_faces(path: Path, nodes: dict[int, tuple[list[float], int]],
               elements: dict[int, _Element], elsets: dict[str, list[tuple[str, int]]],
               surfaces: dict[str, tuple[list[tuple[str, str, int]], int]],
               groups: Sequence[str] | None) -> SurfaceMesh:
    faces: list[list[int]] = []
    lines: list[int] = []
    tags: list[int] = []
    names: dict[int, str] = {}

    def lookup(name: str) -> str | None:
        """A set or surface name, also without its instance ('Name' for 'PART-1-1.NAME',
        when one instance has it)."""
        if name in elsets or name in surfaces:
            return name
        qualified = {n for n in (*elsets, *surfaces) if n.endswith("." + name)}
        return qualified.pop() if len(qualified) == 1 else None

    def members(name: str, seen: tuple[str, ...] = ()) -> list[tuple[int, int]]:
        found = []
        for item, line in elsets[name]:
            if item.lstrip("-").isdigit():
                found.append((int(item), line))
            elif (inner := lookup(item.upper())) in elsets and inner not in seen:
                found += members(inner, (*seen, name))
            else:
                raise MeshFileError(f"{path}:{line}: element set {name} names '{item}', which "
                                    "is neither an element id nor an element set")
        return found

    def element(ident: int, line: int) -> _Element:
        if ident not in elements:
            raise MeshFileError(f"{path}:{line}: element {ident} is not defined")
        return elements[ident]

    def add(el: _Element, corners: list[int], line: int, tag: int) -> None:
        for n in corners:
            if n not in nodes:
                raise MeshFileError(f"{path}:{el.line}: node {n} of the element is not defined")
        faces.append(corners + [-1] * (4 - len(corners)))
        lines.append(line)
        tags.append(tag)

    def surface_element(el: _Element, line: int, tag: int, reverse: bool = False) -> None:
        corners = el.nodes[:3] if el.kind.startswith(("R3D3", "S3", "M3D3", "SFM3D3", "STRI",
                                                      "DS3", "S6", "M3D6", "SFM3D6")) \
            else el.nodes[:4]
        if len(set(corners)) < 3:
            raise MeshFileError(f"{path}:{el.line}: the element has fewer than 3 distinct "
                                "corner nodes")
        add(el, corners[::-1] if reverse else corners, line, tag)

    def solid_face(el: _Element, face: str, line: int, tag: int) -> None:
        corners = _SOLID_CORNERS.get(re.sub(r"[A-Z]*$", "", el.kind) if el.kind not in
                                     _SOLID_CORNERS else el.kind)
        if corners is None:
            corners = next((c for k, c in _SOLID_CORNERS.items() if el.kind.startswith(k)), None)
        if corners is None:
            raise MeshFileError(f"{path}:{line}: element {el.kind} (line {el.line}): expected a "
                                "solid (C3D4, C3D6, C3D8, C3D10, C3D15, C3D20 ...) or surface "
                                "element for a face on a *SURFACE")
        match = re.fullmatch(r"S(\d)", face)
        if match is None or not 1 <= int(match.group(1)) <= len(_SOLID_FACES[corners]):
            raise MeshFileError(f"{path}:{line}: expected a face S1..S"
                                f"{len(_SOLID_FACES[corners])} of the {el.kind} element, got "
                                f"'{face}'")
        if len(el.nodes) < corners:
            raise MeshFileError(f"{path}:{el.line}: the {el.kind} element has {len(el.nodes)} "
                                f"nodes, expected at least {corners}")
        add(el, [el.nodes[i - 1] for i in _SOLID_FACES[corners][int(match.group(1)) - 1]],
            line, tag)

    def from_surface(name: str, tag: int) -> None:
        items, _ = surfaces[name]
        for item, face, line in items:
            if item.lstrip("-").isdigit():
                targets = [(int(item), line)]
            elif (inner := lookup(item)) in elsets:
                targets = [(i, line) for i, _ in members(inner)]
            else:
                raise MeshFileError(f"{path}:{line}: surface {name} names '{item}', which is "
                                    "neither an element id nor an element set")
            for ident, at in targets:
                el = element(ident, at)
                if _SURFACE_TYPES.match(el.kind):
                    surface_element(el, at, tag, reverse=face == "SNEG")
                else:
                    solid_face(el, face, at, tag)

    if groups:
        for tag, wanted in enumerate(groups, start=1):
            name = lookup(wanted.upper())
            if name is None:
                known = ", ".join(sorted({*surfaces, *elsets})) or "none"
                raise MeshFileError(f"{path}: no *SURFACE or element set named '{wanted}' "
                                    f"(defined: {known})")
            names[tag] = wanted
            if name in surfaces:
                if not surfaces[name][0]:
                    raise MeshFileError(f"{path}:{surfaces[name][1]}: surface {wanted} has no "
                                        "element faces (a node-based surface?): give element "
                                        "faces, e.g. '<element set>, S1'")
                from_surface(name, tag)
            else:
                for ident, line in members(name):
                    el = element(ident, line)
                    if not _SURFACE_TYPES.match(el.kind):
                        raise MeshFileError(f"{path}:{el.line}: element set {wanted} holds a "
                                            f"{el.kind} element: an element set names surface "
                                            "elements (R3D3, R3D4, S3, S4, ...); give solid "
                                            "faces by a *SURFACE")
                    surface_element(el, el.line, tag)
    else:
        shells = [el for el in elements.values() if _SURFACE_TYPES.match(el.kind)]
        if shells:
            for el in shells:
                names.setdefault(el.block, f"*ELEMENT block {el.block}")
                surface_element(el, el.line, el.block)
        else:
            for tag, name in enumerate((n for n in surfaces if surfaces[n][0]), start=1):
                names[tag] = name
                from_surface(name, tag)
        if not faces:
            kinds = sorted({el.kind for el in elements.values()})
            held = f"elements of type {', '.join(kinds)}" if kinds else "no elements"
            raise MeshFileError(f"{path}: the Abaqus file holds {held} and no element-based "
                                "*SURFACE: nothing to model (expected R3D3/R3D4 rigid or S3/S4 "
                                "shell elements, or a *SURFACE on the tool faces of solid "
                                "elements)")
    ids = sorted({n for f in faces for n in f if n >= 0})
    index = {n: i for i, n in enumerate(ids)}
    vertices = np.array([nodes[n][0] for n in ids], dtype=np.float64).reshape(-1, 3)
    array = np.array([[index[n] if n >= 0 else -1 for n in f] for f in faces],
                     dtype=np.int64).reshape(-1, 4)
    return SurfaceMesh(path, "Abaqus", vertices, array, np.array(tags, dtype=np.int64),
                       np.array(lines, dtype=np.int64), names)


# ------------------------------------------------------------------------------- meshio


def _read_meshio(path: Path) -> SurfaceMesh:
    import meshio

    if path.suffix.lower() == ".msh":
        try:
            check_gmsh(path, read_input_file(path, "a tool mesh", TOOL_LIMIT))
        except GmshFileError as error:
            raise MeshFileError(str(error)) from None
    try:
        data = meshio.read(path)
    except meshio.ReadError as error:
        message = str(error)
        if "Unknown file format" in message or "Could not deduce" in message:
            message = (f"unknown mesh format '{path.suffix}': expected {MESH_FORMATS}, or a "
                       "CAD file (.step, .iges, .brep)")
        raise MeshFileError(f"{path}: {message}") from None
    except Exception as error:  # meshio raises many types for a damaged file
        raise MeshFileError(f"{path}: cannot read the mesh file: {type(error).__name__}: "
                            f"{error}") from None
    kind = "Gmsh" if path.suffix.lower() == ".msh" else path.suffix.lstrip(".").upper()
    points = np.asarray(data.points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise MeshFileError(f"{path}: the mesh's points are not 2- or 3-dimensional")
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    inside = _within_limits(points)
    if not inside.all():
        raise MeshFileError(f"{path}: point {int(np.argmin(inside)) + 1} has a coordinate that "
                            f"is not a finite number within +-{MAX_LENGTH:g} mm")
    tag_data = data.cell_data.get("gmsh:physical") or data.cell_data.get("gmsh:geometrical")
    names = {int(v[0]): str(k) for k, v in getattr(data, "field_data", {}).items()
             if len(v) > 1 and int(v[1]) == 2}
    faces, tags = [], []
    solids: dict[str, int] = {}
    for b, block in enumerate(data.cells):
        conn = np.asarray(block.data, dtype=np.int64)
        base = block.type.rstrip("0123456789")
        if block.type in ("triangle", "triangle6", "triangle7"):
            f = np.column_stack([conn[:, :3], np.full(len(conn), -1)])
        elif block.type in ("quad", "quad8", "quad9"):
            f = conn[:, :4]
        elif block.type == "polygon" or base == "polygon":
            raise MeshFileError(f"{path}: the file holds polygons of {conn.shape[1]} vertices: "
                                "expected triangles and quadrilaterals")
        else:
            if base in ("tetra", "hexahedron", "wedge", "pyramid"):
                solids[block.type] = solids.get(block.type, 0) + len(conn)
            continue
        faces.append(f)
        tag = np.asarray(tag_data[b], dtype=np.int64) if tag_data is not None else \
            np.ones(len(f), dtype=np.int64)
        tags.append(tag)
    if not faces and solids:
        held = ", ".join(f"{n} {t}" for t, n in sorted(solids.items()))
        raise MeshFileError(f"{path}: the file holds solid cells only ({held}): give the tool "
                            "surface as triangles or quadrilaterals")
    array = np.concatenate(faces) if faces else np.zeros((0, 4), dtype=np.int64)
    used = array[array >= 0]
    if used.size and used.max() >= len(points):
        raise MeshFileError(f"{path}: a cell refers to point {int(used.max())}, beyond the "
                            f"{len(points)} points")
    groups = np.concatenate(tags) if tags else np.zeros(0, dtype=np.int64)
    for tag in np.unique(groups):
        names.setdefault(int(tag), str(int(tag)))
    return SurfaceMesh(path, kind, points, array, groups, np.zeros(len(array), dtype=np.int64),
                       names)


# ---------------------------------------------------------------------- merging, orienting


def prepare_surface_mesh(mesh: SurfaceMesh, merge_tol: float = DEFAULT_MERGE_TOL,
                         blank_side: ArrayLike = (0.0, 0.0, 1.0),
                         blank_point: ArrayLike | None = None) -> SurfaceMesh:
    """Merge, check and orient a mesh as read (see the module's text)."""
    if not 0.0 <= merge_tol < 0.5:
        raise ValueError(f"merge_tol must lie in [0, 0.5) (a fraction of the median edge "
                         f"length), got {merge_tol}")
    mesh = _merge(mesh, merge_tol)
    _check_faces(mesh)
    return _orient(mesh, blank_side, blank_point)


def _edge_lengths(x: NDArray[np.float64], faces: NDArray[np.int64]) -> NDArray[np.float64]:
    c = _corners(faces)
    nxt = np.where(faces[:, 3:] < 0, c[:, [1, 2, 0, 1]], c[:, [1, 2, 3, 0]])
    return np.linalg.norm(x[nxt] - x[c], axis=2)


def _merge(mesh: SurfaceMesh, merge_tol: float) -> SurfaceMesh:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    x, faces = mesh.vertices, mesh.faces
    used = np.unique(_corners(faces))
    lengths = _edge_lengths(x, faces)
    positive = lengths[lengths > 0.0]
    size = float(np.median(positive)) if positive.size else 0.0
    tol = merge_tol * size
    pairs = cKDTree(x[used]).query_pairs(tol, output_type="ndarray")  # tol 0: equal points
    n = len(used)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    ids, first, renumber = np.unique(label, return_index=True, return_inverse=True)
    new_x = x[used][first]
    old_to_new = np.full(len(x), -1, dtype=np.int64)
    old_to_new[used] = renumber.ravel()
    new_faces = np.where(faces < 0, -1, old_to_new[np.maximum(faces, 0)])
    return replace(mesh, vertices=new_x, faces=new_faces, merged=int(n - len(ids)))


def _check_faces(mesh: SurfaceMesh) -> None:
    x, faces = mesh.vertices, mesh.faces
    tri = faces[:, 3] < 0
    c = _corners(faces)
    repeated = np.where(tri, (c[:, 0] == c[:, 1]) | (c[:, 1] == c[:, 2]) | (c[:, 0] == c[:, 2]),
                        (np.diff(np.sort(c, axis=1), axis=1) == 0).any(axis=1))
    if repeated.any():
        f = int(np.flatnonzero(repeated)[0])
        raise mesh.error(f, f"the face is degenerate: two of its corners are one vertex (closer "
                         f"than the merging tolerance); {int(repeated.sum())} such face(s): "
                         "remove them or give a smaller merge tolerance")
    nxt = np.where(tri[:, None], c[:, [1, 2, 0, 1]], c[:, [1, 2, 3, 0]])
    prv = np.where(tri[:, None], c[:, [2, 0, 1, 2]], c[:, [3, 0, 1, 2]])
    e1, e2 = x[nxt] - x[c], x[prv] - x[c]
    cross = np.linalg.norm(np.cross(e1, e2), axis=2)
    scale = np.maximum(np.linalg.norm(e1, axis=2), np.linalg.norm(e2, axis=2))
    flat = (cross <= 1.0e-10 * scale ** 2).any(axis=1)
    if flat.any():
        f = int(np.flatnonzero(flat)[0])
        raise mesh.error(f, f"the face is degenerate: two of its edges are parallel (zero "
                         f"area); {int(flat.sum())} such face(s): remove them from the mesh")
    key = np.sort(faces, axis=1)   # a triangle's -1 sorts first
    _, first, inverse, counts = np.unique(key, axis=0, return_index=True,
                                          return_inverse=True, return_counts=True)
    if np.any(counts > 1):
        group = int(np.flatnonzero(counts > 1)[0])
        twins = np.flatnonzero(inverse.ravel() == group)
        raise mesh.error(int(twins[1]), f"the face repeats the face {mesh.label(int(twins[0]))}"
                         " (the same vertices): remove one of them")


def _orient(mesh: SurfaceMesh, blank_side: ArrayLike, blank_point: ArrayLike | None
            ) -> SurfaceMesh:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    from ddpy.geometry.mesh_normals import face_normals, mesh_topology

    x, faces = mesh.vertices, mesh.faces.copy()
    topology = mesh_topology(faces, len(x))
    if np.any(topology.counts > 2):
        e = int(np.flatnonzero(topology.counts > 2)[0])
        a, b = topology.edges[e]
        raise mesh.error(int(topology.edge_faces[e, 0]), f"non-manifold edge from "
                         f"{point_text(x[a])} to {point_text(x[b])}: {topology.counts[e]} faces "
                         "share it (a surface edge has one or two): remove the faces that do "
                         "not belong to the tool surface")
    inner = np.flatnonzero(topology.counts == 2)
    f, g = topology.edge_faces[inner, 0], topology.edge_faces[inner, 1]
    a = topology.edges[inner, 0]
    # Whether each face runs the edge from its lower vertex: the same direction in both
    # faces means one of them must turn over.
    c = _corners(faces)

    def forward(face: NDArray[np.int64], edge: NDArray[np.int64]) -> NDArray[np.bool_]:
        k = np.argmax(topology.corner_edge[face] == edge[:, None], axis=1)
        return c[face, k] == a

    same = forward(f, inner) == forward(g, inner)
    sign = np.where(same, -1, 1)
    m = len(faces)
    graph = coo_matrix((np.ones(len(f)), (f, g)), shape=(m, m)).tocsr()
    graph = graph + graph.T
    n_parts, part = connected_components(graph, directed=False)
    signs = coo_matrix((np.concatenate([sign, sign]).astype(np.float64),
                        (np.concatenate([f, g]), np.concatenate([g, f]))), shape=(m, m)).tocsr()
    parity = np.zeros(m, dtype=np.int64)
    for p in range(n_parts):
        seed = int(np.flatnonzero(part == p)[0])
        order, predecessor = breadth_first_order(graph, seed, directed=False)
        parity[seed] = 1
        if len(order) < 2:
            continue
        step = np.asarray(signs[order[1:], predecessor[order[1:]]]).ravel().astype(np.int64)
        for i, s in zip(order[1:].tolist(), step.tolist(), strict=True):
            parity[i] = parity[predecessor[i]] * s
    conflict = parity[f] * parity[g] * sign < 0
    if conflict.any():
        e = int(np.flatnonzero(conflict)[0])
        raise mesh.error(int(f[e]), "the faces cannot be oriented consistently: going round "
                         "the surface turns it over (a Moebius band, or faces folded over "
                         "one another)")
    flip = parity < 0
    normal, area = face_normals(x, faces)
    normal[flip] *= -1
    if blank_point is None:
        d = np.asarray(blank_side, dtype=np.float64).reshape(3)
        d = np.broadcast_to(d / np.linalg.norm(d), normal.shape)
    else:
        centre = x[c].mean(axis=1)
        d = np.asarray(blank_point, dtype=np.float64).reshape(3) - centre
        d = d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
    alignment = np.einsum("ij,ij->i", normal, d)
    boundary_faces = np.zeros(m, dtype=bool)
    boundary_faces[topology.edge_faces[topology.counts == 1, 0]] = True
    for p in range(n_parts):
        rows = np.flatnonzero(part == p)
        mean = float((alignment[rows] * area[rows]).sum() / area[rows].sum())
        first = int(rows[0])
        if not boundary_faces[rows].any():
            raise mesh.error(first, f"the surface this face belongs to ({len(rows)} faces) is "
                             "closed (the skin of a solid): a tool surface is open, facing the "
                             "blank; keep only the working faces (--groups, or an Abaqus "
                             "*SURFACE on them)")
        if abs(mean) < AWAY_TOL:
            raise mesh.error(first, f"the surface this face belongs to ({len(rows)} faces) is "
                             "edge-on to the blank side (its normals are perpendicular to the "
                             "blank direction on average): give another blank side or a blank "
                             "point")
        if mean < 0.0:
            flip[rows] = ~flip[rows]
    faces[flip] = np.where(faces[flip, 3:] < 0, faces[flip][:, [0, 2, 1, 3]],
                           faces[flip][:, [0, 3, 2, 1]])
    return replace(mesh, faces=faces, flipped=int(flip.sum()))
