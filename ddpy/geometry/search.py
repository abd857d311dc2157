"""Contact search: candidate patches of each slave node (global) and its orthogonal
projection on them (local), as in the paper's "Contact search algorithm".

>>> import numpy as np
>>> from ddpy.geometry.surfaces import NagataSurface
>>> from ddpy.geometry.search import ContactSearch
>>> plane = NagataSurface([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 0, 1]] * 4,
...                       [[0, 1, 2, 3]])
>>> found = ContactSearch(plane).project([[0.25, 0.5, 0.1]])
>>> found.distance.round(12).tolist(), found.point.round(12).tolist()
([0.1], [[0.25, 0.5, 0.0]])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array
from ddpy.core.constants import constant
from ddpy.core.handles import CoreHandle, check
from ddpy.geometry.surfaces import BezierSurface, NagataSurface

__all__ = ["ContactSearch", "Projection", "SearchArrays", "SearchMemory", "NONE", "INSIDE",
           "EDGE"]

#: Status of a node: no candidate patch; projection inside a patch; held on a patch boundary.
NONE, INSIDE, EDGE = (constant("projection_none"), constant("projection_inside"),
                      constant("projection_edge"))
_KIND = {BezierSurface: constant("surface_bezier"), NagataSurface: constant("surface_nagata")}
_MODE = {"tree": constant("search_mode_tree"), "brute": constant("search_mode_brute")}


class SearchArrays(NamedTuple):
    """The flat arrays of one tool that the core's search reads, in the order of its
    surface_create:
    coefficients, degrees and triangle flags per patch; the box tree (children 1-based);
    the patch frames and their boxes; each patch's first grid point (1-based) and the grid's
    parameters, normals and points."""

    coef: NDArray[np.float64]
    degrees: NDArray[np.int32]
    triangle: NDArray[np.int32]
    tree_lower: NDArray[np.float64]
    tree_upper: NDArray[np.float64]
    tree_child: NDArray[np.int32]
    frame: NDArray[np.float64]
    frame_lower: NDArray[np.float64]
    frame_upper: NDArray[np.float64]
    grid_start: NDArray[np.int32]
    grid_params: NDArray[np.float64]
    grid_normals: NDArray[np.float64]
    grid_points: NDArray[np.float64]


@dataclass(frozen=True)
class Projection:
    """Closest points of k nodes on one tool (arrays indexed by node)."""

    patch: NDArray[np.int32]  #: patch of the closest point, -1 when none was found
    params: NDArray[np.float64]  #: (k, 2) parameters on that patch
    point: NDArray[np.float64]  #: (k, 3) closest point, at the tool's current position
    normal: NDArray[np.float64]  #: (k, 3) unit outward normal there
    tangents: NDArray[np.float64]  #: (k, 2, 3) S_,1 and S_,2 there
    #: (k,) signed normal distance, negative = penetration; at an EDGE point the Euclidean
    #: distance signed by the side of the patch normal, unless the point lies beside the
    #: edge in the patch's tangent plane within 1e-5 of the tool's size (a seam between
    #: patches that miss each other by a fit's tolerance): then the normal distance
    distance: NDArray[np.float64]
    status: NDArray[np.int32]  #: NONE, INSIDE or EDGE
    iterations: NDArray[np.int32]  #: Newton iterations spent on the node (all candidates)
    #: candidate patches projected on: those whose bound was below the nearest distance found
    candidates: NDArray[np.int32]

    @property
    def mean_iterations(self) -> float:
        """Mean Newton iterations per projection (one projection per candidate)."""
        return float(self.iterations.sum() / max(int(self.candidates.sum()), 1))


_MEMORY_ROWS = constant("search_memory_rows")


class SearchMemory:
    """What the tree search remembers of k points from one ``ContactSearch.project`` to the
    next (its ``memory``), updated in place: per point where its last full search was (in
    the tool's frame), the patch it found there and a lower bound there of its distance to
    every other patch. A point that moved less than that bound's margin is projected on
    its patch alone, with the answer of a full search (docs/theory/contact.md, "Search
    memory"). The forming Newton loop keeps one over an increment's evaluations."""

    def __init__(self, k: int) -> None:
        #: (k, ROWS): where each point was last searched in full (x, y, z), the bound, and
        #: 1 where the last call answered the point from the memory (else 0)
        self.bounds = np.zeros((k, _MEMORY_ROWS))
        #: (k,): the core's patch found there (1-based, 0: none, -1: never searched)
        self.patches = np.full(k, -1, dtype=np.int32)

    @property
    def recalled(self) -> NDArray[np.bool_]:
        """Which points the last ``project`` answered from the memory."""
        return self.bounds[:, 4] == 1.0


class ContactSearch:
    """Global and local contact search of points against one tool surface.

    The closest patch of a point is the one on which its projection (the local search,
    started at the patch's grid point nearest to the point) is nearest; an inside projection
    wins a tie, within rounding, with a point held on a patch boundary. The global search
    finds that patch exactly, whatever the sizes of the patches: a bounding volume hierarchy
    over boxes that contain each patch (from its Bernstein control points) gives a lower
    bound of the distance to every patch, patches are projected on in the order of their
    bounds, and the search stops at the first bound beyond the nearest projection found,
    or beyond the reach of ``project`` (docs/theory/contact.md). The grid on each patch,
    ``(n + 2) x (m + 2)`` points for a Bezier patch, 4 to 12 per direction for a Nagata
    patch (more for a long thin one), only gives the local search its start. The core keeps
    the surface with its search structures (``handle``); ``max_iterations`` and ``tol`` are
    fixed with it.
    """

    def __init__(
        self,
        surface: BezierSurface | NagataSurface,
        max_iterations: int = 30,
        tol: float = 1e-12,
    ) -> None:
        if type(surface) not in _KIND:
            raise TypeError(f"surface must be a BezierSurface or NagataSurface, got "
                            f"{type(surface).__name__}")
        if not 1 <= int(max_iterations) <= 1000:
            raise ValueError(f"max_iterations = {max_iterations} is out of range")
        self.surface = surface
        self.kind = _KIND[type(surface)]
        self._max_iterations = int(max_iterations)
        self._tol = float(tol)
        self.mode = _MODE["tree"]
        n = surface.n_patches
        if self.kind == _KIND[BezierSurface]:
            self.stride = constant("bezier_stride")
            self._degrees = surface.degrees.ravel()
            self._triangle = np.zeros(n, dtype=np.int32)
            counts = surface.degrees + 2
        else:
            self.stride = constant("nagata_stride")
            self._degrees = np.zeros(2 * n, dtype=np.int32)
            self._triangle = surface.is_triangle.astype(np.int32)
            counts = np.repeat(_nagata_grid_size(surface)[:, None], 2, axis=1)
        self.grid_patch, self.grid_params, self.grid_start = _grid(
            counts, surface.is_triangle if self.kind == _KIND[NagataSurface]
            else np.zeros(n, bool))
        self.grid_points, _, self.grid_normals = surface.evaluate(self.grid_patch,
                                                                  self.grid_params)
        tree = _core.search_tree(self.kind, self.stride, self.surface.coefficients,
                                 self._degrees, self._triangle)
        # The core takes grid_start and the tree's children 1-based: made once here.
        self.arrays = SearchArrays(
            self.surface.coefficients, self._degrees.astype(np.int32),
            self._triangle.astype(np.int32), *tree,
            (self.grid_start + 1).astype(np.int32), self.grid_params.ravel(),
            self.grid_normals.ravel(), self.grid_points.ravel())
        self._surface: CoreHandle | None = None

    @property
    def handle(self) -> int:
        """The handle of the core's copy of the surface and its search structures
        (``arrays``, fortran/search/ddpy_search_surface.f90), made at the first use: the
        search and the forming problem, which copies it, read that copy."""
        if self._surface is None:
            handle, status = _core.surface_create(self.kind, self.stride, *self.arrays,
                                                  self.mode, self.max_iterations, self.tol)
            check(status, "the tool surface's search structures")
            self._surface = CoreHandle(handle)
        return self._surface.handle

    @property
    def max_iterations(self) -> int:
        """Newton iterations of the local search at most."""
        return self._max_iterations

    @property
    def tol(self) -> float:
        """The local search's tolerance."""
        return self._tol

    def project(
        self,
        points: ArrayLike,
        tool_displacement: ArrayLike = (0.0, 0.0, 0.0),
        node_normals: ArrayLike | None = None,
        brute_force: bool = False,
        reach: float | None = None,
        held: ArrayLike | None = None,
        memory: SearchMemory | None = None,
    ) -> Projection:
        """Closest point on the tool of each of ``points`` (k, 3), the tool moved by
        ``tool_displacement``. With ``node_normals`` (k, 3), only patch points whose outward
        normal opposes the node's within 60 degrees make their patch a candidate (a zero
        row disables the filter). With ``reach`` (mm), projections farther than it
        (Euclidean distance) do not count: a node with none nearer gets status NONE, and
        the search does not look at patches beyond it (None: no limit).
        ``brute_force`` projects on every patch (within the same reach): the reference for
        tests. ``held`` (k,): a patch number holds that point on that patch (no search;
        its projection there counts as inside, with its signed normal distance: on a facet,
        the distance to the facet's plane continued past its edges), -1 searches; the
        forming Newton loop holds pairs so (docs/theory/contact.md). ``memory``: what the
        last calls found for these points (SearchMemory), used and updated by the tree
        search; the answers are those without it."""
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
        if reach is None:
            limit = float(np.finfo(np.float64).max)
        else:
            limit = float(reach)
            if not limit >= 0.0:
                raise ValueError(f"reach must be >= 0 or None, got {reach}")
            limit = min(limit, float(np.finfo(np.float64).max))
        if held is None:
            on_patch = np.full(k, -1, dtype=np.int32)
        else:
            on_patch = np.asarray(held)
            if on_patch.shape != (k,) or not np.issubdtype(on_patch.dtype, np.integer) or \
                    ((on_patch < -1) | (on_patch >= self.surface.n_patches)).any():
                raise ValueError(f"held must be ({k},) patch numbers in -1..."
                                 f"{self.surface.n_patches - 1}")
            on_patch = on_patch.astype(np.int32)
        if k == 0:
            empty = np.zeros(0, dtype=np.int32)
            return Projection(empty, np.zeros((0, 2)), np.zeros((0, 3)), np.zeros((0, 3)),
                              np.zeros((0, 2, 3)), np.zeros(0), empty, empty, empty)
        mode = _MODE["brute"] if brute_force else self.mode
        if memory is not None and memory.patches.shape != (k,):
            raise ValueError(f"memory must be of {k} points, got {memory.patches.size}")
        kept = SearchMemory(k) if memory is None else memory
        (patch, params, point, normal, tangents, distance, status, iterations, ncand_out,
         bounds, patches, refusal) = _core.contact_search(
            self.handle, mode, x.ravel(), nn.ravel(), u, limit, on_patch,
            np.ascontiguousarray(kept.bounds).ravel(), kept.patches)
        check(refusal, "the contact search")
        kept.bounds, kept.patches = bounds.reshape(k, _MEMORY_ROWS), patches
        return Projection(patch, params.reshape(k, 2), point.reshape(k, 3),
                          normal.reshape(k, 3), tangents.reshape(k, 2, 3), distance, status,
                          iterations, ncand_out)

    def patch_boxes(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(lower, upper), each (patches, 3): the axis-aligned box of every patch that the
        search bounds its distance by; every point of patch p lies in box p."""
        a = self.arrays
        leaf = np.flatnonzero(a.tree_child < 0)
        order = np.argsort(-a.tree_child[leaf] - 1)
        lower = a.tree_lower.reshape(-1, 3)[leaf[order]]
        upper = a.tree_upper.reshape(-1, 3)[leaf[order]]
        return lower, upper

    def patch_frame_boxes(self) -> tuple[NDArray[np.float64], ...]:
        """(axes, lower, upper): the box of every patch in its own frame, axes (patches, 3,
        3) with axes[p, a] the unit axis a; every point y of patch p has
        lower[p] <= axes[p] @ y <= upper[p]."""
        n = self.surface.n_patches
        a = self.arrays
        return (a.frame.reshape(n, 3, 3), a.frame_lower.reshape(n, 3),
                a.frame_upper.reshape(n, 3))


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
          ) -> tuple[NDArray[np.int32], NDArray[np.float64], NDArray[np.int32]]:
    """Uniform parameter grid of every patch: (patch of each point, its parameters, the
    first point of each patch and the end), the points of each patch together, in patch
    order."""
    # One small integer per layout (count per direction below 64, triangle or not).
    key = (counts[:, 0] * 64 + counts[:, 1]) * 2 + triangle
    present = np.flatnonzero(np.bincount(key))
    which = np.searchsorted(present, key)
    layouts = []
    for k in present:
        (gu, gv), tri = divmod(int(k) // 2, 64), bool(k % 2)
        s, t = np.meshgrid(np.linspace(0, 1, gu), np.linspace(0, 1, gv), indexing="ij")
        keep = (t <= s + 1e-12) if tri else np.ones_like(s, dtype=bool)
        layouts.append(np.column_stack([s[keep], t[keep]]))
    sizes = np.array([len(uv) for uv in layouts])[which]
    start = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=start[1:])
    # Point j of patch p is row j of its layout, in the layouts stacked one after another.
    offset = np.concatenate([[0], np.cumsum([len(uv) for uv in layouts])])
    first = np.repeat(offset[which] - start[:-1], sizes)
    params = np.vstack(layouts)[first + np.arange(start[-1])]
    patch = np.repeat(np.arange(len(sizes), dtype=np.int32), sizes)
    return patch, params, start.astype(np.int32)
