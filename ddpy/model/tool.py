"""A rigid tool: its surface, the blank nodes that may touch it and its contact settings."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ddpy._validate import float_array, int_array
from ddpy.geometry.search import ContactSearch
from ddpy.geometry.surfaces import BezierSurface, NagataSurface
from ddpy.model.contact import check_friction

__all__ = ["RigidTool", "CONTACT_DISCRETIZATIONS", "FACE_POINTS", "MAX_POINTS", "BARRIER_DEPTH",
           "check_contact_settings", "faces_blank"]

#: How a tool's contact is discretized on the blank: "node" (node-to-surface, DD3IMP's: each
#: slave node's own gap, normal and slip) or "surface" (surface-to-surface: each slave's
#: gap, normal and slip averaged over the Gauss points of the blank faces around it) or
#: "gauss" (a penalty law at the Gauss points of the blank faces, its force spread to their
#: nodes by the shape functions; docs/theory/contact.md).
CONTACT_DISCRETIZATIONS = ("node", "surface", "gauss")
#: Gauss points per direction of the blank faces (n x n per face) of surface-to-surface and
#: Gauss-point contact by default, and at most (the core's max_face_order). Gauss-point
#: contact takes 4: a line contact (a sheet over a radius) then spans several points at the
#: default penalty, which removes the force's chatter (docs/theory/contact.md); the
#: weighted gaps of surface-to-surface contact do not change with more points.
FACE_POINTS = {"node": 2, "surface": 2, "gauss": 4}
MAX_POINTS = 8
#: Depth (a fraction of the blank's thickness) in a tool of Gauss-point contact at which
#: the barrier holds each slave node exactly (docs/theory/contact.md, "The barrier").
BARRIER_DEPTH = 0.005


def check_contact_settings(*, discretization: str | None = None,
                           augmentation: float | None = None, penalty: float | None = None,
                           points: int | None = None, barrier: float | None = None) -> None:
    """A tool's contact settings checked (those given; None: the default), the one check
    of each: ValueError naming the setting as tools.dat does ("penalty must be > 0 (N/mm^3),
    got -1"); tools.dat adds file and line, RigidTool the tool's name."""
    if discretization is not None and discretization not in CONTACT_DISCRETIZATIONS:
        raise ValueError(f"discretization must be one of {', '.join(CONTACT_DISCRETIZATIONS)}"
                         f", got {discretization!r}")
    if augmentation is not None and not augmentation > 0.0:
        raise ValueError(f"augmentation must be > 0 (N/mm, the contact law's r), got "
                         f"{augmentation:g}")
    if penalty is not None and not penalty > 0.0:
        raise ValueError(f"penalty must be > 0 (N/mm^3), got {penalty:g}")
    if points is not None and not (isinstance(points, (int, np.integer))
                                   and not isinstance(points, bool)
                                   and 1 <= points <= MAX_POINTS):
        raise ValueError(f"points (Gauss points per direction of a blank face) must be an "
                         f"integer from 1 to {MAX_POINTS}, got {points!r}")
    if barrier is not None and not 0.0 <= barrier <= 1.0:
        raise ValueError(f"barrier must be a fraction of the blank's thickness from 0 to 1 "
                         f"(or off), got {barrier:g}")


def faces_blank(search: ContactSearch, facing: ArrayLike) -> bool:
    """Whether a patch of the tool of ``search`` faces blank faces whose outward normal is
    ``facing``: some normal of its search grid points against it. Without one no node can
    touch the tool (the run refuses such a tool, and so does ``ddpy check``)."""
    return bool((search.grid_normals @ np.asarray(facing, dtype=float) < 0.0).any())


@dataclass
class RigidTool:
    """A rigid tool: its surface, the blank nodes that may touch it (``slaves``), Coulomb
    friction, and optionally the outward normal of the blank face that meets it
    (``facing``: only patches facing the opposite way are contact candidates), the
    augmentation parameter r of the contact law (default: ``default_augmentation``; for a
    Gauss-point tool's barrier ``barrier_augmentation``) and the
    contact discretization (``contact``, CONTACT_DISCRETIZATIONS: "surface" and "gauss"
    need ``facing``, which picks the blank faces that meet the tool; by default "gauss"
    where it is given, else "node") with, for "gauss", the
    penalty of its law in N/mm^3 (``penalty``, default ``default_penalty``); "surface" and
    "gauss" integrate over the blank faces with ``points`` x ``points`` Gauss points each
    (default FACE_POINTS). A "gauss" tool's ``barrier`` (a fraction of the blank's
    thickness, default BARRIER_DEPTH; None: none) is the depth in the tool at which its
    slave nodes are held exactly (docs/theory/contact.md, "The barrier")."""

    name: str
    surface: BezierSurface | NagataSurface
    slaves: ArrayLike
    friction: float = 0.0
    facing: ArrayLike | None = None
    augmentation: float | None = None
    contact: str | None = None
    penalty: float | None = None
    points: int | None = None
    barrier: float | None = BARRIER_DEPTH
    search: ContactSearch = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.name or not isinstance(self.name, str):
            raise ValueError("a tool needs a name")
        self.slaves = int_array(np.atleast_1d(self.slaves), f"slaves of tool {self.name}",
                                (None,))
        if self.slaves.size == 0:
            raise ValueError(f"tool {self.name} has no slave nodes: nothing can touch it")
        if np.unique(self.slaves).size != self.slaves.size:
            raise ValueError(f"tool {self.name}: slave nodes are repeated")
        try:
            check_friction(self.friction)
        except ValueError as error:
            raise ValueError(f"tool {self.name}: {error}") from None
        if self.contact is None:
            self.contact = "gauss" if self.facing is not None else "node"
        if self.points is None:
            self.points = FACE_POINTS.get(self.contact, 2)
        try:
            check_contact_settings(discretization=self.contact, augmentation=self.augmentation,
                                   penalty=self.penalty, points=self.points,
                                   barrier=self.barrier)
        except ValueError as error:
            raise ValueError(f"tool {self.name}: {error}") from None
        if self.contact in ("surface", "gauss") and self.facing is None:
            raise ValueError(f"tool {self.name}: {self.contact} contact needs facing (the "
                             "outward normal of the blank faces that meet the tool)")
        if self.facing is not None:
            facing = float_array(self.facing, f"facing of tool {self.name}", (3,))
            if np.linalg.norm(facing) == 0.0:
                raise ValueError(f"tool {self.name}: facing must not be zero")
            self.facing = facing / np.linalg.norm(facing)
        self.search = ContactSearch(self.surface)
        if self.facing is not None and not faces_blank(self.search, self.facing):
            raise ValueError(f"tool {self.name}: no patch faces its slave nodes (every normal "
                             f"points along facing {self.facing.tolist()}, away from the "
                             "blank): nothing can touch it; check the normals or facing")
