"""The build itself: OpenMP in the Fortran core and the MUMPS solver behind ddpy.core.linalg."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from ddpy.core.linalg import LinearSolverError, MumpsSolver, spsolve
from ddpy.core.parallel import blas_threads, max_threads, set_threads, threads


@pytest.mark.parametrize("n", [1, 2, 3])
def test_openmp_threads_follow_environment(n: int) -> None:
    env = dict(os.environ, OMP_NUM_THREADS=str(n))
    out = subprocess.run(
        [sys.executable, "-c", "from ddpy.core.parallel import max_threads; print(max_threads())"],
        env=env, capture_output=True, text=True, check=True,
    )
    assert int(out.stdout.strip()) == n


def test_threads_context_restores() -> None:
    before = max_threads()
    with threads(1):
        assert max_threads() == 1
    assert max_threads() == before
    with pytest.raises(ValueError, match="between 1 and"):
        set_threads(0)


def test_the_blas_follows_the_threads() -> None:
    """The BLAS behind MUMPS (OpenBLAS here, with a thread pool of its own) runs on the
    threads asked for: one after set_threads(1), not one per core."""
    if blas_threads() is None:
        pytest.skip("the BLAS behind MUMPS is not OpenBLAS")
    with threads(2):
        assert blas_threads() == 2
        with threads(1):
            assert blas_threads() == 1
        assert blas_threads() == 2


def random_system(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """An unsymmetric, diagonally dominant sparse matrix in coordinates, with duplicates."""
    rng = np.random.default_rng(seed)
    nnz = 8 * n
    rows = np.concatenate([rng.integers(0, n, nnz), np.arange(n)])
    cols = np.concatenate([rng.integers(0, n, nnz), np.arange(n)])
    values = np.concatenate([rng.normal(size=nnz), np.full(n, 10.0)])
    dense = np.zeros((n, n))
    np.add.at(dense, (rows, cols), values)
    return rows, cols, values, dense


def convection_diffusion(m: int, seed: int) -> tuple[np.ndarray, ...]:
    """Unsymmetric 5-point convection-diffusion matrix on an m x m grid, as coordinates,
    with every entry split into two summed duplicates (as FE assembly produces)."""
    rng = np.random.default_rng(seed)
    n = m * m
    index = np.arange(n).reshape(m, m)
    rows, cols, values = [index.ravel()], [index.ravel()], [np.full(n, 5.0)]
    for di, dj, w in ((1, 0, -1.3), (-1, 0, -0.7), (0, 1, -1.2), (0, -1, -0.8)):
        a = index[max(0, -di): m - max(0, di), max(0, -dj): m - max(0, dj)]
        b = index[max(0, di): m + min(0, di) or None, max(0, dj): m + min(0, dj) or None]
        rows.append(a.ravel()), cols.append(b.ravel())
        values.append(w * (1.0 + 0.1 * rng.random(a.size)))
    rows, cols, values = (np.concatenate(x) for x in (rows, cols, values))
    split = rng.random(values.size)
    dense = np.zeros((n, n))
    np.add.at(dense, (rows, cols), values)
    return (np.concatenate([rows, rows]), np.concatenate([cols, cols]),
            np.concatenate([split * values, (1 - split) * values]), dense)


def test_mumps_solves_unsymmetric_system() -> None:
    rows, cols, values, dense = convection_diffusion(30, seed=1)
    n = dense.shape[0]
    assert not np.allclose(dense, dense.T)
    b = np.random.default_rng(2).normal(size=n)
    x = spsolve((n, rows, cols, values), b)
    assert np.linalg.norm(dense @ x - b) / np.linalg.norm(b) < 1e-12
    assert np.allclose(x, np.linalg.solve(dense, b), rtol=1e-10, atol=1e-12)


def test_random_unsymmetric_system_with_refinement() -> None:
    # Threshold pivoting after MUMPS's column matching loses digits on a random matrix
    # (residual about 3e-12 here); two fixed steps of iterative refinement recover them.
    n = 400
    rows, cols, values, dense = random_system(n, seed=1)
    b = np.random.default_rng(2).normal(size=n)
    with MumpsSolver(controls={10: -2}) as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(values)
        x = solver.solve(b)
    assert np.linalg.norm(dense @ x - b) / np.linalg.norm(b) < 1e-14
    with pytest.raises(ValueError, match="ICNTL"):
        MumpsSolver(controls={99: 1})


def test_analysis_reused_for_new_values() -> None:
    n = 300
    rows, cols, values, dense = random_system(n, seed=3)
    b = np.ones(n)
    with MumpsSolver() as solver:
        solver.analyse(n, rows, cols)
        for scale in (1.0, 2.0, -0.5):
            solver.factorize(scale * values)
            x = solver.solve(b)
            assert np.linalg.norm(scale * dense @ x - b) / np.linalg.norm(b) < 1e-12
        assert solver.statistics()["factor_entries"] > 0


def test_symmetric_mode_reads_one_triangle() -> None:
    n = 200
    rng = np.random.default_rng(4)
    a = rng.normal(size=(n, n)) * (rng.random((n, n)) < 0.03)
    spd = a @ a.T + n * np.eye(n)
    rows, cols = np.nonzero(np.tril(spd))
    b = rng.normal(size=n)
    with MumpsSolver(symmetry="spd") as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(spd[rows, cols])
        x = solver.solve(b)
    assert np.linalg.norm(spd @ x - b) / np.linalg.norm(b) < 1e-12


def test_spd_mode_refuses_an_indefinite_matrix() -> None:
    """symmetry="spd" factorizes LDL^T without pivoting, which MUMPS completes on an
    indefinite matrix too (and solves: an answer to the wrong question). Its negative pivots
    are counted (INFOG(12)) and the factorization refused; "symmetric" takes the same matrix,
    with as many negative pivots as it has negative eigenvalues (Sylvester's law)."""
    n = 60
    rng = np.random.default_rng(6)
    a = rng.normal(size=(n, n)) * (rng.random((n, n)) < 0.1)
    indefinite = a + a.T + np.diag(np.linspace(-3.0, 12.0, n))
    negative = int((np.linalg.eigvalsh(indefinite) < 0).sum())
    assert 0 < negative < n
    rows, cols = np.nonzero(np.tril(indefinite))
    b = rng.normal(size=n)
    with MumpsSolver(symmetry="spd") as solver:
        solver.analyse(n, rows, cols)
        with pytest.raises(LinearSolverError, match="code -1007: the matrix is not positive "
                                                    "definite"):
            solver.factorize(indefinite[rows, cols])
        with pytest.raises(LinearSolverError, match="analyse and factorize"):
            solver.solve(b)  # nothing to solve with
        # the instance stays usable: a positive definite matrix on the same structure
        spd = indefinite + 20.0 * np.eye(n)
        solver.factorize(spd[rows, cols])
        assert np.linalg.norm(spd @ solver.solve(b) - b) / np.linalg.norm(b) < 1e-12
        assert solver.statistics()["negative_pivots"] == 0
    with MumpsSolver(symmetry="symmetric") as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(indefinite[rows, cols])
        x = solver.solve(b)
        assert solver.statistics()["negative_pivots"] == negative
    assert np.linalg.norm(indefinite @ x - b) / np.linalg.norm(b) < 1e-10


def test_scipy_sparse_input() -> None:
    sparse = pytest.importorskip("scipy.sparse")
    n = 100
    rows, cols, values, dense = random_system(n, seed=5)
    matrix = sparse.coo_matrix((values, (rows, cols)), shape=(n, n)).tocsr()
    b = np.arange(n, dtype=float)
    x = spsolve(matrix, b)
    # Without refinement MUMPS's threshold pivoting leaves about 1e-12 on this random
    # matrix (0.7e-12 or 1.4e-12, as the rounding of its products falls; see above).
    assert np.linalg.norm(dense @ x - b) / np.linalg.norm(b) < 1e-11


def test_singular_matrix_is_an_error() -> None:
    n = 4
    rows, cols = np.array([0, 1, 2, 3, 0]), np.array([0, 1, 2, 0, 3])
    values = np.array([1.0, 1.0, 1.0, 0.0, 0.0])  # row 3 empty in value
    with pytest.raises(LinearSolverError, match="singular"):
        spsolve((n, rows, cols, values), np.ones(n))


def test_the_workspace_of_a_factorization_is_kept_for_the_next() -> None:
    """MUMPS allocates its workspace at the first factorization of a structure; the next
    ones are given one of that size (the same factors, bitwise); a failed factorization
    (singular) or a new analysis gives it back, and the one after allocates again."""
    n = 60
    rows, cols, values, dense = random_system(n, seed=7)
    b = np.arange(n, dtype=float)
    with MumpsSolver() as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(values)
        first = solver.solve(b)
        assert solver.statistics()["workspace_given"] == 0
        solver.factorize(values)
        given = solver.statistics()["workspace_given"]
        assert given >= solver.statistics()["factor_entries"]
        np.testing.assert_array_equal(solver.solve(b), first)
        with pytest.raises(LinearSolverError, match="singular"):
            solver.factorize(np.zeros_like(values))
        solver.factorize(values)
        assert solver.statistics()["workspace_given"] == 0
        np.testing.assert_array_equal(solver.solve(b), first)
        solver.factorize(values)
        assert solver.statistics()["workspace_given"] == given
        solver.analyse(n, rows, cols)
        solver.factorize(values)
        assert solver.statistics()["workspace_given"] == 0
        np.testing.assert_allclose(dense @ solver.solve(b), b, rtol=0, atol=1e-10 * n)


def test_closed_and_misused_solver_errors() -> None:
    solver = MumpsSolver()
    with pytest.raises(LinearSolverError, match="analyse and factorize"):
        solver.solve(np.ones(0))
    solver.analyse(2, [0, 1], [0, 1])
    with pytest.raises(ValueError, match="shape"):
        solver.factorize([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="0..1"):
        solver.analyse(2, [0, 2], [0, 1])
    solver.close()
    with pytest.raises(LinearSolverError, match="not valid"):
        solver.factorize([1.0, 1.0])
    with pytest.raises(ValueError, match="symmetry"):
        MumpsSolver(symmetry="hermitian")


def test_too_many_open_solvers() -> None:
    open_solvers = []
    with pytest.raises(LinearSolverError, match="too many solvers"):
        for _ in range(64):
            open_solvers.append(MumpsSolver())
    for solver in open_solvers:
        solver.close()
    MumpsSolver().close()  # handles are free again


_BINDING_SCRIPT = """
import numpy as np, scipy.sparse as sp
from ddpy.core.linalg import MumpsSolver
lap = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(40, 40))
a = (sp.kron(sp.kron(lap, sp.eye(40)), sp.eye(4)) + sp.kron(sp.eye(40), sp.kron(lap, sp.eye(4)))
     + 0.1 * sp.eye(6400)).tocoo()
s = MumpsSolver("unsymmetric", "amd")
s.analyse(a.shape[0], a.row, a.col)
s.factorize(a.data)
assert np.abs(a @ s.solve(np.ones(6400)) - 1.0).max() < 1e-10
"""


def test_mumps_calls_the_cores_own_dgemm(tmp_path) -> None:
    """MUMPS's DGEMM references bind to the core's (fortran/solver/ddpy_dgemm.f90, which
    passes one-column products to DGEMV: docs/theory/linear-solver.md), not to the BLAS's:
    the dynamic linker's own account of the binding (glibc's LD_DEBUG)."""
    log = tmp_path / "ld"
    env = {**os.environ, "LD_DEBUG": "bindings", "LD_DEBUG_OUTPUT": str(log)}
    subprocess.run([sys.executable, "-c", _BINDING_SCRIPT], env=env, check=True,
                   capture_output=True)
    logs = list(tmp_path.glob("ld.*"))
    if not logs:
        pytest.skip("the dynamic linker does not report its bindings (not glibc)")
    lines = [line for path in logs for line in path.read_text().splitlines()
             if "symbol `dgemm_'" in line and "mumps" in line]
    assert lines, "MUMPS never bound dgemm_"
    assert all("_core" in line.split(" to ")[1] for line in lines), lines
