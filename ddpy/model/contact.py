"""Frictional contact of nodes with rigid tools: the Alart-Curnier law (docs/theory/contact.md).

The force ``lambda`` that a tool exerts on a node is an unknown beside the displacements.
Its equation C(lambda, x) = 0 holds the Kuhn-Tucker conditions in the normal direction and
Coulomb's law in the tangent plane; :func:`contact_law` gives C with its exact derivatives,
including the curvature of the tool, for the single Newton loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array
from ddpy.core.constants import constant
from ddpy.geometry.search import Projection

__all__ = ["ContactLaw", "check_friction", "contact_law", "INACTIVE", "STICK", "SLIP"]

#: State of a node: no force, sticking, slipping.
INACTIVE, STICK, SLIP = (constant("contact_open"), constant("contact_stick"),
                         constant("contact_slip"))


def check_friction(friction: ArrayLike) -> NDArray[np.float64]:
    """Coulomb friction coefficients (a value or an array) checked: finite and >= 0, else
    ValueError("friction must be >= 0, got ..."), the one check of every reader of a
    friction (the decks and .inp files add where it came from: file and line; a tool its
    name)."""
    mu = np.asarray(friction, dtype=float)
    bad = ~(np.isfinite(mu) & (mu >= 0.0))
    if bad.any():
        raise ValueError(f"friction must be >= 0, got {float(mu[bad].flat[0]):g}")
    return mu


@dataclass(frozen=True)
class ContactLaw:
    """Residual (k, 3), derivatives (k, 3, 3) along lambda and x, and states (k,)."""

    residual: NDArray[np.float64]
    d_lambda: NDArray[np.float64]
    d_x: NDArray[np.float64]
    state: NDArray[np.int32]


def contact_law(
    force: ArrayLike,
    projection: Projection,
    second_derivatives: ArrayLike,
    slip_path: ArrayLike,
    friction: ArrayLike,
    augmentation: ArrayLike,
) -> ContactLaw:
    """The Alart-Curnier residual of k nodes.

    ``force`` (k, 3): the force of the tool on each node; ``projection``: the nodes' closest
    points on the tool (ddpy.geometry.search); ``second_derivatives`` (k, 3, 3) of the tool there;
    ``slip_path`` (k, 3): node displacement relative to the tool since the last converged
    increment; ``friction`` and ``augmentation`` (k,) or scalars: mu >= 0 and r > 0.
    """
    k = projection.distance.shape[0]
    lam = float_array(force, "force", (k, 3))
    second = float_array(second_derivatives, "second_derivatives", (k, 3, 3))
    v = float_array(slip_path, "slip_path", (k, 3))
    mu = check_friction(float_array(np.broadcast_to(friction, (k,)), "friction", (k,)))
    r = float_array(np.broadcast_to(augmentation, (k,)), "augmentation", (k,))
    if (r <= 0).any():
        raise ValueError(f"augmentation must be > 0, got {r.min()}")
    if k == 0:
        z = np.zeros((0, 3, 3))
        return ContactLaw(np.zeros((0, 3)), z, z, np.zeros(0, dtype=np.int32))
    c, dl, dx, state = _core.contact_residual(
        lam.ravel(), np.ascontiguousarray(projection.normal).ravel(), projection.distance,
        np.ascontiguousarray(projection.tangents).ravel(), second.ravel(), v.ravel(), mu, r)
    # Fortran (3, 3, k) column-major: entry (i, j) of node m is at [m, j, i] in C order.
    return ContactLaw(c.reshape(k, 3), dl.reshape(k, 3, 3).transpose(0, 2, 1),
                      dx.reshape(k, 3, 3).transpose(0, 2, 1), state)
