"""A forming model read from an Abaqus / CalculiX input file (docs/abaqus-import.md): the
blank's hexahedra, its material, rigid tools with their surfaces, contact and friction,
symmetry and fixed nodes, and one phase per *STEP.

:func:`read_inp` reads and checks the file before anything is written or computed. What it
cannot map (a keyword, an element type, a parameter, a form of a data line) is refused with
its file and line and what is supported; keywords without mechanics (output requests, the
preprint) are accepted and listed in ``InpModel.ignored``. Every defect found is reported in
one :class:`ddpy.io.case.DeckError` (``.errors`` lists them all).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy.io.case import MAX_TRAVEL_EXTENTS, DeckError, longest_travel
from ddpy.io.inp_assembly import flatten_assembly
from ddpy.io.inp_cards import Card, DataLine, integer, read_cards
from ddpy.io.inp_mesh import ddpy_name
from ddpy.io.inp_read import BLANK_TYPES, TOOL_TYPES, Reader

__all__ = ["InpModel", "InpPhase", "InpTool", "ddpy_name", "read_inp"]

#: Faces S1..S6 of a hexahedron (corner nodes, from 1); by the right-hand rule their
#: normals point into the element.
HEX_FACES = ((1, 2, 3, 4), (5, 8, 7, 6), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 8, 4), (4, 8, 5, 1))

@dataclass
class InpTool:
    """A rigid tool: its faces (k, 4) node ids (-1 last for a triangle), the blank side it
    touches (the slave surface: 'top', 'bottom' or a facing direction), friction,
    discretization, its reference node and where it was defined."""

    name: str
    faces: list[list[int]]
    side: str
    facing: tuple[float, float, float] | None
    friction: float
    discretization: str
    ref_node: int
    where: str
    points: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    lines: list[int] = field(default_factory=list)
    source: Path | None = None


@dataclass
class InpPhase:
    """One *STEP: forming (tools, moves) or springback, its increment settings and the
    zero displacements it adds on the blank (node set name -> components)."""

    name: str
    kind: str
    tools: list[str]
    moves: dict[str, tuple[float, float, float]]
    max_fraction: float | None
    min_fraction: float | None
    increments: int
    where: str
    #: The *STEP it comes from (from 0): a step may make several phases.
    step: int = 0


@dataclass
class InpModel:
    """What :func:`read_inp` found, mapped to ddpy's terms (node and element ids kept)."""

    path: Path
    title: str
    nodes: dict[int, tuple[float, float, float]]
    elements: dict[int, list[int]]
    element_type: str
    normal: str
    elastic: tuple[float, float]
    hardening: list[tuple[float, float]]
    nodesets: dict[str, list[int]]
    #: (node set, components 'xyz' subset, phases: () for all) of the blank.
    constraints: list[tuple[str, str, tuple[str, ...]]]
    tools: list[InpTool]
    phases: list[InpPhase]
    ignored: list[str] = field(default_factory=list)
    #: The input file and the files it includes.
    sources: list[Path] = field(default_factory=list)

def _proportional(a: dict[str, NDArray[np.float64]], b: dict[str, NDArray[np.float64]]
                  ) -> bool:
    """Whether every tool's displacement in ``b`` is that in ``a`` times one factor > 0: the
    two stretches are one straight stretch of the phase."""
    scale = max(float(np.linalg.norm(v)) for v in a.values())
    lead = max(a, key=lambda n: float(np.linalg.norm(a[n])))
    factor = float(a[lead] @ b[lead]) / scale**2
    return factor > 0 and all(np.linalg.norm(b[n] - factor * a[n]) <= 1e-9 * scale * (
        1.0 + factor) for n in a)


class _Mapper:
    """Turns the definitions of a Reader into an InpModel, collecting errors."""

    def __init__(self, r: Reader) -> None:
        self.r = r

    def node_set(self, name: str, line: DataLine) -> list[int]:
        return self.r.node_set(name, line)

    def element_set(self, name: str, line: DataLine) -> list[int]:
        return self.r.element_set(name, line)

    def faces(self, name: str, line: DataLine) -> list[tuple[list[int], DataLine]]:
        """The faces of a *SURFACE as node id lists (as HEX_FACES for solids, SPOS for R3D)."""
        r = self.r
        if name not in r.surfaces:
            raise DeckError(f"no *SURFACE named {name}", line.path, line.number)
        found = []
        for item, face, at in r.surfaces[name][0]:
            for ident in self.element_set(item, at):
                if ident not in r.elements:
                    raise DeckError(f"element {ident} is not defined", at.path, at.number)
                kind, nodes, _ = r.elements[ident]
                if kind in TOOL_TYPES:
                    if face not in ("", "SPOS", "SNEG"):
                        raise DeckError(f"expected SPOS or SNEG for the {kind} element, got "
                                        f"'{face}'", at.path, at.number)
                    found.append((nodes[::-1] if face == "SNEG" else list(nodes), at))
                else:
                    match = re.fullmatch(r"S([1-6])", face)
                    if match is None:
                        raise DeckError(f"expected a face S1..S6 of the {kind} element, got "
                                        f"'{face}'", at.path, at.number)
                    found.append(([nodes[i - 1] for i in HEX_FACES[int(match[1]) - 1]], at))
        return found

    def model(self, path: Path) -> InpModel | None:
        r = self.r
        for ident, (_, nodes, line) in r.elements.items():
            for n in nodes:
                if n not in r.nodes:
                    r.fail(DeckError(f"node {n} of element {ident} is not defined", line.path,
                                     line.number))
                    break
        tool_elements, tool_nodes, refs = self.rigid_bodies()
        blank, material = self.blank(tool_elements)
        if r.errors or material is None:
            return None
        kinds = {r.elements[e][0] for e in blank}
        if len(kinds) > 1:
            first = r.sections[0][2]
            r.fail(first.error(f"the blank mixes element types {', '.join(sorted(kinds))}: "
                               "expected one of them"))
            return None
        coords = np.array([r.nodes[n][0] for e in blank for n in r.elements[e][1]])
        extent = coords.max(axis=0) - coords.min(axis=0)
        normal = "xyz"[int(np.argmin(extent))]
        if normal != "z":  # mesh.dat refuses it: the run takes the sheet normal along z
            r.fail(r.sections[0][2].error(f"the blank is thinnest along {normal}: ddpy takes "
                                          "the sheet normal along z only for now (expected "
                                          "the blank turned to lie in the x-y plane)"))
            return None
        blank_nodes = {n for e in blank for n in r.elements[e][1]}
        for kind, ids, line in r.stabilizers:
            if len(set(ids) & blank_nodes) > 1:
                r.fail(DeckError(f"a {kind} element between blank nodes "
                                 f"{', '.join(map(str, ids))}: it would carry load in the "
                                 "forming, and ddpy has no springs or dashpots (those skipped "
                                 "hold a blank node to the ground)", line.path, line.number))
        tools = self.tools(refs, tool_nodes, blank, normal)
        nodesets: dict[str, list[int]] = {}
        phases = self.phases(tools, refs, blank_nodes, nodesets)
        constraints = self.constraints(blank_nodes, nodesets, phases, refs)
        if r.errors or tools is None or phases is None:
            return None
        mat_name, mat_card = material
        if mat_name not in r.elastic:
            r.fail(mat_card.error(f"material {mat_name} has no *ELASTIC"))
        if mat_name not in r.plastic:
            r.fail(mat_card.error(f"material {mat_name} has no *PLASTIC: ddpy's blank is "
                                  "elastoplastic (give at least '<yield stress>, 0')"))
        if r.errors:
            return None
        return InpModel(path, r.title or path.stem, {n: r.nodes[n][0] for n in sorted(
            blank_nodes)}, {e: r.elements[e][1] for e in sorted(blank)}, kinds.pop(), normal,
            r.elastic[mat_name], r.plastic[mat_name], nodesets, constraints, tools, phases,
            r.ignored)

    def rigid_bodies(self) -> tuple[set[int], dict[int, set[int]], dict[int, tuple[int, int,
                                                                                   str, Card]]]:
        """Elements of the tools, each tool's nodes, and per tool (by its index) the
        reference node, the rotation node (0: none) and its name."""
        r = self.r
        elements: set[int] = set()
        nodes: dict[int, set[int]] = {}
        refs: dict[int, tuple[int, int, str, Card]] = {}
        for index, card in enumerate(r.rigid):
            line = DataLine(card.path, card.number, [])
            try:
                if "ELSET" in card.params:
                    name = card.params["ELSET"].upper()
                    members = self.element_set(name, line)
                    for e in members:
                        if e not in r.elements:
                            raise card.error(f"element {e} of {name} is not defined")
                        kind = r.elements[e][0]
                        if kind not in TOOL_TYPES + ("C3D8",):
                            raise card.error(f"element {e} of the rigid body is a {kind}: "
                                             "expected R3D4, R3D3 or C3D8")
                    elements.update(members)
                    nodes[index] = {n for e in members for n in r.elements[e][1]}
                else:
                    name = card.params["NSET"].upper()
                    nodes[index] = set(self.node_set(name, line))
                    # The elements on the set's nodes are the tool's.
                    elements.update(e for e, (kind, ns, _) in r.elements.items()
                                    if kind in TOOL_TYPES + ("C3D8",) and set(ns) <= nodes[index])
                ref = self._node_param(card, "REF NODE")
                rot = self._node_param(card, "ROT NODE") if "ROT NODE" in card.params else 0
                refs[index] = (ref, rot, ddpy_name(name, "tool"), card)
            except DeckError as error:
                r.fail(error)
        return elements, nodes, refs

    def _node_param(self, card: Card, key: str) -> int:
        value = card.params[key].upper()
        line = DataLine(card.path, card.number, [value])
        ids = self.node_set(value, line) if not value.isdigit() else [integer(line, 0, key)]
        if len(ids) != 1 or ids[0] not in self.r.nodes:
            raise card.error(f"{key}={value}: expected one defined node")
        return ids[0]

    def blank(self, tool_elements: set[int]) -> tuple[set[int], tuple[str, Card] | None]:
        r = self.r
        blank: set[int] = set()
        material: tuple[str, Card] | None = None
        for elset, name, card in r.sections:
            line = DataLine(card.path, card.number, [])
            try:
                members = set(self.element_set(elset, line))
            except DeckError as error:
                r.fail(error)
                continue
            if members <= tool_elements:
                r.ignored.append(f"{card.where}: *SOLID SECTION of rigid body elements")
                continue
            if members & tool_elements:
                r.fail(card.error(f"element set {elset} holds elements of a rigid body and of "
                                  "the blank: expected one or the other"))
                continue
            for e in sorted(members):
                if e not in r.elements:
                    r.fail(card.error(f"element {e} of {elset} is not defined"))
                    break
                if r.elements[e][0] not in BLANK_TYPES:
                    r.fail(card.error(f"element {e} of {elset} is a {r.elements[e][0]}: the "
                                      f"blank is made of {', '.join(BLANK_TYPES)}"))
                    break
            if name not in r.materials:
                r.fail(card.error(f"no *MATERIAL named {name}"))
            elif material is not None and material[0] != name:
                r.fail(card.error(f"a second material {name} for the blank (the first: "
                                  f"{material[0]}): ddpy's blank has one material"))
            else:
                material = (name, r.materials[name])
            blank |= members
        missing = [e for e, (kind, _, _) in r.elements.items()
                   if e not in blank and e not in tool_elements]
        if missing:
            kind, _, line = r.elements[missing[0]]
            r.fail(DeckError(f"element {missing[0]} ({kind}) belongs to no *SOLID SECTION and "
                             f"no *RIGID BODY ({len(missing)} such elements): expected the "
                             "blank's in a solid section, the tools' in a rigid body",
                             line.path, line.number))
        if not blank and not r.errors:
            r.fail(DeckError("no *SOLID SECTION: expected the blank's hexahedra in one",
                             r.path))
        return blank, material

    def tools(self, refs: dict[int, tuple[int, int, str, Card]],
              tool_nodes: dict[int, set[int]], blank: set[int], normal: str
              ) -> list[InpTool] | None:
        r = self.r
        axis = "xyz".index(normal)
        blank_nodes = {n for e in blank for n in r.elements[e][1]}
        found: dict[int, InpTool] = {}
        for pair in r.pairs:
            line = DataLine(pair.card.path, pair.card.number, [])
            try:
                slave = self.faces(pair.slave, line)
                master = self.faces(pair.master, line)
            except DeckError as error:
                r.fail(error)
                continue
            if not slave or not master:
                r.fail(pair.card.error(f"surface {pair.slave if not slave else pair.master} "
                                       "has no faces"))
                continue
            if any(not set(f) <= blank_nodes for f, _ in slave):
                r.fail(pair.card.error(f"the slave surface {pair.slave} is not on the blank: "
                                       "expected '<blank surface>, <tool surface>'"))
                continue
            master_nodes = {n for f, _ in master for n in f}
            owner = [i for i, ns in tool_nodes.items() if master_nodes <= ns]
            if not owner:
                r.fail(pair.card.error(f"the master surface {pair.master} is not on a *RIGID "
                                       "BODY: ddpy's tools are rigid bodies"))
                continue
            index = owner[0]
            if index in found:
                r.fail(pair.card.error(f"a second contact pair on the tool of "
                                       f"{refs[index][3].where}: expected one pair per tool"))
                continue
            if pair.interaction not in r.interactions:
                r.fail(pair.card.error(f"no *SURFACE INTERACTION named {pair.interaction}"))
                continue
            normals = []
            for f, _ in slave:
                x = np.array([r.nodes[n][0] for n in f])
                normals.append(np.cross(x[3] - x[1], x[2] - x[0]))  # S1..S6 turn inwards
            mean = np.sum(normals, axis=0)
            mean = mean / max(float(np.linalg.norm(mean)), 1e-300)
            if mean[axis] > 0.9:
                contact, facing = "top", None
            elif mean[axis] < -0.9:
                contact, facing = "bottom", None
            else:
                contact, facing = "facing", tuple(float(round(v, 6)) for v in mean)
            ref, _, name, card = refs[index]
            found[index] = InpTool(
                name, [f + [-1] * (4 - len(f)) for f, _ in master], contact, facing,
                r.friction.get(pair.interaction, 0.0),
                "surface" if pair.kind == "SURFACE TO SURFACE" else "node", ref, card.where,
                {n: r.nodes[n][0] for f, _ in master for n in f}, [at.number for _, at in master],
                master[0][1].path)
        for index, (_, _, name, card) in refs.items():
            if index not in found:
                r.fail(card.error(f"the rigid body {name} is in no *CONTACT PAIR (as its "
                                  "master surface): a tool must touch the blank"))
        return [found[i] for i in sorted(found)]

    def phases(self, tools: list[InpTool] | None, refs: dict[int, tuple[int, int, str, Card]],
               blank_nodes: set[int], nodesets: dict[str, list[int]]) -> list[InpPhase] | None:
        """One phase per step, or one per stretch of a step in which every tool moves in a
        straight line at proportional speeds (a step whose motions follow *AMPLITUDE tables
        that bend the path or change the tools' relative speeds)."""
        r = self.r
        if not r.steps:
            r.fail(DeckError("no *STEP: expected at least one step moving a tool", r.path))
            return None
        if tools is None:
            return None
        by_ref = {t.ref_node: t for t in tools}
        rot_of = {rot: refs[i][0] for i, (_, rot, _, _) in refs.items() if rot}
        pair_tool = {}
        # Which tool a contact pair drives: the one whose faces its master names.
        for pair in r.pairs:
            try:
                master = {n for f, _ in self.faces(pair.master, DataLine(
                    pair.card.path, pair.card.number, [])) for n in f}
            except DeckError:
                continue
            for t in tools:
                if master <= {n for f in t.faces for n in f if n >= 0}:
                    pair_tool[(pair.slave, pair.master)] = t.name
        spring_nodes = {n for _, ns, _ in r.stabilizers for n in ns} - blank_nodes
        position: dict[str, list[float | None]] = {t.name: [None, None, None] for t in tools}
        low, high = self._model_box(tools, blank_nodes)
        active = {t.name for t in tools}
        phases: list[InpPhase] = []
        names: set[str] = set()
        if r.steps[0].params.get("NLGEOM", None) not in ("", "YES"):
            r.fail(r.steps[0].error("the first *STEP without NLGEOM: ddpy's forming is "
                                    "geometrically nonlinear, expected *STEP, NLGEOM"))
        start_time = 0.0                       # total time at the start of the step
        for step, card in enumerate([None, *r.steps]):
            index = step - 1
            before = {k: list(v) for k, v in position.items()}
            # Per tool and dof: the value, its amplitude ('' for a ramp) and its line.
            given: dict[str, dict[int, tuple[float, str, DataLine]]] = {t.name: {}
                                                                         for t in tools}
            for bc in [b for b in r.bcs if b.step == (None if card is None else index)]:
                try:
                    ids = self.node_set(bc.node_or_set, bc.line)
                except DeckError as error:
                    r.fail(error)
                    continue
                for node in ids:
                    tool = by_ref.get(node) or by_ref.get(rot_of.get(node, -1))
                    rotation = node in rot_of
                    if tool is None:
                        if node in spring_nodes:
                            note = f"{bc.line.where}: *BOUNDARY on {bc.node_or_set}: on the " \
                                "nodes of skipped springs or dashpots"
                            if note not in r.ignored:
                                r.ignored.append(note)
                            continue
                        if node not in blank_nodes:
                            r.fail(DeckError(f"node {node} of the *BOUNDARY is neither a node "
                                             "of the blank nor a tool's REF NODE or ROT NODE",
                                             bc.line.path, bc.line.number))
                            break
                        continue
                    for dof in bc.dofs:
                        if rotation or dof > 3:
                            if bc.value != 0.0:
                                r.fail(DeckError(f"a rotation of tool {tool.name} ({bc.value:g}"
                                                 "): ddpy's tools translate only", bc.line.path,
                                                 bc.line.number))
                            continue
                        held = before[tool.name][dof - 1] or 0.0
                        given[tool.name][dof - 1] = (held, "", bc.line) if bc.fixed else \
                            (bc.value, bc.amplitude, bc.line)
            if card is None:
                for tool_name, dofs in given.items():
                    for dof, (value, _, _) in dofs.items():
                        position[tool_name][dof] = value
                continue
            name = ddpy_name(card.params.get("NAME", f"step{step}").strip('"'), "step")
            if name in names:
                name = f"{name}_{step}"
            names.add(name)
            removed, added = r.removed.get(index, (set(), set()))
            for pair in removed:
                active.discard(pair_tool.get(pair, ""))
            for pair in added:
                active.add(pair_tool.get(pair, ""))
            active.discard("")
            static = r.static.get(index, ())
            period = static[1] if len(static) > 1 else 1.0
            for t in tools:
                for dof, (value, amplitude, _) in given[t.name].items():
                    position[t.name][dof] = value * self._amplitude(
                        amplitude, period, start_time) if amplitude else value
            step_start = start_time
            start_time += period
            if not active:
                increments = max(1, min(1000, round(period / static[0]))) if static else 1
                phases.append(InpPhase(name, "springback", [], {}, None, None, increments,
                                       card.where, index))
                continue
            for t in tools:
                if t.name in active and None in position[t.name]:
                    free = ", ".join(str(i + 1) for i, v in enumerate(position[t.name])
                                     if v is None)
                    r.fail(card.error(f"tool {t.name} (REF NODE {t.ref_node}) has no *BOUNDARY "
                                      f"on dof {free} in this step: ddpy's tools move as "
                                      "prescribed, give all three translations"))
            segments = self._segments(tools, given, before, period, step_start)
            if segments is None:
                continue
            if not segments:
                r.fail(card.error("the step moves no tool: a forming step must move one (the "
                                  "tools drive ddpy's phases), or remove every contact pair "
                                  "(*MODEL CHANGE, TYPE=CONTACT PAIR, REMOVE: springback)"))
                continue
            for k, (t0, t1, deltas) in enumerate(segments):
                moves: dict[str, tuple[float, float, float]] = {}
                for t in tools:
                    delta = deltas[t.name]
                    if not np.any(delta):
                        continue
                    lines = [at for _, _, at in given[t.name].values()]
                    if t.name not in active:
                        r.fail(card.error(f"tool {t.name} moves in a step where its contact "
                                          "pair is removed: ddpy moves active tools only"))
                    moves[t.name] = tuple(float(v) for v in delta)  # type: ignore[assignment]
                    longest = longest_travel(delta, low, high)
                    travel = float(np.linalg.norm(delta))
                    if travel > longest and lines:
                        r.fail(DeckError(
                            f"tool {t.name} moves {travel:.4g} mm in this step, more than "
                            f"{MAX_TRAVEL_EXTENTS:g} times the extent of the model (the "
                            "blank and the tools) along its motion: expected at most "
                            f"{longest:.4g} mm", lines[-1].path, lines[-1].number))
                duration = t1 - t0
                max_fraction = static[3] / duration if len(static) > 3 else None
                min_fraction = static[2] / duration if len(static) > 2 else None
                label = name if len(segments) == 1 else f"{name}_{k + 1}"
                where = card.where if len(segments) == 1 else \
                    f"{card.where}, step time {t0:g} to {t1:g}"
                phases.append(InpPhase(label, "forming",
                                       [t.name for t in tools if t.name in active], moves,
                                       max_fraction, min_fraction, 1, where, index))
        if phases and phases[0].kind == "springback":
            r.fail(r.steps[0].error("the first step removes every contact pair: the first "
                                    "phase must form"))
        return phases

    def _amplitude(self, name: str, time: float, start: float) -> float:
        """The value of an amplitude at step time ``time`` of a step starting at ``start``."""
        amplitude = self.r.amplitudes[name]
        return amplitude.at(time + start if amplitude.total_time else time)

    def _segments(self, tools: list[InpTool],
                  given: dict[str, dict[int, tuple[float, str, DataLine]]],
                  before: dict[str, list[float | None]], period: float, start: float
                  ) -> list[tuple[float, float, dict[str, NDArray[np.float64]]]] | None:
        """The step's path as straight stretches (step time from, to, each tool's
        displacement); a ramp moves a tool from where it was, an amplitude a(t) puts it at
        a(t) x value (as Abaqus). None after an error."""
        r = self.r
        times = {0.0, period}
        for dofs in given.values():
            for _, amplitude, _ in dofs.values():
                if amplitude:
                    shift = start if r.amplitudes[amplitude].total_time else 0.0
                    times |= {t - shift for t, _ in r.amplitudes[amplitude].points
                              if 0.0 < t - shift < period}
        ordered = sorted(times)

        def at(tool: str, dof: int, time: float) -> float:
            was = before[tool][dof] or 0.0
            if dof not in given[tool]:
                return was
            value, amplitude, _ = given[tool][dof]
            if amplitude:
                return value * self._amplitude(amplitude, time, start)
            return was + (value - was) * time / period

        ok = True
        for t in tools:
            for dof, (_, amplitude, line) in given[t.name].items():
                was, first = before[t.name][dof] or 0.0, at(t.name, dof, 0.0)
                if amplitude and abs(first - was) > 1e-9 * (1.0 + abs(was)):
                    r.fail(DeckError(
                        f"AMPLITUDE={amplitude} puts tool {t.name} at {first:g} mm along "
                        f"{'xyz'[dof]} at the start of the step, where it is at {was:g} mm: "
                        "expected the amplitude to start from the tool's position (ddpy's "
                        "tools do not jump)", line.path, line.number))
                    ok = False
        if not ok:
            return None
        points = [{t.name: np.array([at(t.name, d, time) for d in range(3)]) for t in tools}
                  for time in ordered]
        segments: list[tuple[float, float, dict[str, NDArray[np.float64]]]] = []
        for k in range(len(ordered) - 1):
            deltas = {n: points[k + 1][n] - points[k][n] for n in points[k]}
            if not any(np.any(d) for d in deltas.values()):
                continue                        # a dwell: nothing moves, nothing to do
            if segments and _proportional(segments[-1][2], deltas):
                t0, _, previous = segments[-1]
                segments[-1] = (t0, ordered[k + 1],
                                {n: previous[n] + deltas[n] for n in deltas})
            else:
                segments.append((ordered[k], ordered[k + 1], deltas))
        return segments

    def _model_box(self, tools: list[InpTool], blank_nodes: set[int]
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The box around the blank and the tools' surfaces where they start."""
        points = np.array([self.r.nodes[n][0] for n in blank_nodes]
                          + [x for t in tools for x in t.points.values()])
        return points.min(axis=0), points.max(axis=0)

    def constraints(self, blank_nodes: set[int], nodesets: dict[str, list[int]],
                    phases: list[InpPhase] | None, refs: dict[int, tuple[int, int, str, Card]]
                    ) -> list[tuple[str, str, tuple[str, ...]]]:
        """Zero displacements of blank nodes: model-level ones in every phase, a step's from
        its phase on (as Abaqus keeps them)."""
        r = self.r
        result = []
        for bc in r.bcs:
            try:
                ids = [n for n in self.node_set(bc.node_or_set, bc.line) if n in blank_nodes]
            except DeckError:
                continue
            if not ids:
                continue
            components = "".join("xyz"[d - 1] for d in bc.dofs if d <= 3)
            if any(d > 3 for d in bc.dofs):
                r.ignored.append(f"{bc.line.where}: rotations of blank nodes (solid elements "
                                 "have none)")
            if not components:
                continue
            if bc.value != 0.0:
                r.fail(DeckError(f"a displacement of {bc.value:g} on blank nodes: ddpy's "
                                 "constraints on the blank are zero displacements (the tools "
                                 "drive the forming)", bc.line.path, bc.line.number))
                continue
            if bc.step is not None and bc.step > 0 and not bc.fixed:
                r.fail(DeckError("a zero displacement of blank nodes given after the first "
                                 "step: Abaqus and CalculiX take it as a total displacement "
                                 "(moving the nodes back to where they started), ddpy holds "
                                 "nodes where they are: expected *BOUNDARY, FIXED", bc.line.path,
                                 bc.line.number))
                continue
            label = ddpy_name(bc.node_or_set, "node")
            nodesets[label] = sorted(set(ids))
            steps = () if bc.step is None else tuple(p.name for p in phases or []
                                                     if p.step >= bc.step)
            result.append((label, components, steps))
        return result


def read_inp(path: str | Path) -> InpModel:
    """Read and check an Abaqus / CalculiX forming model; DeckError lists every defect."""
    path = Path(path)
    cards = read_cards(path)
    flat, _, errors = flatten_assembly(cards)
    reader = Reader(path)
    reader.errors += errors
    reader.read(flat)
    model = _Mapper(reader).model(path)
    if model is not None:
        model.sources = sorted({card.path for card in cards})
    if reader.errors or model is None:
        raise DeckError.collect(reader.errors or [DeckError("invalid model", path)])
    return model
