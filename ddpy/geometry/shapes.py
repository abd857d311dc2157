"""Exact analytic surfaces: closest points, signed distances, normals and meshes.

They serve as reference geometry (tests, accuracy studies) and as exact tools. Every shape
answers ``closest_point``, ``signed_distance`` (positive on the side the normal points to)
and ``normal`` (outward unit normal at the closest point) for points (k, 3), and ``mesh``
gives vertices on the exact surface with exact normals and faces in the layout of
:class:`ddpy.geometry.surfaces.NagataSurface` (counter-clockwise seen from outside, -1 in the last
column of a triangle).

>>> import numpy as np
>>> from ddpy.geometry.shapes import Sphere
>>> Sphere(2.0).signed_distance([[0, 0, 3], [1, 0, 0]]).tolist()
[1.0, -1.0]
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy._validate import float_array

__all__ = ["Sphere", "Cylinder", "Torus", "Mesh"]

#: vertices (nv, 3), outward unit normals (nv, 3), faces (m, 4) with -1 closing a triangle.
Mesh = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int32]]
Projection = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]


def _unit(v: NDArray[np.float64], fallback: ArrayLike) -> NDArray[np.float64]:
    """Rows of ``v`` scaled to unit length; zero rows become ``fallback``."""
    length = np.linalg.norm(v, axis=1, keepdims=True)
    zero = length[:, 0] == 0.0
    u = v / np.where(zero[:, None], 1.0, length)
    u[zero] = fallback
    return u


def _positive(value: float, name: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a positive number, got {value}")
    return value


def _grid_faces(ids: NDArray[np.int64], kind: str) -> NDArray[np.int32]:
    """Faces of a structured grid of vertex ids (nu + 1, nv + 1).

    The cell (i, j) is (i, j), (i+1, j), (i+1, j+1), (i, j+1): counter-clockwise when the
    first grid direction crossed with the second points outward. Triangles split each cell
    along alternating diagonals.
    """
    a, b = ids[:-1, :-1].ravel(), ids[1:, :-1].ravel()
    c, d = ids[1:, 1:].ravel(), ids[:-1, 1:].ravel()
    if kind == "quad":
        return np.column_stack([a, b, c, d]).astype(np.int32)
    i, j = np.meshgrid(np.arange(ids.shape[0] - 1), np.arange(ids.shape[1] - 1), indexing="ij")
    flip = ((i + j) % 2 == 1).ravel()
    first = np.where(flip[:, None], np.column_stack([a, b, d]), np.column_stack([a, b, c]))
    second = np.where(flip[:, None], np.column_stack([b, c, d]), np.column_stack([a, c, d]))
    tris = np.stack([first, second], axis=1).reshape(-1, 3)
    return np.column_stack([tris, np.full(len(tris), -1)]).astype(np.int32)


def _check_mesh_args(n: int, kind: str) -> None:
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"n (segments per quarter circle) must be an integer >= 1, got {n!r}")
    if kind not in ("quad", "tri"):
        raise ValueError(f'kind must be "quad" or "tri", got {kind!r}')


class _Shape:
    """Queries shared by every shape; subclasses provide ``_project``."""

    def _project(self, p: NDArray[np.float64]) -> Projection:
        """Closest points, outward unit normals there and signed distances of points p."""
        raise NotImplementedError

    def _query(self, points: ArrayLike) -> Projection:
        return self._project(float_array(points, "points", (None, 3)))

    def closest_point(self, points: ArrayLike) -> NDArray[np.float64]:
        """Closest points (k, 3) on the surface to ``points`` (k, 3)."""
        return self._query(points)[0]

    def normal(self, points: ArrayLike) -> NDArray[np.float64]:
        """Outward unit normals (k, 3) at the closest points of ``points`` (k, 3)."""
        return self._query(points)[1]

    def signed_distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """Distances (k,) to the surface, positive outside (the side the normal points to)."""
        return self._query(points)[2]


class Sphere(_Shape):
    """Sphere of ``radius`` about ``center``."""

    def __init__(self, radius: float, center: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        self.radius = _positive(radius, "radius")
        self.center = float_array(center, "center", (3,))

    def _project(self, p: NDArray[np.float64]) -> Projection:
        v = p - self.center
        normal = _unit(v, (0.0, 0.0, 1.0))  # the center projects to the north pole
        return (self.center + self.radius * normal, normal,
                np.linalg.norm(v, axis=1) - self.radius)

    def mesh(self, n: int, kind: Literal["quad", "tri"] = "quad") -> Mesh:
        """Cube sphere: each cube face an n x n grid, equal angles, projected radially."""
        _check_mesh_args(n, kind)
        # Integer lattice on the cube [0, n]^3: faces share their border points exactly.
        i, j = (g.ravel() for g in np.meshgrid(np.arange(n + 1), np.arange(n + 1),
                                                indexing="ij"))
        lattice, grids = [], []
        for axis in range(3):
            p, q = (axis + 1) % 3, (axis + 2) % 3  # e_p x e_q = e_axis
            for side in (0, n):
                u, v = (i, j) if side else (j, i)  # swap on the -axis face: still outward
                point = np.empty((len(i), 3), dtype=np.int64)
                point[:, axis], point[:, p], point[:, q] = side, u, v
                lattice.append(point)
        keys, inverse = np.unique(np.vstack(lattice), axis=0, return_inverse=True)
        for f in range(6):
            grids.append(inverse.ravel()[f * (n + 1) ** 2:(f + 1) * (n + 1) ** 2]
                         .reshape(n + 1, n + 1))
        normals = _unit(np.tan(np.pi / 4.0 * (2.0 * keys / n - 1.0)), (0.0, 0.0, 1.0))
        faces = np.vstack([_grid_faces(g, kind) for g in grids])
        return self.center + self.radius * normals, normals, faces


class Cylinder(_Shape):
    """Lateral surface of a cylinder (no end caps): axis z, from z = 0 to ``height``."""

    def __init__(self, radius: float, height: float) -> None:
        self.radius = _positive(radius, "radius")
        self.height = _positive(height, "height")

    def _project(self, p: NDArray[np.float64]) -> Projection:
        radial = np.column_stack([p[:, :2], np.zeros(len(p))])
        normal = _unit(radial, (1.0, 0.0, 0.0))  # the axis projects towards +x
        closest = self.radius * normal
        closest[:, 2] = np.clip(p[:, 2], 0.0, self.height)
        outside = np.linalg.norm(radial, axis=1) >= self.radius
        distance = np.linalg.norm(p - closest, axis=1)
        return closest, normal, np.where(outside, distance, -distance)

    def mesh(self, n: int, kind: Literal["quad", "tri"] = "quad") -> Mesh:
        """4n segments around and near-square cells along the height."""
        _check_mesh_args(n, kind)
        around = 4 * n
        along = max(1, round(self.height / (self.radius * np.pi / (2 * n))))
        theta = 2.0 * np.pi * np.arange(around) / around
        z = np.linspace(0.0, self.height, along + 1)
        rim = np.column_stack([np.cos(theta), np.sin(theta), np.zeros(around)])
        normals = np.tile(rim, (along + 1, 1))
        vertices = self.radius * normals
        vertices[:, 2] = np.repeat(z, around)
        i, j = np.meshgrid(np.arange(around + 1), np.arange(along + 1), indexing="ij")
        return vertices, normals, _grid_faces(i % around + around * j, kind)


class Torus(_Shape):
    """Ring torus about the z axis: circle of radius ``major`` swept by a tube of ``minor``."""

    def __init__(self, major: float, minor: float) -> None:
        self.major = _positive(major, "major")
        self.minor = _positive(minor, "minor")
        if self.minor >= self.major:
            raise ValueError(f"need minor < major for a ring torus, got {minor} >= {major}")

    def _project(self, p: NDArray[np.float64]) -> Projection:
        radial = _unit(np.column_stack([p[:, :2], np.zeros(len(p))]), (1.0, 0.0, 0.0))
        v = p - self.major * radial  # from the nearest point of the tube's core circle
        normal = _unit(v, 0.0)
        core = np.all(normal == 0.0, axis=1)
        normal[core] = radial[core]  # points on the core circle project outward
        return (self.major * radial + self.minor * normal, normal,
                np.linalg.norm(v, axis=1) - self.minor)

    def mesh(self, n: int, kind: Literal["quad", "tri"] = "quad") -> Mesh:
        """4n segments around the tube, about 4n major/minor around the axis."""
        _check_mesh_args(n, kind)
        tube = 4 * n
        around = max(3, round(tube * self.major / self.minor))
        phi = np.repeat(2.0 * np.pi * np.arange(around) / around, tube)
        theta = np.tile(2.0 * np.pi * np.arange(tube) / tube, around)
        normals = np.column_stack([np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi),
                                   np.sin(theta)])
        centres = self.major * np.column_stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)])
        i, j = np.meshgrid(np.arange(around + 1), np.arange(tube + 1), indexing="ij")
        return centres + self.minor * normals, normals, _grid_faces(i % around * tube + j % tube,
                                                                     kind)
