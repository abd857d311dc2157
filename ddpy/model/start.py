"""Where an increment's Newton iterations start: the last increment's displacement rate
carried on, with the turn of the blank's material lines carried on too
(docs/theory/contact.md, "Start: the turn carried on").

A material line that turns by theta in an increment is lengthened by about theta^2 when
its nodes' last motion is extrapolated along straight lines. At the 2 degree rotation
limit that is 1.2e-3, 250 MPa of elastic stress in steel: on the deep drawing's paper
blank the columns of nodes drawn over die 1's shoulder started every increment stretched
across the thickness (5 times the force scale of residual). Carrying the turn on removes
that term (the stretch falls to 2e-4, the residual to about the force scale); the first
Newton steps there are still cut, by the contact entering die 1's barrier
(docs/theory/speed.md, "The paper blank at the defaults")."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy.model.forming_quantities import nodal_average

#: The corners of the 8-node hexahedron in its natural coordinates (ddpy's node order), over
#: 8: the derivatives of its shape functions at its centre.
_CENTRE_DERIVATIVES = np.array([(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
                                (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)], float) / 8.0


def spin(nodes: ArrayLike, elements: ArrayLike, u: ArrayLike, rate: ArrayLike
         ) -> NDArray[np.float64]:
    """The angular velocity (n, 3) of the displacement rate ``rate`` (n, 3) at each node of
    the 8-node hexahedra ``elements`` (e, 8) placed at ``nodes`` + ``u``: the axial vector
    of the skew part of d(rate)/dx at each element's centre, averaged over the node's
    elements (zero at a node of no element, or of inverted ones only)."""
    x0 = np.asarray(nodes, dtype=float)
    connectivity = np.asarray(elements, dtype=np.int64)
    v = np.asarray(rate, dtype=float)
    corners = (x0 + np.asarray(u, dtype=float))[connectivity]
    jacobian = np.einsum("eai,aj->eij", corners, _CENTRE_DERIVATIVES)
    det = np.linalg.det(jacobian)
    valid = det > 0.0
    gradient = np.zeros_like(jacobian)
    gradient[valid] = np.einsum("eai,aj->eij", v[connectivity[valid]], _CENTRE_DERIVATIVES) \
        @ np.linalg.inv(jacobian[valid])
    skew = 0.5 * (gradient - np.swapaxes(gradient, 1, 2))
    omega = np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)
    return np.stack([nodal_average(connectivity[valid], omega[valid, k], x0.shape[0])
                     for k in range(3)], axis=1)


def increment_starts(nodes: ArrayLike, elements: ArrayLike, u: ArrayLike, rate: ArrayLike,
                     step: float, last_step: float, rate_before: ArrayLike | None = None,
                     step_before: float | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Two starts of an increment of ``step`` (phase factor), as displacement increments
    (n, 3) from the converged ``u`` after an increment of ``last_step`` whose mean
    displacement rate was ``rate`` (per unit factor). The turn carried on: step rate +
    step (step + last_step) / 2 (w x rate), w the rate's spin (``spin``); the rate of an
    increment is its rate at the midpoint, and a point turning at w accelerates by w x
    rate, so this start misses a rigid rotation at a constant rate by the third power of
    the increment's angle, the rate alone by the second. The rate's change carried on:
    step rate + step (step + last_step) / 2 a with a = (rate - rate_before) / ((last_step
    + step_before) / 2), the change between the midpoint rates of the last two increments
    (None without ``rate_before``). Both take the same first-order term; they differ in
    the acceleration: the spin's w x rate, or the one the path measured."""
    v = np.asarray(rate, dtype=float)
    omega = spin(nodes, elements, u, v)
    half = 0.5 * step * (step + last_step)
    turned = step * v + half * np.cross(omega, v)
    if rate_before is None or step_before is None:
        return turned, None
    change = (v - np.asarray(rate_before, dtype=float)) / (0.5 * (last_step + step_before))
    return turned, step * v + half * change


def blended_start(turned: NDArray[np.float64], changed: NDArray[np.float64] | None,
                  weight: float) -> NDArray[np.float64]:
    """The start (a displacement increment) ``weight`` of the way from ``turned`` to
    ``changed`` (``increment_starts``); ``turned`` where there is no ``changed``."""
    if changed is None or weight <= 0.0:
        return turned
    return turned + weight * (changed - turned)


def start_weight(actual: ArrayLike, turned: NDArray[np.float64],
                 changed: NDArray[np.float64] | None) -> float:
    """The weight in [0, 1] of the rate's change in the next increment's start
    (``blended_start``), from the increment ``actual`` that the last one converged to and
    its own two starts: the least-squares weight t of the blend nearest to ``actual``,
    clipped to [0, 1], times the share of the turn's miss |actual - turned|^2 that the
    blend at t removes. A smooth path (a sheet bending, a flange sliding over a shoulder)
    gives about 1: the change explains nearly all of the miss. Where the rate changes
    roughly from increment to increment (contact passing from node to node), the last
    change says little about the next, explains little of the miss, and the start keeps
    to the turn."""
    if changed is None:
        return 0.0
    between = changed - turned
    norm = float(np.vdot(between, between))
    if not norm > 0.0:
        return 0.0
    miss = np.asarray(actual, dtype=float) - turned
    miss_norm = float(np.vdot(miss, miss))
    if not miss_norm > 0.0:
        return 0.0
    weight = min(max(float(np.vdot(miss, between)) / norm, 0.0), 1.0)
    left = miss - weight * between
    return weight * max(1.0 - float(np.vdot(left, left)) / miss_norm, 0.0)
