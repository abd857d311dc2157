"""Threads of the Fortran core's OpenMP regions."""

from __future__ import annotations

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


@contextmanager
def threads(n: int) -> Iterator[None]:
    """Run a block with ``n`` threads, then restore the previous number."""
    before = max_threads()
    set_threads(n)
    try:
        yield
    finally:
        set_threads(before)
