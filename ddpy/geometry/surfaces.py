"""Tool surfaces: Bezier patches (power basis), Nagata patches and bilinear/flat facets.

Every description answers the same questions for a batch of (patch, parameters) pairs:
the point S, the first derivatives S_,a, the unit normal n = unit(S_,1 x S_,2) and the
second derivatives S_,ab. Parameters follow the paper: a Bezier or quadrilateral patch
lives on [0, 1]^2, a triangle on 0 <= zeta <= eta <= 1 (vertices at (0,0), (1,0), (1,1)).
The polynomials are defined beyond the domain too: parameters up to DOMAIN_MARGIN (one domain
width) outside it are evaluated (an extrapolation, a finite difference at an edge), and
farther ones refused, as are patches of zero area (nets or faces collapsed to a point or a
line).

>>> import numpy as np
>>> from ddpy.geometry.surfaces import NagataSurface
>>> square = NagataSurface([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],
...                        [[0, 0, 1]] * 4, [[0, 1, 2, 3]])
>>> points, derivatives, normals = square.evaluate([0], [[0.5, 0.5]])
>>> points.round(3).tolist(), normals.tolist()
([[0.5, 0.5, 0.0]], [[0.0, 0.0, 1.0]])
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array, int_array

__all__ = ["BezierSurface", "NagataSurface", "DEGENERATE_AREA", "DOMAIN_MARGIN",
           "MAX_BEZIER_DEGREE", "NAGATA_DEGENERATE_RATIO", "nagata_edge_coefficient"]

#: Highest Bezier degree in each direction (the paper's cap for a stable power basis).
MAX_BEZIER_DEGREE = 6
#: An edge is straight when its Nagata coefficient exceeds this many times that of a circular
#: arc with the same angle between its end normals (the formula's blow-up near parallel
#: normals); smooth edges stay below 1 to about 5 (docs/theory/surfaces.md).
NAGATA_DEGENERATE_RATIO = 8.0
#: Allowed deviation of a given normal from unit length.
UNIT_TOL = 1.0e-6
#: Parameters are accepted up to this far outside a patch's domain ([0, 1] in each, the
#: triangle 0 <= zeta <= eta <= 1 within the same square): beyond it a polynomial's value says
#: nothing of the tool, and far beyond it overflows.
DOMAIN_MARGIN = 1.0
#: |S_,1 x S_,2| at or below this times the patch's size squared is zero: a patch collapsed to
#: a point or a line there (rounding leaves about 1e-16).
DEGENERATE_AREA = 1.0e-10
#: Where a Bezier patch's tangents are checked: a 3 x 3 grid inside it (a patch may have a
#: singular edge, the pole of a disc-shaped face, never a singular inside).
_INSIDE = np.linspace(0.25, 0.75, 3)

_NB = MAX_BEZIER_DEGREE + 1

Evaluation = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]


class _Surface:
    """What every tool description shares: argument checks and the batch call."""

    n_patches: int

    def _check_queries(
        self, patch_ids: ArrayLike, params: ArrayLike
    ) -> tuple[NDArray[np.int32], NDArray[np.float64]]:
        ids = int_array(np.atleast_1d(patch_ids), "patch_ids", (None,))
        uv = float_array(np.reshape(params, (-1, 2)) if np.size(params) == 0 else params,
                         "params", (ids.shape[0], 2))
        if ids.size and (ids.min() < 0 or ids.max() >= self.n_patches):
            bad = int(np.flatnonzero((ids < 0) | (ids >= self.n_patches))[0])
            raise IndexError(
                f"patch_ids[{bad}] = {ids[bad]} is not a patch: expected 0 <= id < "
                f"{self.n_patches}"
            )
        outside = (np.abs(uv - 0.5) > 0.5 + DOMAIN_MARGIN).any(axis=1)
        if outside.any():
            bad = int(np.flatnonzero(outside)[0])
            raise ValueError(
                f"params[{bad}] = {uv[bad].tolist()} is outside patch {ids[bad]}: expected "
                f"parameters in [0, 1] (up to {DOMAIN_MARGIN:g} beyond: "
                f"{-DOMAIN_MARGIN:g} to {1 + DOMAIN_MARGIN:g})"
            )
        return ids, uv

    def _evaluate_all(
        self, ids: NDArray[np.int32], uv: NDArray[np.float64]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]:
        raise NotImplementedError

    def _run(self, patch_ids: ArrayLike, params: ArrayLike) -> tuple[np.ndarray, ...]:
        ids, uv = self._check_queries(patch_ids, params)
        k = ids.shape[0]
        if k == 0:
            return np.zeros((0, 3)), np.zeros((0, 2, 3)), np.zeros((0, 3)), np.zeros((0, 3, 3))
        points, derivs, normals, second, info = self._evaluate_all(ids, uv.ravel())
        if info != 0:  # unreachable after the checks above; kept so the core never fails silently
            raise RuntimeError(f"core refused patch id at query {info - 1}")
        return (points.reshape(k, 3), derivs.reshape(k, 2, 3), normals.reshape(k, 3),
                second.reshape(k, 3, 3))

    def evaluate(self, patch_ids: ArrayLike, params: ArrayLike) -> Evaluation:
        """Points (k, 3), first derivatives (k, 2, 3) and unit normals (k, 3).

        ``derivatives[:, 0]`` is dS/du, ``derivatives[:, 1]`` is dS/dv. A normal is zero
        where the two tangents are parallel (a singular point of the patch).
        """
        points, derivs, normals, _ = self._run(patch_ids, params)
        return points, derivs, normals

    def second_derivatives(self, patch_ids: ArrayLike, params: ArrayLike) -> NDArray[np.float64]:
        """Second derivatives (k, 3, 3): [:, 0] d2S/du2, [:, 1] d2S/dudv, [:, 2] d2S/dv2."""
        return self._run(patch_ids, params)[3]


class BezierSurface(_Surface):
    """Tensor-product Bezier patches of degree 1..6 in each direction.

    ``control_nets`` is a sequence of Bernstein control nets, each of shape
    (n + 1, m + 1, 3) with ``net[i, j]`` the control point P_ij (i along u, j along v),
    or one array of shape (patches, n + 1, m + 1, 3). The nets are converted once to the
    power basis, in which every evaluation is done.
    """

    def __init__(self, control_nets: Sequence[ArrayLike] | ArrayLike) -> None:
        if control_nets is None or isinstance(control_nets, (str, bytes)):
            raise TypeError("control_nets must be a sequence of (n+1, m+1, 3) arrays")
        nets = list(control_nets)
        if not nets:
            raise ValueError("control_nets is empty: a Bezier surface needs at least one patch")
        self.n_patches = len(nets)
        self.degrees = np.zeros((self.n_patches, 2), dtype=np.int32)
        self.control = np.zeros((self.n_patches, _NB, _NB, 3))
        for p, net in enumerate(nets):
            array = np.asarray(net)
            if array.ndim != 3 or array.shape[2] != 3:
                raise ValueError(
                    f"control net of patch {p} must have shape (n+1, m+1, 3), got {array.shape}"
                )
            array = float_array(array, f"control net of patch {p}", (None, None, 3))
            n, m = array.shape[0] - 1, array.shape[1] - 1
            if not (1 <= n <= MAX_BEZIER_DEGREE and 1 <= m <= MAX_BEZIER_DEGREE):
                raise ValueError(
                    f"patch {p} has degree ({n}, {m}): each degree must be between 1 and "
                    f"{MAX_BEZIER_DEGREE}; split the patch"
                )
            self.degrees[p] = (n, m)
            # Fortran (3, 0:6, 0:6, p) is NumPy (p, 0:6, 0:6, 3) transposed in its middle axes.
            self.control[p, : m + 1, : n + 1] = array.transpose(1, 0, 2)
        coef, info = _core.bezier_power_coefficients(self.degrees.ravel(), self.control.ravel())
        if info != 0:
            raise RuntimeError(f"core refused the degree of patch {info - 1}")
        self.coefficients = coef
        self._check_tangents()

    def _check_tangents(self) -> None:
        """Refuse a patch whose tangents are zero or parallel inside it (no area there)."""
        params = np.column_stack([np.repeat(_INSIDE, _INSIDE.size),
                                  np.tile(_INSIDE, _INSIDE.size)])
        count = self.n_patches
        ids = np.repeat(np.arange(count, dtype=np.int32), len(params))
        overflow = ~np.isfinite(self.coefficients.reshape(count, -1)).all(axis=1)
        if overflow.any():
            p = int(np.flatnonzero(overflow)[0])
            raise ValueError(f"patch {p}'s control points are too large to evaluate: its "
                             "power-basis coefficients overflow")
        derivs = self._run(ids, np.tile(params, (count, 1)))[1].reshape(count, -1, 2, 3)
        with np.errstate(over="ignore", invalid="ignore"):
            cross = np.linalg.norm(np.cross(derivs[..., 0, :], derivs[..., 1, :]), axis=2)
        # The size of each net over its own points (the padded rows and columns are zero).
        k = np.arange(_NB)
        used = ((k[None, :, None] <= self.degrees[:, 1, None, None])
                & (k[None, None, :] <= self.degrees[:, 0, None, None]))[..., None]
        with np.errstate(over="ignore"):
            size = (np.where(used, self.control, -np.inf).max(axis=(1, 2))
                    - np.where(used, self.control, np.inf).min(axis=(1, 2))).max(axis=1)
        size = np.maximum(size, np.finfo(float).tiny)
        degenerate = ~(cross.min(axis=1) / size / size > DEGENERATE_AREA)
        if degenerate.any():
            p = int(np.flatnonzero(degenerate)[0])
            raise ValueError(f"patch {p} is degenerate: its tangents are zero or parallel "
                             "inside it (control points collapsed to a point or a line)")

    def _evaluate_all(self, ids, uv):
        return _core.bezier_evaluate(self.degrees.ravel(), self.coefficients, ids, uv)

    def power_coefficients(self, patch: int) -> NDArray[np.float64]:
        """Power-basis coefficients A[k, l] (vectors) of one patch: S = sum A_kl u^k v^l.

        (The core evaluates about the patch centre, in (u - 1/2)^k (v - 1/2)^l, where the
        coefficients stay small and so does the rounding; these are the plain ones.)"""
        if not 0 <= patch < self.n_patches:
            raise IndexError(f"patch {patch} is not a patch: expected 0 <= id < {self.n_patches}")
        n, m = self.degrees[patch]
        net = self.control[patch, : m + 1, : n + 1].transpose(1, 0, 2)
        return np.einsum("ki,ijx,lj->klx", _power_matrix(int(n)), net, _power_matrix(int(m)))

    def evaluate_de_casteljau(self, patch_ids: ArrayLike, params: ArrayLike) -> NDArray[np.float64]:
        """Points (k, 3) by de Casteljau on the control nets: an independent cross-check."""
        ids, uv = self._check_queries(patch_ids, params)
        if ids.size == 0:
            return np.zeros((0, 3))
        points, info = _core.bezier_de_casteljau(self.degrees.ravel(), self.control.ravel(),
                                                 ids, uv.ravel())
        if info != 0:
            raise RuntimeError(f"core refused patch id at query {info - 1}")
        return points.reshape(-1, 3)


class NagataSurface(_Surface):
    """Nagata patches on a mesh of triangles and quadrilaterals; facets with ``smooth=False``.

    ``vertices`` (n, 3); ``faces`` (m, 4) vertex indices with -1 in the last column for a
    triangle, ordered counter-clockwise seen from the side the normals point to;
    ``normals`` the unit normals, either one per vertex (n, 3) or one per face corner
    (m, 4, 3) so that vertices on a crease carry the normal of each face (the fourth row
    of a triangle is ignored). An edge stays straight when its end normals are parallel, or
    when its Nagata coefficient would exceed ``degenerate_ratio`` times that of a circular
    arc with the same angle between the normals (nearly parallel normals on an edge that is
    not perpendicular to them, where the formula blows up).
    """

    def __init__(
        self,
        vertices: ArrayLike,
        normals: ArrayLike,
        faces: ArrayLike,
        smooth: bool = True,
        degenerate_ratio: float = NAGATA_DEGENERATE_RATIO,
    ) -> None:
        self.vertices = float_array(vertices, "vertices", (None, 3))
        self.faces = int_array(faces, "faces", (None, 4))
        self.smooth = bool(smooth)
        self.degenerate_ratio = _check_ratio(degenerate_ratio)
        n_vertices, n_faces = len(self.vertices), len(self.faces)
        if n_faces == 0:
            raise ValueError("faces is empty: a Nagata surface needs at least one face")
        self.n_patches = n_faces
        self.is_triangle = self.faces[:, 3] == -1
        self._check_faces(n_vertices)
        self.corner_normals = self._corner_normals(normals, n_vertices)
        self._check_orientation()
        coef, info = _core.nagata_coefficients(
            self.vertices.ravel(), self.faces.ravel(), self.corner_normals.ravel(),
            int(self.smooth), self.degenerate_ratio,
        )
        if info != 0:
            raise RuntimeError(f"core refused face {info - 1}")
        self.coefficients = coef

    def _check_faces(self, n_vertices: int) -> None:
        faces, tri = self.faces, self.is_triangle
        # Triangles repeat their first vertex in the fourth slot, so one array serves both.
        used = np.where(tri[:, None], faces[:, [0, 1, 2, 0]], faces)
        bad = np.flatnonzero(((used < 0) | (used >= n_vertices)).any(axis=1))
        if bad.size:
            f = int(bad[0])
            raise ValueError(
                f"face {f} = {faces[f].tolist()}: vertex indices must lie in 0..{n_vertices - 1}"
                " (use -1 only in the last column, for a triangle)"
            )
        quad_repeats = (np.diff(np.sort(faces, axis=1), axis=1) == 0).any(axis=1)
        a, b, c = faces[:, 0], faces[:, 1], faces[:, 2]
        tri_repeats = (a == b) | (b == c) | (a == c)
        repeated = np.where(tri, tri_repeats, quad_repeats)
        if repeated.any():
            f = int(np.flatnonzero(repeated)[0])
            raise ValueError(f"face {f} = {faces[f].tolist()} is degenerate: a vertex repeats")
        # A corner whose two edges are parallel makes a degenerate face.
        x = self.vertices[used]
        nxt = np.where(tri[:, None, None], x[:, [1, 2, 0, 1]], np.roll(x, -1, axis=1))
        prev = np.where(tri[:, None, None], x[:, [2, 0, 1, 2]], np.roll(x, 1, axis=1))
        corner = np.cross(nxt - x, prev - x)
        scale = np.maximum(np.linalg.norm(nxt - x, axis=2), np.linalg.norm(prev - x, axis=2))
        degenerate = (np.linalg.norm(corner, axis=2) <= 1.0e-10 * scale**2).any(axis=1)
        if degenerate.any():
            f = int(np.flatnonzero(degenerate)[0])
            raise ValueError(
                f"face {f} = {faces[f].tolist()} is degenerate: two of its edges are parallel"
            )
        corner[tri, 3] = 0.0
        self._face_normal = corner.sum(axis=1)
        # Four times a quadrilateral's vector area: zero for one whose edges cross (a bow-tie)
        # although no two of its edges are parallel.
        area = np.linalg.norm(self._face_normal, axis=1)
        flat = ~(area > DEGENERATE_AREA * scale.max(axis=1) ** 2)
        if flat.any():
            f = int(np.flatnonzero(flat)[0])
            raise ValueError(
                f"face {f} = {faces[f].tolist()} is degenerate: its area is zero (its edges "
                "cross)"
            )
        self._face_normal /= area[:, None]

    def _corner_normals(self, normals: ArrayLike, n_vertices: int) -> NDArray[np.float64]:
        array = np.asarray(normals)
        n_faces = len(self.faces)
        if array.ndim == 2:
            vertex_normals = float_array(array, "normals", (n_vertices, 3))
            _check_unit(vertex_normals, "normals", "vertex")
            corner = vertex_normals[np.where(self.faces < 0, self.faces[:, :1], self.faces)]
        elif array.ndim == 3:
            corner = float_array(array, "normals", (n_faces, 4, 3)).copy()
            corner[self.is_triangle, 3] = corner[self.is_triangle, 0]
            _check_unit(corner.reshape(-1, 3), "normals", "face corner", per=4)
        else:
            raise ValueError(
                f"normals must have shape ({n_vertices}, 3) (one per vertex) or "
                f"({n_faces}, 4, 3) (one per face corner), got {array.shape}"
            )
        return np.ascontiguousarray(corner)

    def _check_orientation(self) -> None:
        dots = np.einsum("fcx,fx->fc", self.corner_normals, self._face_normal)
        wrong = (dots <= 0.0) & ~(self.is_triangle[:, None] & (np.arange(4) == 3))
        if wrong.any():
            f, c = (int(i) for i in np.argwhere(wrong)[0])
            raise ValueError(
                f"face {f} = {self.faces[f].tolist()}: its vertex order gives a normal opposite "
                f"to the given normal at corner {c}; order the face counter-clockwise seen from "
                "the side the normals point to, or flip the normals"
            )

    def _evaluate_all(self, ids, uv):
        return _core.nagata_evaluate(self.coefficients, ids, uv)

    def patch_coefficients(self, patch: int) -> NDArray[np.float64]:
        """The 8 coefficient vectors (8, 3) c00, c10, c01, c11, c20, c02, c21, c12 of a patch."""
        return self.coefficients.reshape(self.n_patches, 8, 3)[patch].copy()


def nagata_edge_coefficient(
    x0: ArrayLike, x1: ArrayLike, n0: ArrayLike, n1: ArrayLike,
    degenerate_ratio: float = NAGATA_DEGENERATE_RATIO,
) -> NDArray[np.float64]:
    """Quadratic coefficient c of the Nagata curve C(s) = x0 + (x1 - x0 - c) s + c s^2.

    Arguments are (3,) vectors or (m, 3) batches; normals must be unit vectors.
    """
    arrays = [np.atleast_2d(np.asarray(a, dtype=float)) for a in (x0, x1, n0, n1)]
    m = arrays[0].shape[0]
    names = ("x0", "x1", "n0", "n1")
    arrays = [float_array(a, name, (m, 3)) for a, name in zip(arrays, names, strict=True)]
    for a, name in zip(arrays[2:], names[2:], strict=True):
        _check_unit(a, name, "edge end")
    ratio = _check_ratio(degenerate_ratio)
    if m == 0:
        return np.zeros((0, 3))
    c = _core.nagata_edge_coefficient(*(a.ravel() for a in arrays), ratio)
    return c.reshape(m, 3) if np.ndim(x0) == 2 else c.reshape(3)


def _power_matrix(n: int) -> NDArray[np.float64]:
    """M[k, i] = (-1)^(k-i) C(n, k) C(k, i): B_i^n(u) = sum_k M[k, i] u^k."""
    from math import comb

    return np.array([[(-1) ** (k - i) * comb(n, k) * comb(k, i) if k >= i else 0
                      for i in range(n + 1)] for k in range(n + 1)], dtype=float)


def _check_ratio(ratio: float) -> float:
    value = float(ratio)
    if not 1.0 <= value < np.inf:
        raise ValueError(f"degenerate_ratio must be a finite number >= 1, got {ratio}")
    return value


def _check_unit(normals: NDArray[np.float64], name: str, what: str, per: int = 0) -> None:
    length = np.linalg.norm(normals, axis=-1)
    bad = np.flatnonzero(np.abs(length - 1.0) > UNIT_TOL)
    if bad.size:
        i = int(bad[0])
        where = f"face {i // per}, corner {i % per}" if per else f"{what} {i}"
        kind = "zero" if length[i] == 0.0 else f"of length {length[i]:.6g}"
        raise ValueError(
            f"{name}: the normal of {where} is {kind}; normals must be unit vectors"
            " (normalize them first)"
        )

