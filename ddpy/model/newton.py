"""The core's Newton loop of one increment trial, as the forming and the static problems
call it (fortran/solver/ddpy_forming_newton.f90, ``forming_increment``).

One loop serves both: the static problem is the forming problem without tools, whose fixed
dofs move to prescribed values. ``Layout`` numbers the unknowns and reads the Jacobian's
coordinate structure from the core, ``ToolPack`` gathers the tools' contact (the blank
faces that face each, their Gauss points' areas, the penalties), ``CoreProblem`` hands the
core a problem's fixed data once (its handle), ``Loop`` says how the loop runs,
``increment`` makes a trial and says what came of it (``Trial``), ``contact`` looks at the
contact alone and ``equations`` at the equations the loop solves.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy.core.constants import constant
from ddpy.core.handles import CoreHandle, check
from ddpy.core.linalg import LinearSolverError, distinct
from ddpy.core.memory import keep_freed_memory
from ddpy.model.control import FormingTuning
from ddpy.model.mesh import HexMesh, boundary_faces, face_area_vectors
from ddpy.model.solid import ElementError, Solid, SolidState, _flat
from ddpy.model.tool import RigidTool

#: What the core's forming_increment returns.
CONVERGED, LANDING, ELEMENT, NOT_FINITE, SOLVER, STALLED, HOLD = (
    constant(f"outcome_{name}") for name in
    ("converged", "landing", "element", "not_finite", "solver", "stalled", "hold"))
#: Line searches of the core's loop: none (whole steps, halved only where an element
#: fails); Deuflhard's natural monotonicity test with the residual-norm fallback (forming:
#: the contact law has no potential); the energy line search (a problem with a potential).
SEARCH_NONE, SEARCH_MONOTONICITY, SEARCH_ENERGY = (
    constant(f"line_search_{name}") for name in ("none", "monotonicity", "energy"))
#: The core's code of each contact discretization.
SURFACE_CODES = {name: constant(f"discretization_{name}")
                 for name in ("node", "surface", "gauss")}
#: The parts of a trial's time, as the core measures them.
PARTS = ("assembly", "contact", "factorization", "solve")
#: The columns of the core's iteration history.
_HISTORY = {name: constant(f"history_{name}_offset")
            for name in ("residual", "relative_residual", "relative_correction", "step",
                         "points_switched", "pairs_switched", "yield_switched",
                         "relative_error")}


class Iteration(NamedTuple):
    """One Newton iteration of an increment: the residual over the force scale, the
    correction that led to the iterate over the increment's motion (inf before the first),
    the length of its step (0 at the start), what changed since the previous iterate (0 at
    the start: the contact points whose pressure turned on or off, the pairs whose contact
    state changed, the blank's integration points that turned from elastic to plastic or
    back), and the iterate's error over the motion as the convergence test estimates it
    (the correction, or less once whole Newton steps contract; docs/theory/contact.md,
    "The convergence test"). Convergence is judged on the residual and the error."""

    residual: float
    correction: float
    step: float = 0.0
    points_switched: int = 0
    pairs_switched: int = 0
    yield_switched: int = 0
    error: float = float("nan")


def _join(parts: Sequence[NDArray], dtype: type) -> NDArray:
    """The arrays one after another (an empty array of dtype for none)."""
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)


def contact_faces(tools: Sequence[RigidTool], mesh: HexMesh) -> list[NDArray[np.int32]]:
    """Per tool, the blank's boundary faces (f, 4) that face it: outward normal within 60
    degrees of its ``facing`` direction (none for a tool without one). Their nodes give a
    node-to-surface tool's slaves their normals for the facing filter, and a
    surface-to-surface or Gauss-point tool its contact surface (Gauss points and patches)."""
    if not tools:
        return []
    boundary = boundary_faces(mesh.elements)
    area = face_area_vectors(mesh.nodes, boundary)
    return [np.zeros((0, 4), dtype=np.int32) if tool.facing is None else
            boundary[area @ tool.facing > 0.5 * np.linalg.norm(area, axis=1)].astype(np.int32)
            for tool in tools]


def corner_areas(nodes: NDArray[np.float64], faces: NDArray[np.integer], corners:
                 NDArray[np.integer], n_slaves: int, order: int = 2) -> NDArray[np.float64]:
    """Each slave's share of the faces' area (n_slaves,): int N_a dA over the faces (f, 4)
    whose corners (f, 4) name it (-1: no slave), by order x order Gauss points."""
    share = gauss_face_weights(nodes, faces, order) @ face_basis(order)  # (f, 4)
    area = np.zeros(n_slaves)
    np.add.at(area, corners[corners >= 0], share[corners >= 0])
    return area


def gauss_face_weights(nodes: NDArray[np.float64], faces: NDArray[np.integer],
                       order: int = 2) -> NDArray[np.float64]:
    """The area each of the order x order Gauss points of quadrilateral faces (f, 4) stands
    for (f, order^2): the Gauss weights times |dX/dxi x dX/deta| at the point, in the order
    of the core's points (xi runs fastest, each from -1 to 1), the corners (xi, eta) =
    (-1, -1), (1, -1), (1, 1), (-1, 1). They sum to each face's area."""
    x = nodes[faces]                                              # (f, 4, 3)
    points_xi, points_eta, gauss = face_gauss_points(order)
    weights = np.empty((faces.shape[0], order * order), dtype=float)
    for g, (xi, eta) in enumerate(zip(points_xi, points_eta, strict=True)):
        dxi = 0.25 * FACE_CORNERS[:, 0] * (1.0 + FACE_CORNERS[:, 1] * eta)    # dN_q/dxi
        deta = 0.25 * FACE_CORNERS[:, 1] * (1.0 + FACE_CORNERS[:, 0] * xi)
        weights[:, g] = gauss[g] * np.linalg.norm(
            np.cross(np.einsum("q,fqk->fk", dxi, x), np.einsum("q,fqk->fk", deta, x)), axis=1)
    return weights


#: The corners (xi, eta) of a quadrilateral face, in the order of its nodes.
FACE_CORNERS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


def face_gauss_points(order: int
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The order x order Gauss points of a quadrilateral face in the core's order (xi runs
    fastest, each from -1 to 1): xi, eta and weight of each (order^2,)."""
    points, weights = np.polynomial.legendre.leggauss(order)
    return (np.tile(points, order), np.repeat(points, order),
            np.tile(weights, order) * np.repeat(weights, order))


def face_basis(order: int) -> NDArray[np.float64]:
    """The 4 shape functions of a quadrilateral face at its Gauss points (order^2, 4)."""
    xi, eta, _ = face_gauss_points(order)
    return 0.25 * (1.0 + np.outer(xi, FACE_CORNERS[:, 0])) * (
        1.0 + np.outer(eta, FACE_CORNERS[:, 1]))


class Layout:
    """The unknowns of one constraint set and the Jacobian's coordinate structure, which
    the core computes (fortran/solver/ddpy_jacobian_layout.f90): free displacement dofs
    first, then 3 force components per (tool, slave) pair, then one displacement per
    force-controlled tool. ``symmetric``: the solid's block as its lower triangle (a
    symmetric MUMPS instance; only without tools, whose contact blocks are not symmetric).
    Each pair's law depends on the positions of its patch of nodes (``patch_first``,
    ``patch_node``): its own node for a node-to-surface tool, every node of the tool's
    contact faces at its node for a surface-to-surface or Gauss-point one (its own node
    alone where it is on none). ``holds``: the force-controlled tools (indices into
    ``tools``), each pressing along ``-facing``: its displacement along that axis is one
    more unknown after the pairs' forces, its equation the balance of its pairs' forces
    with the prescribed force.

    The core's copy of the problem (``core_problem``) is made here, and the structure
    (``rows``, ``cols``: 0-based, in the order the core writes the values; ``n`` unknowns,
    ``k_slots`` of the solid's tangent first) is read from it; the solver is analysed with
    its distinct ``entries``."""

    def __init__(self, solid: Solid, tools: Sequence[RigidTool], fixed: NDArray[np.bool_],
                 symmetric: bool = False, holds: Sequence[int] = ()) -> None:
        if symmetric and tools:
            raise ValueError("a symmetric layout has no tools: the contact law's Jacobian "
                             "is not symmetric")
        for k in holds:
            if tools[k].facing is None:
                raise ValueError(f"tool {tools[k].name} has no facing direction: a force "
                                 "along it cannot be held")
        n = solid.mesh.n_nodes
        free = ~fixed.ravel()
        self.symmetric = symmetric
        self.nf = int(free.sum())
        eqn = np.full(3 * n, -1, dtype=np.int32)
        eqn[free] = np.arange(self.nf, dtype=np.int32)
        self.eqn = eqn
        #: each pair's node and tool, each tool's first pair (int32: as the core takes them)
        self.node = _join([t.slaves for t in tools], np.int32)
        self.tool_of = _join([np.full(t.slaves.size, i) for i, t in enumerate(tools)],
                             np.int64)
        self.first = np.concatenate([[0], np.cumsum([t.slaves.size for t in tools])]
                                    ).astype(np.int32)
        # The blank faces that face each tool (and the areas of their Gauss points), as the
        # core's contact takes them; the penalties are the pack's (core_problem), the
        # barriers' depths too, but which tools have one shapes the layout.
        pack = ToolPack(tools, solid.mesh, barrier_depth=[
            0.0 if t.contact == "gauss" and t.barrier is not None else -1.0 for t in tools])
        patches = []
        for tool, (faces, _, _) in zip(tools, pack.tool_faces, strict=True):
            if tool.contact not in ("surface", "gauss"):
                patches.extend([s] for s in tool.slaves)
                continue
            around: dict[int, set[int]] = {int(s): {int(s)} for s in tool.slaves}
            for face in faces.tolist():
                for node in face:
                    if node in around:
                        around[node].update(face)
            patches.extend(sorted(around[int(s)]) for s in tool.slaves)
        self.patch_first = np.concatenate([[0], np.cumsum([len(p) for p in patches])]
                                          ).astype(np.int32)
        self.patch_node = _join([np.asarray(p) for p in patches], np.int32)
        #: the force-controlled tools (indices) and the axes they press along (-facing)
        self.holds = np.asarray(holds, dtype=np.int32)
        self.hold_axis = np.array([-np.asarray(tools[k].facing, dtype=float) for k in holds]
                                  ).reshape(-1, 3)
        self._problem = CoreProblem(solid, self, pack)
        n_unknowns, nvalues, k_slots, status = _core.problem_layout_size(self._problem.handle)
        check(status, "the Jacobian's layout")
        rows, cols, status = _core.problem_layout(self._problem.handle, nvalues)
        check(status, "the Jacobian's layout")
        self.n, self.k_slots = int(n_unknowns), int(k_slots)
        self.rows, self.cols = rows, cols

    def entries(self) -> tuple[NDArray[np.int32], NDArray[np.int32]]:
        """The Jacobian's distinct entries (rows, cols; 0-based, by row, then column): the
        coordinates summed, which the solver is analysed with and the core's Newton loop
        factorizes (a forming blank's coordinates repeat each entry about twice, once per
        element around it; MUMPS would keep them all, docs/theory/linear-solver.md, "The
        entries"). A symmetric layout's are those of its one triangle. Computed at each
        call (the analysis needs them once; kept, they would hold memory all run)."""
        key = distinct(self.rows.astype(np.int64) * self.n + self.cols)
        return (key // self.n).astype(np.int32), (key % self.n).astype(np.int32)

    def core_problem(self, pack: ToolPack | None) -> CoreProblem:
        """The core's copy of the problem of this layout, with the penalties and barriers
        of ``pack`` (none: the static problem, or the layout's own, zero)."""
        problem = self._problem
        if pack is not None and pack is not problem.pack:
            problem.set_pack(pack)
        return problem


class ToolPack:
    """Every tool's contact with the blank: its search (the core's copy of its surface,
    ``RigidTool.search``), its facing direction and discretization, the blank faces that
    face it with the area each of their Gauss points stands for, and the penalty of each
    Gauss-point tool (``penalty``, per tool; 0 for the others) with its barrier's depth
    (``barrier_depth``, mm; negative: none): what the
    core's contact reads (fortran/mechanics/ddpy_forming.f90), per tool (``tool_faces``)
    and, for contact_pressure, one tool after another. Made once; empty for none."""

    def __init__(self, tools: Sequence[RigidTool], mesh: HexMesh,
                 penalty: Sequence[float] | None = None,
                 barrier_depth: Sequence[float] | None = None) -> None:
        self.tools = list(tools)
        self.names = [t.name for t in tools]
        faces = contact_faces(tools, mesh)
        # Per tool with a facing direction, the blank's boundary faces that face it (normal
        # within 60 degrees) and the slave index of their corners (-1: not a slave): the
        # search keeps only patches opposing the blank's normal at each slave; a
        # surface-to-surface or Gauss-point tool projects their Gauss points, which stand
        # for the areas face_weight of the undeformed blank (n x n per face, n the tool's
        # points).
        # A Gauss-point tool's points are followed by one per slave, its node point
        # (forming_contact: its barrier), which stands for the slave's share of the faces'
        # area.
        corners, weights = [], []
        for tool, chosen in zip(tools, faces, strict=True):
            where = np.full(mesh.n_nodes, -1, dtype=np.int32)
            where[tool.slaves] = np.arange(tool.slaves.size)
            corners.append(where[chosen])
            weights.append(gauss_face_weights(mesh.nodes, chosen, tool.points).ravel()
                           if tool.contact != "node"
                           else np.zeros(chosen.shape[0] * tool.points**2))
            if tool.contact == "gauss":
                weights[-1] = np.concatenate([weights[-1], corner_areas(
                    mesh.nodes, chosen, corners[-1], tool.slaves.size)])
        #: per tool, its faces (f, 4), their corners' slave indices (f, 4) and the area of
        #: each of its points (the core's face_weight)
        self.tool_faces = [(f.astype(np.int32), c.astype(np.int32), w.astype(np.float64))
                           for f, c, w in zip(faces, corners, weights, strict=True)]
        self.face_first = np.concatenate([[0], np.cumsum([f.shape[0] for f in faces])]
                                         ).astype(np.int32)
        self.faces = _join([f.ravel() for f in faces], np.int32)
        self.face_weight = _join(weights, np.float64)
        #: per tool, where its points start in the flat point arrays (and the end)
        self.point_first = np.concatenate([[0], np.cumsum([w.size for w in weights])]
                                          ).astype(np.int64)
        #: per tool, the normal (= tangential) penalty of Gauss-point contact (N/mm^3) and
        #: the depth of its barrier (mm; negative: none)
        self.penalty = np.zeros(len(tools)) if penalty is None else \
            np.asarray(penalty, dtype=float).reshape(len(tools))
        self.barrier_depth = np.full(len(tools), -1.0) if barrier_depth is None else \
            np.asarray(barrier_depth, dtype=float).reshape(len(tools))
        #: Gauss points of all faces: their tangential tractions are (3,) each
        self.n_points = int(self.face_weight.size)

    def arguments(self, positions: dict[str, NDArray[np.float64]],
                  positions_n: dict[str, NDArray[np.float64]], reach: float, size: float
                  ) -> ToolPlacement:
        """The tools where they are (``positions``) and where they were at the last
        converged increment (``positions_n``), with the search's reach and the element
        size, as the core's contact and loop take them."""
        return ToolPlacement(self, _join([positions[n] for n in self.names], np.float64),
                             _join([positions_n[n] for n in self.names], np.float64),
                             float(reach), float(size))


@dataclass(frozen=True)
class ToolPlacement:
    """The tools of ``pack`` at ``positions`` (3 per tool), at ``positions_n`` at the last
    converged increment, with the contact search's ``reach`` and the blank's element
    ``size`` (mm)."""

    pack: ToolPack
    positions: NDArray[np.float64]
    positions_n: NDArray[np.float64]
    reach: float
    size: float


class CoreProblem:
    """A problem's fixed data handed to the core once (fortran/api/ddpy_api_forming.f90),
    held behind a handle of its table: the blank of ``solid`` with the unknowns of
    ``layout``, the tools of ``pack`` one by one with their pairs, and the force-controlled
    tools; the core computes the Jacobian's layout from them. Each trial then gives the
    core what changes: settings, limits, state, tools' positions, pairs' law."""

    def __init__(self, solid: Solid, layout: Layout, pack: ToolPack) -> None:
        tools = pack.tools
        if layout.first.size != len(tools) + 1:
            raise ValueError(f"the layout has {layout.first.size - 1} tool(s), the pack "
                             f"{len(tools)}")
        self.solid = solid
        keep_freed_memory()  # the loop's work arrays stay mapped between iterations
        handle, status = _core.problem_create(solid.blank_handle, layout.eqn,
                                              int(layout.symmetric))
        check(status, "the problem's blank and unknowns")
        self._handle = CoreHandle(handle)
        for k, tool in enumerate(tools):
            faces, corners, weights = pack.tool_faces[k]
            pairs = slice(layout.first[k], layout.first[k + 1])
            patch_first = layout.patch_first[layout.first[k]:layout.first[k + 1] + 1]
            check(_core.problem_add_tool(
                handle, tool.search.handle, faced=int(tool.facing is not None),
                facing=np.zeros(3) if tool.facing is None else tool.facing,
                discretization=SURFACE_CODES[tool.contact], order=tool.points,
                faces=faces.ravel(), corner=corners.ravel(), face_weight=weights,
                slaves=layout.node[pairs], patch_first=patch_first - patch_first[0],
                patch_node=layout.patch_node[patch_first[0]:patch_first[-1]]),
                f"tool {tool.name}'s contact")
        if layout.holds.size:
            check(_core.problem_set_holds(handle, layout.holds, layout.hold_axis.ravel()),
                  "the force-controlled tools")
        self.pack = pack
        self.set_pack(pack)

    @property
    def handle(self) -> int:
        return self._handle.handle

    def set_pack(self, pack: ToolPack) -> None:
        """The penalties and barriers of Gauss-point contact of ``pack``'s tools, the
        problem's tools (the blank faces facing them are the same: the pack's are not
        read)."""
        if [t.name for t in pack.tools] != [t.name for t in self.pack.tools]:
            raise ValueError(f"the pack's tools {pack.names} are not the problem's "
                             f"{self.pack.names}")
        for k in range(len(pack.tools)):
            check(_core.problem_set_penalty(
                self.handle, k, normal_penalty=pack.penalty[k],
                tangential_penalty=pack.penalty[k], barrier_depth=pack.barrier_depth[k]),
                f"tool {pack.names[k]}'s penalty")
        self.pack = pack

    def set_state(self, state: SolidState) -> None:
        """The blank's converged state the next trials and evaluations start from."""
        check(_core.problem_set_state(
            self.handle, _flat(state.displacement), _flat(state.axes.transpose(0, 1, 3, 2)),
            _flat(state.stress), _flat(state.ep), _flat(state.strain),
            self.solid.backstress_in(state)), "the blank's converged state")

    def set_start(self, u_n: NDArray[np.float64], external: NDArray[np.float64],
                  prescribed: NDArray[np.float64], guess: NDArray[np.float64] | None,
                  force_n: NDArray[np.float64]) -> None:
        """The converged displacements u_n (n, 3), the nodal loads, the fixed dofs'
        values, the iterations' start (none: u_n) and the pairs' converged forces."""
        check(_core.problem_set_start(
            self.handle, u_n.ravel(), external.ravel(), prescribed.ravel(),
            (u_n if guess is None else guess).ravel(), int(guess is not None), force_n),
            "the increment's start")

    def set_tools(self, placement: ToolPlacement, hold_force: ArrayLike | None,
                  holds: int) -> None:
        """Where the tools are, and the forces of the ``holds`` force-controlled tools (N;
        default zero)."""
        force = np.zeros(holds) if hold_force is None else np.asarray(hold_force, float)
        if force.shape != (holds,):
            raise ValueError(f"{holds} force-controlled tool(s) need as many forces, got "
                             f"{force.size}")
        check(_core.problem_set_tools(self.handle, placement.positions, placement.positions_n,
                                      force), "the tools")

    def set_law(self, on: NDArray[np.bool_], r: ArrayLike, mu: ArrayLike,
                traction_n: ArrayLike, pressure_n: ArrayLike) -> None:
        """The pairs' law: which take part, their augmentation and friction, the Gauss
        points' tangential tractions (points, 3) and pressure multipliers at the last
        converged increment."""
        check(_core.problem_set_law(self.handle, on.astype(np.int32), r, mu,
                                    np.asarray(traction_n, float).ravel(), pressure_n),
              "the pairs' law")

    def set_limits(self, *, reach: float, element_size: float, touching: float = 0.0,
                   resting: bool = True, penetration: float = 0.0, min_step: float = 1.0,
                   yield_tolerance: float | None = None, size_ratio: float = 1.0,
                   hold_step: float = 0.0) -> None:
        """The limits of the next trials and looks (fortran/mechanics/ddpy_forming_data.f90,
        increment_limits)."""
        check(_core.problem_set_limits(
            self.handle, reach=reach, element_size=element_size, touching=touching,
            resting=int(resting), penetration=penetration, min_step=min_step,
            yield_tolerance=-1.0 if yield_tolerance is None else yield_tolerance,
            size_ratio=size_ratio, hold_step=hold_step), "the increment's limits")


@dataclass(frozen=True)
class Loop:
    """How the core's loop runs an increment trial: the convergence tolerances and
    iterations, the force scale's floor (N), the yield landing's tolerance (None: off),
    the penetration limit (element sizes) and the shortest step it may leave, the linear
    solver (reuse of older factors by GMRES: its tolerance bounds, the linear residual a
    possibly last correction may leave in force tolerances, iterations at most and after
    which the next correction factorizes), the line search (SEARCH_*) with the
    residual ratio under which a whole step that changed contact states stands although
    it fails the monotonicity test (0: off), the touching predictor's gap and resting
    flag, the size ratio: the largest increment over this one's size (at least 1), by
    which the convergence test scales the increment's motion up, so that a cut does not
    tighten it (docs/theory/contact.md, "The convergence test"), and whether the contact
    search remembers its answers over the trial's evaluations (the same answers, found
    with less work: docs/theory/contact.md, "Search memory")."""

    force_tolerance: float
    displacement_tolerance: float
    max_iterations: int
    floor: float
    yield_tolerance: float | None = None
    penetration: float = 0.0
    min_step: float = 1.0
    reuse: bool = False
    krylov_loose: float = FormingTuning.krylov_loose
    krylov_tight: float = FormingTuning.krylov_tight
    krylov_last: float = FormingTuning.krylov_last
    krylov_max: int = FormingTuning.krylov_max
    krylov_keep: int = FormingTuning.krylov_keep
    search: int = SEARCH_MONOTONICITY
    whole_step: float = 0.0
    touching: float = 0.0
    resting: bool = True
    size_ratio: float = 1.0
    search_memory: bool = True


@dataclass
class Trial:
    """What one increment trial gives: converged (``failure`` empty and ``landing`` 1) with
    the new state, the internal forces, its residual history and the contact states, gaps
    and normals of the pairs; or the fraction of the increment at which the first elastic
    point lands on the yield surface (``landing`` < 1); or why it failed (``solver``: the
    status of the factorization or solve that failed, 0 where none did). Always: the work
    done (``counters``: evaluations, corrections, factorizations, Krylov iterations,
    line-search fallbacks) and its time per part (PARTS)."""

    failure: str = ""
    landing: float = 1.0
    solver: int = 0
    u: NDArray[np.float64] | None = None
    state: SolidState | None = None
    force: NDArray[np.float64] | None = None
    fint: NDArray[np.float64] | None = None
    residuals: list[float] = field(default_factory=list)
    #: per iteration from the start (Iteration)
    convergence: list[Iteration] = field(default_factory=list)
    in_contact: NDArray[np.int32] | None = None
    #: the tangential traction of every Gauss point of Gauss-point contact (points, 3)
    traction: NDArray[np.float64] | None = None
    #: the normal pressure of every Gauss point of Gauss-point contact (points,)
    pressure: NDArray[np.float64] | None = None
    gap: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
    #: per force-controlled tool (Layout.holds), its displacement along its axis from
    #: where the increment took it
    shift: NDArray[np.float64] | None = None
    #: the force-controlled tool that lost its hold on the blank (its index), with why
    hold: tuple[int, str] | None = None
    counters: tuple[int, ...] = (0, 0, 0, 0, 0)
    timings: dict[str, float] = field(default_factory=dict)


@dataclass
class Factors:
    """What the MUMPS instance holds between calls: factors of a Jacobian of this layout
    (``factored``), and whether the last GMRES on them converged fast (``reuse_next``)."""

    handle: int
    factored: bool = False
    reuse_next: bool = True


@dataclass(frozen=True)
class Pairs:
    """The (tool, slave) pairs of an increment: the tools where the increment takes them
    (``ToolPack.arguments``), the pairs that take part (``on``), their augmentation ``r``,
    friction ``mu`` and contact forces at the converged state, and the tangential traction
    of each Gauss point of Gauss-point contact there (``traction_n``, (points, 3)) with its
    pressure multiplier (``pressure_n``, (points,): the augmented Lagrangian's, 0 for the
    plain penalty). ``hold_force``: per force-controlled tool (Layout.holds), the force
    it presses on the blank with at the increment's end (N); ``hold_step``: the most it
    may move in one Newton step (mm)."""

    tools: ToolPlacement
    on: NDArray[np.bool_]
    r: NDArray[np.float64]
    mu: NDArray[np.float64]
    force_n: NDArray[np.float64]
    traction_n: NDArray[np.float64]
    pressure_n: NDArray[np.float64]
    hold_force: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    hold_step: float = 0.0


def increment(solid: Solid, layout: Layout, factors: Factors, state: SolidState,
              u_n: NDArray[np.float64], external: NDArray[np.float64],
              prescribed: NDArray[np.float64], guess: NDArray[np.float64] | None, loop: Loop,
              pairs: Pairs | None = None) -> Trial:
    """One increment trial by the core from the converged (u_n, state): nodal loads
    ``external`` (n, 3), the fixed dofs to ``prescribed`` (n, 3; u_n there for supports
    that hold), starting at ``guess`` (unless an element fails there) or at u_n, with the
    contact ``pairs`` of the tools (none: the static problem). ``factors`` is updated."""
    if pairs is None and layout.node.size:
        raise ValueError("a layout with contact pairs needs their Pairs")
    placement = None if pairs is None else pairs.tools
    problem = layout.core_problem(None if placement is None else placement.pack)
    handle = problem.handle
    check(_core.problem_set_newton(
        handle, force_tolerance=loop.force_tolerance,
        displacement_tolerance=loop.displacement_tolerance,
        max_iterations=loop.max_iterations, floor=loop.floor, reuse=int(loop.reuse),
        krylov_loose=loop.krylov_loose, krylov_tight=loop.krylov_tight,
        krylov_last=loop.krylov_last, krylov_max=loop.krylov_max,
        krylov_keep=loop.krylov_keep, line_search=loop.search,
        whole_step=loop.whole_step, search_memory=int(loop.search_memory)),
        "the Newton loop's settings")
    problem.set_limits(
        reach=0.0 if placement is None else placement.reach,
        element_size=solid.mesh.element_size() if placement is None else placement.size,
        touching=loop.touching, resting=loop.resting, penetration=loop.penetration,
        min_step=loop.min_step, yield_tolerance=loop.yield_tolerance,
        size_ratio=loop.size_ratio, hold_step=0.0 if pairs is None else pairs.hold_step)
    problem.set_state(state)
    force_n = np.zeros(0) if pairs is None else \
        np.where(pairs.on[:, None], pairs.force_n, 0.0).ravel()
    problem.set_start(u_n, external, prescribed, guess, force_n)
    if pairs is not None:  # (the static problem has no tools and no pairs)
        problem.set_tools(placement, pairs.hold_force, layout.holds.size)
        problem.set_law(pairs.on, pairs.r, pairs.mu, pairs.traction_n, pairs.pressure_n)
    # The static problem never reuses older factors (its loop has no Krylov solves).
    factored, reuse_next, outcome, status = _core.problem_increment(
        handle, factors.handle, int(factors.factored),
        int(factors.reuse_next) if pairs is not None else 0)
    check(status, "the increment trial")
    factors.factored = bool(factored)
    if pairs is not None:
        factors.reuse_next = bool(reuse_next)
    (_, niter, evaluations, corrections, factorizations, krylov, fallbacks, *spent,
     element_status, element, solver_status, flipped, hold_tool, hold_reason, landing,
     residual, correction, status) = _core.problem_report(handle)
    check(status, "the increment's report")
    history, status = _core.problem_history(handle, niter)
    check(status, "the increment's history")
    history = history.reshape(-1, constant("history_width"))
    work = {"counters": (evaluations, corrections, factorizations, krylov, fallbacks),
            "timings": {key: float(t) for key, t in zip(PARTS, spent, strict=True)},
            "residuals": history[:, _HISTORY["residual"]].tolist(),
            "convergence": [Iteration(float(row[_HISTORY["relative_residual"]]),
                                      float(row[_HISTORY["relative_correction"]]),
                                      float(row[_HISTORY["step"]]),
                                      int(row[_HISTORY["points_switched"]]),
                                      int(row[_HISTORY["pairs_switched"]]),
                                      int(row[_HISTORY["yield_switched"]]),
                                      float(row[_HISTORY["relative_error"]]))
                            for row in history]}
    if outcome == CONVERGED:
        return _converged(solid, layout, problem, work)
    if outcome == LANDING:
        return Trial(landing=float(landing), **work)
    if outcome == ELEMENT:
        return Trial(str(ElementError(int(element_status), int(element) - 1)), **work)
    if outcome == NOT_FINITE:
        return Trial("the residual is not finite", **work)
    if outcome == SOLVER:
        factors.factored = False
        return Trial(str(LinearSolverError(int(solver_status), "factorization or solve")),
                     solver=int(solver_status), **work)
    if outcome == HOLD:
        why = ("nothing holds it along its axis: no slave node is in contact with it"
               if hold_reason == constant("hold_no_stiffness") else
               "it moved farther than the contact search's reach in one increment: the "
               "blank does not carry its force")
        return Trial(f"force-controlled tool {hold_tool} lost the blank: {why}",
                     hold=(int(hold_tool), why), **work)
    if outcome == STALLED:
        return Trial(stalled(loop.max_iterations, float(residual), float(correction),
                             loop.force_tolerance, loop.displacement_tolerance,
                             int(flipped)), **work)
    raise RuntimeError(f"forming_increment ended with an unknown outcome {outcome}")


def _converged(solid: Solid, layout: Layout, problem: CoreProblem, work: dict) -> Trial:
    """The converged trial's answer, read from the core into new arrays."""
    out = solid.state_buffer()
    n = solid.mesh.n_nodes
    u, fint = np.empty(3 * n), np.empty(3 * n)
    check(_core.problem_blank_answer(
        problem.handle, u, fint, out.stress.ravel(), out.ep.ravel(), out.strain.ravel(),
        out.axes.transpose(0, 1, 3, 2).ravel(), solid.backstress_out(out))[-1],
        "the increment's answer")
    npoint = problem.pack.n_points
    force, state, gap, normal, traction, pressure, shift, status = _core.problem_pair_answer(
        problem.handle, layout.node.size, npoint, layout.holds.size)
    check(status, "the increment's answer")
    converged = SolidState(out.stress, out.ep, out.strain, out.axes, u.reshape(n, 3),
                           out.backstress if solid.mixed else None)
    return Trial(u=u.reshape(n, 3), state=converged, force=force.reshape(-1, 3),
                 fint=fint.reshape(n, 3), in_contact=state, gap=(gap, normal.reshape(-1, 3)),
                 traction=traction.reshape(-1, 3), pressure=pressure, shift=shift, **work)


def contact(solid: Solid, layout: Layout, placement: ToolPlacement, on: NDArray[np.bool_],
            force: NDArray[np.float64], r: ArrayLike, mu: ArrayLike, traction_n: ArrayLike,
            pressure_n: ArrayLike, x: NDArray[np.float64], x_n: NDArray[np.float64],
            residual: NDArray[np.float64], values: NDArray[np.float64],
            touching: float = 0.0, resting: bool = True,
            hold_force: ArrayLike | None = None
            ) -> tuple[NDArray[np.int32], NDArray[np.float64], NDArray[np.float64]]:
    """Contact of every pair at positions x (n, 3), from the converged x_n, in one call to
    the core, the same as an evaluation of the loop: the search of each tool with a pair
    that takes part (``on``), the law (augmentation ``r``, friction ``mu``, the Gauss
    points' tractions and pressures at the last converged increment) at the pairs' forces
    ``force`` (pairs, 3), with the touching predictor of the first iteration for pairs
    within ``touching`` (docs/theory/contact.md). It writes the law's rows of ``residual``
    and subtracts the pairs' forces from its equilibrium rows (which hold fint -
    external), and writes the contact entries of ``values`` (none when it is empty: a look
    at the gaps), and the rows and entries of the force-controlled tools, pressing with
    ``hold_force``. Returns the pairs' states, gaps (inf: no patch) and normals (pairs,
    3)."""
    problem = layout.core_problem(placement.pack)
    problem.set_limits(reach=placement.reach, element_size=placement.size, touching=touching,
                       resting=resting)
    problem.set_tools(placement, hold_force, layout.holds.size)
    problem.set_law(on, r, mu, traction_n, pressure_n)
    residual[:], values[:], state, gap, normal, _, _, status = _core.problem_contact(
        problem.handle, np.asarray(x, float).ravel(), np.asarray(x_n, float).ravel(),
        np.asarray(force, float).ravel(), residual, values, placement.pack.n_points)
    check(status, "the contact of the pairs")
    return state, gap, normal.reshape(-1, 3)


def equations(solid: Solid, layout: Layout, placement: ToolPlacement, state: SolidState,
              u_n: NDArray[np.float64], external: NDArray[np.float64],
              u: NDArray[np.float64], force: NDArray[np.float64], r: ArrayLike,
              mu: ArrayLike, traction_n: ArrayLike, pressure_n: ArrayLike,
              touching: float = 0.0, hold_force: ArrayLike | None = None
              ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int32]]:
    """The equations the core's loop solves, as the core evaluates them (problem_evaluate)
    at displacements u (n, 3) and pair forces ``force`` (pairs, 3), in the increment from
    the converged (u_n, ``state``) under the nodal loads ``external`` (n, 3), with the tools
    of ``placement`` and every pair taking part (augmentation ``r``, friction ``mu``, the
    Gauss points' tractions and pressures at the last converged increment); pairs within
    ``touching`` count as closed, as in an increment's first iteration. ``hold_force``:
    the force-controlled tools' forces (N). Returns the residual, the Jacobian's values in
    the layout's slots (``Layout.rows``, ``cols``) and the pairs' states (a Gauss-point
    pair's law rows are lambda - F(x), before the loop eliminates its multiplier). Raises
    ElementError where an element fails."""
    problem = layout.core_problem(placement.pack)
    problem.set_limits(reach=placement.reach, element_size=placement.size, touching=touching)
    problem.set_tools(placement, hold_force, layout.holds.size)
    problem.set_law(np.ones(layout.node.size, dtype=bool), r, mu, traction_n, pressure_n)
    problem.set_state(state)
    problem.set_start(u_n, external, u_n, None, np.zeros(3 * layout.node.size))
    residual, values, pair_state, element_status, element, status = _core.problem_evaluate(
        problem.handle, np.asarray(u, float).ravel(), np.asarray(force, float).ravel(),
        layout.n, layout.rows.size)
    check(status, "the equations")
    if element_status:
        raise ElementError(int(element_status), int(element) - 1)
    return residual, values, pair_state


def stalled(iterations: int, residual: float, correction: float, tol_force: float,
            tol_disp: float, flipped: int) -> str:
    """Why an increment did not converge: its last residual and correction against their
    tolerances, and how many contact pairs changed state in its last iteration."""
    text = (f"no convergence in {iterations} iterations: residual {residual:.2e} of the force "
            f"scale (tolerance {tol_force:.0e}), correction {correction:.2e} of the motion "
            f"(tolerance {tol_disp:.0e})")
    if flipped > 0:
        text += f"; {flipped} contact pair(s) still changed state in the last iteration"
    return text
