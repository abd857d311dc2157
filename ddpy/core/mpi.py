"""Several processes through MPI: rank 0 runs the driver, ranks > 0 serve its MUMPS calls.

The core follows MUMPS's host-and-workers pattern (docs/mpi.md): under ``mpirun -n N``
every process starts the same program; rank 0 goes on as a single process would, and each
MUMPS call it makes (analysis, factorization, solve) is broadcast to the ranks > 0, which
wait in ``serve`` and take their part of the parallel MUMPS. ``finish`` (registered at exit
by ``start``) tells them to stop. The sequential build (the default) runs the same code in
one process.
"""

from __future__ import annotations

import atexit
import os

from ddpy import _core

__all__ = ["MpiError", "launched_size", "parallel_build", "start", "serve", "finish", "world"]

#: Variables that MPI launchers set to the number of processes (OpenMPI, MPICH/Hydra, Slurm).
_SIZE_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "MPI_LOCALNRANKS")


class MpiError(RuntimeError):
    """The processes cannot work together: e.g. the sequential build under mpirun."""


def launched_size() -> int:
    """Processes the MPI launcher started (its environment), 1 when none started this one."""
    for name in _SIZE_VARIABLES:
        value = os.environ.get(name, "")
        if value.isdigit() and int(value) > 0:
            return int(value)
    return 1


def world() -> tuple[int, int]:
    """This process's rank and the number of processes, starting MPI in the core when it
    has not started (the sequential build: always (0, 1))."""
    rank, size, _parallel, _status = _core.solver_world()
    return int(rank), int(size)


def parallel_build() -> bool:
    """Whether the core has the parallel MUMPS (built with ``-Dmumps=mpi``)."""
    return bool(_core.solver_world()[2])


_finish_registered = False


def start() -> int:
    """Start MPI and return this process's rank. On rank 0 ``finish`` is registered to run
    at exit, so the ranks > 0 are always told to stop. MpiError when a launcher started
    several processes but the core sees one (ddpy built without ``-Dmumps=mpi``): each
    would run the whole case alone."""
    global _finish_registered
    # Idle ranks wait in MPI_Bcast; OpenMPI spins there unless told to yield the core,
    # which rank 0's threads need on a machine with few cores.
    os.environ.setdefault("OMPI_MCA_mpi_yield_when_idle", "1")
    launched = launched_size()
    rank, size = world()
    if launched > 1 and (size == 1 or not parallel_build()):
        raise MpiError(f"started as one of {launched} MPI processes, but this ddpy is the "
                       "sequential build (one process); build the MPI variant with "
                       "./setup.sh --mpi and run .venv-mpi/bin/ddpy (docs/mpi.md)")
    if rank == 0 and not _finish_registered:
        atexit.register(finish)
        _finish_registered = True
    return rank


def serve() -> None:
    """Ranks > 0: take part in rank 0's MUMPS calls until it finishes (then MPI is ended
    here too). Returns at once on rank 0."""
    _core.solver_serve()


def finish() -> None:
    """Rank 0: free every MUMPS instance, stop the ranks > 0 and end MPI (once; also at
    exit). The solver cannot be used after it in this process."""
    _core.solver_finish()
