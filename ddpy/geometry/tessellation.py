"""A tool surface as a mesh of flat triangles and quadrilaterals, to be looked at (ParaView).

Facets are taken as they are (one cell per facet). A smooth patch (Bezier, Nagata) is cut
into k x k cells (k^2 triangles for a Nagata triangle) evaluated on the surface: k is the
smallest for which the patch's bulge from the flat facet through its corners, divided by
k^2 (how a cut shrinks a sagitta), is at most MAX_SAG of the patch's size (its longest
corner-to-corner distance), from 1 to MAX_CUTS: each cell's sagitta is then about MAX_SAG
of the patch's size (on a circular arc 5 % more). A quarter circle as one patch takes about
14 cuts; a square Nagata patch over 5 degrees of a radius takes 3.

>>> points, cells, kinds = tessellate(surface)   # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ddpy.geometry.surfaces import BezierSurface, NagataSurface

__all__ = ["MAX_CUTS", "MAX_SAG", "TRIANGLE", "QUADRILATERAL", "tessellate"]

#: Largest sagitta of a cell over the size of its patch.
MAX_SAG = 1e-3
#: Most cuts of a patch per direction.
MAX_CUTS = 16
#: Cell kinds (the number of corners).
TRIANGLE, QUADRILATERAL = 3, 4
#: Where the bulge of a patch is measured: its centre and the middles of its edges.
_PROBES = np.array([[0.5, 0.5], [0.5, 0.0], [1.0, 0.5], [0.5, 1.0], [0.0, 0.5]])
#: The same on a Nagata triangle (parameters 0 <= v <= u <= 1): its centroid and edges.
_TRIANGLE_PROBES = np.array([[2.0 / 3.0, 1.0 / 3.0], [0.5, 0.0], [1.0, 0.5], [0.5, 0.5]])


def _cuts(surface: BezierSurface | NagataSurface, triangle: NDArray[np.bool_]
          ) -> NDArray[np.int64]:
    """Per patch, how many cells per direction it is cut into (see the module)."""
    n = surface.n_patches
    if isinstance(surface, NagataSurface) and not surface.smooth:
        return np.ones(n, dtype=np.int64)
    ids = np.arange(n)
    corners_uv = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    corners = surface.evaluate(np.repeat(ids, 4), np.tile(corners_uv, (n, 1)))[0].reshape(
        n, 4, 3)
    corners[triangle, 3] = corners[triangle, 2]  # (a triangle has three)
    probes = np.where(triangle[:, None, None], np.vstack([_TRIANGLE_PROBES, [[0.5, 0.5]]]),
                      _PROBES[None])                                    # (n, 5, 2)
    on = surface.evaluate(np.repeat(ids, 5), probes.reshape(-1, 2))[0].reshape(n, 5, 3)
    u, v = probes[..., 0:1], probes[..., 1:2]
    a, b, c, d = (corners[:, None, i] for i in range(4))
    flat = np.where(triangle[:, None, None],
                    a + u * (b - a) + v * (c - b),                      # linear triangle
                    (1 - u) * (1 - v) * a + u * (1 - v) * b + u * v * c + (1 - u) * v * d)
    bulge = np.linalg.norm(on - flat, axis=2).max(axis=1)
    size = np.max([np.linalg.norm(corners[:, i] - corners[:, j], axis=1)
                   for i in range(4) for j in range(i + 1, 4)], axis=0)
    k = np.ceil(np.sqrt(bulge / np.maximum(MAX_SAG * size, 1e-300)))
    return np.clip(k, 1, MAX_CUTS).astype(np.int64)


def _quad_grid(k: int) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Parameters ((k+1)^2, 2) and quadrilaterals (k^2, 4) of a k x k grid on [0, 1]^2."""
    t = np.linspace(0.0, 1.0, k + 1)
    uv = np.column_stack([np.tile(t, k + 1), np.repeat(t, k + 1)])   # u fastest
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="xy")
    first = (j * (k + 1) + i).ravel()
    return uv, np.column_stack([first, first + 1, first + k + 2, first + k + 1])


def _triangle_grid(k: int) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Parameters and triangles (k^2, 3) of the triangle 0 <= v <= u <= 1 cut k times."""
    index = {}
    uv = []
    for i in range(k + 1):
        for j in range(i + 1):
            index[i, j] = len(uv)
            uv.append((i / k, j / k))
    cells = []
    for i in range(k):
        for j in range(i + 1):
            cells.append((index[i, j], index[i + 1, j], index[i + 1, j + 1]))
            if j < i:
                cells.append((index[i, j], index[i + 1, j + 1], index[i, j + 1]))
    return np.array(uv, dtype=float), np.array(cells, dtype=np.int64)


def tessellate(surface: BezierSurface | NagataSurface
               ) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.int64]]:
    """Points (p, 3) of the surface and its cells: their corner indices one cell after
    another (``cells``, the sum of their corners) and their ``kinds`` (c,), TRIANGLE or
    QUADRILATERAL (the number of corners). Cells keep the orientation of their patches."""
    triangle = (surface.is_triangle if isinstance(surface, NagataSurface)
                else np.zeros(surface.n_patches, dtype=bool))
    cuts = _cuts(surface, triangle)
    ids, params, cells, kinds, start = [], [], [], [], 0
    for patch in range(surface.n_patches):
        k = int(cuts[patch])
        uv, cell = _triangle_grid(k) if triangle[patch] else _quad_grid(k)
        ids.append(np.full(len(uv), patch))
        params.append(uv)
        cells.append(cell + start)
        kinds.append(np.full(len(cell), cell.shape[1]))
        start += len(uv)
    points = surface.evaluate(np.concatenate(ids), np.vstack(params))[0]
    return points, np.concatenate([c.ravel() for c in cells]), np.concatenate(kinds)
