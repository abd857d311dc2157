"""Programs that tests/test_mpi.py starts under mpirun: rank 0 drives, ranks > 0 serve.

python tests/mpi_driver.py MODE OUT: ``solve`` writes the solution of a random sparse system
and the solver's statistics to OUT (.npz); ``singular`` factorizes a singular matrix and
writes the error's message; ``raise`` fails with an uncaught error after a factorization;
``die`` leaves the process without a word (os._exit) while the ranks > 0 wait.
"""

from __future__ import annotations

import os
import sys

import numpy as np

from ddpy.core import mpi


def system(n: int = 3000, seed: int = 0) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """A random unsymmetric sparse system with a dominant diagonal (n, rows, cols, values)."""
    rng = np.random.default_rng(seed)
    rows = np.concatenate([np.arange(n), rng.integers(0, n, 12 * n)])
    cols = np.concatenate([np.arange(n), rng.integers(0, n, 12 * n)])
    values = np.concatenate([np.full(n, 20.0), rng.normal(size=12 * n)])
    return n, rows, cols, values


def main(mode: str, out: str) -> int:
    if mpi.start() > 0:
        mpi.serve()
        return 0
    from ddpy.core.linalg import LinearSolverError, MumpsSolver

    solver = MumpsSolver()
    if mode == "singular":
        solver.analyse(3, [0, 1, 2], [0, 1, 2])
        try:
            solver.factorize([1.0, 0.0, 1.0])
        except LinearSolverError as error:
            with open(out, "w") as file:
                file.write(str(error))
        return 0
    n, rows, cols, values = system()
    solver.analyse(n, rows, cols)
    solver.factorize(values)
    x = solver.solve(np.ones(n))
    if mode == "raise":
        raise RuntimeError("rank 0 failed on purpose")
    if mode == "die":
        os._exit(3)
    stats = solver.statistics()
    np.savez(out, x=x, processes=stats["processes"], flops=stats["flops"],
             memory=stats["estimated_memory_mb_max"])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
