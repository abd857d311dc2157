"""The deformable blank: large-strain hexahedra, their assembly and a Newton-Raphson driver.

The Fortran core does the element work (``fortran/mechanics/ddpy_hex8.f90``) and assembles internal
forces and the tangent straight into MUMPS coordinate storage, in parallel
(``fortran/solver/ddpy_solid_assembly.f90``); see ``docs/theory/solid.md`` for the formulation.
Displacements are total, in global axes; stresses are per Gauss point, Voigt order
11, 22, 33, 12, 23, 31.

Example::

    mesh = HexMesh.box(10, 2, 1, 20, 4, 3)
    problem = StaticProblem(Solid(mesh, props))
    problem.fix(mesh.select(x=0), "xyz")
    problem.load(mesh.select(x=10), [0, 0, -1.0])
    result = problem.solve(increments=4)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array, int_array
from ddpy.core.linalg import LinearSolverError, MumpsSolver
from ddpy.core.ordering import mesh_solver, nested_dissection, node_adjacency
from ddpy.core.parallel import threads as thread_count
from ddpy.model.control import NewtonSettings
from ddpy.model.mesh import HexMesh

__all__ = ["Assembly", "Solid", "SolidState", "StaticProblem", "SolidResult", "ConvergenceError",
           "ElementError", "material_props"]

PROP_COUNT = 16
_STATUS = {1: "is inverted (det F <= 0 or det J0 <= 0 at a Gauss point)",
           2: "failed in the material update (return mapping)",
           3: "has a node index out of range", 4: "has inconsistent tangent slots"}
_COMPONENTS = {"x": 0, "y": 1, "z": 2}


class ElementError(RuntimeError):
    """An element could not be evaluated; ``element`` is its 0-based index."""

    def __init__(self, status: int, element: int) -> None:
        self.status, self.element = status, element
        super().__init__(f"element {element} {_STATUS.get(status, f'status {status}')}")


class ConvergenceError(RuntimeError):
    """Newton-Raphson failed after all allowed cuts; ``result`` holds what converged."""

    def __init__(self, message: str, result: SolidResult) -> None:
        super().__init__(message)
        self.result = result


def material_props(material: Any) -> NDArray[np.float64]:
    """The 16 material properties of ``material`` (anything with ``props()``, or the vector
    itself), checked: E > 0, -1 < nu < 0.5, a convex Hill'48 surface, a known hardening law
    with positive parameters.

    Layout: (0) E, (1) nu, (2:8) Hill F, G, H, L, M, N, (8) hardening (1 Swift, 2 Voce),
    (9:12) Swift K, eps0, n or Voce Y0, Q, b; the rest is reserved (zero).
    """
    props = material.props() if hasattr(material, "props") else material
    props = float_array(props, "material properties", (PROP_COUNT,))
    e, nu = props[0], props[1]
    if not e > 0.0:
        raise ValueError(f"Young's modulus must be positive, got {e}")
    if not -1.0 < nu < 0.5:
        raise ValueError(f"Poisson's ratio must lie in (-1, 0.5), got {nu}")
    f, g, h, l_, m, n = props[2:8]
    if min(l_, m, n) <= 0.0 or min(f + g, g + h, h + f) <= 0.0 or f * g + g * h + h * f <= 0.0:
        raise ValueError(
            f"Hill'48 coefficients F, G, H, L, M, N = {props[2:8].tolist()} do not define a "
            "convex yield surface (need L, M, N > 0, F+G, G+H, H+F > 0, FG+GH+HF > 0)")
    law = props[8]
    if law == 1.0:
        k, eps0, n_ = props[9:12]
        if not (k > 0.0 and eps0 > 0.0 and n_ >= 0.0):
            raise ValueError(f"Swift K, eps0 must be positive and n >= 0, got {k}, {eps0}, {n_}")
    elif law == 2.0:
        y0, q, b = props[9:12]
        if not (y0 > 0.0 and q >= 0.0 and b >= 0.0):
            raise ValueError(f"Voce Y0 must be positive and Q, b >= 0, got {y0}, {q}, {b}")
    else:
        raise ValueError(f"hardening must be 1 (Swift) or 2 (Voce), got {law}")
    info = int(_core.material_check(props))
    if info:
        raise ValueError(f"material property {info - 1} (0-based) is out of range "
                         "(see ddpy.model.material for the accepted ranges)")
    return props


@dataclass
class SolidState:
    """State of the blank at a converged increment, the reference configuration of the next
    (updated Lagrangian): per Gauss point the rotated Kirchhoff stress in material axes
    (m, 8, 6), the equivalent plastic strain (m, 8), the accumulated logarithmic strain in
    material axes (m, 8, 6) and the material axes as columns (m, 8, 3, 3); per node the
    displacements (n, 3)."""

    stress: NDArray[np.float64]
    ep: NDArray[np.float64]
    strain: NDArray[np.float64]
    axes: NDArray[np.float64]
    displacement: NDArray[np.float64]

    @classmethod
    def zeros(cls, n_elements: int, n_nodes: int) -> SolidState:
        """Stress-free, undeformed state with the material axes along the global axes."""
        axes = np.broadcast_to(np.eye(3), (n_elements, 8, 3, 3)).copy()
        return cls(np.zeros((n_elements, 8, 6)), np.zeros((n_elements, 8)),
                   np.zeros((n_elements, 8, 6)), axes, np.zeros((n_nodes, 3)))

    def copy(self) -> SolidState:
        # order="K" keeps the layout of axes (a transposed view when written by assemble),
        # so that the copy goes back to the core without another copy.
        return SolidState(self.stress.copy(), self.ep.copy(), self.strain.copy(),
                          self.axes.copy(order="K"), self.displacement.copy())


def _flat(a: NDArray[np.float64]) -> NDArray[np.float64]:
    """C-ordered flat float64 view (or copy) for the core."""
    return np.ascontiguousarray(a, dtype=np.float64).ravel()


class Assembly(NamedTuple):
    """What one assembly returns: internal forces (n, 3), tangent values in the slots of the
    pattern, the trial state, and K dp when asked for (else None)."""

    fint: NDArray[np.float64]
    values: NDArray[np.float64]
    state: SolidState
    kdu: NDArray[np.float64] | None


@dataclass
class _Pattern:
    """Equation numbers and the tangent's coordinate structure for one constraint set."""

    eqn: NDArray[np.int32]
    symmetric: bool
    offsets: NDArray[np.int32]
    rows: NDArray[np.int32]
    cols: NDArray[np.int32]


class Solid:
    """A hexahedral mesh of one material, oriented by its rolling direction.

    ``material``: a ``ddpy.model.material.Material`` or its 16-vector of properties (see
    ``material_props``). ``rolling_direction_deg``: angle of the rolling direction from the
    global x axis about z, one value or one per element.
    """

    def __init__(self, mesh: HexMesh, material: Any,
                 rolling_direction_deg: float | ArrayLike = 0.0) -> None:
        if not isinstance(mesh, HexMesh):
            raise TypeError(f"mesh must be a HexMesh, got {type(mesh).__name__}")
        self.mesh = mesh
        self.props = material_props(material)
        angle = np.asarray(rolling_direction_deg, dtype=float)
        if angle.ndim == 0:
            angle = np.full(mesh.n_elements, float(angle))
        self.angle = np.radians(float_array(angle, "rolling_direction_deg", (mesh.n_elements,)))
        self._x = mesh.nodes.ravel()
        self._conn = mesh.elements.ravel()

    @property
    def n_dofs(self) -> int:
        return 3 * self.mesh.n_nodes

    def node_order(self) -> NDArray[np.int64]:
        """Nested-dissection elimination order of the mesh nodes (computed once)."""
        if getattr(self, "_node_order", None) is None:
            graph = node_adjacency(self.mesh.elements, self.mesh.n_nodes)
            self._node_order = nested_dissection(graph, self.mesh.nodes)
        return self._node_order

    def initial_state(self) -> SolidState:
        """Stress-free, undeformed state with no plastic strain; the material axes are the
        rolling direction, its normal in the x-y plane and z."""
        state = SolidState.zeros(self.mesh.n_elements, self.mesh.n_nodes)
        c, s = np.cos(self.angle), np.sin(self.angle)
        axes = np.zeros((self.mesh.n_elements, 3, 3))
        axes[:, 0, 0], axes[:, 1, 0] = c, s
        axes[:, 0, 1], axes[:, 1, 1] = -s, c
        axes[:, 2, 2] = 1.0
        state.axes[:] = axes[:, None, :, :]
        return state

    def state_buffer(self) -> SolidState:
        """Uninitialized arrays of a state, in the layout ``assemble`` writes (``out``)."""
        m, n = self.mesh.n_elements, self.mesh.n_nodes
        return SolidState(np.empty((m, 8, 6)), np.empty((m, 8)), np.empty((m, 8, 6)),
                          np.empty((m, 8, 3, 3)).transpose(0, 1, 3, 2), np.empty((n, 3)))

    def pattern(self, eqn: ArrayLike | None = None, symmetric: bool = True) -> _Pattern:
        """Coordinate structure of the tangent for equation numbers ``eqn`` (n, 3) (0-based,
        -1 for a constrained dof; default: every dof free, numbered 3 node + component)."""
        if eqn is None:
            eqn = np.arange(self.n_dofs, dtype=np.int32)
        eqn = int_array(np.asarray(eqn).reshape(-1), "eqn", (self.n_dofs,))
        counts, status, element = _core.solid_coo_count(self._conn, eqn, int(symmetric))
        if status:
            raise ElementError(int(status), int(element) - 1)
        offsets = np.zeros(self.mesh.n_elements + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
        if offsets[-1] > np.iinfo(np.int32).max:
            raise ValueError("the tangent has more than 2^31 entries; not supported")
        offsets = offsets.astype(np.int32)
        rows, cols, status, element = _core.solid_coo_pattern(
            self._conn, eqn, int(symmetric), offsets, int(offsets[-1]))
        if status:
            raise ElementError(int(status), int(element) - 1)
        return _Pattern(eqn, symmetric, offsets, rows, cols)

    def assemble(self, u: ArrayLike, state: SolidState | None = None,
                 pattern: _Pattern | None = None, tangent: bool = True,
                 values: NDArray[np.float64] | None = None,
                 dp: ArrayLike | None = None, out: SolidState | None = None) -> Assembly:
        """Internal forces (n, 3), tangent values in the slots of ``pattern`` (empty when
        ``tangent`` is False) and the trial state at total displacements ``u`` (n, 3),
        over the increment from the converged ``state`` (its displacements are the
        reference configuration); with ``dp`` (n, 3) also the product K dp of
        the tangent over all dofs with dp. ``values`` may be given as the output buffer,
        and ``out`` (from ``state_buffer`` or an earlier assembly) as the arrays of the
        trial state: it must not share memory with ``state``, and is overwritten.
        Raises ElementError when an element is inverted or its material update fails."""
        n = self.mesh.n_nodes
        u = float_array(u, "u", (n, 3))
        state = self.initial_state() if state is None else state
        pattern = self.pattern() if pattern is None else pattern
        if not tangent:
            values = np.zeros(0)
        elif values is None or values.shape != pattern.rows.shape:
            values = np.empty(pattern.rows.shape[0])
        product = dp is not None and tangent
        dp = np.zeros(3 * n) if dp is None else float_array(dp, "dp", (n, 3)).ravel()
        # The trial state is written into given arrays (fresh ones when out is None) rather
        # than into arrays f2py allocates and zeroes: 28 MB per call on 20,000 elements.
        m = self.mesh.n_elements
        if out is None:
            out = self.state_buffer()
        else:
            for name, array, shape in (("stress", out.stress, (m, 8, 6)), ("ep", out.ep, (m, 8)),
                                       ("strain", out.strain, (m, 8, 6)),
                                       ("axes", out.axes.transpose(0, 1, 3, 2), (m, 8, 3, 3))):
                if (array.shape != shape or array.dtype != np.float64
                        or not array.flags.c_contiguous):
                    raise ValueError(f"out.{name} is not a buffer of this solid's state")
                if any(np.may_share_memory(array, held) for held in (
                        state.stress, state.ep, state.strain, state.axes)):
                    raise ValueError("out shares memory with state")
        values, fint, kdu, stress, ep, strain, axes, status, element = _core.solid_assemble(
            self._x, self._conn, _flat(state.displacement), u.ravel(), self.props,
            _flat(state.axes.transpose(0, 1, 3, 2)), _flat(state.stress), _flat(state.ep),
            _flat(state.strain), pattern.eqn, int(pattern.symmetric), int(tangent),
            pattern.offsets, values, int(product), dp, out.stress.ravel(), out.ep.ravel(),
            out.strain.ravel(), out.axes.transpose(0, 1, 3, 2).ravel())
        if status:
            raise ElementError(int(status), int(element) - 1)
        trial = SolidState(stress.reshape(m, 8, 6), ep.reshape(m, 8), strain.reshape(m, 8, 6),
                           axes.reshape(m, 8, 3, 3).transpose(0, 1, 3, 2), u.copy())
        return Assembly(fint.reshape(-1, 3), values, trial,
                        kdu.reshape(-1, 3) if product else None)

    def internal_force(self, u: ArrayLike, state: SolidState | None = None,
                       ) -> tuple[NDArray[np.float64], SolidState]:
        """Internal forces (n, 3) and trial state at total displacements u (n, 3)."""
        out = self.assemble(u, state, tangent=False)
        return out.fint, out.state

    def tangent(self, u: ArrayLike, state: SolidState | None = None, symmetric: bool = False,
                ) -> tuple[NDArray[np.int32], NDArray[np.int32], NDArray[np.float64]]:
        """Tangent d fint / d u over all 3n dofs (dof 3 node + component) as a coordinate
        triple (rows, cols, values), duplicates to be summed; ``symmetric``: lower triangle
        only."""
        pattern = self.pattern(symmetric=symmetric)
        return pattern.rows, pattern.cols, self.assemble(u, state, pattern).values

    def stresses(self, u: ArrayLike, state: SolidState,
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Second Piola-Kirchhoff and Cauchy stress in global axes (m, 8, 6) and the current
        Gauss point positions (m, 8, 3) of ``state`` at total displacements ``u``."""
        u = float_array(u, "u", (self.mesh.n_nodes, 3))
        pk2, cauchy, points, status, element = _core.solid_stresses(
            self._x, self._conn, u.ravel(), _flat(state.axes.transpose(0, 1, 3, 2)),
            _flat(state.stress))
        if status:
            raise ElementError(int(status), int(element) - 1)
        m = self.mesh.n_elements
        return pk2.reshape(m, 8, 6), cauchy.reshape(m, 8, 6), points.reshape(m, 8, 3)


@dataclass
class SolidResult:
    """Converged increments of a static run. Per increment s: load factor ``factors[s]``,
    ``displacements[s]`` (n, 3), ``reactions[s]`` (n, 3; nonzero on constrained dofs),
    ``pk2[s]`` and ``cauchy[s]`` (m, 8, 6), ``ep[s]`` (m, 8), the norms of the free residual
    at every iteration ``residuals[s]`` and of the corrections ``corrections[s]``.
    ``timings`` lists the seconds of every assembly (with tangent), factorization, solve and
    force-only assembly of the line search."""

    factors: list[float] = field(default_factory=list)
    displacements: list[NDArray[np.float64]] = field(default_factory=list)
    reactions: list[NDArray[np.float64]] = field(default_factory=list)
    pk2: list[NDArray[np.float64]] = field(default_factory=list)
    cauchy: list[NDArray[np.float64]] = field(default_factory=list)
    ep: list[NDArray[np.float64]] = field(default_factory=list)
    residuals: list[list[float]] = field(default_factory=list)
    corrections: list[list[float]] = field(default_factory=list)
    cuts: int = 0
    state: SolidState | None = None
    timings: dict[str, list[float]] = field(
        default_factory=lambda: {"assembly": [], "factorization": [], "solve": [],
                                 "line_search": []})

    @property
    def iterations(self) -> list[int]:
        """Newton iterations (factorizations) of every converged increment."""
        return [len(c) for c in self.corrections]


def _components(components: int | str | Iterable[int | str]) -> list[int]:
    if isinstance(components, str):
        items: list[int | str] = list(components.lower())
    elif isinstance(components, int | np.integer):
        items = [int(components)]
    else:
        items = list(components)
    out = []
    for c in items:
        c = _COMPONENTS.get(c, c) if isinstance(c, str) else c
        if not isinstance(c, int | np.integer) or not 0 <= int(c) <= 2:
            raise ValueError(f"components must be 0, 1, 2 or 'x', 'y', 'z', got {components!r}")
        out.append(int(c))
    if len(set(out)) != len(out) or not out:
        raise ValueError(f"components must be distinct and not empty, got {components!r}")
    return out


class StaticProblem:
    """Quasi-static equilibrium of a Solid under prescribed displacements and nodal loads,
    solved by Newton-Raphson with MUMPS.

    ``symmetry``: "symmetric" (lower triangle, LDL^T; the tangent is symmetric) or
    "unsymmetric"; ``ordering``: "nested" (nested dissection of the mesh, ddpy.core.ordering) or
    a MUMPS ordering name ("scotch", "pord", "amd", ...). The MUMPS instance and its analysis
    are kept for every iteration, increment and call of ``solve`` until the set of
    constrained dofs changes.
    """

    def __init__(self, solid: Solid, symmetry: str = "symmetric",
                 ordering: str = "nested") -> None:
        if symmetry not in ("symmetric", "unsymmetric"):
            raise ValueError(f"symmetry must be 'symmetric' or 'unsymmetric', got {symmetry!r}")
        self.solid = solid
        self.symmetry, self.ordering = symmetry, ordering
        n = solid.mesh.n_nodes
        self.fixed = np.zeros((n, 3), dtype=bool)
        self.values = np.zeros((n, 3))
        self.forces = np.zeros((n, 3))
        self._owner = np.full((n, 3), -1, dtype=np.int64)
        self._paths: list[tuple[NDArray[np.int32], list[int], Callable[[float], ArrayLike]]] = []
        self._pattern: _Pattern | None = None
        self._solver: MumpsSolver | None = None

    def _nodes(self, nodes: ArrayLike) -> NDArray[np.int32]:
        nodes = int_array(np.atleast_1d(np.asarray(nodes)), "nodes", (None,))
        n = self.solid.mesh.n_nodes
        bad = nodes[(nodes < 0) | (nodes >= n)]
        if bad.size:
            raise ValueError(f"node {int(bad[0])} does not exist (nodes are 0..{n - 1})")
        if np.unique(nodes).size != nodes.size:
            raise ValueError("nodes are repeated")
        return nodes

    def fix(self, nodes: ArrayLike, components: int | str | Iterable[int | str] = "xyz",
            values: ArrayLike | Callable[[float], ArrayLike] = 0.0) -> None:
        """Prescribe displacement ``components`` of ``nodes``: zero for symmetry planes and
        clamps. ``values`` (scalar, per node (k,), or (k, len(components))) are reached at
        the end of the run, proportionally to the load factor; or a function of the load
        factor in [0, 1] returning them, for a path that is not a straight line (a rigid
        rotation, unloading). A later call overrides an earlier one on the same dofs."""
        nodes = self._nodes(nodes)
        comps = _components(components)
        if (self.forces[nodes][:, comps] != 0.0).any():
            raise ValueError("a fixed dof carries a load; remove the load first")
        path = values if callable(values) else None
        v = self._path_values(path, 1.0, nodes.size, len(comps)) if path else \
            self._shape_values(values, nodes.size, len(comps))
        if path is not None:
            self._shape_values(path(0.0), nodes.size, len(comps))
        before = self.fixed.copy()
        self.fixed[np.ix_(nodes, comps)] = True
        self.values[np.ix_(nodes, comps)] = 0.0 if path else v
        self._owner[np.ix_(nodes, comps)] = len(self._paths) if path else -1
        if path is not None:
            self._paths.append((nodes, comps, path))
        if not np.array_equal(before, self.fixed):
            self._reset_solver()

    @staticmethod
    def _shape_values(values: ArrayLike, k: int, c: int) -> NDArray[np.float64]:
        v = float_array(values, "values", (None,) * np.ndim(values))
        if v.ndim == 1 and v.size == k:
            v = v[:, None]
        try:
            return np.broadcast_to(v, (k, c))
        except ValueError:
            raise ValueError(f"values must be a scalar, ({k},) or ({k}, {c}), got shape "
                             f"{v.shape}") from None

    def _path_values(self, path: Callable[[float], ArrayLike], factor: float, k: int,
                     c: int) -> NDArray[np.float64]:
        return self._shape_values(path(factor), k, c)

    def prescribed(self, factor: float) -> NDArray[np.float64]:
        """Prescribed displacements (n, 3) at load factor ``factor`` (zero on free dofs)."""
        u = factor * self.values
        for k, (nodes, comps, path) in enumerate(self._paths):
            v = self._path_values(path, factor, nodes.size, len(comps))
            mine = self._owner[np.ix_(nodes, comps)] == k
            block = u[np.ix_(nodes, comps)]
            block[mine] = v[mine]
            u[np.ix_(nodes, comps)] = block
        return u

    def load(self, nodes: ArrayLike, forces: ArrayLike) -> None:
        """Add nodal forces (3,) per node or (k, 3), reached at the end of the run."""
        nodes = self._nodes(nodes)
        f = float_array(np.broadcast_to(np.asarray(forces, dtype=float), (nodes.size, 3)),
                        "forces", (nodes.size, 3))
        if (self.fixed[nodes] & (f != 0.0)).any():
            raise ValueError("a load acts on a fixed dof; loads go on free dofs only")
        self.forces[nodes] += f

    def _reset_solver(self) -> None:
        if self._solver is not None:
            self._solver.close()
        self._solver, self._pattern = None, None

    def _check_supports(self) -> None:
        """Refuse constraints that leave a rigid-body motion of the whole mesh free."""
        x = self.solid.mesh.nodes - self.solid.mesh.nodes.mean(axis=0)
        modes = np.zeros((x.shape[0], 3, 6))
        for axis in range(3):
            modes[:, axis, axis] = 1.0
            modes[:, :, 3 + axis] = np.cross(np.eye(3)[axis], x)
        restrained = modes.reshape(-1, 6)[self.fixed.ravel()]
        if restrained.shape[0] >= 6:
            _, sing, vt = np.linalg.svd(restrained, full_matrices=False)
            if sing[-1] > 1e-10 * sing[0] * max(1.0, np.abs(x).max()):
                return
            mode = vt[-1]
        else:
            mode = np.linalg.svd(np.vstack([restrained, np.zeros((6, 6))]))[2][-1]
        names = ["translation along x", "translation along y", "translation along z",
                 "rotation about x", "rotation about y", "rotation about z"]
        main = int(np.argmax(np.abs(mode)))
        raise ValueError(f"the fixed dofs leave a rigid-body motion free ({names[main]}"
                         f"{' and others' if np.sum(np.abs(mode) > 1e-6) > 1 else ''}): "
                         "fix more dofs, e.g. symmetry planes or a clamp")

    def _prepare(self) -> tuple[_Pattern, MumpsSolver]:
        if self._pattern is None or self._solver is None:
            free = ~self.fixed.ravel()
            if not free.any():
                raise ValueError("every dof is fixed: nothing to solve")
            self._check_supports()
            eqn = np.full(free.size, -1, dtype=np.int32)
            eqn[free] = np.arange(int(free.sum()), dtype=np.int32)
            pattern = self.solid.pattern(eqn, symmetric=self.symmetry == "symmetric")
            solver = mesh_solver(self.symmetry, self.ordering, self.solid.node_order,
                                 np.flatnonzero(free) // 3)
            solver.analyse(int(free.sum()), pattern.rows, pattern.cols)
            self._pattern, self._solver = pattern, solver
        return self._pattern, self._solver

    def solve(self, increments: int = 1, newton: NewtonSettings | None = None,
              max_cuts: int = 6, threads: int | None = None, predictor: str = "tangent",
              line_search: bool = True) -> SolidResult:
        """Apply loads and prescribed displacements in ``increments`` equal steps.

        Each increment starts from a linearized predictor, the prescribed increment entering
        through the tangent (K_ff du_f = -(r_f + K_fp dp)) rather than as a jump of the
        boundary nodes. ``predictor``: "tangent" uses the consistent tangent of the last
        iteration of the previous increment (plastic where the material was loading; the
        first increment and retries after a cut use "elastic"); "elastic" the tangent at the
        converged state; "extrapolate" starts from the previous displacement increment.
        ``newton`` (default NewtonSettings(), as in a deck): it has converged when
        ||r_free|| <= force_tolerance max(||f_ext||, ||reactions||, floor) and
        ||correction|| <= displacement_tolerance ||increment of u||; on divergence, an
        inverted element or a failed return mapping the increment is cut by ``cutback`` and
        retried from the converged state, at most ``max_cuts`` times in a row.
        ``line_search``: energy line search when a full Newton step overshoots.
        ``threads``: OpenMP threads.
        """
        newton = NewtonSettings() if newton is None else newton
        if int(increments) < 1:
            raise ValueError(f"increments must be at least 1, got {increments}")
        if int(max_cuts) < 0:
            raise ValueError(f"max_cuts must be >= 0, got {max_cuts}")
        if predictor not in ("tangent", "elastic", "extrapolate"):
            raise ValueError(f"predictor must be 'tangent', 'elastic' or 'extrapolate', got "
                             f"{predictor!r}")
        if threads is not None:
            with thread_count(int(threads)):
                return self._run(int(increments), newton, int(max_cuts), predictor,
                                 line_search)
        return self._run(int(increments), newton, int(max_cuts), predictor, line_search)

    def _run(self, increments: int, newton_settings: NewtonSettings, max_cuts: int,
             predictor: str, line_search: bool) -> SolidResult:
        pattern, solver = self._prepare()
        solid = self.solid
        fixed = self.fixed.ravel()
        # Floor of the force scale: a microstrain over one element's face.
        mesh = solid.mesh
        face = (mesh.volume() / mesh.n_elements) ** (2.0 / 3.0)
        newton = _Newton(solid, pattern, solver, fixed, newton_settings.force_tolerance,
                         newton_settings.displacement_tolerance,
                         newton_settings.max_iterations, 1e-6 * solid.props[0] * face,
                         line_search)
        result = SolidResult()
        newton.timings = result.timings
        u = np.zeros(solid.n_dofs)
        state = solid.initial_state()
        nominal = 1.0 / increments
        factor, step = 0.0, nominal
        previous: tuple[float, NDArray[np.float64]] | None = None
        carry: _Carry | None = None
        cuts_in_row = 0
        while factor < 1.0 - 1e-12:
            target = 1.0 if 1.0 - (factor + step) < 1e-12 else factor + step
            delta = target - factor
            prescribed = self.prescribed(target)
            start: Any = None
            if predictor == "extrapolate" and previous is not None and cuts_in_row == 0:
                guess = u + delta / previous[0] * previous[1]
                guess[fixed] = prescribed.ravel()[fixed]
                start = guess
            elif predictor == "tangent" and carry is not None and carry.target == target:
                start = carry
            # The next increment if this one converges, for the tangent predictor.
            on_grid = abs(target / nominal - round(target / nominal)) < 1e-9
            after = nominal if cuts_in_row == 0 or on_grid else step
            following = 1.0 if 1.0 - (target + after) < 1e-12 else target + after
            dp_next = None
            if predictor == "tangent" and target < 1.0:
                dp_next = np.where(self.fixed, self.prescribed(following) - prescribed, 0.0)
            outcome = newton.increment(u, state, prescribed.ravel()[fixed],
                                       target * self.forces.ravel(), start, dp_next)
            if isinstance(outcome, str):
                cuts_in_row += 1
                result.cuts += 1
                if cuts_in_row > max_cuts:
                    result.state = state.copy()
                    raise ConvergenceError(
                        f"increment to load factor {target:.6g} failed after {max_cuts} cuts: "
                        f"{outcome}", result)
                step = delta * newton_settings.cutback
                continue
            new_u, new_state, reactions, residuals, corrections, carry = outcome
            if carry is not None:
                carry.target = following
            previous = (delta, new_u - u)
            u, state, factor = new_u, new_state, target
            pk2, cauchy, _ = solid.stresses(u.reshape(-1, 3), state)
            result.factors.append(factor)
            result.displacements.append(u.reshape(-1, 3).copy())
            result.reactions.append(reactions.reshape(-1, 3))
            result.pk2.append(pk2)
            result.cauchy.append(cauchy)
            result.ep.append(state.ep.copy())
            result.residuals.append(residuals)
            result.corrections.append(corrections)
            step = after
            if after == nominal:
                cuts_in_row = 0
        result.state = state.copy()
        return result

    def close(self) -> None:
        """Free the MUMPS instance."""
        self._reset_solver()


@dataclass
class _Carry:
    """From the last iteration of a converged increment to the next increment: tangent
    values, K dp of the next prescribed increment, internal forces; for load factor
    ``target``."""

    values: NDArray[np.float64]
    kdu: NDArray[np.float64]
    fint: NDArray[np.float64]
    target: float = -1.0


class _Newton:
    """Newton-Raphson iterations of one increment on the free dofs, with an energy line
    search (secant on s(alpha) = du . r(u + alpha du)) when a full step overshoots."""

    #: A full step is accepted when |s(1)| <= LINE_SEARCH |s(0)| or s(1) < 0.
    LINE_SEARCH = 0.5
    #: Secant steps of one line search at most.
    LINE_SEARCH_STEPS = 5

    def __init__(self, solid: Solid, pattern: _Pattern, solver: MumpsSolver,
                 fixed: NDArray[np.bool_], tol_force: float, tol_disp: float,
                 max_iterations: int, floor: float, line_search: bool) -> None:
        self.solid, self.pattern, self.solver = solid, pattern, solver
        self.fixed, self.free = fixed, ~fixed
        self.tol_force, self.tol_disp = tol_force, tol_disp
        self.max_iterations, self.floor = max_iterations, floor
        self.line_search = line_search
        self.values = np.empty(pattern.rows.shape[0])
        # Two sets of trial-state arrays, used in turn: an assembly writes into the set that
        # is not its converged input (a trial state lives until the next assembly, or
        # becomes the converged state of the next increment). Saves the allocation and
        # zeroing of the state arrays at every assembly; _run copies the state it returns.
        self.buffers = (solid.state_buffer(), solid.state_buffer())
        self.timings: dict[str, list[float]] = {
            "assembly": [], "factorization": [], "solve": [], "line_search": []}
        self.factorized = False

    def _assemble(self, u: NDArray[np.float64], state: SolidState,
                  dp: NDArray[np.float64] | None = None, tangent: bool = True,
                  ) -> Assembly | str:
        start = time.perf_counter()
        buffer = self.buffers[0]
        if np.may_share_memory(buffer.stress, state.stress):
            buffer = self.buffers[1]
        try:
            out = self.solid.assemble(u.reshape(-1, 3), state, self.pattern, tangent=tangent,
                                      values=self.values if tangent else None, dp=dp,
                                      out=buffer)
        except ElementError as error:
            return str(error)
        self.timings["assembly" if tangent else "line_search"].append(
            time.perf_counter() - start)
        return out

    def _solve(self, values: NDArray[np.float64], rhs: NDArray[np.float64],
               ) -> NDArray[np.float64] | str:
        start = time.perf_counter()
        try:
            self.solver.factorize(values)
        except LinearSolverError as error:
            if not self.factorized:
                raise ValueError(
                    f"the stiffness matrix is singular ({error}): is a part of the mesh free to "
                    "move without straining?") from error
            return str(error)
        self.factorized = True
        self.timings["factorization"].append(time.perf_counter() - start)
        start = time.perf_counter()
        du = self.solver.solve(rhs)
        self.timings["solve"].append(time.perf_counter() - start)
        return du

    def _step(self, u: NDArray[np.float64], state: SolidState, du: NDArray[np.float64],
              r: NDArray[np.float64], fext: NDArray[np.float64],
              dp: NDArray[np.float64] | None,
              ) -> tuple[NDArray[np.float64], Assembly, float] | str:
        """u + alpha du and its assembly: alpha = 1 unless the energy line search (or an
        inverted element, by halving) asks for less."""
        free = self.free
        alpha = 1.0
        for _ in range(4):
            trial = u.copy()
            trial[free] += alpha * du
            out = self._assemble(trial, state, dp)
            if not isinstance(out, str):
                break
            alpha *= 0.5
        else:
            return out
        s0 = float(du @ r[free])
        s1 = float(du @ (out.fint.ravel() - fext)[free])
        if not (self.line_search and s0 < 0.0 < s1 and s1 > self.LINE_SEARCH * -s0):
            return trial, out, alpha
        lo, s_lo, hi, s_hi = 0.0, s0, alpha, s1
        for _ in range(self.LINE_SEARCH_STEPS):
            alpha = hi - s_hi * (hi - lo) / (s_hi - s_lo)
            alpha = min(max(alpha, lo + 0.1 * (hi - lo)), hi - 0.1 * (hi - lo))
            trial = u.copy()
            trial[free] += alpha * du
            probe = self._assemble(trial, state, tangent=False)
            if isinstance(probe, str):
                hi, s_hi = alpha, abs(s_hi)
                continue
            s = float(du @ (probe.fint.ravel() - fext)[free])
            if abs(s) <= self.LINE_SEARCH * -s0:
                break
            if s > 0.0:
                hi, s_hi = alpha, s
            else:
                lo, s_lo = alpha, s
        trial = u.copy()
        trial[free] += alpha * du
        out = self._assemble(trial, state, dp)
        if isinstance(out, str):
            return out
        return trial, out, alpha

    def increment(self, u_n: NDArray[np.float64], state: SolidState,
                  prescribed: NDArray[np.float64], fext: NDArray[np.float64], start: Any,
                  dp_next: NDArray[np.float64] | None) -> Any:
        """Iterate from ``start``: a displacement guess; a _Carry, the consistent tangent of
        the last converged iteration with K_fp dp (the tangent predictor); or None, the
        linearized predictor at the converged state, K_ff du_f = -(r_f + K_fp dp), whose
        tangent is elastic. ``dp_next``: prescribed increment of the next increment, for
        its tangent predictor. Returns (u, state, reactions, residual norms, correction
        norms, _Carry or None) or the reason of failure."""
        free, fixed = self.free, self.fixed
        residuals: list[float] = []
        corrections: list[float] = []
        norm_fext = float(np.linalg.norm(fext))
        dp_now = np.zeros_like(u_n)
        dp_now[fixed] = prescribed - u_n[fixed]
        if start is None or isinstance(start, _Carry):
            if isinstance(start, _Carry):
                values, rhs = start.values, (start.fint - fext + start.kdu)[free]
            else:
                out = self._assemble(u_n, state, dp_now.reshape(-1, 3))
                if isinstance(out, str):
                    return out
                values, rhs = out.values, (out.fint.ravel() - fext + out.kdu.ravel())[free]
            residuals.append(float(np.linalg.norm(rhs)))
            du = self._solve(values, -rhs)
            if isinstance(du, str):
                return du
            u = u_n + dp_now
            u[free] += du
            corrections.append(float(np.linalg.norm(du)))
        else:
            u = start
        dp = None if dp_next is None else dp_next.reshape(-1, 3)
        out = self._assemble(u, state, dp)
        if isinstance(out, str):
            return out
        correction = corrections[-1] if corrections else np.inf
        for iteration in range(len(corrections), self.max_iterations + 1):
            r = out.fint.ravel() - fext
            norm_r = float(np.linalg.norm(r[free]))
            residuals.append(norm_r)
            if not np.isfinite(norm_r):
                return "the residual is not finite"
            reactions = np.where(fixed, r, 0.0)
            scale = max(norm_fext, float(np.linalg.norm(reactions)), self.floor)
            step = float(np.linalg.norm(u - u_n))
            if norm_r <= self.tol_force * scale and (
                    correction <= self.tol_disp * step or (iteration == 0 and step == 0.0)):
                carry = None
                if out.kdu is not None:
                    carry = _Carry(out.values.copy(), out.kdu.ravel(), out.fint.ravel())
                return u, out.state, reactions, residuals, corrections, carry
            if iteration == self.max_iterations:
                return f"no convergence in {self.max_iterations} iterations"
            if iteration >= 4 and residuals[-1] > residuals[-2] > residuals[-3] > residuals[-4]:
                return "the residual grows"
            du = self._solve(out.values, -r[free])
            if isinstance(du, str):
                return du
            stepped = self._step(u, state, du, r, fext, dp)
            if isinstance(stepped, str):
                return stepped
            u, out, alpha = stepped
            correction = alpha * float(np.linalg.norm(du))
            corrections.append(correction)
        return "no convergence"  # not reached
