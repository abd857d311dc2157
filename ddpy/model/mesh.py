"""Meshes of 8-node hexahedra for the deformable blank.

Node order of an element: the bottom face 0-1-2-3 counter-clockwise seen from above
(+zeta), then the top face 4-5-6-7 above it, as in Abaqus C3D8 and Gmsh.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array, int_array

__all__ = ["HEX_EDGES", "HEX_FACES", "MAX_ELEMENTS", "MAX_NODES", "RIGID_MODES", "BadElement",
           "HexMesh", "MeshError",
           "boundary_faces", "free_rigid_modes",
           "corner_scaled_jacobians", "element_volumes", "face_area_vectors", "find_bad_elements",
           "largest_rotation", "through_thickness_columns", "zeta_along_normal",
           "zeta_off_normal"]

#: Largest mesh (elements) a HexMesh holds, made or read from a deck (docs/input-format.md).
MAX_ELEMENTS = 5_000_000
#: Largest number of nodes: those of MAX_ELEMENTS hexahedra that share none.
MAX_NODES = 8 * MAX_ELEMENTS
#: Relative size below which a Jacobian determinant counts as degenerate.
DEGENERATE = 1e-10
#: A corner of a hexahedron whose scaled Jacobian is at most this is degenerate.
MIN_SCALED_JACOBIAN = 1e-6
#: Bad elements a MeshError's message names (it carries them all).
NAMED_IN_MESSAGE = 3
#: A boundary face belongs to a contact side when its outward normal makes less than
#: about 45 degrees with the side's direction.
SIDE_COSINE = 0.7
#: Most element layers through the thickness that through_thickness_columns follows.
MAX_LAYERS = 64
#: The six faces of an 8-node hexahedron (bottom 0-1-2-3 counter-clockwise seen from the top
#: 4-5-6-7), each ordered counter-clockwise seen from outside the element.
HEX_FACES = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6],
                      [3, 0, 4, 7]])
#: The four edges of each local direction (xi, eta, zeta) of a hexahedron.
HEX_EDGES = np.array([[[0, 1], [3, 2], [4, 5], [7, 6]],
                      [[0, 3], [1, 2], [4, 7], [5, 6]],
                      [[0, 4], [1, 5], [2, 6], [3, 7]]])


def boundary_faces(elements: ArrayLike) -> NDArray[np.int32]:
    """Faces (f, 4) of hexahedra (m, 8) that belong to one element only, counter-clockwise
    seen from outside."""
    faces = np.asarray(elements).reshape(-1, 8)[:, HEX_FACES].reshape(-1, 4)
    _, inverse, counts = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True,
                                   return_counts=True)
    return faces[counts[inverse.reshape(-1)] == 1].astype(np.int32)


def through_thickness_columns(nodes: ArrayLike, elements: ArrayLike, normal: ArrayLike
                              ) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
    """Bottom and top node of the through-thickness column of every node of a sheet meshed in
    layers of hexahedra (one element per layer through the thickness at every point).

    In each element, the four edges of the local direction closest to ``normal`` go through
    the thickness; oriented along ``normal`` they link each node to the one above it. The
    thickness at a node is then the distance between the top and bottom node of its column.
    ValueError when a node would have two different nodes above or below it (the mesh is not
    layered)."""
    x = np.asarray(nodes, dtype=float).reshape(-1, 3)
    e = np.asarray(elements, dtype=np.int64).reshape(-1, 8)
    d = np.asarray(normal, dtype=float)
    n = len(x)
    if len(e) == 0:
        idx = np.arange(n, dtype=np.int32)
        return idx, idx.copy()
    edges = e[:, HEX_EDGES]  # (m, 3, 4, 2)
    vectors = x[edges[..., 1]] - x[edges[..., 0]]  # (m, 3, 4, 3)
    lengths = np.linalg.norm(vectors, axis=-1)
    alignment = np.abs((vectors @ d) / np.where(lengths > 0, lengths, 1.0)).mean(axis=2)
    family = np.argmax(alignment, axis=1)  # (m,)
    worst = int(np.argmin(alignment.max(axis=1)))
    if alignment[worst].max() < 0.5:
        raise ValueError(f"the mesh is not layered through the thickness: no edges of element "
                         f"{worst} run along the sheet normal")
    chosen = edges[np.arange(len(e)), family]  # (m, 4, 2)
    up = (x[chosen[..., 1]] - x[chosen[..., 0]]) @ d >= 0
    lower = np.where(up, chosen[..., 0], chosen[..., 1]).ravel()
    upper = np.where(up, chosen[..., 1], chosen[..., 0]).ravel()
    pairs = np.unique(np.column_stack([lower, upper]), axis=0)
    above = np.full(n, -1, dtype=np.int64)
    below = np.full(n, -1, dtype=np.int64)
    for link, (src, dst) in ((above, (0, 1)), (below, (1, 0))):
        keys, counts = np.unique(pairs[:, src], return_counts=True)
        if np.any(counts > 1):
            node = int(keys[np.argmax(counts > 1)])
            raise ValueError(f"the mesh is not layered through the thickness: node {node} has "
                             f"{int(counts.max())} different neighbours "
                             f"{'above' if src == 0 else 'below'} it")
        link[pairs[:, src]] = pairs[:, dst]
    ends = []
    for link in (below, above):
        end = np.arange(n, dtype=np.int64)
        for _ in range(MAX_LAYERS + 1):  # one pass per layer
            step = link[end]
            moved = step >= 0
            if not moved.any():
                break
            end = np.where(moved, step, end)
        else:
            raise ValueError(f"the mesh is not layered through the thickness: a column of "
                             f"nodes has more than {MAX_LAYERS} layers, or loops")
        ends.append(end.astype(np.int32))
    return ends[0], ends[1]


def _normal_axis(nodes: ArrayLike, elements: ArrayLike, normal: ArrayLike
                 ) -> NDArray[np.int64]:
    """Per element, which of its edge directions (0 xi, 1 eta, 2 zeta: HEX_EDGES) is on
    average the closest to ``normal``."""
    x = np.asarray(nodes, dtype=float).reshape(-1, 3)
    e = np.asarray(elements, dtype=np.int64).reshape(-1, 8)
    vectors = x[e[:, HEX_EDGES][..., 1]] - x[e[:, HEX_EDGES][..., 0]]  # (m, 3, 4, 3)
    lengths = np.linalg.norm(vectors, axis=-1)
    alignment = np.abs(vectors @ np.asarray(normal, dtype=float)) / np.where(lengths > 0,
                                                                              lengths, 1.0)
    return np.argmax(alignment.mean(axis=2), axis=1)


def zeta_off_normal(nodes: ArrayLike, elements: ArrayLike, normal: ArrayLike
                    ) -> NDArray[np.int64]:
    """0-based indices of the elements whose zeta edges (nodes 0-4, 1-5, 2-6, 3-7) are not,
    of their three edge directions, the one closest to ``normal``: the elements the
    solid-shell cannot take as they are (it needs zeta through the thickness)."""
    return np.flatnonzero(_normal_axis(nodes, elements, normal) != 2)


#: Node orders that turn a hexahedron's xi (row 0) or eta (row 1) edges into its zeta edges
#: (nodes 0-4, 1-5, 2-6, 3-7), each a cyclic change of its axes (the volume keeps its sign).
ZETA_FROM = np.array([[0, 3, 7, 4, 1, 2, 6, 5],
                      [0, 4, 5, 1, 3, 7, 6, 2],
                      [0, 1, 2, 3, 4, 5, 6, 7]])


def zeta_along_normal(nodes: ArrayLike, elements: ArrayLike, normal: ArrayLike
                      ) -> NDArray[np.int32]:
    """The elements (m, 8) with each one's nodes reordered so that its zeta edges are, of
    its three edge directions, the one closest to ``normal`` (what the solid-shell needs);
    the same element, by a cyclic change of its axes."""
    e = np.asarray(elements, dtype=np.int64).reshape(-1, 8)
    closest = _normal_axis(nodes, e, normal)
    return np.take_along_axis(e, ZETA_FROM[closest], axis=1).astype(np.int32)


def _frozen(array: NDArray) -> NDArray:
    out = np.array(array)
    out.flags.writeable = False
    return out


def face_area_vectors(nodes: NDArray[np.float64], faces: NDArray[np.integer]
                      ) -> NDArray[np.float64]:
    """Outward area vectors (f, 3) of quadrilateral faces: half the cross product of their
    diagonals."""
    return 0.5 * np.cross(nodes[faces[:, 2]] - nodes[faces[:, 0]],
                          nodes[faces[:, 3]] - nodes[faces[:, 1]])


@dataclass(frozen=True)
class BadElement:
    """An element a mesh cannot be solved on: its 0-based ``index``, its ``label`` (the
    deck's id), what is wrong (``fault``: 'node out of range', 'repeated node', 'inverted'
    or 'degenerate') and ``message``, a sentence naming it by its label."""

    index: int
    label: int
    fault: str
    message: str


class MeshError(ValueError):
    """A mesh that cannot be solved on. ``bad_elements`` lists every element at fault, in
    element order (empty when the fault is not an element's, e.g. a bad shape); ``element``
    is the 0-based index of the first (-1 when there is none)."""

    def __init__(self, message: str, bad_elements: Sequence[BadElement] = ()) -> None:
        super().__init__(message)
        self.bad_elements: tuple[BadElement, ...] = tuple(bad_elements)

    @property
    def element(self) -> int:
        return self.bad_elements[0].index if self.bad_elements else -1

    @classmethod
    def of_elements(cls, bad_elements: Sequence[BadElement]) -> MeshError:
        """The error of one or more bad elements: its message names the first few and says
        how many there are in all."""
        if len(bad_elements) == 1:
            return cls(bad_elements[0].message, bad_elements)
        named = "; ".join(b.message for b in bad_elements[:NAMED_IN_MESSAGE])
        first = ("" if len(bad_elements) <= NAMED_IN_MESSAGE else
                 f", the first {NAMED_IN_MESSAGE}")
        return cls(f"{len(bad_elements)} bad elements{first}: {named}", bad_elements)


#: Corner, and its neighbours along xi, eta, zeta with the sign of each direction.
_CORNERS = np.array([[0, 1, 3, 4], [1, 0, 2, 5], [2, 3, 1, 6], [3, 2, 0, 7],
                     [4, 5, 7, 0], [5, 4, 6, 1], [6, 7, 5, 2], [7, 6, 4, 3]])
_SIGNS = np.array([[1, 1, 1], [-1, 1, 1], [-1, -1, 1], [1, -1, 1],
                   [1, 1, -1], [-1, 1, -1], [-1, -1, -1], [1, -1, -1]], dtype=float)


def corner_scaled_jacobians(nodes: ArrayLike, elements: ArrayLike) -> NDArray[np.float64]:
    """Scaled Jacobian at the 8 corners of each hexahedron, (m, 8): the determinant of the
    three unit edge vectors leaving the corner along xi, eta, zeta. 1 at a corner of a cube,
    whatever its size or aspect ratio; <= 0 at an inverted corner; 0 where an edge has no
    length."""
    return _corner_scaled(_element_coordinates(nodes, elements)).T


def _element_coordinates(nodes: ArrayLike, elements: ArrayLike) -> NDArray[np.float64]:
    """Node coordinates of each element as (3, 8, m): component, corner, element; each
    component of a corner is then one contiguous array over the elements."""
    x = np.ascontiguousarray(np.asarray(nodes, dtype=np.float64).reshape(-1, 3).T)
    return x[:, np.asarray(elements).reshape(-1, 8).T]


def _corner_scaled(coords: NDArray[np.float64]) -> NDArray[np.float64]:
    """corner_scaled_jacobians of element coordinates (3, 8, m), as (8, m)."""
    scaled = np.empty(coords.shape[1:])
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for c, (corner, *neighbours) in enumerate(_CORNERS):
            e1, e2, e3 = ((coords[:, b] - coords[:, corner]) * sign
                          for b, sign in zip(neighbours, _SIGNS[c], strict=True))  # (3, m)
            det = (e1[0] * (e2[1] * e3[2] - e2[2] * e3[1])
                   + e1[1] * (e2[2] * e3[0] - e2[0] * e3[2])
                   + e1[2] * (e2[0] * e3[1] - e2[1] * e3[0]))
            lengths = np.sqrt((e1 * e1).sum(axis=0) * (e2 * e2).sum(axis=0)
                              * (e3 * e3).sum(axis=0))
            scaled[c] = det / lengths
    return np.where(np.isfinite(scaled), scaled, 0.0)


def find_bad_elements(nodes: ArrayLike, elements: ArrayLike,
                      node_ids: ArrayLike | None = None,
                      element_ids: ArrayLike | None = None) -> list[BadElement]:
    """Every element of a hexahedral mesh that cannot be solved on, in element order, each
    with the first of these faults it has; node and element ids name them in the messages
    (default the 0-based indices). The checks, and why each is there:

    - a node index outside the nodes: the element has no geometry;
    - a node repeated within the element: a collapsed edge or face; exact in the indices,
      and the plainest thing to tell (the corner checks would call it degenerate);
    - at a corner, a scaled Jacobian <= MIN_SCALED_JACOBIAN (1e-6): an inverted corner, or
      its three edges nearly in one plane. It measures the corner's shape alone, the same
      for a small, thin or long element; det J > 0 at the Gauss points does not imply it
      (a corner pushed through the element);
    - det J <= DEGENERATE (1e-10) x the element's size cubed / 8 at a Gauss point or a
      corner: the solver integrates at the Gauss points and needs det J > 0 there, which
      the corners do not imply for a twisted element; the floor, relative to the size,
      refuses an element flattened to rounding whatever the angles at its corners.

    The point named is the worst corner when a corner fails, else the worst Gauss point;
    'inverted' when the value there is negative, 'degenerate' else. An inverted element
    usually has its top and bottom faces swapped, or a face listed clockwise."""
    x = np.asarray(nodes, dtype=np.float64).reshape(-1, 3)
    conn = np.asarray(elements).reshape(-1, 8)
    n = len(x)
    node_labels = np.arange(n) if node_ids is None else np.asarray(node_ids)
    labels = (np.arange(len(conn)) if element_ids is None else np.asarray(element_ids)).tolist()
    bad: dict[int, BadElement] = {}

    outside = ((conn < 0) | (conn >= n)).any(axis=1)
    for e in np.flatnonzero(outside).tolist():
        bad[e] = BadElement(e, labels[e], "node out of range",
                            f"element {labels[e]} has node indices {conn[e].tolist()} outside "
                            f"0..{n - 1}")
    inside = np.flatnonzero(~outside)
    conn = np.ascontiguousarray(conn[inside], dtype=np.int32)  # only these have a geometry
    if len(conn) == 0:
        return [bad[e] for e in sorted(bad)]

    ordered = np.sort(conn, axis=1)
    repeats = (ordered[:, 1:] == ordered[:, :-1]).any(axis=1)
    for k in np.flatnonzero(repeats).tolist():
        e = int(inside[k])
        bad[e] = BadElement(e, labels[e], "repeated node", f"element {labels[e]} repeats a "
                            f"node: {node_labels[conn[k]].tolist()}")

    detj, status, element = _core.solid_jacobians(x.ravel(), conn.ravel())
    if status:  # the indices were checked above
        raise ValueError(f"element {element - 1} has a node index out of range")
    detj = detj.reshape(-1, 16)  # 8 Gauss points, then 8 corners
    coords = _element_coordinates(x, conn)
    scaled = _corner_scaled(coords).T  # (m, 8)
    size = (coords.max(axis=1) - coords.min(axis=1)).max(axis=0)
    with np.errstate(over="ignore"):
        low = detj <= (DEGENERATE * size**3 / 8.0)[:, None]
    bad_corner = (scaled <= MIN_SCALED_JACOBIAN) | low[:, 8:]
    bad_gauss = low[:, :8]
    rows = np.flatnonzero((bad_corner.any(axis=1) | bad_gauss.any(axis=1)) & ~repeats)
    if rows.size == 0:
        return [bad[e] for e in sorted(bad)]
    # The worst failing point of each bad element, all at once (a mesh may have many).
    at_corner = bad_corner[rows].any(axis=1)
    corner = np.argmin(np.where(bad_corner[rows], scaled[rows], np.inf), axis=1)
    gauss = np.argmin(np.where(bad_gauss[rows], detj[rows, :8], np.inf), axis=1)
    value = np.where(at_corner, scaled[rows, corner], detj[rows, gauss])
    corner_detj = detj[rows, 8 + corner]
    corner_node = node_labels[conn[rows, corner]]
    hints = {"inverted": "expected the first four counter-clockwise seen from the last four "
                         "above them",
             "degenerate": "the element is flat or collapsed there"}
    for k, on_corner, c, g, v, dj, node, ids in zip(
            rows.tolist(), at_corner.tolist(), corner.tolist(), gauss.tolist(), value.tolist(),
            corner_detj.tolist(), corner_node.tolist(), node_labels[conn[rows]].tolist(),
            strict=True):
        e = int(inside[k])
        fault = "inverted" if v < 0 else "degenerate"
        where = (f"at its corner {c}, node {node} (scaled Jacobian {v:.3g}, det J {dj:.3g})"
                 if on_corner else
                 f"at its Gauss point {g}, next to corner {g} (det J {v:.3g})")
        bad[e] = BadElement(e, labels[e], fault, f"element {labels[e]} is {fault} {where}, "
                            f"nodes {ids}: {hints[fault]}")
    return [bad[e] for e in sorted(bad)]


def _jacobians(nodes: ArrayLike, elements: ArrayLike) -> NDArray[np.float64]:
    """det J of each hexahedron (m, 16): 8 Gauss points, then 8 corners (the core's)."""
    x = np.ascontiguousarray(nodes, dtype=np.float64).ravel()
    conn = np.ascontiguousarray(elements, dtype=np.int32).ravel()
    detj, status, element = _core.solid_jacobians(x, conn)
    if status:
        raise ValueError(f"element {element - 1} has a node index out of range")
    return detj.reshape(-1, 16)


def element_volumes(nodes: ArrayLike, elements: ArrayLike) -> NDArray[np.float64]:
    """Each hexahedron's volume (m,): det J at 2 x 2 x 2 Gauss points, exact for trilinear
    hexahedra (negative for an inverted one). Nodes (n, 3), elements (m, 8) of 0-based
    indices; no other check (HexMesh checks its own)."""
    return _jacobians(nodes, elements)[:, :8].sum(axis=1)


class HexMesh:
    """The blank: nodes (n, 3) in mm and 8-node hexahedra (m, 8) of 0-based node indices,
    checked on creation, with the labels of its deck (``node_ids``, ``element_ids``;
    default the 0-based indices), the sheet normal (a unit vector along a global axis:
    ``top`` is the side it points to) and where it came from (``source``, for messages).
    The arrays are read-only: the mesh is the reference configuration of a run.

    Raises :class:`MeshError` for bad shapes and for bad elements: it lists every element
    :func:`find_bad_elements` finds (node indices out of range, a repeated node, inverted or
    degenerate at a corner or a Gauss point) and its message names the first few by their
    labels.
    """

    def __init__(self, nodes: ArrayLike, elements: ArrayLike,
                 node_ids: ArrayLike | None = None, element_ids: ArrayLike | None = None,
                 normal: ArrayLike = (0.0, 0.0, 1.0), source: str = "") -> None:
        self.nodes = _frozen(float_array(nodes, "nodes", (None, 3)))
        self.elements = _frozen(int_array(elements, "elements", (None, 8)))
        n, m = self.nodes.shape[0], self.elements.shape[0]
        if n == 0 or m == 0:
            raise MeshError("a mesh needs at least one node and one element")
        if m > MAX_ELEMENTS or n > MAX_NODES:
            raise MeshError(f"a mesh of {n} nodes and {m} elements: at most {MAX_NODES} "
                            f"nodes and {MAX_ELEMENTS} elements")
        self.node_ids = _frozen(np.arange(n) if node_ids is None else
                                int_array(node_ids, "node_ids", (n,)).astype(np.int64))
        self.element_ids = _frozen(np.arange(m) if element_ids is None else
                                   int_array(element_ids, "element_ids", (m,)).astype(np.int64))
        axis = float_array(normal, "normal", (3,))
        if np.count_nonzero(axis) != 1 or abs(float(np.abs(axis).sum()) - 1.0) > 1e-12:
            raise MeshError(f"the sheet normal must be a unit vector along x, y or z, got "
                            f"{axis.tolist()}")
        self.normal: tuple[float, float, float] = (float(axis[0]), float(axis[1]),
                                                   float(axis[2]))
        self.source = source
        bad = find_bad_elements(self.nodes, self.elements, self.node_ids, self.element_ids)
        if bad:
            raise MeshError.of_elements(bad)

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def n_elements(self) -> int:
        return int(self.elements.shape[0])

    def jacobians(self, displacement: ArrayLike | None = None) -> NDArray[np.float64]:
        """det J of the reference map, (m, 16): 8 Gauss points, then 8 corners; of the
        nodes moved by ``displacement`` (n, 3) when it is given."""
        x = self.nodes if displacement is None else \
            self.nodes + float_array(displacement, "displacement", (self.n_nodes, 3))
        return _jacobians(x, self.elements)

    def element_volumes(self, displacement: ArrayLike | None = None) -> NDArray[np.float64]:
        """Each element's volume (m,) (element_volumes), of the nodes moved by
        ``displacement`` (n, 3) when it is given."""
        return self.jacobians(displacement)[:, :8].sum(axis=1)

    def volume(self, displacement: ArrayLike | None = None) -> float:
        """Total volume (element_volumes summed)."""
        return float(self.element_volumes(displacement).sum())

    def element_size(self) -> float:
        """The mean element size: the cube root of the mean element volume (mm)."""
        return (self.volume() / self.n_elements) ** (1.0 / 3.0)

    def select(self, x: float | None = None, y: float | None = None, z: float | None = None,
               tol: float = 1e-9) -> NDArray[np.int32]:
        """Indices of the nodes with the given coordinates (within tol), e.g. on a plane."""
        mask = np.ones(self.n_nodes, dtype=bool)
        for axis, value in enumerate((x, y, z)):
            if value is not None:
                mask &= np.abs(self.nodes[:, axis] - value) <= tol
        return np.flatnonzero(mask).astype(np.int32)

    @property
    def normal_axis(self) -> int:
        """Index of the global axis of the sheet normal."""
        return int(np.argmax(np.abs(self.normal)))

    def bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Lower and upper corners of the bounding box."""
        return self.nodes.min(axis=0), self.nodes.max(axis=0)

    def index(self, ids: ArrayLike) -> NDArray[np.int32]:
        """0-based indices of node labels; -1 where a label is not in the mesh."""
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        order = np.argsort(self.node_ids, kind="stable")
        sorted_ids = self.node_ids[order]
        pos = np.clip(np.searchsorted(sorted_ids, ids), 0, len(sorted_ids) - 1)
        found = sorted_ids[pos] == ids
        return np.where(found, order[pos], -1).astype(np.int32)

    def boundary_faces(self) -> NDArray[np.int32]:
        """Faces (f, 4) that belong to one element only, counter-clockwise seen from outside."""
        return boundary_faces(self.elements)

    def face_normals(self, faces: NDArray[np.int32],
                     nodes: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        """Unit outward normals (f, 3) of quadrilateral faces (cross product of diagonals),
        at the reference nodes or at ``nodes``."""
        n = face_area_vectors(self.nodes if nodes is None else nodes, faces)
        length = np.linalg.norm(n, axis=1, keepdims=True)
        return n / np.where(length > 0, length, 1.0)

    def surface_nodes(self, direction: ArrayLike, cosine: float = SIDE_COSINE
                      ) -> NDArray[np.int32]:
        """Nodes of the boundary faces whose outward normal makes an angle of less than
        arccos(cosine) with ``direction``: the nodes a tool on that side can touch."""
        d = np.asarray(direction, dtype=float)
        d = d / np.linalg.norm(d)
        faces = self.boundary_faces()
        facing = self.face_normals(faces) @ d > cosine
        return np.unique(faces[facing]).astype(np.int32)

    def columns(self) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
        """For each node, the bottom and top node of its through-thickness column; ValueError
        when the mesh is not layered through the thickness (see through_thickness_columns)."""
        return through_thickness_columns(self.nodes, self.elements, self.normal)

    def initial_thickness(self) -> float:
        """The blank's thickness (mm): the thinnest of its through-thickness columns that
        span more than one node, or its extent along its normal when it is not layered."""
        try:
            bottom, top = self.columns()
        except ValueError:
            return float(np.ptp(self.nodes[:, self.normal_axis]))
        spanning = top != bottom
        if not spanning.any():
            return float(np.ptp(self.nodes[:, self.normal_axis]))
        x = self.nodes
        return float(np.linalg.norm(x[top[spanning]] - x[bottom[spanning]], axis=1).min())

    def thickness(self, displacement: ArrayLike | None = None) -> NDArray[np.float64]:
        """Per node, the distance between the top and bottom node of its column, in the
        current configuration (nodes + displacement)."""
        bottom, top = self.columns()
        x = self.nodes if displacement is None else self.nodes + np.reshape(displacement,
                                                                            (-1, 3))
        return np.linalg.norm(x[top] - x[bottom], axis=1)

    @classmethod
    def box(cls, lx: float, ly: float, lz: float, nx: int, ny: int, nz: int,
            origin: ArrayLike = (0.0, 0.0, 0.0)) -> HexMesh:
        """Structured mesh of the box [0, lx] x [0, ly] x [0, lz] (shifted by origin) with
        nx x ny x nz elements (at most MAX_ELEMENTS, checked before anything is allocated);
        node (i, j, k) has index i + (nx + 1) (j + (ny + 1) k)."""
        for name, value in (("lx", lx), ("ly", ly), ("lz", lz)):
            if not float(value) > 0.0:
                raise ValueError(f"{name} must be positive, got {value}")
        for name, value in (("nx", nx), ("ny", ny), ("nz", nz)):
            if int(value) != value or int(value) < 1:
                raise ValueError(f"{name} must be a positive integer, got {value}")
        nx, ny, nz = int(nx), int(ny), int(nz)
        if nx * ny * nz > MAX_ELEMENTS:
            raise MeshError(f"the box has {nx * ny * nz} elements ({nx} x {ny} x {nz}): at "
                            f"most {MAX_ELEMENTS}")
        x0 = float_array(origin, "origin", (3,))
        gx, gy, gz = (np.linspace(0.0, float(length), count + 1)
                      for length, count in ((lx, nx), (ly, ny), (lz, nz)))
        zz, yy, xx = np.meshgrid(gz, gy, gx, indexing="ij")
        nodes = np.column_stack([xx.ravel(), yy.ravel(), zz.ravel()]) + x0
        index = np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nz + 1, ny + 1, nx + 1)
        c = index[:-1, :-1, :-1]
        elements = np.stack([
            c, index[:-1, :-1, 1:], index[:-1, 1:, 1:], index[:-1, 1:, :-1],
            index[1:, :-1, :-1], index[1:, :-1, 1:], index[1:, 1:, 1:], index[1:, 1:, :-1],
        ], axis=-1).reshape(-1, 8)
        return cls(nodes, elements)

    def __repr__(self) -> str:
        return f"HexMesh({self.n_nodes} nodes, {self.n_elements} hexahedra)"


def largest_rotation(x: NDArray[np.float64], elements: NDArray[np.integer],
                     du: NDArray[np.float64]) -> float:
    """Largest element rotation (radians) of a displacement increment du (n, 3) of the mesh
    at positions x (n, 3): the axial vector of the skew part of the gradient of the linear
    field that fits each element's nodal increments in least squares (the r_min rotation
    limit, docs/theory/contact.md)."""
    coords = x[elements] - x[elements].mean(axis=1, keepdims=True)   # (m, 8, 3)
    moves = du[elements] - du[elements].mean(axis=1, keepdims=True)  # (m, 8, 3)
    gram = np.einsum("mai,maj->mij", coords, coords)
    gradient = np.linalg.solve(gram, np.einsum("mai,maj->mij", coords, moves))
    skew = 0.5 * (gradient - gradient.transpose(0, 2, 1))
    axial = np.stack([skew[:, 1, 2], skew[:, 2, 0], skew[:, 0, 1]], axis=1)
    return float(np.linalg.norm(axial, axis=1).max()) if len(axial) else 0.0


#: The six rigid-body motions, in the order of free_rigid_modes' columns.
RIGID_MODES = ("translation along x", "translation along y", "translation along z",
               "rotation about x", "rotation about y", "rotation about z")


def free_rigid_modes(x: ArrayLike, fixed: ArrayLike) -> NDArray[np.float64]:
    """The rigid-body motions of a body with nodes at ``x`` (n, 3) that the fixed dofs
    ``fixed`` (n, 3) leave free: an orthonormal basis (k, 6) of (translation, rotation about
    the centroid) vectors, none when every motion is stopped. A motion is stopped where it
    moves a fixed dof: its rows are the six motions along each fixed dof's direction, the
    rotations' arms scaled by the body's size, so that the rank test (singular values above
    1e-9) does not depend on units."""
    x = float_array(x, "x", (None, 3))
    node, axis = np.nonzero(np.asarray(fixed, dtype=bool))
    if not node.size:
        return np.eye(6)
    arm = (x[node] - x.mean(axis=0)) / max(float(np.ptp(x, axis=0).max()), 1e-300)
    direction = np.eye(3)[axis]
    rows = np.concatenate([direction, np.cross(arm, direction)], axis=1)
    _, sing, vt = np.linalg.svd(rows, full_matrices=True)
    rank = int((sing > 1e-9).sum())
    return vt[rank:]
