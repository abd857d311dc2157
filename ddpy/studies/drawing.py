"""Measurements of the reverse deep drawing benchmark (paper Fig. 17-21) and physical checks
of a forming run.

The cup's axis is a global axis (``axis``, default z) through the origin; radii are measured
from it. Lengths in mm, forces in N.

- :func:`hexahedron_volumes`, :func:`volume_change`: the exact volume of trilinear 8-node
  hexahedra (2 x 2 x 2 Gauss points integrate the Jacobian determinant exactly), and the
  relative change of the blank's volume (plastic flow keeps it; only the elastic strains
  change it).
- :func:`cup_height`, :func:`rim_radius`, :func:`rim_nodes`: the cup's extent along the axis
  and the radius of the blank's outer edge (the flange's radius while there is a flange).
- :func:`element_centroids`, :func:`plane_section`: values along a radial section, the
  points that lie within a band about a symmetry plane, ordered by their radius.
- :func:`contact_force_balance`: a tool's reaction against the sum of the nodal contact
  forces of the nodes in contact with it (equal and opposite when the contact forces are
  the only load between the blank and the tool).
- :func:`penetration`: the largest depth of blank nodes inside a tool, from an orthogonal
  projection on the tool at its position (:class:`ddpy.geometry.search.ContactSearch`).
- :func:`siebel_force`, :func:`tensile_limit`, :func:`swift_stress`: a hand estimate of a
  cylindrical draw's largest punch force (Siebel's elementary theory of deep drawing) and
  the force at which the cup's wall would neck, to hold a computed force against.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy._validate import float_array
from ddpy.model.contact import check_friction
from ddpy.model.mesh import element_volumes

if TYPE_CHECKING:
    from ddpy.geometry.search import ContactSearch

__all__ = ["ForceBalance", "Penetration", "contact_force_balance", "cup_height",
           "element_centroids", "hexahedron_volumes", "penetration", "plane_section",
           "rim_nodes", "rim_radius", "siebel_force", "swift_stress", "tensile_limit",
           "volume_change"]


def hexahedron_volumes(coordinates: ArrayLike, elements: ArrayLike) -> NDArray[np.float64]:
    """Volume of each trilinear hexahedron, (m,) mm^3: the integral of det J over the
    element by 2 x 2 x 2 Gauss points, exact for a trilinear map (det J is of degree 2 in
    each natural coordinate). Nodes (n, 3), elements (m, 8) of 0-based indices in Gmsh
    order; an inverted element has a negative volume."""
    x = float_array(coordinates, "coordinates", (None, 3))
    connectivity = np.asarray(elements, dtype=np.int64)
    if connectivity.ndim != 2 or connectivity.shape[1] != 8:
        raise ValueError(f"elements must have shape (m, 8), got {connectivity.shape}")
    return element_volumes(x, connectivity)


def volume_change(initial: ArrayLike, current: ArrayLike, elements: ArrayLike) -> float:
    """Relative change of the total volume of the hexahedra from ``initial`` to
    ``current`` node positions: V / V0 - 1."""
    v0 = hexahedron_volumes(initial, elements).sum()
    return float(hexahedron_volumes(current, elements).sum() / v0 - 1.0)


def _radius(points: NDArray[np.float64], axis: int) -> NDArray[np.float64]:
    others = [i for i in range(3) if i != axis]
    return np.hypot(points[:, others[0]], points[:, others[1]])


def cup_height(coordinates: ArrayLike, axis: int = 2) -> float:
    """The part's extent along the cup's ``axis`` (largest minus smallest coordinate of its
    nodes): from the outside of the cup's bottom to the top of its flange or rim, the
    thickness included."""
    x = float_array(coordinates, "coordinates", (None, 3))
    return float(np.ptp(x[:, axis]))


def rim_nodes(initial: ArrayLike, radius: float, tolerance: float = 1e-6, axis: int = 2
              ) -> NDArray[np.int64]:
    """Indices of the nodes initially on the blank's outer edge, a circle of ``radius``
    about ``axis`` (within ``tolerance``)."""
    x = float_array(initial, "initial", (None, 3))
    return np.flatnonzero(_radius(x, axis) >= radius - tolerance)


def rim_radius(coordinates: ArrayLike, rim: ArrayLike, axis: int = 2
               ) -> tuple[float, float, float]:
    """Mean, smallest and largest current radius of the nodes ``rim`` (the blank's edge):
    the flange's outer radius, and its spread (ears of an anisotropic sheet)."""
    x = float_array(coordinates, "coordinates", (None, 3))
    r = _radius(x[np.asarray(rim, dtype=np.int64)], axis)
    if r.size == 0:
        raise ValueError("no rim node")
    return float(r.mean()), float(r.min()), float(r.max())


def element_centroids(coordinates: ArrayLike, elements: ArrayLike) -> NDArray[np.float64]:
    """Mean of the 8 node positions of each hexahedron, (m, 3)."""
    x = float_array(coordinates, "coordinates", (None, 3))
    return x[np.asarray(elements, dtype=np.int64)].mean(axis=1)


def plane_section(points: ArrayLike, values: ArrayLike, band: float, plane_axis: int = 1,
                  axis: int = 2) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A radial section: the ``values`` at the ``points`` (k, 3) that lie within ``band``
    of the plane ``x[plane_axis] = 0`` (a symmetry plane through the cup's axis), as
    (radius about ``axis``, value), ordered by radius. Pass initial positions to plot
    against the initial radius."""
    x = float_array(points, "points", (None, 3))
    v = np.asarray(values, dtype=float)
    if v.shape[0] != x.shape[0]:
        raise ValueError(f"values must have {x.shape[0]} rows, got {v.shape[0]}")
    near = np.abs(x[:, plane_axis]) <= band
    r = _radius(x[near], axis)
    order = np.argsort(r, kind="stable")
    return r[order], v[near][order]


@dataclass(frozen=True)
class ForceBalance:
    """A tool's reaction against the nodal contact forces of the nodes touching it (N)."""

    reaction: NDArray[np.float64]     #: (3,) reaction force on the tool
    nodal_sum: NDArray[np.float64]    #: (3,) sum of the contact forces on its nodes
    nodes: int                        #: nodes in contact with the tool

    @property
    def mismatch(self) -> float:
        """|reaction + nodal sum| (N): zero when the two are equal and opposite."""
        return float(np.linalg.norm(self.reaction + self.nodal_sum))

    @property
    def relative(self) -> float:
        """The mismatch over |reaction| (0 when both are zero)."""
        scale = float(np.linalg.norm(self.reaction))
        return self.mismatch / scale if scale > 0.0 else (0.0 if self.mismatch == 0.0
                                                           else float("inf"))


def contact_force_balance(reaction: ArrayLike, contact_force: ArrayLike,
                          contact_tool: ArrayLike, tool: int) -> ForceBalance:
    """The reaction on tool number ``tool`` (3,) against the contact forces on the blank's
    nodes (n, 3) whose ``contact_tool`` (n,) is that tool. The force on a node is the
    tool's push on the blank, the reaction the blank's push on the tool: by Newton's third
    law they cancel."""
    force = float_array(contact_force, "contact_force", (None, 3))
    which = np.asarray(contact_tool).reshape(-1)
    if which.shape[0] != force.shape[0]:
        raise ValueError(f"contact_tool must have {force.shape[0]} entries, got {which.size}")
    mine = which == tool
    return ForceBalance(float_array(reaction, "reaction", (3,)).copy(),
                        force[mine].sum(axis=0), int(mine.sum()))


@dataclass(frozen=True)
class Penetration:
    """The deepest node inside a tool: depth (mm, 0 when none is inside) and its index
    (-1 when none)."""

    depth: float
    node: int
    inside: int          #: nodes inside the tool (distance < 0)


def penetration(points: ArrayLike, search: ContactSearch, tool_displacement: ArrayLike = (0, 0, 0),
                nodes: ArrayLike | None = None) -> Penetration:
    """Largest penetration of ``points`` (n, 3) into a tool: ``search`` is its
    :class:`ddpy.geometry.search.ContactSearch`, ``tool_displacement`` where the tool has
    moved since its file's position. Only ``nodes`` (indices; default all) are checked: the blank's
    surface facing the tool (the other surface lies a thickness behind it). Nodes whose
    closest point is inside a patch count; those held on a patch's boundary (beyond the
    tool's edge) do not."""
    from ddpy.geometry.search import INSIDE

    x = float_array(points, "points", (None, 3))
    index = np.arange(x.shape[0]) if nodes is None else np.asarray(nodes, dtype=np.int64)
    found = search.project(x[index], tool_displacement)
    depth = np.where(found.status == INSIDE, -found.distance, -np.inf)
    inside = int(np.sum(depth > 0.0))
    if inside == 0:
        return Penetration(0.0, -1, 0)
    k = int(np.argmax(depth))
    return Penetration(float(depth[k]), int(index[k]), inside)


def swift_stress(strain: float, k: float, eps0: float, n: float) -> float:
    """Swift's flow stress K (eps0 + strain)^n (MPa) at an equivalent plastic strain."""
    return float(k * (eps0 + strain) ** n)


def tensile_limit(k: float, eps0: float, n: float, ratio: float = 1.0) -> float:
    """The engineering tensile strength (MPa) of a Swift material: the largest load per
    initial section, c K (eps0 + e)^n exp(-e / c), over the equivalent plastic strain e
    (elastic strain neglected), where c is ``ratio``, the major stress over the
    equivalent one: 1 in uniaxial tension, ``Hill48.plane_strain_ratio`` in a wall that
    cannot shrink across the load (its major strain is then e / c, by equal plastic
    work, and its section falls as exp(-e / c)). Reached at Considere's e = c n - eps0
    (at e = 0 when eps0 >= c n)."""
    if not ratio > 0.0:
        raise ValueError(f"ratio must be positive, got {ratio}")
    e = max(0.0, ratio * n - eps0)
    return ratio * swift_stress(e, k, eps0, n) * float(np.exp(-e / ratio))


def siebel_force(diameter: float, mean_diameter: float, thickness: float,
                 flow_stress_mean: float, flow_stress_bend: float, friction: float,
                 radii: tuple[float, ...], wrap: float, holder_force: float = 0.0,
                 entry: tuple[tuple[float, float], ...] = ()) -> float:
    """Siebel's estimate of the largest punch force (N, the whole cup) of a cylindrical
    draw that reduces ``diameter`` (the blank's, or the last cup's, at the start of the
    draw) to ``mean_diameter`` (the new cup's mid-wall diameter) in a sheet of
    ``thickness`` (mm):

        F = pi d_m s [exp(mu alpha) (s_in + 1.1 k_m ln(D / d_m) + 2 mu F_N / (pi D s))
                      + sum_r k_b s / (2 r)]

    the ideal work of the flange's radial drawing (k_m its mean flow stress, 1.1 for the
    inhomogeneity), the blank-holder's friction (F_N its force), the belt friction over the
    angle ``wrap`` (rad) that the sheet wraps around the tool radii ``radii`` after the
    drawing zone, and the bending and unbending over each of them at the flow stress
    ``flow_stress_bend``. ``entry``: the (radius, wrap) of each tool radius the sheet
    passes *before* the drawing zone, coming in without tension (a reverse redraw: the
    first cup's wall turning half a turn over the last punch's nose before the end ring on
    which its diameter shrinks). Each bends the sheet in and out, k_b s / (4 r) each, the
    friction of its wrap acting on what the bending brought in:
    s <- (s + k_b s / (4 r)) exp(mu alpha_r) + k_b s / (4 r), from s = 0; s_in is the
    result. Friction over the whole wrap of a reverse redraw applied to the ideal
    drawing stress would count half a turn that the drawing stress never passes. An
    elementary bound to hold a computed force against (to 10 or 20 %), not a model."""
    for name, value in (("diameter", diameter), ("mean_diameter", mean_diameter),
                        ("thickness", thickness), ("flow_stress_mean", flow_stress_mean),
                        ("flow_stress_bend", flow_stress_bend)):
        if not value > 0.0:
            raise ValueError(f"{name} must be positive, got {value}")
    if not diameter > mean_diameter:
        raise ValueError(f"the draw must reduce the diameter: {diameter} -> {mean_diameter}")
    check_friction(friction)
    if (any(not r > 0.0 for r in radii) or wrap < 0.0 or holder_force < 0.0
            or any(not r > 0.0 or a < 0.0 for r, a in entry)):
        raise ValueError("radii must be positive; wrap, entry wraps and holder_force >= 0")
    incoming = 0.0
    for r, a in entry:
        half_bend = flow_stress_bend * thickness / (4.0 * r)
        incoming = (incoming + half_bend) * np.exp(friction * a) + half_bend
    ideal = 1.1 * flow_stress_mean * np.log(diameter / mean_diameter)
    holder = 2.0 * friction * holder_force / (np.pi * diameter * thickness)
    bending = sum(flow_stress_bend * thickness / (2.0 * r) for r in radii)
    stress = np.exp(friction * wrap) * (incoming + ideal + holder) + bending
    return float(np.pi * mean_diameter * thickness * stress)
