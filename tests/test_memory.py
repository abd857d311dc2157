"""The allocator's limits (ddpy.core.memory): work arrays freed between Newton iterations
keep their pages, so allocating them again costs no page faults."""

import subprocess
import sys

import pytest

from ddpy.core.memory import keep_freed_memory

#: Ten 2 MiB arrays written and freed, again and again, as an iteration's work arrays
#: are; prints the minor page faults of the cycles after the first.
CYCLES = """
import resource, sys
import numpy as np
if sys.argv[1] == "keep":
    from ddpy.core.memory import keep_freed_memory
    assert keep_freed_memory()
def cycle():
    arrays = [np.ones(2**18) for _ in range(10)]
    del arrays
cycle()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(5):
    cycle()
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _faults(mode: str) -> int:
    out = subprocess.run([sys.executable, "-c", CYCLES, mode], capture_output=True, text=True,
                         check=True)
    return int(out.stdout.strip())


@pytest.mark.skipif(not sys.platform.startswith("linux") or not keep_freed_memory(),
                    reason="glibc's mallopt only")
def test_freed_work_arrays_keep_their_pages():
    pages = 5 * 10 * 2 * 2**20 // 4096  # what the five cycles write
    default, kept = _faults("default"), _faults("keep")
    assert default > 0.5 * pages  # glibc's own limits: faulted in again each cycle
    assert kept < 0.02 * pages
