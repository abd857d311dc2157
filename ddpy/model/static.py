"""The static problem: a solid under prescribed displacements and nodal loads.

Example::

    mesh = HexMesh.box(10, 2, 1, 20, 4, 3)
    problem = StaticProblem(Solid(mesh, props))
    problem.fix(mesh.select(x=0), "xyz")
    problem.load(mesh.select(x=10), [0, 0, -1.0])
    result = problem.solve(increments=4)

The Newton iterations of an increment are the core's (``ddpy.model.newton``): the same loop
as a forming increment, with no tools and the fixed dofs moving to their prescribed values.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy._validate import float_array, int_array
from ddpy.core.linalg import MumpsSolver
from ddpy.core.ordering import mesh_solver
from ddpy.core.parallel import threads as thread_count
from ddpy.model.control import NewtonSettings
from ddpy.model.mesh import RIGID_MODES, free_rigid_modes
from ddpy.model.newton import (
    SEARCH_ENERGY,
    SEARCH_NONE,
    Factors,
    Iteration,
    Layout,
    Loop,
    increment,
)
from ddpy.model.solid import Solid, SolidState, _components
from ddpy.model.work import Work

__all__ = ["StaticProblem", "SolidResult", "ConvergenceError"]

#: Floor of the force scale of the convergence test, in E times an element face: a
#: microstrain over one face (a problem without loads or reactions still has a scale).
FORCE_FLOOR = 1e-6


@dataclass
class SolidResult(Work):
    """Converged increments of a static run. Per increment s: load factor ``factors[s]``,
    ``displacements[s]`` (n, 3), ``reactions[s]`` (n, 3; nonzero on constrained dofs),
    ``pk2[s]`` and ``cauchy[s]`` (m, 8, 6), ``ep[s]`` (m, 8), the norm of the free residual
    at every iteration ``residuals[s]`` and, per iteration, what convergence is judged on
    (``convergence[s]``, Iteration: the residual over the force scale and the correction
    over the increment of u, inf before the first correction, with the step and what
    changed). The work of every trial increment,
    the cut ones included, counted as Work: evaluations (assemblies, line-search trials
    included), Newton corrections, factorizations, cuts and the seconds of each part
    (``timings``)."""

    factors: list[float] = field(default_factory=list)
    displacements: list[NDArray[np.float64]] = field(default_factory=list)
    reactions: list[NDArray[np.float64]] = field(default_factory=list)
    pk2: list[NDArray[np.float64]] = field(default_factory=list)
    cauchy: list[NDArray[np.float64]] = field(default_factory=list)
    ep: list[NDArray[np.float64]] = field(default_factory=list)
    residuals: list[list[float]] = field(default_factory=list)
    convergence: list[list[Iteration]] = field(default_factory=list)
    state: SolidState | None = None

    @property
    def iterations(self) -> list[int]:
        """Newton iterations (corrections) of every converged increment."""
        return [len(r) - 1 for r in self.residuals]


class ConvergenceError(RuntimeError):
    """Newton-Raphson failed after all allowed cuts; ``result`` holds what converged."""

    def __init__(self, message: str, result: SolidResult) -> None:
        super().__init__(message)
        self.result = result


class StaticProblem:
    """Quasi-static equilibrium of a Solid under prescribed displacements and nodal loads,
    solved by the core's Newton loop (the forming problem's, without tools) with MUMPS.

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
        self._layout: Layout | None = None
        self._solver: MumpsSolver | None = None
        self._factors = Factors(0)
        self._factorized = False  # a factorization has succeeded: the stiffness is regular

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
        self._solver, self._layout = None, None

    def _check_supports(self) -> None:
        """Refuse constraints that leave a rigid-body motion of the whole mesh free."""
        free = free_rigid_modes(self.solid.mesh.nodes, self.fixed)
        if not len(free):
            return
        main = int(np.argmax(np.abs(free[0])))
        others = " and others" if len(free) > 1 or np.sum(np.abs(free[0]) > 1e-6) > 1 else ""
        raise ValueError(f"the fixed dofs leave a rigid-body motion free ({RIGID_MODES[main]}"
                         f"{others}): fix more dofs, e.g. symmetry planes or a clamp")

    def _prepare(self) -> Layout:
        if self._layout is None or self._solver is None:
            free = ~self.fixed.ravel()
            if not free.any():
                raise ValueError("every dof is fixed: nothing to solve")
            self._check_supports()
            layout = Layout(self.solid, [], self.fixed, self.symmetry == "symmetric")
            solver = mesh_solver(self.symmetry, self.ordering, self.solid.node_order,
                                 np.flatnonzero(free) // 3)
            solver.analyse(layout.n, *layout.entries())
            self._layout, self._solver = layout, solver
            self._factors = Factors(solver.handle)
        return self._layout

    def solve(self, increments: int = 1, newton: NewtonSettings | None = None,
              max_cuts: int = 6, threads: int | None = None,
              predictor: str = "extrapolate",
              line_search: bool = True) -> SolidResult:
        """Apply loads and prescribed displacements in ``increments`` equal steps.

        The prescribed increment enters through the tangent (K_ff du_f = -(r_f + K_fp dp)),
        not as a jump of the boundary nodes. ``predictor``: "extrapolate" starts from the
        previous displacement increment, scaled to this one, as a forming increment does
        (the first increment and retries after a cut start as "elastic"); "elastic" from
        the converged state, the first correction with its tangent (elastic: no strain
        increment yet).
        ``newton`` (default NewtonSettings(), as in a deck): it has converged when
        ||r_free|| <= force_tolerance max(||f_ext||, ||reactions||, floor) and
        ||correction|| <= displacement_tolerance ||increment of u|| (scaled up to a whole
        increment's, ``1 / increments``, when a cut made it smaller); on divergence, an
        inverted element or a failed return mapping the increment is cut by ``cutback`` and
        retried from the converged state, at most ``max_cuts`` times in a row.
        ``line_search``: the energy line search, a secant on s(alpha) = du . r(u + alpha du)
        when a whole step overshoots (off: whole steps, halved only where an element would
        invert). ``threads``: OpenMP threads.
        """
        newton = NewtonSettings() if newton is None else newton
        if int(increments) < 1:
            raise ValueError(f"increments must be at least 1, got {increments}")
        if int(max_cuts) < 0:
            raise ValueError(f"max_cuts must be >= 0, got {max_cuts}")
        if predictor not in ("elastic", "extrapolate"):
            raise ValueError(f"predictor must be 'elastic' or 'extrapolate', got {predictor!r}")
        if threads is not None:
            with thread_count(int(threads)):
                return self._run(int(increments), newton, int(max_cuts), predictor,
                                 line_search)
        return self._run(int(increments), newton, int(max_cuts), predictor, line_search)

    def _run(self, increments: int, newton: NewtonSettings, max_cuts: int, predictor: str,
             line_search: bool) -> SolidResult:
        layout = self._prepare()
        solid, mesh = self.solid, self.solid.mesh
        face = (mesh.volume() / mesh.n_elements) ** (2.0 / 3.0)
        floor = FORCE_FLOOR * solid.props[0] * face
        result = SolidResult()
        u = np.zeros((mesh.n_nodes, 3))
        state = solid.initial_state()
        nominal = 1.0 / increments
        factor, step = 0.0, nominal
        previous: tuple[float, NDArray[np.float64]] | None = None
        cuts_in_row = 0
        while factor < 1.0 - 1e-12:
            target = 1.0 if 1.0 - (factor + step) < 1e-12 else factor + step
            delta = target - factor
            prescribed = np.where(self.fixed, self.prescribed(target), u)
            external = target * self.forces
            guess = None
            if predictor == "extrapolate" and previous is not None and cuts_in_row == 0:
                guess = np.where(self.fixed, prescribed, u + delta / previous[0] * previous[1])
            # The force scale's ||f_ext|| is constant over the increment: part of the floor.
            loop = Loop(newton.force_tolerance, newton.displacement_tolerance,
                        newton.max_iterations, max(floor, float(np.linalg.norm(external))),
                        search=SEARCH_ENERGY if line_search else SEARCH_NONE,
                        size_ratio=max(1.0, nominal / delta))
            trial = increment(solid, layout, self._factors, state, u, external, prescribed,
                              guess, loop)
            factorizations = result.factorizations
            result.count(trial)
            if trial.solver and not self._factorized and result.factorizations == factorizations:
                raise ValueError(
                    f"the stiffness matrix is singular ({trial.failure}): is a part of the mesh "
                    "free to move without straining?")
            self._factorized = self._factorized or result.factorizations > factorizations
            if trial.failure:
                cuts_in_row += 1
                result.cuts += 1
                if cuts_in_row > max_cuts:
                    result.state = state.copy()
                    raise ConvergenceError(
                        f"increment to load factor {target:.6g} failed after {max_cuts} cuts: "
                        f"{trial.failure}", result)
                step = delta * newton.cutback
                continue
            assert trial.u is not None and trial.state is not None and trial.fint is not None
            previous = (delta, trial.u - u)
            u, state, factor = trial.u, trial.state, target
            pk2, cauchy, _ = solid.stresses(u, state)
            result.factors.append(factor)
            result.displacements.append(u.copy())
            result.reactions.append(np.where(self.fixed, trial.fint, 0.0))
            result.pk2.append(pk2)
            result.cauchy.append(cauchy)
            result.ep.append(state.ep.copy())
            result.residuals.append(trial.residuals)
            result.convergence.append(trial.convergence)
            # Back to the nominal size once a cut increment ends on the grid of increments.
            on_grid = abs(target / nominal - round(target / nominal)) < 1e-9
            if cuts_in_row == 0 or on_grid:
                step, cuts_in_row = nominal, 0
        result.state = state.copy()
        return result

    def close(self) -> None:
        """Free the MUMPS instance."""
        self._reset_solver()
