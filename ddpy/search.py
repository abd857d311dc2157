"""Contact search: candidate patches of each slave node (global) and its orthogonal
projection on them (local), as in the paper's "Contact search algorithm".

>>> import numpy as np
>>> from ddpy.surfaces import NagataSurface
>>> from ddpy.search import ContactSearch
>>> plane = NagataSurface([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 0, 1]] * 4,
...                       [[0, 1, 2, 3]])
>>> found = ContactSearch(plane).project([[0.25, 0.5, 0.1]])
>>> found.distance.round(12).tolist(), found.point.round(12).tolist()
([0.1], [[0.25, 0.5, 0.0]])
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array
from ddpy.surfaces import BezierSurface, NagataSurface

__all__ = ["ContactSearch", "Projection", "NONE", "INSIDE", "EDGE"]

#: Status of a node: no candidate patch; projection inside a patch; held on a patch boundary.
NONE, INSIDE, EDGE = 0, 1, 2
_KIND = {BezierSurface: 1, NagataSurface: 2}
_MODE = {"grid": 1, "vertices": 2, "brute": 3}
_MAX_CANDIDATES = 64


@dataclass(frozen=True)
class Projection:
    """Closest points of k nodes on one tool (arrays indexed by node)."""

    patch: NDArray[np.int32]  #: patch of the closest point, -1 when none was found
    params: NDArray[np.float64]  #: (k, 2) parameters on that patch
    point: NDArray[np.float64]  #: (k, 3) closest point, at the tool's current position
    normal: NDArray[np.float64]  #: (k, 3) unit outward normal there
    tangents: NDArray[np.float64]  #: (k, 2, 3) S_,1 and S_,2 there
    #: (k,) signed normal distance, negative = penetration; at an EDGE point the Euclidean
    #: distance signed by the side of the patch normal
    distance: NDArray[np.float64]
    status: NDArray[np.int32]  #: NONE, INSIDE or EDGE
    iterations: NDArray[np.int32]  #: Newton iterations spent on the node (all candidates)
    candidates: NDArray[np.int32]  #: candidate patches projected on

    @property
    def mean_iterations(self) -> float:
        """Mean Newton iterations per projection (one projection per candidate)."""
        return float(self.iterations.sum() / max(int(self.candidates.sum()), 1))


class ContactSearch:
    """Global and local contact search of points against one tool surface.

    Bezier tools use a uniform grid of ``(n + 2) x (m + 2)`` points on every patch (its
    density from the degrees) and a spatial index over all of them; Nagata and facet tools
    a spatial index over the mesh vertices, the patches around the ``vertices_per_query``
    nearest vertices, and a grid on each patch whose density grows with the ratio of its
    longest to shortest edge. Either way the ``candidates`` nearest patches (10, as in the
    paper) are projected on, each from its nearest grid point.
    """

    def __init__(
        self,
        surface: BezierSurface | NagataSurface,
        candidates: int = 10,
        vertices_per_query: int = 8,
        max_iterations: int = 30,
        tol: float = 1e-12,
    ) -> None:
        if type(surface) not in _KIND:
            raise TypeError(f"surface must be a BezierSurface or NagataSurface, got "
                            f"{type(surface).__name__}")
        for name, value, low in (("candidates", candidates, 1),
                                 ("vertices_per_query", vertices_per_query, 1),
                                 ("max_iterations", max_iterations, 1)):
            if not low <= int(value) <= (_MAX_CANDIDATES if name != "max_iterations" else 1000):
                raise ValueError(f"{name} = {value} is out of range")
        self.surface = surface
        self.kind = _KIND[type(surface)]
        self.candidates = int(candidates)
        self.vertices_per_query = int(vertices_per_query)
        self.max_iterations = int(max_iterations)
        self.tol = float(tol)
        n = surface.n_patches
        if self.kind == 1:
            self._stride = 147
            self._degrees = surface.degrees.ravel()
            self._triangle = np.zeros(n, dtype=np.int32)
            counts = surface.degrees + 2
        else:
            self._stride = 24
            self._degrees = np.zeros(2 * n, dtype=np.int32)
            self._triangle = surface.is_triangle.astype(np.int32)
            counts = np.repeat(_nagata_grid_size(surface)[:, None], 2, axis=1)
        self.grid_patch, self.grid_params = _grid(counts, surface.is_triangle
                                                  if self.kind == 2 else np.zeros(n, bool))
        self.grid_start = np.searchsorted(self.grid_patch, np.arange(n + 1)).astype(np.int32)
        self.grid_points, _, self.grid_normals = surface.evaluate(self.grid_patch,
                                                                  self.grid_params)
        if self.kind == 1:
            self.mode = _MODE["grid"]
            index_points, group = self.grid_points, self.grid_patch
            self._vertex_start = np.zeros(1, dtype=np.int32)
            self._vertex_patches = np.zeros(1, dtype=np.int32)
        else:
            self.mode = _MODE["vertices"]
            index_points = surface.vertices
            group = np.arange(len(index_points), dtype=np.int32)
            self._vertex_start, self._vertex_patches = _vertex_patches(surface)
        self._index_points = np.ascontiguousarray(index_points, dtype=np.float64)
        self._group = np.ascontiguousarray(group, dtype=np.int32)
        # The core takes these index arrays 1-based: made once here, not on every call.
        self._group1 = self._group + 1
        self._grid_start1 = self.grid_start + 1
        self._vertex_start1 = self._vertex_start + 1
        self._vertex_patches1 = self._vertex_patches + 1
        self._origin, self._h, self._dims = _core.index_layout(self._index_points.ravel())
        ncell = int(np.prod(self._dims))
        self._cell_start, self._cell_items = _core.index_build(
            self._index_points.ravel(), self._origin, self._h, self._dims, ncell)

    def project(
        self,
        points: ArrayLike,
        tool_displacement: ArrayLike = (0.0, 0.0, 0.0),
        node_normals: ArrayLike | None = None,
        brute_force: bool = False,
    ) -> Projection:
        """Closest point on the tool of each of ``points`` (k, 3), the tool moved by
        ``tool_displacement``. With ``node_normals`` (k, 3), only patch points whose outward
        normal opposes the node's within 60 degrees make their patch a candidate (a zero
        row disables the filter).
        ``brute_force`` projects on every patch: the reference for tests."""
        x = float_array(np.reshape(points, (-1, 3)) if np.size(points) == 0 else points,
                        "points", (None, 3))
        k = x.shape[0]
        u = float_array(tool_displacement, "tool_displacement", (3,))
        if node_normals is None:
            nn = np.zeros_like(x)
        else:
            nn = float_array(node_normals, "node_normals", (k, 3))
            length = np.linalg.norm(nn, axis=1, keepdims=True)
            nn = nn / np.where(length > 0.0, length, 1.0)  # the cone test needs unit rows
        if k == 0:
            empty = np.zeros(0, dtype=np.int32)
            return Projection(empty, np.zeros((0, 2)), np.zeros((0, 3)), np.zeros((0, 3)),
                              np.zeros((0, 2, 3)), np.zeros(0), empty, empty, empty)
        mode = _MODE["brute"] if brute_force else self.mode
        out = _core.contact_search(
            self.kind, self._stride, self.surface.coefficients, self._degrees, self._triangle,
            mode, self._index_points.ravel(), self._group1, self._origin, self._h, self._dims,
            self._cell_start, self._cell_items, self._grid_start1, self.grid_params.ravel(),
            self.grid_normals.ravel(), self.grid_points.ravel(), self._vertex_start1,
            self._vertex_patches1, x.ravel(), nn.ravel(), u, self.candidates,
            self.vertices_per_query, self.max_iterations, self.tol,
        )
        patch, params, point, normal, tangents, distance, status, iterations, ncand_out = out
        return Projection(patch, params.reshape(k, 2), point.reshape(k, 3),
                          normal.reshape(k, 3), tangents.reshape(k, 2, 3), distance, status,
                          iterations, ncand_out)


def _nagata_grid_size(surface: NagataSurface) -> NDArray[np.int64]:
    """Grid points per direction of each patch: 4 for a regular patch, more when its
    longest edge is much longer than its shortest (up to 12)."""
    faces = surface.faces
    corners = np.where(surface.is_triangle[:, None], faces[:, [0, 1, 2, 0]], faces)
    x = surface.vertices[corners]
    edges = np.linalg.norm(np.roll(x, -1, axis=1) - x, axis=2)
    edges[surface.is_triangle, 3] = edges[surface.is_triangle, 2]  # the padding edge is zero
    ratio = edges.max(axis=1) / edges.min(axis=1)
    return np.clip(3 + np.ceil(ratio).astype(np.int64), 4, 12)


def _grid(counts: NDArray[np.int64], triangle: NDArray[np.bool_]
          ) -> tuple[NDArray[np.int32], NDArray[np.float64]]:
    """Uniform parameter grid of every patch: (patch of each point, its parameters)."""
    patches, params = [], []
    for (gu, gv), tri in {(tuple(c), bool(t)) for c, t in zip(counts, triangle, strict=True)}:
        s, t = np.meshgrid(np.linspace(0, 1, gu), np.linspace(0, 1, gv), indexing="ij")
        keep = (t <= s + 1e-12) if tri else np.ones_like(s, dtype=bool)
        uv = np.column_stack([s[keep], t[keep]])
        ids = np.flatnonzero((counts[:, 0] == gu) & (counts[:, 1] == gv) & (triangle == tri))
        patches.append(np.repeat(ids, len(uv)))
        params.append(np.tile(uv, (len(ids), 1)))
    patch = np.concatenate(patches)
    order = np.argsort(patch, kind="stable")
    return patch[order].astype(np.int32), np.ascontiguousarray(np.concatenate(params)[order])


def _vertex_patches(surface: NagataSurface) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
    """Inverse connectivity as CSR: patches of vertex v are patches[start[v]:start[v+1]]."""
    faces = surface.faces
    face_of = np.repeat(np.arange(len(faces)), 4)
    vertex = faces.ravel()
    keep = vertex >= 0
    vertex, face_of = vertex[keep], face_of[keep]
    order = np.argsort(vertex, kind="stable")
    start = np.searchsorted(vertex[order], np.arange(len(surface.vertices) + 1))
    return start.astype(np.int32), face_of[order].astype(np.int32)
