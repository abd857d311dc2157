"""Fill-reducing pivot orders for the sparse direct solver, from the mesh geometry.

The tangent of a sheet is, up to its few layers, the matrix of a two-dimensional mesh, for
which nested dissection is the optimal order. The orderings this MUMPS build offers (SCOTCH,
PORD, AMD variants; Debian's has no METIS) find it only partly. ``nested_dissection`` cuts
the mesh recursively by planes across its longest extent; each cut's separator (the nodes
on one side that touch the other) is eliminated after both halves. Measured on the
20,172-hexahedron strip of docs/benchmarks/solid_bending.md: see docs/building.md.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy.core.linalg import MumpsSolver, distinct

__all__ = ["Graph", "node_adjacency", "nested_dissection", "equation_order", "mesh_solver"]


class Graph(NamedTuple):
    """Compressed adjacency lists: the neighbours of vertex i are
    ``indices[indptr[i]:indptr[i + 1]]`` (the vertex itself included)."""

    indptr: NDArray[np.int64]
    indices: NDArray[np.int64]

    @property
    def n(self) -> int:
        return self.indptr.size - 1


def node_adjacency(elements: ArrayLike, n_nodes: int) -> Graph:
    """Node-to-node adjacency of a mesh: nodes sharing an element."""
    elements = np.asarray(elements, dtype=np.int64)
    k = elements.shape[1]
    keys = distinct((np.repeat(elements, k, axis=1) * n_nodes
                     + np.tile(elements, (1, k))).ravel())
    rows, cols = np.divmod(keys, n_nodes)
    indptr = np.zeros(n_nodes + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=n_nodes), out=indptr[1:])
    return Graph(indptr, cols)


def _touching(graph: Graph, vertices: NDArray[np.int64], mark: NDArray[np.bool_],
              ) -> NDArray[np.bool_]:
    """Which of ``vertices`` have a neighbour with ``mark`` set."""
    starts = graph.indptr[vertices]
    lengths = graph.indptr[vertices + 1] - starts
    first = np.cumsum(lengths) - lengths
    positions = np.repeat(starts - first, lengths) + np.arange(lengths.sum())
    hits = mark[graph.indices[positions]].astype(np.int64)
    return np.add.reduceat(hits, first) > 0 if vertices.size else np.zeros(0, dtype=bool)


def nested_dissection(graph: Graph, points: ArrayLike, leaf: int = 48) -> NDArray[np.int64]:
    """Elimination order of the vertices of ``graph`` located at ``points`` (n, d):
    recursive coordinate bisection across the longest extent, each separator after the two
    parts it separates; parts of at most ``leaf`` vertices keep their order."""
    points = np.asarray(points, dtype=float)
    n = graph.n
    if points.shape[0] != n:
        raise ValueError(f"points has {points.shape[0]} rows for a graph of {n} vertices")
    mark = np.zeros(n, dtype=bool)  # the current right part, scratch
    order: list[NDArray[np.int64]] = []

    def dissect(part: NDArray[np.int64]) -> None:
        if part.size <= leaf:
            order.append(part)
            return
        xyz = points[part]
        axis = int(np.argmax(xyz.max(axis=0) - xyz.min(axis=0)))
        right_mask = xyz[:, axis] >= np.median(xyz[:, axis])
        if right_mask.all() or not right_mask.any():  # all on the cut: split by position
            right_mask = np.arange(part.size) >= part.size // 2
        left, right = part[~right_mask], part[right_mask]
        mark[right] = True
        touching = _touching(graph, left, mark)
        mark[right] = False
        separator, left = left[touching], left[~touching]
        if separator.size == left.size + separator.size and right.size == 0:
            order.append(part)
            return
        dissect(left)
        dissect(right)
        order.append(separator)

    dissect(np.arange(n, dtype=np.int64))
    return np.concatenate(order)


def equation_order(node_order: ArrayLike, equation_nodes: ArrayLike,
                   first: ArrayLike | None = None, last: ArrayLike | None = None
                   ) -> NDArray[np.int64]:
    """Pivot position of every equation (0-based, a permutation) when the equations of each
    node (``equation_nodes[i]``: the node equation i belongs to, e.g. a displacement
    component or a contact multiplier of that node) are eliminated together, nodes in
    ``node_order``. ``first`` (bool per equation): these come before all the others (each
    group in node order), e.g. contact multipliers, which couple to their node only: in
    the separators they would widen every front. ``last`` (bool per equation): these come
    after all the others, e.g. a force-controlled tool's, which couples to every node it
    touches."""
    node_order = np.asarray(node_order, dtype=np.int64)
    equation_nodes = np.asarray(equation_nodes, dtype=np.int64)
    rank = np.empty(node_order.size, dtype=np.int64)
    rank[node_order] = np.arange(node_order.size)
    group = (np.zeros(equation_nodes.size, dtype=np.int64) if first is None else
             np.where(np.asarray(first, dtype=bool), 0, 1))
    if last is not None:
        group = np.where(np.asarray(last, dtype=bool), 2, group)
    sequence = np.lexsort((np.arange(equation_nodes.size), rank[equation_nodes], group))
    position = np.empty(equation_nodes.size, dtype=np.int64)
    position[sequence] = np.arange(equation_nodes.size)
    return position


def mesh_solver(symmetry: str, ordering: str, node_order: Callable[[], NDArray[np.int64]],
                equation_nodes: ArrayLike, first: ArrayLike | None = None,
                last: ArrayLike | None = None, precision: str = "double") -> MumpsSolver:
    """A MUMPS solver with the pivot order ``ordering``: "nested" for the nested dissection
    of the mesh (``node_order()``, computed only then; ``equation_nodes``: the node of every
    equation; ``first``, ``last``: equations eliminated before and after the others, see
    equation_order), or
    one of MUMPS's own orderings by name; ``precision``: MumpsSolver's."""
    if ordering != "nested":
        return MumpsSolver(symmetry, ordering, precision=precision)
    solver = MumpsSolver(symmetry, "amd", precision=precision)
    solver.set_ordering(equation_order(node_order(), equation_nodes, first, last))
    return solver
