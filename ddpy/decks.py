"""Input decks: a case is a folder of plain-text files, one concern each (docs/input-format.md).

    control.dat    title, solver settings, phases (active tools, motions, increments, output)
    mesh.dat       the blank: own node and hexahedron blocks, a generated box, or a mesh file
    bc.dat         node sets, symmetry planes, fixed nodes
    material.dat   elasticity, yield criterion (von Mises, Hill'48), hardening (Swift, Voce)
    tools.dat      per tool: description, tool file, friction, the blank side it touches

:func:`read_case` reads and checks them all before any numerics and returns the validated
:class:`ddpy.case.Case`; any defect raises one :class:`DeckError` listing every error found,
each as ``file:line: what is wrong, what was expected``.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ddpy._validate import input_lines
from ddpy.case import (
    AXES,
    BlankMaterial,
    BoundaryConditions,
    Case,
    Constraint,
    Control,
    DeckError,
    HoldGap,
    Mesh,
    Move,
    Newton,
    NodeSet,
    Phase,
    RminLimits,
    Tool,
    blank_thickness,
    rigid_body_modes_free,
)
from ddpy.forming import MAX_INCREMENTS, blank_stiffness
from ddpy.material import Hill48, Material, Swift, Voce
from ddpy.mesh import HEX_EDGES

__all__ = ["DECKS", "DeckError", "parse_case", "read_case"]

#: The decks of a case folder, in reading order.
DECKS = ("control.dat", "mesh.dat", "bc.dat", "material.dat", "tools.dat")
#: Largest mesh a deck may generate or list (elements).
MAX_ELEMENTS = 5_000_000
#: Mesh files read through meshio.
MESH_SUFFIXES = (".inp", ".msh")
#: A corner of a hexahedron with a scaled Jacobian below this is degenerate.
MIN_SCALED_JACOBIAN = 1e-6
#: Largest length a deck may give (mm): displacements, gaps, increments, box sizes.
MAX_LENGTH = 1e6
#: Plausibility bounds of the material (docs/input-format.md): stresses, including the
#: initial yield stress, at most 1e5 MPa (a hundred times the strongest steels); Swift's
#: eps0 at most 10 (a strain: 1e300 made the yield stress infinite).
MAX_STRESS, MAX_EPS0 = 1e5, 10.0
#: Young's modulus (MPa): above the largest it is refused, below the smallest a warning
#: asks whether it is in MPa (polymers to tungsten carbide lie between).
MIN_MODULUS, MAX_MODULUS = 1e3, 1e6
#: Hill'48 coefficients at most 100: the uniaxial yield stress along an axis,
#: 1 / sqrt(G + H) etc. times the hardening law's, is then at least a tenth of it.
MAX_HILL = 100.0
#: Lankford coefficients (given, or H/G and H/F of the coefficients) outside this range are
#: warned about: sheet metals lie between about 0.2 and 3.
R_VALUE_RANGE = (0.1, 10.0)
#: Largest node or element id.
MAX_ID = 2**31 - 1
#: Largest number of errors reported for one kind of defect in a block of data lines.
_MAX_REPORTED = 5
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_.\-]{0,63}")
_INT = re.compile(r"[+-]?[0-9]+")
#: The numbers of the decks (docs/input-format.md): decimal with an optional exponent, in
#: ASCII digits; float() alone would also take '210_000', full-width digits and 'nan'.
_NUMBER = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?|[+-]?(inf|nan)",
                     re.ASCII)


class _Bad(Exception):
    """A defect in the line being read; the deck loop records it with the line number."""


@dataclass
class _Line:
    number: int
    words: list[str]
    text: str

    @property
    def key(self) -> str:
        return self.words[0]


class _Deck:
    """The meaningful lines of one deck ('#' starts a comment), its errors and warnings."""

    def __init__(self, path: Path, text: str) -> None:
        self.path = path
        self.lines: list[_Line] = []
        self.errors: list[DeckError] = []
        self.warnings: list[str] = []
        raw_lines = input_lines(text)
        self.last = len(raw_lines)
        for number, raw in enumerate(raw_lines, start=1):
            content = raw.split("#", 1)[0].strip()
            if content:
                self.lines.append(_Line(number, content.split(), content))

    def where(self, line: int | None) -> str:
        return f"{self.path}:{line}" if line is not None else str(self.path)

    def error(self, line: int | None, message: str) -> None:
        self.errors.append(DeckError(message, self.path, line))

    def warn(self, line: int | None, message: str) -> None:
        self.warnings.append(f"{self.where(line)}: {message}")


def _guard(deck: _Deck, line: _Line | int | None, action: Callable[[], Any]) -> Any:
    """Run ``action``; record a _Bad it raises at ``line`` and return None."""
    try:
        return action()
    except _Bad as bad:
        deck.error(line.number if isinstance(line, _Line) else line, str(bad))
        return None


# ------------------------------------------------------------------------- words and values


def _show(text: str, limit: int = 60) -> str:
    text = text if len(text) <= limit else text[: limit - 3] + "..."
    return f"'{text}'"


def _arity(line: _Line, form: str, low: int, high: int | None = None) -> None:
    """Require low..high words after the keyword (high None: exactly low; -1: no limit)."""
    n = len(line.words) - 1
    high = low if high is None else high
    if n < low or (high >= 0 and n > high):
        raise _Bad(f"expected '{form}', got {_show(line.text)}")


def _float(word: str, what: str, *, gt: float | None = None, ge: float | None = None,
           lt: float | None = None, le: float | None = None, allow_inf: bool = False) -> float:
    if not _NUMBER.fullmatch(word):
        raise _Bad(f"expected a number for {what} (decimal, e.g. 0.114, -28.5 or 1e-4), got "
                   f"{_show(word)}")
    value = float(word)
    if math.isnan(value) or (math.isinf(value) and not allow_inf):
        raise _Bad(f"expected a finite number for {what}, got {_show(word)}")
    for bound, ok, sign in ((gt, lambda b: value > b, ">"), (ge, lambda b: value >= b, ">="),
                            (lt, lambda b: value < b, "<"), (le, lambda b: value <= b, "<=")):
        if bound is not None and not ok(bound):
            raise _Bad(f"{what} must be {sign} {bound:g}, got {word}")
    return value


def _int(word: str, what: str, low: int | None = None, high: int | None = None) -> int:
    if not _INT.fullmatch(word):
        raise _Bad(f"expected an integer for {what}, got {_show(word)}")
    value = int(word)
    if low is not None and value < low:
        raise _Bad(f"{what} must be >= {low}, got {value}")
    if high is not None and value > high:
        raise _Bad(f"{what} must be <= {high}, got {value}")
    return value


def _name(word: str, what: str) -> str:
    if not _NAME.fullmatch(word):
        raise _Bad(f"expected a name for {what} (a letter, then letters, digits, '_', '.' or "
                   f"'-', at most 64), got {_show(word)}")
    return word


def _choice(word: str, what: str, choices: tuple[str, ...]) -> str:
    if word not in choices:
        raise _Bad(f"expected {what} among {', '.join(choices)}, got {_show(word)}")
    return word


def _vector(words: list[str], what: str, limit: float | None = None
            ) -> tuple[float, float, float]:
    x, y, z = (_float(w, what) if limit is None else _float(w, what, ge=-limit, le=limit)
               for w in words)
    return (x, y, z)


def _unit(words: list[str], what: str) -> tuple[float, float, float]:
    v = np.array(_vector(words, what))
    v = v / max(float(np.abs(v).max()), 1e-300)
    length = float(np.linalg.norm(v))
    if not length > 0 or not math.isfinite(length):
        raise _Bad(f"{what} must be a non-zero finite vector, got {' '.join(words)}")
    return tuple(float(c) for c in v / length)  # type: ignore[return-value]


def _pairs(line: _Line, start: int, keys: tuple[str, ...], required: tuple[str, ...],
           form: str) -> dict[str, str]:
    """``KEY VALUE`` pairs after word ``start``: each key once, all required ones present."""
    words = line.words[start:]
    if len(words) % 2:
        raise _Bad(f"expected '{form}' (keys and values in pairs), got {_show(line.text)}")
    values: dict[str, str] = {}
    for key, value in zip(words[::2], words[1::2], strict=True):
        if key not in keys:
            raise _Bad(f"unknown key {_show(key)} in '{form}': expected {', '.join(keys)}")
        if key in values:
            raise _Bad(f"{key} given twice")
        values[key] = value
    missing = [k for k in required if k not in values]
    if missing:
        raise _Bad(f"missing {', '.join(missing)}: expected '{form}'")
    return values


def _once(deck: _Deck, seen: dict[str, int], line: _Line, key: str | None = None) -> bool:
    """Record ``key`` (default the line's keyword) as given; error and False when repeated."""
    key = key or line.key
    if key in seen:
        deck.error(line.number, f"'{key}' given twice (first at line {seen[key]})")
        return False
    seen[key] = line.number
    return True


# ----------------------------------------------------------------------------------- reading


def read_case(folder: str | Path, geometry: bool = True) -> Case:
    """Read and validate the case folder; raise DeckError listing every defect found.
    With ``geometry`` the tool models are read (when ddpy.toolfile is available) and the
    positions of the tools checked against the blank (docs/input-format.md, "Checks")."""
    folder = Path(folder)
    if not folder.is_dir():
        raise DeckError(f"not a case folder (expected a folder holding {', '.join(DECKS)})",
                        folder)
    texts: dict[str, str] = {}
    errors: list[DeckError] = []
    for name in DECKS:
        path = folder / name
        try:
            texts[name] = path.read_bytes().decode("utf-8")
        except FileNotFoundError:
            errors.append(DeckError(f"missing: every case needs {', '.join(DECKS)}", path))
        except UnicodeDecodeError as error:
            errors.append(DeckError(f"not UTF-8 text (byte {error.start}): expected a "
                                    "plain-text deck", path))
        except OSError as error:
            errors.append(DeckError(f"cannot read: {error.strerror or error}", path))
    if errors:
        raise DeckError.collect(errors)
    return parse_case(texts, folder, geometry=geometry)


def parse_case(texts: Mapping[str, str], folder: str | Path = ".",
               geometry: bool = True) -> Case:
    """Validate decks given as text (``{"control.dat": "...", ...}``); relative file paths in
    them are taken from ``folder``. Raise DeckError listing every defect found."""
    folder = Path(folder)
    missing = [name for name in DECKS if name not in texts]
    if missing:
        raise DeckError.collect([DeckError("missing: every case needs " + ", ".join(DECKS),
                                           folder / name) for name in missing])
    decks = {name: _Deck(folder / name, texts[name]) for name in DECKS}
    control = _parse_control(decks["control.dat"])
    parsed_mesh = _parse_mesh(decks["mesh.dat"])
    bc = _parse_bc(decks["bc.dat"])
    material = _parse_material(decks["material.dat"])
    tools = _parse_tools(decks["tools.dat"])
    errors = [e for d in decks.values() for e in d.errors]
    if errors:
        raise DeckError.collect(errors)
    assert parsed_mesh is not None and material is not None
    mesh, mesh_sets = parsed_mesh
    cross = _Cross(decks, folder)
    case = cross.build(control, mesh, mesh_sets, bc, material, tools)
    errors = [e for d in decks.values() for e in d.errors]
    if errors or case is None:
        raise DeckError.collect(errors or [DeckError("invalid case", folder)])
    if geometry:
        from ddpy.casecheck import geometry_checks

        errors, warnings = geometry_checks(case)
        if errors:
            raise DeckError.collect(errors)
        if warnings:
            case = dataclasses.replace(case, warnings=case.warnings + tuple(warnings))
    return case


# ----------------------------------------------------------------------------------- control

#: Settings allowed at the top of control.dat (defaults of every phase) and inside a phase.
_SETTINGS: dict[str, Callable[[str], Any]] = {
    "max_increment": lambda w: _float(w, "max_increment", gt=0, le=MAX_LENGTH),
    "min_increment": lambda w: _float(w, "min_increment", gt=0, le=MAX_LENGTH),
    # The run's increment control (forming.IncrementLimits) takes fractions below 1 only.
    "rmin_yield": lambda w: _float(w, "rmin_yield", ge=0, lt=1),
    "rmin_strain": lambda w: _float(w, "rmin_strain", gt=0, lt=1),
    "rmin_rotation": lambda w: _float(w, "rmin_rotation", gt=0, le=90),
    "rmin_contact": lambda w: _choice(w, "rmin_contact", ("on", "off")) == "on",
    "rmin_release": lambda w: _float(w, "rmin_release", ge=0, le=1),
    "rmin_release_redos": lambda w: (None if w == "off"
                                     else _int(w, "rmin_release_redos", 0, 10**6)),
    "newton_force": lambda w: _float(w, "newton_force", gt=0, lt=1),
    "newton_displacement": lambda w: _float(w, "newton_displacement", gt=0, lt=1),
    "max_iterations": lambda w: _int(w, "max_iterations", 1, 1000),
    "cutback": lambda w: _float(w, "cutback", gt=0, lt=1),
    "output_every": lambda w: _int(w, "output_every", 0, 10**9),
}
_PHASE_KEYS = ("type", "tools", "move", "gap", "lead", "output_at", "increments")
#: Default largest increment: this fraction of the lead tool's travel.
DEFAULT_INCREMENT_FRACTION = 0.01
#: Default smallest increment: this fraction of the largest.
DEFAULT_MIN_FRACTION = 1e-3
DEFAULT_OUTPUT_EVERY = 10


@dataclass
class _PhaseDraft:
    name: str
    line: int
    kind: str = "forming"
    tools: list[str] = field(default_factory=list)
    tools_line: int | None = None
    moves: list[tuple[str, tuple[float, float, float], int]] = field(default_factory=list)
    gaps: list[tuple[str, str, float, int]] = field(default_factory=list)
    lead: tuple[str, int] | None = None
    output_at: tuple[list[float], int] | None = None
    increments: tuple[int, int] | None = None
    settings: dict[str, tuple[Any, int]] = field(default_factory=dict)
    seen: dict[str, int] = field(default_factory=dict)


@dataclass
class _ControlDraft:
    title: str | None = None
    settings: dict[str, tuple[Any, int]] = field(default_factory=dict)
    phases: list[_PhaseDraft] = field(default_factory=list)


def _parse_control(deck: _Deck) -> _ControlDraft:
    draft = _ControlDraft()
    seen: dict[str, int] = {}
    phase: _PhaseDraft | None = None
    for line in deck.lines:
        key = line.key
        try:
            if key == "phase":
                _arity(line, "phase NAME", 1)
                if phase is not None:
                    deck.error(phase.line, f"phase '{phase.name}' is not closed: expected "
                               f"'end' before the next 'phase' (line {line.number})")
                phase = _PhaseDraft(_name(line.words[1], "the phase"), line.number)
                draft.phases.append(phase)
            elif key == "end":
                _arity(line, "end", 0)
                if phase is None:
                    raise _Bad("'end' without a 'phase NAME' to close")
                phase = None
            elif key == "title":
                if phase is not None:
                    raise _Bad("'title' belongs at the top of control.dat, not in a phase")
                if _once(deck, seen, line):
                    draft.title = line.text[len("title"):].strip() or None
                    if draft.title is None:
                        raise _Bad("expected 'title TEXT'")
            elif key in _SETTINGS:
                _arity(line, f"{key} VALUE", 1)
                target = phase.settings if phase is not None else draft.settings
                where = phase.seen if phase is not None else seen
                if _once(deck, where, line):
                    target[key] = (_SETTINGS[key](line.words[1]), line.number)
            elif key in _PHASE_KEYS:
                if phase is None:
                    raise _Bad(f"'{key}' belongs inside a phase: expected 'phase NAME' ... "
                               "'end' around it")
                _phase_line(deck, phase, line)
            else:
                where = "in a phase" if phase is not None else "at the top of control.dat"
                allowed = (_PHASE_KEYS + ("end",)) if phase is not None else (
                    "title", "phase")
                raise _Bad(f"unknown keyword {_show(key)} {where}: expected one of "
                           f"{', '.join(allowed + tuple(_SETTINGS))}")
        except _Bad as bad:
            deck.error(line.number, str(bad))
    if phase is not None:
        deck.error(phase.line, f"phase '{phase.name}' is not closed: expected 'end' before "
                   "the end of the file")
    if not draft.phases and not deck.errors:
        deck.error(None, "no phase: expected at least one 'phase NAME' ... 'end' block")
    return draft


def _phase_line(deck: _Deck, phase: _PhaseDraft, line: _Line) -> None:
    key, words = line.key, line.words
    if key == "type":
        _arity(line, "type forming|springback", 1)
        if _once(deck, phase.seen, line):
            phase.kind = _choice(words[1], "the phase type", ("forming", "springback"))
    elif key == "tools":
        _arity(line, "tools TOOL...", 1, -1)
        if _once(deck, phase.seen, line):
            names = [_name(w, "a tool") for w in words[1:]]
            repeated = sorted({n for n in names if names.count(n) > 1})
            if repeated:
                raise _Bad(f"tool '{repeated[0]}' listed twice")
            phase.tools, phase.tools_line = names, line.number
    elif key == "move":
        _arity(line, "move TOOL DX DY DZ", 4)
        tool = _name(words[1], "the tool")
        phase.moves.append((tool, _vector(words[2:], "the displacement", MAX_LENGTH),
                            line.number))
    elif key == "gap":
        _arity(line, "gap TOOL OTHER VALUE", 3)
        tool, other = _name(words[1], "the tool"), _name(words[2], "the other tool")
        if tool == other:
            raise _Bad(f"a tool cannot keep a gap to itself: expected 'gap TOOL OTHER VALUE' "
                       f"with two tools, got '{tool}' twice")
        gap = _float(words[3], "the gap", gt=0, le=MAX_LENGTH)
        phase.gaps.append((tool, other, gap, line.number))
    elif key == "lead":
        _arity(line, "lead TOOL", 1)
        if _once(deck, phase.seen, line):
            phase.lead = (_name(words[1], "the lead tool"), line.number)
    elif key == "output_at":
        _arity(line, "output_at TRAVEL...", 1, -1)
        if _once(deck, phase.seen, line):
            values = [_float(w, "an output travel", gt=0, le=MAX_LENGTH) for w in words[1:]]
            if any(b <= a for a, b in zip(values, values[1:], strict=False)):
                raise _Bad("output_at travels must increase strictly, got "
                           + " ".join(words[1:]))
            phase.output_at = (values, line.number)
    elif key == "increments":
        _arity(line, "increments N", 1)
        if _once(deck, phase.seen, line):
            phase.increments = (_int(words[1], "increments", 1, 1_000_000), line.number)


# ----------------------------------------------------------------------------------- mesh


@dataclass
class _RawMesh:
    nodes: NDArray[np.float64]
    elements: NDArray[np.int64]  # 0-based
    node_ids: NDArray[np.int64]
    element_ids: NDArray[np.int64]
    element_lines: NDArray[np.int64] | None  # deck line of each element (own format)
    nodesets: dict[str, NDArray[np.int64]]
    source: str
    node_lines: NDArray[np.int64] | None = None  # deck line of each node (own format)


def _parse_mesh(deck: _Deck) -> tuple[Mesh, dict[str, NDArray[np.int64]]] | None:
    seen: dict[str, int] = {}
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    scale = 1.0
    origin = np.zeros(3)
    raw: _RawMesh | None = None
    sources: list[tuple[str, int]] = []
    lines = deck.lines
    i = 0
    while i < len(lines):
        line = lines[i]
        i += 1
        key = line.key
        try:
            if key == "normal":
                _arity(line, "normal x|y|z|-x|-y|-z", 1)
                if _once(deck, seen, line):
                    word = _choice(line.words[1], "the sheet normal",
                                   ("x", "y", "z", "+x", "+y", "+z", "-x", "-y", "-z"))
                    vector = [0.0, 0.0, 0.0]
                    vector[AXES[word[-1]]] = -1.0 if word.startswith("-") else 1.0
                    normal = (vector[0], vector[1], vector[2])
            elif key == "scale":
                _arity(line, "scale FACTOR", 1)
                if _once(deck, seen, line):
                    scale = _float(line.words[1], "the scale factor", gt=0)
            elif key == "origin":
                _arity(line, "origin X Y Z", 3)
                if _once(deck, seen, line):
                    origin = np.array(_vector(line.words[1:], "the origin", MAX_LENGTH))
            elif key in ("nodes", "hexahedra", "box", "file"):
                if key != "hexahedra":
                    if sources:
                        deck.error(line.number, f"'{key}' conflicts with '{sources[0][0]}' at "
                                   f"line {sources[0][1]}: give the mesh one way ('nodes' and "
                                   "'hexahedra' blocks, 'box' or 'file')")
                        return None
                    sources.append((key, line.number))
                if key == "box":
                    _arity(line, "box LX LY LZ NX NY NZ", 6)
                    if _once(deck, seen, line):
                        raw = _box(line)
                elif key == "file":
                    _arity(line, "file PATH", 1)
                    if _once(deck, seen, line):
                        raw = _mesh_file(deck, line)
                elif key == "nodes":
                    if _once(deck, seen, line):
                        i, raw = _own_mesh(deck, lines, i - 1)
                        if raw is None:
                            return None  # the rest of the file cannot be told apart
                else:
                    raise _Bad("'hexahedra' must follow the 'nodes' block")
            else:
                raise _Bad(f"unknown keyword {_show(key)}: expected normal, scale, origin, "
                           "nodes, hexahedra, box or file")
        except _Bad as bad:
            deck.error(line.number, str(bad))
    if deck.errors:
        return None
    if raw is None:
        deck.error(None, "no mesh: expected 'nodes' and 'hexahedra' blocks, 'box LX LY LZ NX "
                   "NY NZ' or 'file PATH'")
        return None
    if "origin" in seen and sources[0][0] != "box":
        deck.error(seen["origin"], "'origin' applies to a generated 'box' only")
        return None
    with np.errstate(over="ignore", invalid="ignore"):
        nodes = raw.nodes * scale + (origin if sources[0][0] == "box" else 0.0)
    with np.errstate(invalid="ignore"):
        if not np.all(np.abs(nodes) <= MAX_LENGTH):
            deck.error(seen.get("scale", sources[0][1]), f"node coordinates beyond +-"
                       f"{MAX_LENGTH:g} mm (after scaling)")
            return None
    if not _check_elements(deck, raw, nodes):
        return None
    mesh = Mesh(nodes, raw.elements, raw.node_ids, raw.element_ids, normal, raw.source)
    return mesh, raw.nodesets


def _box(line: _Line) -> _RawMesh:
    w = line.words
    size = [_float(v, f"the box length L{a}", gt=0, le=MAX_LENGTH)
            for v, a in zip(w[1:4], "XYZ", strict=True)]
    counts = [_int(v, f"the element count N{a}", 1, MAX_ELEMENTS)
              for v, a in zip(w[4:7], "XYZ", strict=True)]
    nx, ny, nz = counts
    if nx * ny * nz > MAX_ELEMENTS:
        raise _Bad(f"the box has {nx * ny * nz} elements: at most {MAX_ELEMENTS}")
    gx, gy, gz = (np.linspace(0.0, s, c + 1) for s, c in zip(size, counts, strict=True))
    zz, yy, xx = np.meshgrid(gz, gy, gx, indexing="ij")
    nodes = np.column_stack([xx.ravel(), yy.ravel(), zz.ravel()])
    index = np.arange(len(nodes)).reshape(nz + 1, ny + 1, nx + 1)
    c = index[:-1, :-1, :-1]
    elements = np.stack([c, index[:-1, :-1, 1:], index[:-1, 1:, 1:], index[:-1, 1:, :-1],
                         index[1:, :-1, :-1], index[1:, :-1, 1:], index[1:, 1:, 1:],
                         index[1:, 1:, :-1]], axis=-1).reshape(-1, 8)
    return _RawMesh(nodes, elements, np.arange(1, len(nodes) + 1),
                    np.arange(1, len(elements) + 1), None, {},
                    f"box {' '.join(w[1:7])}")


def _own_mesh(deck: _Deck, lines: list[_Line], start: int) -> tuple[int, _RawMesh | None]:
    """The 'nodes N' block at lines[start] and the 'hexahedra M' block after it."""
    blocks = {}
    i = start
    for keyword, width, form in (("nodes", 4, "ID X Y Z"), ("hexahedra", 9, "ID N1 ... N8")):
        if i >= len(lines):
            deck.error(deck.last, f"the file ends where '{keyword} COUNT' was expected")
            return i, None
        head = lines[i]
        if head.key != keyword:
            deck.error(head.number, f"expected '{keyword} COUNT', got {_show(head.text)}")
            return i, None
        try:
            _arity(head, f"{keyword} COUNT", 1)
            count = _int(head.words[1], f"the number of {keyword}", 1, 8 * MAX_ELEMENTS)
        except _Bad as bad:
            deck.error(head.number, str(bad))
            return i + 1, None
        i += 1
        rows: list[list[str]] = []
        numbers: list[int] = []
        while len(rows) < count and i < len(lines) and lines[i].key not in _MESH_KEYS:
            rows.append(lines[i].words)
            numbers.append(lines[i].number)
            i += 1
        if len(rows) < count:
            where = lines[i].number if i < len(lines) else deck.last
            got = f"'{lines[i].key}'" if i < len(lines) else "the end of the file"
            deck.error(where, f"expected {count} lines '{form}' after line {head.number}, got "
                       f"{len(rows)} before {got}")
            return i, None
        bad = [k for k, r in enumerate(rows) if len(r) != width]
        if bad:
            for k in bad[:_MAX_REPORTED]:
                deck.error(numbers[k], f"expected '{form}' ({width} numbers), got "
                           f"{_show(' '.join(rows[k]))}")
            return i, None
        blocks[keyword] = (rows, np.array(numbers))
    return i, _own_arrays(deck, blocks)


_MESH_KEYS = ("normal", "scale", "origin", "nodes", "hexahedra", "box", "file")


def _own_arrays(deck: _Deck, blocks: dict) -> _RawMesh | None:
    (node_rows, node_lines), (elem_rows, elem_lines) = blocks["nodes"], blocks["hexahedra"]
    ok = True

    def numbers(rows: list[list[str]], lines: NDArray, kind: type, what: str) -> NDArray | None:
        """The rows as an array; on a bad word, an error at its line and None."""
        pattern = _NUMBER if kind is float else _INT
        if kind is float and all(pattern.fullmatch(word) for row in rows for word in row):
            return np.array(rows, dtype=float)  # non-finite values are refused below
        for row, number in zip(rows, lines, strict=True):
            for word in row:
                try:
                    if not pattern.fullmatch(word):
                        raise ValueError(word)
                    value = float(word) if kind is float else int(word)
                except ValueError:
                    deck.error(int(number), f"expected {what}, got {_show(' '.join(row))}")
                    return None
                if kind is not float and abs(value) > MAX_ID:
                    deck.error(int(number), f"{word} is out of range: ids are at most {MAX_ID}")
                    return None
        return np.array(rows, dtype=float if kind is float else np.int64)

    node_ids = numbers([r[:1] for r in node_rows], node_lines, int, "an integer node id")
    coords = numbers([r[1:] for r in node_rows], node_lines, float, "numbers X Y Z")
    elem = numbers(elem_rows, elem_lines, int, "integers ID N1 ... N8")
    if node_ids is None or coords is None or elem is None:
        return None
    node_ids = node_ids[:, 0]
    with np.errstate(invalid="ignore"):
        finite = (np.abs(coords) <= MAX_LENGTH).all(axis=1)
    for k in np.flatnonzero(~finite)[:_MAX_REPORTED]:
        deck.error(int(node_lines[k]), f"expected finite coordinates X Y Z within +-{MAX_LENGTH:g}"
                   " mm, got " + _show(" ".join(node_rows[k][1:])))
    ok &= bool(finite.all())
    for ids, lines, what in ((node_ids, node_lines, "node"), (elem[:, 0], elem_lines,
                                                              "element")):
        if (ids < 1).any():
            k = int(np.argmax(ids < 1))
            deck.error(int(lines[k]), f"{what} ids must be >= 1, got {ids[k]}")
            ok = False
        order = np.argsort(ids, kind="stable")
        dup = np.flatnonzero(ids[order][1:] == ids[order][:-1])
        for d in dup[:_MAX_REPORTED]:
            first, again = order[d], order[d + 1]
            deck.error(int(lines[again]), f"{what} {ids[again]} defined twice (first at line "
                       f"{lines[first]})")
            ok = False
    if not ok:
        return None
    if len(elem) > MAX_ELEMENTS:
        deck.error(int(elem_lines[0]), f"{len(elem)} elements: at most {MAX_ELEMENTS}")
        return None
    order = np.argsort(node_ids)
    sorted_ids = node_ids[order]
    refs = elem[:, 1:]
    pos = np.clip(np.searchsorted(sorted_ids, refs), 0, len(sorted_ids) - 1)
    known = sorted_ids[pos] == refs
    for k in np.flatnonzero(~known.all(axis=1))[:_MAX_REPORTED]:
        missing = refs[k][~known[k]][0]
        deck.error(int(elem_lines[k]), f"element {elem[k, 0]} refers to node {missing}, which "
                   "is not in the 'nodes' block")
    if not known.all():
        return None
    return _RawMesh(coords, order[pos], node_ids, elem[:, 0], elem_lines, {}, "mesh.dat",
                    node_lines)


def _mesh_file(deck: _Deck, line: _Line) -> _RawMesh:
    path = Path(line.words[1])
    if not path.is_absolute():
        path = deck.path.parent / path
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise _Bad(f"expected a mesh file ending in {' or '.join(MESH_SUFFIXES)} (Abaqus input "
                   f"or Gmsh), got {_show(line.words[1])}")
    if not path.is_file():
        raise _Bad(f"mesh file {path} not found")
    if path.suffix.lower() == ".msh":
        _check_gmsh_counts(path)
    try:
        import meshio

        data = meshio.read(path)
    except Exception as error:  # meshio raises many types for a bad file
        raise _Bad(f"cannot read mesh file {path}: {type(error).__name__}: {error}") from None
    solids = {"tetra", "hexahedron", "wedge", "pyramid"}
    other = {}
    hexes = []
    for block in data.cells:
        if block.type == "hexahedron":
            hexes.append(np.asarray(block.data, dtype=np.int64))
        elif block.type.rstrip("0123456789") in solids:
            other[block.type] = other.get(block.type, 0) + len(block.data)
    if other:
        found = ", ".join(f"{n} {t}" for t, n in sorted(other.items()))
        raise _Bad(f"mesh file {path.name} holds {found} cells: only 8-node hexahedra are "
                   "accepted")
    if not hexes:
        raise _Bad(f"mesh file {path.name} holds no hexahedra")
    elements = np.concatenate(hexes)
    if len(elements) > MAX_ELEMENTS:
        raise _Bad(f"mesh file {path.name} has {len(elements)} elements: at most {MAX_ELEMENTS}")
    points = np.asarray(data.points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise _Bad(f"mesh file {path.name} is not three-dimensional")
    if elements.size and (elements.min() < 0 or elements.max() >= len(points)):
        raise _Bad(f"mesh file {path.name} has elements with node indices out of range")
    # Nodes outside the hexahedra (geometry points, lower-dimensional cells) are dropped.
    used = np.unique(elements)
    renumber = np.full(len(points), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    nodesets = {}
    for name, indices in _file_nodesets(data).items():
        kept = renumber[np.asarray(indices, dtype=np.int64)]
        nodesets[name] = kept[kept >= 0]
    return _RawMesh(points[used], renumber[elements], used + 1,
                    np.arange(1, len(elements) + 1), None, nodesets, path.name)


def _check_gmsh_counts(path: Path) -> None:
    """The counts of an ASCII Gmsh file's $Nodes and $Elements sections against the lines they
    hold: meshio reads as many entries as a count says and ignores the rest, so a count made
    too small would silently drop elements. Binary files are left to meshio."""
    try:
        with open(path, encoding="latin-1") as f:
            lines = f.read().split("\n")
    except OSError as error:
        raise _Bad(f"cannot read mesh file {path}: {error.strerror or error}") from None
    version, binary = None, False
    sections: dict[str, tuple[int, list[str]]] = {}
    start = None
    for number, raw in enumerate(lines, start=1):
        text = raw.strip()
        if text in ("$MeshFormat", "$Nodes", "$Elements"):
            start = (text[1:], number)
            body: list[str] = []
        elif start is not None and text == f"$End{start[0]}":
            sections[start[0]] = (start[1], body)
            start = None
        elif start is not None:
            body.append(text)
    if "MeshFormat" in sections and sections["MeshFormat"][1]:
        words = sections["MeshFormat"][1][0].split()
        version = words[0] if words else None
        binary = len(words) > 1 and words[1] == "1"
    if binary or version is None:
        return
    for name in ("Nodes", "Elements"):
        if name not in sections:
            continue
        first, body = sections[name]
        body = [b for b in body if b]
        try:
            header = [int(w) for w in body[0].split()] if body else []
            if version.startswith("2"):
                expected, found = header[0], len(body) - 1
            else:  # 4.x: blocks, each a header line and its entries (nodes: tags, then xyz)
                expected, found, row = header[1], 0, 1
                while row < len(body):
                    count = int(body[row].split()[3])
                    found += count
                    row += 1 + (2 * count if name == "Nodes" else count)
                if row != len(body):
                    raise ValueError
        except (IndexError, ValueError):
            raise _Bad(f"mesh file {path.name}:{first}: the ${name} section is malformed") \
                from None
        if expected != found:
            raise _Bad(f"mesh file {path.name}:{first + 1}: ${name} says {expected} entries, "
                       f"the section holds {found}")


def _file_nodesets(data: Any) -> dict[str, NDArray[np.int64]]:
    """Node sets of a mesh file: Abaqus NSETs, and the nodes of each Gmsh physical group."""
    sets: dict[str, NDArray[np.int64]] = {}

    def clean(name: str) -> str:
        text = re.sub(r"[^A-Za-z0-9_.\-]", "_", str(name))[:64]
        return text if text[:1].isalpha() else f"set_{text}"[:64]

    for name, indices in getattr(data, "point_sets", {}).items():
        sets[clean(name)] = np.asarray(indices, dtype=np.int64).ravel()
    physical = getattr(data, "cell_data", {}).get("gmsh:physical")
    if physical is not None:
        for name, (tag, _dim) in getattr(data, "field_data", {}).items():
            members = [np.asarray(b.data)[np.asarray(t) == tag].ravel()
                       for b, t in zip(data.cells, physical, strict=False)
                       if len(t) == len(b.data)]
            nodes = np.unique(np.concatenate(members)) if members else np.zeros(0, np.int64)
            if nodes.size:
                sets[clean(name)] = nodes
    return sets


#: Corner, and its neighbours along xi, eta, zeta with the sign of each direction.
_CORNERS = np.array([[0, 1, 3, 4], [1, 0, 2, 5], [2, 3, 1, 6], [3, 2, 0, 7],
                     [4, 5, 7, 0], [5, 4, 6, 1], [6, 7, 5, 2], [7, 6, 4, 3]])
_SIGNS = np.array([[1, 1, 1], [-1, 1, 1], [-1, -1, 1], [1, -1, 1],
                   [1, 1, -1], [-1, 1, -1], [-1, -1, -1], [1, -1, -1]], dtype=float)


def scaled_jacobians(nodes: NDArray[np.float64], elements: NDArray[np.int64]
                     ) -> NDArray[np.float64]:
    """Scaled Jacobian (det of the three unit edge vectors) at the 8 corners, (m, 8):
    1 for a cube, <= 0 for an inverted or degenerate corner."""
    x = nodes[elements]  # (m, 8, 3)
    corner = x[:, _CORNERS[:, 0]]
    edges = (x[:, _CORNERS[:, 1:]] - corner[:, :, None, :]) * _SIGNS[None, :, :, None]
    lengths = np.linalg.norm(edges, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = edges / lengths[..., None]
        det = np.linalg.det(unit)
    return np.where(np.isfinite(det), det, 0.0)


def _check_elements(deck: _Deck, raw: _RawMesh, nodes: NDArray[np.float64]) -> bool:
    elements = raw.elements
    ordered = np.sort(elements, axis=1)
    repeats = np.flatnonzero((ordered[:, 1:] == ordered[:, :-1]).any(axis=1))
    where = (lambda k: int(raw.element_lines[k])) if raw.element_lines is not None else (
        lambda k: None)
    label = f" of {raw.source}" if raw.element_lines is None else ""
    for k in repeats[:_MAX_REPORTED]:
        deck.error(where(k), f"element {raw.element_ids[k]}{label} repeats a node: "
                   f"{raw.node_ids[elements[k]].tolist()}")
    if repeats.size:
        return False
    jac = scaled_jacobians(nodes, elements)
    bad = np.flatnonzero(jac.min(axis=1) <= MIN_SCALED_JACOBIAN)
    for k in bad[:_MAX_REPORTED]:
        c = int(np.argmin(jac[k]))
        kind = "inverted" if jac[k].max() <= 0 else "inverted or degenerate"
        deck.error(where(k), f"element {raw.element_ids[k]}{label} is {kind} at its corner "
                   f"{c} (scaled Jacobian {jac[k, c]:.3g}): expected nodes 1-4 counter-"
                   "clockwise seen from nodes 5-8 above them")
    if bad.size > _MAX_REPORTED:
        deck.error(where(int(bad[_MAX_REPORTED])), f"... and {bad.size - _MAX_REPORTED} more "
                   "inverted or degenerate elements")
    used = np.zeros(len(nodes), bool)
    used[elements.ravel()] = True
    if raw.node_lines is not None:  # mesh files: nodes outside the hexahedra were dropped
        for k in np.flatnonzero(~used)[:_MAX_REPORTED]:
            deck.error(int(raw.node_lines[k]), f"node {raw.node_ids[k]} belongs to no element: "
                       "remove it (a free node makes the stiffness singular)")
    return not bad.size and bool(used.all())


# ----------------------------------------------------------------------------------- bc


@dataclass
class _BcDraft:
    tolerance: tuple[float, int] | None = None
    nodesets: list[tuple[str, str, list[str], int]] = field(default_factory=list)
    symmetries: list[tuple[int, str, int]] = field(default_factory=list)
    fixes: list[tuple[str, tuple[int, ...], list[str], int]] = field(default_factory=list)


def _parse_bc(deck: _Deck) -> _BcDraft:
    draft = _BcDraft()
    seen: dict[str, int] = {}
    for line in deck.lines:
        key, w = line.key, line.words
        try:
            if key == "tolerance":
                _arity(line, "tolerance VALUE", 1)
                if _once(deck, seen, line):
                    draft.tolerance = (_float(w[1], "the tolerance", gt=0), line.number)
            elif key == "nodeset":
                _arity(line, "nodeset NAME ids|box|plane ...", 2, -1)
                name = _name(w[1], "the node set")
                kind = _choice(w[2], "the node set kind", ("ids", "box", "plane"))
                if kind == "ids":
                    _arity(line, "nodeset NAME ids ID...", 3, -1)
                    for word in w[3:]:
                        _id_range(word)
                elif kind == "box":
                    _arity(line, "nodeset NAME box XMIN XMAX YMIN YMAX ZMIN ZMAX", 8)
                    b = [_float(v, "a box bound", allow_inf=True) for v in w[3:]]
                    for a in range(3):
                        if b[2 * a] > b[2 * a + 1]:
                            raise _Bad(f"box bounds of {'xyz'[a]}: min {w[3 + 2 * a]} > max "
                                       f"{w[4 + 2 * a]}")
                else:
                    _arity(line, "nodeset NAME plane AXIS VALUE", 4)
                    _choice(w[3], "the plane axis", ("x", "y", "z"))
                    _float(w[4], "the plane position")
                draft.nodesets.append((name, kind, w[3:], line.number))
            elif key == "symmetry":
                _arity(line, "symmetry AXIS VALUE|NODESET", 2)
                axis = AXES[_choice(w[1], "the symmetry axis", ("x", "y", "z"))]
                if not _NAME.fullmatch(w[2]):
                    _float(w[2], "the plane position")
                draft.symmetries.append((axis, w[2], line.number))
            elif key == "fix":
                _arity(line, "fix NODESET COMPONENTS [phase PHASE...]", 2, -1)
                name = _name(w[1], "the node set")
                comps = w[2]
                if comps == "all":
                    comps = "xyz"
                if not comps or any(c not in "xyz" for c in comps) or len(set(comps)) != len(
                        comps):
                    raise _Bad(f"expected components among x, y, z (such as 'z', 'xy', 'xyz' "
                               f"or 'all'), got {_show(w[2])}")
                phases: list[str] = []
                if len(w) > 3:
                    if w[3] != "phase" or len(w) < 5:
                        raise _Bad(f"expected 'fix NODESET COMPONENTS [phase PHASE...]', got "
                                   f"{_show(line.text)}")
                    phases = [_name(p, "a phase") for p in w[4:]]
                draft.fixes.append((name, tuple(sorted(AXES[c] for c in comps)), phases,
                                    line.number))
            else:
                raise _Bad(f"unknown keyword {_show(key)}: expected tolerance, nodeset, "
                           "symmetry or fix")
        except _Bad as bad:
            deck.error(line.number, str(bad))
    return draft


def _id_range(word: str) -> tuple[int, int]:
    match = re.fullmatch(r"([0-9]+)(?:-([0-9]+))?", word)
    if not match:
        raise _Bad(f"expected a node id or a range FIRST-LAST, got {_show(word)}")
    first = int(match.group(1))
    last = int(match.group(2)) if match.group(2) else first
    if first < 1 or last < first:
        raise _Bad(f"expected a range FIRST-LAST with 1 <= FIRST <= LAST, got {_show(word)}")
    return first, last


# ----------------------------------------------------------------------------------- material


def _parse_material(deck: _Deck) -> BlankMaterial | None:
    seen: dict[str, int] = {}
    elastic: tuple[float, float] | None = None
    criterion: tuple[Hill48, str] | None = None
    hardening: Swift | Voce | None = None
    angle = 0.0
    for line in deck.lines:
        key, w = line.key, line.words
        try:
            if key == "elastic":
                if _once(deck, seen, line):
                    v = _pairs(line, 1, ("E", "nu"), ("E", "nu"), "elastic E VALUE nu VALUE")
                    elastic = (_float(v["E"], "Young's modulus E", gt=0, le=MAX_MODULUS),
                               _float(v["nu"], "Poisson's ratio nu", gt=-1, lt=0.5))
                    if elastic[0] < MIN_MODULUS:
                        deck.warn(line.number, f"Young's modulus {elastic[0]:g} MPa is outside "
                                  "1e3 to 1e6 MPa (polymers to tungsten carbide): is it in "
                                  "MPa?")
            elif key == "yield":
                _arity(line, "yield vonmises|hill48 ...", 1, -1)
                if _once(deck, seen, line):
                    criterion = _yield(line, deck)
            elif key == "hardening":
                _arity(line, "hardening swift|voce ...", 1, -1)
                if _once(deck, seen, line):
                    hardening = _hardening(line)
            elif key == "rolling_direction":
                _arity(line, "rolling_direction ANGLE", 1)
                if _once(deck, seen, line):
                    angle = _float(w[1], "the rolling direction angle", ge=-360, le=360)
            else:
                raise _Bad(f"unknown keyword {_show(key)}: expected elastic, yield, hardening "
                           "or rolling_direction")
        except _Bad as bad:
            deck.error(line.number, str(bad))
    for key, form in (("elastic", "elastic E VALUE nu VALUE"),
                      ("yield", "yield vonmises | yield hill48 ..."),
                      ("hardening", "hardening swift ... | hardening voce ...")):
        if key not in seen:
            deck.error(None, f"no '{key}' line: expected '{form}'")
    if deck.errors or elastic is None or criterion is None or hardening is None:
        return None
    try:
        material = Material(elastic[0], elastic[1], criterion[0], hardening)
    except (ValueError, TypeError) as error:
        deck.error(seen["elastic"], f"invalid material: {error}")
        return None
    return BlankMaterial(material, angle, criterion[1], deck.where(seen["yield"]))


def _yield(line: _Line, deck: _Deck) -> tuple[Hill48, str]:
    kind = _choice(line.words[1], "the yield criterion", ("vonmises", "hill48"))
    if kind == "vonmises":
        _arity(line, "yield vonmises", 1)
        return Hill48.von_mises(), "von Mises"
    keys = line.words[2::2]
    try:
        if "r0" in keys or "r45" in keys or "r90" in keys:
            form = "yield hill48 r0 VALUE r45 VALUE r90 VALUE"
            v = _pairs(line, 2, ("r0", "r45", "r90"), ("r0", "r45", "r90"), form)
            r = {k: _float(v[k], k, gt=0) for k in ("r0", "r45", "r90")}
            hill = Hill48.from_r_values(r["r0"], r["r45"], r["r90"])
            text = f"Hill'48 from r0 = {r['r0']:g}, r45 = {r['r45']:g}, r90 = {r['r90']:g}"
        else:
            form = "yield hill48 F VALUE G VALUE H VALUE [L VALUE M VALUE] N VALUE"
            v = _pairs(line, 2, ("F", "G", "H", "L", "M", "N"), ("F", "G", "H", "N"), form)
            c = {k: _float(x, f"Hill48 {k}") for k, x in v.items()}
            hill = Hill48(**c)
            text = "Hill'48 " + ", ".join(f"{k} = {x:g}" for k, x in c.items())
            r = {k: hill.H / d for k, d in (("r0", hill.G), ("r90", hill.F)) if d > 0}
    except (ValueError, TypeError) as error:
        raise _Bad(str(error)) from None
    large = {k: x for k in "FGHLMN" if (x := getattr(hill, k)) > MAX_HILL}
    if large:
        raise _Bad(f"Hill'48 {', '.join(f'{k} = {x:.3g}' for k, x in large.items())} above "
                   f"{MAX_HILL:g}: a yield stress below a tenth of the hardening law's along "
                   "an axis (coefficients are normalized so that G + H = 1 for the rolling "
                   "direction)")
    low, high = R_VALUE_RANGE
    odd = {k: x for k, x in r.items() if not low <= x <= high}
    if odd:
        listed = ", ".join(f"{k} = {x:.3g}" for k, x in odd.items())
        deck.warn(line.number, f"Lankford coefficient(s) {listed} outside {low:g} to "
                  f"{high:g} (sheet metals: about 0.2 to 3)")
    return hill, text


def _hardening(line: _Line) -> Swift | Voce:
    kind = _choice(line.words[1], "the hardening law", ("swift", "voce"))
    try:
        if kind == "swift":
            v = _pairs(line, 2, ("K", "eps0", "n"), ("K", "eps0", "n"),
                       "hardening swift K VALUE eps0 VALUE n VALUE")
            law = Swift(_float(v["K"], "Swift K", gt=0),
                        _float(v["eps0"], "Swift eps0", gt=0, le=MAX_EPS0),
                        _float(v["n"], "Swift n", ge=0, le=1))
            initial = law.K * law.eps0**law.n
            if not initial <= MAX_STRESS:
                raise _Bad(f"the initial yield stress K eps0^n = {initial:.3g} MPa is beyond "
                           f"{MAX_STRESS:g} MPa: K or eps0 is not in MPa or not a strain")
            return law
        v = _pairs(line, 2, ("Y0", "Q", "b"), ("Y0", "Q", "b"),
                   "hardening voce Y0 VALUE Q VALUE b VALUE")
        return Voce(_float(v["Y0"], "Voce Y0", gt=0, le=MAX_STRESS),
                    _float(v["Q"], "Voce Q", ge=0, le=MAX_STRESS),
                    _float(v["b"], "Voce b", ge=0, le=1e6))
    except (ValueError, TypeError) as error:
        raise _Bad(str(error)) from None


# ----------------------------------------------------------------------------------- tools


@dataclass
class _ToolDraft:
    name: str
    line: int
    values: dict[str, Any] = field(default_factory=dict)
    seen: dict[str, int] = field(default_factory=dict)
    model: Any = None


_TOOL_KEYS = ("description", "file", "friction", "contact", "augmentation")
_TOOL_REQUIRED = ("description", "file", "friction", "contact")
_DESCRIPTIONS = ("bezier", "nagata", "facets")


def _parse_tools(deck: _Deck) -> list[_ToolDraft]:
    tools: list[_ToolDraft] = []
    names: dict[str, int] = {}
    tool: _ToolDraft | None = None
    for line in deck.lines:
        key, w = line.key, line.words
        try:
            if key == "tool":
                _arity(line, "tool NAME", 1)
                if tool is not None:
                    deck.error(tool.line, f"tool '{tool.name}' is not closed: expected 'end' "
                               f"before the next 'tool' (line {line.number})")
                    _finish_tool(deck, tool)
                tool = _ToolDraft(_name(w[1], "the tool"), line.number)
                if tool.name in names:
                    deck.error(line.number, f"tool '{tool.name}' defined twice (first at line "
                               f"{names[tool.name]})")
                names.setdefault(tool.name, line.number)
                tools.append(tool)
            elif key == "end":
                _arity(line, "end", 0)
                if tool is None:
                    raise _Bad("'end' without a 'tool NAME' to close")
                _finish_tool(deck, tool)
                tool = None
            elif key in _TOOL_KEYS:
                if tool is None:
                    raise _Bad(f"'{key}' belongs inside a tool: expected 'tool NAME' ... 'end' "
                               "around it")
                if not _once(deck, tool.seen, line):
                    continue
                if key == "description":
                    _arity(line, "description bezier|nagata|facets", 1)
                    tool.values[key] = _choice(w[1], "the description", _DESCRIPTIONS)
                elif key == "file":
                    _arity(line, "file PATH", 1)
                    path = Path(w[1])
                    tool.values[key] = path if path.is_absolute() else deck.path.parent / path
                elif key == "augmentation":
                    _arity(line, "augmentation R", 1)
                    tool.values[key] = _float(w[1], "the augmentation parameter", gt=0)
                elif key == "friction":
                    _arity(line, "friction MU", 1)
                    mu = _float(w[1], "friction", ge=0)
                    if mu > 1:
                        deck.warn(line.number, f"friction coefficient {mu:g} is above 1")
                    tool.values[key] = mu
                else:
                    _arity(line, "contact top|bottom|facing NX NY NZ", 1, 4)
                    side = _choice(w[1], "the contact side", ("top", "bottom", "facing"))
                    if side == "facing":
                        _arity(line, "contact facing NX NY NZ", 4)
                        tool.values[key] = (side, _unit(w[2:], "the facing direction"))
                    else:
                        _arity(line, f"contact {side}", 1)
                        tool.values[key] = (side, None)
            else:
                where = "in a tool" if tool is not None else "at the top of tools.dat"
                raise _Bad(f"unknown keyword {_show(key)} {where}: expected "
                           + ("description, file, friction, contact, augmentation or end" if tool
                   else "tool"))
        except _Bad as bad:
            deck.error(line.number, str(bad))
    if tool is not None:
        deck.error(tool.line, f"tool '{tool.name}' is not closed: expected 'end' before the "
                   "end of the file")
    if not tools and not deck.errors:
        deck.error(None, "no tool: expected at least one 'tool NAME' ... 'end' block")
    return tools


def _finish_tool(deck: _Deck, tool: _ToolDraft) -> None:
    """Check a closed tool block: required keywords, the file and its description."""
    forms = {"description": "description bezier|nagata|facets", "file": "file PATH",
             "friction": "friction MU",
             "contact": "contact top|bottom|facing NX NY NZ (the blank surface it touches)"}
    for key in _TOOL_REQUIRED:
        if key not in tool.seen:
            extra = " (a tool with no contact partner)" if key == "contact" else ""
            deck.error(tool.line, f"tool '{tool.name}' has no '{key}'{extra}: expected "
                       f"'{forms[key]}'")
    path = tool.values.get("file")
    if path is None:
        return
    line = tool.seen["file"]
    if not path.is_file():
        deck.error(line, f"tool file {path} not found")
        return
    try:
        from ddpy import toolfile
    except ImportError:  # the tool file reader is not part of this build
        return
    try:
        model = toolfile.read_tool(path)
    except Exception as error:  # ToolFileError, or anything a broken file provokes
        kind = "" if isinstance(error, ValueError) else f"{type(error).__name__}: "
        deck.error(line, f"cannot read tool file: {kind}{error}")
        return
    description = tool.values.get("description")
    if description is not None and description != model.description and not (
            description == "facets" and model.description == "nagata"):
        deck.error(tool.seen["description"], f"description {description}, but {path.name} is a "
                   f"{model.description} tool file (a nagata file may also be used as facets)")
        return
    tool.model = model


# ----------------------------------------------------------------------------------- cross


class _Cross:
    """Checks across decks and the build of the Case."""

    def __init__(self, decks: dict[str, _Deck], folder: Path) -> None:
        self.decks = decks
        self.folder = folder
        self.control = decks["control.dat"]
        self.bc = decks["bc.dat"]
        self.tools_deck = decks["tools.dat"]
        self.mesh_deck = decks["mesh.dat"]

    def build(self, control: _ControlDraft, mesh: Mesh, mesh_sets: dict[str, NDArray[np.int64]],
              bc: _BcDraft, material: BlankMaterial, tool_drafts: list[_ToolDraft]
              ) -> Case | None:
        tools = self._tools(tool_drafts, mesh)
        phases = self._phases(control, {t.name: t for t in tools}, mesh)
        boundary = self._boundary(bc, mesh, mesh_sets, [p.name for p in control.phases])
        if any(d.errors for d in self.decks.values()) or boundary is None:
            return None
        self._springback_constraints(phases, control, boundary, mesh)
        used = {name for p in phases for name in p.tools}
        # Only a tool that sets its augmentation needs the blank's stiffness to compare it with.
        stiffness = blank_stiffness(mesh.nodes, mesh.elements, material.material.E) \
            if mesh.elements.size and any("augmentation" in d.values for d in tool_drafts) \
            else 0.0
        for t, draft in zip(tools, tool_drafts, strict=True):
            if t.name not in used:
                self.tools_deck.warn(draft.line, f"tool '{t.name}' is active in no phase")
            r = draft.values.get("augmentation")
            if r is not None and stiffness > 0.0 and not 1e-3 <= r / stiffness <= 1e3:
                self.tools_deck.warn(draft.seen["augmentation"], f"augmentation {r:g} N/mm is "
                                     f"{r / stiffness:.3g} times the blank's stiffness E t^2 / "
                                     f"h = {stiffness:.4g} N/mm (the default): far from it, "
                                     "contact states flip on tiny gaps or forces")
        title = control.title or self.folder.resolve().name
        warnings = tuple(w for d in self.decks.values() for w in d.warnings)
        return Case(self.folder, Control(title, tuple(phases), str(self.control.path)), mesh,
                    boundary, material, tuple(tools), warnings)

    # tools ----------------------------------------------------------------------------------

    def _tools(self, drafts: list[_ToolDraft], mesh: Mesh) -> list[Tool]:
        tools = []
        normal = np.array(mesh.normal)
        for d in drafts:
            side, facing = d.values["contact"]
            if side == "top":
                facing = tuple(normal)
            elif side == "bottom":
                facing = tuple(-normal)
            tool = Tool(d.name, d.values["description"], d.values["file"],
                        d.values["friction"], side if side != "facing" else
                        "surface facing (" + ", ".join(f"{c:.3g}" for c in facing) + ")",
                        facing, d.values.get("augmentation"), self.tools_deck.where(d.line))
            if d.model is not None:
                object.__setattr__(tool, "_model", d.model)
            if tool.contact_nodes(mesh).size == 0:
                self.tools_deck.error(d.seen["contact"], f"tool '{d.name}' has no contact "
                                      f"partner: no boundary face of the blank faces "
                                      f"({', '.join(f'{c:.3g}' for c in facing)})")
            tools.append(tool)
        return tools

    # phases ---------------------------------------------------------------------------------

    def _phases(self, control: _ControlDraft, tools: dict[str, Tool], mesh: Mesh
                ) -> list[Phase]:
        deck = self.control
        names: dict[str, int] = {}
        phases = []
        thickness = blank_thickness(mesh)
        for p in control.phases:
            if p.name in names:
                deck.error(p.line, f"phase '{p.name}' defined twice (first at line "
                           f"{names[p.name]})")
                continue
            names[p.name] = p.line
            if not phases and p.kind == "springback":
                deck.error(p.line, f"the first phase '{p.name}' is a springback phase: there is "
                           "nothing to release yet (expected a forming phase first)")
                continue
            phase = (self._springback(p, control) if p.kind == "springback"
                     else self._forming(p, control, tools, thickness))
            if phase is not None:
                phases.append(phase)
        return phases

    def _setting(self, p: _PhaseDraft, control: _ControlDraft, key: str, default: Any) -> Any:
        if key in p.settings:
            return p.settings[key][0]
        if key in control.settings:
            return control.settings[key][0]
        return default

    def _common(self, p: _PhaseDraft, control: _ControlDraft) -> dict[str, Any]:
        s = lambda key, default: self._setting(p, control, key, default)  # noqa: E731
        r, n = RminLimits(), Newton()
        return dict(
            rmin=RminLimits(s("rmin_yield", r.yield_tolerance), s("rmin_strain", r.strain),
                            s("rmin_rotation", r.rotation), s("rmin_contact", r.contact),
                            s("rmin_release", r.release_share),
                            s("rmin_release_redos", r.release_redos)),
            newton=Newton(s("newton_force", n.force_tolerance),
                          s("newton_displacement", n.displacement_tolerance),
                          s("max_iterations", n.max_iterations), s("cutback", n.cutback)),
            output_every=s("output_every", DEFAULT_OUTPUT_EVERY),
            origin=self.control.where(p.line))

    def _springback(self, p: _PhaseDraft, control: _ControlDraft) -> Phase | None:
        deck = self.control
        wrong = [k for k in ("tools", "move", "gap", "lead", "output_at") if k in p.seen]
        wrong += [k for k in ("max_increment", "min_increment") if k in p.settings]
        lines = [p.seen.get(k) or p.settings[k][1] for k in wrong]
        if p.moves:
            wrong.append("move")
            lines.append(p.moves[0][2])
        if p.gaps:
            wrong.append("gap")
            lines.append(p.gaps[0][3])
        if wrong:
            deck.error(lines[0], f"phase '{p.name}' is a springback phase: the tools are removed,"
                       f" so '{wrong[0]}' does not apply (expected only 'increments' and solver "
                       "settings)")
            return None
        increments = p.increments[0] if p.increments else 1
        return Phase(p.name, "springback", increments=increments, **self._common(p, control))

    def _forming(self, p: _PhaseDraft, control: _ControlDraft, tools: dict[str, Tool],
                 thickness: float | None) -> Phase | None:
        deck = self.control
        errors_before = len(deck.errors)
        if p.increments is not None:
            deck.error(p.increments[1], f"'increments' applies to springback phases; phase "
                       f"'{p.name}' is a forming phase (its increments follow max_increment)")
        if not p.tools:
            deck.error(p.line, f"phase '{p.name}' has no active tool: expected 'tools TOOL...'")
            return None
        for name in p.tools:
            if name not in tools:
                deck.error(p.tools_line, f"unknown tool '{name}' in phase '{p.name}': tools.dat "
                           f"defines {', '.join(tools) or 'none'}")
        active = set(p.tools)
        motions: list[Move | HoldGap] = []
        moved: dict[str, int] = {}
        for tool, vector, line in p.moves:
            if self._motion_target(p, tool, line, active, tools, moved):
                motions.append(Move(tool, vector, deck.where(line)))
        for tool, other, gap, line in p.gaps:
            if not self._motion_target(p, tool, line, active, tools, moved):
                continue
            if other not in active:
                what = "an unknown tool" if other not in tools else "not active in the phase"
                deck.error(line, f"phase '{p.name}': gap partner '{other}' is {what}: expected "
                           f"one of the tools of the phase ({', '.join(p.tools)})")
                continue
            a, b = tools[tool].facing, tools[other].facing
            if float(np.dot(a, b)) > -0.5:
                deck.error(line, f"phase '{p.name}': '{tool}' and '{other}' touch the same side "
                           "of the blank: a gap is held between tools on opposite sides")
                continue
            if thickness is not None and gap < thickness * (1 - 1e-6):
                deck.error(line, f"phase '{p.name}': gap {gap:g} mm is smaller than the blank "
                           f"thickness {thickness:.4g} mm")
                continue
            motions.append(HoldGap(tool, other, gap, deck.where(line)))
        gaps = {m.tool: m.other for m in motions if isinstance(m, HoldGap)}
        for start in gaps:
            seen, tool = {start}, gaps[start]
            while tool in gaps:
                if tool in seen:
                    deck.error(moved[start], f"phase '{p.name}': the gaps of {sorted(seen)} "
                               "refer to each other in a loop: one of them must move or stay")
                    break
                seen.add(tool)
                tool = gaps[tool]
            else:
                continue
            break
        if len(deck.errors) > errors_before:
            return None
        moving = [m for m in motions if isinstance(m, Move) and m.travel > 0]
        if not moving:
            deck.error(p.line, f"phase '{p.name}' moves no tool: expected a 'move TOOL DX DY DZ' "
                       "with a non-zero displacement")
            return None
        if p.lead is not None:
            lead, line = p.lead
            if lead not in {m.tool for m in moving}:
                deck.error(line, f"phase '{p.name}': lead tool '{lead}' must be a tool that "
                           f"moves in the phase ({', '.join(m.tool for m in moving)})")
                return None
        else:
            lead = max(moving, key=lambda m: m.travel).tool
        travel = next(m.travel for m in moving if m.tool == lead)
        max_inc = self._setting(p, control, "max_increment",
                                travel * DEFAULT_INCREMENT_FRACTION)
        min_inc = self._setting(p, control, "min_increment", max_inc * DEFAULT_MIN_FRACTION)
        line = self._line_of(p, control, "min_increment") or p.line
        if min_inc > max_inc:
            deck.error(line, f"phase '{p.name}': min_increment {min_inc:g} mm exceeds "
                       f"max_increment {max_inc:g} mm")
            return None
        if travel / max_inc > MAX_INCREMENTS:
            deck.error(self._line_of(p, control, "max_increment") or p.line,
                       f"phase '{p.name}': max_increment {max_inc:g} mm would take more than "
                       f"{MAX_INCREMENTS:,} increments over the travel {travel:g} mm of the "
                       f"lead tool '{lead}'")
            return None
        if max_inc > travel:
            deck.warn(self._line_of(p, control, "max_increment"), f"phase '{p.name}': "
                      f"max_increment {max_inc:g} mm exceeds the travel {travel:g} mm of the "
                      f"lead tool '{lead}'")
        output_at: tuple[float, ...] = ()
        if p.output_at is not None:
            values, line = p.output_at
            if values[-1] > travel * (1 + 1e-12):
                deck.error(line, f"phase '{p.name}': output_at {values[-1]:g} mm is beyond the "
                           f"travel {travel:g} mm of the lead tool '{lead}'")
                return None
            output_at = tuple(values)
        return Phase(p.name, "forming", tuple(p.tools), tuple(motions), lead, max_inc, min_inc,
                     output_at=output_at, **self._common(p, control))

    def _motion_target(self, p: _PhaseDraft, tool: str, line: int, active: set[str],
                       tools: dict[str, Tool], moved: dict[str, int]) -> bool:
        deck = self.control
        if tool not in tools:
            deck.error(line, f"unknown tool '{tool}' in phase '{p.name}': tools.dat defines "
                       f"{', '.join(tools) or 'none'}")
            return False
        if tool not in active:
            deck.error(line, f"phase '{p.name}' moves tool '{tool}', which is not active in it: "
                       f"add it to 'tools' (now: {', '.join(p.tools)})")
            return False
        if tool in moved:
            deck.error(line, f"phase '{p.name}': tool '{tool}' already has a motion at line "
                       f"{moved[tool]} (expected one 'move' or 'gap' per tool)")
            return False
        moved[tool] = line
        return True

    @staticmethod
    def _line_of(p: _PhaseDraft, control: _ControlDraft, key: str) -> int | None:
        if key in p.settings:
            return p.settings[key][1]
        if key in control.settings:
            return control.settings[key][1]
        return None

    # boundary conditions --------------------------------------------------------------------

    def _boundary(self, bc: _BcDraft, mesh: Mesh, mesh_sets: dict[str, NDArray[np.int64]],
                  phase_names: list[str]) -> BoundaryConditions | None:
        deck = self.bc
        tol = bc.tolerance[0] if bc.tolerance else 1e-4
        x = mesh.nodes
        if bc.tolerance and mesh.elements.size:
            # A tolerance that reaches the next row of nodes selects it too (100 mm fixed
            # every node of a blank).
            pairs = HEX_EDGES.reshape(-1, 2)
            edges = np.linalg.norm(x[mesh.elements[:, pairs[:, 0]]]
                                   - x[mesh.elements[:, pairs[:, 1]]], axis=2)
            shortest = float(edges.min())
            if tol >= 0.5 * shortest:
                deck.error(bc.tolerance[1], f"tolerance {tol:g} mm is not below half the "
                           f"shortest element edge ({shortest:.3g} mm): a plane or box would "
                           "also select the next row of nodes")
                return None
        sets: dict[str, NodeSet] = {}
        lines: dict[str, int] = {}
        for name, nodes in mesh_sets.items():
            sets[name] = NodeSet(name, nodes, f"{mesh.source} (node set of the mesh file)")
        for name, kind, args, line in bc.nodesets:
            if name in sets:
                first = f"line {lines[name]}" if name in lines else sets[name].origin
                deck.error(line, f"node set '{name}' defined twice (first at {first})")
                continue
            lines[name] = line
            selected = _guard(deck, line, lambda k=kind, a=args: _select(k, a, mesh, tol))
            if selected is None:
                continue
            if selected.size == 0:
                deck.error(line, f"node set '{name}' ({kind} {' '.join(args)}) selects no node "
                           f"of the mesh (tolerance {tol:g} mm)")
                continue
            sets[name] = NodeSet(name, selected, deck.where(line))
        constraints = []
        for axis, target, line in bc.symmetries:
            if _NAME.fullmatch(target):
                if target not in sets:
                    self._unknown_set(line, target, sets)
                    continue
                nodes, label = sets[target].nodes, f"symmetry {'xyz'[axis]} on {target}"
            else:
                value = float(target)
                nodes = np.flatnonzero(np.abs(x[:, axis] - value) <= tol)
                label = f"symmetry {'xyz'[axis]} = {value:g}"
                if nodes.size == 0:
                    deck.error(line, f"symmetry plane {'xyz'[axis]} = {value:g} holds no node of "
                               f"the mesh (tolerance {tol:g} mm; the blank spans "
                               f"{x[:, axis].min():.4g} to {x[:, axis].max():.4g})")
                    continue
            constraints.append(Constraint(label, nodes, (axis,), (), deck.where(line)))
        for name, comps, phases, line in bc.fixes:
            if name not in sets:
                self._unknown_set(line, name, sets)
                continue
            unknown = [q for q in phases if q not in phase_names]
            if unknown:
                deck.error(line, f"unknown phase '{unknown[0]}': control.dat defines "
                           f"{', '.join(phase_names)}")
                continue
            label = f"fix {name} {''.join('xyz'[c] for c in comps)}"
            constraints.append(Constraint(label, sets[name].nodes, comps, tuple(phases),
                                          deck.where(line)))
        if deck.errors:
            return None
        return BoundaryConditions(sets, tuple(constraints), tol)

    def _unknown_set(self, line: int, name: str, sets: dict[str, NodeSet]) -> None:
        known = ", ".join(sorted(sets)) or "none"
        self.bc.error(line, f"unknown node set '{name}': expected one defined by 'nodeset' "
                      f"before it or in the mesh file (known: {known})")

    def _springback_constraints(self, phases: list[Phase], control: _ControlDraft,
                                boundary: BoundaryConditions, mesh: Mesh) -> None:
        for p in phases:
            if not p.is_springback:
                continue
            free = rigid_body_modes_free(mesh.nodes, boundary.dofs(p.name))
            if free:
                line = next(d.line for d in control.phases if d.name == p.name)
                self.control.error(line, f"springback phase '{p.name}' removes the tools, and the "
                                   f"constraints of bc.dat leave rigid-body motion free ("
                                   f"{', '.join(free)}): fix more components in that phase, "
                                   f"e.g. 'fix NODESET COMPONENTS phase {p.name}'")


def _select(kind: str, args: list[str], mesh: Mesh, tol: float) -> NDArray[np.int64]:
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
            raise _Bad(f"the ids list more nodes than the mesh has ({mesh.n_nodes})")
        parts.append(np.arange(first, last + 1))
    ids = np.concatenate(parts)
    index = mesh.index(ids)
    if (index < 0).any():
        missing = ids[index < 0]
        raise _Bad(f"node {missing[0]} is not in the mesh"
                   + (f" (and {missing.size - 1} more ids)" if missing.size > 1 else ""))
    return index.astype(np.int64)


