"""Accuracy of vertex normals estimated from a mesh, and of the Nagata patches built on them.

The 3D counterpart of :mod:`ddpy.studies.accuracy` (the paper's Fig. 3 and 4 on an arc):
exact surfaces given by a parametrization (a cylinder, a sphere cap, a torus band running from
its outer to its inner equator, a saddle), meshed in their parameter rectangle at a size h
(structured, perturbed or unstructured; quadrilaterals or triangles), vertices placed exactly
on the surface. Against the exact normals and the exact surface it measures

- :func:`normal_errors`: the angle between each estimated vertex normal
  (:func:`ddpy.geometry.mesh_normals.estimate_normals`) and the exact one;
- :func:`shape_errors`: the distance from the Nagata patches (estimated or exact normals) and
  from the flat facets of the mesh to the exact surface, on a grid of samples per patch,
  each projected on the surface by Gauss-Newton from its parameters.

``benchmarks/mesh_normals/run.py`` runs the refinement study and writes the report.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ddpy.geometry.mesh_normals import estimate_normals
from ddpy.geometry.surfaces import NagataSurface

__all__ = ["MESH_KINDS", "SURFACES", "ExactSurface", "MeshSample", "angle_between",
           "fit_order", "make_mesh", "normal_errors", "shape_errors"]

#: Structured grids, the same with interior vertices moved at random by up to 30 % of the
#: spacing, and gmsh's Frontal-Delaunay (recombined by Blossom for quadrilaterals).
MESH_KINDS = ("structured quad", "structured tri", "perturbed quad", "perturbed tri",
              "unstructured quad", "unstructured tri")
_PERTURBATION = 0.3


def angle_between(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angles (degrees) between rows of a and b, accurate down to 1e-14 rad."""
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.degrees(np.arctan2(cross, np.einsum("...i,...i->...", a, b)))


def fit_order(h: NDArray[np.float64], error: NDArray[np.float64]) -> float:
    """Least-squares slope of log(error) against log(h)."""
    return float(np.polyfit(np.log(h), np.log(np.maximum(error, 1e-300)), 1)[0])


@dataclass(frozen=True)
class ExactSurface:
    """A parametrized surface on the rectangle ``bounds`` ((u0, u1), (v0, v1)) in mm of arc
    (so a mesh of the rectangle is near isotropic on the surface); ``radius`` the smallest
    radius of curvature, the length the element sizes are given against. ``evaluate(u, v)``
    answers points (k, 3) and the two tangents (k, 2, 3); S_u x S_v points to the normal's
    side."""

    name: str
    radius: float
    bounds: tuple[tuple[float, float], tuple[float, float]]
    evaluate: Callable[[NDArray[np.float64], NDArray[np.float64]],
                       tuple[NDArray[np.float64], NDArray[np.float64]]]
    description: str = ""

    def point(self, uv: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.evaluate(uv[:, 0], uv[:, 1])[0]

    def normal(self, uv: NDArray[np.float64]) -> NDArray[np.float64]:
        d = self.evaluate(uv[:, 0], uv[:, 1])[1]
        n = np.cross(d[:, 0], d[:, 1])
        return n / np.linalg.norm(n, axis=1)[:, None]

    def project(self, x: NDArray[np.float64], uv: NDArray[np.float64], iterations: int = 12
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Closest points of ``x`` from the guesses ``uv`` (Gauss-Newton; the surface is
        extended beyond its rectangle): (signed distances along the normal, parameters)."""
        uv = uv.copy()
        for _ in range(iterations):
            s, d = self.evaluate(uv[:, 0], uv[:, 1])
            jtj = np.einsum("kai,kbi->kab", d, d)
            step = np.linalg.solve(jtj, np.einsum("kai,ki->ka", d, x - s)[..., None])[..., 0]
            uv += step
            if np.abs(step).max() < 1e-14 * self.radius:
                break
        s, _ = self.evaluate(uv[:, 0], uv[:, 1])
        return np.einsum("ij,ij->i", x - s, self.normal(uv)), uv


def _cylinder(radius: float = 10.0, length: float = 15.0) -> ExactSurface:
    """A quarter of a cylinder, axis y, crown up: theta in [-45, 45] degrees from +z."""

    def evaluate(u, v):
        t = u / radius
        s, c = np.sin(t), np.cos(t)
        x = np.column_stack([radius * s, v, radius * c])
        d = np.stack([np.column_stack([c, 0 * v, -s]),
                      np.column_stack([0 * u, np.ones_like(v), 0 * u])], axis=1)
        return x, d

    q = radius * np.pi / 4
    return ExactSurface("cylinder", radius, ((-q, q), (0.0, length)), evaluate,
                        f"radius {radius:g}, 90 degrees of arc, {length:g} long")


def _sphere(radius: float = 10.0) -> ExactSurface:
    """A sphere cap: one face of the cube sphere, 90 degrees across."""

    def evaluate(u, v):
        a, b = np.tan(u / radius), np.tan(v / radius)
        p = np.column_stack([a, b, np.ones_like(a)])
        length = np.linalg.norm(p, axis=1)
        x = radius * p / length[:, None]
        da = np.column_stack([1 + a * a, 0 * a, 0 * a]) / radius   # dp/du
        db = np.column_stack([0 * b, 1 + b * b, 0 * b]) / radius
        derivatives = []
        for dp in (da, db):
            along = np.einsum("ij,ij->i", p, dp) / length**2
            derivatives.append(radius * (dp - p * along[:, None]) / length[:, None])
        return x, np.stack(derivatives, axis=1)

    q = radius * np.pi / 4
    return ExactSurface("sphere", radius, ((-q, q), (-q, q)), evaluate,
                        f"radius {radius:g}, a cap 90 degrees across")


def _torus(major: float = 20.0, minor: float = 6.0) -> ExactSurface:
    """A band of a torus: 60 degrees around its axis z, the tube from its outer equator
    over the top to its inner equator (positive, zero and negative Gaussian curvature)."""

    def evaluate(u, v):
        phi, theta = u / major, v / minor
        r = major + minor * np.cos(theta)
        cp, sp, ct, st = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta)
        x = np.column_stack([r * cp, r * sp, minor * st])
        du = np.column_stack([-r * sp, r * cp, 0 * r]) / major
        dv = np.column_stack([-st * cp, -st * sp, ct])
        return x, np.stack([du, dv], axis=1)

    return ExactSurface("torus", minor, ((0.0, major * np.pi / 3), (0.0, minor * np.pi)),
                        evaluate, f"radii {major:g} and {minor:g}, 60 degrees around, "
                        "outer to inner equator")


def _saddle(radius: float = 10.0, half: float = 8.0) -> ExactSurface:
    """The saddle z = (x^2 - y^2) / (2 radius) over a square."""

    def evaluate(u, v):
        x = np.column_stack([u, v, (u * u - v * v) / (2 * radius)])
        du = np.column_stack([np.ones_like(u), 0 * u, u / radius])
        dv = np.column_stack([0 * v, np.ones_like(v), -v / radius])
        return x, np.stack([du, dv], axis=1)

    return ExactSurface("saddle", radius, ((-half, half), (-half, half)), evaluate,
                        f"z = (x^2 - y^2) / {2 * radius:g} over a square {2 * half:g} across")


SURFACES: dict[str, Callable[[], ExactSurface]] = {
    "cylinder": _cylinder, "sphere": _sphere, "torus": _torus, "saddle": _saddle}


@dataclass
class MeshSample:
    """A mesh of an exact surface: vertices on it, their parameters, faces (m, 4) (-1 last for
    a triangle) counter-clockwise seen from the normal side, exact vertex normals."""

    surface: ExactSurface
    kind: str
    h: float
    vertices: NDArray[np.float64]
    uv: NDArray[np.float64]
    faces: NDArray[np.int64]
    normals: NDArray[np.float64]

    @property
    def mean_edge(self) -> float:
        """Mean edge length (mm)."""
        c = np.where(self.faces < 0, self.faces[:, :1], self.faces)
        x = self.vertices[c]
        return float(np.linalg.norm(x - np.roll(x, -1, axis=1), axis=2)[
            np.roll(self.faces, -1, axis=1) >= 0].mean())


def make_mesh(surface: ExactSurface, kind: str, per_arc: int, seed: int = 0) -> MeshSample:
    """A mesh of ``kind`` (:data:`MESH_KINDS`) with elements of about ``per_arc`` per 90
    degrees of the smallest radius of curvature: h = (pi / 2) radius / per_arc."""
    if kind not in MESH_KINDS:
        raise ValueError(f"kind must be one of {MESH_KINDS}, got {kind!r}")
    h = np.pi / 2 * surface.radius / per_arc
    (u0, u1), (v0, v1) = surface.bounds
    style, element = kind.split()
    if style == "unstructured":
        uv, faces = _gmsh_rectangle(surface.bounds, h, element == "quad")
    else:
        nu, nv = (max(1, int(np.ceil((b - a) / h - 1e-9))) for a, b in surface.bounds)
        u, v = np.meshgrid(np.linspace(u0, u1, nu + 1), np.linspace(v0, v1, nv + 1),
                           indexing="ij")
        if style == "perturbed":
            rng = np.random.default_rng(seed + per_arc)
            du, dv = (u1 - u0) / nu, (v1 - v0) / nv
            shift = rng.uniform(-_PERTURBATION, _PERTURBATION, (2, nu - 1, nv - 1))
            u[1:-1, 1:-1] += shift[0] * du
            v[1:-1, 1:-1] += shift[1] * dv
        uv = np.column_stack([u.ravel(), v.ravel()])
        ids = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
        a, b = ids[:-1, :-1].ravel(), ids[1:, :-1].ravel()
        c, d = ids[1:, 1:].ravel(), ids[:-1, 1:].ravel()
        if element == "quad":
            faces = np.column_stack([a, b, c, d])
        else:
            tris = np.stack([np.column_stack([a, b, c]), np.column_stack([a, c, d])], axis=1)
            tris = tris.reshape(-1, 3)
            faces = np.column_stack([tris, np.full(len(tris), -1)])
    faces = np.asarray(faces, dtype=np.int64)
    return MeshSample(surface, kind, h, surface.point(uv), uv, faces, surface.normal(uv))


def _gmsh_rectangle(bounds: tuple[tuple[float, float], tuple[float, float]], h: float,
                    quad: bool) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """gmsh's Frontal-Delaunay mesh of a rectangle (recombined into quadrilaterals)."""
    import gmsh

    (u0, u1), (v0, v1) = bounds
    own = not gmsh.isInitialized()   # (ddpy.cad.gmsh_session is a layer apart)
    if own:
        gmsh.initialize(["", "-nopopup"], readConfigFiles=False, interruptible=False)
    terminal = gmsh.option.getNumber("General.Terminal")
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.add("rectangle")
        try:
            gmsh.model.occ.addRectangle(u0, v0, 0.0, u1 - u0, v1 - v0)
            gmsh.model.occ.synchronize()
            gmsh.option.setNumber("Mesh.Algorithm", 6)
            gmsh.option.setNumber("Mesh.MeshSizeMin", h)
            gmsh.option.setNumber("Mesh.MeshSizeMax", h)
            gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
            gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
            gmsh.option.setNumber("Mesh.RecombineAll", 1 if quad else 0)
            gmsh.option.setNumber("Mesh.RandomSeed", 1)
            gmsh.model.mesh.generate(2)
            tags, coord, _ = gmsh.model.mesh.getNodes()
            types, _, connectivity = gmsh.model.mesh.getElements(2)
        finally:
            gmsh.model.remove()
            gmsh.option.setNumber("Mesh.RecombineAll", 0)
    finally:
        gmsh.option.setNumber("General.Terminal", terminal)
        if own:
            gmsh.finalize()
    coord = np.asarray(coord).reshape(-1, 3)
    index = np.full(int(np.max(tags)) + 1, -1, dtype=np.int64)
    index[np.asarray(tags, dtype=np.int64)] = np.arange(len(tags))
    blocks = []
    for kind, conn in zip(types, connectivity, strict=True):
        conn = index[np.asarray(conn, dtype=np.int64)]
        if kind == 3:
            blocks.append(conn.reshape(-1, 4))
        elif kind == 2:
            tri = conn.reshape(-1, 3)
            blocks.append(np.column_stack([tri, np.full(len(tri), -1)]))
    faces = np.concatenate(blocks)
    used = np.unique(faces[faces >= 0])
    renumber = np.full(len(coord), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    faces = np.where(faces < 0, -1, renumber[np.maximum(faces, 0)])
    uv = coord[used, :2]
    # gmsh orients the rectangle's elements about +z: counter-clockwise in (u, v) already.
    return uv, faces


def normal_errors(mesh: MeshSample, estimator: str, crease_angle: float | None = None
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], int]:
    """Angles (degrees) between the estimated and the exact normal at every (vertex, sheet),
    the estimated corner normals (m, 4, 3) and the number of edges taken for creases."""
    kwargs = {} if crease_angle is None else {"crease_angle": crease_angle}
    result = estimate_normals(mesh.vertices, mesh.faces, estimator, **kwargs)
    valid = result.corner_sheet >= 0
    table = np.zeros((len(result.sheet_vertex), 3))
    table[result.corner_sheet[valid]] = result.corner_normals[valid]
    error = angle_between(table, mesh.normals[result.sheet_vertex])
    return error, result.corner_normals, int(result.crease.sum())


def shape_errors(mesh: MeshSample, corner_normals: NDArray[np.float64] | None,
                 smooth: bool = True, samples: int = 5) -> NDArray[np.float64]:
    """Distances (mm) from the patches to the exact surface at ``samples`` x ``samples``
    parameters per patch (triangles: half of them): Nagata patches with the given corner
    normals (exact ones if None) or, with ``smooth=False``, the flat facets."""
    normals = mesh.normals if corner_normals is None else corner_normals
    surface = NagataSurface(mesh.vertices, normals, mesh.faces, smooth=smooth)
    g = np.linspace(0.0, 1.0, samples)
    grid = np.column_stack([np.repeat(g, samples), np.tile(g, samples)])
    distances = []
    for triangle in (False, True):
        patches = np.flatnonzero(surface.is_triangle == triangle)
        if patches.size == 0:
            continue
        st = grid[grid[:, 1] <= grid[:, 0] + 1e-12] if triangle else grid
        ids = np.repeat(patches, len(st))
        params = np.tile(st, (len(patches), 1))
        points = surface.evaluate(ids, params)[0]
        corner_uv = mesh.uv[np.where(mesh.faces < 0, mesh.faces[:, :1], mesh.faces)][ids]
        s, t = params[:, :1], params[:, 1:]
        if triangle:   # vertices at (0, 0), (1, 0), (1, 1)
            guess = corner_uv[:, 0] + s * (corner_uv[:, 1] - corner_uv[:, 0]) \
                + t * (corner_uv[:, 2] - corner_uv[:, 1])
        else:
            guess = ((1 - s) * (1 - t) * corner_uv[:, 0] + s * (1 - t) * corner_uv[:, 1]
                     + s * t * corner_uv[:, 2] + (1 - s) * t * corner_uv[:, 3])
        distances.append(mesh.surface.project(points, guess)[0])
    return np.concatenate(distances)
