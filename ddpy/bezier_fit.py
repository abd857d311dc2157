"""Non-rational Bezier patches fitted to CAD faces (gmsh's OpenCASCADE, degree <= 6).

A face is mapped from the unit square (s, t): by its parameter rectangle when the face fills
it, or by a Coons patch of its four edges in the parameter plane when it is a trimmed 4-sided
face. On each region of the square, every degree pair (n, m) <= 6 is fitted by least squares
to exact CAD points on a 13 x 13 Chebyshev grid, and its error measured on a finer 31 x 31 grid
as the distance to the CAD point of the same parameters (a bound of the distance to the surface
that also keeps patch edges on the face edges). The cheapest pair within the tolerance wins;
when none is, the region is split in two across its worse direction. The accepted patches are
checked again with the true point-to-surface distance on a third grid.
"""

from __future__ import annotations

from collections.abc import Callable
from math import comb
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ddpy.surfaces import MAX_BEZIER_DEGREE

if TYPE_CHECKING:
    from ddpy.cad import ToolBuilder

__all__ = ["bernstein", "evaluate_net", "fit_face"]

_FIT = (1.0 - np.cos(np.pi * np.arange(13) / 12)) / 2.0   # Chebyshev-Lobatto points
_CHECK = np.linspace(0.0, 1.0, 31)
_VERIFY = (np.arange(40) + 0.5) / 40.0
#: Regions narrower than this fraction of the face are not split further.
MIN_REGION = 1.0 / 4096
DEGREES = range(1, MAX_BEZIER_DEGREE + 1)

Mapping = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.float64]]


def bernstein(n: int, t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Bernstein basis of degree n at t: (len(t), n + 1)."""
    t = np.asarray(t, dtype=np.float64)[:, None]
    i = np.arange(n + 1)
    return np.array([comb(n, k) for k in i]) * t**i * (1.0 - t) ** (n - i)


def evaluate_net(net: NDArray[np.float64], s: NDArray[np.float64],
                 t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points of a Bernstein net (n+1, m+1, 3) on the grid s x t: (len(s), len(t), 3)."""
    n, m = net.shape[0] - 1, net.shape[1] - 1
    return np.einsum("ai,ijk,bj->abk", bernstein(n, s), net, bernstein(m, t))


def _net_normal(net: NDArray[np.float64]) -> NDArray[np.float64]:
    """S_u x S_v of a net at (1/2, 1/2)."""
    n, m = net.shape[0] - 1, net.shape[1] - 1
    half = np.array([0.5])
    du = n * np.einsum("ai,ijk,bj->k", bernstein(n - 1, half), np.diff(net, axis=0),
                       bernstein(m, half))
    dv = m * np.einsum("ai,ijk,bj->k", bernstein(n, half), np.diff(net, axis=1),
                       bernstein(m - 1, half))
    return np.cross(du, dv)


_PINV = {n: np.linalg.pinv(bernstein(n, _FIT)) for n in DEGREES}
_CHECK_BASIS = {n: bernstein(n, _CHECK) for n in range(MAX_BEZIER_DEGREE + 1)}


def _face_mapping(builder: ToolBuilder, face: int) -> Mapping:
    """(s, t) in [0, 1]^2 -> (u, v) on the face: its parameter box or a Coons patch."""
    import gmsh

    lo, hi = (np.asarray(b, dtype=np.float64) for b in gmsh.model.getParametrizationBounds(2, face))
    k = 9
    g = (np.arange(k) + 0.5) / k
    grid = np.column_stack([np.repeat(lo[0] + g * (hi[0] - lo[0]), k),
                            np.tile(lo[1] + g * (hi[1] - lo[1]), k)])
    if gmsh.model.isInside(2, face, grid.ravel(), parametric=True) == k * k:
        def box(s: NDArray[np.float64], t: NDArray[np.float64]) -> NDArray[np.float64]:
            return np.column_stack([lo[0] + s * (hi[0] - lo[0]), lo[1] + t * (hi[1] - lo[1])])
        return box
    edges = gmsh.model.getBoundary([(2, face)], combined=False, oriented=True)
    if len(edges) != 4:
        raise builder.error(face, f"is trimmed and has {len(edges)} edges: Bezier patches need "
                            "a face that fills its parameter rectangle or a 4-sided face; split "
                            "the face in the CAD")

    def edge(i: int, f: NDArray[np.float64]) -> NDArray[np.float64]:
        """uv of edge i at fractions f along the face's loop direction."""
        tag = edges[i][1]
        a, b = (float(x[0]) for x in gmsh.model.getParametrizationBounds(1, abs(tag)))
        p = a + f * (b - a) if tag > 0 else b - f * (b - a)
        return np.asarray(gmsh.model.reparametrizeOnSurface(1, abs(tag), p, face)).reshape(-1, 2)

    ends = np.array([0.0, 1.0])
    corner_a, corner_b = edge(0, ends)
    corner_c, corner_d = edge(2, ends)   # edge 2 runs from C to D

    def coons(s: NDArray[np.float64], t: NDArray[np.float64]) -> NDArray[np.float64]:
        s_, t_ = s[:, None], t[:, None]
        bottom, right = edge(0, s), edge(1, t)
        top, left = edge(2, 1.0 - s), edge(3, 1.0 - t)
        return ((1 - t_) * bottom + t_ * top + (1 - s_) * left + s_ * right
                - (1 - s_) * (1 - t_) * corner_a - s_ * (1 - t_) * corner_b
                - s_ * t_ * corner_c - (1 - s_) * t_ * corner_d)
    return coons


def _points(face: int, mapping: Mapping, s: NDArray[np.float64],
            t: NDArray[np.float64]) -> NDArray[np.float64]:
    """Exact CAD points on the grid s x t: (len(s), len(t), 3)."""
    import gmsh

    ss, tt = np.repeat(s, len(t)), np.tile(t, len(s))
    uv = mapping(ss, tt)
    return np.asarray(gmsh.model.getValue(2, face, uv.ravel())).reshape(len(s), len(t), 3)


def _fit_region(face: int, mapping: Mapping, region: tuple[float, float, float, float],
                tol: float, angle_tol: float
                ) -> tuple[NDArray[np.float64] | None, dict[tuple[int, int], float]]:
    """Cheapest net within ``tol`` and ``angle_tol`` on the region (None if none) and the
    error of each degree pair, relative to the tolerances (<= 1 is good)."""
    import gmsh

    s0, s1, t0, t1 = region
    fit = _points(face, mapping, s0 + (s1 - s0) * _FIT, t0 + (t1 - t0) * _FIT)
    s, t = s0 + (s1 - s0) * _CHECK, t0 + (t1 - t0) * _CHECK
    check = _points(face, mapping, s, t)
    uv = mapping(np.repeat(s, len(t)), np.tile(t, len(s)))
    normal = np.asarray(gmsh.model.getNormal(face, uv.ravel())).reshape(len(s), len(t), 3)
    cos_tol = np.cos(np.radians(angle_tol))
    errors: dict[tuple[int, int], float] = {}
    nets: dict[tuple[int, int], NDArray[np.float64]] = {}
    for n in DEGREES:
        half = np.einsum("ia,abk->ibk", _PINV[n], fit)
        for m in DEGREES:
            net = np.einsum("ibk,jb->ijk", half, _PINV[m])
            approx = np.einsum("ai,ijk,bj->abk", _CHECK_BASIS[n], net, _CHECK_BASIS[m])
            distance = float(np.linalg.norm(approx - check, axis=2).max()) / tol
            du = n * np.einsum("ai,ijk,bj->abk", _CHECK_BASIS[n - 1], np.diff(net, axis=0),
                               _CHECK_BASIS[m])
            dv = m * np.einsum("ai,ijk,bj->abk", _CHECK_BASIS[n], np.diff(net, axis=1),
                               _CHECK_BASIS[m - 1])
            cross = np.cross(du, dv)
            length = np.maximum(np.linalg.norm(cross, axis=2), 1e-300)
            cosine = np.abs(np.einsum("abk,abk->ab", cross, normal)) / length
            # Angle error relative to its tolerance, through 1 - cos ~ angle^2 / 2.
            angle = float(np.sqrt(max(1.0 - cosine.min(), 0.0) / (1.0 - cos_tol)))
            errors[n, m] = max(distance, angle)
            nets[n, m] = net
    good = [p for p in errors if errors[p] <= 1.0]
    if not good:
        return None, errors
    best = min(good, key=lambda p: ((p[0] + 1) * (p[1] + 1), max(p), errors[p]))
    return nets[best], errors


def fit_face(builder: ToolBuilder, face: int, tol: float, angle_tol: float,
             flip: int) -> list[NDArray[np.float64]]:
    """Bezier nets (n+1, m+1, 3) covering one face within ``tol`` mm and ``angle_tol``
    degrees, their normals along ``flip`` times the CAD normal."""
    import gmsh

    mapping = _face_mapping(builder, face)
    nets: list[NDArray[np.float64]] = []
    regions = [(0.0, 1.0, 0.0, 1.0)]
    while regions:
        region = regions.pop(0)
        net, errors = _fit_region(face, mapping, region, tol, angle_tol)
        s0, s1, t0, t1 = region
        if net is None:
            split_s = errors[MAX_BEZIER_DEGREE - 1, MAX_BEZIER_DEGREE] >= errors[
                MAX_BEZIER_DEGREE, MAX_BEZIER_DEGREE - 1]
            width = s1 - s0 if split_s else t1 - t0
            if width <= MIN_REGION:
                best = errors[MAX_BEZIER_DEGREE, MAX_BEZIER_DEGREE]
                raise builder.error(face, f"cannot be fitted by Bezier patches of degree <= "
                                    f"{MAX_BEZIER_DEGREE} within {tol:g} mm and {angle_tol:g} "
                                    f"degrees: still {best:.3g} times the tolerance on a region "
                                    f"of {width:.2g} of the face (a singular point?); split the "
                                    "face or raise the tolerances")
            if split_s:
                mid = 0.5 * (s0 + s1)
                regions += [(s0, mid, t0, t1), (mid, s1, t0, t1)]
            else:
                mid = 0.5 * (t0 + t1)
                regions += [(s0, s1, t0, mid), (s0, s1, mid, t1)]
            continue
        centre = mapping(np.array([0.5 * (s0 + s1)]), np.array([0.5 * (t0 + t1)]))
        cad_normal = flip * np.asarray(gmsh.model.getNormal(face, centre.ravel()))
        if float(_net_normal(net) @ cad_normal) < 0.0:
            net = net[::-1].copy()
        nets.append(net)
    deviation = max(surface_distance(face, net) for net in nets)
    if deviation > tol:  # cannot happen: the fit error bounds the distance; kept as a guard
        raise builder.error(face, f"Bezier patches deviate {deviation:.3g} mm from the surface,"
                            f" more than bezier_tol = {tol:g} mm")
    builder.bezier_deviation[face] = deviation
    return nets


def surface_distance(face: int, net: NDArray[np.float64]) -> float:
    """Largest distance from a 40 x 40 grid of the patch to the CAD face's surface."""
    import gmsh

    points = evaluate_net(net, _VERIFY, _VERIFY).reshape(-1, 3)
    closest = np.asarray(gmsh.model.getClosestPoint(2, face, points.ravel())[0]).reshape(-1, 3)
    return float(np.linalg.norm(points - closest, axis=1).max())
