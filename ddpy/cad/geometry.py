"""Closest points on a CAD face (gmsh's OpenCASCADE), robust where gmsh's own answer is not:
the Bezier fit (:mod:`ddpy.cad.bezier_fit`) and the shape error of tool models
(:mod:`ddpy.cad.shape_error`) measure against them. Call inside :func:`ddpy.cad.gmsh_session`
with the model loaded."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["closest_points"]


def closest_points(face: int, points: ArrayLike) -> tuple[NDArray[np.float64],
                                                          NDArray[np.float64]]:
    """Closest points (k, 3) on a face's surface and their parameters (k, 2).

    ``gmsh.model.getClosestPoint`` keeps to the face's parameter range and, for a point whose
    foot lies just beyond it, may answer a far stationary point (the antipode on a sphere).
    Where its answer is farther than 1e-4 of the face's size and than the nearest node of a
    33 x 33 grid of the face, the point is projected again from that node by Gauss-Newton
    with backtracking, wrapped around a seam and kept within the parameter range otherwise
    (beyond a pole the extended surface turns its normal over).
    """
    import gmsh

    x = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(x) == 0:
        return np.zeros((0, 3)), np.zeros((0, 2))
    closest, uv = gmsh.model.getClosestPoint(2, face, x.ravel())
    closest, uv = np.asarray(closest).reshape(-1, 3), np.asarray(uv).reshape(-1, 2)
    distance = np.linalg.norm(x - closest, axis=1)
    lo, hi = (np.asarray(b, dtype=np.float64) for b in gmsh.model.getParametrizationBounds(2, face))
    g = np.linspace(0.0, 1.0, 33)
    grid_uv = np.column_stack([np.repeat(lo[0] + g * (hi[0] - lo[0]), len(g)),
                               np.tile(lo[1] + g * (hi[1] - lo[1]), len(g))])
    grid_x = np.asarray(gmsh.model.getValue(2, face, grid_uv.ravel())).reshape(-1, 3)
    # An answer within 1e-4 of the face's size cannot be a far stationary point: only the
    # others are checked against the grid.
    size = float(np.linalg.norm(np.ptp(grid_x, axis=0)))
    check = np.flatnonzero(distance > 1e-4 * size)
    centre = grid_x.mean(axis=0)
    gx, xx = grid_x - centre, x[check] - centre
    nearest = np.empty(len(check), dtype=np.int64)
    for start in range(0, len(check), 4096):   # |x - g|^2 = |x|^2 - 2 x.g + |g|^2
        d2 = (gx**2).sum(axis=1)[None, :] - 2.0 * xx[start:start + 4096] @ gx.T
        nearest[start:start + 4096] = d2.argmin(axis=1)
    grid_d2 = ((x[check] - grid_x[nearest]) ** 2).sum(axis=1)
    worse = distance[check] ** 2 > grid_d2 * (1.0 + 1e-9) + 1e-24
    bad, nearest = check[worse], nearest[worse]
    if bad.size:
        uv_bad, x_bad = _gauss_newton(face, x[bad], grid_uv[nearest], lo, hi)
        closest[bad], uv[bad] = x_bad, uv_bad
    return closest, uv


def _periods(face: int, lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Whether the face closes on itself along u and along v (a seam)."""
    import gmsh

    f = np.linspace(0.0, 1.0, 5)
    closed = []
    for k in range(2):
        a, b = np.empty((5, 2)), np.empty((5, 2))
        a[:, k], b[:, k] = lo[k], hi[k]
        a[:, 1 - k] = b[:, 1 - k] = lo[1 - k] + f * (hi[1 - k] - lo[1 - k])
        xa = np.asarray(gmsh.model.getValue(2, face, a.ravel())).reshape(-1, 3)
        xb = np.asarray(gmsh.model.getValue(2, face, b.ravel())).reshape(-1, 3)
        size = np.ptp(np.vstack([xa, xb]), axis=0).max()
        closed.append(bool(np.linalg.norm(xa - xb, axis=1).max() <= 1e-9 * max(size, 1e-12)))
    return np.array(closed)


def _gauss_newton(face: int, x: NDArray[np.float64], uv: NDArray[np.float64],
                  lo: NDArray[np.float64], hi: NDArray[np.float64]
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Minimize |S(uv) - x| from ``uv`` within [lo, hi]: (uv, S(uv))."""
    import gmsh

    def value(uv: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(gmsh.model.getValue(2, face, uv.ravel())).reshape(-1, 3)

    periodic = _periods(face, lo, hi)
    period = hi - lo

    def keep(uv: NDArray[np.float64]) -> NDArray[np.float64]:
        """Wrapped along a closed direction, clipped along an open one."""
        return np.where(periodic, lo + np.mod(uv - lo, period), np.clip(uv, lo, hi))

    uv = uv.copy()
    s = value(uv)
    d2 = ((x - s) ** 2).sum(axis=1)
    tol = 1e-13 * np.maximum(hi - lo, 1e-12)
    for _ in range(30):
        d = np.asarray(gmsh.model.getDerivative(2, face, uv.ravel())).reshape(-1, 2, 3)
        jtj = np.einsum("kai,kbi->kab", d, d)
        jtj += (1e-12 * np.trace(jtj, axis1=1, axis2=2) + 1e-300)[:, None, None] * np.eye(2)
        step = np.linalg.solve(jtj, np.einsum("kai,ki->ka", d, x - s)[..., None])[..., 0]
        step = np.where(periodic, step, np.clip(uv + step, lo, hi) - uv)
        active = np.any(np.abs(step) > tol, axis=1)
        if not active.any():
            break
        for _ in range(20):   # halve the step where it does not bring the point closer
            rows = np.flatnonzero(active)
            trial = keep(uv[rows] + step[rows])
            s_trial = value(trial)
            d2_trial = ((x[rows] - s_trial) ** 2).sum(axis=1)
            better = d2_trial <= d2[rows]
            ok = rows[better]
            uv[ok], s[ok], d2[ok] = trial[better], s_trial[better], d2_trial[better]
            active[ok] = False
            if not active.any():
                break
            step[active] *= 0.5
    return uv, s
