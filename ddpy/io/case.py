"""The validated model of a case: what a run needs, built by :mod:`ddpy.io.decks` from a folder of
plain-text decks (docs/input-format.md). Units mm, N, MPa, s.

Everything here has been checked by the parser: the solver may trust it. Arrays are read-only;
node and element indices are 0-based (``HexMesh.node_ids`` keeps the labels of the deck for
messages). ``origin`` fields say where a value was read (``control.dat:12``).

>>> from ddpy.io.decks import read_case
>>> case = read_case("examples/bending")                    # doctest: +SKIP
>>> phase = case.control.phases[0]                          # doctest: +SKIP
>>> phase.displacement("punch"), case.tool("punch").friction  # doctest: +SKIP
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy.model.control import FormingTuning, IncrementLimits, NewtonSettings
from ddpy.model.forming_limits import FormingLimitCurve
from ddpy.model.material import Material
from ddpy.model.mesh import HEX_FACES, HexMesh
from ddpy.model.solid import DEFAULT_ELEMENT
from ddpy.model.tool import BARRIER_DEPTH, FACE_POINTS

if TYPE_CHECKING:
    from ddpy.io.toolfile import ToolModel

__all__ = ["AXES", "BlankMaterial", "BoundaryConditions", "Case", "Constraint", "Control",
           "DeckError", "HoldForce", "HoldGap", "Move", "NodeSet", "Phase",
           "Tool", "HEX_FACES", "blank_thickness", "longest_travel", "summarize_alike"]

#: Axis names and their index.
AXES = {"x": 0, "y": 1, "z": 2}



def _frozen(array: ArrayLike, dtype: type) -> NDArray:
    out = np.array(array, dtype=dtype)
    out.flags.writeable = False
    return out


# ----------------------------------------------------------------------------------- mesh


class DeckError(ValueError):
    """Bad input in a case folder. ``path`` and ``line`` locate the (first) error, ``line`` is
    None for a whole file; ``errors`` holds every error found (each a DeckError)."""

    def __init__(self, message: str, path: str | Path | None = None, line: int | None = None,
                 errors: tuple[DeckError, ...] = ()) -> None:
        self.path = Path(path) if path is not None else None
        self.line = line
        self.message = message
        self.errors: tuple[DeckError, ...] = errors or (self,)
        super().__init__(str(self))

    @property
    def location(self) -> str:
        if self.path is None:
            return ""
        return f"{self.path}:{self.line}" if self.line is not None else str(self.path)

    def __str__(self) -> str:
        if len(self.errors) > 1:
            return "\n".join(str(e) for e in self.errors)
        return f"{self.location}: {self.message}" if self.path is not None else self.message

    @classmethod
    def collect(cls, errors: list[DeckError]) -> DeckError:
        """One error standing for several (located at the first)."""
        if len(errors) == 1:
            return errors[0]
        first = errors[0]
        return cls(first.message, first.path, first.line, tuple(errors))


#: Longest travel of a tool in a phase, in extents of the model along the motion (the box
#: around the blank and every tool where they start): a punch moved by 1,000 mm over a
#: model 45 mm high ran 8,772 increments.
MAX_TRAVEL_EXTENTS = 10.0


def longest_travel(displacement: ArrayLike, low: ArrayLike, high: ArrayLike) -> float:
    """The longest travel (mm) allowed a tool moving along ``displacement`` in a model whose
    box is ``low`` to ``high`` (the blank and the tools where they start):
    MAX_TRAVEL_EXTENTS times the box's extent along the motion."""
    d = np.asarray(displacement, dtype=float)
    direction = d / np.linalg.norm(d)
    extent = float(np.abs(direction) @ (np.asarray(high, float) - np.asarray(low, float)))
    return MAX_TRAVEL_EXTENTS * extent


def summarize_alike(warnings: list[str], alike: str, keep: int = 3) -> list[str]:
    """Warnings of one kind (one per phase, say) as the user reads them: the first ``keep``
    as they are, the rest in one line that counts them (``alike`` says what they share), so
    that a case of many phases does not print as many lines."""
    if len(warnings) <= keep + 1:
        return list(warnings)
    return [*warnings[:keep], f"{warnings[keep]} (and {len(warnings) - keep - 1:,} more "
            f"{alike})"]


# ------------------------------------------------------------------------- boundary conditions


def blank_thickness(mesh: HexMesh) -> float | None:
    """Smallest initial thickness of a layered blank (mm); its extent along the normal else
    (HexMesh.initial_thickness); None for a flat one."""
    return mesh.initial_thickness() or None


@dataclass(frozen=True, eq=False)
class NodeSet:
    """A named set of nodes (0-based indices, sorted, unique)."""

    name: str
    nodes: NDArray[np.int32]
    origin: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "nodes", _frozen(np.unique(self.nodes), np.int32))


@dataclass(frozen=True, eq=False)
class Constraint:
    """Zero displacement of ``components`` (0 = x, 1 = y, 2 = z) at ``nodes``, in the phases
    named (all phases when empty). ``label`` says what it is: ``symmetry x = 0``,
    ``fix centre z``."""

    label: str
    nodes: NDArray[np.int32]
    components: tuple[int, ...]
    phases: tuple[str, ...] = ()
    origin: str = ""
    symmetry: bool = False  # a symmetry plane (bc.dat 'symmetry'), normal to its component

    def __post_init__(self) -> None:
        object.__setattr__(self, "nodes", _frozen(np.unique(self.nodes), np.int32))

    def applies(self, phase: str) -> bool:
        return not self.phases or phase in self.phases


@dataclass(frozen=True, eq=False)
class BoundaryConditions:
    """Node sets and zero-displacement constraints (symmetry planes, fixed nodes)."""

    nodesets: Mapping[str, NodeSet] = field(default_factory=dict)
    constraints: tuple[Constraint, ...] = ()
    tolerance: float = 1e-4

    @property
    def symmetry_axes(self) -> str:
        """The normal axis of each symmetry plane, in bc.dat's order ("xy" for a quarter
        model with planes x = 0 and y = 0)."""
        return "".join("xyz"[c.components[0]] for c in self.constraints if c.symmetry)

    def constrained(self, phase: str) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
        """Nodes and components held at zero displacement in ``phase``: two arrays of equal
        length, unique (node, component) pairs sorted by degree of freedom."""
        dofs = self.dofs(phase)
        return (dofs // 3).astype(np.int32), (dofs % 3).astype(np.int32)

    def dofs(self, phase: str) -> NDArray[np.int64]:
        """Sorted global degrees of freedom (3 node + component) held at zero in ``phase``."""
        parts = [(c.nodes[:, None].astype(np.int64) * 3 + np.array(c.components)).ravel()
                 for c in self.constraints if c.applies(phase)]
        if not parts:
            return np.zeros(0, dtype=np.int64)
        return np.unique(np.concatenate(parts))


def rigid_body_modes_free(nodes: NDArray[np.float64], dofs: NDArray[np.int64]) -> list[str]:
    """The rigid-body motions of the blank that the constrained ``dofs`` leave free, described
    in words (empty when all six are stopped)."""
    centre = nodes.mean(axis=0)
    size = max(float(np.ptp(nodes, axis=0).max()), 1e-12)
    r = (nodes - centre) / size
    modes = np.zeros((nodes.shape[0], 3, 6))
    for k in range(3):
        modes[:, k, k] = 1.0
    # rotation about axis a: u = e_a x r
    modes[:, 1, 3], modes[:, 2, 3] = -r[:, 2], r[:, 1]
    modes[:, 0, 4], modes[:, 2, 4] = r[:, 2], -r[:, 0]
    modes[:, 0, 5], modes[:, 1, 5] = -r[:, 1], r[:, 0]
    rows = modes.reshape(-1, 6)[dofs]
    gram = rows.T @ rows
    values, vectors = np.linalg.eigh(gram)
    scale = max(float(values.max()), 1.0)
    free = []
    for value, vector in zip(values, vectors.T, strict=True):
        if value > 1e-10 * scale:
            continue
        t, w = vector[:3], vector[3:]
        if np.linalg.norm(t) >= np.linalg.norm(w):
            free.append(f"translation along {_direction_words(t)}")
        else:
            free.append(f"rotation about {_direction_words(w)}")
    return free


def _direction_words(v: NDArray[np.float64]) -> str:
    v = v / np.linalg.norm(v)
    axis = int(np.argmax(np.abs(v)))
    if abs(v[axis]) > 0.999:
        return "xyz"[axis]
    return "(" + ", ".join(f"{c:.2f}" for c in v) + ")"


# ----------------------------------------------------------------------------------- material


@dataclass(frozen=True)
class BlankMaterial:
    """The material of the blank (:class:`ddpy.model.material.Material`) and the rolling direction:
    ``rolling_angle`` degrees in the sheet plane from the first in-plane axis after the normal
    axis in the order x, y, z (from x towards y when the normal is z)."""

    material: Material
    rolling_angle: float = 0.0
    yield_input: str = "von Mises"
    origin: str = ""
    forming_limit: FormingLimitCurve | None = None  # material.dat's table; None: Keeler-Brazier

    def axes(self, normal: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> NDArray[np.float64]:
        """Rows RD, TD, ND of the material axes in global coordinates (a rotation matrix)."""
        nd = np.asarray(normal, dtype=float)
        axis = int(np.argmax(np.abs(nd)))
        a1 = np.eye(3)[(axis + 1) % 3]
        a2 = np.cross(nd, a1)
        angle = math.radians(self.rolling_angle)
        rd = math.cos(angle) * a1 + math.sin(angle) * a2
        return np.array([rd, np.cross(nd, rd), nd])


# ----------------------------------------------------------------------------------- tools


@dataclass(frozen=True)
class Tool:
    """A rigid tool: its description (bezier, nagata or facets), its tool file, the Coulomb
    friction coefficient, the side of the blank it touches (``side``: top, bottom or a
    surface facing a direction, tools.dat's ``contact``; ``facing``: the outward normal of
    that blank surface), the augmentation
    parameter r of its contact law, N/mm (None: the solver chooses it), and its contact
    discretization (``discretization``: "node", node-to-surface, "surface",
    surface-to-surface, or "gauss", Gauss-point contact) with its penalty, N/mm^3 (None:
    the solver chooses it), Gauss points per direction of a blank face (``points``) and,
    for "gauss", its barrier depth (a fraction of the blank's thickness, default
    BARRIER_DEPTH; None: off)."""

    name: str
    description: Literal["bezier", "nagata", "facets"]
    file: Path
    friction: float
    side: str
    facing: tuple[float, float, float]
    augmentation: float | None = None
    origin: str = ""
    discretization: str = "gauss"
    penalty: float | None = None
    points: int | None = None
    barrier: float | None = BARRIER_DEPTH

    @property
    def face_points(self) -> int | None:
        """Gauss points per direction of a blank face as the solver takes them (the deck's
        ``points`` or the default of the discretization); None for node-to-surface."""
        if self.discretization == "node":
            return None
        return self.points or FACE_POINTS[self.discretization]

    def model(self) -> ToolModel:
        """The tool model read from the file (ddpy.io.toolfile); a Nagata file used with
        description facets gives its facets (same mesh, flat patches)."""
        model = self.__dict__.get("_model")  # read once while the decks were checked
        if model is None:
            from ddpy.io.toolfile import read_tool

            model = read_tool(self.file)
        if self.description == "facets" and model.description == "nagata":
            return model.facets()
        return model

    def contact_nodes(self, mesh: HexMesh) -> NDArray[np.int32]:
        """The blank nodes this tool can touch: nodes of the boundary faces facing it."""
        return mesh.surface_nodes(self.facing)


# ----------------------------------------------------------------------------------- control

@dataclass(frozen=True)
class Move:
    """``tool`` moves by ``displacement`` (mm) over the phase, in straight line."""

    tool: str
    displacement: tuple[float, float, float]
    origin: str = ""

    @property
    def travel(self) -> float:
        return math.hypot(*self.displacement)


@dataclass(frozen=True)
class HoldGap:
    """``tool`` is held at ``gap`` mm from ``other`` along the sheet normal: at the start of
    the phase it is placed so that the distance between its surface and the other's, measured
    along the sheet normal where they face each other, is ``gap``; then it follows the
    other's motion (a position-controlled blank-holder)."""

    tool: str
    other: str
    gap: float
    origin: str = ""


@dataclass(frozen=True)
class HoldForce:
    """``tool`` presses on the blank with ``force`` N along its axis (minus its facing
    direction, towards the blank) instead of following a motion: a force-controlled
    blank-holder. Its displacement along the axis is solved for; with ``ramp`` the force
    grows from 0 at the start of the phase to ``force`` at its end, else it holds from the
    first increment (docs/input-format.md, control.dat ``force``)."""

    tool: str
    force: float
    ramp: bool = False
    origin: str = ""

    def at(self, fraction: float) -> float:
        """The force at ``fraction`` of the phase (N)."""
        return self.force * fraction if self.ramp else self.force


@dataclass(frozen=True)
class Phase:
    """One stage of the process.

    Forming: the ``tools`` listed are active (the others are switched off), each fixed unless
    it has a :class:`Move`, a :class:`HoldGap` or a :class:`HoldForce`; increments are
    measured as travel of the
    ``lead`` tool, at most ``max_increment`` and at least ``min_increment`` mm. Springback:
    no tool; the contact forces of the previous phase are released in ``increments`` equal
    steps. Fields are written every ``output_every`` increments (0: never), at each travel
    of ``output_at`` and at the end of the phase."""

    name: str
    kind: Literal["forming", "springback"]
    tools: tuple[str, ...] = ()
    motions: tuple[Move | HoldGap | HoldForce, ...] = ()
    lead: str | None = None
    max_increment: float = 0.0
    min_increment: float = 0.0
    limits: IncrementLimits = IncrementLimits()
    newton: NewtonSettings = NewtonSettings()
    output_every: int = 10
    output_at: tuple[float, ...] = ()
    increments: int = 1
    origin: str = ""

    @property
    def is_springback(self) -> bool:
        return self.kind == "springback"

    def motion(self, tool: str) -> Move | HoldGap | HoldForce | None:
        """The motion of an active tool (None: fixed)."""
        for m in self.motions:
            if m.tool == tool:
                return m
        return None

    def displacement(self, tool: str) -> NDArray[np.float64]:
        """Prescribed displacement of a tool over the phase (zero when fixed or inactive;
        a gap-held tool follows its partner: the partner's displacement; a force-controlled
        tool's is solved for: zero here)."""
        m = self.motion(tool)
        if isinstance(m, Move):
            return np.array(m.displacement)
        if isinstance(m, HoldGap):
            return self.displacement(m.other)
        return np.zeros(3)

    @property
    def travel(self) -> float:
        """Travel of the lead tool over the phase, mm (0 for springback)."""
        m = self.motion(self.lead) if self.lead else None
        return m.travel if isinstance(m, Move) else 0.0


@dataclass(frozen=True)
class Control:
    """Title and phases, in order, and the run's tuning (control.dat's ``tune`` lines; the
    defaults without them)."""

    title: str
    phases: tuple[Phase, ...]
    origin: str = ""
    tuning: FormingTuning = FormingTuning()

    def phase(self, name: str) -> Phase:
        for p in self.phases:
            if p.name == name:
                return p
        raise KeyError(f"no phase named {name!r}: phases are {[p.name for p in self.phases]}")


# ----------------------------------------------------------------------------------- case


@dataclass(frozen=True, eq=False)
class Case:
    """A validated case: control and phases, blank mesh, boundary conditions, material and
    tools. ``warnings`` lists what is legal but suspicious; ``element`` is the blank's
    element (ddpy.model.solid.ELEMENTS)."""

    folder: Path
    control: Control
    mesh: HexMesh
    boundary: BoundaryConditions
    material: BlankMaterial
    tools: tuple[Tool, ...]
    warnings: tuple[str, ...] = ()
    element: str = DEFAULT_ELEMENT

    @property
    def title(self) -> str:
        return self.control.title

    @property
    def phases(self) -> tuple[Phase, ...]:
        return self.control.phases

    @property
    def tool_names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.tools)

    def tool(self, name: str) -> Tool:
        for t in self.tools:
            if t.name == name:
                return t
        raise KeyError(f"no tool named {name!r}: tools are {list(self.tool_names)}")

    def summary(self) -> str:
        """A few lines that say what the case is."""
        m, mat = self.mesh, self.material.material
        lo, hi = m.bounds()
        size = " x ".join(f"{v:.4g}" for v in hi - lo)
        hard = type(mat.hardening).__name__
        if hasattr(mat.hardening, "strains"):
            hard = f"tabulated ({len(mat.hardening.strains)} points)"
        if mat.kinematic is not None:
            hard += (f" and Armstrong-Frederick kinematic (C {mat.kinematic.C:g}, Xsat "
                     f"{mat.kinematic.X_sat:g} MPa)")
        lines = [
            f"case {self.folder}: {self.title}",
            f"  blank: {m.n_nodes} nodes, {m.n_elements} hexahedra, element {self.element} "
            f"({_ELEMENT_NAMES.get(self.element, self.element)}), {size} mm, normal "
            f"{_axis_name(m.normal)} ({m.source})",
            f"  material: E = {mat.E:g} MPa, nu = {mat.nu:g}, {self.material.yield_input}, "
            f"{hard} hardening, initial yield {mat.hardening.initial_yield_stress:.4g} MPa, "
            f"rolling direction {self.material.rolling_angle:g} deg"
            + (f", forming limit {self.material.forming_limit.describe()}"
               if self.material.forming_limit is not None else ""),
            f"  boundary: {len(self.boundary.nodesets)} node sets, "
            f"{len(self.boundary.constraints)} constraints"
            + (f", symmetry planes normal to {' and '.join(self.boundary.symmetry_axes)}"
               if self.boundary.symmetry_axes else ""),
        ]
        for t in self.tools:
            lines.append(f"  tool {t.name}: {t.description}, {t.file.name}, friction "
                         f"{t.friction:g}, contacts the {t.side} of the blank, contact "
                         f"discretization {t.discretization} ("
                         + {"surface": "surface-to-surface",
                            "gauss": "Gauss-point contact",
                            "node": "node-to-surface"}[t.discretization]
                         + (f", {t.face_points} x {t.face_points} points per blank face"
                            if t.face_points else "") + ")"
                         + (f", penalty {t.penalty:g} N/mm^3" if t.penalty is not None else "")
                         + (f", barrier at {t.barrier:g} of the thickness"
                            if t.discretization == "gauss" and t.barrier is not None else ""))
        for p in self.phases:
            if p.is_springback:
                lines.append(f"  phase {p.name}: springback in {p.increments} step(s)")
                continue
            moves = ", ".join(_motion_text(mv) for mv in p.motions)
            estimate = math.ceil(p.travel / p.max_increment - 1e-9) if p.max_increment else 0
            lines.append(f"  phase {p.name}: forming with {', '.join(p.tools)}; {moves}; lead "
                         f"{p.lead}, max increment {p.max_increment:g} mm (>= {estimate} "
                         "increments)")
        tuned = _tuned_text(self.control.tuning)
        if tuned:
            lines.append(f"  tuning (control.dat tune): {tuned}")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)


def _tuned_text(tuning: FormingTuning) -> str:
    """The tuning's values that differ from the defaults, as control.dat's tune names them
    ("" when none)."""
    changed = []
    for group, ours, default in (("", tuning, FormingTuning()),
                                 ("increment.", tuning.increment, FormingTuning().increment)):
        for name, value in vars(ours).items():
            if name != "increment" and value != getattr(default, name):
                changed.append(f"{group}{name} {value:g}")
    return ", ".join(changed)


def _motion_text(motion: Move | HoldGap | HoldForce) -> str:
    """A phase's motion of a tool as the case summary says it."""
    if isinstance(motion, Move):
        return f"{motion.tool} by ({', '.join(f'{c:g}' for c in motion.displacement)})"
    if isinstance(motion, HoldGap):
        return f"{motion.tool} at gap {motion.gap:g} from {motion.other}"
    return (f"{motion.tool} pressed on the blank with {motion.force:g} N along its axis "
            + ("(ramped from 0 over the phase)" if motion.ramp else "(from the first "
               "increment)") + ", its position solved for")


#: What the blank's elements are, for the case summary (docs/theory/element_choice.md).
_ELEMENT_NAMES = {"solid-shell": "8-node solid-shell, enhanced strains, free of locking in "
                                 "bending",
                  "hexahedron": "8-node mean-dilatation hexahedron"}


def _axis_name(normal: tuple[float, float, float]) -> str:
    axis = int(np.argmax(np.abs(normal)))
    return ("-" if normal[axis] < 0 else "+") + "xyz"[axis]
