"""The counts, codes and indices that Python and the Fortran core share, read from the core
(``core_constants`` in fortran/api/ddpy_api.f90) once, at import: element kinds and
statuses, the material vector's layout, surface kinds, search modes, contact states and
discretizations, line searches, the Newton loop's outcomes and history columns, the
refusals of the core's handle table and the linear solver's statuses. Offsets are 0-based
positions in a Python array. Python never writes one of these numbers itself: a code the
core changes changes here (tests/test_core_constants.py holds the two views together).

>>> from ddpy.core.constants import constant
>>> constant("shell_modes")
13
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from ddpy import _core

__all__ = ["CORE", "constant", "core_constants"]


def core_constants() -> dict[str, int]:
    """Every constant the core exports, by name."""
    count = int(_core.core_constant_count())
    names, values = _core.core_constants(count)
    width = names.size // max(count, 1)
    text = names.tobytes().decode("ascii")
    return {text[i * width:(i + 1) * width].strip(): int(v)
            for i, v in enumerate(values.tolist())}


#: The core's constants, read once.
CORE: Mapping[str, int] = MappingProxyType(core_constants())


def constant(name: str) -> int:
    """The core's constant ``name`` (KeyError naming it when the core has none such)."""
    try:
        return CORE[name]
    except KeyError:
        raise KeyError(f"the core exports no constant {name!r} (fortran/api/ddpy_api.f90, "
                       "core_constants)") from None
