"""Forming: the blank in frictional contact with moving rigid tools, solved in one loop.

DD3IMP's single Newton loop: the nodal displacements and the contact forces of every
(tool, slave node) pair are the unknowns of one generalized Newton-Raphson, whose equations
are the equilibrium of the blank and the Alart-Curnier contact law (ddpy.model.contact). The
Jacobian is exact (material, geometric and tool curvature terms), so it converges
quadratically, also through stick-slip changes. See docs/theory/contact.md.

Example::

    problem = FormingProblem(Solid(mesh, material), [RigidTool("punch", surface, slaves)])
    problem.fix(mesh.select(x=0), "x")                    # symmetry plane
    result = problem.run({"punch": (0, 0, -5.0)}, max_increment=0.1)
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ddpy._validate import float_array, int_array
from ddpy.core.constants import constant
from ddpy.core.linalg import MumpsSolver
from ddpy.core.ordering import mesh_solver
from ddpy.geometry.search import INSIDE, NONE
from ddpy.model.contact import INACTIVE
from ddpy.model.control import (
    FormingTuning,
    IncrementController,
    IncrementLimits,
    NewtonSettings,
    check_max_increment,
)
from ddpy.model.forming_quantities import FieldFrame, SheetMeasures, nodal_average
from ddpy.model.mesh import HEX_EDGES, free_rigid_modes, largest_rotation
from ddpy.model.newton import (
    SEARCH_MONOTONICITY,
    SEARCH_NONE,
    Factors,
    Iteration,
    Layout,
    Loop,
    Pairs,
    ToolPack,
    ToolPlacement,
    Trial,
    contact,
    contact_faces,
    equations,
    face_basis,
    gauss_face_weights,
    increment,
)
from ddpy.model.solid import Solid, SolidState, _components
from ddpy.model.start import blended_start, increment_starts, start_weight
from ddpy.model.tool import RigidTool
from ddpy.model.work import Work

_log = logging.getLogger(__name__)
#: barrier_augmentation's cap as a share of E T, measured (docs/theory/contact.md).
BARRIER_SHARE = 0.1
#: the core's status for single-precision factors too coarse to precondition a Jacobian
_SINGLE_TOO_COARSE = constant("solver_single_too_coarse")
#: A phase's first increment starts from the blank lying on its tools, a degenerate
#: contact set (pairs at g = 0, p = 0) whose path turns on small differences: its possibly
#: last corrections keep Eisenstat and Walker's tenth of the tolerance (a looser one made
#: the built-in case's first increment cut on one process and not on two).
_FIRST_KRYLOV_LAST = 0.1

__all__ = ["RigidTool", "FieldFrame", "FormingProblem", "FormingResult", "FormingError",
           "FormingState", "IncrementRecord",
           "Linearization", "PhaseProgress", "cut_hint", "default_augmentation",
           "barrier_augmentation", "default_penalty",
           "start_depth_limit"]

def _trial(target: float, step: float | None, travel: float) -> str:
    """An increment trial as messages name it: the lead tool's stroke in mm it goes to (and
    its size), or its phase factor in a phase that moves no tool."""
    if travel > 0.0:
        where = f"increment to {target * travel:.4g} mm of the {travel:.4g} mm stroke"
        return where if step is None else f"{where} (step {step * travel:.3g} mm)"
    where = f"increment to phase factor {target:.6g}"
    return where if step is None else f"{where} (step {step:.3g})"


def cut_hint(failure: str) -> str:
    """One thing to try when increments fail for ``failure`` (docs/running.md)."""
    if "changed state" in failure:
        return "contact pairs still open and close at the end: a smaller max_increment where " \
            "the blank first touches a tool, or Gauss-point contact (tools.dat: " \
            "discretization gauss)"
    if failure.startswith("no convergence"):
        return "lower max_increment or raise max_iterations (control.dat)"
    if "inverted" in failure:
        return "an element turns inside out: lower max_increment, or refine the blank where " \
            "it bends"
    if "singular" in failure:
        return "a part of the model is free to move: check the constraints (bc.dat) and that " \
            "every node belongs to an element"
    if "not finite" in failure:
        return "a load or a material value is not a number"
    return "lower max_increment (control.dat)"




@dataclass(frozen=True)
class _Touching:
    """The closed predictor of an increment's first iteration: pairs the law leaves open
    within ``distance`` of their tool close; those of a tool at rest in the increment only
    where the blank needs them (``resting`` False) or all of them (True)."""

    distance: float
    resting: bool = True


def start_depth_limit(strain: float, size: float) -> float:
    """How deep a tool may start inside the blank (mm): what the first increment can push
    a node out by without exceeding the strain limit ``strain`` over an element of mean
    size ``size`` (HexMesh.element_size). ``ddpy check`` and ``FormingProblem.run`` both
    use it, so what the check accepts the run starts."""
    return strain * size


@dataclass(frozen=True)
class Linearization:
    """The forming problem's equations at one point (``FormingProblem.linearization``), as
    the core evaluates them (``ddpy.model.newton.equations``): the residual, free
    equilibrium rows first (``n_free``), then the three contact-law rows of each pair; its
    Jacobian in coordinate form (``rows``, ``cols``: the core's layout; ``values``;
    duplicates add up), as MUMPS reads it; the contact states of the pairs (0 open, 1
    stick, 2 slip); and the node of each unknown."""

    residual: NDArray[np.float64]
    rows: NDArray[np.int32]
    cols: NDArray[np.int32]
    values: NDArray[np.float64]
    state: NDArray[np.int32]
    nodes: NDArray[np.int64]
    n_free: int

    def matrix(self) -> NDArray[np.float64]:
        """The Jacobian as a dense array (small problems: tests and inspection)."""
        n = self.residual.size
        dense = np.zeros((n, n))
        np.add.at(dense, (self.rows, self.cols), self.values)
        return dense


@dataclass
class PhaseProgress:
    """Where a ``FormingProblem.run`` stands after a converged increment: the tool positions
    at the start of the phase, the offsets of gap-held tools, the phase factor reached, the
    next trial increment with what set it, and the last displacement increment and
    pressure change per unit factor and that increment's size. Given back as ``resume``
    (with the problem's state restored) the run continues exactly as it would have."""

    start: dict[str, NDArray[np.float64]]
    offsets: dict[str, tuple[str, NDArray[np.float64]]]
    factor: float
    step: float
    reason: str
    last_du: NDArray[np.float64] | None
    last_dp: NDArray[np.float64] | None = None
    #: the last increment's size (phase factor; None: taken as the next one's)
    last_size: float | None = None
    #: the increment's number (counted over the FormingResult), the phase's name given to
    #: run, and the leading tool's travel since the start of the run's motion (mm)
    increment: int = 0
    phase: str = ""
    travel: float = 0.0
    #: the displacement rate and size of the increment before the last, and the weight of
    #: the next start's blend (``ddpy.model.start``)
    before_du: NDArray[np.float64] | None = None
    before_size: float | None = None
    start_weight: float = 0.0


class FormingError(RuntimeError):
    """A run stopped: ``result`` keeps every increment that converged before."""

    def __init__(self, message: str, result: FormingResult) -> None:
        super().__init__(message)
        self.result = result


@dataclass
class FormingState:
    """What a FormingProblem carries from one converged increment to the next, and so all
    a checkpoint needs of it (``FormingProblem.state``, ``restore``): the blank's
    displacements (n, 3) and its solid state, where each tool is (3,), and per pair its
    contact force (pairs, 3) and the law's state at the last increment (pairs,: 0 open, 1
    stick, 2 slip, which the release control reads); per Gauss point of Gauss-point
    contact its tangential traction (points, 3) and the multiplier of its augmented law
    (points,). Add here any new state of the loop (a checkpoint stores every field)."""

    u: NDArray[np.float64]
    solid: SolidState
    positions: dict[str, NDArray[np.float64]]
    force: NDArray[np.float64]
    contact_state: NDArray[np.int32]
    traction: NDArray[np.float64]
    pressure: NDArray[np.float64]


@dataclass
class IncrementRecord:
    """The fields of one converged increment: the blank's displacements (n, 3) and, per
    tool, the contact state of every slave (0 open, 1 stick, 2 slip). A FormingResult
    keeps the last one (``last``), and every one only when asked (``history``)."""

    displacement: NDArray[np.float64]
    contact_states: dict[str, NDArray[np.int32]] = field(default_factory=dict)


@dataclass
class FormingResult(Work):
    """Converged increments of a run, per increment: the phase factor and the increment
    size (as a fraction of the phase), each tool's displacement and the force the blank
    exerts on it, the nodes in contact per tool and its deepest penetration, Newton
    iterations with the residual norms: small records, kept for every increment. The
    fields of an increment (its displacements and the contact states of the tools' pairs,
    an IncrementRecord) are kept for the last increment (``last``) and, with ``history``,
    for every one (``displacements``, ``contact_states``): a run of many increments on a
    large blank would otherwise hold a copy of its displacements per increment (the runner
    writes each increment to the results file instead). The work of all trials is counted
    as Work: cuts, evaluations, corrections, factorizations, GMRES iterations, fallbacks
    and the seconds of the core's loop (``timings``; the rest of a run's time is the
    caller's to measure: ddpy.app.runner records it per increment)."""

    #: keep every increment's fields (``displacements``, ``contact_states``)
    history: bool = False
    factors: list[float] = field(default_factory=list)
    sizes: list[float] = field(default_factory=list)
    #: what set each increment: "max", "touch", "release", "strain", "rotation", "yield",
    #: "cut" or "regrow" (growing back after a cut, at most doubling per increment)
    limited_by: list[str] = field(default_factory=list)
    tool_displacements: dict[str, list[NDArray[np.float64]]] = field(default_factory=dict)
    tool_forces: dict[str, list[NDArray[np.float64]]] = field(default_factory=dict)
    contacts: dict[str, list[int]] = field(default_factory=dict)
    residuals: list[list[float]] = field(default_factory=list)
    #: per increment and Newton iteration (Iteration), what convergence is judged on: the
    #: residual norm over the force scale and the correction over the increment's
    #: displacement, scaled up to a whole increment's when the increment is smaller (inf
    #: before the first correction); the step's length and what changed in the iteration
    convergence: list[list[Iteration]] = field(default_factory=list)
    #: per tool and increment, the deepest penetration of the blank into the tool (mm, 0
    #: when none): the most negative signed distance of its slave nodes from it (for
    #: node-to-surface contact their gaps; for the others the nodes projected on the tool,
    #: which leaves out the chord of a face over a tool radius between its nodes)
    penetration: dict[str, list[float]] = field(default_factory=dict)
    #: Uzawa updates of the Gauss points' pressure multipliers (each one more solve of its
    #: increment, its iterations counted in the increment's)
    augmentations: int = 0
    #: the last converged increment's fields (None before the first)
    last: IncrementRecord | None = None
    #: with ``history``, per increment the blank displacements, and per tool and increment
    #: the contact state of every slave (IncrementRecord)
    displacements: list[NDArray[np.float64]] = field(default_factory=list)
    contact_states: dict[str, list[NDArray[np.int32]]] = field(default_factory=dict)
    #: the blank's fields at the end of each run and springback (FieldFrame: displacement,
    #: stress, plastic strain, thickness, contact pressure...; ``frame.to_meshio()``)
    frames: list[FieldFrame] = field(default_factory=list)

    @property
    def iterations(self) -> list[int]:
        """Newton iterations of every converged increment."""
        return [len(r) - 1 for r in self.residuals]

    def add_tools(self, names: Iterable[str]) -> None:
        """Make room for the per-tool records of ``names``."""
        for name in names:
            for records in (self.tool_displacements, self.tool_forces, self.contacts,
                            self.contact_states, self.penetration):
                records.setdefault(name, [])

    def record(self, size: float, reason: str, factor: float, residuals: list[float],
               convergence: list[Iteration], u: NDArray[np.float64],
               tools: Mapping[str, tuple[NDArray[np.float64], NDArray[np.float64],
                                         NDArray[np.int32], float]] | None = None) -> None:
        """A converged increment of ``size`` (set by ``reason``) to phase factor ``factor``
        with its residual history, the blank's displacements ``u`` and per tool its
        position, its pairs' forces on the blank and contact states, and its deepest
        penetration."""
        self.sizes.append(size)
        self.limited_by.append(reason)
        self.factors.append(factor)
        self.residuals.append(residuals)
        self.convergence.append(convergence)
        states: dict[str, NDArray[np.int32]] = {}
        for name, (position, force, state, depth) in (tools or {}).items():
            self.tool_displacements[name].append(position.copy())
            self.tool_forces[name].append(-force.sum(axis=0))
            self.contacts[name].append(int((state != INACTIVE).sum()))
            self.penetration[name].append(depth)
            states[name] = state.copy()
        self.last = IncrementRecord(u.copy(), states)
        if self.history:
            self.displacements.append(self.last.displacement)
            for name, state in states.items():
                self.contact_states[name].append(state)


@dataclass
class _Attempt:
    """An increment trial of a phase's run: the phase factor it goes to, where it puts the
    tools, the force-controlled tools' forces, its touching predictor, its size ratio
    (Loop.size_ratio), the core's outcome and, once it converged, its deepest penetration
    per tool and its largest strain and rotation increments."""

    target: float
    positions: dict[str, NDArray[np.float64]]
    pressing: NDArray[np.float64]
    touching: _Touching
    size_ratio: float
    outcome: Trial
    depth: list[float] = field(default_factory=list)
    #: the two starts it blended (``ddpy.model.start.increment_starts``), None at rest
    starts: tuple[NDArray[np.float64], NDArray[np.float64] | None] | None = None
    strain: float = 0.0
    rotation: float = 0.0


@dataclass
class _PhaseRun:
    """What ``FormingProblem.run`` carries from one increment to the next within a phase:
    its layout and settings, the result it records into, the tools' motions, gap offsets,
    force ramps and start positions, the phase factor reached, the last increment's rates
    of the displacements and the pairs' pressures and its size, the increment controller,
    and the lifted tools' release histories waiting to join the first increment's."""

    layout: Layout
    newton: NewtonSettings
    limits: IncrementLimits
    result: FormingResult
    phase: str
    moves: dict[str, NDArray[np.float64]]
    offsets: dict[str, tuple[str, NDArray[np.float64]]]
    travel: float
    on: NDArray[np.bool_]
    holders: list[str]
    ramp: NDArray[np.float64]
    start: dict[str, NDArray[np.float64]]
    control: IncrementController
    factor: float = 0.0
    last_du: NDArray[np.float64] | None = None
    last_dp: NDArray[np.float64] | None = None
    last_size: float | None = None
    before_du: NDArray[np.float64] | None = None
    before_size: float | None = None
    start_weight: float = 0.0
    initial: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    released: tuple[list, list] = ([], [])


class FormingProblem:
    """The blank (a Solid) and its rigid tools. ``fix`` holds displacement components of
    nodes at zero (symmetry planes, clamps); ``run`` moves tools through a phase, and
    successive calls continue from where the last one stopped (multi-stage processes)."""

    def __init__(self, solid: Solid, tools: Iterable[RigidTool], ordering: str = "nested",
                 linear_solver: str = "auto", tuning: FormingTuning | None = None) -> None:
        if linear_solver not in ("auto", "direct", "reuse"):
            raise ValueError(f"linear_solver must be 'auto', 'direct' or 'reuse', got "
                             f"{linear_solver!r}")
        #: "direct": factorize the Jacobian at every Newton iteration; "reuse": solve with
        #: the last factorization as the preconditioner of GMRES while it converges fast,
        #: factorizing again when it does not; "auto": reuse from tuning.reuse_from unknowns
        self.linear_solver = linear_solver
        #: the constants of the Newton loop, the contact and the increment policy
        self.tuning = FormingTuning() if tuning is None else tuning
        self.solid = solid
        self.tools = list(tools)
        names = [t.name for t in self.tools]
        if len(set(names)) != len(names):
            raise ValueError(f"tool names must be unique, got {names}")
        n = solid.mesh.n_nodes
        for tool in self.tools:
            if tool.slaves.max() >= n or tool.slaves.min() < 0:
                raise ValueError(f"tool {tool.name}: slave node out of range 0..{n - 1}")
        self.ordering = ordering
        self.fixed = np.zeros((n, 3), dtype=bool)
        mesh = solid.mesh
        self.size = mesh.element_size()
        self.thickness = mesh.initial_thickness()
        default_r = default_augmentation(solid)
        barrier_r = capped_augmentation(default_r, float(solid.props[0]), self.thickness)
        self.r = np.concatenate([
            np.full(t.slaves.size, t.augmentation or (barrier_r if t.contact == "gauss"
                                                      else default_r))
            for t in self.tools])
        #: per tool, the blank's faces that meet it (RigidTool.facing)
        self._faces = contact_faces(self.tools, mesh)
        #: per tool, the penalty of Gauss-point contact (N/mm^3; unused by the others)
        self.penalty = [t.penalty or (default_penalty(solid, faces) if t.contact == "gauss"
                                      else 0.0)
                        for t, faces in zip(self.tools, self._faces, strict=True)]
        self._pack = ToolPack(self.tools, mesh, self.penalty,
                              [-1.0 if t.barrier is None or t.contact != "gauss"
                               else t.barrier * self.thickness for t in self.tools])
        #: pairs of Gauss-point tools: their law is a function of the positions (a penalty),
        #: continuous at a release, which the release control leaves alone
        self._gauss = np.concatenate([np.full(t.slaves.size, t.contact == "gauss")
                                      for t in self.tools]) if self.tools else np.zeros(0, bool)
        self.mu = np.concatenate([np.full(t.slaves.size, t.friction) for t in self.tools])
        #: pairs of one tool whose nodes share an element (first touch: a contact's front)
        self._neighbours = _neighbour_pairs(mesh.elements, self.tools, mesh.n_nodes)
        # State carried between increments and phases.
        self.u = np.zeros((n, 3))
        #: the blank's solid state at the last converged increment (stresses, plastic
        #: strains, material axes...)
        self.solid_state: SolidState = solid.initial_state()
        self.position = {t.name: np.zeros(3) for t in self.tools}
        npair = sum(t.slaves.size for t in self.tools)
        self.force = np.zeros((npair, 3))
        #: the tangential traction of every Gauss point of Gauss-point contact (points, 3)
        self.traction = np.zeros((self._pack.n_points, 3))
        #: the pressure of every Gauss point at the last converged increment (points,): the
        #: multiplier of its augmented Lagrangian law p = max(0, p_n - eps g)
        self.pressure = np.zeros(self._pack.n_points)
        #: the pressure of every Gauss point of Gauss-point contact at the last converged
        #: increment (points,), MPa of the undeformed blank face: what contact_pressure
        #: reads (not carried: with the plain penalty ``pressure`` stays zero)
        self.point_pressure = np.zeros(self._pack.n_points)
        #: whether the Gauss points' law is augmented (NewtonSettings.augment of the run):
        #: else a converged increment leaves their multipliers at zero, the plain penalty
        self._augment = False
        #: the blank's thickness (mm), the scale of NewtonSettings.penetration
        self._gap = (np.full(npair, np.inf), np.zeros((npair, 3)))
        #: reach of the contact search (mm): see FormingTuning.reach_sizes; run() adds its
        #: tool travel
        self._reach = self.tuning.reach_sizes * self.size
        self._contact_state = np.zeros(npair, dtype=np.int32)  # of the law, last increment
        self.external = np.zeros((n, 3))
        self._layout: Layout | None = None
        self._solver: MumpsSolver | None = None
        self._factors = Factors(0)
        #: single-precision factors failed to precondition a Jacobian of this problem
        #: (its condition number near 1/eps_single): double ones from then on
        self._single_too_coarse = False

    # -- set-up ------------------------------------------------------------------------

    def fix(self, nodes: ArrayLike, components: int | str | Iterable[int | str] = "xyz"
            ) -> None:
        """Hold ``components`` of ``nodes`` at their current displacement."""
        nodes = int_array(np.atleast_1d(nodes), "nodes", (None,))
        if nodes.size and (nodes.min() < 0 or nodes.max() >= self.solid.mesh.n_nodes):
            raise ValueError("fixed node out of range")
        self.fixed[np.ix_(nodes, _components(components))] = True
        self._reset()

    def release(self, nodes: ArrayLike, components: int | str | Iterable[int | str] = "xyz"
                ) -> None:
        """Free components held by ``fix`` (e.g. the clamps of a stage before springback)."""
        nodes = int_array(np.atleast_1d(nodes), "nodes", (None,))
        self.fixed[np.ix_(nodes, _components(components))] = False
        self._reset()

    def _reset(self) -> None:
        if self._solver is not None:
            self._solver.close()
        self._solver, self._layout = None, None

    def constrain(self, fixed: NDArray[np.bool_]) -> None:
        """Hold exactly the components ``fixed`` (n, 3) marks (a phase's constraints), the
        others free; the solver's analysis is made again at the next run."""
        fixed = np.asarray(fixed)
        if fixed.shape != self.fixed.shape or fixed.dtype != bool:
            raise ValueError(f"fixed must be booleans of shape {self.fixed.shape}, got "
                             f"{fixed.dtype} {fixed.shape}")
        self.fixed[:] = fixed
        self._reset()

    # -- state -------------------------------------------------------------------------

    def state(self) -> FormingState:
        """A copy of what the problem carries from one increment to the next."""
        return FormingState(self.u.copy(), self.solid_state.copy(),
                            {name: p.copy() for name, p in self.position.items()},
                            self.force.copy(), self._contact_state.copy(),
                            self.traction.copy(), self.pressure.copy())

    def restore(self, state: FormingState) -> None:
        """Continue from ``state`` (``state()`` of this problem, or of one built alike:
        a checkpoint's), checked against the problem: ValueError naming what does not fit
        (another mesh, tools or material)."""
        expected = {"u": self.u.shape, "force": self.force.shape,
                    "contact_state": self._contact_state.shape,
                    "traction": self.traction.shape, "pressure": self.pressure.shape}
        for name, shape in expected.items():
            value = getattr(state, name)
            if value.shape != shape:
                raise ValueError(f"{name} {value.shape}, expected {shape} (another mesh or "
                                 "tools)")
        if set(state.positions) != set(self.position):
            raise ValueError(f"tools {sorted(state.positions)}, expected "
                             f"{sorted(self.position)}")
        solid = state.solid
        if solid.stress.shape != self.solid_state.stress.shape:
            raise ValueError(f"stress {solid.stress.shape}, expected "
                             f"{self.solid_state.stress.shape} (another mesh)")
        if self.solid.mixed and solid.backstress is None:
            # No guess of the backstress: zero would restart a hardened sheet as fresh.
            raise ValueError("no backstress, which the mixed hardening of the material needs")
        if solid.backstress is not None and (
                not self.solid.mixed or solid.backstress.shape != solid.stress.shape):
            raise ValueError(f"a backstress {solid.backstress.shape}, which the material "
                             "does not have (another material or mesh)")
        self.u, self.force = state.u.copy(), state.force.copy()
        self._contact_state = state.contact_state.astype(np.int32)
        self.traction, self.pressure = state.traction.copy(), state.pressure.copy()
        self.position = {name: np.array(p, dtype=float) for name, p in state.positions.items()}
        self.solid_state = solid.copy()

    def _prepare(self, holds: tuple[int, ...] = ()) -> Layout:
        """The layout and the analysed MUMPS instance of the present constraints with the
        force-controlled tools ``holds`` (indices), made again when they change."""
        if self._layout is not None and tuple(self._layout.holds.tolist()) != holds:
            self._reset()
        if self._layout is None or self._solver is None:
            layout = Layout(self.solid, self.tools, self.fixed, holds=holds)
            self._layout, self._solver = layout, self._analysed_solver(layout)
            self._factors = Factors(self._solver.handle)
        return self._layout

    def _analysed_solver(self, layout: Layout) -> MumpsSolver:
        """A MUMPS instance analysed for ``layout``: single precision where the loop solves
        with older factors and tuning.single_factors asks for it, unless single factors
        already failed this problem."""
        # The contact multipliers first: each couples to its own node only, and
        # eliminated with it they would widen every separator's front (the paper's
        # bending mesh: 5.8e10 flops per factorization with them, 4.4e10 first). A
        # closed stick pair has a zero pivot there (its law does not involve lambda):
        # MUMPS delays it to its node's front.
        # A force-controlled tool's unknown couples to every node it touches: last.
        single = (self.tuning.single_factors and self._reuses(layout)
                  and not self._single_too_coarse)
        solver = mesh_solver("unsymmetric", self.ordering, self.solid.node_order,
                             np.concatenate([np.flatnonzero(~self.fixed.ravel()) // 3,
                                             np.repeat(layout.node, 3),
                                             np.zeros(layout.holds.size, np.int64)]),
                             first=(np.arange(layout.n) >= layout.nf)
                             & (np.arange(layout.n) < layout.n - layout.holds.size),
                             last=np.arange(layout.n) >= layout.n - layout.holds.size,
                             precision="single" if single else "double")
        solver.analyse(layout.n, *layout.entries())
        return solver

    # -- the run -----------------------------------------------------------------------

    def run(
        self,
        motion: Mapping[str, ArrayLike],
        max_increment: float,
        active: Iterable[str] | None = None,
        newton: NewtonSettings | None = None,
        limits: IncrementLimits | None = None,
        gaps: Mapping[str, tuple[str, float, ArrayLike]] | None = None,
        result: FormingResult | None = None,
        on_increment: Callable[[PhaseProgress], bool | None] | None = None,
        resume: PhaseProgress | None = None,
        phase: str = "",
        frames: bool = True,
        forces: Mapping[str, float | tuple[float, float]] | None = None,
    ) -> FormingResult:
        """Move each tool of ``motion`` by its displacement (3,) over the phase, linearly in
        the phase factor; tools not in ``active`` (default: all) are lifted off (their
        forces vanish). ``max_increment`` is the largest travel of the leading (longest
        moving) tool per increment, in mm. ``newton``: convergence (default
        NewtonSettings()): the free residual and the contact law below its force tolerance
        times the force scale and the iterate's estimated error below its displacement
        tolerance times the increment's motion, scaled up to an increment of size
        ``max_increment`` when it is smaller (a cut does not tighten the test); an increment
        that fails is cut by its ``cutback`` and retried, until a
        cut would go below ``limits.min_fraction``. ``limits``: the r_min control (default
        IncrementLimits(); the policy is ddpy.model.control.IncrementController's). Both
        defaults are those of a deck that sets nothing. ``gaps``:
        tools held at a fixed gap from another, e.g. ``{"holder": ("die", 1.13, (0, 0, 1))}``:
        the holder is set, along the direction, at 1.13 mm from the die (the smallest
        distance between their surfaces) in the first increment and then follows the die
        (a position-controlled blank-holder).
        ``result``: where the increments are recorded (default: a new FormingResult, which
        keeps the last increment's fields only; ``FormingResult(history=True)`` keeps them
        all). ``on_increment`` is called after every converged increment (the result holds
        its data) with a PhaseProgress that also says which increment it was (counted over
        ``result``), the phase (``phase``, a name for it) and the leading tool's travel
        since the start of the run's motion (mm); a true return stops the run there.
        ``resume`` continues a run from the progress such a call received. ``frames``:
        append the blank's fields at the end of the run to ``result.frames``
        (``fields``). ``forces``: tools held under a force instead of a
        motion, e.g. ``{"holder": 5000.0}``: the holder presses on the blank with 5000 N
        along its axis, -``facing`` (a blank-holder force); ``(f0, f1)`` ramps it from f0
        at the start of the phase to f1 at its end. Its displacement along the axis is one
        more unknown of the Newton loop; at the start of the phase a tool that does not
        touch the blank is first brought onto it (docs/theory/contact.md,
        "Force-controlled tools"). A tool that loses the blank stops the run
        (FormingError)."""
        run = self._begin(motion, max_increment, active, newton, limits, gaps, result,
                          resume, phase, forces)
        while run.factor < 1.0 - 1e-12:
            trial = self._attempt(run)
            if self._cut(run, trial) or not self._settle(run, trial):
                continue
            progress = self._accept(run, trial)
            if on_increment is not None and on_increment(progress):
                break
        if frames:
            run.result.frames.append(self.fields(len(run.result.factors), phase,
                                                 run.factor * run.travel))
        return run.result

    def _begin(self, motion: Mapping[str, ArrayLike], max_increment: float,
               active: Iterable[str] | None, newton: NewtonSettings | None,
               limits: IncrementLimits | None,
               gaps: Mapping[str, tuple[str, float, ArrayLike]] | None,
               result: FormingResult | None, resume: PhaseProgress | None, phase: str,
               forces: Mapping[str, float | tuple[float, float]] | None) -> _PhaseRun:
        """A phase's run checked and set up (``run``'s arguments): the layout with its
        force-controlled tools brought onto the blank, the start refused where a tool lies
        deeper in the blank than an increment may push it out, the lifted tools released,
        and the increment controller at its first trial (or where ``resume`` left it)."""
        limits = IncrementLimits() if limits is None else limits
        newton = NewtonSettings() if newton is None else newton
        self._augment = newton.augment
        unknown = set(motion) - {t.name for t in self.tools}
        if unknown:
            raise ValueError(f"motion names unknown tools: {sorted(unknown)}")
        active_set = {t.name for t in self.tools} if active is None else set(active)
        if active_set - {t.name for t in self.tools}:
            raise ValueError(f"active names unknown tools: {sorted(active_set)}")
        moves = {t.name: float_array(motion.get(t.name, (0.0, 0.0, 0.0)),
                                     f"motion of {t.name}", (3,)) for t in self.tools}
        offsets = self._gap_offsets(gaps or {}, moves) if resume is None else resume.offsets
        ramps = self._hold_ramps(forces or {}, moves, active_set, gaps or {})
        travel = max(float(np.linalg.norm(m)) for m in moves.values())
        check_max_increment(max_increment, travel)
        result = FormingResult() if result is None else result
        result.add_tools([t.name for t in self.tools])
        layout = self._prepare(tuple(sorted(ramps)))
        on = np.concatenate([np.full(t.slaves.size, t.name in active_set) for t in self.tools])
        tuning = self.tuning
        self._reach = max(tuning.reach_sizes * self.size,
                          tuning.reach_travels * min(max_increment, travel))
        if resume is None:
            for k in layout.holds:
                self._touch_down(layout, int(k))
        nominal = min(1.0, max_increment / travel) if travel > 0.0 else 1.0
        run = _PhaseRun(layout, newton, limits, result, phase, moves, offsets, travel, on,
                        [self.tools[k].name for k in layout.holds],
                        np.array([ramps[k] for k in layout.holds]).reshape(-1, 2),
                        {name: p.copy() for name, p in self.position.items()},
                        IncrementController(limits, newton.cutback, nominal,
                                            tuning.increment))
        if resume is not None:
            run.start, run.factor = resume.start, resume.factor
            run.control.resume(resume.step, resume.reason)
            run.last_du, run.last_dp = resume.last_du, resume.last_dp
            run.last_size = resume.last_size
            run.before_du, run.before_size = resume.before_du, resume.before_size
            run.start_weight = resume.start_weight
        self._check_start(run)
        # Tools lifted off at the start of the phase let go of the blank gradually, before
        # the phase's first increment (docs/theory/contact.md): their iterations count as
        # that increment's.
        if resume is None:
            run.released = self._release(layout, on, run.initial, newton, result,
                                         run.ramp[:, 0])
        return run

    def _check_start(self, run: _PhaseRun) -> None:
        """The gaps at the start of the phase (tools held at a gap placed there), for first
        touch; a tool deeper in the blank than one increment may push it out is refused
        (seen here within the search's reach; the deck's checks search without one)."""
        layout, limits = run.layout, run.limits
        x = self.solid.mesh.nodes + self.u
        run.initial = dict(self.position)
        for name, (other, offset) in run.offsets.items():
            run.initial[name] = self.position[other] + offset
        self._gap = self._contact(layout, x, x, run.initial, run.on, self.force,
                                  np.zeros(layout.n), np.empty(0))[1]
        # (Gauss-point contact that carries a force sits in the tool by its penalty's depth.)
        holding = self._gauss & (np.abs(self.force).sum(axis=1) > 0.0)
        # (A force-controlled tool was just brought onto the blank: it presses as it must.)
        holding |= np.isin(layout.tool_of, layout.holds)
        depth = np.where(run.on & np.isfinite(self._gap[0]) & ~holding, -self._gap[0],
                         -np.inf)
        worst = int(np.argmax(depth)) if depth.size else 0
        if depth.size and depth[worst] > start_depth_limit(limits.strain, self.size):
            raise ValueError(
                f"tool {self.tools[int(layout.tool_of[worst])].name} starts inside the blank: "
                f"slave node {int(layout.node[worst])} is {depth[worst]:.3g} mm deep, more "
                f"than the strain limit times the element size ({limits.strain:g} x "
                f"{self.size:.3g} mm); move the tool out first")

    def _reuses(self, layout: Layout) -> bool:
        """Whether the Newton loop solves with older factors between factorizations (its
        exact solves aside): linear_solver "reuse", or "auto" from tuning.reuse_from
        unknowns. Only then are the factors single precision (tuning.single_factors)."""
        return self.linear_solver == "reuse" or (
            self.linear_solver == "auto" and layout.n >= self.tuning.reuse_from)

    def _attempt(self, run: _PhaseRun) -> _Attempt:
        """One increment trial of ``run``: its size limited ahead by first touch and the
        release trend, the tools placed, the core's Newton loop from the last increment's
        rate; where the phase's first increment fails from its default start, once more
        from a careful start (docs/theory/contact.md)."""
        control, layout = run.control, run.layout
        if control.touch:
            control.shorten(self._touch_factor(layout, run.on, run.moves, control.step,
                                               run.last_du, run.limits), "touch")
        if control.release_ahead(run.last_dp is not None):
            assert run.limits.release is not None and run.last_dp is not None
            control.shorten(self._release_ahead(control.step, run.last_dp, run.limits.release,
                                                self._minor(layout, run.limits.release_share)),
                            "release")
        step, factor = control.step, run.factor
        target = min(1.0, factor + step)
        positions = {n: run.start[n] + target * run.moves[n] for n in run.start}
        for name, (other, offset) in run.offsets.items():
            positions[name] = positions[other] + offset
        for name in run.holders:  # from where the last increment left it
            positions[name] = self.position[name].copy()
        pressing = run.ramp[:, 0] + target * (run.ramp[:, 1] - run.ramp[:, 0])
        landing = control.landing()
        # Start from the last increment's displacement rate, and its turn or its change as
        # the last increment preferred (docs/theory/contact.md, "Start").
        starts = None if run.last_du is None else increment_starts(
            self.solid.mesh.nodes, self.solid.mesh.elements, self.u, run.last_du,
            target - factor, run.last_size or target - factor, run.before_du,
            run.before_size)
        guess = None if starts is None else \
            self.u + blended_start(starts[0], starts[1], run.start_weight)
        careful = control.start(run.last_du is None)
        touching = _Touching(self.tuning.touching * self.size, resting=not careful)
        size_ratio = control.nominal / (target - factor)
        trial = _Attempt(target, positions, pressing, touching, size_ratio, self._increment(
            layout, positions, run.on, run.newton, run.result, landing, touching, guess,
            careful=careful, size_ratio=size_ratio, hold_force=pressing,
            first=run.last_du is None), starts=starts)
        self._check_hold(trial.outcome, target, run.travel, pressing, layout, run.result)
        if trial.outcome.failure and run.last_du is None and not careful:
            # The first increment of a phase starts with the blank lying on its tools:
            # a second start keeps open the touching pairs of the tools at rest that
            # the blank does not need, with exact solves and full steps (a careful
            # start, docs/theory/contact.md), before cutting; so do the retries of
            # this increment.
            _log.info("%s starts again with the resting tools' touching pairs open: %s",
                      _trial(target, step, run.travel), trial.outcome.failure)
            control.careful = True
            trial.touching = _Touching(self.tuning.touching * self.size, resting=False)
            trial.outcome = self._increment(layout, positions, run.on, run.newton, run.result,
                                            landing, trial.touching, guess, careful=True,
                                            size_ratio=size_ratio, hold_force=pressing)
            self._check_hold(trial.outcome, target, run.travel, pressing, layout, run.result)
        return trial

    def _cut(self, run: _PhaseRun, trial: _Attempt) -> bool:
        """Whether ``trial`` is done again: shorter where it lands a yield point, cut where
        it failed (FormingError where the controller allows no more cuts)."""
        outcome, control = trial.outcome, run.control
        if outcome.landing < 1.0:  # an elastic point would overshoot the yield stress
            control.shorten(outcome.landing, "yield")
            return True
        if not outcome.failure:
            return False
        where, hint = _trial(trial.target, None, run.travel), cut_hint(outcome.failure)
        _log.info("%s cut: %s (hint: %s)", _trial(trial.target, control.step, run.travel),
                  outcome.failure, hint)
        run.result.cuts += 1
        stop = control.cut(run.factor)
        if stop == "cuts":
            raise FormingError(f"{where} failed after {control.max_cuts} cuts: "
                               f"{outcome.failure} (hint: {hint})", run.result)
        if stop == "smallest":
            raise FormingError(
                f"{where} failed: a cut would make it smaller than the smallest increment "
                f"({run.limits.min_fraction:g} of the largest): {outcome.failure} (hint: "
                f"{hint})", run.result)
        return True

    def _settle(self, run: _PhaseRun, trial: _Attempt) -> bool:
        """A converged ``trial`` with its penetration (its Gauss points' pressures augmented
        while too deep), checked against the strain, rotation and release limits: whether
        it stands (False: the controller redoes it shorter)."""
        layout, control = run.layout, run.control
        trial.depth = self._penetration(layout, trial.outcome, run.on,
                                        self._placed(layout, trial.positions, trial.outcome))
        if run.newton.augment:
            trial.outcome, trial.depth = self._augmented(
                trial.outcome, trial.depth, run.newton.penetration * self.thickness, layout,
                trial.positions, run.on, run.newton, run.result, trial.touching,
                trial.size_ratio, trial.pressing)
        trial.positions = self._placed(layout, trial.positions, trial.outcome)
        outcome = trial.outcome
        assert outcome.state is not None and outcome.u is not None
        trial.strain = _equivalent_strain_increment(outcome.state.strain - self.solid_state.strain)
        if control.strain_redo(trial.strain):
            return False
        trial.rotation = largest_rotation(self.solid.mesh.nodes + self.u,
                                          self.solid.mesh.elements, outcome.u - self.u)
        if control.rotation_redo(trial.rotation):
            return False
        if control.checks_release:
            assert outcome.gap is not None and outcome.in_contact is not None
            change = None if run.last_dp is None else run.last_dp * (trial.target - run.factor)
            release = self._release_factor(outcome.force, outcome.in_contact, outcome.gap,
                                           change, self._minor(layout,
                                                               run.limits.release_share))
            if control.release_redo(release):
                return False
        return True

    def _accept(self, run: _PhaseRun, trial: _Attempt) -> PhaseProgress:
        """A settled ``trial`` as the problem's state, recorded in the run's result; the
        controller sizes the next. Returns the progress the run reached."""
        outcome, layout, result = trial.outcome, run.layout, run.result
        assert outcome.u is not None and outcome.gap is not None
        residuals, convergence = outcome.residuals, outcome.convergence
        if run.released[0]:
            # One history for the release and the increment: each later solve's start
            # (the residual after the load's change) is left out, so that its
            # iterations count the corrections of both.
            residuals = run.released[0] + list(residuals)[1:]
            convergence = run.released[1] + list(convergence)[1:]
            run.released = ([], [])
        size = trial.target - run.factor
        if trial.starts is not None:
            run.start_weight = start_weight(outcome.u - self.u, *trial.starts)
        run.before_du, run.before_size = run.last_du, run.last_size
        run.last_du = (outcome.u - self.u) / size
        run.last_size = size
        run.last_dp = np.einsum("ij,ij->i", outcome.force - self.force,
                                outcome.gap[1]) / size
        self._take(outcome)
        self.position = trial.positions
        run.factor = trial.target
        result.record(size, run.control.reason, run.factor, residuals, convergence, outcome.u,
                      {t.name: (trial.positions[t.name],
                                outcome.force[layout.first[i]:layout.first[i + 1]],
                                outcome.in_contact[layout.first[i]:layout.first[i + 1]],
                                trial.depth[i])
                       for i, t in enumerate(self.tools)})
        run.control.accept(trial.strain, trial.rotation)
        return PhaseProgress(run.start, run.offsets, run.factor, run.control.step,
                             run.control.reason, run.last_du, run.last_dp, size,
                             increment=len(result.factors), phase=run.phase,
                             travel=run.factor * run.travel, before_du=run.before_du,
                             before_size=run.before_size, start_weight=run.start_weight)

    def _release(self, layout: Layout, on: NDArray[np.bool_],
                 positions: Mapping[str, NDArray[np.float64]], newton: NewtonSettings,
                 result: FormingResult, hold_force: NDArray[np.float64] | None = None
                 ) -> tuple[list, list]:
        """Let go of the blank where tools that held it are lifted off (pairs not ``on``
        that carry a force): their forces become nodal loads, brought to zero in
        IncrementTuning.release_steps steps (halved while one fails) with the other tools at
        ``positions``, as springback does with all of them. Lifting them in one increment
        leaves the blank out of balance by their whole force, which the first increment
        of the phase has to absorb whatever its size: a cut cannot help it. The
        force-controlled tools press with ``hold_force`` meanwhile (and move to where each
        step leaves them). Returns the
        residual norms and the relative residuals and corrections of the steps' converged
        iterations (none when nothing is lifted)."""
        lifted = ~on & (np.abs(self.force).sum(axis=1) > 0.0)
        if not lifted.any():
            return [], []
        loads = np.zeros_like(self.u)
        np.add.at(loads, layout.node[lifted], self.force[lifted])
        self.force = np.where(lifted[:, None], 0.0, self.force)
        steps = self.tuning.increment.release_steps
        done, size, spent, convergence = 0.0, 1.0 / steps, [], []
        last_du: NDArray[np.float64] | None = None
        base = self.external.copy()
        try:
            while done < 1.0 - 1e-12:
                target = min(1.0, done + size)
                self.external = base + loads * (1.0 - target)
                guess = None if last_du is None else self.u + (target - done) * last_du
                outcome = self._increment(layout, positions, on, newton, result,
                                          touching=_Touching(self.tuning.touching * self.size,
                                                             True),
                                          guess=guess, exact=True,
                                          size_ratio=1.0 / (steps * size),
                                          hold_force=hold_force)
                if outcome.failure:
                    if size / 2.0 < self.tuning.increment.release_smallest:
                        raise FormingError(f"release of the lifted tools at {done:.4g} of "
                                           f"their force failed: {outcome.failure}", result)
                    size /= 2.0
                    continue
                # A later step's start is left out (see run): the corrections count.
                skip = 1 if spent else 0
                spent += list(outcome.residuals)[skip:]
                convergence += list(outcome.convergence)[skip:]
                last_du = (outcome.u - self.u) / (target - done)
                self._take(outcome)
                positions = self._placed(layout, positions, outcome)
                for k in layout.holds:
                    self.position[self.tools[k].name] = positions[self.tools[k].name]
                done = target
                size = min(2.0 * size, 1.0 / steps)
        finally:
            self.external = base
        return spent, convergence

    def _take(self, outcome: Trial) -> None:
        """A converged increment's state as the problem's (with the augmented law its Gauss
        points' pressures the multipliers of the next increment; with the plain penalty
        zero)."""
        self.u, self.solid_state, self.force, self._gap = (outcome.u, outcome.state, outcome.force,
                                                     outcome.gap)
        self.traction, self._contact_state = outcome.traction, outcome.in_contact
        assert outcome.pressure is not None
        self.pressure = outcome.pressure if self._augment else np.zeros_like(outcome.pressure)
        self.point_pressure = outcome.pressure.copy()

    def _penetration(self, layout: Layout, outcome: Trial, on: NDArray[np.bool_],
                     positions: Mapping[str, NDArray[np.float64]]) -> list[float]:
        """Per tool, the deepest penetration of the blank at a converged ``outcome`` of
        an increment with the tools at ``positions`` (mm, >= 0): its slave nodes' most
        negative gap for node-to-surface contact; for surface-to-surface and Gauss-point
        contact, whose pairs' gaps are averages over faces, the slave nodes projected on
        the tool within the search's reach (those inside a patch count)
        (FormingResult.penetration)."""
        assert outcome.gap is not None and outcome.u is not None
        x = self.solid.mesh.nodes + outcome.u
        depth = []
        for i, t in enumerate(self.tools):
            pairs = slice(layout.first[i], layout.first[i + 1])
            if not on[pairs].any():
                depth.append(0.0)
                continue
            if t.contact == "node":
                gap = np.where(np.isfinite(outcome.gap[0][pairs]), outcome.gap[0][pairs], np.inf)
            else:
                found = t.search.project(x[t.slaves], positions[t.name], reach=self._reach)
                gap = np.where(found.status == INSIDE, found.distance, np.inf)
            depth.append(max(0.0, -float(gap.min(initial=np.inf))))
        return depth

    def _augmented(self, outcome: Trial, depth: list[float], limit: float, layout: Layout,
                   positions: Mapping[str, NDArray[np.float64]], on: NDArray[np.bool_],
                   newton: NewtonSettings, result: FormingResult, touching: _Touching,
                   size_ratio: float = 1.0,
                   hold_force: NDArray[np.float64] | None = None
                   ) -> tuple[Trial, list[float]]:
        """The converged ``outcome`` of an increment, whose penetration per tool is
        ``depth`` (``_penetration``), with the slave nodes of its Gauss-point tools at most
        ``limit`` (mm) inside them: while one is deeper, the points' multipliers take their
        pressures (an Uzawa update of the augmented Lagrangian) and the increment is solved
        again from there, at most IncrementTuning.max_augmentations times. The residual
        histories of the solves are joined, as the release's are. A solve that fails leaves the last
        converged answer (its depth is recorded, and the run warns). Returns the answer
        and its depth."""
        gauss = [i for i, t in enumerate(self.tools) if t.contact == "gauss"]
        for _ in range(self.tuning.increment.max_augmentations):
            if max((depth[i] for i in gauss), default=0.0) <= limit:
                break
            again = self._increment(layout, positions, on, newton, result, touching=touching,
                                    guess=outcome.u, pressure=outcome.pressure,
                                    size_ratio=size_ratio, hold_force=hold_force)
            if again.failure or again.landing < 1.0:
                _log.info("an augmentation of the Gauss points' pressures failed: %s",
                          again.failure or "a yield landing")
                break
            result.augmentations += 1
            again.residuals = list(outcome.residuals) + list(again.residuals)[1:]
            again.convergence = list(outcome.convergence) + list(again.convergence)[1:]
            outcome = again
            depth = self._penetration(layout, outcome, on,
                                      self._placed(layout, positions, outcome))
        return outcome, depth

    def _hold_ramps(self, forces: Mapping[str, float | tuple[float, float]],
                    moves: Mapping[str, NDArray[np.float64]], active: set[str],
                    gaps: Mapping[str, object]) -> dict[int, tuple[float, float]]:
        """The force-controlled tools of a phase (their indices) with the force each presses
        with at its start and its end (N), checked: known and active tools with a facing
        direction, neither moved nor held at a gap, forces finite and >= 0."""
        index = {t.name: i for i, t in enumerate(self.tools)}
        ramps: dict[int, tuple[float, float]] = {}
        for name, value in forces.items():
            if name not in index:
                raise ValueError(f"force on an unknown tool: {name}")
            if name not in active:
                raise ValueError(f"tool {name} is held under a force: it must be active")
            if np.any(moves[name] != 0.0) or name in gaps:
                raise ValueError(f"tool {name} is held under a force: it cannot also be moved "
                                 "or held at a gap")
            if self.tools[index[name]].facing is None:
                raise ValueError(f"tool {name} has no facing direction: a force along it "
                                 "cannot be held")
            pair = (value, value) if np.ndim(value) == 0 else tuple(value)  # type: ignore[arg-type]
            # (A tool pressing with nothing at the end of an increment holds nothing.)
            if len(pair) != 2 or not all(np.isfinite(f) and f >= 0.0 for f in pair) or \
                    not pair[1] > 0.0:
                raise ValueError(f"force of {name} must be a finite value > 0 (N), or two "
                                 f"(from >= 0 to > 0), got {value!r}")
            ramps[index[name]] = (float(pair[0]), float(pair[1]))
        return ramps

    def _touch_down(self, layout: Layout, k: int) -> None:
        """Bring force-controlled tool ``k`` onto the blank along its axis, tuning.touch_depth
        element sizes into its nearest slave node (its slave nodes projected on it within
        the search's reach, those inside a patch: the gaps along its normals there),
        unless its pairs already carry a force."""
        tool = self.tools[k]
        pairs = slice(layout.first[k], layout.first[k + 1])
        if np.abs(self.force[pairs]).sum() > 0.0:
            return
        axis = layout.hold_axis[int(np.flatnonzero(layout.holds == k)[0])]
        x = self.solid.mesh.nodes + self.u
        found = tool.search.project(x[tool.slaves], self.position[tool.name], reach=self._reach)
        gap, closing = found.distance, found.normal @ axis
        seen = (found.status == INSIDE) & (closing > 0.5)
        if not seen.any():
            raise ValueError(f"force-controlled tool {tool.name} does not reach the blank: no "
                             f"slave node lies within the contact search's reach "
                             f"({self._reach:.3g} mm) of it along its axis; place it on the "
                             "blank")
        travel = float(np.min(gap[seen] / closing[seen])) + self.tuning.touch_depth * self.size
        self.position[tool.name] = self.position[tool.name] + travel * axis

    def _placed(self, layout: Layout, positions: Mapping[str, NDArray[np.float64]],
                outcome: Trial) -> dict[str, NDArray[np.float64]]:
        """``positions`` with each force-controlled tool moved by its shift of ``outcome``."""
        placed = dict(positions)
        if outcome.shift is not None:
            for h, k in enumerate(layout.holds):
                name = self.tools[k].name
                placed[name] = positions[name] + outcome.shift[h] * layout.hold_axis[h]
        return placed

    def _check_hold(self, outcome: Trial, target: float, travel: float,
                    pressing: NDArray[np.float64], layout: Layout,
                    result: FormingResult) -> None:
        """Stop the run where a force-controlled tool lost the blank in ``outcome``: a cut
        cannot give it back what holds it, and it must never fly off."""
        if outcome.hold is None:
            return
        k, why = outcome.hold
        force = pressing[int(np.flatnonzero(layout.holds == k)[0])]
        raise FormingError(f"{_trial(target, None, travel)}: force-controlled tool "
                           f"'{self.tools[k].name}' lost the blank pressing with {force:.6g} "
                           f"N: {why}; the phase stops here", result)

    def _gap_offsets(self, gaps: Mapping[str, tuple[str, float, ArrayLike]],
                     moves: Mapping[str, NDArray[np.float64]],
                     ) -> dict[str, tuple[str, NDArray[np.float64]]]:
        """Offset of each gap-held tool from its partner that puts their surfaces at the
        gap: the holder's grid points projected on the partner give the present gap."""
        tools = {t.name: t for t in self.tools}
        out: dict[str, tuple[str, NDArray[np.float64]]] = {}
        for name, spec in gaps.items():
            if len(spec) != 3:
                raise ValueError(f"gap of {name} must be (other tool, gap, direction)")
            other, gap, direction = spec
            if name not in tools or other not in tools or name == other:
                raise ValueError(f"gap {name} -> {other}: both must be tools, and different")
            if np.any(moves[name] != 0.0):
                raise ValueError(f"tool {name} is held at a gap: it cannot also be moved")
            if not (np.isfinite(gap) and gap >= 0.0):
                raise ValueError(f"gap of {name} must be >= 0, got {gap}")
            axis = float_array(direction, f"gap direction of {name}", (3,))
            if np.linalg.norm(axis) == 0.0:
                raise ValueError(f"gap direction of {name} must not be zero")
            axis = axis / np.linalg.norm(axis)
            holder = tools[name].search
            points = holder.grid_points + self.position[name]
            found = tools[other].search.project(points, self.position[other])
            present = float(np.min(np.abs(found.distance[found.status != NONE])))
            offset = self.position[name] - self.position[other] + (gap - present) * axis
            out[name] = (other, offset)
        return out

    def free_rigid_modes(self) -> int:
        """How many rigid-body motions of the blank the fixed dofs leave free."""
        return len(free_rigid_modes(self.solid.mesh.nodes + self.u, self.fixed))

    def support_rigid_modes(self) -> list[tuple[int, int]]:
        """Fix the fewest dofs (a 3-2-1 set on three far apart nodes of the deformed blank)
        that stop the rigid-body motions the present constraints leave free. Returns the
        (node, component) pairs fixed."""
        x = self.solid.mesh.nodes + self.u
        first = int(np.argmin(np.linalg.norm(x - x.mean(axis=0), axis=1)))
        second = int(np.argmax(np.linalg.norm(x - x[first], axis=1)))
        along = (x[second] - x[first]) / np.linalg.norm(x[second] - x[first])
        off = (x - x[first]) - np.outer((x - x[first]) @ along, along)
        third = int(np.argmax(np.linalg.norm(off, axis=1)))
        added: list[tuple[int, int]] = []
        fixed = self.fixed.copy()
        free = len(free_rigid_modes(x, fixed))
        for node in (first, second, third):
            for comp in range(3):
                if free == 0 or fixed[node, comp]:
                    continue
                fixed[node, comp] = True
                left = len(free_rigid_modes(x, fixed))
                if left < free:
                    free = left
                    added.append((node, comp))
                else:
                    fixed[node, comp] = False
        if free:
            raise ValueError("could not find supports that stop every rigid-body motion")
        for node, comp in added:
            self.fix([node], comp)
        return added

    def springback(self, increments: int = 5, newton: NewtonSettings | None = None,
                   result: FormingResult | None = None, frames: bool = True,
                   max_cuts: int = 6) -> FormingResult:
        """Remove the tools and let the blank unload. The forces that held it at the end of
        forming (contact forces, reactions of released clamps) become nodal loads, brought
        to zero in ``increments`` steps (unloading is elastic unless it yields in reverse),
        with the tools lifted off. Keep
        only the constraints that stop rigid-body motion: ``release`` clamps first; if the
        remaining constraints leave rigid motions free, ``support_rigid_modes`` adds a
        3-2-1 set of supports (docs/theory/contact.md). ``newton``: convergence of each
        step (default NewtonSettings()); a step that fails is cut by its ``cutback``, and
        the steps grow back after each converged one by the increment policy's ``regrow``
        (IncrementTuning) up to 1 / ``increments`` of the release; a step of
        2^-``max_cuts`` of that that fails stops it (FormingError). ``frames``:
        append the blank's fields at its end to ``result.frames``."""
        newton = NewtonSettings() if newton is None else newton
        if int(increments) < 1:
            raise ValueError(f"increments must be at least 1, got {increments}")
        if int(max_cuts) < 0:
            raise ValueError(f"max_cuts must be at least 0, got {max_cuts}")
        if self.free_rigid_modes():
            self.support_rigid_modes()
        result = FormingResult() if result is None else result
        layout = self._prepare()
        # The blank is in equilibrium under the tools and the supports it had: its internal
        # forces are those loads. Every one on a dof that is free now (contact forces, and
        # reactions of released clamps) is brought to zero.
        loads, _ = self.solid.internal_force(self.u, self.solid_state)
        loads[self.fixed] = 0.0
        self.force = np.zeros_like(self.force)
        self.traction = np.zeros_like(self.traction)
        self.pressure = np.zeros_like(self.pressure)
        self.point_pressure = np.zeros_like(self.point_pressure)
        off = np.zeros(layout.node.size, dtype=bool)
        last_du: NDArray[np.float64] | None = None
        # The release counted in units of the smallest step, 1 / (increments 2^max_cuts),
        # so that equal steps release exactly k / increments.
        full = 2 ** int(max_cuts)
        whole = int(increments) * full
        released, step, last_step = 0, full, full
        regrow = self.tuning.increment.regrow
        try:
            while released < whole:
                target = min(released + step, whole)
                self.external = loads * (1.0 - target / whole)
                # The blank unloads nearly elastically: each step starts from the last
                # one's displacement change, scaled to its size.
                guess = None if last_du is None else \
                    self.u + last_du * ((target - released) / last_step)
                # Exact solves: the free blank on its supports is soft in bending, and a
                # direction from GMRES on older factors, within its relative tolerance,
                # is poor along those modes; the bending paper mesh took 16 iterations
                # per step with it (320 for 20 steps, 413 s on 2 threads), 3 with a
                # factorization at every iteration (62).
                outcome = self._increment(layout, self.position, off, newton, result,
                                          guess=guess, exact=True)
                if outcome.failure:
                    if target - released == 1:
                        raise FormingError(
                            f"springback step to {target / whole:.4g} of the release failed "
                            f"at 1/{full} of its size: {outcome.failure}",
                            result)
                    _log.info("springback step to %.4g of the release cut back: %s",
                              target / whole, outcome.failure)
                    result.cuts += 1
                    step = max(1, math.floor((target - released) * newton.cutback))
                    continue
                last_du, last_step = outcome.u - self.u, target - released
                self.u, self.solid_state = outcome.u, outcome.state
                result.record(last_step / whole, "springback", target / whole,
                              outcome.residuals, outcome.convergence, self.u)
                released, step = target, min(full, max(last_step + 1,
                                                        math.floor(last_step * regrow)))
        finally:
            self.external = np.zeros_like(self.u)
        if frames:
            result.frames.append(self.fields(len(result.factors), "springback"))
        return result

    def _touch_factor(self, layout: Layout, on: NDArray[np.bool_],
                      moves: Mapping[str, NDArray[np.float64]], step: float,
                      last_du: NDArray[np.float64] | None, limits: IncrementLimits) -> float:
        """Fraction of the next increment at which the first free node reaches a tool: its
        gap over the approach, the tool's motion against the node's (extrapolated from the
        last increment) along the normal at its closest point."""
        gap, normal = self._gap
        tool_step = np.concatenate([np.tile(step * moves[t.name], (t.slaves.size, 1))
                                    for t in self.tools])
        node_step = 0.0 if last_du is None else step * last_du[layout.node]
        approach = np.einsum("ij,ij->i", tool_step - node_step, normal)
        loaded = np.abs(self.force).sum(axis=1) > 0.0
        free = on & ~loaded & np.isfinite(gap)
        free &= gap > limits.touch_gap * self.size
        hits = free & (approach > gap)
        if limits.touch == "new" and hits.any():
            # Nodes linked to the contact by a chain of nodes that all touch within the
            # increment are its advancing front: the Newton loop closes them inside it
            # (docs/theory/contact.md); only a new contact zone lands.
            joined = loaded.copy()
            while True:
                front = hits & ~joined & (self._neighbours @ joined.astype(float) > 0.0)
                if not front.any():
                    break
                joined |= front
            hits &= ~joined
        if not hits.any():
            return 1.0
        # Land just past the surface, so that the node is caught in contact.
        return float(np.min(gap[hits] / approach[hits])) * (
            1.0 + self.tuning.increment.touch_past)

    def _minor(self, layout: Layout, share: float) -> NDArray[np.bool_]:
        """Pairs whose normal force at the start of the increment is at most ``share`` of
        their tool's: released inside an increment, they change the tool's force by less
        than that (IncrementLimits.release_share)."""
        pressure = np.einsum("ij,ij->i", self.force, self._gap[1])
        pressure = np.where(self._contact_state != INACTIVE, np.maximum(pressure, 0.0), 0.0)
        total = np.add.reduceat(pressure, layout.first[:-1]) if pressure.size else pressure
        return pressure <= share * total[layout.tool_of]

    def _release_ahead(self, step: float, rate: NDArray[np.float64], margin: float,
                       minor: NDArray[np.bool_]) -> float:
        """Fraction of the next increment at which the first node in contact is released,
        its pressure extrapolated at the rate of the last increment (``rate``, per unit
        phase factor), plus ``margin / 2`` so that it is free at the end."""
        pressure = np.einsum("ij,ij->i", self.force, self._gap[1])
        falling = (self._contact_state != INACTIVE) & (pressure > 0.0) & (rate < 0.0) & ~minor
        falling &= ~self._gauss
        ahead = np.full(pressure.size, np.inf)
        ahead[falling] = pressure[falling] / (-rate[falling] * step)
        first = float(ahead.min()) if ahead.size else np.inf
        return first * (1.0 + margin / 2.0) if first * (1.0 + margin / 2.0) < 1.0 else 1.0

    def _release_factor(self, force: NDArray[np.float64], state: NDArray[np.int32],
                        gap: tuple[NDArray[np.float64], NDArray[np.float64]],
                        change: NDArray[np.float64] | None, minor: NDArray[np.bool_]
                        ) -> float:
        """Fraction of a converged increment at which the first node in contact at its start
        and open at its end was released; 1 when none was. The semi-smooth Newton opens a
        pulled node in its first iteration, so a release is seen only after the increment.
        A node whose pressure fell in the last increment (``change``: that rate times this
        increment) is released where the extrapolated pressure reaches zero; otherwise (the
        start of a phase, or when the extrapolation would not release it) where its
        augmented pressure p_aug = p - r g, whose sign opens and closes the law, reaches
        zero, interpolated between p at the start (g = 0) and -r g at the end (p = 0)."""
        distance, normal = gap
        pressure = np.einsum("ij,ij->i", self.force, normal)
        after = np.einsum("ij,ij->i", force, normal) - self.r * distance
        released = (self._contact_state != INACTIVE) & (state == INACTIVE) & (pressure > 0.0)
        released &= np.isfinite(distance) & (after < 0.0) & ~minor & ~self._gauss
        if not released.any():
            return 1.0
        p = pressure[released]
        fraction = p / (p - after[released])
        # A small fraction says p << r g: r is then far from the node's own stiffness and
        # the interpolation is biased towards zero (on the paper's bending blank, nodes at
        # the die shoulder pressed by 1e-3 N gave 1e-3 again and again while their pressure
        # rose); bisect instead.
        fraction = np.where(fraction < self.tuning.increment.bisect_below, 0.5, fraction)
        if change is not None:
            drop = -change[released]
            trend = np.divide(p, drop, out=np.full(p.size, np.inf), where=drop > 0.0)
            fraction = np.where(trend < 1.0, trend, fraction)
        return float(fraction.min())

    def contact_pressure(self) -> NDArray[np.float64]:
        """The contact pressure at every blank node at the last converged increment (n,),
        MPa: the normal force the tools press the node with over the area it stands for,
        both spread from the blank's contact faces by the faces' shape functions (each
        node's share of the present face area). For Gauss-point contact the force is that
        of the faces' Gauss points (their pressures times the undeformed areas they stand
        for); for node-to-surface and surface-to-surface contact the node's own normal
        force. Zero away from contact; where several tools press a node, the sum."""
        mesh = self.solid.mesh
        x = mesh.nodes + self.u
        n = mesh.n_nodes
        out = np.zeros(n)
        pack = self._pack  # the blank faces facing each tool, as the contact uses them
        first_point, first_pair = 0, 0
        normal = self._gap[1]
        for i, tool in enumerate(self.tools):
            faces = pack.faces[4 * pack.face_first[i]:4 * pack.face_first[i + 1]].reshape(-1, 4)
            npf = tool.points**2
            count = npf * faces.shape[0]
            pairs = slice(first_pair, first_pair + tool.slaves.size)
            first_pair += tool.slaves.size
            if not faces.shape[0]:
                first_point += count
                continue
            if tool.contact == "gauss":
                basis = face_basis(tool.points)                              # (npf, 4)
                area = gauss_face_weights(x, faces, tool.points)              # (f, npf)
                points = slice(first_point, first_point + count)
                force = (self.point_pressure[points] * pack.face_weight[points]).reshape(-1, npf)
                node_force = np.bincount(faces.ravel(), (force @ basis).ravel(), minlength=n)
            else:
                basis = face_basis(2)
                area = gauss_face_weights(x, faces, 2)
                node_force = np.zeros(n)
                node_force[tool.slaves] = np.maximum(
                    np.einsum("ij,ij->i", self.force[pairs], normal[pairs]), 0.0)
            first_point += count
            node_area = np.bincount(faces.ravel(), (area @ basis).ravel(), minlength=n)
            out += np.divide(node_force, node_area, out=np.zeros(n), where=node_area > 0.0)
        return out

    def fields(self, increment: int = 0, phase: str = "", travel: float = 0.0) -> FieldFrame:
        """The blank's fields at the present state (a snapshot: FieldFrame), labelled with
        ``increment``, ``phase`` and ``travel``."""
        mesh = self.solid.mesh
        cauchy = self.solid.stresses(self.u, self.solid_state)[1].mean(axis=1)
        thickness = thinning = None
        strains: dict[str, NDArray[np.float64]] = {}
        measures = self.sheet_measures
        if measures is not None:
            thickness, thinning = measures.thickness(self.u), measures.thinning(self.u)
            strains = measures.surface_strains(self.u)
        return FieldFrame(mesh.nodes, mesh.elements, int(increment), str(phase), float(travel),
                          self.u.copy(), cauchy, self.solid_state.ep.mean(axis=1),
                          nodal_average(mesh.elements, self.solid_state.ep, mesh.n_nodes),
                          self.contact_pressure(), thickness, thinning, strains)

    @cached_property
    def sheet_measures(self) -> SheetMeasures | None:
        """Thickness and surface strains of the blank (None when it is not meshed in layers
        through its thickness)."""
        mesh = self.solid.mesh
        try:
            return SheetMeasures(mesh.nodes, mesh.elements, mesh.normal)
        except ValueError:
            return None

    def contact_state(self, u: ArrayLike | None = None,
                      positions: Mapping[str, ArrayLike] | None = None,
                      ) -> tuple[NDArray[np.int32], NDArray[np.float64], NDArray[np.float64]]:
        """The contact of every (tool, slave) pair, pairs in the order of the tools and their
        slaves, at displacements ``u`` (n, 3) (default: the present ones) with the tools at
        ``positions`` (default: where they are), for the present contact forces: the law's
        states (0 open, 1 stick, 2 slip), the signed gaps (inf where no patch lies within
        the search's reach or the facing filter leaves none) and the tools' unit normals at
        the closest points (pairs, 3). The same core call as an evaluation of a run."""
        # The layout of the run if there is one; else one made for this look only (no MUMPS
        # analysis: nothing is solved).
        layout = self._layout or Layout(self.solid, self.tools, self.fixed)
        n = self.solid.mesh.n_nodes
        u = self.u if u is None else float_array(u, "u", (n, 3))
        where = self._positions(positions)
        x = self.solid.mesh.nodes + u
        on = np.ones(layout.node.size, dtype=bool)
        state, (gap, normal) = self._contact(layout, x, self.solid.mesh.nodes + self.u,
                                             where, on, self._multipliers(), np.zeros(layout.n),
                                             np.empty(0))
        return state, gap, normal

    def _positions(self, positions: Mapping[str, ArrayLike] | None
                   ) -> dict[str, NDArray[np.float64]]:
        """Where the tools are, with those named in ``positions`` moved there."""
        where = dict(self.position)
        for name, value in (positions or {}).items():
            if name not in where:
                raise ValueError(f"positions names an unknown tool: {name}")
            where[name] = float_array(value, f"position of {name}", (3,))
        return where

    def _tool_arguments(self, positions: Mapping[str, NDArray[np.float64]]) -> ToolPlacement:
        """The tools where they are (``positions``) and where they were at the last
        converged increment, with the search's reach and the element size: what the core's
        contact and loop take (ToolPack.arguments)."""
        return self._pack.arguments(positions, self.position, self._reach, self.size)

    def _multipliers(self) -> NDArray[np.float64]:
        """The pairs' multipliers as the core's laws take them: their forces, but a barrier
        pair's multiplier is its slave's own force, which its node point carries as its
        traction (the pair's force holds the Gauss points' lumped force too)."""
        force = self.force.copy()
        first = np.concatenate([[0], np.cumsum([t.slaves.size for t in self.tools])])
        for k, tool in enumerate(self.tools):
            if tool.contact == "gauss" and tool.barrier is not None:
                end = self._pack.point_first[k + 1]
                force[first[k]:first[k + 1]] = self.traction[end - tool.slaves.size:end]
        return force

    def _contact(self, layout: Layout, x: NDArray[np.float64], x_n: NDArray[np.float64],
                 positions: Mapping[str, NDArray[np.float64]], on: NDArray[np.bool_],
                 force: NDArray[np.float64], residual: NDArray[np.float64],
                 values: NDArray[np.float64], touching: _Touching | None = None,
                 hold_force: NDArray[np.float64] | None = None
                 ) -> tuple[NDArray[np.int32], tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """Contact of every pair at positions x, in one call to the core: the search of each
        active tool (with the blank's normals at its slaves as the facing filter), the law
        and the touching predictor of the first iteration (docs/theory/contact.md). It
        writes the law's rows of ``residual`` and subtracts the pairs' forces from its
        equilibrium rows (which hold fint - external), and writes the contact entries of
        ``values`` (none when it is empty: a look at the gaps), and the rows and entries of
        the force-controlled tools, pressing with ``hold_force``. Returns the pairs'
        states, and their gaps (inf: no patch) and normals."""
        state, gap, normal = contact(
            self.solid, layout, self._tool_arguments(positions), on, force, self.r, self.mu,
            self.traction, self.pressure, x, x_n, residual, values,
            0.0 if touching is None else touching.distance,
            touching is None or touching.resting, hold_force)
        return state, (gap, normal)

    def linearization(self, u: ArrayLike | None = None, force: ArrayLike | None = None,
                      positions: Mapping[str, ArrayLike] | None = None,
                      touching: float = 0.0, holds: Mapping[str, float] | None = None
                      ) -> Linearization:
        """The equations the Newton loop solves, at displacements ``u`` (n, 3) and pair
        multipliers ``force`` (pairs, 3) (default: the present ones; a barrier pair's is its
        slave's own force, ``_multipliers``) with the tools at
        ``positions`` (default: where they are), in the increment from the present
        converged state: the residual and its Jacobian (the same core calls as an
        evaluation of the loop; every pair takes part). With ``touching`` > 0 the pairs
        within that gap count as closed, as in an increment's first iteration. ``holds``:
        force-controlled tools and their forces (N); their displacements along their axes
        are the last unknowns, zero at ``positions``, their force balances the last rows.
        Raises ElementError where an element is inverted."""
        index = {t.name: i for i, t in enumerate(self.tools)}
        chosen = sorted(index[name] for name in holds or {})
        layout = self._layout if self._layout is not None and \
            self._layout.holds.tolist() == chosen else \
            Layout(self.solid, self.tools, self.fixed, holds=chosen)
        hold_force = np.array([(holds or {})[self.tools[k].name] for k in chosen], dtype=float)
        n, npair = self.solid.mesh.n_nodes, layout.node.size
        u = self.u if u is None else float_array(u, "u", (n, 3))
        force = self._multipliers() if force is None else \
            float_array(force, "force", (npair, 3))
        residual, values, state = equations(
            self.solid, layout, self._tool_arguments(self._positions(positions)),
            self.solid_state, self.u, self.external, u, force, self.r, self.mu,
            self.traction, self.pressure, touching, hold_force)
        nodes = np.concatenate([np.flatnonzero(~self.fixed.ravel()) // 3,
                                np.repeat(layout.node, 3), np.full(layout.holds.size, -1)])
        return Linearization(residual, layout.rows, layout.cols, values, state, nodes,
                             layout.nf)

    def _increment(self, layout: Layout,
                   positions: Mapping[str, NDArray[np.float64]], on: NDArray[np.bool_],
                   newton: NewtonSettings, result: FormingResult,
                   yield_tolerance: float | None = None,
                   touching: _Touching | None = None,
                   guess: NDArray[np.float64] | None = None,
                   careful: bool = False, exact: bool = False,
                   pressure: NDArray[np.float64] | None = None,
                   size_ratio: float = 1.0,
                   hold_force: NDArray[np.float64] | None = None,
                   first: bool = False) -> Trial:
        """One increment trial, the Newton iterations run by the core (forming_increment,
        fortran/solver/ddpy_forming_newton.f90): the new state, or (with
        ``yield_tolerance``) the fraction of the increment at which the first elastic Gauss
        point reaches the yield surface, from the strains of the first full step (the
        elastic predictor), when below 1; or why it failed. With ``touching``, the first
        iteration takes pairs within that gap as closed (see ``_contact``). With ``guess``
        (displacements, the last increment's rate times this one's size) the iterations
        start there instead of at the converged u_n, unless an element fails there; the
        converged state does not depend on the start. ``careful``: exact solves (a
        factorization at every iteration, never GMRES on older factors) and full steps (no
        line search), for the first increment of a phase whose default start failed: a
        semi-smooth Newton on a degenerate contact set (pairs at g = 0, p = 0) needs exact
        active-set steps (docs/theory/contact.md). ``exact``: exact solves only, the line
        search kept (springback). ``pressure``: the Gauss points' pressure multipliers
        (default: the last converged pressures). ``size_ratio``: the largest increment over
        this one's size; the correction is judged against the increment's motion scaled up
        by it, the motion of a whole increment (Loop.size_ratio). ``hold_force``: the force
        each force-controlled tool of the layout presses with (N; default zero).
        ``first``: a phase's first increment, from the blank lying on its tools: a
        correction that may be the last leaves at most _FIRST_KRYLOV_LAST force tolerances
        of linear residual (docs/theory/linear-solver.md, "Tolerance").

        The semi-smooth Newton step is globalized by backtracking until Deuflhard's natural
        monotonicity test holds (the simplified correction at the trial point, solved with
        this iteration's factors, shorter than the step), else on the residual norm: a
        node switching between stick and slip (or contact and release) at every iteration
        would otherwise make it cycle. The norm alone is the wrong measure for a thin sheet
        that bends: a step that bends it right leaves a large membrane residual of second
        order (docs/theory/contact.md)."""
        tuning = self.tuning
        reuse = not (careful or exact) and self._reuses(layout)
        max_iterations = newton.max_iterations
        if careful:
            max_iterations *= tuning.increment.careful_iterations
        loop = Loop(newton.force_tolerance, newton.displacement_tolerance, max_iterations,
                    1e-8 * self.solid.props[0] * self.size**2, yield_tolerance,
                    tuning.penetration, tuning.min_step, reuse, krylov_loose=tuning.krylov_loose,
                    krylov_tight=tuning.krylov_tight,
                    krylov_last=min(tuning.krylov_last, _FIRST_KRYLOV_LAST) if first
                    else tuning.krylov_last,
                    krylov_max=tuning.krylov_max, krylov_keep=tuning.krylov_keep,
                    touching=0.0 if touching is None else touching.distance,
                    resting=touching is None or touching.resting,
                    search=SEARCH_NONE if careful else SEARCH_MONOTONICITY,
                    whole_step=tuning.whole_step, size_ratio=max(1.0, size_ratio),
                    search_memory=bool(tuning.search_memory))
        pairs = Pairs(self._tool_arguments(positions), on, self.r, self.mu, self.force,
                      self.traction, self.pressure if pressure is None else pressure,
                      np.zeros(layout.holds.size) if hold_force is None else hold_force,
                      tuning.hold_step * self._reach)
        trial = increment(self.solid, layout, self._factors, self.solid_state, self.u,
                          self.external, self.u, guess, loop, pairs)
        result.count(trial)
        if trial.solver == _SINGLE_TOO_COARSE:
            # The same trial again on double-precision factors, for the rest of the run.
            _log.warning("single-precision factors do not precondition this problem's "
                         "Jacobian (GMRES on fresh ones missed its tolerance): double "
                         "precision from here on")
            self._single_too_coarse = True
            assert self._solver is not None
            self._solver.close()
            self._solver = self._analysed_solver(layout)
            self._factors = Factors(self._solver.handle)
            trial = increment(self.solid, layout, self._factors, self.solid_state, self.u,
                              self.external, self.u, guess, loop, pairs)
            result.count(trial)
        if _log.isEnabledFor(logging.DEBUG):
            for k, it in enumerate(trial.convergence):
                _log.debug("iteration %d: residual %.3e of the force scale, correction %.3e "
                           "of the motion%s", k, it.residual, it.correction,
                           f"; switched: {it.points_switched} contact points, "
                           f"{it.pairs_switched} pairs, {it.yield_switched} points between "
                           f"elastic and plastic, step length {it.step:.4g}" if k else "")
        return trial

    def close(self) -> None:
        """Free the MUMPS instance."""
        self._reset()


def _neighbour_pairs(elements: NDArray[np.int_], tools: list[RigidTool],
                     n_nodes: int) -> sp.csr_matrix:
    """Pairs x pairs: 1 where two pairs of the same tool have nodes that share an element
    (the diagonal left out)."""
    k = elements.shape[1]
    rows, cols = np.repeat(elements, k, axis=1).ravel(), np.tile(elements, (1, k)).ravel()
    nodes = sp.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n_nodes, n_nodes))
    blocks = [nodes[t.slaves][:, t.slaves] for t in tools]
    pairs = sp.block_diag(blocks, format="csr") if blocks else sp.csr_matrix((0, 0))
    pairs.setdiag(0.0)
    pairs.eliminate_zeros()
    return pairs


def default_augmentation(solid: Solid) -> float:
    """The augmentation parameter r (N/mm) of the contact law when a tool sets none:
    E t^2 / h, the median over the elements of t, their thinnest mean edge length along
    the three natural directions, and h, the geometric mean of the other two. For a cube
    it is E h, the stiffness of a node pressed into a solid; for the flat elements of a
    sheet it is lower by (t / h)^2, as a sheet is pressed by a tool mostly in bending.
    r changes only how the Newton loop decides between open, stick and slip (p - r g,
    lambda_T - r s): a value far above the blank's stiffness decides on gaps of 1e-3 mm
    and flips contact states from iteration to iteration (docs/theory/contact.md). The
    barrier of a Gauss-point tool takes barrier_augmentation."""
    return blank_stiffness(solid.mesh.nodes, solid.mesh.elements, float(solid.props[0]))


def barrier_augmentation(solid: Solid) -> float:
    """The augmentation r (N/mm) of a Gauss-point tool's barrier (its nodes' own law) when
    the tool sets none: default_augmentation, at most E T / 10 (T the blank's thickness).
    E t^2 / h grows with the elements' aspect ratio to E t on nearly cubic ones, far above
    what a node of the sheet carries against the Gauss points' penalty, and a step that
    lifts such a node by a micrometre opens it (p - r g < 0): on the deep drawing's paper
    blank (58,136 N/mm) each increment's first trials changed 50 to 150 pairs and were cut,
    and E T / 10 (20,580 N/mm) took a quarter fewer iterations and half the time per mm
    (docs/theory/contact.md, "The barrier's augmentation")."""
    return capped_augmentation(default_augmentation(solid), float(solid.props[0]),
                               solid.mesh.initial_thickness())


def capped_augmentation(stiffness: float, young: float, thickness: float) -> float:
    """barrier_augmentation from the blank's E t^2 / h, E and thickness T: min(E t^2 / h,
    BARRIER_SHARE E T)."""
    return min(stiffness, BARRIER_SHARE * young * thickness)


def default_penalty(solid: Solid, faces: NDArray[np.integer]) -> float:
    """The penalty eps (N/mm^3) of Gauss-point contact when a tool sets none: 8 sigma_0 T /
    h^2, sigma_0 the initial yield stress, T the blank's thickness (its volume over the
    area of the tool's contact faces) and h their size (the median over them of the
    shorter of their two mean edge lengths). Under the pressure sigma_0 T / R of a sheet
    drawn at yield over a radius R the faces then sink h^2 / (8 R) into it, the depth at
    which node-to-surface contact already lets a face cut into a radius between two nodes;
    lower loads (free bending) want a softer one (docs/theory/contact.md)."""
    area = gauss_face_weights(solid.mesh.nodes, faces).sum(axis=1)
    if area.size == 0:
        raise ValueError("Gauss-point contact needs blank faces that face the tool")
    x = solid.mesh.nodes[faces]                                     # (f, 4, 3)
    along = np.linalg.norm(x[:, 1] - x[:, 0], axis=1) + np.linalg.norm(x[:, 2] - x[:, 3], axis=1)
    across = np.linalg.norm(x[:, 3] - x[:, 0], axis=1) + np.linalg.norm(x[:, 2] - x[:, 1], axis=1)
    h = float(np.median(0.5 * np.minimum(along, across)))
    thickness = solid.mesh.volume() / float(area.sum())
    return 8.0 * solid.yield_stress * thickness / h**2


def blank_stiffness(nodes: ArrayLike, elements: ArrayLike, young: float) -> float:
    """E t^2 / h of default_augmentation, from the nodes (n, 3) and hexahedra (m, 8)."""
    x = np.asarray(nodes, dtype=float)
    edges = np.asarray(elements)[:, HEX_EDGES]  # (m, 3, 4, 2)
    lengths = np.linalg.norm(x[edges[..., 1]] - x[edges[..., 0]], axis=-1).mean(axis=2)
    lengths.sort(axis=1)
    ratio = lengths[:, 0] ** 2 / np.sqrt(lengths[:, 1] * lengths[:, 2])
    return float(young * np.median(ratio))


def _equivalent_strain_increment(delta: NDArray[np.float64]) -> float:
    """Largest sqrt(2/3 de:de) over Gauss points of Voigt strain increments (engineering
    shears)."""
    if delta.size == 0:
        return 0.0
    normal = (delta[..., :3] ** 2).sum(axis=-1)
    shear = (delta[..., 3:] ** 2).sum(axis=-1) / 2.0
    return float(np.sqrt(2.0 / 3.0 * (normal + shear)).max())
