"""Tool models from CAD through gmsh's OpenCASCADE: Nagata, facet and Bezier tool files.

:func:`build_tool_models` reads a STEP, IGES or BREP file (or takes the faces of the current
gmsh model) and writes three tool files (``docs/tool-files.md``):

- ``<name>.nagata.tool``: every CAD face meshed in quadrilaterals (structured on 4-sided
  faces and on faces closed on a seam or a pole, :mod:`ddpy.cad.mesh`) or triangles,
  ``patches_per_arc`` elements per 90 degrees along curved edges and edges of at most ``size``
  along straight ones; vertex normals from the exact CAD surface, one per CAD face at crease
  vertices; all faces oriented towards the blank;
- ``<name>.facets.tool``: the same construction from its own mesh, ``facets_per_arc`` per 90
  degrees (the CAD is meshed twice when the two densities differ);
- ``<name>.bezier.tool``: every CAD face fitted by non-rational Bezier patches of degree <= 6,
  split until they deviate from the CAD surface by less than ``bezier_tol`` and
  ``bezier_angle_tol`` (:mod:`ddpy.cad.bezier_fit`).

Errors (:class:`CadError`) name the CAD file and the face.
"""
from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy.cad.bezier_fit import fit_face
from ddpy.cad.mesh import element_array, grid_mesh, point_text, prepare_mesh
from ddpy.cad.read import CadError, gmsh_session, load_cad
from ddpy.geometry.surfaces import BezierSurface, NagataSurface
from ddpy.io.toolfile import ToolModel, write_tool

__all__ = ["ToolBuilder", "build_tool_models"]

#: Face normals at a shared vertex within this angle (degrees) are one normal (tangent faces).
TANGENT_ANGLE = 0.1
#: A face whose normals point away from the blank on average (mean n . d < -tol) fails.
AWAY_TOL = 1.0e-3
MODELS = ("nagata", "facets", "bezier")
#: Smallest Bezier fitting tolerances: ten times the CAD kernel's precision, and a thousandth
#: of a degree.
MIN_BEZIER_TOL, MIN_BEZIER_ANGLE_TOL = 1.0e-6, 1.0e-3
#: A tool name becomes a file name in the output folder: no path separators, no '..'.
_PLAIN_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}")


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

    def mesh(self, per_arc: int, element: str = "quad", size: float | None = None,
             arc_size: float | None = None) -> _Mesh:
        """Mesh the faces, orient them towards the blank and give each corner its normal."""
        import gmsh

        if element not in ("quad", "tri"):
            raise ValueError(f"element must be 'quad' or 'tri', got {element!r}")
        if per_arc < 1:
            raise ValueError(f"the number of patches per arc must be >= 1, got {per_arc}")
        if size is not None and not size > 0.0:
            raise ValueError(f"size must be positive (mm), got {size}")
        if arc_size is not None and not arc_size > 0.0:
            raise ValueError(f"arc_size must be positive (mm), got {arc_size}")
        plan = prepare_mesh(self.faces, per_arc, element, size, arc_size)
        gmsh.model.mesh.clear()
        failure = ""
        try:
            gmsh.model.mesh.generate(2)
        except Exception as error:
            failure = f": {error}"
        next_tag = int(gmsh.model.mesh.getMaxNodeTag()) + 1
        nodes: dict[int, tuple[NDArray, NDArray, NDArray]] = {}
        elements: dict[int, NDArray[np.int64]] = {}
        for face in self.faces:
            if face in plan.grids:
                try:
                    tags, coord, uv, conn = grid_mesh(face, plan.grids[face], element, next_tag)
                except ValueError as error:
                    text = str(error)
                    raise self.error(face, text if text.startswith("the surface normal")
                                     else f"cannot be meshed: {text}") from None
                next_tag = max(next_tag, int(tags.max()) + 1)
                nodes[face], elements[face] = (tags, coord, uv), conn
                continue
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
            try:
                elements[face] = element_array(types, connectivity)
            except ValueError as error:
                raise self.error(face, str(error)) from None
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
                raise self.error(face, f"the surface normal is undefined at "
                                 f"{point_text(coord[bad[0]])} (a singular point such as a cone "
                                 "apex): split the face")
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
                   source: str | None = None, arc_size: float | None = None) -> ToolModel:
        """A Nagata (``smooth``) or facet model from a mesh of ``per_arc`` patches per arc."""
        mesh = self.mesh(per_arc, element, size, arc_size)
        surface = NagataSurface(mesh.vertices, mesh.corner_normals, mesh.elements, smooth=smooth)
        return ToolModel(name, "nagata" if smooth else "facets", surface, mesh.element_face,
                         source)

    def bezier_model(self, name: str, tol: float = 1.0e-3, angle_tol: float = 0.01,
                     source: str | None = None) -> ToolModel:
        """Bezier patches (degree <= 6) within ``tol`` mm and ``angle_tol`` degrees (normal)
        of every face."""
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
    corner_normals = normal[np.where(tri[:, None], conn[:, [0, 1, 2, 2]], conn)]
    corner_dots = np.einsum("icj,ij->ic", corner_normals, cross)
    dots = corner_dots.sum(axis=1)
    scale = np.linalg.norm(cross, axis=1)
    folded = (corner_dots.max(axis=1) > 1e-9 * scale) & (corner_dots.min(axis=1) < -1e-9 * scale)
    if np.any(scale == 0.0) or np.any(folded):
        bad = int(np.flatnonzero((scale == 0.0) | folded)[0])
        raise builder.error(face, f"the mesh has a degenerate or folded element near "
                            f"{point_text(x[bad].mean(axis=0))}: the surface turns too much "
                            "within one element; raise the number of patches per arc or give a "
                            "size")
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
    arc_size: float | None = None,
) -> dict[str, Path]:
    """Write ``<name>.nagata.tool``, ``<name>.facets.tool`` and ``<name>.bezier.tool``.

    ``cad`` is a STEP, IGES or BREP file, or None (or the ``gmsh.model`` module) for the faces
    of the current gmsh model. ``faces`` selects CAD face tags (default: all). Densities are
    per 90 degrees of arc along curved edges, whose elements ``arc_size`` (mm) also bounds
    if given (for both meshes: write the facets in a call of their own to give them another);
    ``size`` (mm) bounds straight edges (default: one element). Returns the paths written, by
    model.
    """
    unknown = [m for m in models if m not in MODELS]
    if unknown or not models:
        raise ValueError(f"models must be among {MODELS}, got {list(models)}")
    # Below the CAD kernel's own precision (1e-7 mm) a fit cannot be checked.
    if not (MIN_BEZIER_TOL <= bezier_tol <= 1e3):
        raise ValueError(f"bezier_tol must lie between {MIN_BEZIER_TOL:g} and 1000 mm, got "
                         f"{bezier_tol:g}")
    if not (MIN_BEZIER_ANGLE_TOL <= bezier_angle_tol <= 90.0):
        raise ValueError(f"bezier_angle_tol must lie between {MIN_BEZIER_ANGLE_TOL:g} and 90 "
                         f"degrees, got {bezier_angle_tol:g}")
    if not _PLAIN_NAME.fullmatch(name):
        raise ValueError(f"name must be a plain file name (letters, digits, '_', '.', '-', "
                         f"not starting with '.'), got '{name}'")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: a file is there; the output must be a folder")
    with output_folder(out) as target, gmsh_session(), \
            _cad_model(cad) as (available, label, source):
        selected = list(available) if faces is None else [int(f) for f in faces]
        missing = sorted(set(selected) - set(available))
        if missing:
            raise CadError(f"{label}: face {missing[0]} is not in the model (faces: "
                           f"{_ranges(available)})")
        builder = ToolBuilder(selected, label, blank_side, blank_point)
        paths: dict[str, Path] = {}
        nagata = None
        if "nagata" in models or ("facets" in models and facets_per_arc == patches_per_arc):
            nagata = builder.mesh_model(name, patches_per_arc, element, size, True, source,
                                        arc_size)
            if "nagata" in models:
                paths["nagata"] = write_tool(target(f"{name}.nagata.tool"), nagata)
        if "facets" in models:
            if nagata is not None and facets_per_arc == patches_per_arc:
                facets = nagata.facets()
            else:
                if builder.flips is None:  # orientation comes from the coarser mesh
                    builder.mesh(min(patches_per_arc, facets_per_arc), element, size, arc_size)
                facets = builder.mesh_model(name, facets_per_arc, element, size, False, source,
                                            arc_size)
            paths["facets"] = write_tool(target(f"{name}.facets.tool"), facets)
        if "bezier" in models:
            bezier = builder.bezier_model(name, bezier_tol, bezier_angle_tol, source)
            paths["bezier"] = write_tool(target(f"{name}.bezier.tool"), bezier)
    return paths


@contextlib.contextmanager
def output_folder(out: Path) -> Iterator[Callable[[str], Path]]:
    """Paths for files in the folder ``out``, made (with its missing parents) when the first
    is asked for; if the block then fails, the folders made are removed again, innermost
    first, as far as they are empty."""
    created: list[Path] = []

    def target(file: str) -> Path:
        if not out.is_dir():
            created.extend(_missing_folders(out))
            out.mkdir(parents=True, exist_ok=True)
        return out / file

    try:
        yield target
    except BaseException:
        for folder in reversed(created):
            try:
                folder.rmdir()
            except OSError:
                break
        raise


def _missing_folders(path: Path) -> list[Path]:
    """The folders of ``path`` (itself included) that do not exist, outermost first."""
    missing = []
    while not path.exists() and path != path.parent:
        missing.append(path)
        path = path.parent
    return missing[::-1]


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
