"""The cards of an Abaqus / CalculiX forming model read into definitions (nodes, elements,
sets, material, sections, rigid bodies, surfaces, contact, boundary conditions, steps): each
keyword and parameter checked against what ddpy maps (:data:`SUPPORTED`), those without
mechanics (:data:`IGNORED`) noted, every defect recorded with its file:line.
:mod:`ddpy.io.inp_model` maps the definitions to ddpy's terms.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ddpy.io.case import DeckError
from ddpy.io.inp_cards import Card, DataLine, integer, number
from ddpy.io.inp_mesh import STABILIZING_TYPES, MeshReader
from ddpy.model.contact import check_friction
from ddpy.model.material import HardeningTable, TablePointError

__all__ = ["BLANK_TYPES", "BOUNDARY_TYPES", "IGNORED", "SUPPORTED", "TOOL_TYPES", "Amplitude",
           "Boundary", "Pair", "Reader"]

#: Element types of the blank, and of rigid tools (besides bricks of a *RIGID BODY).
BLANK_TYPES = ("C3D8", "C3D8R", "C3D8I")
TOOL_TYPES = ("R3D4", "R3D3")
#: Keywords read, and their parameters (a value of None: any value, else the values allowed).
SUPPORTED: dict[str, dict[str, tuple[str, ...] | None]] = {
    "HEADING": {},
    "NODE": {"NSET": None},
    "ELEMENT": {"TYPE": None, "ELSET": None},
    "NSET": {"NSET": None, "GENERATE": ("",), "INTERNAL": ("",)},
    "ELSET": {"ELSET": None, "GENERATE": ("",), "INTERNAL": ("",)},
    "MATERIAL": {"NAME": None},
    "ELASTIC": {"TYPE": ("ISOTROPIC",)},
    "PLASTIC": {"HARDENING": ("ISOTROPIC",)},
    "SOLID SECTION": {"ELSET": None, "MATERIAL": None},
    "RIGID BODY": {"ELSET": None, "NSET": None, "REF NODE": None, "ROT NODE": None},
    "SURFACE": {"NAME": None, "TYPE": ("ELEMENT",), "INTERNAL": ("",)},
    "CONTACT PAIR": {"INTERACTION": None, "TYPE": ("SURFACE TO SURFACE", "NODE TO SURFACE")},
    "SURFACE INTERACTION": {"NAME": None},
    "SURFACE BEHAVIOR": {"PRESSURE-OVERCLOSURE": ("HARD", "LINEAR")},
    "FRICTION": {},
    "BOUNDARY": {"OP": ("MOD",), "TYPE": ("DISPLACEMENT",), "FIXED": ("", "YES"),
                 "AMPLITUDE": None},
    "AMPLITUDE": {"NAME": None, "DEFINITION": ("TABULAR",),
                  "TIME": ("STEP TIME", "TOTAL TIME"), "VALUE": ("RELATIVE",)},
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
#: Cards of the springs and dashpots skipped with their elements (inp_mesh.STABILIZING_TYPES).
STABILIZER_CARDS = ("SPRING", "DASHPOT")
def _stiffness_note(card: Card) -> str:
    """What a linear *SPRING's elements carry in the deck's own model: a spring to the
    ground pushes back its stiffness for each mm its node moves, so a stiff one changes the
    tool forces a run of the deck reports (3 springs of 1 N/mm once held 21 N of a 62 N
    punch force at 7 mm: benchmarks/calculix_same_deck, deck.SPRING)."""
    if card.keyword != "SPRING" or "NONLINEAR" in card.params or not card.data:
        return ""
    try:
        stiffness = float(card.data[-1].words[0])
    except (IndexError, ValueError):
        return ""
    return (f": stiffness {stiffness:g} each; in the deck's own model a spring to the "
            "ground takes that much force per unit its node moves, out of the tool forces")


#: What to do instead, for keywords users meet most.
_HINTS = {
    "ORIENTATION": "write the rolling direction in material.dat (rolling_direction)",
    "POTENTIAL": "write Hill'48 in material.dat by hand (yield hill48)",
    "CLOAD": "ddpy's tools drive the forming: move a tool instead",
    "DLOAD": "ddpy's tools drive the forming: move a tool instead",
    "DYNAMIC": "ddpy's forming is quasi-static: use *STATIC",
    "ANALYTICAL SURFACE": "mesh the tool surface (R3D4/R3D3 elements) in a *RIGID BODY",
    "EQUATION": "ddpy has no multi-point constraints",
    "COUPLING": "ddpy has no multi-point constraints",
}
#: Degrees of freedom of the *BOUNDARY types.
BOUNDARY_TYPES = {"XSYMM": (1, 5, 6), "YSYMM": (2, 4, 6), "ZSYMM": (3, 4, 5),
                  "ENCASTRE": (1, 2, 3, 4, 5, 6), "PINNED": (1, 2, 3)}

@dataclass
class Pair:
    slave: str
    master: str
    interaction: str
    kind: str
    card: Card


@dataclass
class Boundary:
    node_or_set: str
    dofs: tuple[int, ...]
    value: float
    step: int | None
    line: DataLine
    fixed: bool = False
    amplitude: str = ""


@dataclass
class Amplitude:
    """A tabular *AMPLITUDE: (time, value) points, times in step time or total time."""

    name: str
    points: list[tuple[float, float]]
    total_time: bool
    card: Card

    def at(self, time: float) -> float:
        """The value at ``time``, linear between the points, constant beyond them."""
        times = [t for t, _ in self.points]
        values = [v for _, v in self.points]
        return float(np.interp(time, times, values))


class Reader(MeshReader):
    """Walks the cards once, recording definitions; then maps them, collecting errors."""

    def __init__(self, path: Path) -> None:
        super().__init__(path)
        self.title = ""
        self.amplitudes: dict[str, Amplitude] = {}
        self.materials: dict[str, Card] = {}
        self.elastic: dict[str, tuple[float, float]] = {}
        self.plastic: dict[str, list[tuple[float, float]]] = {}
        self.sections: list[tuple[str, str, Card]] = []
        self.rigid: list[Card] = []
        self.pairs: list[Pair] = []
        self.interactions: dict[str, Card] = {}
        self.friction: dict[str, float] = {}
        self.bcs: list[Boundary] = []
        self.steps: list[Card] = []
        self.static: dict[int, tuple[float, ...]] = {}
        self.removed: dict[int, tuple[set[tuple[str, str]], set[tuple[str, str]]]] = {}

    # ----------------------------------------------------------------------- reading cards

    def read(self, cards: list[Card]) -> None:
        material = interaction = ""
        step: int | None = None
        unsupported: dict[str, list[Card]] = {}
        for card in cards:
            key = card.keyword
            if key in IGNORED:
                self.ignored.append(f"{card.where}: *{key}")
                continue
            if key in STABILIZER_CARDS:
                self.ignored.append(f"{card.where}: *{key} (its elements are skipped)"
                                    + _stiffness_note(card))
                continue
            if key not in SUPPORTED:
                unsupported.setdefault(key, []).append(card)
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
                    if any(line.words for line in card.data):
                        self.ignored.append(f"{card.data[0].where}: the out-of-plane "
                                            "thickness of *SURFACE INTERACTION (2D models)")
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
        for key, found in unsupported.items():
            # An instanced part repeats its cards: each line is named once.
            where = list(dict.fromkeys(c.where for c in found))
            more = f" (also at {', '.join(where[1:4])}" + \
                (f" and {len(where) - 4} more)" if len(where) > 4 else ")") \
                if len(where) > 1 else ""
            hint = _HINTS.get(key, "the keywords ddpy reads are listed in "
                              "docs/abaqus-import.md")
            self.fail(found[0].error(f"keyword *{key} is not supported{more}: {hint}"))

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
    def _no_data(card: Card) -> None:
        if any(line.words for line in card.data):  # CAE writes a ',' after a section
            raise card.error(f"*{card.keyword} takes no data lines, got "
                             f"'{', '.join(card.data[0].words)[:60]}'", card.data[0])

    def _element(self, card: Card, *_: object) -> None:
        kind = card.params.get("TYPE", "").upper()
        if kind not in BLANK_TYPES + TOOL_TYPES + STABILIZING_TYPES:
            raise card.error(f"element type {kind or '(none)'} is not supported: expected "
                             f"TYPE= {', '.join(BLANK_TYPES)} (the blank, and bricks of a "
                             f"*RIGID BODY) or {', '.join(TOOL_TYPES)} (rigid tools); springs "
                             "and dashpots are skipped")
        super()._element(card)

    def _amplitude(self, card: Card, *_: object) -> None:
        name = self._name(card, "NAME")
        values = [(line, i) for line in card.data for i in range(len(line.words))]
        if not values or len(values) % 2:
            raise card.error("expected data lines of 'time, value' pairs (up to four a line)",
                             card.data[-1] if card.data else None)
        points: list[tuple[float, float]] = []
        for k in range(0, len(values), 2):
            (line, i), (line2, j) = values[k], values[k + 1]
            time, value = number(line, i, "a time"), number(line2, j, "an amplitude value")
            if points and time <= points[-1][0]:
                raise DeckError(f"time {time:g} is not after the one before ({points[-1][0]:g}):"
                                " expected increasing times", line.path, line.number)
            points.append((time, value))
        self.amplitudes[name] = Amplitude(name, points, card.params.get("TIME", "").upper()
                                          == "TOTAL TIME", card)

    def _heading(self, card: Card, *_: object) -> None:
        self.title = " ".join(", ".join(d.words) for d in card.data[:1])

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
            table.append((number(line, 1, "the plastic strain"),
                          number(line, 0, "the yield stress")))
        try:  # the table's rules are the model's (HardeningTable), at the point's line
            HardeningTable(tuple(ep for ep, _ in table), tuple(y for _, y in table))
        except TablePointError as error:
            line = card.data[error.point]
            raise DeckError(str(error), line.path, line.number) from None
        except ValueError as error:  # the table as a whole (its number of points)
            raise card.error(str(error)) from None
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

    def _contact_pair(self, card: Card, *_: object) -> None:
        interaction = self._name(card, "INTERACTION")
        kind = card.params.get("TYPE", "NODE TO SURFACE").upper()
        for line in card.data:
            if len(line.words) != 2:
                raise DeckError("expected '<slave surface>, <master surface>'", line.path,
                                line.number)
            self.pairs.append(Pair(line.words[0].upper(), line.words[1].upper(), interaction,
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
        try:
            check_friction(mu)
        except ValueError as error:
            raise DeckError(str(error), line.path, line.number) from None
        self.friction[interaction] = mu
        if len(line.words) == 2:
            self.ignored.append(f"{line.where}: the stick slope of *FRICTION (ddpy's Coulomb "
                                "friction sticks exactly)")

    def _boundary(self, card: Card, material: str, interaction: str, step: int | None) -> None:
        fixed = "FIXED" in card.params
        amplitude = card.params.get("AMPLITUDE", "").strip('"').upper()
        if amplitude and amplitude not in self.amplitudes:
            raise card.error(f"AMPLITUDE={amplitude}: no *AMPLITUDE of that name before this "
                             "card")
        if amplitude and step is None:
            raise card.error("AMPLITUDE= on a *BOUNDARY before the first step: give the "
                             "motion in a step")
        for line in card.data:
            target = line.words[0].upper() if line.words else ""
            if len(line.words) == 2 and line.words[1].upper() in BOUNDARY_TYPES:
                self.bcs.append(Boundary(target, BOUNDARY_TYPES[line.words[1].upper()], 0.0, step,
                                         line, fixed, amplitude))
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
            self.bcs.append(Boundary(target, tuple(range(first, last + 1)), value, step, line,
                                     fixed, amplitude))

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


