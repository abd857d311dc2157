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
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy.geometry.search import INSIDE, ContactSearch
from ddpy.geometry.surfaces import BezierSurface, NagataSurface
from ddpy.io.case import (
    MAX_TRAVEL_EXTENTS,
    Case,
    DeckError,
    HoldForce,
    HoldGap,
    Move,
    Phase,
    blank_thickness,
    longest_travel,
    summarize_alike,
)
from ddpy.model.forming import start_depth_limit
from ddpy.model.tool import faces_blank

__all__ = ["geometry_checks", "geometry_errors", "geometry_warnings"]

#: Tools on opposite sides of the blank may not come closer than this fraction of its
#: thickness during a phase.
CLEARANCE = 0.5
#: Positions along each phase where the clearance is checked.
SAMPLES = 10
#: Most surface points of one tool used for the clearance check.
MAX_POINTS = 2000
#: A tool's size (the diagonal of the box around it) against the blank's: a tool more than
#: TOOL_SIZE_REFUSED times larger or smaller is refused (a tool file in other units, or
#: scaled by mistake: 1e30, 3e-11 mm were run), beyond TOOL_SIZE_WARNED it is warned about.
TOOL_SIZE_REFUSED, TOOL_SIZE_WARNED = 1e3, 1e2

#: An axis-aligned box: lower and upper corner.
Box = tuple[NDArray[np.float64], NDArray[np.float64]]


def _error(origin: str, message: str) -> DeckError:
    path, _, line = origin.rpartition(":")
    if path and line.isdigit():
        return DeckError(message, Path(path), int(line))
    return DeckError(message, Path(origin) if origin else None)


def geometry_checks(case: Case) -> tuple[list[DeckError], list[str]]:
    """Errors and warnings of the tool sizes, positions and motions (geometry_errors and
    geometry_warnings), with one search per tool; none when the tool models cannot be read
    here. A tool of absurd size stops the checks there: its search would mean nothing."""
    try:
        surfaces = {t.name: t.model().surface for t in case.tools}
    except ImportError:  # ddpy.io.toolfile is not part of this build
        return [], []
    boxes = {name: surface_box(surface) for name, surface in surfaces.items()}
    errors, warnings = _size_checks(case, boxes)
    if errors:
        return errors, warnings
    searches = {name: ContactSearch(surface) for name, surface in surfaces.items()}
    return (geometry_errors(case, searches, boxes),
            warnings + geometry_warnings(case, searches, boxes))


def _searches(case: Case) -> dict[str, ContactSearch] | None:
    """A contact search per tool; None when ddpy.io.toolfile is not part of this build."""
    try:
        return {t.name: ContactSearch(t.model().surface) for t in case.tools}
    except ImportError:
        return None


def surface_box(surface: BezierSurface | NagataSurface) -> Box:
    """The box around a tool surface: its vertices (a Nagata patch bulges past them by a
    fraction of its size, which the checks of sizes and travels can ignore) or its Bezier
    control points (a patch lies in their convex hull)."""
    if isinstance(surface, NagataSurface):
        points = surface.vertices
    else:
        points = np.concatenate([surface.control[p, :m + 1, :n + 1].reshape(-1, 3)
                                 for p, (n, m) in enumerate(surface.degrees)])
    return points.min(axis=0), points.max(axis=0)


def _boxes(searches: dict[str, ContactSearch]) -> dict[str, Box]:
    return {name: surface_box(search.surface) for name, search in searches.items()}


def geometry_errors(case: Case, searches: dict[str, ContactSearch] | None = None,
                    boxes: dict[str, Box] | None = None) -> list[DeckError]:
    """Errors of the tool positions and motions; [] when the tool models cannot be read here."""
    searches = _searches(case) if searches is None else searches
    if searches is None:
        return []
    boxes = _boxes(searches) if boxes is None else boxes
    thickness = blank_thickness(case.mesh) or 1.0
    return (_facing_errors(case, searches) + _travel_errors(case, boxes)
            + _start_errors(case, searches)
            + _clearance_errors(case, searches, boxes, thickness))


def _size_checks(case: Case, boxes: dict[str, Box]) -> tuple[list[DeckError], list[str]]:
    """Each tool's size against the blank's: errors beyond TOOL_SIZE_REFUSED, warnings
    beyond TOOL_SIZE_WARNED."""
    low, high = case.mesh.bounds()
    blank = float(np.linalg.norm(high - low))
    errors, warnings = [], []
    for tool in case.tools:
        lo, hi = boxes[tool.name]
        size = float(np.linalg.norm(hi - lo))
        ratio = size / blank
        if TOOL_SIZE_REFUSED ** -1 <= ratio <= TOOL_SIZE_REFUSED and \
                TOOL_SIZE_WARNED ** -1 <= ratio <= TOOL_SIZE_WARNED:
            continue
        what = (f"tool '{tool.name}' is {size:.3g} mm across ({tool.file.name}), the blank "
                f"{blank:.3g} mm: {ratio:.3g} times its size")
        if not TOOL_SIZE_REFUSED ** -1 <= ratio <= TOOL_SIZE_REFUSED:
            errors.append(_error(tool.origin, f"{what}; expected a tool within "
                                 f"{TOOL_SIZE_REFUSED ** -1:g} to {TOOL_SIZE_REFUSED:g} times "
                                 "the blank's size (is its file in other units, or scaled?)"))
        else:
            warnings.append(f"{tool.origin}: {what} (is its file in other units, or "
                            "scaled?)")
    return errors, warnings


def _facing_errors(case: Case, searches: dict[str, ContactSearch]) -> list[DeckError]:
    """A tool none of whose patches faces the blank side it touches: the run refuses it
    (ddpy.model.tool.RigidTool), whichever phase uses it."""
    return [_error(t.origin, f"no patch of tool '{t.name}' faces the {t.side} of the "
                   f"blank: no normal of {t.file.name} points against the blank's outward "
                   f"normal ({_xyz(np.asarray(t.facing))}); expected a tool file whose "
                   "normals point towards the blank")
            for t in case.tools if not faces_blank(searches[t.name], t.facing)]


def _phase_starts(case: Case) -> Iterator[tuple[Phase, dict[str, NDArray[np.float64]],
                                                list[str]]]:
    """Each forming phase, the tools' displacements at its start (from their positions in
    the tool files) and its active tools whose position is known there: not set by a gap or a force,
    in this phase or an earlier one."""
    position = {t.name: np.zeros(3) for t in case.tools}
    placed = set(position)
    for phase in case.phases:
        if phase.is_springback:
            continue
        for name in phase.tools:
            if isinstance(phase.motion(name), (HoldGap, HoldForce)):
                placed.discard(name)
        yield phase, position, [n for n in phase.tools if n in placed]
        for name in phase.tools:
            if name in placed:
                position[name] = position[name] + phase.displacement(name)


def _travel_errors(case: Case, boxes: dict[str, Box]) -> list[DeckError]:
    """A move longer than MAX_TRAVEL_EXTENTS times the model's extent along it: the box
    around the blank and the tools where they start, measured along the motion."""
    corners = [case.mesh.bounds(), *boxes.values()]
    low = np.min([lo for lo, _ in corners], axis=0)
    high = np.max([hi for _, hi in corners], axis=0)
    errors = []
    for phase in case.phases:
        for move in phase.motions:
            if not isinstance(move, Move) or move.travel == 0.0:
                continue
            longest = longest_travel(move.displacement, low, high)
            if move.travel > longest:
                errors.append(_error(move.origin, f"phase '{phase.name}': tool '{move.tool}' "
                                     f"travels {move.travel:.4g} mm, more than "
                                     f"{MAX_TRAVEL_EXTENTS:g} times the extent of the model "
                                     "(the blank and the tools) along its motion, "
                                     f"{longest / MAX_TRAVEL_EXTENTS:.4g} mm; expected a "
                                     f"travel of at most {longest:.4g} mm"))
    return errors


def _passing_warnings(case: Case, boxes: dict[str, Box]) -> list[str]:
    """Pairs of active tools of a phase whose boxes start level or before each other along
    an axis and end entirely past each other: one tool would go through the other (or the
    blank between them would be carried past a tool that touches it)."""
    warnings = []
    for phase, position, known in _phase_starts(case):
        for a, b in itertools.combinations(known, 2):
            relative = phase.displacement(a) - phase.displacement(b)  # a seen from b
            if not relative.any():
                continue
            lo_a, hi_a = (c + position[a] - position[b] for c in boxes[a])
            lo_b, hi_b = boxes[b]
            for axis in np.flatnonzero(relative):
                r = relative[axis]
                passes = (hi_a[axis] >= lo_b[axis] and hi_a[axis] + r < lo_b[axis]) if r < 0 \
                    else (lo_a[axis] <= hi_b[axis] and lo_a[axis] + r > hi_b[axis])
                if passes:
                    mover = phase.motion(a) if phase.displacement(a).any() else phase.motion(b)
                    where = mover.origin if isinstance(mover, Move) else phase.origin
                    sign = "-" if r < 0 else "+"
                    warnings.append(f"{where}: phase '{phase.name}': the boxes around tools "
                                    f"'{a}' and '{b}' end entirely past each other along "
                                    f"{sign}{'xyz'[axis]}: does one go through the other?")
                    break
    return summarize_alike(warnings, "pairs of tools that pass each other")


def geometry_warnings(case: Case, searches: dict[str, ContactSearch] | None = None,
                      boxes: dict[str, Box] | None = None) -> list[str]:
    """What is legal but most likely a slip: the lead tool of a forming phase moving away
    from the blank, or, in the first phase (the blank as meshed), starting so far from it
    that its travel never brings it there; two tools whose boxes pass each other."""
    searches = _searches(case) if searches is None else searches
    if searches is None:
        return []
    boxes = _boxes(searches) if boxes is None else boxes
    mesh = case.mesh
    thickness = blank_thickness(mesh) or 1.0
    warnings: list[str] = []
    away: list[str] = []
    first = next((p for p in case.phases if not p.is_springback), None)
    for phase in case.phases:
        lead = phase.lead  # resolved by the deck reader for every forming phase
        if lead is not None:
            tool, move = case.tool(lead), phase.displacement(lead)
            mover = phase.motion(lead)
            where = mover.origin if isinstance(mover, Move) else phase.origin
            towards = -float(np.dot(move, tool.facing))
            if towards <= 0.0:
                away.append(f"{where}: phase '{phase.name}': the lead tool '{lead}' moves "
                            f"away from the blank (its {tool.side} faces the tool, the "
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
    return (summarize_alike(away, "phases whose lead tool moves away from the blank")
            + warnings + _passing_warnings(case, boxes))


def _start_errors(case: Case, searches: dict[str, ContactSearch]) -> list[DeckError]:
    errors = []
    mesh, first = case.mesh, case.phases[0]
    # The run refuses a tool deeper than its first increment may push the blank out by.
    size = mesh.element_size()
    allowed = start_depth_limit(first.limits.strain, size)
    for name in first.tools:
        if isinstance(first.motion(name), (HoldGap, HoldForce)):
            continue  # placed by its gap, or brought onto the blank by its force
        tool = case.tool(name)
        nodes = tool.contact_nodes(mesh)
        found = searches[name].project(mesh.nodes[nodes])
        inside = found.status == INSIDE
        along = found.normal @ np.asarray(tool.facing)
        clear = inside & (np.abs(along) > 0.5)
        if inside.any() and not clear.any():
            errors.append(_error(tool.origin, f"tool '{name}' faces no node of the "
                                 f"blank's {tool.side}: its normals are side-on to the "
                                 f"contact direction {_xyz(np.asarray(tool.facing))} (the "
                                 "search only pairs a node with a tool surface within 60 "
                                 "degrees of facing it); expected the side of the blank the "
                                 "tool touches"))
            continue
        if clear.any() and (along[clear] > 0).all():
            errors.append(_error(tool.origin, f"the normals of tool '{name}' point away from "
                                 f"the blank (the {tool.side} of the blank faces them): "
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
                                 f"expected the tool on the {tool.side} of the blank, "
                                 "at most that deep in it"))
    return errors


def _clearance_errors(case: Case, searches: dict[str, ContactSearch], boxes: dict[str, Box],
                      thickness: float) -> list[DeckError]:
    errors = []
    points = {name: _samples(s) for name, s in searches.items()}
    limit = CLEARANCE * thickness
    for phase, position, known in _phase_starts(case):
        for a, b in itertools.combinations(known, 2):
            fa, fb = case.tool(a).facing, case.tool(b).facing
            if float(np.dot(fa, fb)) > -0.5:
                continue  # same side of the blank
            da, db = phase.displacement(a), phase.displacement(b)
            if not (da.any() or db.any()):
                continue
            shift = position[a] - position[b]  # a relative to b at the start of the phase
            window = _boxes_meet(boxes[a], boxes[b], shift, da - db, limit)
            if window is None:
                continue  # their boxes stay farther apart than the limit
            close = _first_approach(points, searches, a, b, shift, da - db, limit, window)
            if close is not None:
                gap, fraction = close
                mover = phase.motion(a) if da.any() else phase.motion(b)
                assert isinstance(mover, Move)
                how = (f"cross each other ({-gap:.3g} mm deep)" if gap < 0 else
                       f"come {gap:.3g} mm apart, less than half the blank thickness "
                       f"{thickness:.3g} mm")
                errors.append(_error(mover.origin, f"phase '{phase.name}': tools '{a}' and "
                                     f"'{b}' {how} at {100 * fraction:.3g} % of the phase: "
                                     "the motion goes through the blank"))
                return errors  # later positions follow from this one
    return errors


def _boxes_meet(box_a: Box, box_b: Box, shift: NDArray[np.float64],
                relative: NDArray[np.float64], margin: float) -> tuple[float, float] | None:
    """The fractions of the phase between which the box of tool a, shifted by ``shift`` and
    moving by ``relative`` over the phase, comes within ``margin`` of the box of tool b
    (each axis an interval of the fraction, intersected); None when it never does."""
    (lo_a, hi_a), (lo_b, hi_b) = box_a, box_b
    start, end = 0.0, 1.0
    for k in range(3):
        # Overlap along k: lo_a + shift + t r <= hi_b + margin and hi_a + shift + t r >=
        # lo_b - margin.
        upper = hi_b[k] + margin - (lo_a[k] + shift[k])  # t r <= upper
        lower = lo_b[k] - margin - (hi_a[k] + shift[k])  # t r >= lower
        r = relative[k]
        if r == 0.0:
            if lower > 0.0 or upper < 0.0:
                return None
            continue
        first, last = sorted((lower / r, upper / r))
        start, end = max(start, first), min(end, last)
        if start > end:
            return None
    return start, end


def _first_approach(points: dict[str, NDArray[np.float64]],
                    searches: dict[str, ContactSearch], a: str, b: str,
                    shift: NDArray[np.float64], relative: NDArray[np.float64], limit: float,
                    window: tuple[float, float]) -> tuple[float, float] | None:
    """The first position along the phase (fraction) where a surface point of either tool is
    less than ``limit`` in front of the other's surface, and the smallest distance there.
    Only the relative motion matters: all positions go to the search in one batch. The
    positions are SAMPLES within the ``window`` of the phase where the tools' boxes meet
    (the start of the phase left out: the first phase's start is checked on its own): over
    the whole phase a long motion could pass a tool between two of them."""
    start, end = window
    fractions = np.linspace(start, end, SAMPLES + 1)[1:] if start == 0.0 else \
        np.linspace(start, end, SAMPLES)
    count = fractions.size
    offsets = shift + fractions[:, None] * relative  # a relative to b
    smallest = np.full(count, np.inf)
    for p, q, sign in ((a, b, 1.0), (b, a, -1.0)):
        moved = (points[p][None, :, :] + sign * offsets[:, None, :]).reshape(-1, 3)
        found = searches[q].project(moved)
        distance = np.where(found.status == INSIDE, found.distance, np.inf)
        smallest = np.minimum(smallest, distance.reshape(count, -1).min(axis=1))
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
