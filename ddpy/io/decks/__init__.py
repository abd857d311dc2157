"""Input decks: a case is a folder of plain-text files, one concern each (docs/input-format.md).

    control.dat    title, solver settings, phases (active tools, motions, increments, output)
    mesh.dat       the blank: own node and hexahedron blocks, a generated box, or a mesh file
    bc.dat         node sets, symmetry planes, fixed nodes
    material.dat   elasticity, yield criterion (von Mises, Hill'48), hardening (Swift, Voce)
    tools.dat      per tool: description, tool file, friction, the blank side it touches

:func:`read_case` reads and checks them all before any numerics and returns the validated
:class:`ddpy.io.case.Case`; any defect raises one :class:`DeckError` listing every error found,
each as ``file:line: what is wrong, what was expected``.

One module per deck reads it: :mod:`ddpy.io.decks.control`, :mod:`ddpy.io.decks.mesh`,
:mod:`ddpy.io.decks.boundary` (bc.dat), :mod:`ddpy.io.decks.material`, :mod:`ddpy.io.decks.tools`;
:mod:`ddpy.io.decks.lines` holds the line reader and value grammar they share, and
:mod:`ddpy.io.decks.cross` the checks across decks and the build of the Case.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path

from ddpy._validate import DECK_LIMIT, MESH_LIMIT, InputFileError, read_input_file
from ddpy.io.case import Case, DeckError
from ddpy.io.decks.boundary import _parse_bc
from ddpy.io.decks.control import _PHASE_KEYS as _PHASE_KEYS
from ddpy.io.decks.control import _SETTINGS as _SETTINGS
from ddpy.io.decks.control import _parse_control
from ddpy.io.decks.cross import _Cross
from ddpy.io.decks.lines import Deck
from ddpy.io.decks.material import _parse_material
from ddpy.io.decks.mesh import _parse_mesh
from ddpy.io.decks.tools import _TOOL_KEYS as _TOOL_KEYS
from ddpy.io.decks.tools import _parse_tools

# _SETTINGS, _PHASE_KEYS (control.dat) and _TOOL_KEYS (tools.dat) stay readable as
# ddpy.io.decks._SETTINGS etc.: tests/test_input_docs.py checks docs/input-format.md against them.
__all__ = ["DECKS", "DeckError", "parse_case", "read_case"]

#: The decks of a case folder, in reading order.
DECKS = ("control.dat", "mesh.dat", "bc.dat", "material.dat", "tools.dat")


def read_case(folder: str | Path, geometry: bool = True) -> Case:
    """Read and validate the case folder; raise DeckError listing every defect found.
    With ``geometry`` the tool models are read (when ddpy.io.toolfile is available) and the
    positions of the tools checked against the blank (docs/input-format.md, "Checks")."""
    folder = Path(folder)
    if not folder.is_dir():
        raise DeckError(f"not a case folder (expected a folder holding {', '.join(DECKS)})",
                        folder)
    texts: dict[str, str] = {}
    errors: list[DeckError] = []
    for name in DECKS:
        path = folder / name
        limit = MESH_LIMIT if name == "mesh.dat" else DECK_LIMIT
        try:
            texts[name] = read_input_file(path, "a deck", limit).decode("utf-8")
        except FileNotFoundError:
            errors.append(DeckError(f"missing: every case needs {', '.join(DECKS)}", path))
        except InputFileError as error:
            errors.append(DeckError(error.reason, path))
        except UnicodeDecodeError as error:
            errors.append(DeckError(f"not UTF-8 text (byte {error.start}): expected a "
                                    "plain-text deck", path))
    if errors:
        raise DeckError.collect(errors)
    return parse_case(texts, folder, geometry=geometry)


def parse_case(texts: Mapping[str, str], folder: str | Path = ".",
               geometry: bool = True) -> Case:
    """Validate decks given as text (``{"control.dat": "...", ...}``); relative file paths in
    them are taken from ``folder``. Raise DeckError listing every defect found."""
    folder = Path(folder)
    missing = [name for name in DECKS if name not in texts]
    if missing:
        raise DeckError.collect([DeckError("missing: every case needs " + ", ".join(DECKS),
                                           folder / name) for name in missing])
    decks = {name: Deck(folder / name, texts[name]) for name in DECKS}
    control = _parse_control(decks["control.dat"])
    parsed_mesh = _parse_mesh(decks["mesh.dat"])
    bc = _parse_bc(decks["bc.dat"])
    material = _parse_material(decks["material.dat"])
    tools = _parse_tools(decks["tools.dat"])
    errors = [e for d in decks.values() for e in d.errors]
    if errors:
        raise DeckError.collect(errors)
    assert parsed_mesh is not None and material is not None
    mesh, mesh_sets, element = parsed_mesh
    cross = _Cross(decks, folder)
    case = cross.build(control, mesh, mesh_sets, bc, material, tools)
    if case is not None:
        case = dataclasses.replace(case, element=element)
    errors = [e for d in decks.values() for e in d.errors]
    if errors or case is None:
        raise DeckError.collect(errors or [DeckError("invalid case", folder)])
    if geometry:
        from ddpy.io.casecheck import geometry_checks

        errors, warnings = geometry_checks(case)
        if errors:
            raise DeckError.collect(errors)
        if warnings:
            case = dataclasses.replace(case, warnings=case.warnings + tuple(warnings))
    return case
