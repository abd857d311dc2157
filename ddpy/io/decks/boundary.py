"""bc.dat: the selection tolerance, node sets (ids, box, plane), symmetry planes and fixed
nodes; and the selection of a node set's nodes from the mesh.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ddpy.io.case import AXES
from ddpy.io.decks.lines import (
    NAME_PATTERN,
    BadValue,
    Deck,
    check_arity,
    first_time,
    read_choice,
    read_float,
    read_name,
    show,
)
from ddpy.model.mesh import HexMesh

#: Smallest selection tolerance (mm): coordinates written with 10 digits (ddpy convert)
#: are off by up to 1e-7 mm in a blank a metre long.
MIN_TOLERANCE = 1e-6


@dataclass
class _BcDraft:
    tolerance: tuple[float, int] | None = None
    nodesets: list[tuple[str, str, list[str], int]] = field(default_factory=list)
    symmetries: list[tuple[int, str, int]] = field(default_factory=list)
    fixes: list[tuple[str, tuple[int, ...], list[str], int]] = field(default_factory=list)


def _parse_bc(deck: Deck) -> _BcDraft:
    draft = _BcDraft()
    seen: dict[str, int] = {}
    for line in deck.lines:
        key, w = line.key, line.words
        try:
            if key == "tolerance":
                check_arity(line, "tolerance VALUE", 1)
                if first_time(deck, seen, line):
                    tolerance = read_float(w[1], "the tolerance", gt=0)
                    if tolerance < MIN_TOLERANCE:
                        raise BadValue(f"tolerance {w[1]} mm is below {MIN_TOLERANCE:g} mm: "
                                       "a node off a plane by the rounding of its "
                                       "coordinates would not be selected")
                    draft.tolerance = (tolerance, line.number)
            elif key == "nodeset":
                check_arity(line, "nodeset NAME ids|box|plane ...", 2, -1)
                name = read_name(w[1], "the node set")
                kind = read_choice(w[2], "the node set kind", ("ids", "box", "plane"))
                if kind == "ids":
                    check_arity(line, "nodeset NAME ids ID...", 3, -1)
                    for word in w[3:]:
                        _id_range(word)
                elif kind == "box":
                    check_arity(line, "nodeset NAME box XMIN XMAX YMIN YMAX ZMIN ZMAX", 8)
                    b = [read_float(v, "a box bound", allow_inf=True) for v in w[3:]]
                    for a in range(3):
                        if b[2 * a] > b[2 * a + 1]:
                            raise BadValue(f"box bounds of {'xyz'[a]}: min {w[3 + 2 * a]} > max "
                                       f"{w[4 + 2 * a]}")
                else:
                    check_arity(line, "nodeset NAME plane AXIS VALUE", 4)
                    read_choice(w[3], "the plane axis", ("x", "y", "z"))
                    read_float(w[4], "the plane position")
                draft.nodesets.append((name, kind, w[3:], line.number))
            elif key == "symmetry":
                check_arity(line, "symmetry AXIS VALUE|NODESET", 2)
                axis = AXES[read_choice(w[1], "the symmetry axis", ("x", "y", "z"))]
                if not NAME_PATTERN.fullmatch(w[2]):
                    read_float(w[2], "the plane position")
                draft.symmetries.append((axis, w[2], line.number))
            elif key == "fix":
                check_arity(line, "fix NODESET COMPONENTS [phase PHASE...]", 2, -1)
                name = read_name(w[1], "the node set")
                comps = w[2]
                if comps == "all":
                    comps = "xyz"
                if not comps or any(c not in "xyz" for c in comps) or len(set(comps)) != len(
                        comps):
                    raise BadValue(f"expected components among x, y, z (such as 'z', 'xy', 'xyz' "
                               f"or 'all'), got {show(w[2])}")
                phases: list[str] = []
                if len(w) > 3:
                    if w[3] != "phase" or len(w) < 5:
                        raise BadValue(f"expected 'fix NODESET COMPONENTS [phase PHASE...]', got "
                                   f"{show(line.text)}")
                    phases = [read_name(p, "a phase") for p in w[4:]]
                draft.fixes.append((name, tuple(sorted(AXES[c] for c in comps)), phases,
                                    line.number))
            else:
                raise BadValue(f"unknown keyword {show(key)}: expected tolerance, nodeset, "
                           "symmetry or fix")
        except BadValue as bad:
            deck.error(line.number, str(bad))
    return draft


def _id_range(word: str) -> tuple[int, int]:
    match = re.fullmatch(r"([0-9]+)(?:-([0-9]+))?", word)
    if not match:
        raise BadValue(f"expected a node id or a range FIRST-LAST, got {show(word)}")
    first = int(match.group(1))
    last = int(match.group(2)) if match.group(2) else first
    if first < 1 or last < first:
        raise BadValue(f"expected a range FIRST-LAST with 1 <= FIRST <= LAST, got {show(word)}")
    return first, last



def _select(kind: str, args: list[str], mesh: HexMesh, tol: float) -> NDArray[np.int64]:
    x = mesh.nodes
    if kind == "box":
        b = np.array([float(v) for v in args]).reshape(3, 2)
        inside = ((x >= b[:, 0] - tol) & (x <= b[:, 1] + tol)).all(axis=1)
        return np.flatnonzero(inside)
    if kind == "plane":
        axis = AXES[args[0]]
        return np.flatnonzero(np.abs(x[:, axis] - float(args[1])) <= tol)
    parts = []
    total = 0
    for word in args:
        first, last = _id_range(word)
        total += last - first + 1
        if total > mesh.n_nodes:
            raise BadValue(f"the ids list more nodes than the mesh has ({mesh.n_nodes})")
        parts.append(np.arange(first, last + 1))
    ids = np.concatenate(parts)
    index = mesh.index(ids)
    if (index < 0).any():
        missing = ids[index < 0]
        raise BadValue(f"node {missing[0]} is not in the mesh"
                   + (f" (and {missing.size - 1} more ids)" if missing.size > 1 else ""))
    return index.astype(np.int64)
