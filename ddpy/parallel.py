"""Threads of the Fortran core's OpenMP regions."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from ddpy import _core


def max_threads() -> int:
    """Threads the core's parallel regions use (OMP_NUM_THREADS unless changed)."""
    return int(_core.max_threads())


def set_threads(n: int) -> None:
    """Set the number of threads of the core's parallel regions."""
    if int(n) < 1:
        raise ValueError(f"number of threads must be at least 1, got {n}")
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
