"""Checks of a case against the geometry of its tools, before any run (docs/input-format.md,
"Checks"): each tool of the first phase starts outside the blank, on the side it touches, with
its normals towards the blank; no forming phase brings two tools on opposite sides of the blank
closer than half its thickness (a motion through the blank).

They need the tool models (``ddpy.io.toolfile``); without that module they are skipped. The
contact search (:class:`ddpy.geometry.search.ContactSearch`) measures the distances, so a check sees
the surface the solver will see.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy.geometry.search import INSIDE, ContactSearch
from ddpy.geometry.surfaces import NagataSurface
from ddpy.io.case import Case, DeckError, HoldGap, Move, blank_thickness
from ddpy.model.forming import start_depth_limit

__all__ = ["geometry_checks", "geometry_errors", "geometry_warnings"]

#: Tools on opposite sides of the blank may not come closer than this fraction of its
#: thickness during a phase.
CLEARANCE = 0.5
#: Positions along each phase where the clearance is checked.
SAMPLES = 10
#: Most surface points of one tool used for the clearance check.
MAX_POINTS = 2000


def _error(origin: str, message: str) -> DeckError:
    path, _, line = origin.rpartition(":")
    if path and line.isdigit():
        return DeckError(message, Path(path), int(line))
    return DeckError(message, Path(origin) if origin else None)


def geometry_checks(case: Case) -> tuple[list[DeckError], list[str]]:
    """Errors and warnings of the tool positions and motions (geometry_errors and
    geometry_warnings), with one search per tool; none when the tool models cannot be read
    here."""
    searches = _searches(case)
    if searches is None:
        return [], []
    return geometry_errors(case, searches), geometry_warnings(case, searches)


def _searches(case: Case) -> dict[str, ContactSearch] | None:
    """A contact search per tool; None when ddpy.io.toolfile is not part of this build."""
    try:
        return {t.name: ContactSearch(t.model().surface) for t in case.tools}
    except ImportError:
        return None


def geometry_errors(case: Case, searches: dict[str, ContactSearch] | None = None
                    ) -> list[DeckError]:
    """Errors of the tool positions and motions; [] when the tool models cannot be read here."""
    searches = _searches(case) if searches is None else searches
    if searches is None:
        return []
    thickness = blank_thickness(case.mesh) or 1.0
    return _start_errors(case, searches) + _clearance_errors(case, searches, thickness)


def geometry_warnings(case: Case, searches: dict[str, ContactSearch] | None = None
                      ) -> list[str]:
    """What is legal but most likely a slip: the lead tool of a forming phase moving away
    from the blank, or, in the first phase (the blank as meshed), starting so far from it
    that its travel never brings it there."""
    searches = _searches(case) if searches is None else searches
    if searches is None:
        return []
    mesh = case.mesh
    thickness = blank_thickness(mesh) or 1.0
    warnings = []
    first = next((p for p in case.phases if not p.is_springback), None)
    for phase in case.phases:
        lead = phase.lead  # resolved by the deck reader for every forming phase
        if lead is not None:
            tool, move = case.tool(lead), phase.displacement(lead)
            mover = phase.motion(lead)
            where = mover.origin if isinstance(mover, Move) else phase.origin
            towards = -float(np.dot(move, tool.facing))
            if towards <= 0.0:
                warnings.append(f"{where}: phase '{phase.name}': the lead tool '{lead}' moves "
                                f"away from the blank (its {tool.contact} faces the tool, the "
                                f"motion {_xyz(move)} points the other way)")
            elif phase is first:
                nodes = tool.contact_nodes(mesh)
                found = searches[lead].project(mesh.nodes[nodes])
                gap = np.where(found.status != 0, np.abs(found.distance), np.inf).min() \
                    if nodes.size else np.inf
                if gap > towards + thickness:
                    warnings.append(f"{where}: phase '{phase.name}': the lead tool '{lead}' "
                                    f"starts {gap:.4g} mm from the blank and moves "
                                    f"{towards:.4g} mm towards it: it never reaches it")
    return warnings


def _start_errors(case: Case, searches: dict[str, ContactSearch]) -> list[DeckError]:
    errors = []
    mesh, first = case.mesh, case.phases[0]
    # The run refuses a tool deeper than its first increment may push the blank out by.
    size = mesh.element_size()
    allowed = start_depth_limit(first.limits.strain, size)
    for name in first.tools:
        if isinstance(first.motion(name), HoldGap):
            continue  # placed by its gap
        tool = case.tool(name)
        nodes = tool.contact_nodes(mesh)
        found = searches[name].project(mesh.nodes[nodes])
        inside = found.status == INSIDE
        along = found.normal @ np.asarray(tool.facing)
        clear = inside & (np.abs(along) > 0.5)
        if inside.any() and not clear.any():
            errors.append(_error(tool.origin, f"tool '{name}' faces no node of the "
                                 f"blank's {tool.contact}: its normals are side-on to the "
                                 f"contact direction {_xyz(np.asarray(tool.facing))} (the "
                                 "search only pairs a node with a tool surface within 60 "
                                 "degrees of facing it); expected the side of the blank the "
                                 "tool touches"))
            continue
        if clear.any() and (along[clear] > 0).all():
            errors.append(_error(tool.origin, f"the normals of tool '{name}' point away from "
                                 f"the blank (the {tool.contact} of the blank faces them): "
                                 "expected a tool file whose normals point towards the blank"))
            continue
        depth = np.where(inside, -found.distance, -np.inf)
        worst = int(np.argmax(depth))
        if depth[worst] > allowed:
            x = mesh.nodes[nodes[worst]]
            errors.append(_error(tool.origin, f"tool '{name}' starts inside the blank: node "
                                 f"{mesh.node_ids[nodes[worst]]} at ({_xyz(x)}) is "
                                 f"{depth[worst]:.3g} mm behind its surface, more than the "
                                 f"first phase's rmin_strain times the element size "
                                 f"({first.limits.strain:g} x {size:.3g} = {allowed:.3g} mm); "
                                 f"expected the tool on the {tool.contact} of the blank, "
                                 "at most that deep in it"))
    return errors


def _clearance_errors(case: Case, searches: dict[str, ContactSearch], thickness: float
                      ) -> list[DeckError]:
    errors = []
    position = {t.name: np.zeros(3) for t in case.tools}
    placed = set(position)  # tools whose position is known (not set by a gap)
    points = {name: _samples(s) for name, s in searches.items()}
    for phase in case.phases:
        if phase.is_springback:
            continue
        for name in phase.tools:
            if isinstance(phase.motion(name), HoldGap):
                placed.discard(name)
        known = [n for n in phase.tools if n in placed]
        for a, b in itertools.combinations(known, 2):
            fa, fb = case.tool(a).facing, case.tool(b).facing
            if float(np.dot(fa, fb)) > -0.5:
                continue  # same side of the blank
            da, db = phase.displacement(a), phase.displacement(b)
            if not (da.any() or db.any()):
                continue
            close = _first_approach(points, searches, a, b, position, da, db,
                                    CLEARANCE * thickness)
            if close is not None:
                gap, fraction = close
                mover = phase.motion(a) if da.any() else phase.motion(b)
                assert isinstance(mover, Move)
                how = (f"cross each other ({-gap:.3g} mm deep)" if gap < 0 else
                       f"come {gap:.3g} mm apart, less than half the blank thickness "
                       f"{thickness:.3g} mm")
                errors.append(_error(mover.origin, f"phase '{phase.name}': tools '{a}' and "
                                     f"'{b}' {how} at {fraction:.0%} of the phase: the motion "
                                     "goes through the blank"))
                return errors  # later positions follow from this one
        for name in phase.tools:
            if name in placed:
                position[name] = position[name] + phase.displacement(name)
    return errors


def _first_approach(points: dict[str, NDArray[np.float64]],
                    searches: dict[str, ContactSearch], a: str, b: str,
                    position: dict[str, NDArray[np.float64]], da: NDArray[np.float64],
                    db: NDArray[np.float64], limit: float) -> tuple[float, float] | None:
    """The first position along the phase (fraction) where a surface point of either tool is
    less than ``limit`` in front of the other's surface, and the smallest distance there.
    Only the relative motion matters: all positions go to the search in one batch."""
    fractions = np.linspace(1.0 / SAMPLES, 1.0, SAMPLES)
    shift = (position[a] - position[b]) + fractions[:, None] * (da - db)  # a relative to b
    smallest = np.full(SAMPLES, np.inf)
    for p, q, sign in ((a, b, 1.0), (b, a, -1.0)):
        moved = (points[p][None, :, :] + sign * shift[:, None, :]).reshape(-1, 3)
        found = searches[q].project(moved)
        distance = np.where(found.status == INSIDE, found.distance, np.inf)
        smallest = np.minimum(smallest, distance.reshape(SAMPLES, -1).min(axis=1))
    below = np.flatnonzero(smallest < limit)
    if below.size == 0:
        return None
    return float(smallest[below[0]]), float(fractions[below[0]])


def _samples(search: ContactSearch) -> NDArray[np.float64]:
    """Points on a tool surface: 3 x 3 per Nagata patch (the triangle folded from the
    square), the search grid on Bezier patches (few and large); at most MAX_POINTS."""
    surface = search.surface
    if isinstance(surface, NagataSurface):
        u, v = (g.ravel() for g in np.meshgrid([0.0, 0.5, 1.0], [0.0, 0.5, 1.0]))
        count = surface.n_patches
        triangle = np.repeat(surface.is_triangle, u.size)
        uu, vv = np.tile(u, count), np.tile(v, count)
        params = np.column_stack([uu, np.where(triangle, uu * vv, vv)])
        x = surface.evaluate(np.repeat(np.arange(count), u.size), params)[0]
    else:
        x = search.grid_points
    if len(x) <= MAX_POINTS:
        return x
    return x[np.linspace(0, len(x) - 1, MAX_POINTS).astype(int)]


def _xyz(x: NDArray[np.float64]) -> str:
    return ", ".join(f"{c:.4g}" for c in x)
