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
             values=a.data, position=rng.permutation(n), elements=1, plastic=1.0)
    monkeypatch.setattr(bench, "MATRIX", path)
    return path


@pytest.mark.parametrize("solver", ["mumps_nested", "mumps_metis", "superlu", "pardiso"])
def test_each_installed_solver_solves_the_matrix(small_matrix: Path, solver: str) -> None:
    if not bench.available(solver):
        pytest.skip(f"{solver} is not installed")
    out = bench.measure(solver)
    assert out["n"] == 300 and out["residual"] < 1e-10
    assert out["factorization_s"] > 0 and out["solve_s"] > 0


def test_the_report_weighs_factorizations_and_solves_as_the_run_did() -> None:
    mix = {"factorizations": 10, "iterations": 100, "solves": 500}
    ours = {"solver": "mumps_nested", "threads": 1, "factorization_s": 1.0, "solve_s": 0.05,
            "analysis_s": 0.2, "factor_entries": 5e7, "residual": 1e-16, "peak_memory_mb": 900}
    other = {**ours, "solver": "pardiso", "factorization_s": 0.8, "solve_s": 0.15}
    # (10 x 1.0 + 500 x 0.05) / 100 = 0.35 s; (10 x 0.8 + 500 x 0.15) / 100 = 0.83 s
    assert bench._per_iteration(ours, mix) == pytest.approx(0.35)
    text = bench.report([ours, other, {"solver": "superlu", "threads": 1,
                                       "failed": "over 900 s"}],
                        {"n": 300, "entries": 2000, "elements": 1, "plastic": 1.0,
                         "machine": "x86_64, 2 cores"}, "abc1234", mix)
    assert "| 0.350 |" in text and "| 0.830 |" in text
    assert "factorization 0.80 times, solve 3.00 times, per Newton iteration 2.37 times" in text
    assert "failed: over 900 s" in text
    assert "UMFPACK (scikits.umfpack) (Debian libsuitesparse-dev, PyPI scikit-umfpack)" in text
