"""Vertex normals of a surface mesh, for Nagata patches built without the CAD.

A tool mesh (STL, Abaqus, Gmsh) carries no normals, or only flat facet normals; Nagata patches
need a normal at each vertex, and their accuracy rests on it (docs/mesh-tools.md). This module
estimates them from the mesh alone:

- **Creases and boundaries.** An edge shared by two faces whose normals differ by more than
  ``crease_angle`` degrees is a crease; an edge of one face is a boundary. Around a vertex the
  faces fall into *sheets*: the faces that follow one another across smooth edges. A vertex
  inside a smooth region has one sheet; a vertex on a crease has one per side, and each gets
  its own normal, used by the corners of its faces (``NagataSurface`` takes normals per face
  corner).
- **Estimators**, per sheet at a vertex, over the sheet's faces only:

  ======== ==============================================================================
  area     face normals weighted by the face areas
  angle    face normals weighted by the corner angles (Thurmer and Wuthrich 1998)
  max      corner cross products e1 x e2 / (|e1|^2 |e2|^2) (Max 1999): exact on a sphere
  quadric  weighted least-squares height function z = b x + c y + d x^2 + e xy + f y^2
           through the vertex, in the tangent plane of ``max``, fitted to the vertices of
           the faces around it (its 1-ring, the 2-ring where that has fewer than 6 points),
           then once more in the tangent plane of that fit: second order on any mesh
  cubic    the same with the cubic terms too (an osculating jet of order 3, Cazals and Pouget
           2003) on the 2-ring, the 3-ring where that has fewer than 18 points: third order
           on any mesh
  ======== ==============================================================================

  The fits weigh each point by 1 / r^4 (r its distance from the vertex), so the nearest lead;
  they use the sheet's own faces, so near a crease they see one side of it only. Where a
  neighbourhood is too small or too flat for a cubic (the corner of a structured grid) the
  quadric is fitted; where neither can be, or a fitted normal leans beyond a face of its sheet
  (it would turn that Nagata patch inside out), ``max`` is taken, and then ``angle``.

Faces are (m, 4) vertex indices with -1 last for a triangle, oriented consistently (every
shared edge run in opposite directions by its two faces): ``ddpy.cad.surface_mesh`` orients a
file's mesh before it gets here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy._validate import float_array, int_array

__all__ = ["DEFAULT_CREASE_ANGLE", "DEFAULT_ESTIMATOR", "ESTIMATORS", "MeshNormals",
           "MeshTopology", "estimate_normals", "face_normals", "mesh_topology"]

#: The estimators, cheapest first.
ESTIMATORS = ("area", "angle", "max", "quadric", "cubic")
#: Chosen by measurement (docs/benchmarks/mesh_normals.md): the smallest normal errors and the
#: highest order on every mesh measured.
DEFAULT_ESTIMATOR = "cubic"
#: Dihedral angle (degrees) above which an edge is a crease. Chosen by measurement
#: (docs/benchmarks/mesh_normals.md): above the largest angle between neighbouring faces of
#: smooth surfaces meshed with 4 elements per 90 degrees, structured or not, and well below
#: the 90 degrees of the edges of a tool's working face.
DEFAULT_CREASE_ANGLE = 40.0
#: Smallest cosine between a fitted normal and each face of its sheet: below it the fit falls
#: back (a Nagata patch needs n . face normal > 0 at every corner).
MIN_FACE_COSINE = 0.05
#: The fits each estimator tries in turn: (unknowns of the height function through the
#: vertex, 5 quadratic or 9 cubic; ring of faces whose vertices it fits).
_ATTEMPTS = {"quadric": ((5, 1), (5, 2), (5, 3)),
             "cubic": ((9, 2), (9, 3), (5, 1), (5, 2), (5, 3))}
#: Points wanted in a fit of 5 and of 9 unknowns (fewer, and a one-sided cubic at a boundary
#: of a structured grid, 14 points in its 2-ring, errs by degrees where the 3-ring's does
#: not).
_WANTED = {5: 6, 9: 18}
#: Largest ring of faces a fit may reach.
_MAX_RING = 3
#: Smallest ratio of the smallest to the largest eigenvalue of a fit's normal matrix.
_MIN_CONDITION = 1e-7


@dataclass
class MeshTopology:
    """Edges of a mesh: ``edges`` (e, 2) vertex pairs (lower first), ``edge_faces`` (e, 2)
    the faces on each edge (-1 for the second of a boundary edge), ``corner_edge`` (m, 4) the
    edge from corner k to the next (-1 for a triangle's fourth), ``counts`` (e,) faces per
    edge (1 boundary, 2 interior, more: a non-manifold edge, whose ``edge_faces`` lists two
    of them)."""

    edges: NDArray[np.int64]
    edge_faces: NDArray[np.int64]
    corner_edge: NDArray[np.int64]
    counts: NDArray[np.int64]


@dataclass
class MeshNormals:
    """Estimated normals: ``corner_normals`` (m, 4, 3) unit normals per face corner (a
    triangle's fourth repeats its first), ``corner_sheet`` (m, 4) the index of the (vertex,
    sheet) each corner belongs to (-1 for a triangle's fourth), ``sheet_vertex`` the vertex of
    each, ``crease`` (e,) whether each edge of ``topology`` is a crease (boundary edges are
    not), ``dihedral`` (e,) the angle between the normals of its faces (degrees, NaN on a
    boundary), ``fallbacks`` the sheets whose fit fell back to a weighted mean."""

    corner_normals: NDArray[np.float64]
    corner_sheet: NDArray[np.int64]
    sheet_vertex: NDArray[np.int64]
    topology: MeshTopology
    crease: NDArray[np.bool_]
    dihedral: NDArray[np.float64]
    estimator: str
    crease_angle: float
    fallbacks: int = 0

    @property
    def crease_vertices(self) -> NDArray[np.int64]:
        """Vertices with more than one normal (on a crease)."""
        counts = np.bincount(self.sheet_vertex)
        return np.flatnonzero(counts > 1)

    def vertex_normals(self, n_vertices: int) -> NDArray[np.float64]:
        """One normal per vertex (n, 3): the mean of its sheets' normals (unit)."""
        table = np.zeros((len(self.sheet_vertex), 3))
        valid = self.corner_sheet >= 0
        table[self.corner_sheet[valid]] = self.corner_normals[valid]
        total = np.zeros((n_vertices, 3))
        np.add.at(total, self.sheet_vertex, table)
        return total / np.maximum(np.linalg.norm(total, axis=1), 1e-300)[:, None]


def _next_prev(faces: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The vertex after and before each corner (m, 4); a triangle's fourth corner repeats its
    first."""
    tri = faces[:, 3] < 0
    nxt = np.where(tri[:, None], faces[:, [1, 2, 0, 1]], faces[:, [1, 2, 3, 0]])
    prv = np.where(tri[:, None], faces[:, [2, 0, 1, 2]], faces[:, [3, 0, 1, 2]])
    return nxt, prv


def _corners(faces: NDArray[np.int64]) -> NDArray[np.int64]:
    """Corner vertices (m, 4), a triangle's fourth repeating its first."""
    return np.where(faces < 0, faces[:, :1], faces)


def face_normals(vertices: ArrayLike, faces: ArrayLike
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Unit normals (m, 3) and areas (m,) of the faces (quadrilaterals: half the cross product
    of the diagonals, their vector area)."""
    x = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64)
    c = x[_corners(f)]
    tri = f[:, 3] < 0
    vector = 0.5 * np.where(tri[:, None], np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]),
                            np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]))
    area = np.linalg.norm(vector, axis=1)
    return vector / np.maximum(area, 1e-300)[:, None], area


def mesh_topology(faces: ArrayLike, n_vertices: int) -> MeshTopology:
    """The edges of a mesh and the faces on each."""
    f = np.asarray(faces, dtype=np.int64)
    nxt, _ = _next_prev(f)
    start = _corners(f)
    valid = np.ones(f.shape, dtype=bool)
    valid[:, 3] = f[:, 3] >= 0
    a, b = start[valid], nxt[valid]
    face = np.broadcast_to(np.arange(len(f))[:, None], f.shape)[valid]
    key = np.minimum(a, b) * np.int64(n_vertices) + np.maximum(a, b)
    unique, first, inverse, counts = np.unique(key, return_index=True, return_inverse=True,
                                               return_counts=True)
    corner_edge = np.full(f.shape, -1, dtype=np.int64)
    corner_edge[valid] = inverse
    edge_faces = np.full((len(unique), 2), -1, dtype=np.int64)
    order = np.argsort(inverse, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    edge_faces[:, 0] = face[order[starts]]
    two = counts >= 2
    edge_faces[two, 1] = face[order[starts[two] + 1]]
    edges = np.column_stack([np.minimum(a, b)[first], np.maximum(a, b)[first]])
    return MeshTopology(edges, edge_faces, corner_edge, counts.astype(np.int64))


def estimate_normals(vertices: ArrayLike, faces: ArrayLike, estimator: str = DEFAULT_ESTIMATOR,
                     crease_angle: float = DEFAULT_CREASE_ANGLE) -> MeshNormals:
    """Normals per face corner of a consistently oriented mesh (see the module's text)."""
    if estimator not in ESTIMATORS:
        raise ValueError(f"estimator must be one of {', '.join(ESTIMATORS)}, got {estimator!r}")
    angle = float(crease_angle)
    if not 0.0 < angle <= 180.0:
        raise ValueError(f"crease_angle must lie in (0, 180] degrees, got {crease_angle}")
    x = float_array(vertices, "vertices", (None, 3))
    f = int_array(faces, "faces", (None, 4)).astype(np.int64)
    if len(f) == 0:
        raise ValueError("faces is empty")
    used = _corners(f)
    if used.min() < 0 or used.max() >= len(x):
        raise ValueError(f"faces refer to vertices outside 0..{len(x) - 1}")
    topology = mesh_topology(f, len(x))
    if np.any(topology.counts > 2):
        e = int(np.flatnonzero(topology.counts > 2)[0])
        raise ValueError(f"edge {topology.edges[e].tolist()} is shared by "
                         f"{topology.counts[e]} faces: the mesh is not a manifold surface")
    normal, _ = face_normals(x, f)
    interior = topology.counts == 2
    dihedral = np.full(len(topology.edges), np.nan)
    ef = topology.edge_faces[interior]
    cosine = np.clip(np.einsum("ij,ij->i", normal[ef[:, 0]], normal[ef[:, 1]]), -1.0, 1.0)
    dihedral[interior] = np.degrees(np.arccos(cosine))
    crease = np.zeros(len(topology.edges), dtype=bool)
    crease[interior] = dihedral[interior] > angle
    corner_sheet, sheet_vertex = _sheets(f, topology, crease)
    normals, fallbacks = _estimate(x, f, corner_sheet, sheet_vertex, estimator)
    corner = normals[np.where(corner_sheet < 0, corner_sheet[:, :1], corner_sheet)]
    return MeshNormals(corner, corner_sheet, sheet_vertex, topology, crease, dihedral, estimator,
                       angle, fallbacks)


def _sheets(f: NDArray[np.int64], topology: MeshTopology, crease: NDArray[np.bool_]
            ) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Group the corners of each vertex into sheets: corners of two faces on a smooth edge
    join at both ends of it. Returns the sheet of each corner (m, 4) and the vertex of each
    sheet."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = len(f)
    start = _corners(f)
    smooth = np.flatnonzero((topology.counts == 2) & ~crease)
    links_a, links_b = [], []
    for end in (0, 1):
        v = topology.edges[smooth, end]
        sides = []
        for side in (0, 1):
            face = topology.edge_faces[smooth, side]
            k = np.argmax(start[face] == v[:, None], axis=1)
            sides.append(face * 4 + k)
        links_a.append(sides[0])
        links_b.append(sides[1])
    a, b = np.concatenate(links_a), np.concatenate(links_b)
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(4 * m, 4 * m))
    _, label = connected_components(graph, directed=False)
    valid = np.ones((m, 4), dtype=bool)
    valid[:, 3] = f[:, 3] >= 0
    label = label.reshape(m, 4)
    ids, sheet = np.unique(label[valid], return_inverse=True)
    corner_sheet = np.full((m, 4), -1, dtype=np.int64)
    corner_sheet[valid] = sheet
    sheet_vertex = np.empty(len(ids), dtype=np.int64)
    sheet_vertex[corner_sheet[valid]] = start[valid]
    return corner_sheet, sheet_vertex


def _weighted(x: NDArray[np.float64], f: NDArray[np.int64], corner_sheet: NDArray[np.int64],
              n_sheets: int, kind: str) -> NDArray[np.float64]:
    """Weighted sums of face or corner normals per sheet (unit; zero where they cancel)."""
    nxt, prv = _next_prev(f)
    start = _corners(f)
    e1, e2 = x[nxt] - x[start], x[prv] - x[start]
    cross = np.cross(e1, e2)
    normal, area = face_normals(x, f)
    if kind == "area":
        w = np.broadcast_to((normal * area[:, None])[:, None], cross.shape)
    elif kind == "angle":
        l1, l2 = np.linalg.norm(e1, axis=2), np.linalg.norm(e2, axis=2)
        cosine = np.einsum("fkx,fkx->fk", e1, e2) / np.maximum(l1 * l2, 1e-300)
        w = np.arccos(np.clip(cosine, -1.0, 1.0))[..., None] * normal[:, None]
    else:  # max
        w = cross / np.maximum((e1 ** 2).sum(axis=2) * (e2 ** 2).sum(axis=2), 1e-300)[..., None]
    valid = corner_sheet >= 0
    total = np.zeros((n_sheets, 3))
    np.add.at(total, corner_sheet[valid], w[valid])
    length = np.linalg.norm(total, axis=1)
    return total / np.where(length > 0.0, length, 1.0)[:, None]


def _estimate(x: NDArray[np.float64], f: NDArray[np.int64], corner_sheet: NDArray[np.int64],
              sheet_vertex: NDArray[np.int64], estimator: str) -> tuple[NDArray[np.float64], int]:
    n_sheets = len(sheet_vertex)
    normal, _ = face_normals(x, f)
    valid = corner_sheet >= 0
    sheet_of = corner_sheet[valid]
    face_of = np.broadcast_to(np.arange(len(f))[:, None], f.shape)[valid]

    def worst_cosine(n: NDArray[np.float64]) -> NDArray[np.float64]:
        """The smallest n . face normal over each sheet's faces."""
        worst = np.full(n_sheets, np.inf)
        np.minimum.at(worst, sheet_of, np.einsum("ij,ij->i", n[sheet_of], normal[face_of]))
        return worst

    fallbacks = 0
    if estimator in ("quadric", "cubic"):
        start = _weighted(x, f, corner_sheet, n_sheets, "max")
        result, ok = _fit(x, f, corner_sheet, sheet_vertex, start, estimator)
        ok &= worst_cosine(result) > MIN_FACE_COSINE
        fallbacks = int((~ok).sum())
        result[~ok] = start[~ok]
    else:
        result = _weighted(x, f, corner_sheet, n_sheets, estimator)
    for kind in ("max", "angle"):
        bad = worst_cosine(result) <= MIN_FACE_COSINE * (kind == "max")
        if not bad.any():
            break
        result[bad] = _weighted(x, f, corner_sheet, n_sheets, kind)[bad]
    bad = worst_cosine(result) <= 0.0
    if bad.any():
        v = int(sheet_vertex[np.flatnonzero(bad)[0]])
        raise ValueError(f"the faces around vertex {v} at {np.round(x[v], 6).tolist()} turn too "
                         "much for one normal (more than 90 degrees between them without a "
                         "crease): lower the crease angle or refine the mesh there")
    return result, fallbacks


def _rings(f: NDArray[np.int64], corner_sheet: NDArray[np.int64], n_vertices: int,
           n_sheets: int, rings: int):
    """Sparse (sheets x vertices) incidence of the vertices of each sheet's 1.. ``rings``
    rings of faces: ring 1 the sheet's faces, ring k + 1 the faces that share a sheet (a
    vertex, on the same side of any crease) with ring k."""
    from scipy.sparse import csr_matrix

    valid = corner_sheet >= 0
    face_of = np.broadcast_to(np.arange(len(f))[:, None], f.shape)[valid]
    incidence = csr_matrix((np.ones(len(face_of)), (corner_sheet[valid], face_of)),
                           shape=(n_sheets, len(f)))          # sheets x faces
    face_vertex = csr_matrix((np.ones(len(face_of)), (face_of, _corners(f)[valid])),
                             shape=(len(f), n_vertices))       # faces x vertices
    share = (incidence.T @ incidence).astype(bool).astype(np.float64)  # faces x faces
    ring = incidence.astype(bool).astype(np.float64)
    result = []
    for _ in range(rings):
        result.append((ring @ face_vertex).astype(bool).tocsr())
        ring = (ring @ share).astype(bool).astype(np.float64)
    return result


def _frames(n: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two unit tangents t1, t2 with t1 x t2 = n."""
    axis = np.eye(3)[np.argmin(np.abs(n), axis=1)]
    t1 = np.cross(n, axis)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return t1, np.cross(n, t1)


def _basis(u: NDArray[np.float64], v: NDArray[np.float64], terms: int) -> NDArray[np.float64]:
    columns = [u, v, u * u, u * v, v * v]
    if terms == 9:
        columns += [u ** 3, u * u * v, u * v * v, v ** 3]
    return np.column_stack(columns)


def _fit(x: NDArray[np.float64], f: NDArray[np.int64], corner_sheet: NDArray[np.int64],
         sheet_vertex: NDArray[np.int64], start: NDArray[np.float64], estimator: str
         ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Height-function fits per sheet: the normals and whether each fit could be made.

    Each sheet tries the attempts of its estimator in turn (:data:`_ATTEMPTS`: the terms and
    the ring of faces whose vertices it fits) until one has enough points and a well
    conditioned normal matrix: a boundary vertex of a structured grid sees too few distinct
    rows for a cubic in its 2-ring, a corner of the grid too few points."""
    n_sheets = len(sheet_vertex)
    rings = _rings(f, corner_sheet, len(x), n_sheets, _MAX_RING)
    counts = [np.asarray(r.sum(axis=1)).ravel() - 1 for r in rings]  # less the vertex itself
    normal = start.copy()
    done = np.zeros(n_sheets, dtype=bool)
    for terms, ring in _ATTEMPTS[estimator]:
        wanted = _WANTED[terms]
        todo = np.flatnonzero(~done & (counts[ring - 1] >= wanted))
        if todo.size == 0:
            continue
        fitted, ok = _fit_sheets(x, sheet_vertex, start, rings[ring - 1], todo, terms)
        normal[todo[ok]] = fitted[ok]
        done[todo[ok]] = True
    return normal, done


def _fit_sheets(x: NDArray[np.float64], sheet_vertex: NDArray[np.int64],
                start: NDArray[np.float64], ring, todo: NDArray[np.int64], terms: int
                ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Fits of ``terms`` terms for the sheets ``todo`` to the vertices of their ``ring``
    (sparse sheets x vertices): the normals (len(todo), 3) and which fits were made."""
    coo = ring[todo].tocoo()
    sheet, vertex = coo.row, coo.col            # sheet: index into todo
    keep = vertex != sheet_vertex[todo][sheet]
    sheet, vertex = sheet[keep], vertex[keep]
    k = len(todo)
    origin = x[sheet_vertex[todo]]
    normal = start[todo].copy()
    ok = np.ones(k, dtype=bool)
    for _ in range(2):   # the second fit in the tangent plane of the first
        t1, t2 = _frames(normal)
        d = x[vertex] - origin[sheet]
        scale = np.sqrt(np.bincount(sheet, (d ** 2).sum(axis=1), minlength=k)
                        / np.maximum(np.bincount(sheet, minlength=k), 1))
        d /= np.maximum(scale[sheet], 1e-300)[:, None]
        u = np.einsum("ij,ij->i", d, t1[sheet])
        v = np.einsum("ij,ij->i", d, t2[sheet])
        h = np.einsum("ij,ij->i", d, normal[sheet])
        phi = _basis(u, v, terms)
        w = 1.0 / np.maximum(u * u + v * v, 1e-12) ** 2   # 1 / r^4: the nearest points lead
        matrix = np.zeros((k, terms, terms))
        rhs = np.zeros((k, terms))
        for lo in range(0, len(sheet), 100_000):
            s = slice(lo, lo + 100_000)
            np.add.at(matrix, sheet[s], w[s, None, None] * phi[s, :, None] * phi[s, None, :])
            np.add.at(rhs, sheet[s], w[s, None] * phi[s] * h[s, None])
        rows = np.flatnonzero(ok)
        eig = np.linalg.eigvalsh(matrix[rows])
        good = eig[:, 0] > _MIN_CONDITION * np.maximum(eig[:, -1], 1e-300)
        ok[rows[~good]] = False
        rows = rows[good]
        coef = np.linalg.solve(matrix[rows], rhs[rows][..., None])[..., 0]
        fitted = normal[rows] - coef[:, :1] * t1[rows] - coef[:, 1:2] * t2[rows]
        normal[rows] = fitted / np.linalg.norm(fitted, axis=1)[:, None]
    return normal, ok
