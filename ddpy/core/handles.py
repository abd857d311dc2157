"""Objects the core keeps behind handles of its one table (fortran/solver/ddpy_handle_table.f90):
a blank, a tool surface with its search structures, a forming problem. ``CoreHandle`` owns one
and releases it when it is closed or garbage-collected; ``check`` turns a refusal of the
core into an exception that says what was refused.
"""

from __future__ import annotations

import weakref

from ddpy import _core
from ddpy.core.constants import constant

__all__ = ["CoreHandle", "CoreRefusal", "check"]


class CoreRefusal(ValueError):
    """The core refused a call: what it was given does not fit what the handle holds."""


def _reasons() -> dict[int, str]:
    return {constant("refusal_handle"): "the handle holds no such object (released?)",
            constant("refusal_size"): "an array's size does not fit",
            constant("refusal_index"): "an index is out of range or out of order",
            constant("refusal_full"): f"the core's handle table is full "
                                      f"({constant('max_handles')} objects: blanks, tool "
                                      "surfaces, problems and linear solvers); release some",
            constant("refusal_value"): "a value is out of range",
            constant("refusal_order"): "a call came before the ones it needs"}


_REASONS = _reasons()


def check(status: int, what: str) -> None:
    """Raise CoreRefusal naming ``what`` when ``status`` is a refusal (0: done)."""
    if status:
        reason = _REASONS.get(int(status), f"status {int(status)}")
        raise CoreRefusal(f"{what}: the core refused it: {reason}")


def _release(handle: int) -> None:
    _core.handle_release(handle)


class CoreHandle:
    """One handle of the core's table, released by ``close`` or when this object goes."""

    def __init__(self, handle: int) -> None:
        self.handle = int(handle)
        self._finalizer = weakref.finalize(self, _release, self.handle)

    def close(self) -> None:
        """Release the handle now (later calls do nothing)."""
        self._finalizer()

    @property
    def closed(self) -> bool:
        return not self._finalizer.alive
