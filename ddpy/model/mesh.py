"""Meshes of 8-node hexahedra for the deformable blank.

Node order of an element: the bottom face 0-1-2-3 counter-clockwise seen from above
(+zeta), then the top face 4-5-6-7 above it, as in Abaqus C3D8 and Gmsh.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array, int_array

__all__ = ["HEX_EDGES", "HEX_FACES", "HexMesh", "boundary_faces", "face_area_vectors"]

#: Relative size below which a Jacobian determinant counts as degenerate.
DEGENERATE = 1e-10
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


def face_area_vectors(nodes: NDArray[np.float64], faces: NDArray[np.integer]
                      ) -> NDArray[np.float64]:
    """Outward area vectors (f, 3) of quadrilateral faces: half the cross product of their
    diagonals."""
    return 0.5 * np.cross(nodes[faces[:, 2]] - nodes[faces[:, 0]],
                          nodes[faces[:, 3]] - nodes[faces[:, 1]])


class HexMesh:
    """Nodes (n, 3) and hexahedra (m, 8) of 0-based node indices, checked on creation.

    Raises ValueError for bad shapes, node indices out of range, repeated nodes in an
    element, and inverted or degenerate elements (det J <= 0, or below 1e-10 of the
    element's size cubed, at a Gauss point or a corner), naming the element.
    """

    def __init__(self, nodes: ArrayLike, elements: ArrayLike) -> None:
        self.nodes = float_array(nodes, "nodes", (None, 3))
        self.elements = int_array(elements, "elements", (None, 8))
        n, m = self.nodes.shape[0], self.elements.shape[0]
        if n == 0 or m == 0:
            raise ValueError("a mesh needs at least one node and one element")
        bad = np.flatnonzero((self.elements < 0).any(axis=1) | (self.elements >= n).any(axis=1))
        if bad.size:
            e = int(bad[0])
            raise ValueError(
                f"element {e} has node indices {self.elements[e].tolist()} outside 0..{n - 1}")
        ordered = np.sort(self.elements, axis=1)
        bad = np.flatnonzero((ordered[:, 1:] == ordered[:, :-1]).any(axis=1))
        if bad.size:
            e = int(bad[0])
            raise ValueError(f"element {e} repeats a node: {self.elements[e].tolist()}")
        detj = self.jacobians()
        size = np.ptp(self.nodes[self.elements], axis=1).max(axis=1)
        floor = DEGENERATE * size**3 / 8.0
        bad = np.flatnonzero((detj <= floor[:, None]).any(axis=1))
        if bad.size:
            e = int(bad[0])
            where = int(np.argmin(detj[e]))
            place = f"Gauss point {where}" if where < 8 else f"corner {where - 8}"
            kind = "inverted" if detj[e, where] < 0 else "degenerate"
            raise ValueError(
                f"element {e} is {kind}: det J = {detj[e, where]:.3g} at {place} "
                f"(nodes {self.elements[e].tolist()}; expected the bottom face 0-1-2-3 "
                "counter-clockwise seen from the top face 4-5-6-7)")

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
