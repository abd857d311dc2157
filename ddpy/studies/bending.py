"""Measurements of the unconstrained cylindrical bending benchmark (paper Fig. 9-11, Table 2).

Quarter model: symmetry planes x = 0 and y = 0, the punch's axis along y, the punch moving
down (-z). Angles in degrees.

- :func:`contact_angle`, the paper's theta_1..theta_4 (Fig. 10): the angle, at the punch's
  axis, between the two contact points with the punch farthest from the centreline (the
  symmetry plane x = 0). A quarter model holds one of the two; by symmetry the angle is twice
  the angle between the downward vertical through the axis and that point.
- :func:`line_angle`, for beta_1 and beta_2 (Fig. 11, after forming and after springback): the
  inclination to the horizontal (x axis) of the straight line fitted, in the xz-plane, to a
  segment of the sheet; which segment is the caller's choice (the report script measures the
  free flange, the part of the sheet beyond the die shoulder).
- :func:`force_oscillation`, for Fig. 9: the root mean square deviation of the punch force
  from a smoothed curve, a local polynomial (moving least squares, Savitzky-Golay on uneven
  steps) of degree ``order`` over a stroke window ``window`` centred at each point.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy._validate import float_array

__all__ = ["contact_angle", "line_angle", "force_oscillation", "smooth_curve"]


def contact_angle(points: ArrayLike, in_contact: ArrayLike, axis_point: ArrayLike,
                  axis: ArrayLike = (0.0, 1.0, 0.0), down: ArrayLike = (0.0, 0.0, -1.0),
                  symmetric: bool = True) -> float:
    """Angle (degrees) at the punch's axis from the lowest line of the punch (``down`` from
    the axis) to the contact point farthest from it, doubled when ``symmetric`` (the
    other half of the model holds its mirror image): the paper's theta.

    ``points`` (n, 3) are the deformed positions of the blank nodes that may touch the punch,
    ``in_contact`` (n,) which of them do; ``axis_point`` a point of the punch's axis, ``axis``
    its direction. Points are projected on the plane normal to the axis. 0 when no point is
    in contact.
    """
    x = float_array(points, "points", (None, 3))
    flags = np.asarray(in_contact, dtype=bool)
    if flags.shape != (x.shape[0],):
        raise ValueError(f"in_contact must have shape ({x.shape[0]},), got {flags.shape}")
    a = _unit(axis, "axis")
    d = _unit(down, "down")
    d = d - (d @ a) * a
    if np.linalg.norm(d) < 1e-12:
        raise ValueError("down must not be parallel to the axis")
    d /= np.linalg.norm(d)
    if not flags.any():
        return 0.0
    r = x[flags] - float_array(axis_point, "axis_point", (3,))
    r -= np.outer(r @ a, a)
    side = np.linalg.norm(r - np.outer(r @ d, d), axis=1)
    angle = float(np.degrees(np.arctan2(side, r @ d)).max())
    return 2.0 * angle if symmetric else angle


def line_angle(points: ArrayLike, along: int = 0, up: int = 2) -> float:
    """Inclination (degrees, in [0, 90]) to the ``along`` axis of the straight line fitted in
    total least squares to ``points`` (n, 3) projected on the plane of the ``along`` and
    ``up`` axes (default: the xz-plane, inclination to the horizontal x axis)."""
    x = float_array(points, "points", (None, 3))
    if x.shape[0] < 2:
        raise ValueError("a line needs at least two points")
    p = x[:, [along, up]] - x[:, [along, up]].mean(axis=0)
    direction = np.linalg.svd(p, full_matrices=False)[2][0]
    return float(np.degrees(np.arctan2(abs(direction[1]), abs(direction[0]))))


def smooth_curve(s: ArrayLike, f: ArrayLike, window: float = 1.0, order: int = 2
                 ) -> NDArray[np.float64]:
    """The curve f(s) smoothed by a moving polynomial of degree ``order``: at each s_i, the
    least-squares polynomial through the points with |s - s_i| <= window / 2, evaluated at
    s_i (Savitzky-Golay for uneven steps). A window holding too few points for the degree is
    widened to the nearest ``order + 2`` points."""
    s = float_array(s, "s", (None,))
    f = float_array(f, "f", (s.size,))
    if not window > 0.0 or order < 0:
        raise ValueError(f"window must be > 0 and order >= 0, got {window}, {order}")
    if s.size < order + 2:
        raise ValueError(f"at least {order + 2} points are needed, got {s.size}")
    out = np.empty_like(f)
    for i, si in enumerate(s):
        near = np.flatnonzero(np.abs(s - si) <= 0.5 * window)
        if near.size < order + 2:
            near = np.argsort(np.abs(s - si), kind="stable")[:order + 2]
        scale = max(float(np.ptp(s[near])), 1e-300)
        coeffs = np.polyfit((s[near] - si) / scale, f[near], order)
        out[i] = coeffs[-1]
    return out


def force_oscillation(s: ArrayLike, f: ArrayLike, window: float = 1.0, order: int = 2,
                      start: float | None = None) -> float:
    """Root mean square of f - smooth_curve(s, f, window, order) over the points with
    s >= ``start`` (default all): how much the force oscillates about its trend, in the
    units of f. A smooth curve (a polynomial of degree <= ``order`` over each window) gives 0;
    an oscillation of amplitude A much shorter than the window gives about A / sqrt(2)."""
    s = float_array(s, "s", (None,))
    f = float_array(f, "f", (s.size,))
    deviation = f - smooth_curve(s, f, window, order)
    keep = np.ones(s.size, dtype=bool) if start is None else s >= start
    if not keep.any():
        raise ValueError(f"no point at s >= {start}")
    return float(np.sqrt(np.mean(deviation[keep] ** 2)))


def _unit(v: ArrayLike, name: str) -> NDArray[np.float64]:
    u = float_array(v, name, (3,))
    norm = float(np.linalg.norm(u))
    if norm == 0.0:
        raise ValueError(f"{name} must not be zero")
    return u / norm
