"""Nagata and facet tool models from a tool surface mesh (STL, Abaqus, Gmsh, ...).

:func:`build_mesh_tool_models` reads a mesh (:mod:`ddpy.cad.surface_mesh`: merged, checked,
oriented towards the blank), gives every face corner a normal and writes
``<name>.nagata.tool`` and ``<name>.facets.tool`` with the same writer and format as the CAD
path (:mod:`ddpy.cad.build`), so ``ddpy run`` takes them unchanged. The facet model is the
same mesh with flat facets: a mesh has one density.

The normals are estimated from the mesh (:mod:`ddpy.geometry.mesh_normals`: creases by
dihedral angle, one normal per smooth sheet at a crease vertex), or, given the CAD the mesh
was made from, taken from the exact CAD surface as the CAD path does: each face is assigned
the nearest CAD face and each of its corners the CAD normal at the vertex's projection on
it; where CAD faces meet tangentially (within 0.1 degree) a vertex keeps their mean.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy.cad.build import _PLAIN_NAME, TANGENT_ANGLE, _ranges, _vector, output_folder
from ddpy.cad.mesh import point_text
from ddpy.cad.read import CAD_SUFFIXES, CadError, gmsh_session, load_cad
from ddpy.cad.surface_mesh import (
    AWAY_TOL,
    DEFAULT_MERGE_TOL,
    MeshFileError,
    SurfaceMesh,
    prepare_surface_mesh,
    read_surface_mesh,
)
from ddpy.geometry.mesh_normals import (
    DEFAULT_CREASE_ANGLE,
    DEFAULT_ESTIMATOR,
    ESTIMATORS,
    estimate_normals,
    face_normals,
)
from ddpy.geometry.surfaces import NagataSurface
from ddpy.io.toolfile import ToolModel, write_tool

__all__ = ["MESH_MODELS", "build_mesh_tool_models", "build_surface_tool_models", "is_cad_file",
           "mesh_corner_normals"]

MESH_MODELS = ("nagata", "facets")
#: A mesh vertex farther than this many median edge lengths from its CAD face does not lie
#: on the CAD: the two do not match.
CAD_MATCH_TOL = 0.01


def is_cad_file(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is read as CAD (STEP, IGES, BREP) rather than as a mesh."""
    return Path(path).suffix.lower() in CAD_SUFFIXES


def mesh_corner_normals(mesh: SurfaceMesh, estimator: str = DEFAULT_ESTIMATOR,
                        crease_angle: float = DEFAULT_CREASE_ANGLE,
                        blank_side: ArrayLike = (0.0, 0.0, 1.0),
                        blank_point: ArrayLike | None = None) -> NDArray[np.float64]:
    """Estimated normals per face corner (m, 4, 3) of a prepared mesh; refuses a region
    bounded by creases that faces away from the blank."""
    try:
        result = estimate_normals(mesh.vertices, mesh.faces, estimator, crease_angle)
    except ValueError as error:
        raise MeshFileError(f"{mesh.path}: {error}") from None
    # The smooth regions: faces joined across edges that are not creases.
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    topology = result.topology
    smooth = (topology.counts == 2) & ~result.crease
    f, g = topology.edge_faces[smooth, 0], topology.edge_faces[smooth, 1]
    m = len(mesh.faces)
    _, region = connected_components(coo_matrix((np.ones(len(f)), (f, g)), shape=(m, m)),
                                     directed=False)
    normal, area = face_normals(mesh.vertices, mesh.faces)
    direction = _towards_blank(mesh, blank_side, blank_point)
    alignment = np.einsum("ij,ij->i", normal, direction) * area
    total = np.bincount(region, alignment) / np.bincount(region, area)
    away = np.flatnonzero(total < -AWAY_TOL)
    if away.size:
        face = int(np.flatnonzero(region == away[0])[0])
        raise mesh.error(face, f"the region of {int((region == away[0]).sum())} faces around "
                         "this one (bounded by creases) faces away from the blank once oriented"
                         " like the faces it shares edges with: the tool cannot face the blank "
                         "side everywhere; check the blank side or leave those faces out")
    return result.corner_normals


def _towards_blank(mesh: SurfaceMesh, blank_side: ArrayLike, blank_point: ArrayLike | None
                   ) -> NDArray[np.float64]:
    c = np.where(mesh.faces < 0, mesh.faces[:, :1], mesh.faces)
    if blank_point is None:
        d = np.asarray(blank_side, dtype=np.float64)
        return np.broadcast_to(d / np.linalg.norm(d), (len(c), 3))
    d = np.asarray(blank_point, dtype=np.float64) - mesh.vertices[c].mean(axis=1)
    return d / np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]


def cad_corner_normals(mesh: SurfaceMesh, cad: str | os.PathLike[str],
                       faces: Sequence[int] | None = None
                       ) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Normals per face corner (m, 4, 3) from the CAD a prepared mesh was made from, and the
    CAD face of each mesh face (inside :func:`gmsh_session`)."""
    import gmsh

    from ddpy.cad.geometry import closest_points

    available = load_cad(cad)
    selected = list(available) if faces is None else [int(f) for f in faces]
    missing = sorted(set(selected) - set(available))
    if missing:
        raise CadError(f"{cad}: face {missing[0]} is not in the model (faces: "
                       f"{_ranges(available)})")
    x, elems = mesh.vertices, mesh.faces
    corners = np.where(elems < 0, elems[:, :1], elems)
    centres = x[corners].mean(axis=1)
    lengths = np.linalg.norm(x[corners] - x[np.roll(corners, -1, axis=1)], axis=2)
    size = float(np.median(lengths[lengths > 0]))
    best = np.full(len(elems), np.inf)
    tag = np.zeros(len(elems), dtype=np.int64)
    for face in selected:
        closest, _ = closest_points(face, centres)
        d = np.linalg.norm(closest - centres, axis=1)
        better = d < best
        best[better], tag[better] = d[better], face
    normal, _ = face_normals(x, elems)
    corner = np.empty((len(elems), 4, 3))
    per_vertex: dict[int, dict[int, NDArray[np.float64]]] = {}
    for face in np.unique(tag):
        rows = np.flatnonzero(tag == face)
        vertices = np.unique(corners[rows])
        closest, uv = closest_points(int(face), x[vertices])
        far = np.linalg.norm(closest - x[vertices], axis=1)
        if far.max() > CAD_MATCH_TOL * size + 1e-9:
            k = int(np.argmax(far))
            raise CadError(f"{mesh.path}: the vertex at {point_text(x[vertices[k]])} lies "
                           f"{far[k]:.3g} mm from CAD face {int(face)} of {cad} (more than "
                           f"{CAD_MATCH_TOL:g} of the median edge, {size:.3g} mm): the mesh was "
                           "not made from this CAD (or from other faces of it)")
        n = np.asarray(gmsh.model.getNormal(int(face), uv.ravel())).reshape(-1, 3)
        lookup = np.searchsorted(vertices, corners[rows])
        if float(np.einsum("ckx,cx->", n[lookup], normal[rows])) < 0.0:
            n = -n   # the CAD face's own orientation against the mesh's (towards the blank)
        corner[rows] = n[lookup]
        for v, nv in zip(vertices.tolist(), n, strict=True):
            per_vertex.setdefault(v, {})[int(face)] = nv
    cos_tangent = np.cos(np.radians(TANGENT_ANGLE))
    for v, by_face in per_vertex.items():
        if len(by_face) < 2:
            continue
        items = list(by_face.items())
        for face, n in items:   # tangent faces share the mean of their normals
            close = [m for _, m in items if float(m @ n) >= cos_tangent]
            mean = np.sum(close, axis=0)
            mean /= np.linalg.norm(mean)
            rows, k = np.nonzero((corners == v) & (tag[:, None] == face))
            corner[rows, k] = mean
    dots = np.einsum("fkx,fx->fk", corner, normal)
    dots[elems[:, 3] < 0, 3] = 1.0
    bad = np.flatnonzero((dots <= 0.0).any(axis=1))
    if bad.size:
        raise mesh.error(int(bad[0]), f"the CAD normal of face {int(tag[bad[0]])} points against "
                         "this face at a corner: the mesh folds over the CAD surface there")
    return corner, tag


def build_mesh_tool_models(
    mesh: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    name: str,
    models: Sequence[str] = MESH_MODELS,
    blank_side: ArrayLike = (0.0, 0.0, 1.0),
    blank_point: ArrayLike | None = None,
    estimator: str = DEFAULT_ESTIMATOR,
    crease_angle: float = DEFAULT_CREASE_ANGLE,
    merge_tol: float = DEFAULT_MERGE_TOL,
    groups: Sequence[str] | None = None,
    cad: str | os.PathLike[str] | None = None,
    cad_faces: Sequence[int] | None = None,
) -> dict[str, Path]:
    """Write ``<name>.nagata.tool`` and ``<name>.facets.tool`` from a tool mesh file.

    ``groups`` keeps only the named groups of the file (STL solids, Abaqus *SURFACE or ELSET
    names, Gmsh physical names); ``merge_tol`` is the distance below which vertices merge, as
    a fraction of the median edge length; ``estimator`` (:data:`ESTIMATORS`) and
    ``crease_angle`` (degrees) set the estimated normals, unless ``cad`` gives the CAD file the
    mesh was made from (``cad_faces``: which of its faces). Returns the paths written."""
    if "bezier" in models:
        raise ValueError("a Bezier model is fitted to CAD faces: it cannot be built from a mesh "
                         "(build it from the CAD file, or leave 'bezier' out of the models)")
    unknown = [m for m in models if m not in MESH_MODELS]
    if unknown or not models:
        raise ValueError(f"models must be among {MESH_MODELS} for a mesh, got {list(models)}")
    if estimator not in ESTIMATORS:
        raise ValueError(f"the normal estimator must be one of {', '.join(ESTIMATORS)}, got "
                         f"'{estimator}'")
    if not 0.0 < crease_angle <= 180.0:
        raise ValueError(f"crease_angle must lie in (0, 180] degrees, got {crease_angle:g}")
    if not _PLAIN_NAME.fullmatch(name):
        raise ValueError(f"name must be a plain file name (letters, digits, '_', '.', '-', "
                         f"not starting with '.'), got '{name}'")
    side = _vector(blank_side, "blank_side")
    point = None if blank_point is None else _vector(blank_point, "blank_point")
    if point is None and np.linalg.norm(side) == 0.0:
        raise ValueError("blank_side must not be the zero vector")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: a file is there; the output must be a folder")

    surface_mesh = prepare_surface_mesh(read_surface_mesh(mesh, groups), merge_tol, side, point)
    return _write_models(surface_mesh, out, name, models, side, point, estimator, crease_angle,
                         cad, cad_faces)


def build_surface_tool_models(
    surface_mesh: SurfaceMesh,
    out_dir: str | os.PathLike[str],
    name: str,
    models: Sequence[str] = MESH_MODELS,
    blank_side: ArrayLike = (0.0, 0.0, 1.0),
    estimator: str = DEFAULT_ESTIMATOR,
    crease_angle: float = DEFAULT_CREASE_ANGLE,
    merge_tol: float = DEFAULT_MERGE_TOL,
) -> dict[str, Path]:
    """Write ``<name>.nagata.tool`` and ``<name>.facets.tool`` from a surface mesh already
    read (an importer's tool faces), as :func:`build_mesh_tool_models` does from a file."""
    side = _vector(blank_side, "blank_side")
    prepared = prepare_surface_mesh(surface_mesh, merge_tol, side, None)
    return _write_models(prepared, Path(out_dir), name, models, side, None, estimator,
                         crease_angle, None, None)


def _write_models(surface_mesh: SurfaceMesh, out: Path, name: str, models: Sequence[str],
                  side: NDArray[np.float64], point: NDArray[np.float64] | None, estimator: str,
                  crease_angle: float, cad: str | os.PathLike[str] | None,
                  cad_faces: Sequence[int] | None) -> dict[str, Path]:
    if cad is None:
        corner = mesh_corner_normals(surface_mesh, estimator, crease_angle, side, point)
        tags, source = surface_mesh.groups, None
    else:
        with gmsh_session():
            import gmsh

            previous = gmsh.model.getCurrent()
            try:
                corner, tags = cad_corner_normals(surface_mesh, cad, cad_faces)
            finally:
                if gmsh.model.getCurrent() == Path(cad).stem:
                    gmsh.model.remove()
                    try:
                        gmsh.model.setCurrent(previous)
                    except Exception:  # noqa: BLE001 - the previous model may be gone
                        pass
        source = str(Path(cad).resolve())
    try:
        surface = NagataSurface(surface_mesh.vertices, corner, surface_mesh.faces, smooth=True)
    except ValueError as error:  # a defect the checks above missed: still the file's
        raise MeshFileError(f"{surface_mesh.path}: {error}") from None
    nagata = ToolModel(name, "nagata", surface, tags, source)

    paths: dict[str, Path] = {}
    with output_folder(out) as target:
        if "nagata" in models:
            paths["nagata"] = write_tool(target(f"{name}.nagata.tool"), nagata)
        if "facets" in models:
            paths["facets"] = write_tool(target(f"{name}.facets.tool"), nagata.facets())
    return paths
