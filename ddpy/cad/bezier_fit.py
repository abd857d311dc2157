"""Non-rational Bezier patches fitted to CAD faces (gmsh's OpenCASCADE, degree <= 6).

A face is mapped from the unit square (s, t): by its parameter rectangle when the face fills
it, by a Coons patch of its four edges in the parameter plane when it is a trimmed 4-sided
face, or by an O-grid of five Coons patches (a square in the middle, four around it) when it is
bounded by one closed edge, like the flat bottom of a cylindrical punch. On each region of the
square, every degree pair (n, m) <= 6 is fitted by least squares
to exact CAD points on a 13 x 13 Chebyshev grid, and its error measured on a finer 31 x 31 grid
as the distance to the CAD point of the same parameters (a bound of the distance to the surface
that also keeps patch edges on the face edges). The cheapest pair within the tolerance wins;
when none is, the region is split in two across its worse direction. The accepted patches are
checked again with the true point-to-surface distance on a third grid
(:func:`ddpy.cad.geometry.closest_points`).
"""

from __future__ import annotations

from collections.abc import Callable
from math import comb
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from ddpy.cad.geometry import closest_points
from ddpy.geometry.surfaces import MAX_BEZIER_DEGREE


class FaceSource(Protocol):
    """What the fit needs of :class:`ddpy.cad.ToolBuilder`: its errors naming the file and
    the face, and where it records each face's deviation."""

    bezier_deviation: dict[int, float]

    def error(self, face: int | None, message: str) -> Exception: ...

__all__ = ["bernstein", "evaluate_net", "fit_face"]

_FIT = (1.0 - np.cos(np.pi * np.arange(13) / 12)) / 2.0   # Chebyshev-Lobatto points
_CHECK = np.linspace(0.0, 1.0, 31)
_VERIFY = (np.arange(40) + 0.5) / 40.0
#: Regions narrower than this fraction of the face are not split further.
MIN_REGION = 1.0 / 4096
#: Most Bezier patches one face may take: a tolerance no patch can meet would otherwise halve
#: regions towards MIN_REGION in both directions, millions of them (--bezier-tol 1e-15).
MAX_PATCHES_PER_FACE = 1024
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


Curve = Callable[[NDArray[np.float64]], NDArray[np.float64]]


def _coons(bottom: Curve, right: Curve, top: Curve, left: Curve) -> Mapping:
    """Coons patch of four curves of the parameter plane: bottom and top run with s (left to
    right), left and right with t (bottom to top)."""
    ends = np.array([0.0, 1.0])
    a, b = bottom(ends)
    d, c = top(ends)

    def mapping(s: NDArray[np.float64], t: NDArray[np.float64]) -> NDArray[np.float64]:
        s_, t_ = s[:, None], t[:, None]
        return ((1 - t_) * bottom(s) + t_ * top(s) + (1 - s_) * left(t) + s_ * right(t)
                - (1 - s_) * (1 - t_) * a - s_ * (1 - t_) * b - s_ * t_ * c - (1 - s_) * t_ * d)
    return mapping


def _segment(p: NDArray[np.float64], q: NDArray[np.float64]) -> Curve:
    return lambda f: p + np.asarray(f)[:, None] * (q - p)


def _face_mappings(builder: FaceSource, face: int) -> list[Mapping]:
    """Maps (s, t) in [0, 1]^2 -> (u, v) covering the face: its parameter box; a Coons patch of
    its edges if it is a trimmed 4-sided face; an O-grid of five Coons patches if it is
    bounded by one closed edge (a disc)."""
    import gmsh

    lo, hi = (np.asarray(b, dtype=np.float64) for b in gmsh.model.getParametrizationBounds(2, face))
    k = 9
    g = (np.arange(k) + 0.5) / k
    grid = np.column_stack([np.repeat(lo[0] + g * (hi[0] - lo[0]), k),
                            np.tile(lo[1] + g * (hi[1] - lo[1]), k)])
    if gmsh.model.isInside(2, face, grid.ravel(), parametric=True) == k * k:
        def box(s: NDArray[np.float64], t: NDArray[np.float64]) -> NDArray[np.float64]:
            return np.column_stack([lo[0] + s * (hi[0] - lo[0]), lo[1] + t * (hi[1] - lo[1])])
        return [box]
    edges = gmsh.model.getBoundary([(2, face)], combined=False, oriented=True)

    def edge(i: int, offset: float = 0.0, length: float = 1.0) -> Curve:
        """uv of edge i at fractions offset + length f along the face's loop direction."""
        tag = edges[i][1]
        a, b = (float(x[0]) for x in gmsh.model.getParametrizationBounds(1, abs(tag)))

        def curve(f: NDArray[np.float64]) -> NDArray[np.float64]:
            f = offset + length * np.asarray(f, dtype=np.float64)
            p = a + f * (b - a) if tag > 0 else b - f * (b - a)
            uv = gmsh.model.reparametrizeOnSurface(1, abs(tag), p, face)
            return np.asarray(uv).reshape(-1, 2)
        return curve

    def reverse(curve: Curve) -> Curve:
        return lambda f: curve(1.0 - np.asarray(f))

    if len(edges) == 4:
        mappings = [_coons(edge(0), edge(1), reverse(edge(2)), reverse(edge(3)))]
    elif len(edges) == 1:
        loop = edge(0)
        centre = loop(np.linspace(0.0, 1.0, 64, endpoint=False)).mean(axis=0)
        rim = loop(np.arange(5) / 4.0)
        inner = centre + 0.5 * (rim - centre)
        mappings = [_coons(_segment(inner[0], inner[1]), _segment(inner[1], inner[2]),
                           _segment(inner[3], inner[2]), _segment(inner[0], inner[3]))]
        for q in range(4):
            mappings.append(_coons(_segment(inner[q], inner[q + 1]),
                                   _segment(inner[q + 1], rim[q + 1]),
                                   edge(0, q / 4.0, 0.25), _segment(inner[q], rim[q])))
    else:
        raise builder.error(face, f"is trimmed and has {len(edges)} edges: Bezier patches need "
                            "a face that fills its parameter rectangle, a 4-sided face or a "
                            "face bounded by one closed edge; split the face in the CAD")
    for mapping in mappings:
        uv = mapping(np.repeat(g, k), np.tile(g, k))
        if gmsh.model.isInside(2, face, uv.ravel(), parametric=True) != k * k:
            raise builder.error(face, "is trimmed and its edges do not map it onto a square "
                                "(a concave or folded outline): split the face in the CAD")
    return mappings


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
    halves = {n: np.einsum("ia,abk->ibk", _PINV[n], fit) for n in DEGREES}

    def fitted(n: int, m: int) -> tuple[NDArray[np.float64], float]:
        net = np.einsum("ibk,jb->ijk", halves[n], _PINV[m])
        approx = np.einsum("ai,ijk,bj->abk", _CHECK_BASIS[n], net, _CHECK_BASIS[m])
        distance = float(np.linalg.norm(approx - check, axis=2).max()) / tol
        du = n * np.einsum("ai,ijk,bj->abk", _CHECK_BASIS[n - 1], np.diff(net, axis=0),
                           _CHECK_BASIS[m])
        dv = m * np.einsum("ai,ijk,bj->abk", _CHECK_BASIS[n], np.diff(net, axis=1),
                           _CHECK_BASIS[m - 1])
        cross = np.cross(du, dv)
        length = np.linalg.norm(cross, axis=2)
        tangent = np.maximum(np.linalg.norm(du, axis=2), np.linalg.norm(dv, axis=2))
        defined = length > 1e-6 * tangent**2   # not at a point collapsed to a pole
        cosine = np.einsum("abk,abk->ab", cross, normal)[defined] / length[defined]
        cosine = cosine * (1.0 if cosine.sum() >= 0.0 else -1.0)
        # Angle error relative to its tolerance, through 1 - cos ~ angle^2 / 2.
        angle = float(np.sqrt(max(1.0 - cosine.min(), 0.0) / (1.0 - cos_tol)))
        return net, max(distance, angle)

    # Cheapest first (fewest control points, then lowest top degree); stop at the first group
    # with a pair within the tolerances.
    groups: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for n in DEGREES:
        for m in DEGREES:
            groups.setdefault(((n + 1) * (m + 1), max(n, m)), []).append((n, m))
    for key in sorted(groups):
        nets = {}
        for pair in groups[key]:
            nets[pair], errors[pair] = fitted(*pair)
        good = [p for p in groups[key] if errors[p] <= 1.0]
        if good:
            return nets[min(good, key=errors.__getitem__)], errors
    return None, errors


def fit_face(builder: FaceSource, face: int, tol: float, angle_tol: float,
             flip: int) -> list[NDArray[np.float64]]:
    """Bezier nets (n+1, m+1, 3) covering one face within ``tol`` mm and ``angle_tol``
    degrees, their normals along ``flip`` times the CAD normal."""
    import gmsh

    nets: list[NDArray[np.float64]] = []
    regions = [(mapping, (0.0, 1.0, 0.0, 1.0)) for mapping in _face_mappings(builder, face)]
    while regions:
        mapping, region = regions.pop(0)
        net, errors = _fit_region(face, mapping, region, tol, angle_tol)
        s0, s1, t0, t1 = region
        if net is None and len(nets) + len(regions) + 2 > MAX_PATCHES_PER_FACE:
            raise builder.error(face, f"needs more than {MAX_PATCHES_PER_FACE} Bezier patches "
                                f"of degree <= {MAX_BEZIER_DEGREE} within {tol:g} mm and "
                                f"{angle_tol:g} degrees; raise the tolerances")
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
                regions += [(mapping, (s0, mid, t0, t1)), (mapping, (mid, s1, t0, t1))]
            else:
                mid = 0.5 * (t0 + t1)
                regions += [(mapping, (s0, s1, t0, mid)), (mapping, (s0, s1, mid, t1))]
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
    points = evaluate_net(net, _VERIFY, _VERIFY).reshape(-1, 3)
    closest = closest_points(face, points)[0]
    return float(np.linalg.norm(points - closest, axis=1).max())
