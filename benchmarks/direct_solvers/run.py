"""Sparse direct solvers on the bending benchmark's paper blank: MUMPS as ddpy calls it
against the ones a user can install from Debian or PyPI (SciPy's SuperLU, UMFPACK through
scikit-umfpack, Intel's PARDISO through pypardiso). Writes docs/benchmarks/direct_solvers.md.

The matrix is the solid's tangent of the paper blank (the solid-shell, Hill'48 steel;
docs/benchmarks/cylindrical_bending_paper.md) at a uniform stretch of 0.5 % along x, past
the yield strain everywhere, so the consistent elasto-plastic tangent; its supports are the
quarter model's symmetry planes and the line under the punch (x = 0) held along z, which
stand in for the tools. It has the pattern of the forming Jacobian's solid block, the block
that sets a factorization's cost (the contact rows of the Gauss-point tools add no fill:
their multipliers are eliminated into the equilibrium rows, docs/theory/contact.md). Each
solver runs in its own process with the threads given (OMP_NUM_THREADS, MKL_NUM_THREADS),
on a matrix read from results/matrix.npz: the analysis (ordering, symbolic factorization),
the factorization and the solve are timed apart, best of REPEATS, and the solution checked
by its residual.

    python run.py            # the matrix (once), then every solver installed, 1 and 2 threads
    python run.py --reuse    # the report from the kept runs (direct_solvers_runs.json)
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from bench_common import DOCS, code_version, computed_at, cores, runs_file  # noqa: E402
from bench_common import table_row as _row  # noqa: E402

CASE = HERE.parent / "cylindrical_bending" / "cases" / "paper" / "nagata"
MATRIX = HERE / "results" / "matrix.npz"
STEM = "direct_solvers"
#: The stretch along x (past Hill'48 steel's yield strain, about 0.15 %).
STRETCH = 5e-3
#: Factorizations and solves timed per solver; the best counts.
REPEATS = 3
#: A solver that takes longer than this for its whole measurement is reported as such.
TIME_LIMIT = 900
#: solver -> its short name in the report's sentences
SHORT = {"mumps_nested": "ddpy's MUMPS", "mumps_metis": "MUMPS with METIS",
         "mumps_coordinates": "MUMPS on the coordinates",
         "superlu": "SuperLU", "umfpack": "UMFPACK", "pardiso": "PARDISO"}
#: solver -> (what it is, where it comes from, whether threads apply)
SOLVERS = {
    "mumps_nested": ("MUMPS 5, LU, ddpy's nested-dissection order (ddpy's default)",
                     "Debian libmumps-seq (setup.sh)", True),
    "mumps_metis": ("MUMPS 5, LU, METIS order", "Debian libmumps-seq (setup.sh)", True),
    "mumps_coordinates": ("MUMPS 5, LU, ddpy's order, given the coordinates with their "
                          "duplicates (ddpy's Newton loop until 2026-12-05)",
                          "Debian libmumps-seq (setup.sh)", True),
    "superlu": ("SuperLU, COLAMD order (scipy.sparse.linalg.splu)", "PyPI scipy (setup.sh)",
                False),
    "umfpack": ("UMFPACK (scikits.umfpack)",
                "Debian libsuitesparse-dev, PyPI scikit-umfpack", True),
    "pardiso": ("PARDISO, MKL (pypardiso)", "PyPI pypardiso (MKL)", True),
}


def build_matrix() -> Path:
    """Assemble the matrix; save it to MATRIX with what ddpy's pivot order is made of (the
    nodes' nested-dissection order, each equation's node)."""
    from ddpy.app.runner import build_problem
    from ddpy.io.decks import read_case
    from ddpy.model.newton import Layout

    if not (CASE / "control.dat").exists():
        subprocess.run([sys.executable, str(CASE.parents[2] / "make_case.py"), "--mesh",
                        "paper"], check=True)
    solid = build_problem(read_case(CASE)).solid
    nodes = solid.mesh.nodes
    fixed = np.zeros((nodes.shape[0], 3), dtype=bool)
    fixed[:, 0] = np.abs(nodes[:, 0]) < 1e-9        # symmetry plane x = 0
    fixed[:, 1] = np.abs(nodes[:, 1]) < 1e-9        # symmetry plane y = 0
    fixed[:, 2] = np.abs(nodes[:, 0]) < 1e-9        # the line under the punch
    u = np.zeros_like(nodes)
    u[:, 0] = STRETCH * nodes[:, 0]
    layout = Layout(solid, [], fixed)
    # (without tools the layout's slots are the solid's tangent's)
    assembly = solid.assemble(u, pattern=solid.pattern(layout.eqn, symmetric=False))
    plastic = float(np.mean(assembly.state.ep > 0))
    MATRIX.parent.mkdir(parents=True, exist_ok=True)
    np.savez(MATRIX, n=layout.n, rows=layout.rows, cols=layout.cols, values=assembly.values,
             node_order=solid.node_order(), equation_nodes=np.flatnonzero(~fixed.ravel()) // 3,
             elements=solid.mesh.n_elements, plastic=plastic)
    return MATRIX


def _best(call: Any, repeats: int) -> tuple[float, Any]:
    best, out = float("inf"), None
    for _ in range(repeats):
        start = time.perf_counter()
        out = call()
        best = min(best, time.perf_counter() - start)
    return best, out


def measure(solver: str) -> dict[str, Any]:
    """Time one solver on MATRIX in this process: analysis, factorization, solve (s), and
    the relative residual of the solution."""
    import scipy.sparse as sp

    from ddpy.app.runner import peak_memory_mb

    data = np.load(MATRIX)
    n = int(data["n"])
    rows, cols, values = data["rows"], data["cols"], data["values"]
    matrix = sp.csr_matrix((values, (rows, cols)), shape=(n, n))
    rng = np.random.default_rng(1)
    b = matrix @ rng.standard_normal(n)
    out: dict[str, Any] = {"solver": solver, "n": n, "entries": int(matrix.nnz)}
    if solver.startswith("mumps"):
        from ddpy.core.ordering import mesh_solver

        mumps = mesh_solver("unsymmetric", "metis" if solver == "mumps_metis" else "nested",
                            lambda: data["node_order"], data["equation_nodes"])
        # ddpy's loop gives MUMPS the coordinates summed (ddpy.model.newton.Layout.entries)
        coo = matrix.tocoo()
        if solver == "mumps_coordinates":
            coo = sp.coo_matrix((values, (rows, cols)), shape=(n, n))
        out["analysis_s"], _ = _best(lambda: mumps.analyse(n, coo.row, coo.col), 1)
        out["factorization_s"], _ = _best(lambda: mumps.factorize(coo.data), REPEATS)
        out["solve_s"], x = _best(lambda: mumps.solve(b), REPEATS)
        stats = mumps.statistics()
        out["factor_entries"] = stats.get("factor_entries")
        out["flops"] = stats.get("flops")
    elif solver == "superlu":
        from scipy.sparse.linalg import splu

        csc = matrix.tocsc()
        out["analysis_s"] = None  # splu orders and factorizes in one call
        out["factorization_s"], lu = _best(lambda: splu(csc, permc_spec="COLAMD"), 1)
        out["solve_s"], x = _best(lambda: lu.solve(b), REPEATS)
        out["factor_entries"] = int(lu.L.nnz + lu.U.nnz)
    elif solver == "umfpack":
        from scikits.umfpack import UMFPACK_A, UmfpackContext

        csc = matrix.tocsc()
        csc.sort_indices()
        csc.indices = csc.indices.astype(np.int64)
        csc.indptr = csc.indptr.astype(np.int64)
        umf = UmfpackContext("dl")
        out["analysis_s"], _ = _best(lambda: umf.symbolic(csc), 1)
        out["factorization_s"], _ = _best(lambda: umf.numeric(csc), REPEATS)
        out["solve_s"], x = _best(lambda: umf.solve(UMFPACK_A, csc, b, autoTranspose=True),
                                  REPEATS)
        out["factor_entries"] = None
    elif solver == "pardiso":
        pardiso = _Pardiso(matrix.tocsr())
        out["analysis_s"], _ = _best(lambda: pardiso.call(11, np.zeros(n)), 1)
        out["factorization_s"], _ = _best(lambda: pardiso.call(22, np.zeros(n)), REPEATS)
        out["solve_s"], x = _best(lambda: pardiso.call(33, b), REPEATS)
        out["factor_entries"] = int(pardiso.solver.iparm[17]) or None  # iparm(18)
    else:
        raise SystemExit(f"unknown solver {solver!r}")
    out["residual"] = float(np.linalg.norm(matrix @ x - b) / np.linalg.norm(b))
    out["peak_memory_mb"] = peak_memory_mb()
    return out


class _Pardiso:
    """MKL PARDISO (real unsymmetric, mtype 11) on one CSR matrix through pypardiso's
    handle to the library, its 1-based index arrays made once: pypardiso's own calls make
    them at each call, which would add their time to every solve."""

    def __init__(self, csr: Any) -> None:
        from pypardiso import PyPardisoSolver

        csr.sort_indices()
        self.solver = PyPardisoSolver(mtype=11)
        self.solver._check_A(csr)  # sets the iparm entries pypardiso sets for a CSR input
        self.csr = csr
        self.ia = (csr.indptr + 1).astype(np.int32)
        self.ja = (csr.indices + 1).astype(np.int32)

    def call(self, phase: int, b: np.ndarray) -> np.ndarray:
        import ctypes

        s, a = self.solver, self.csr
        b = np.ascontiguousarray(b, dtype=np.float64)
        x = np.zeros_like(b)
        error = ctypes.c_int32(0)
        i32, f64 = ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_double)
        one = ctypes.c_int32(1)
        s._mkl_pardiso(s.pt.ctypes.data_as(ctypes.POINTER(s._pt_type[0])), ctypes.byref(one),
                       ctypes.byref(one), ctypes.byref(ctypes.c_int32(11)),
                       ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(
                           a.shape[0])), a.data.ctypes.data_as(f64),
                       self.ia.ctypes.data_as(i32), self.ja.ctypes.data_as(i32),
                       s.perm.ctypes.data_as(i32), ctypes.byref(one),
                       s.iparm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(0)),
                       b.ctypes.data_as(f64), x.ctypes.data_as(f64), ctypes.byref(error))
        if error.value:
            raise RuntimeError(f"PARDISO error {error.value} in phase {phase}")
        return x


def available(solver: str) -> bool:
    """Whether the solver's Python package imports here."""
    module = {"superlu": "scipy.sparse.linalg", "umfpack": "scikits.umfpack",
              "pardiso": "pypardiso"}.get(solver, "ddpy.core.linalg")
    probe = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True)
    return probe.returncode == 0


def run_one(solver: str, threads: int) -> dict[str, Any]:
    """``measure(solver)`` in a child process with ``threads`` threads."""
    env = {**os.environ, "OMP_NUM_THREADS": str(threads), "MKL_NUM_THREADS": str(threads),
           "OPENBLAS_NUM_THREADS": str(threads)}
    try:
        done = subprocess.run([sys.executable, __file__, "--measure", solver], env=env,
                              capture_output=True, text=True, timeout=TIME_LIMIT)
    except subprocess.TimeoutExpired:
        return {"solver": solver, "threads": threads, "failed": f"over {TIME_LIMIT} s"}
    if done.returncode != 0:
        return {"solver": solver, "threads": threads,
                "failed": (done.stderr.strip().splitlines() or ["no output"])[-1]}
    return {**json.loads(done.stdout.strip().splitlines()[-1]), "threads": threads}


def _s(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def run_mixes() -> dict[str, dict[str, Any]]:
    """What the linear solver did in two runs of the bending paper mesh with Nagata tools:
    the paper report's (GMRES on older factors between factorizations) and the levers
    report's with direct solves (a factorization at every iteration): LU factorizations,
    Newton iterations (forming and springback), the run's total time in solves with
    factors (GMRES's and the line search's included) and its threads. Empty for a run
    not kept."""
    mixes = {}
    for name, (stem, key) in {"reuse": ("cylindrical_bending_paper", "nagata"),
                              "exact": ("cylindrical_bending_levers", "direct")}.items():
        path = runs_file(stem)
        entry = json.loads(path.read_text()).get(key) if path.exists() else None
        if not entry:
            continue
        n = entry["numbers"]
        iterations = n["iterations"] + n["springback_iterations"]
        mixes[name] = {"factorizations": n["factorizations"], "iterations": iterations,
                       "solve_s": n["per_iteration_s"]["solve"] * iterations,
                       "threads": n["threads"]}
    return mixes


def linear_time(run: dict[str, Any], mix: dict[str, Any], base: dict[str, Any]) -> float:
    """The linear solver's time over a run with ``mix`` had it used the solver of ``run``:
    its factorizations at ``run``'s time each, and the run's time in solves scaled by
    ``run``'s solve against ``base``'s (ddpy's MUMPS on the run's threads, which the run
    used)."""
    return (mix["factorizations"] * run["factorization_s"]
            + mix["solve_s"] * run["solve_s"] / base["solve_s"])


MIX_TEXT = {"reuse": "the paper report's Nagata run (GMRES on older factors)",
            "exact": "the levers report's run with direct solves (a factorization at "
                     "every iteration)"}


def report(runs: list[dict[str, Any]], matrix: dict[str, Any], code: str,
           mixes: dict[str, dict[str, Any]]) -> str:
    """The report of the kept runs; ``mixes``: run_mixes()."""
    lines = [
        "# Sparse direct solvers on the paper blank's matrix", "",
        computed_at(code) + f" Machine: {matrix['machine']}.", "",
        "Written by `benchmarks/direct_solvers/run.py` (its docstring says how the matrix is "
        "made and how each solver is timed). The matrix: "
        f"{matrix['n']:,} unknowns, {matrix['entries']:,} entries, the tangent of the "
        f"bending benchmark's paper blank ({matrix['elements']:,} solid-shells) with "
        f"{matrix['plastic']:.0%} of its integration points plastic. Times in s, the best "
        f"of {REPEATS} factorizations and solves (SuperLU: one factorization, its ordering "
        "inside).", "",
        _row(["solver", "from", "threads", "analysis", "factorization", "solve",
              "factor entries", "residual", "peak memory (MB)"]),
        _row(["---"] * 9)]
    for r in runs:
        what, where, _ = SOLVERS[r["solver"]]
        if "failed" in r:
            lines.append(_row([what, where, r["threads"], "-", f"failed: {r['failed']}", "-",
                               "-", "-", "-"]))
            continue
        entries = r.get("factor_entries")
        lines.append(_row([what, where, r["threads"], _s(r.get("analysis_s")),
                           _s(r["factorization_s"]), _s(r["solve_s"]),
                           f"{entries / 1e6:.1f} M" if entries else "-",
                           f"{r['residual']:.1e}", f"{r['peak_memory_mb']:.0f}"]))
    done = [r for r in runs if "failed" not in r]
    ours = {r["threads"]: r for r in done if r["solver"] == "mumps_nested"}
    lines += ["", "## What it says", ""]
    for threads, base in sorted(ours.items()):
        others = [r for r in done if r["threads"] == threads and r["solver"] != "mumps_nested"]
        if others:
            lines.append(
                f"- On {threads} thread(s), against ddpy's MUMPS (factorization "
                f"{base['factorization_s']:.3f} s, solve {base['solve_s']:.4f} s): "
                + "; ".join(f"{SHORT[r['solver']]} factorization "
                            f"{r['factorization_s'] / base['factorization_s']:.2f} times, "
                            f"solve {r['solve_s'] / base['solve_s']:.2f} times"
                            for r in others) + ".")
    usable = {name: mix for name, mix in mixes.items() if mix["threads"] in ours}
    if usable:
        lines += [
            "", "## Over a whole run", "",
            "A forming run factorizes and solves in proportions its linear solver sets. The "
            "linear solver's time over two measured runs of the bending paper mesh with "
            "Nagata tools, had each used the solver of the row (their factorizations at the "
            "row's time each, their time in solves scaled by the row's solve against ddpy's "
            "MUMPS on the run's threads): " + "; ".join(
                f"{name}: {MIX_TEXT[name]}, {mix['factorizations']} LU factorizations over "
                f"{mix['iterations']} Newton iterations on {mix['threads']} thread(s)"
                for name, mix in usable.items()) + ". Assembly and contact search come on "
            "top, per Newton iteration.", "",
            _row(["solver", "threads", *(f"{name}: linear time of the run [s]"
                                         for name in usable)]),
            _row(["---"] * (2 + len(usable)))]
        for r in done:
            lines.append(_row([SHORT[r["solver"]], r["threads"], *(
                f"{linear_time(r, mix, ours[mix['threads']]):.0f}"
                for mix in usable.values())]))
        lines.append("")
        for name, mix in usable.items():
            best = min(done, key=lambda r, m=mix: linear_time(r, m, ours[m["threads"]]))
            lines.append(f"- {name}: the least linear time with "
                         f"{SHORT[best['solver']]} on {best['threads']} thread(s), "
                         f"{linear_time(best, mix, ours[mix['threads']]):.0f} s.")
    missing = sorted({s for s in SOLVERS} - {r["solver"] for r in runs})
    if missing:
        lines.append(("\n" if not usable else "") + "- Not installed where this report "
                     "was written: " + ", ".join(
            f"{SOLVERS[s][0]} ({SOLVERS[s][1]})" for s in missing) + ".")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reuse", action="store_true", help="report from the kept runs")
    parser.add_argument("--measure", choices=SOLVERS, help=argparse.SUPPRESS)
    parser.add_argument("--solvers", default=",".join(SOLVERS),
                        help="comma-separated among " + ", ".join(SOLVERS))
    args = parser.parse_args(argv)
    if args.measure:
        print(json.dumps(measure(args.measure)))
        return 0
    kept = runs_file(STEM)
    if args.reuse:
        stored = json.loads(kept.read_text())
        runs, matrix, code = stored["runs"], stored["matrix"], stored["code"]
    else:
        if not MATRIX.exists():
            build_matrix()
        data = np.load(MATRIX)
        matrix = {"n": int(data["n"]), "entries": 0, "elements": int(data["elements"]),
                  "plastic": float(data["plastic"]),
                  "machine": f"{platform.machine()}, {cores()} cores"}
        runs = []
        for solver in [s.strip() for s in args.solvers.split(",") if s.strip()]:
            if not available(solver):
                print(f"{solver}: not installed", file=sys.stderr)
                continue
            for threads in (1, 2) if SOLVERS[solver][2] else (1,):
                print(f"{solver}, {threads} thread(s) ...", file=sys.stderr, flush=True)
                runs.append(run_one(solver, threads))
                print(f"  {runs[-1]}", file=sys.stderr, flush=True)
        matrix["entries"] = next((r["entries"] for r in runs if "entries" in r), 0)
        code = code_version()  # the code that measured, stated by the report
        kept.write_text(json.dumps({"code": code, "matrix": matrix, "runs": runs},
                                   indent=1) + "\n")
    out = DOCS / f"{STEM}.md"
    out.write_text(report(runs, matrix, code, run_mixes()))
    print(f"wrote {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
