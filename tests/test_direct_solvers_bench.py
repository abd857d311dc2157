"""The direct-solver benchmark (benchmarks/direct_solvers/run.py) on a small matrix: each
installed solver solves it, and the report weighs factorizations and solves as the forming
run does. No large matrix, no timing asserted."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "direct_solvers"
sys.path.insert(0, str(BENCH.parent))
from bench_common import load_module  # noqa: E402

bench = load_module(BENCH / "run.py", "direct_solvers_run")


@pytest.fixture()
def small_matrix(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An unsymmetric, diagonally dominant 300 x 300 matrix in the benchmark's file format."""
    rng = np.random.default_rng(3)
    n = 300
    a = sp.random(n, n, density=0.02, random_state=4, format="coo")
    a = (a + sp.diags(np.abs(a).sum(axis=1).A1 + 1.0)).tocoo()
    path = tmp_path / "matrix.npz"
    np.savez(path, n=n, rows=a.row.astype(np.int32), cols=a.col.astype(np.int32),
             values=a.data, node_order=rng.permutation(n), equation_nodes=np.arange(n),
             elements=1, plastic=1.0)
    monkeypatch.setattr(bench, "MATRIX", path)
    return path


@pytest.mark.parametrize("solver", ["mumps_nested", "mumps_metis", "superlu", "pardiso"])
def test_each_installed_solver_solves_the_matrix(small_matrix: Path, solver: str) -> None:
    if not bench.available(solver):
        pytest.skip(f"{solver} is not installed")
    out = bench.measure(solver)
    assert out["n"] == 300 and out["residual"] < 1e-10
    assert out["factorization_s"] > 0 and out["solve_s"] > 0


def test_the_report_weighs_factorizations_and_solves_as_each_run_did() -> None:
    mixes = {"reuse": {"factorizations": 10, "iterations": 100, "solve_s": 25.0, "threads": 1},
             "exact": {"factorizations": 60, "iterations": 50, "solve_s": 5.0, "threads": 1}}
    ours = {"solver": "mumps_nested", "threads": 1, "factorization_s": 1.0, "solve_s": 0.05,
            "analysis_s": 0.2, "factor_entries": 5e7, "residual": 1e-16, "peak_memory_mb": 900}
    other = {**ours, "solver": "pardiso", "factorization_s": 0.5, "solve_s": 0.15}
    # reuse: 10 x 1.0 + 25 = 35 s against 10 x 0.5 + 25 x 3 = 80 s;
    # exact: 60 x 1.0 + 5 = 65 s against 60 x 0.5 + 5 x 3 = 45 s
    assert bench.linear_time(other, mixes["exact"], ours) == pytest.approx(45.0)
    text = bench.report([ours, other, {"solver": "superlu", "threads": 1,
                                       "failed": "over 900 s"}],
                        {"n": 300, "entries": 2000, "elements": 1, "plastic": 1.0,
                         "machine": "x86_64, 2 cores"}, "abc1234", mixes)
    assert "| ddpy's MUMPS | 1 | 35 | 65 |" in text and "| PARDISO | 1 | 80 | 45 |" in text
    assert "PARDISO factorization 0.50 times, solve 3.00 times" in text
    assert "- reuse: the least linear time with ddpy's MUMPS on 1 thread(s), 35 s." in text
    assert "- exact: the least linear time with PARDISO on 1 thread(s), 45 s." in text
    assert "failed: over 900 s" in text
    assert "UMFPACK (scikits.umfpack) (Debian libsuitesparse-dev, PyPI scikit-umfpack)" in text
