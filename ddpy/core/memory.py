"""How the C library's allocator returns freed memory to the system.

A Newton iteration allocates and frees the same large work arrays again and again (the
contact's per-pair derivatives, MUMPS's solve workspace, GMRES's basis). By default glibc
serves a block above its mmap threshold with pages of its own and gives them back when
the block is freed, and trims the top of its heap once more than twice that threshold is
free there: every such array's pages are faulted in and zeroed by the kernel again at the
next allocation. ``keep_freed_memory`` raises both limits, so freed blocks up to 32 MiB
stay in the heap for the next allocation (docs/theory/speed.md, "Cheaper iterations").
"""

from __future__ import annotations

import ctypes
import ctypes.util

__all__ = ["MMAP_THRESHOLD", "TRIM_THRESHOLD", "keep_freed_memory"]

#: Blocks at or below this come from the heap (glibc's largest allowed value on 64-bit
#: systems: HEAP_MAX_SIZE / 2); larger ones keep pages of their own.
MMAP_THRESHOLD = 32 * 2**20
#: Free memory at the heap's top up to this stays with the process. With mmap switched
#: off altogether (every block from the heap) the paper deep drawing's peak resident size
#: grew from 1.61 to 1.97 GB (fragmentation); with these two limits it was 1.62 GB.
TRIM_THRESHOLD = 2**30
#: mallopt's parameter numbers (glibc's malloc.h).
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3

_applied: bool | None = None


def keep_freed_memory() -> bool:
    """Set the allocator's limits once per process; whether they are in effect (False where
    the C library has no glibc mallopt, which is then left as it is)."""
    global _applied
    if _applied is None:
        _applied = _set_limits()
    return _applied


def _set_limits() -> bool:
    name = ctypes.util.find_library("c")
    try:
        mallopt = ctypes.CDLL(name).mallopt if name else None
    except (OSError, AttributeError):
        mallopt = None
    if mallopt is None:
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and \
        bool(mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))
