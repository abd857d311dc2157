"""The core's Newton loop of one increment trial, as the forming and the static problems
call it (fortran/solver/ddpy_forming_newton.f90, ``forming_increment``).

One loop serves both: the static problem is the forming problem without tools, whose fixed
dofs move to prescribed values. ``Layout`` numbers the unknowns and fixes the Jacobian's
coordinate structure, ``ToolPack`` packs the tools' surfaces and search structures,
``Loop`` says how the loop runs, and ``increment`` makes the call and says what came of
it (``Trial``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy.core.linalg import LinearSolverError, RowStructure, row_structure
from ddpy.geometry.search import SearchArrays
from ddpy.model.mesh import HexMesh, boundary_faces, face_area_vectors
from ddpy.model.solid import ElementError, Solid, SolidState, _flat
from ddpy.model.tool import RigidTool

#: What the core's forming_increment returns.
CONVERGED, LANDING, ELEMENT, NOT_FINITE, SOLVER, STALLED, HOLD = range(7)
#: Line searches of the core's loop: none (whole steps, halved only where an element
#: fails); Deuflhard's natural monotonicity test with the residual-norm fallback (forming:
#: the contact law has no potential); the energy line search (a problem with a potential).
SEARCH_NONE, SEARCH_MONOTONICITY, SEARCH_ENERGY = range(3)
#: The table's code of each contact discretization (ddpy_forming's f_surface column).
SURFACE_CODES = {"node": 0, "surface": 1, "gauss": 2}
#: The parts of a trial's time, as the core measures them.
PARTS = ("assembly", "contact", "factorization", "solve")


def _join(parts: Sequence[NDArray], dtype: type) -> NDArray:
    """The arrays one after another (an empty array of dtype for none)."""
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)


def _padded(values: ArrayLike, dtype: type) -> NDArray:
    """``values`` as a flat array of dtype at least one long (a zero after an empty one):
    f2py passes no empty array."""
    flat = np.asarray(values, dtype=dtype).ravel()
    return flat if flat.size else np.zeros(1, dtype=dtype)


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
    """Unknowns and the fixed coordinate structure of the Jacobian for one constraint set:
    free displacement dofs first, then 3 force components per (tool, slave) pair.
    ``symmetric``: the solid's block as its lower triangle (a symmetric MUMPS instance; only
    without tools, whose contact blocks are not symmetric). Each pair's law depends on the
    positions of its patch of nodes (``patch_first``, ``patch_node``): its own node for a
    node-to-surface tool, every node of the tool's contact faces at its node for a
    surface-to-surface or Gauss-point one (its own node alone where it is on none).
    ``holds``: the force-controlled tools (indices into ``tools``), each pressing along
    ``-facing``: its displacement along that axis is one more unknown after the pairs'
    forces, its equation the balance of its pairs' forces with the prescribed force."""

    def __init__(self, solid: Solid, tools: Sequence[RigidTool], fixed: NDArray[np.bool_],
                 symmetric: bool = False, holds: Sequence[int] = ()) -> None:
        if symmetric and tools:
            raise ValueError("a symmetric layout has no tools: the contact law's Jacobian "
                             "is not symmetric")
        n = solid.mesh.n_nodes
        free = ~fixed.ravel()
        self.symmetric = symmetric
        self.nf = int(free.sum())
        eqn = np.full(3 * n, -1, dtype=np.int32)
        eqn[free] = np.arange(self.nf, dtype=np.int32)
        self.eqn = eqn
        self.pattern = solid.pattern(eqn, symmetric=symmetric)
        #: each pair's node and tool, each tool's first pair (int32: as the core takes them)
        self.node = _join([t.slaves for t in tools], np.int32)
        self.tool_of = _join([np.full(t.slaves.size, i) for i, t in enumerate(tools)],
                             np.int64)
        self.first = np.concatenate([[0], np.cumsum([t.slaves.size for t in tools])]
                                    ).astype(np.int32)
        npair = self.node.size
        patches = []
        for tool, faces in zip(tools, contact_faces(tools, solid.mesh), strict=True):
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
        self.n = self.nf + 3 * npair
        lam = self.nf + 3 * np.arange(npair)[:, None] + np.arange(3)  # (npair, 3)
        equ = eqn.reshape(n, 3)[self.node]                              # (npair, 3)
        # Components of a slave whose displacement is fixed: its force there is a support
        # reaction, so that row of the law becomes lambda_k = 0.
        self.held_flags = (equ < 0).astype(np.int32).ravel()
        self.fixed_flags = fixed.astype(np.int32).ravel()
        # The structure of the contact blocks, in the order the core writes their values:
        # the coupling entries (-1), dC/dx at the free dofs of each pair's patch (pair, row,
        # patch node, column), dC/dlambda (pair, row, column). A Gauss-point pair's
        # multiplier is eliminated (lambda = F(x), ddpy_forming): its coupling entries are 0
        # and its patch entries, -dF/dx, lie in its node's equilibrium rows (or, for a held
        # component, zero in its law row), where the faces' nodes already couple: no fill.
        #: per pair, whether its multiplier is eliminated (a Gauss-point tool's)
        self.eliminated = _join([np.full(t.slaves.size, t.contact == "gauss")
                                 for t in tools], bool)
        coupling = equ >= 0
        size = np.diff(self.patch_first)
        width = int(size.max()) if npair else 1
        entry = self.patch_first[:-1, None] + np.arange(width)          # (npair, width)
        inside = np.arange(width) < size[:, None]
        patch = eqn.reshape(n, 3)[self.patch_node[np.where(inside, entry, 0)]]
        free_patch = inside[:, :, None] & (patch >= 0)                  # (npair, width, 3)
        pi, ii, ei, jj = np.nonzero(np.broadcast_to(free_patch[:, None],
                                                    (npair, 3, width, 3)))
        # A held component of a surface-to-surface or Gauss-point pair (a slave on a
        # symmetry plane) has the law lambda_k = 0, with no patch entries: in its row they
        # would join the nodes of the patch to one another through the multiplier (the
        # pivot order does not see that), and the paper's bending mesh took 81 million
        # factor entries instead of 59 for these 410 pairs.
        patch_pair = _join([np.full(t.slaves.size, t.contact in ("surface", "gauss"))
                            for t in tools], bool)
        keep = ~(patch_pair[pi] & (equ[pi, ii] < 0))
        pi, ii, ei, jj = pi[keep], ii[keep], ei[keep], jj[keep]
        into = np.where(self.eliminated[pi] & (equ[pi, ii] >= 0), equ[pi, ii], lam[pi, ii])
        rows = [self.pattern.rows, equ[coupling], into, np.repeat(lam, 3, axis=1).ravel()]
        cols = [self.pattern.cols, lam[coupling], patch[pi, ei, jj],
                np.tile(lam, (1, 3)).ravel()]
        self.rows = np.concatenate(rows).astype(np.int32)
        self.cols = np.concatenate(cols).astype(np.int32)
        self.k_slots = self.pattern.rows.size
        self.n_coupling = int(coupling.sum())
        #: the coupling entries' values: -1, 0 for an eliminated multiplier
        self.coupling_values = np.where(np.broadcast_to(self.eliminated[:, None], equ.shape),
                                        0.0, -1.0)[coupling]
        self._hold_entries(tools, holds, lam, equ, into, pi, ii)

    def _hold_entries(self, tools: Sequence[RigidTool], holds: Sequence[int],
                      lam: NDArray, equ: NDArray, into: NDArray, pi: NDArray, ii: NDArray
                      ) -> None:
        """The unknowns, equations and Jacobian entries of the force-controlled tools
        ``holds``, after the contact blocks in the order the core writes them
        (forming_increment): per tool its column (3 law rows per pair; a Gauss-point pair's
        free equilibrium rows), its row (a . lambda_p of each pair: the constant a_j at
        lambda_p,j, or for a Gauss-point pair -a_i times each of its -dF_i/dx entries, the
        source), its diagonal. ``lam``, ``equ``: the pairs' law and equilibrium rows;
        ``into``, ``pi``, ``ii``: the rows, pairs and components of the patch entries."""
        for k in holds:
            if tools[k].facing is None:
                raise ValueError(f"tool {tools[k].name} has no facing direction: a force "
                                 "along it cannot be held")
        #: the force-controlled tools (indices) and the axes they press along (-facing)
        self.holds = np.asarray(holds, dtype=np.int32)
        self.hold_axis = np.array([-np.asarray(tools[k].facing, dtype=float) for k in holds]
                                  ).reshape(-1, 3)
        first_patch = self.k_slots + self.n_coupling  # the patch entries' first slot
        rows, cols, source, coef, first = [], [], [], [], [0]
        for h, k in enumerate(self.holds):
            row = self.nf + 3 * self.node.size + h
            pairs = np.arange(self.first[k], self.first[k + 1])
            column = np.where(self.eliminated[pairs, None], equ[pairs], lam[pairs])
            column = column[column >= 0]
            rows.append(column)
            cols.append(np.full(column.size, row))
            a = self.hold_axis[h]
            plain = pairs[~self.eliminated[pairs]]
            slots = np.flatnonzero(np.isin(pi, pairs) & self.eliminated[pi])
            src = np.concatenate([np.full(3 * plain.size, -1), first_patch + slots])
            source.append(src)
            coef.append(np.concatenate([np.tile(a, plain.size), -a[ii[slots]]]))
            rows.append(np.full(src.size + 1, row))
            cols.append(np.concatenate([lam[plain].ravel(), self.cols[first_patch + slots],
                                        [row]]))
            first.append(first[-1] + src.size)
        self.n += self.holds.size
        self.rows = np.concatenate([self.rows, *rows]).astype(np.int32)
        self.cols = np.concatenate([self.cols, *cols]).astype(np.int32)
        #: per force-controlled tool, its row's entries in hold_source and hold_coef
        self.hold_first = np.asarray(first, dtype=np.int32)
        self.hold_source = _join(source, np.int32)
        self.hold_coef = _join(coef, np.float64)

    def hold_arguments(self, force: ArrayLike | None = None) -> tuple:
        """The force-controlled tools as the core's forming_contact and forming_increment
        take them, pressing with ``force`` (N, per tool; default zero): their count, tools
        (1-based), axes and forces, and their rows' sources (arrays at least one long)."""
        force = np.zeros(self.holds.size) if force is None else np.asarray(force, dtype=float)
        if force.shape != self.holds.shape:
            raise ValueError(f"{self.holds.size} force-controlled tool(s) need as many "
                             f"forces, got {force.size}")
        return (self.holds.size, _padded(self.holds + 1, np.int32),
                _padded(self.hold_axis, np.float64), _padded(force, np.float64),
                self.hold_first, self.hold_source.size, _padded(self.hold_source, np.int32),
                _padded(self.hold_coef, np.float64))

    @cached_property
    def by_rows(self) -> RowStructure:
        """The Jacobian's structure by rows, for the products of GMRES in the core: sorted
        once, at the first increment (a layout made for a look at the contact needs none)."""
        return row_structure(self.n, self.rows, self.cols, self.symmetric)


class ToolPack:
    """Every tool's surface and search structures packed one after another in flat arrays,
    with a table of their offsets, and the blank faces that face each tool: what the core's
    forming_contact reads (fortran/mechanics/ddpy_forming.f90), with the penalty of each
    Gauss-point tool (``penalty``, per tool; 0 for the others). Made once; empty for none."""

    def __init__(self, tools: Sequence[RigidTool], mesh: HexMesh,
                 penalty: Sequence[float] | None = None,
                 barrier: Sequence[tuple[float, float, float]] | None = None) -> None:
        searches = [t.search for t in tools]
        faces = contact_faces(tools, mesh)
        table = np.zeros((len(tools), 13), dtype=np.int32)
        offsets = np.zeros(4, dtype=np.int64)  # coef, patch, tree, grid
        first_point = 0
        for i, (tool, s) in enumerate(zip(tools, searches, strict=True)):
            n = s.surface.n_patches
            table[i] = (s.kind, s.stride, n, s.mode, s.max_iterations, *offsets,
                        tool.facing is not None, SURFACE_CODES[tool.contact], tool.points,
                        first_point)
            offsets += (s.surface.coefficients.size, n, 2 * n - 1, s.grid_params.shape[0])
            first_point += tool.points**2 * faces[i].shape[0] + (
                tool.slaves.size if tool.contact == "gauss" else 0)
        self.names = [t.name for t in tools]
        self.table = table.ravel()
        self.tol = np.array([s.tol for s in searches], dtype=float)
        integers = {"degrees", "triangle", "tree_child", "grid_start"}
        #: every tool's search arrays, one after another, in the core's argument order
        self.arrays = SearchArrays(*(
            _join([getattr(s.arrays, name) for s in searches],
                  np.int32 if name in integers else np.float64)
            for name in SearchArrays._fields))
        self.facing = _join([np.zeros(3) if t.facing is None else t.facing for t in tools],
                            np.float64)
        # Per tool with a facing direction, the blank's boundary faces that face it (normal
        # within 60 degrees) and the slave index of their corners (-1: not a slave): the
        # search keeps only patches opposing the blank's normal at each slave; a
        # surface-to-surface or Gauss-point tool projects their Gauss points, which stand
        # for the areas face_weight of the undeformed blank (n x n per face, n the tool's
        # points).
        # A Gauss-point tool's points are followed by one per slave, its barrier
        # (forming_contact), which stands for the slave's share of the faces' area.
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
        self.face_first = np.concatenate([[0], np.cumsum([f.shape[0] for f in faces])]
                                         ).astype(np.int32)
        self.faces = _join([f.ravel() for f in faces], np.int32)
        self.corner = _join([c.ravel() for c in corners], np.int32)
        self.face_weight = _join(weights, np.float64)
        #: per tool, the normal and tangential penalty of Gauss-point contact (N/mm^3) and
        #: its barrier's stiffness (N/mm^3; 0: none), start and width (mm)
        eps = np.zeros(len(tools)) if penalty is None else np.asarray(penalty, dtype=float)
        bars = np.zeros((len(tools), 3)) if barrier is None else np.asarray(barrier, float)
        self.penalty = np.column_stack([eps, eps, bars.reshape(len(tools), 3)]).ravel()
        #: Gauss points of all faces: their tangential tractions are (3,) each
        self.n_points = first_point if len(tools) else 0

    def arguments(self, positions: dict[str, NDArray[np.float64]],
                  positions_n: dict[str, NDArray[np.float64]], reach: float, size: float
                  ) -> tuple:
        """The tools as the core's forming_contact and forming_increment take them: the
        table and search arrays of every tool, their facing directions and faces, where
        they are and where they were at the last converged increment, the search's reach
        and the element size."""
        return (self.table, self.tol, *self.arrays, self.facing, self.face_first, self.faces,
                self.corner, self.face_weight, self.penalty,
                _join([positions[n] for n in self.names], np.float64),
                _join([positions_n[n] for n in self.names], np.float64), reach, size)


@dataclass(frozen=True)
class Loop:
    """How the core's loop runs an increment trial: the convergence tolerances and
    iterations, the force scale's floor (N), the yield landing's tolerance (None: off),
    the penetration limit (element sizes) and the shortest step it may leave, the linear
    solver (reuse of older factors by GMRES: its tolerance bounds, iterations at most and
    after which the next correction factorizes), the line search (SEARCH_*) with the
    residual ratio under which a whole step that changed contact states stands although
    it fails the monotonicity test (0: off), the touching predictor's gap and resting
    flag, and the size ratio: the largest increment over this one's size (at least 1), by
    which the convergence test scales the increment's motion up, so that a cut does not
    tighten it (docs/theory/contact.md, "The convergence test")."""

    force_tolerance: float
    displacement_tolerance: float
    max_iterations: int
    floor: float
    yield_tolerance: float | None = None
    penetration: float = 0.0
    min_step: float = 1.0
    reuse: bool = False
    krylov_loose: float = 1e-2
    krylov_tight: float = 1e-10
    krylov_max: int = 12
    krylov_keep: int = 8
    search: int = SEARCH_MONOTONICITY
    whole_step: float = 0.0
    touching: float = 0.0
    resting: bool = True
    size_ratio: float = 1.0


@dataclass
class Trial:
    """What one increment trial gives: converged (``failure`` empty and ``landing`` 1) with
    the new state, the internal forces, its residual history and the contact states, gaps
    and normals of the pairs; or the fraction of the increment at which the first elastic
    point lands on the yield surface (``landing`` < 1); or why it failed (``solver``: a
    factorization or solve failed). Always: the work done (``counters``: evaluations,
    corrections, factorizations, Krylov iterations, line-search fallbacks) and its time per
    part (PARTS)."""

    failure: str = ""
    landing: float = 1.0
    solver: bool = False
    u: NDArray[np.float64] | None = None
    state: SolidState | None = None
    force: NDArray[np.float64] | None = None
    fint: NDArray[np.float64] | None = None
    residuals: list[float] = field(default_factory=list)
    relative: list[tuple[float, float]] = field(default_factory=list)
    #: per iteration after the first, the length of the step that led to it
    steps: list[float] = field(default_factory=list)
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
    """The (tool, slave) pairs of an increment: the tools (``ToolPack.arguments``) where
    the increment takes them, the pairs that take part (``on``), their augmentation ``r``,
    friction ``mu`` and contact forces at the converged state, and the tangential traction
    of each Gauss point of Gauss-point contact there (``traction_n``, (points, 3)) with its
    pressure multiplier (``pressure_n``, (points,): the augmented Lagrangian's, 0 for the
    plain penalty). ``hold_force``: per force-controlled tool (Layout.holds), the force
    it presses on the blank with at the increment's end (N); ``hold_step``: the most it
    may move in one Newton step (mm)."""

    tools: tuple
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
    settings = np.array([loop.force_tolerance, loop.displacement_tolerance,
                         -1.0 if loop.yield_tolerance is None else loop.yield_tolerance,
                         loop.penetration, loop.min_step, loop.krylov_loose, loop.krylov_tight,
                         loop.floor, loop.whole_step, loop.size_ratio])
    isettings = np.array([loop.max_iterations, loop.krylov_max, loop.krylov_keep, loop.reuse,
                          factors.handle, guess is not None, loop.resting, layout.symmetric,
                          loop.search], dtype=np.int32)
    factored = np.array([factors.factored], dtype=np.int32)
    reuse_next = np.array([factors.reuse_next], dtype=np.int32)
    out = solid.state_buffer()
    solid_state = (solid._x, solid._conn, solid._kind, solid.props, _flat(state.displacement),
                   _flat(state.axes.transpose(0, 1, 3, 2)), _flat(state.stress),
                   _flat(state.ep), _flat(state.strain), solid.backstress_in(state), layout.eqn,
                   layout.pattern.offsets,
                   layout.fixed_flags, layout.nf, layout.k_slots)
    start = (u_n if guess is None else guess).ravel()
    buffers = (out.stress.ravel(), out.ep.ravel(), out.strain.ravel(),
               out.axes.transpose(0, 1, 3, 2).ravel(), solid.backstress_out(out),
               loop.max_iterations + 1)
    if pairs is None:
        if layout.node.size:
            raise ValueError("a layout with contact pairs needs their Pairs")
        (factored, u, fint, stress, ep, strain, axes, back, niter, history, counters, spent,
         outcome, info, detail) = _core.static_increment(
            *solid_state, layout.rows.size, layout.by_rows.row_start, layout.by_rows.col,
            layout.by_rows.sources, layout.by_rows.source_start, solid.mesh.element_size(),
            u_n.ravel(),
            external.ravel(), prescribed.ravel(), start, settings, isettings, factored,
            *buffers)
        force = pair_state = gap = normal = traction = pressure = shift = np.zeros(0)
    else:
        (factored, reuse_next, u, force, fint, stress, ep, strain, axes, back, pair_state, gap,
         normal, traction, pressure, niter, history, counters, spent, outcome, info,
         detail, shift) = \
            _core.forming_increment(
                *solid_state, layout.n_coupling, layout.rows.size, *layout.by_rows,
                *pairs.tools, loop.touching, layout.first, layout.node, layout.patch_first,
                layout.patch_node, pairs.on.astype(np.int32), pairs.r,
                pairs.mu, layout.held_flags, pairs.traction_n.ravel(), pairs.pressure_n,
                u_n.ravel(),
                np.where(pairs.on[:, None], pairs.force_n, 0.0).ravel(), external.ravel(),
                prescribed.ravel(), start, settings, isettings, factored, reuse_next,
                *buffers, *layout.hold_arguments(pairs.hold_force), pairs.hold_step,
                np.zeros(max(layout.holds.size, 1)))
        shift = shift[:layout.holds.size]
        factors.reuse_next = bool(reuse_next[0])
    factors.factored = bool(factored[0])
    history = history.reshape(-1, 4)[:niter]
    work = {"counters": tuple(int(c) for c in counters),
            "timings": {key: float(s) for key, s in zip(PARTS, spent, strict=True)},
            "residuals": history[:, 0].tolist(),
            "relative": [(float(a), float(b)) for a, b in history[:, 1:3]],
            "steps": history[1:, 3].tolist()}
    if outcome == CONVERGED:
        m = solid.mesh.n_elements
        converged = SolidState(stress.reshape(m, 8, 6), ep.reshape(m, 8),
                               strain.reshape(m, 8, 6),
                               axes.reshape(m, 8, 3, 3).transpose(0, 1, 3, 2),
                               u.reshape(-1, 3), back.reshape(m, 8, 6) if solid.mixed else None)
        return Trial(u=u.reshape(-1, 3), state=converged, force=force.reshape(-1, 3),
                     fint=fint.reshape(-1, 3), in_contact=pair_state,
                     gap=(gap, normal.reshape(-1, 3)), traction=traction.reshape(-1, 3),
                     pressure=pressure, shift=shift, **work)
    if outcome == LANDING:
        return Trial(landing=float(detail[0]), **work)
    if outcome == ELEMENT:
        return Trial(str(ElementError(int(info[0]), int(info[1]) - 1)), **work)
    if outcome == NOT_FINITE:
        return Trial("the residual is not finite", **work)
    if outcome == SOLVER:
        factors.factored = False
        return Trial(str(LinearSolverError(int(info[2]), "factorization or solve")),
                     solver=True, **work)
    if outcome == HOLD:
        tool = int(info[0]) - 1  # the tool's index
        why = ("nothing holds it along its axis: no slave node is in contact with it"
               if int(info[1]) == 1 else
               "it moved farther than the contact search's reach in one increment: the "
               "blank does not carry its force")
        return Trial(f"force-controlled tool {tool} lost the blank: {why}",
                     hold=(tool, why), **work)
    if outcome == STALLED:
        return Trial(stalled(loop.max_iterations, float(detail[0]), float(detail[1]),
                             loop.force_tolerance, loop.displacement_tolerance,
                             int(info[3])), **work)
    raise RuntimeError(f"forming_increment refused its input (outcome {outcome}): the "
                       "layout, the tools' packed arrays or the history do not fit")


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
