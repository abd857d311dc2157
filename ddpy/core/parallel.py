"""Threads of the Fortran core's OpenMP regions, and of the BLAS that its MUMPS calls."""

from __future__ import annotations

import ctypes
import os
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from ddpy import _core


def max_threads() -> int:
    """Threads the core's parallel regions use (OMP_NUM_THREADS unless changed)."""
    return int(_core.max_threads())


def thread_limit() -> int:
    """The most threads set_threads accepts: four per core, at least 64. OpenMP starts every
    thread of a region at once; 100,000 of them exhaust the process and abort it."""
    return max(64, 4 * (os.cpu_count() or 1))


def set_threads(n: int) -> None:
    """Set the number of threads of the core's parallel regions (1 to thread_limit())."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"number of threads must be an integer, got {n!r}")
    if not 1 <= n <= thread_limit():
        raise ValueError(f"number of threads must be between 1 and {thread_limit()} (four per "
                         f"core of this machine, at least 64), got {n}")
    _core.set_threads(int(n))
    set_blas_threads(int(n))


def blas_threads() -> int | None:
    """Threads of the BLAS behind MUMPS when it is OpenBLAS (Debian's build: its own
    thread pool, not OpenMP's), else None."""
    function = _openblas("openblas_get_num_threads")
    return None if function is None else int(function())


def set_blas_threads(n: int) -> None:
    """Hold the BLAS behind MUMPS to ``n`` threads, where it is OpenBLAS (another BLAS is
    left as it is). set_threads calls it: OpenBLAS starts a thread per core whatever the
    OpenMP setting, and between its calls an idle one spins on the other core; a run on
    one thread took 3 minutes of system time beside 3.5 of its own (the coarse reverse
    deep drawing), and slowed the run on the other core."""
    function = _openblas("openblas_set_num_threads")
    if function is not None:
        function(int(n))


def _openblas(name: str) -> ctypes._CFuncPtr | None:
    """A function of the OpenBLAS the core loaded (not loaded again: RTLD_NOLOAD)."""
    try:
        library = ctypes.CDLL("libopenblas.so.0", mode=os.RTLD_NOLOAD)
    except OSError:
        return None
    return getattr(library, name, None)


@contextmanager
def threads(n: int) -> Iterator[None]:
    """Run a block with ``n`` threads, then restore the previous number."""
    before = max_threads()
    set_threads(n)
    try:
        yield
    finally:
        set_threads(before)
