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

from ddpy.io.case import DeckError
from ddpy.io.inp_cards import Card, DataLine, integer, number, read_cards

__all__ = ["BLANK_TYPES", "IGNORED", "SUPPORTED", "TOOL_TYPES", "InpModel", "InpPhase",
           "InpTool", "read_inp"]

#: Element types of the blank, and of rigid tools (besides bricks of a *RIGID BODY).
BLANK_TYPES = ("C3D8", "C3D8R", "C3D8I")
TOOL_TYPES = ("R3D4", "R3D3")
#: Keywords read, and their parameters (a value of None: any value, else the values allowed).
SUPPORTED: dict[str, dict[str, tuple[str, ...] | None]] = {
    "HEADING": {},
    "NODE": {"NSET": None},
    "ELEMENT": {"TYPE": None, "ELSET": None},
    "NSET": {"NSET": None, "GENERATE": ("",)},
    "ELSET": {"ELSET": None, "GENERATE": ("",)},
    "MATERIAL": {"NAME": None},
    "ELASTIC": {"TYPE": ("ISOTROPIC",)},
    "PLASTIC": {"HARDENING": ("ISOTROPIC",)},
    "SOLID SECTION": {"ELSET": None, "MATERIAL": None},
    "RIGID BODY": {"ELSET": None, "NSET": None, "REF NODE": None, "ROT NODE": None},
    "SURFACE": {"NAME": None, "TYPE": ("ELEMENT",)},
    "CONTACT PAIR": {"INTERACTION": None, "TYPE": ("SURFACE TO SURFACE", "NODE TO SURFACE")},
    "SURFACE INTERACTION": {"NAME": None},
    "SURFACE BEHAVIOR": {"PRESSURE-OVERCLOSURE": ("HARD", "LINEAR")},
    "FRICTION": {},
    "BOUNDARY": {"OP": ("MOD",), "TYPE": ("DISPLACEMENT",), "FIXED": ("", "YES")},
    "STEP": {"NAME": None, "NLGEOM": ("", "YES"), "INC": None},
    "STATIC": {},
    "MODEL CHANGE": {"TYPE": ("CONTACT PAIR",), "REMOVE": ("",), "ADD": ("",)},
    "END STEP": {},
}
#: Keywords accepted and ignored: they request output or change no mechanics (density:
#: ddpy's forming is quasi-static, without inertia).
IGNORED = ("PREPRINT", "NODE PRINT", "EL PRINT", "NODE FILE", "EL FILE", "OUTPUT",
           "NODE OUTPUT", "ELEMENT OUTPUT", "CONTACT OUTPUT", "CONTACT PRINT", "CONTACT FILE",
           "RESTART", "MONITOR", "DENSITY")
#: Faces S1..S6 of a hexahedron (corner nodes, from 1); by the right-hand rule their
#: normals point into the element.
HEX_FACES = ((1, 2, 3, 4), (5, 8, 7, 6), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 8, 4), (4, 8, 5, 1))
#: Degrees of freedom of the *BOUNDARY types.
BOUNDARY_TYPES = {"XSYMM": (1, 5, 6), "YSYMM": (2, 4, 6), "ZSYMM": (3, 4, 5),
                  "ENCASTRE": (1, 2, 3, 4, 5, 6), "PINNED": (1, 2, 3)}
_NAME = re.compile(r"[^A-Za-z0-9_.\-]")


def ddpy_name(name: str, prefix: str = "s") -> str:
    """An Abaqus name as a ddpy name (lower case, other characters '_', a letter first)."""
    text = _NAME.sub("_", name).lower()[:64]
    return text if text[:1].isalpha() else f"{prefix}_{text}"[:64]


@dataclass
class InpTool:
    """A rigid tool: its faces (k, 4) node ids (-1 last for a triangle), the blank side it
    touches (the slave surface: 'top', 'bottom' or a facing direction), friction,
    discretization, its reference node and where it was defined."""

    name: str
    faces: list[list[int]]
    contact: str
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


@dataclass
class _Pair:
    slave: str
    master: str
    interaction: str
    kind: str
    card: Card


@dataclass
class _Bc:
    node_or_set: str
    dofs: tuple[int, ...]
    value: float
    step: int | None
    line: DataLine
    fixed: bool = False


class _Reader:
    """Walks the cards once, recording definitions; then maps them, collecting errors."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.errors: list[DeckError] = []
        self.ignored: list[str] = []
        self.title = ""
        self.nodes: dict[int, tuple[tuple[float, float, float], DataLine]] = {}
        self.elements: dict[int, tuple[str, list[int], DataLine]] = {}
        self.nsets: dict[str, list[tuple[str, DataLine]]] = {}
        self.elsets: dict[str, list[tuple[str, DataLine]]] = {}
        self.materials: dict[str, Card] = {}
        self.elastic: dict[str, tuple[float, float]] = {}
        self.plastic: dict[str, list[tuple[float, float]]] = {}
        self.sections: list[tuple[str, str, Card]] = []
        self.rigid: list[Card] = []
        self.surfaces: dict[str, tuple[list[tuple[str, str, DataLine]], Card]] = {}
        self.pairs: list[_Pair] = []
        self.interactions: dict[str, Card] = {}
        self.friction: dict[str, float] = {}
        self.bcs: list[_Bc] = []
        self.steps: list[Card] = []
        self.static: dict[int, tuple[float, ...]] = {}
        self.removed: dict[int, tuple[set[tuple[str, str]], set[tuple[str, str]]]] = {}

    # ----------------------------------------------------------------------- reading cards

    def fail(self, error: DeckError) -> None:
        self.errors.append(error)

    def read(self, cards: list[Card]) -> None:
        material = interaction = ""
        step: int | None = None
        for card in cards:
            key = card.keyword
            if key in IGNORED:
                self.ignored.append(f"{card.where}: *{key}")
                continue
            if key not in SUPPORTED:
                self.fail(card.error(f"keyword *{key} is not supported: expected one of "
                                     + ", ".join(f"*{k}" for k in (*SUPPORTED, "INCLUDE"))
                                     + " (or, ignored, " + ", ".join(f"*{k}" for k in IGNORED)
                                     + "); see docs/abaqus-import.md"))
                continue
            if not self._params(card) and key not in ("STEP", "END STEP"):
                continue                # a step is still opened: no errors follow from it
            try:
                if key == "STEP":
                    if step is not None:
                        raise card.error("*STEP inside a step: expected *END STEP first")
                    self.steps.append(card)
                    step = len(self.steps) - 1
                    self._no_data(card)
                elif key == "END STEP":
                    if step is None:
                        raise card.error("*END STEP outside a step")
                    step = None
                elif key in ("STATIC", "MODEL CHANGE") and step is None:
                    raise card.error(f"*{key} outside a step: expected it after *STEP")
                elif step is not None and key not in ("STATIC", "MODEL CHANGE", "BOUNDARY"):
                    raise card.error(f"*{key} inside a step: in a step ddpy reads *STATIC, "
                                     "*BOUNDARY and *MODEL CHANGE; define the model before "
                                     "the first *STEP")
                elif key == "MATERIAL":
                    material = self._name(card, "NAME")
                    self.materials[material] = card
                    self._no_data(card)
                elif key in ("ELASTIC", "PLASTIC") and not material:
                    raise card.error(f"*{key} outside a *MATERIAL")
                elif key in ("FRICTION", "SURFACE BEHAVIOR") and not interaction:
                    raise card.error(f"*{key} outside a *SURFACE INTERACTION")
                elif key == "SURFACE INTERACTION":
                    interaction = self._name(card, "NAME")
                    self.interactions[interaction] = card
                    self._no_data(card)
                else:
                    getattr(self, "_" + key.lower().replace(" ", "_"))(card, material,
                                                                       interaction, step)
            except DeckError as error:
                self.fail(error)
            if key not in ("ELASTIC", "PLASTIC", "MATERIAL"):
                material = ""
            if key not in ("FRICTION", "SURFACE BEHAVIOR", "SURFACE INTERACTION"):
                interaction = ""
        if step is not None:
            self.fail(self.steps[step].error("the step has no *END STEP"))

    def _params(self, card: Card) -> bool:
        allowed = SUPPORTED[card.keyword]
        for key, value in card.params.items():
            if key not in allowed:
                known = ", ".join(allowed) or "none"
                self.fail(card.error(f"parameter {key} of *{card.keyword} is not supported "
                                     f"(supported: {known})"))
                return False
            choices = allowed[key]
            if choices is not None and value.upper() not in choices:
                shown = ", ".join(f"{key}={c}" if c else key for c in choices)
                self.fail(card.error(f"{key}={value} of *{card.keyword} is not supported "
                                     f"(supported: {shown})"))
                return False
        return True

    @staticmethod
    def _name(card: Card, key: str) -> str:
        name = card.params.get(key, "").strip('"').upper()
        if not name:
            raise card.error(f"*{card.keyword} without {key}=<name>")
        return name

    @staticmethod
    def _no_data(card: Card) -> None:
        if card.data:
            raise card.error(f"*{card.keyword} takes no data lines, got "
                             f"'{', '.join(card.data[0].words)[:60]}'", card.data[0])

    def _heading(self, card: Card, *_: object) -> None:
        self.title = " ".join(", ".join(d.words) for d in card.data[:1])

    def _node(self, card: Card, *_: object) -> None:
        nset = card.params.get("NSET", "").upper()
        for line in card.data:
            try:
                ident = integer(line, 0, "the node id")
                if not 3 <= len(line.words) <= 4:
                    raise DeckError(f"expected '<node id>, <x>, <y>, <z>', got "
                                    f"'{', '.join(line.words)[:60]}'", line.path, line.number)
                xyz = tuple(number(line, i, "a coordinate") if i < len(line.words) else 0.0
                            for i in (1, 2, 3))
                if ident in self.nodes:
                    raise DeckError(f"node {ident} is defined again (first at "
                                    f"{self.nodes[ident][1].where})", line.path, line.number)
                self.nodes[ident] = (xyz, line)  # type: ignore[assignment]
                if nset:
                    self.nsets.setdefault(nset, []).append((str(ident), line))
            except DeckError as error:
                self.fail(error)

    def _element(self, card: Card, *_: object) -> None:
        kind = card.params.get("TYPE", "").upper()
        if kind not in BLANK_TYPES + TOOL_TYPES + ("C3D8",):
            raise card.error(f"element type {kind or '(none)'} is not supported: expected "
                             f"TYPE= {', '.join(BLANK_TYPES)} (the blank, and bricks of a "
                             f"*RIGID BODY) or {', '.join(TOOL_TYPES)} (rigid tools)")
        count = {"R3D4": 4, "R3D3": 3}.get(kind, 8)
        elset = card.params.get("ELSET", "").upper()
        for line in card.data:
            try:
                ident = integer(line, 0, "the element id")
                if len(line.words) != count + 1:
                    raise DeckError(f"expected '<element id>, <{count} node ids>' for a {kind} "
                                    f"element, got {len(line.words) - 1} nodes", line.path,
                                    line.number)
                nodes = [integer(line, i, "a node id") for i in range(1, count + 1)]
                if ident in self.elements:
                    raise DeckError(f"element {ident} is defined again (first at "
                                    f"{self.elements[ident][2].where})", line.path, line.number)
                self.elements[ident] = (kind, nodes, line)
                if elset:
                    self.elsets.setdefault(elset, []).append((str(ident), line))
            except DeckError as error:
                self.fail(error)

    def _set(self, card: Card, sets: dict[str, list[tuple[str, DataLine]]], key: str) -> None:
        name = self._name(card, key)
        items = sets.setdefault(name, [])
        for line in card.data:
            if "GENERATE" in card.params:
                if not 2 <= len(line.words) <= 3:
                    raise DeckError("expected '<first>, <last>[, <step>]' (GENERATE)",
                                    line.path, line.number)
                first, last = integer(line, 0, "the first id"), integer(line, 1, "the last id")
                inc = integer(line, 2, "the step") if len(line.words) == 3 else 1
                if last < first:
                    raise DeckError(f"GENERATE from {first} to {last}: the last id is below "
                                    "the first", line.path, line.number)
                items += [(str(i), line) for i in range(first, last + 1, inc)]
            else:
                items += [(w.upper(), line) for w in line.words if w]

    def _nset(self, card: Card, *_: object) -> None:
        self._set(card, self.nsets, "NSET")

    def _elset(self, card: Card, *_: object) -> None:
        self._set(card, self.elsets, "ELSET")

    def _elastic(self, card: Card, material: str, *_: object) -> None:
        if len(card.data) != 1 or len(card.data[0].words) != 2:
            raise card.error("expected one data line 'E, nu' (no temperature dependence)",
                             card.data[0] if card.data else None)
        line = card.data[0]
        self.elastic[material] = (number(line, 0, "Young's modulus E"),
                                  number(line, 1, "Poisson's ratio nu"))

    def _plastic(self, card: Card, material: str, *_: object) -> None:
        if not card.data:
            raise card.error("expected data lines 'yield stress, plastic strain'")
        table = []
        for line in card.data:
            if len(line.words) != 2:
                raise DeckError("expected 'yield stress, plastic strain' (no temperature "
                                f"dependence), got '{', '.join(line.words)[:60]}'", line.path,
                                line.number)
            y, ep = number(line, 0, "the yield stress"), number(line, 1, "the plastic strain")
            if table and ep <= table[-1][0]:
                raise DeckError(f"plastic strain {line.words[1]} is not above the one before "
                                f"({table[-1][0]:g}): expected increasing strains", line.path,
                                line.number)
            if not table and ep != 0.0:
                raise DeckError(f"the first plastic strain must be 0 (the initial yield "
                                f"stress), got {line.words[1]}", line.path, line.number)
            if table and y < table[-1][1]:
                raise DeckError(f"yield stress {line.words[0]} is below the one before "
                                f"({table[-1][1]:g}): softening is not supported", line.path,
                                line.number)
            if y <= 0:
                raise DeckError(f"the yield stress must be positive, got {line.words[0]}",
                                line.path, line.number)
            table.append((ep, y))
        self.plastic[material] = table

    def _solid_section(self, card: Card, *_: object) -> None:
        self._no_data(card)
        self.sections.append((self._name(card, "ELSET"), self._name(card, "MATERIAL"), card))

    def _rigid_body(self, card: Card, *_: object) -> None:
        self._no_data(card)
        if ("ELSET" in card.params) == ("NSET" in card.params):
            raise card.error("expected one of ELSET=<tool elements> or NSET=<tool nodes>")
        if not card.params.get("REF NODE"):
            raise card.error("expected REF NODE=<node id>: the tool's motion is that of its "
                             "reference node")
        self.rigid.append(card)

    def _surface(self, card: Card, *_: object) -> None:
        name = self._name(card, "NAME")
        items = []
        for line in card.data:
            if not 1 <= len(line.words) <= 2:
                raise DeckError("expected '<element or element set>[, <face>]'", line.path,
                                line.number)
            face = line.words[1].upper() if len(line.words) == 2 else ""
            items.append((line.words[0].upper(), face, line))
        self.surfaces[name] = (items, card)

    def _contact_pair(self, card: Card, *_: object) -> None:
        interaction = self._name(card, "INTERACTION")
        kind = card.params.get("TYPE", "NODE TO SURFACE").upper()
        for line in card.data:
            if len(line.words) != 2:
                raise DeckError("expected '<slave surface>, <master surface>'", line.path,
                                line.number)
            self.pairs.append(_Pair(line.words[0].upper(), line.words[1].upper(), interaction,
                                    kind, card))

    def _surface_behavior(self, card: Card, *_: object) -> None:
        if card.data:
            self.ignored.append(f"{card.data[0].where}: *SURFACE BEHAVIOR values (ddpy "
                                "enforces contact exactly, by an augmented Lagrangian: the "
                                "penalty stiffness is not used)")

    def _friction(self, card: Card, material: str, interaction: str, *_: object) -> None:
        if len(card.data) != 1 or not 1 <= len(card.data[0].words) <= 2:
            raise card.error("expected one data line 'mu[, stick slope]'",
                             card.data[0] if card.data else None)
        line = card.data[0]
        mu = number(line, 0, "the friction coefficient")
        if mu < 0:
            raise DeckError(f"the friction coefficient must be >= 0, got {line.words[0]}",
                            line.path, line.number)
        self.friction[interaction] = mu
        if len(line.words) == 2:
            self.ignored.append(f"{line.where}: the stick slope of *FRICTION (ddpy's Coulomb "
                                "friction sticks exactly)")

    def _boundary(self, card: Card, material: str, interaction: str, step: int | None) -> None:
        fixed = "FIXED" in card.params
        for line in card.data:
            target = line.words[0].upper() if line.words else ""
            if len(line.words) == 2 and line.words[1].upper() in BOUNDARY_TYPES:
                self.bcs.append(_Bc(target, BOUNDARY_TYPES[line.words[1].upper()], 0.0, step,
                                    line, fixed))
                continue
            if not 2 <= len(line.words) <= 4:
                raise DeckError("expected '<node or node set>, <first dof>[, <last dof>[, "
                                "<value>]]' or '<node or node set>, XSYMM|YSYMM|ZSYMM|"
                                "ENCASTRE|PINNED'", line.path, line.number)
            first = integer(line, 1, "the first degree of freedom")
            last = integer(line, 2, "the last degree of freedom") if len(line.words) > 2 \
                and line.words[2] else first
            if not 1 <= first <= last <= 6:
                raise DeckError(f"degrees of freedom {first} to {last}: expected 1 <= first "
                                "<= last <= 6", line.path, line.number)
            value = number(line, 3, "the displacement") if len(line.words) == 4 else 0.0
            if fixed and len(line.words) == 4:
                raise DeckError("*BOUNDARY, FIXED holds the nodes where they are: expected no "
                                "value", line.path, line.number)
            self.bcs.append(_Bc(target, tuple(range(first, last + 1)), value, step, line,
                                fixed))

    def _static(self, card: Card, material: str, interaction: str, step: int | None) -> None:
        assert step is not None
        if len(card.data) > 1 or (card.data and len(card.data[0].words) > 4):
            raise card.error("expected at most one data line 'initial, period[, min[, max]]'")
        values = tuple(number(card.data[0], i, "a time increment")
                       for i in range(len(card.data[0].words))) if card.data else ()
        if any(v <= 0 for v in values):
            raise card.error("*STATIC's time increments and period must be positive",
                             card.data[0])
        self.static[step] = values

    def _model_change(self, card: Card, material: str, interaction: str,
                      step: int | None) -> None:
        assert step is not None
        if ("REMOVE" in card.params) == ("ADD" in card.params):
            raise card.error("expected one of REMOVE or ADD")
        if card.params.get("TYPE", "").upper() != "CONTACT PAIR":
            raise card.error("expected TYPE=CONTACT PAIR (ddpy switches tools on and off)")
        removed, added = self.removed.setdefault(step, (set(), set()))
        for line in card.data:
            if len(line.words) != 2:
                raise DeckError("expected '<slave surface>, <master surface>'", line.path,
                                line.number)
            pair = (line.words[0].upper(), line.words[1].upper())
            (removed if "REMOVE" in card.params else added).add(pair)
            known = {(p.slave, p.master) for p in self.pairs}
            if pair not in known:
                raise DeckError(f"no *CONTACT PAIR {pair[0]}, {pair[1]}", line.path,
                                line.number)


class _Mapper:
    """Turns the definitions of a _Reader into an InpModel, collecting errors."""

    def __init__(self, r: _Reader) -> None:
        self.r = r

    def node_set(self, name: str, line: DataLine, seen: tuple[str, ...] = ()) -> list[int]:
        r = self.r
        if name.isdigit():
            return [int(name)]
        if name not in r.nsets or name in seen:
            raise DeckError(f"no node set named {name}", line.path, line.number)
        ids: list[int] = []
        for item, at in r.nsets[name]:
            ids += self.node_set(item, at, (*seen, name))
        return ids

    def element_set(self, name: str, line: DataLine, seen: tuple[str, ...] = ()) -> list[int]:
        r = self.r
        if name.isdigit():
            return [int(name)]
        if name not in r.elsets or name in seen:
            raise DeckError(f"no element set named {name}", line.path, line.number)
        ids: list[int] = []
        for item, at in r.elsets[name]:
            ids += self.element_set(item, at, (*seen, name))
        return ids

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
        blank_nodes = {n for e in blank for n in r.elements[e][1]}
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
        position = {t.name: [None, None, None] for t in tools}   # prescribed totals
        active = {t.name for t in tools}
        phases = []
        names: set[str] = set()
        if r.steps[0].params.get("NLGEOM", None) not in ("", "YES"):
            r.fail(r.steps[0].error("the first *STEP without NLGEOM: ddpy's forming is "
                                    "geometrically nonlinear, expected *STEP, NLGEOM"))
        for step, card in enumerate([None, *r.steps]):
            index = step - 1
            before = {k: list(v) for k, v in position.items()}
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
                        if bc.fixed:
                            position[tool.name][dof - 1] = before[tool.name][dof - 1] or 0.0
                        else:
                            position[tool.name][dof - 1] = bc.value
            if card is None:
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
            moves = {}
            for t in tools:
                now, old = position[t.name], before[t.name]
                if t.name in active and None in now:
                    free = ", ".join(str(i + 1) for i, v in enumerate(now) if v is None)
                    r.fail(card.error(f"tool {t.name} (REF NODE {t.ref_node}) has no *BOUNDARY "
                                      f"on dof {free} in this step: ddpy's tools move as "
                                      "prescribed, give all three translations"))
                    continue
                delta = tuple((a or 0.0) - (b or 0.0) for a, b in zip(now, old, strict=True))
                if any(delta):
                    if t.name not in active:
                        r.fail(card.error(f"tool {t.name} moves in a step where its contact "
                                          "pair is removed: ddpy moves active tools only"))
                    moves[t.name] = delta
            static = r.static.get(index, ())
            if not active:
                period = static[1] if len(static) > 1 else 1.0
                increments = max(1, min(1000, round(period / static[0]))) if static else 1
                phases.append(InpPhase(name, "springback", [], {}, None, None, increments,
                                       card.where))
                continue
            if not moves:
                r.fail(card.error("the step moves no tool: a forming step must move one (the "
                                  "tools drive ddpy's phases), or remove every contact pair "
                                  "(*MODEL CHANGE, TYPE=CONTACT PAIR, REMOVE: springback)"))
                continue
            period = static[1] if len(static) > 1 else 1.0
            max_fraction = static[3] / period if len(static) > 3 else None
            min_fraction = static[2] / period if len(static) > 2 else None
            phases.append(InpPhase(name, "forming", [t.name for t in tools if t.name in active],
                                   moves, max_fraction, min_fraction, 1, card.where))
        if phases and phases[0].kind == "springback":
            r.fail(r.steps[0].error("the first step removes every contact pair: the first "
                                    "phase must form"))
        return phases

    def constraints(self, blank_nodes: set[int], nodesets: dict[str, list[int]],
                    phases: list[InpPhase] | None, refs: dict[int, tuple[int, int, str, Card]]
                    ) -> list[tuple[str, str, tuple[str, ...]]]:
        """Zero displacements of blank nodes: model-level ones in every phase, a step's from
        its phase on (as Abaqus keeps them)."""
        r = self.r
        result = []
        names = [p.name for p in phases or []]
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
            steps = () if bc.step is None else tuple(names[bc.step:])
            result.append((label, components, steps))
        return result


def read_inp(path: str | Path) -> InpModel:
    """Read and check an Abaqus / CalculiX forming model; DeckError lists every defect."""
    path = Path(path)
    reader = _Reader(path)
    reader.read(read_cards(path))
    model = _Mapper(reader).model(path)
    if reader.errors or model is None:
        raise DeckError.collect(reader.errors or [DeckError("invalid model", path)])
    return model
