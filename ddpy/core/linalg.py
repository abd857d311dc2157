"""Sparse direct solution through the core's MUMPS (sequential, or parallel under MPI:
docs/mpi.md).

The structure is analysed once (``analyse``), then factorized (``factorize``) and solved
(``solve``) as often as the values change, as the Newton loop of a forming run does.
``row_structure`` gives the core's GMRES (``_core.krylov_solve``, the one its Newton loop
runs) the rows of a coordinate matrix, so that a correction is solved with an older
factorization as the preconditioner instead of factorizing again
(docs/theory/linear-solver.md).
"""

from __future__ import annotations

import operator
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ddpy import _core
from ddpy._validate import float_array, int_array
from ddpy.core import mpi
from ddpy.core.constants import constant

__all__ = ["MumpsSolver", "LinearSolverError", "RowStructure", "distinct", "row_structure",
           "spsolve"]

#: MUMPS's integers (sizes, indices, entry counts) are 32-bit here.
INT32_MAX = 2**31 - 1
_SYMMETRY = {"unsymmetric": 0, "spd": 1, "symmetric": 2}
_ORDERING = {"amd": 0, "amf": 2, "scotch": 3, "pord": 4, "metis": 5, "qamd": 6, "auto": 7}
_PRECISION = {"double": constant("precision_double"),
              "single": constant("precision_single")}
_MESSAGES = {
    -6: "the matrix is structurally singular",
    -10: "the matrix is numerically singular",
    -8: "the integer workspace is too small",
    -9: "the real workspace is too small",
    -13: "memory allocation failed",
    constant("solver_bad_handle"): "the solver handle is not valid (closed?)",
    constant("solver_not_analysed"): "analyse and factorize before solving",
    constant("solver_size_mismatch"): "the size differs from the analysed structure",
    constant("solver_no_free_handle"): "too many solvers open at once (or the core's handle "
                                       "table is full); close some",
    constant("solver_finished"): "the processes were finished (ddpy.core.mpi.finish)",
    constant("solver_not_host"): "only rank 0 drives the solver; ranks > 0 serve it "
                                 "(ddpy.core.mpi.serve)",
    constant("solver_bad_precision"): "the precision must be 'double' or 'single'",
    constant("solver_single_too_coarse"): "GMRES on fresh single-precision factors did not "
                                          "reach its tolerance: the matrix's condition "
                                          "number is near 1/eps_single",
    constant("solver_not_positive_definite"): "the matrix is not positive definite (MUMPS "
                                              "found negative pivots, INFOG(12)); factorize it "
                                              "with symmetry='symmetric' if it is meant to be "
                                              "indefinite",
}


#: Where solver_info puts each statistic (the core's constants), and the two flop counts.
_INFO = {name: constant(f"info_{name}_offset") for name in (
    "infog1", "ordering", "factor_entries", "estimated_factor_entries",
    "estimated_memory_mb_max", "estimated_memory_mb_total", "memory_mb_max",
    "memory_mb_total", "memory_used_mb_max", "memory_used_mb_total", "processes",
    "negative_pivots", "workspace_given")}
_FLOPS = {name: constant(f"flops_{name}_offset") for name in ("elimination", "estimate")}


def distinct(keys: NDArray[np.int64]) -> NDArray[np.int64]:
    """The distinct values of ``keys``, sorted: a sort and a mask. np.unique hashes in
    NumPy 2.4, 30 times a sort on the paper bending blank's 11.7 million coordinate keys
    (0.95 s against 0.2 s on its 1.3 million node pairs)."""
    keys = np.sort(keys)
    return keys[np.concatenate([[True], keys[1:] != keys[:-1]])]


class RowStructure(NamedTuple):
    """A coordinate structure (duplicates summed, as MUMPS does) by rows, for products with
    the matrix in the core: row i's entries are ``row_start[i] .. row_start[i + 1] - 1``
    (0-based), each with its column ``col`` and the positions in the coordinate values
    that add up to it, ``sources[source_start[k] .. source_start[k + 1] - 1]``."""

    row_start: NDArray[np.int32]
    col: NDArray[np.int32]
    sources: NDArray[np.int32]
    source_start: NDArray[np.int32]


def row_structure(n: int, rows: ArrayLike, cols: ArrayLike, symmetric: bool = False
                  ) -> RowStructure:
    """The rows of the n x n matrix with entries at 0-based (rows, cols); ``symmetric``: they
    are one triangle, each off-diagonal entry standing for its mirror too. Sorted once per
    structure, so that each product with new values sums the duplicates in parallel and
    runs over the rows in parallel (docs/theory/linear-solver.md)."""
    rows = int_array(rows, "rows", (None,)).astype(np.int64)
    cols = int_array(cols, "cols", (rows.size,)).astype(np.int64)
    origin = np.arange(rows.size, dtype=np.int64)
    if symmetric:
        off = np.flatnonzero(rows != cols)
        rows, cols = np.concatenate([rows, cols[off]]), np.concatenate([cols, rows[off]])
        origin = np.concatenate([origin, off])
    key, slot = np.unique(rows * n + cols, return_inverse=True)
    order = np.argsort(slot, kind="stable")
    source_start = np.zeros(key.size + 1, dtype=np.int32)
    np.cumsum(np.bincount(slot, minlength=key.size), out=source_start[1:])
    return RowStructure(np.searchsorted(key // n, np.arange(n + 1)).astype(np.int32),
                        (key % n).astype(np.int32), origin[order].astype(np.int32),
                        source_start)


class LinearSolverError(RuntimeError):
    """MUMPS or the solver handle reported an error; ``code`` is INFOG(1) or ours."""

    def __init__(self, code: int, stage: str) -> None:
        self.code = code
        reason = _MESSAGES.get(code, "see the MUMPS user guide, INFOG(1)")
        super().__init__(f"MUMPS {stage} failed with code {code}: {reason}")


class MumpsSolver:
    """One MUMPS instance: analyse a structure once, then factorize and solve repeatedly.

    ``symmetry`` is "unsymmetric", "symmetric" or "spd" (for the last two give one triangle;
    "spd" refuses, at ``factorize``, a matrix that is not positive definite);
    ``ordering`` a MUMPS ordering name ("metis" by default; MUMPS
    falls back to its own choice when the library lacks it); ``controls`` sets further MUMPS
    ICNTL entries by their 1-based index, e.g. ``{10: -2}`` for two refinement steps, and
    ``real_controls`` CNTL entries, e.g. ``{7: 1e-9}`` for the block low-rank tolerance.
    ``precision`` "single" factorizes and solves in single precision (MUMPS's SMUMPS) the
    double-precision values and right-hand sides it is given: half the factor memory and
    its traffic, for solutions good to about eps_single times the condition number, fit for
    preconditioning (docs/theory/linear-solver.md, "Single-precision factors").
    """

    def __init__(
        self, symmetry: str = "unsymmetric", ordering: str = "metis",
        controls: dict[int, int] | None = None,
        real_controls: dict[int, float] | None = None, precision: str = "double",
    ) -> None:
        if symmetry not in _SYMMETRY:
            raise ValueError(f"symmetry must be one of {sorted(_SYMMETRY)}, got {symmetry!r}")
        if ordering not in _ORDERING:
            raise ValueError(f"ordering must be one of {sorted(_ORDERING)}, got {ordering!r}")
        if precision not in _PRECISION:
            raise ValueError(f"precision must be one of {sorted(_PRECISION)}, got "
                             f"{precision!r}")
        mpi.start()
        handle, status = _core.solver_create(_SYMMETRY[symmetry], _ORDERING[ordering],
                                             _PRECISION[precision])
        if status < 0:
            raise LinearSolverError(int(status), "initialization")
        self._handle = int(handle)
        for position, value in (controls or {}).items():
            if _core.solver_set_control(self._handle, int(position), int(value)) < 0:
                self.close()
                raise ValueError(f"MUMPS has no control ICNTL({position})")
        for position, value in (real_controls or {}).items():
            if _core.solver_set_real_control(self._handle, int(position), float(value)) < 0:
                self.close()
                raise ValueError(f"MUMPS has no control CNTL({position})")
        self.n = 0
        self.nnz = 0

    def set_ordering(self, position: ArrayLike) -> None:
        """Use a given pivot order in the next analyses instead of MUMPS's own:
        ``position[i]`` is the 0-based place of variable i in the elimination (a
        permutation of 0..n-1; see ddpy.core.ordering)."""
        position = int_array(position, "position", (None,))
        if not np.array_equal(np.sort(position), np.arange(position.size)):
            raise ValueError("position must be a permutation of 0..n-1")
        if _core.solver_set_ordering(self._live(), position) < 0:
            raise LinearSolverError(-1001, "ordering")

    def analyse(self, n: int, rows: ArrayLike, cols: ArrayLike) -> None:
        """Symbolic analysis of an n x n matrix with entries at 0-based (rows, cols).

        ValueError, before MUMPS sees it: n not a positive 32-bit integer (MUMPS's
        integers), an entry outside 0..n-1, or fewer entries than unknowns: such a matrix
        has empty rows (structurally singular) and MUMPS would allocate for all n, 23 GB for
        n = 2**30 with one entry."""
        rows = int_array(rows, "rows", (None,))
        cols = int_array(cols, "cols", (rows.shape[0],))
        try:
            n = operator.index(n)
        except TypeError:
            raise ValueError(f"matrix size must be an integer, got {n!r}") from None
        if not 1 <= n <= INT32_MAX:
            raise ValueError(f"matrix size must lie in 1..{INT32_MAX} (32-bit MUMPS), got {n}")
        if rows.shape[0] > INT32_MAX:
            raise ValueError(f"at most {INT32_MAX} entries (32-bit MUMPS), got {rows.shape[0]}")
        if rows.size and (min(rows.min(), cols.min()) < 0 or max(rows.max(), cols.max()) >= n):
            raise ValueError(f"rows and cols must lie in 0..{n - 1}")
        if rows.shape[0] < n:
            raise ValueError(f"a {n} x {n} matrix with {rows.shape[0]} entries has empty rows: "
                             "structurally singular (expected at least one entry per row)")
        status = _core.solver_analyse(self._live(), n, rows, cols)
        if status < 0:
            raise LinearSolverError(int(status), "analysis")
        self.n, self.nnz = n, rows.shape[0]

    def analyse_elements(self, n: int, element_variables: ArrayLike) -> None:
        """Symbolic analysis only, of the n x n matrix assembled from elements:
        ``element_variables[e]`` are the 0-based unknowns element e couples (MUMPS's
        elemental input). For MUMPS's estimates of a large structure (``statistics()``:
        flops, factor entries, memory per process) without its coordinates in memory; the
        instance cannot factorize after it (analyse coordinates for that)."""
        variables = int_array(element_variables, "element_variables", (None, None))
        n = operator.index(n)
        if not 1 <= n <= INT32_MAX:
            raise ValueError(f"matrix size must lie in 1..{INT32_MAX} (32-bit MUMPS), got {n}")
        if variables.size == 0 or variables.size > INT32_MAX:
            raise ValueError(f"between 1 and {INT32_MAX} element variables, got {variables.size}")
        if variables.min() < 0 or variables.max() >= n:
            raise ValueError(f"element variables must lie in 0..{n - 1}")
        status = _core.solver_analyse_elements(self._live(), n, variables.shape[1],
                                               np.ascontiguousarray(variables).ravel())
        if status < 0:
            raise LinearSolverError(int(status), "analysis")
        self.n, self.nnz = 0, 0

    @property
    def handle(self) -> int:
        """The core's handle of this instance, for the core's own calls (its Newton loop)."""
        return self._live()

    def factorize(self, values: ArrayLike) -> None:
        """LU (or LDL^T) factorization with the values of the analysed entries.
        LinearSolverError when MUMPS fails, and for "spd" when the matrix has a negative
        pivot (it is not positive definite)."""
        values = float_array(values, "values", (self.nnz,))
        status = _core.solver_factorize(self._live(), values)
        if status < 0:
            raise LinearSolverError(int(status), "factorization")

    def solve(self, rhs: ArrayLike) -> NDArray[np.float64]:
        """Solution x of A x = rhs with the last factorization."""
        b = float_array(rhs, "rhs", (self.n,))
        x, status = _core.solver_solve(self._live(), b)
        if status < 0:
            raise LinearSolverError(int(status), "solve")
        return x

    def statistics(self) -> dict[str, float]:
        """MUMPS figures of the last calls: ordering used, entries in factors, flops of the
        last factorization; the analysis's estimates (``estimated_flops`` RINFOG(1),
        ``estimated_factor_entries`` INFOG(3), ``estimated_memory_mb_max``/``_total``
        INFOG(16)/(17): in-core memory of the factorization on the largest process / all
        processes); after a factorization the memory it allocated (``memory_mb_max``/
        ``_total``, INFOG(18)/(19)) and used (``memory_used_mb_max``/``_total``,
        INFOG(21)/(22)); ``processes``, the MPI processes sharing the work;
        ``negative_pivots``, those of the last factorization with "symmetric" or "spd"
        (INFOG(12); with "unsymmetric" MUMPS counts its off-diagonal pivots there);
        ``workspace_given``, the entries of the workspace given to MUMPS for the last
        factorization (0: MUMPS allocated its own; from the second factorization of a
        structure on, the core gives it what MUMPS took the first time, so that it is not
        allocated and faulted in again at every factorization)."""
        values, flops, status = _core.solver_info(self._live())
        if status < 0:
            raise LinearSolverError(int(status), "statistics")

        def entries(value: int) -> int:
            return int(value) if value >= 0 else -int(value) * 1_000_000

        info = {name: int(values[at]) for name, at in _INFO.items()}
        for name in ("factor_entries", "estimated_factor_entries", "workspace_given"):
            info[name] = entries(info[name])
        info.update({"flops": float(flops[_FLOPS["elimination"]]),
                     "estimated_flops": float(flops[_FLOPS["estimate"]])})
        return info

    def close(self) -> None:
        """Free the MUMPS instance (also done when the object is collected)."""
        if self._handle:
            _core.solver_destroy(self._handle)
            self._handle = 0

    def _live(self) -> int:
        if not self._handle:
            raise LinearSolverError(-1001, "call")
        return self._handle

    def __enter__(self) -> MumpsSolver:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # interpreter shutdown: the module may already be gone
            pass


def spsolve(matrix: Any, rhs: ArrayLike) -> NDArray[np.float64]:
    """Solve a sparse system once. ``matrix`` is anything with ``tocoo()`` (SciPy sparse)
    or a tuple (n, rows, cols, values) of 0-based coordinates (duplicates are summed)."""
    if hasattr(matrix, "tocoo"):
        coo = matrix.tocoo()
        if coo.shape[0] != coo.shape[1]:
            raise ValueError(f"matrix must be square, got shape {coo.shape}")
        n, rows, cols, values = coo.shape[0], coo.row, coo.col, coo.data
    else:
        n, rows, cols, values = matrix
    with MumpsSolver() as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(values)
        return solver.solve(rhs)
