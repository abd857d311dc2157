"""Tool models from CAD through gmsh's OpenCASCADE: Nagata, facet and Bezier tool files.

:func:`build_tool_models` reads a STEP, IGES or BREP file (or takes the faces of the current
gmsh model) and writes three tool files (``docs/tool-files.md``):

- ``<name>.nagata.tool``: every CAD face meshed in quadrilaterals (structured on 4-sided faces)
  or triangles, ``patches_per_arc`` elements per 90 degrees along curved edges and edges of at
  most ``size`` along straight ones; vertex normals from the exact CAD surface, one per CAD face
  at crease vertices; all faces oriented towards the blank;
- ``<name>.facets.tool``: the same construction from its own mesh, ``facets_per_arc`` per 90
  degrees (the CAD is meshed twice when the two densities differ);
- ``<name>.bezier.tool``: every CAD face fitted by non-rational Bezier patches of degree <= 6,
  split until they deviate from the CAD surface by less than ``bezier_tol``.

Errors (:class:`CadError`) name the CAD file and the face.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy.surfaces import BezierSurface, NagataSurface
from ddpy.toolfile import ToolModel, write_tool

__all__ = ["CadError", "CAD_SUFFIXES", "ToolBuilder", "build_tool_models", "gmsh_session",
           "load_cad", "quiet"]

CAD_SUFFIXES = {".step": "STEP", ".stp": "STEP", ".iges": "IGES", ".igs": "IGES",
                ".brep": "BREP", ".brp": "BREP"}
#: Face normals at a shared vertex within this angle (degrees) are one normal (tangent faces).
TANGENT_ANGLE = 0.1
#: A face whose normals point away from the blank on average (mean n . d < -tol) fails.
AWAY_TOL = 1.0e-3
MODELS = ("nagata", "facets", "bezier")


class CadError(ValueError):
    """A CAD model that cannot become a tool model; the message names the file and face."""


# ------------------------------------------------------------------------------------ gmsh


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Silence what OpenCASCADE prints on the process's stdout (STEP and IGES writers)."""
    try:
        sys.stdout.flush()
        saved = os.dup(1)
    except (OSError, ValueError):  # no real stdout (captured): nothing to silence
        yield
        return
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


@contextlib.contextmanager
def gmsh_session() -> Iterator[None]:
    """Initialize gmsh without output if it is not running; finalize only what was started."""
    import gmsh

    own = not gmsh.isInitialized()
    if own:
        gmsh.initialize(["", "-nopopup"], readConfigFiles=False, interruptible=False)
    terminal = gmsh.option.getNumber("General.Terminal")
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield
    finally:
        if own:
            gmsh.finalize()
        else:
            gmsh.option.setNumber("General.Terminal", terminal)


def load_cad(path: str | os.PathLike[str]) -> list[int]:
    """Import a CAD file into a new gmsh model (inside :func:`gmsh_session`); its face tags.

    Faces that touch are made to share their edges (``removeAllDuplicates``), so the same file
    always gives the same tags: tool files refer to faces by these tags.
    """
    import gmsh

    path = Path(path)
    kind = CAD_SUFFIXES.get(path.suffix.lower())
    if kind is None:
        raise CadError(f"{path}: unknown CAD format '{path.suffix}': expected STEP (.step, "
                       ".stp), IGES (.iges, .igs) or BREP (.brep)")
    if not path.is_file():
        raise CadError(f"{path}: no such CAD file")
    gmsh.model.add(path.stem)
    occ = gmsh.model.occ
    try:
        with quiet():
            occ.importShapes(str(path))
            occ.removeAllDuplicates()
            occ.synchronize()
    except Exception as error:  # gmsh raises a bare Exception with its last message
        raise CadError(f"{path}: cannot read the {kind} file: {error}") from None
    tags = [t for _, t in gmsh.model.getEntities(2)]
    if not tags:
        raise CadError(f"{path}: the {kind} file holds no faces (surfaces): nothing to model")
    return tags


# --------------------------------------------------------------------------------- builder


@dataclass
class _Mesh:
    """A surface mesh of the selected faces, oriented and with per-corner normals."""

    vertices: NDArray[np.float64]        # (n, 3)
    elements: NDArray[np.int64]          # (m, 4), -1 last for a triangle
    element_face: NDArray[np.int64]      # (m,) CAD face tag
    corner_normals: NDArray[np.float64]  # (m, 4, 3)
    flips: dict[int, int]                # CAD face tag -> +1 / -1 (raw CAD normal to blank side)


class ToolBuilder:
    """Builds tool models from faces of the current gmsh model (inside :func:`gmsh_session`).

    ``label`` names the CAD in error messages; ``blank_side`` is a direction the blank lies
    towards, ``blank_point`` (if given, used instead) a point on the blank side.
    """

    def __init__(self, faces: Sequence[int], label: str,
                 blank_side: ArrayLike = (0.0, 0.0, 1.0),
                 blank_point: ArrayLike | None = None) -> None:
        self.faces = [int(f) for f in faces]
        self.label = label
        self.blank_point = None if blank_point is None else _vector(blank_point, "blank_point")
        self.blank_side = _vector(blank_side, "blank_side")
        if self.blank_point is None and np.linalg.norm(self.blank_side) == 0.0:
            raise ValueError("blank_side must not be the zero vector")
        if self.blank_point is None:
            self.blank_side = self.blank_side / np.linalg.norm(self.blank_side)
        self.flips: dict[int, int] | None = None
        #: Largest true distance (mm) of the Bezier patches from each face, after a fit.
        self.bezier_deviation: dict[int, float] = {}

    def error(self, face: int | None, message: str) -> CadError:
        where = f"{self.label}: face {face}" if face is not None else self.label
        return CadError(f"{where}: {message}")

    def towards_blank(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """Unit directions (k, 3) from ``points`` towards the blank."""
        if self.blank_point is None:
            return np.broadcast_to(self.blank_side, points.shape)
        d = self.blank_point - points
        return d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]

    # -------------------------------------------------------------------------- meshing

    def mesh(self, per_arc: int, element: str = "quad", size: float | None = None) -> _Mesh:
        """Mesh the faces, orient them towards the blank and give each corner its normal."""
        import gmsh

        if element not in ("quad", "tri"):
            raise ValueError(f"element must be 'quad' or 'tri', got {element!r}")
        if per_arc < 1:
            raise ValueError(f"the number of patches per arc must be >= 1, got {per_arc}")
        if size is not None and not size > 0.0:
            raise ValueError(f"size must be positive (mm), got {size}")
        _set_mesh_sizes(self.faces, per_arc, element, size)
        gmsh.model.mesh.clear()
        failure = ""
        try:
            gmsh.model.mesh.generate(2)
        except Exception as error:
            failure = f": {error}"
        nodes: dict[int, tuple[NDArray, NDArray, NDArray]] = {}
        elements: dict[int, NDArray[np.int64]] = {}
        for face in self.faces:
            tags, coord, uv = gmsh.model.mesh.getNodes(2, face, includeBoundary=True,
                                                       returnParametricCoord=True)
            types, _, connectivity = gmsh.model.mesh.getElements(2, face)
            if len(tags) == 0 or sum(len(c) for c in connectivity) == 0:
                raise self.error(face, f"cannot be meshed{failure or ' (gmsh made no elements)'}")
            coord = np.asarray(coord).reshape(-1, 3)
            uv = np.asarray(uv)
            if uv.size != 2 * len(tags):
                uv = np.asarray(gmsh.model.getParametrization(2, face, coord.ravel()))
            nodes[face] = (np.asarray(tags, dtype=np.int64), coord, uv.reshape(-1, 2))
            elements[face] = _element_array(self, face, types, connectivity)
        return self._assemble(nodes, elements)

    def _assemble(self, nodes: dict[int, tuple[NDArray, NDArray, NDArray]],
                  elements: dict[int, NDArray[np.int64]]) -> _Mesh:
        import gmsh

        all_tags = np.unique(np.concatenate([n[0] for n in nodes.values()]))
        vertices = np.empty((len(all_tags), 3))
        raw: dict[int, NDArray[np.float64]] = {}   # face -> raw CAD normal per local node
        local: dict[int, NDArray[np.int64]] = {}   # face -> global index per local node
        blocks, block_face = [], []
        for face in self.faces:
            tags, coord, uv = nodes[face]
            index = np.searchsorted(all_tags, tags)
            vertices[index] = coord
            normal = np.asarray(gmsh.model.getNormal(face, uv.ravel())).reshape(-1, 3)
            length = np.linalg.norm(normal, axis=1)
            bad = np.flatnonzero(~(np.abs(length - 1.0) < 1e-6))
            if bad.size:
                x = coord[bad[0]]
                raise self.error(face, f"the surface normal is undefined at ({x[0]:.6g}, "
                                 f"{x[1]:.6g}, {x[2]:.6g}) (a singular point): split the face")
            raw[face], local[face] = normal, index
            conn = elements[face]
            order = np.argsort(tags)
            position = order[np.searchsorted(tags[order], np.maximum(conn, 0))]
            conn_local = np.where(conn < 0, -1, position)
            blocks.append(_orient_elements(self, face, coord, normal, conn_local, index))
            block_face.append(np.full(len(conn), face, dtype=np.int64))
        elems = np.concatenate(blocks)
        elem_face = np.concatenate(block_face)
        if self.flips is None:
            self.flips = self._orientation(vertices, elems, elem_face, raw, local)
        flips = self.flips
        flip_elem = np.array([flips[f] for f in elem_face]) < 0
        elems[flip_elem] = _reverse(elems[flip_elem])
        corner = self._corner_normals(len(vertices), elems, elem_face,
                                      {f: flips[f] * raw[f] for f in self.faces}, local)
        return _Mesh(vertices, elems, elem_face, corner, dict(flips))

    def _orientation(self, vertices: NDArray, elems: NDArray, elem_face: NDArray,
                     raw: dict[int, NDArray], local: dict[int, NDArray]) -> dict[int, int]:
        """+1 / -1 per face: consistent through shared edges, seeded towards the blank."""
        relations = _face_relations(self, elems, elem_face, len(vertices))
        alignment = {}
        for face in self.faces:
            x = vertices[local[face]]
            alignment[face] = np.einsum("ij,ij->i", raw[face], self.towards_blank(x))
        flips: dict[int, int] = {}
        for component in _components(self.faces, relations):
            seed = max(component, key=lambda f: abs(float(alignment[f].mean())))
            mean = float(alignment[seed].mean())
            if abs(mean) < AWAY_TOL:
                raise self.error(seed, "is edge-on to the blank side (its normals are "
                                 "perpendicular to blank_side): give another blank_side or a "
                                 "blank point")
            parity = _propagate(self, seed, component, relations)
            for face in component:
                flips[face] = parity[face] * (1 if mean > 0 else -1)
                if flips[face] * float(alignment[face].mean()) < -AWAY_TOL:
                    raise self.error(face, f"points away from the blank once oriented like face "
                                     f"{seed} (they share edges): the tool cannot face the blank"
                                     f" side {self._blank_text()} everywhere; check blank_side or"
                                     " leave this face out")
        return flips

    def _blank_text(self) -> str:
        if self.blank_point is not None:
            return "point " + ",".join(f"{v:g}" for v in self.blank_point)
        return "direction " + ",".join(f"{v:g}" for v in self.blank_side)

    def _corner_normals(self, n_vertices: int, elems: NDArray, elem_face: NDArray,
                        oriented: dict[int, NDArray], local: dict[int, NDArray]) -> NDArray:
        """One normal per (vertex, face); averaged where faces meet tangentially."""
        cos_tangent = np.cos(np.radians(TANGENT_ANGLE))
        per_vertex: dict[int, list[tuple[int, NDArray]]] = {}
        count = np.zeros(n_vertices, dtype=np.int64)
        for face in self.faces:
            count[local[face]] += 1
        normal_of: dict[int, NDArray[np.float64]] = {}   # face -> (n_vertices, 3), sparse use
        for face in self.faces:
            table = np.zeros((n_vertices, 3))
            table[local[face]] = oriented[face]
            normal_of[face] = table
            for i, n in zip(local[face][count[local[face]] > 1], oriented[face][
                    count[local[face]] > 1], strict=True):
                per_vertex.setdefault(int(i), []).append((face, n))
        for i, entries in per_vertex.items():
            groups: list[list[tuple[int, NDArray]]] = []
            for face, n in entries:
                for group in groups:
                    if float(group[0][1] @ n) >= cos_tangent:
                        group.append((face, n))
                        break
                else:
                    groups.append([(face, n)])
            for group in groups:
                mean = np.sum([n for _, n in group], axis=0)
                mean /= np.linalg.norm(mean)
                for face, _ in group:
                    normal_of[face][i] = mean
        corner = np.empty((len(elems), 4, 3))
        padded = np.where(elems < 0, elems[:, :1], elems)
        for face in self.faces:
            rows = elem_face == face
            corner[rows] = normal_of[face][padded[rows]]
        return corner

    # ---------------------------------------------------------------------------- models

    def mesh_model(self, name: str, per_arc: int, element: str = "quad",
                   size: float | None = None, smooth: bool = True,
                   source: str | None = None) -> ToolModel:
        """A Nagata (``smooth``) or facet model from a mesh of ``per_arc`` patches per arc."""
        mesh = self.mesh(per_arc, element, size)
        surface = NagataSurface(mesh.vertices, mesh.corner_normals, mesh.elements, smooth=smooth)
        return ToolModel(name, "nagata" if smooth else "facets", surface, mesh.element_face,
                         source)

    def bezier_model(self, name: str, tol: float = 1.0e-3, angle_tol: float = 0.01,
                     source: str | None = None) -> ToolModel:
        """Bezier patches (degree <= 6) within ``tol`` mm and ``angle_tol`` degrees (normal)
        of every face."""
        from ddpy.bezier_fit import fit_face

        if not tol > 0.0:
            raise ValueError(f"bezier_tol must be positive (mm), got {tol}")
        if not 0.0 < angle_tol < 90.0:
            raise ValueError(f"bezier_angle_tol must be in (0, 90) degrees, got {angle_tol}")
        if self.flips is None:
            self.mesh(2)
        assert self.flips is not None
        nets, tags = [], []
        for face in self.faces:
            for net in fit_face(self, face, tol, angle_tol, self.flips[face]):
                nets.append(net)
                tags.append(face)
        return ToolModel(name, "bezier", BezierSurface(nets), np.array(tags), source)


def _vector(value: ArrayLike, name: str) -> NDArray[np.float64]:
    v = np.asarray(value, dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be 3 finite numbers (x, y, z), got {value!r}")
    return v


def _curve_shape(curve: int) -> tuple[float, float]:
    """(turning angle in radians, length) of a curve, from 129 samples."""
    import gmsh

    lo, hi = gmsh.model.getParametrizationBounds(1, curve)
    t = np.linspace(lo[0], hi[0], 129)
    x = np.asarray(gmsh.model.getValue(1, curve, t)).reshape(-1, 3)
    length = float(np.linalg.norm(np.diff(x, axis=0), axis=1).sum())
    d = np.asarray(gmsh.model.getDerivative(1, curve, t)).reshape(-1, 3)
    norm = np.linalg.norm(d, axis=1)
    if length == 0.0 or not np.all(norm > 0.0):
        return 0.0, length
    tangent = d / norm[:, None]
    cosines = np.clip(np.einsum("ij,ij->i", tangent[1:], tangent[:-1]), -1.0, 1.0)
    return float(np.arccos(cosines).sum()), length


def _set_mesh_sizes(faces: list[int], per_arc: int, element: str, size: float | None) -> None:
    """Divisions of every edge, structured 4-sided faces, recombination for quadrilaterals."""
    import gmsh

    boundary: dict[int, list[int]] = {}
    shape: dict[int, tuple[float, float]] = {}
    for face in faces:
        curves = [abs(c) for _, c in gmsh.model.getBoundary([(2, face)], combined=False,
                                                            oriented=True)]
        boundary[face] = curves
        for c in curves:
            if c not in shape:
                shape[c] = _curve_shape(c)
    scale = max((s[1] for s in shape.values()), default=1.0)
    divisions: dict[int, int] = {}
    for c, (angle, length) in shape.items():
        if length <= 1e-9 * scale:
            continue  # a degenerate edge (the pole of a sphere)
        if angle > 1e-6:  # curved: by the angle only
            divisions[c] = max(1, int(np.ceil(per_arc * angle / (np.pi / 2) - 1e-6)))
        else:             # straight: by the size, one element without it
            divisions[c] = 1 if size is None else max(1, int(np.ceil(length / size - 1e-6)))
    structured = [f for f, cs in boundary.items()
                  if len(cs) == 4 and all(c in divisions for c in cs)]
    changed = True
    while changed:  # opposite edges of a structured face need the same division
        changed = False
        for f in structured:
            cs = boundary[f]
            for a, b in ((cs[0], cs[2]), (cs[1], cs[3])):
                if divisions[a] != divisions[b]:
                    divisions[a] = divisions[b] = max(divisions[a], divisions[b])
                    changed = True
    for c, n in divisions.items():
        gmsh.model.mesh.setTransfiniteCurve(c, n + 1)
    for f in faces:
        if f in structured:
            gmsh.model.mesh.setTransfiniteSurface(f)
        if element == "quad":
            gmsh.model.mesh.setRecombine(2, f)
    gmsh.option.setNumber("Mesh.Algorithm", 8 if element == "quad" else 6)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 4 * per_arc)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size if size is not None else 1e22)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    # Only the selected faces (and their edges) are meshed.
    gmsh.model.setVisibility(gmsh.model.getEntities(), 0)
    gmsh.model.setVisibility([(2, f) for f in faces], 1, recursive=True)
    gmsh.option.setNumber("Mesh.MeshOnlyVisible", 1)


def _element_array(builder: ToolBuilder, face: int, types: Sequence[int],
                   connectivity: Sequence[NDArray]) -> NDArray[np.int64]:
    blocks = []
    for kind, conn in zip(types, connectivity, strict=True):
        conn = np.asarray(conn, dtype=np.int64)
        if kind == 3:      # 4-node quadrangle
            blocks.append(conn.reshape(-1, 4))
        elif kind == 2:    # 3-node triangle
            tri = conn.reshape(-1, 3)
            blocks.append(np.column_stack([tri, np.full(len(tri), -1)]))
        else:
            raise builder.error(face, f"gmsh made elements of type {kind}: expected linear "
                                "triangles and quadrangles")
    return np.concatenate(blocks)


def _reverse(elems: NDArray[np.int64]) -> NDArray[np.int64]:
    """The same elements ordered the other way round (first vertex kept)."""
    tri = elems[:, 3] < 0
    return np.where(tri[:, None], elems[:, [0, 2, 1, 3]], elems[:, [0, 3, 2, 1]])


def _orient_elements(builder: ToolBuilder, face: int, coord: NDArray, normal: NDArray,
                     conn: NDArray[np.int64], index: NDArray[np.int64]) -> NDArray[np.int64]:
    """Global connectivity of a face, each element counter-clockwise about the raw CAD normal."""
    tri = conn[:, 3] < 0
    x = coord[np.where(tri[:, None], conn[:, [0, 1, 2, 2]], conn)]
    cross = np.cross(x[:, 2] - x[:, 0], np.where(tri[:, None], x[:, 2] - x[:, 1],
                                                  x[:, 3] - x[:, 1]))
    mean_normal = normal[np.where(tri[:, None], conn[:, [0, 1, 2, 2]], conn)].sum(axis=1)
    dots = np.einsum("ij,ij->i", cross, mean_normal)
    scale = np.linalg.norm(cross, axis=1) * np.linalg.norm(mean_normal, axis=1)
    if np.any(np.abs(dots) <= 1e-12 * np.maximum(scale, 1e-300)):
        raise builder.error(face, "has a degenerate (flat or folded) element: mesh it finer")
    result = np.where(conn < 0, -1, index[np.maximum(conn, 0)])
    backwards = dots < 0
    result[backwards] = _reverse(result[backwards])
    return result


def _face_relations(builder: ToolBuilder, elems: NDArray, elem_face: NDArray,
                    n_vertices: int) -> dict[tuple[int, int], int]:
    """For faces sharing a mesh edge: +1 if they agree in orientation, -1 if one must flip."""
    tri = elems[:, 3] < 0
    nxt = np.where(tri[:, None], elems[:, [1, 2, 0, 0]], elems[:, [1, 2, 3, 0]])
    a, b = elems.ravel(), nxt.ravel()
    face = np.repeat(elem_face, 4)
    keep = np.repeat(~tri, 4) | (np.tile(np.arange(4), len(elems)) < 3)
    a, b, face = a[keep], b[keep], face[keep]
    key = np.minimum(a, b) * n_vertices + np.maximum(a, b)
    forward = a < b
    order = np.lexsort((face, key))
    key, forward, face = key[order], forward[order], face[order]
    shared = np.flatnonzero((key[1:] == key[:-1]) & (face[1:] != face[:-1]))
    relations: dict[tuple[int, int], int] = {}
    for i in shared:
        f, g = int(face[i]), int(face[i + 1])
        sign = -1 if forward[i] == forward[i + 1] else 1
        pair = (min(f, g), max(f, g))
        if relations.setdefault(pair, sign) != sign:
            raise builder.error(f, f"and face {g} meet along edges in both orientations: they "
                                "cannot be oriented consistently (overlapping or folded faces)")
    return relations


def _components(faces: list[int], relations: dict[tuple[int, int], int]) -> list[list[int]]:
    neighbours: dict[int, list[int]] = {f: [] for f in faces}
    for f, g in relations:
        neighbours[f].append(g)
        neighbours[g].append(f)
    seen: set[int] = set()
    components = []
    for f in faces:
        if f in seen:
            continue
        stack, component = [f], []
        seen.add(f)
        while stack:
            h = stack.pop()
            component.append(h)
            for k in neighbours[h]:
                if k not in seen:
                    seen.add(k)
                    stack.append(k)
        components.append(component)
    return components


def _propagate(builder: ToolBuilder, seed: int, component: list[int],
               relations: dict[tuple[int, int], int]) -> dict[int, int]:
    neighbours: dict[int, list[tuple[int, int]]] = {f: [] for f in component}
    for (a, b), sign in relations.items():
        if a in neighbours:
            neighbours[a].append((b, sign))
            neighbours[b].append((a, sign))
    parity = {seed: 1}
    stack = [seed]
    while stack:
        f = stack.pop()
        for g, sign in neighbours[f]:
            want = parity[f] * sign
            if g not in parity:
                parity[g] = want
                stack.append(g)
            elif parity[g] != want:
                raise builder.error(g, "cannot be oriented consistently with its neighbours "
                                    "(the surface is not orientable, like a Moebius strip)")
    return parity


# ------------------------------------------------------------------------------ top level


def build_tool_models(
    cad: str | os.PathLike[str] | None,
    out_dir: str | os.PathLike[str],
    name: str,
    patches_per_arc: int = 4,
    facets_per_arc: int = 30,
    element: str = "quad",
    size: float | None = None,
    blank_side: ArrayLike = (0.0, 0.0, 1.0),
    blank_point: ArrayLike | None = None,
    bezier_tol: float = 1.0e-3,
    bezier_angle_tol: float = 0.01,
    faces: Sequence[int] | None = None,
    models: Sequence[str] = MODELS,
) -> dict[str, Path]:
    """Write ``<name>.nagata.tool``, ``<name>.facets.tool`` and ``<name>.bezier.tool``.

    ``cad`` is a STEP, IGES or BREP file, or None (or the ``gmsh.model`` module) for the faces
    of the current gmsh model. ``faces`` selects CAD face tags (default: all). Densities are
    per 90 degrees of arc along curved edges; ``size`` (mm) bounds straight edges (default:
    one element). Returns the paths written, by model.
    """
    unknown = [m for m in models if m not in MODELS]
    if unknown or not models:
        raise ValueError(f"models must be among {MODELS}, got {list(models)}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with gmsh_session(), _cad_model(cad) as (available, label, source):
        selected = list(available) if faces is None else [int(f) for f in faces]
        missing = sorted(set(selected) - set(available))
        if missing:
            raise CadError(f"{label}: face {missing[0]} is not in the model (faces: "
                           f"{_ranges(available)})")
        builder = ToolBuilder(selected, label, blank_side, blank_point)
        paths: dict[str, Path] = {}
        nagata = None
        if "nagata" in models or ("facets" in models and facets_per_arc == patches_per_arc):
            nagata = builder.mesh_model(name, patches_per_arc, element, size, True, source)
            if "nagata" in models:
                paths["nagata"] = write_tool(out / f"{name}.nagata.tool", nagata)
        if "facets" in models:
            if nagata is not None and facets_per_arc == patches_per_arc:
                facets = nagata.facets()
            else:
                if builder.flips is None:  # orientation comes from the coarser mesh
                    builder.mesh(min(patches_per_arc, facets_per_arc), element, size)
                facets = builder.mesh_model(name, facets_per_arc, element, size, False, source)
            paths["facets"] = write_tool(out / f"{name}.facets.tool", facets)
        if "bezier" in models:
            bezier = builder.bezier_model(name, bezier_tol, bezier_angle_tol, source)
            paths["bezier"] = write_tool(out / f"{name}.bezier.tool", bezier)
    return paths


@contextlib.contextmanager
def _cad_model(cad: str | os.PathLike[str] | None) -> Iterator[tuple[list[int], str, str | None]]:
    """(face tags, label for errors, source path) of a CAD file loaded into a model removed
    afterwards, or of the current gmsh model (``cad`` None or ``gmsh.model``)."""
    import gmsh

    if cad is None or cad is gmsh.model:
        available = [t for _, t in gmsh.model.getEntities(2)]
        label = f"gmsh model '{gmsh.model.getCurrent()}'"
        if not available:
            raise CadError(f"{label}: the model has no faces (surfaces): nothing to model")
        yield available, label, None
        return
    previous = gmsh.model.getCurrent()
    try:
        yield load_cad(cad), str(cad), str(Path(cad).resolve())
    finally:
        if gmsh.model.getCurrent() == Path(cad).stem:
            gmsh.model.remove()
            with contextlib.suppress(Exception):
                gmsh.model.setCurrent(previous)


def _ranges(tags: Sequence[int]) -> str:
    tags = sorted(tags)
    return ", ".join(str(t) for t in tags[:20]) + (", ..." if len(tags) > 20 else "")
