"""Meshes of 8-node hexahedra for the deformable blank.

Node order of an element: the bottom face 0-1-2-3 counter-clockwise seen from above
(+zeta), then the top face 4-5-6-7 above it, as in Abaqus C3D8 and Gmsh.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array, int_array

__all__ = ["HEX_EDGES", "HEX_FACES", "HexMesh", "MeshError", "boundary_faces",
           "face_area_vectors", "largest_rotation", "through_thickness_columns"]

#: Relative size below which a Jacobian determinant counts as degenerate.
DEGENERATE = 1e-10
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


class MeshError(ValueError):
    """A mesh that cannot be solved on: ``element`` is the 0-based index of the element at
    fault (-1 when the fault is not one element's)."""

    def __init__(self, message: str, element: int = -1) -> None:
        super().__init__(message)
        self.element = element


class HexMesh:
    """The blank: nodes (n, 3) in mm and 8-node hexahedra (m, 8) of 0-based node indices,
    checked on creation, with the labels of its deck (``node_ids``, ``element_ids``;
    default the 0-based indices), the sheet normal (a unit vector along a global axis:
    ``top`` is the side it points to) and where it came from (``source``, for messages).
    The arrays are read-only: the mesh is the reference configuration of a run.

    Raises :class:`MeshError` for bad shapes, node indices out of range, repeated nodes in
    an element, and inverted or degenerate elements (det J <= 0, or below 1e-10 of the
    element's size cubed, at a Gauss point or a corner), naming the element by its label.
    """

    def __init__(self, nodes: ArrayLike, elements: ArrayLike,
                 node_ids: ArrayLike | None = None, element_ids: ArrayLike | None = None,
                 normal: ArrayLike = (0.0, 0.0, 1.0), source: str = "") -> None:
        self.nodes = _frozen(float_array(nodes, "nodes", (None, 3)))
        self.elements = _frozen(int_array(elements, "elements", (None, 8)))
        n, m = self.nodes.shape[0], self.elements.shape[0]
        if n == 0 or m == 0:
            raise MeshError("a mesh needs at least one node and one element")
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
        labels = self.element_ids
        bad = np.flatnonzero((self.elements < 0).any(axis=1) | (self.elements >= n).any(axis=1))
        if bad.size:
            e = int(bad[0])
            raise MeshError(f"element {labels[e]} has node indices {self.elements[e].tolist()} "
                            f"outside 0..{n - 1}", e)
        ordered = np.sort(self.elements, axis=1)
        bad = np.flatnonzero((ordered[:, 1:] == ordered[:, :-1]).any(axis=1))
        if bad.size:
            e = int(bad[0])
            raise MeshError(f"element {labels[e]} repeats a node: "
                            f"{self.node_ids[self.elements[e]].tolist()}", e)
        detj = self.jacobians()
        size = np.ptp(self.nodes[self.elements], axis=1).max(axis=1)
        floor = DEGENERATE * size**3 / 8.0
        bad = np.flatnonzero((detj <= floor[:, None]).any(axis=1))
        if bad.size:
            e = int(bad[0])
            where = int(np.argmin(detj[e]))
            place = f"Gauss point {where}" if where < 8 else f"corner {where - 8}"
            kind = "inverted" if detj[e, where] < 0 else "degenerate"
            raise MeshError(
                f"element {labels[e]} is {kind}: det J = {detj[e, where]:.3g} at {place} "
                f"(nodes {self.node_ids[self.elements[e]].tolist()}; expected the bottom face "
                "0-1-2-3 counter-clockwise seen from the top face 4-5-6-7)", e)

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def n_elements(self) -> int:
        return int(self.elements.shape[0])

    def jacobians(self) -> NDArray[np.float64]:
        """det J of the reference map, (m, 16): 8 Gauss points, then 8 corners."""
        detj, status, element = _core.solid_jacobians(self.nodes.ravel(), self.elements.ravel())
        if status:
            raise ValueError(f"element {element - 1} has a node index out of range")
        return detj.reshape(-1, 16)

    def volume(self) -> float:
        """Total volume (2 x 2 x 2 Gauss points: exact for trilinear hexahedra)."""
        return float(self.jacobians()[:, :8].sum())

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
        nx x ny x nz elements; node (i, j, k) has index i + (nx + 1) (j + (ny + 1) k)."""
        for name, value in (("lx", lx), ("ly", ly), ("lz", lz)):
            if not float(value) > 0.0:
                raise ValueError(f"{name} must be positive, got {value}")
        for name, value in (("nx", nx), ("ny", ny), ("nz", nz)):
            if int(value) != value or int(value) < 1:
                raise ValueError(f"{name} must be a positive integer, got {value}")
        nx, ny, nz = int(nx), int(ny), int(nz)
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
