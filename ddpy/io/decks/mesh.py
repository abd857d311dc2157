"""mesh.dat: the blank, as own 'nodes' and 'hexahedra' blocks, a generated 'box' or a mesh file
(Abaqus input, read by ddpy's .inp reader with its ids kept, or Gmsh, checked entry by entry
at its lines, then read through meshio), with
its sheet normal, scale and origin, and the element it is discretized with. The nodes are
checked to belong to an element here, the elements by HexMesh (ddpy.model.mesh,
find_bad_elements), whose findings are reported at the elements' lines.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ddpy._validate import MESH_LIMIT, InputFileError, check_input_file, read_input_file
from ddpy.io.case import DeckError
from ddpy.io.decks.lines import (
    INT_PATTERN,
    MAX_LENGTH,
    NUMBER_PATTERN,
    BadValue,
    Deck,
    Line,
    check_arity,
    first_time,
    read_choice,
    read_float,
    read_int,
    read_vector,
    show,
)
from ddpy.io.gmsh import GmshFileError, check_gmsh
from ddpy.io.inp_mesh import ddpy_name, read_inp_mesh
from ddpy.model.mesh import (
    MAX_ELEMENTS,
    HexMesh,
    MeshError,
    zeta_along_normal,
    zeta_off_normal,
)
from ddpy.model.solid import DEFAULT_ELEMENT, ELEMENTS, check_element

#: Mesh files: Abaqus input (ddpy's reader), Gmsh (through meshio).
MESH_SUFFIXES = (".inp", ".msh")
#: Largest node or element id.
MAX_ID = 2**31 - 1
#: Largest number of errors reported for one kind of defect in a block of data lines (or
#: of bad elements).
_MAX_REPORTED = 5


@dataclass
class _RawMesh:
    nodes: NDArray[np.float64]
    elements: NDArray[np.int64]  # 0-based
    node_ids: NDArray[np.int64]
    element_ids: NDArray[np.int64]
    element_lines: NDArray[np.int64] | None  # deck line of each element (own format)
    nodesets: dict[str, NDArray[np.int64]]
    source: str
    node_lines: NDArray[np.int64] | None = None  # deck line of each node (own format)


def _parse_mesh(deck: Deck) -> tuple[HexMesh, dict[str, NDArray[np.int64]], str] | None:
    """The mesh, its node sets and the element (ddpy.model.solid.ELEMENTS), or None after
    reporting what is wrong."""
    seen: dict[str, int] = {}
    element = DEFAULT_ELEMENT
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    scale = 1.0
    origin = np.zeros(3)
    raw: _RawMesh | None = None
    sources: list[tuple[str, int]] = []
    lines = deck.lines
    i = 0
    while i < len(lines):
        line = lines[i]
        i += 1
        key = line.key
        try:
            if key == "normal":
                check_arity(line, "normal x|y|z|-x|-y|-z", 1)
                if first_time(deck, seen, line):
                    word = read_choice(line.words[1], "the sheet normal",
                                   ("x", "y", "z", "+x", "+y", "+z", "-x", "-y", "-z"))
                    if word[-1] != "z":
                        # ddpy run refuses it (the Solid turns the material axes about z).
                        raise BadValue(f"a sheet normal along {word[-1]} is not supported yet "
                                       "(the solid takes the rolling direction as an angle "
                                       "about z): expected 'normal z' or 'normal -z', the "
                                       "mesh turned to match")
                    normal = (0.0, 0.0, -1.0 if word.startswith("-") else 1.0)
            elif key == "element":
                check_arity(line, "element " + " | ".join(ELEMENTS), 1)
                if first_time(deck, seen, line):
                    try:  # Solid's check
                        element = check_element(line.words[1])
                    except ValueError as error:
                        raise BadValue(str(error)) from None
            elif key == "scale":
                check_arity(line, "scale FACTOR", 1)
                if first_time(deck, seen, line):
                    scale = read_float(line.words[1], "the scale factor", gt=0)
            elif key == "origin":
                check_arity(line, "origin X Y Z", 3)
                if first_time(deck, seen, line):
                    origin = np.array(read_vector(line.words[1:], "the origin", MAX_LENGTH))
            elif key in ("nodes", "hexahedra", "box", "file"):
                if key != "hexahedra":
                    if sources:
                        deck.error(line.number, f"'{key}' conflicts with '{sources[0][0]}' at "
                                   f"line {sources[0][1]}: give the mesh one way ('nodes' and "
                                   "'hexahedra' blocks, 'box' or 'file')")
                        return None
                    sources.append((key, line.number))
                if key == "box":
                    check_arity(line, "box LX LY LZ NX NY NZ", 6)
                    if first_time(deck, seen, line):
                        raw = _box(line)
                elif key == "file":
                    check_arity(line, "file PATH", 1)
                    if first_time(deck, seen, line):
                        raw = _mesh_file(deck, line)
                elif key == "nodes":
                    if first_time(deck, seen, line):
                        i, raw = _own_mesh(deck, lines, i - 1)
                        if raw is None:
                            return None  # the rest of the file cannot be told apart
                else:
                    raise BadValue("'hexahedra' must follow the 'nodes' block")
            else:
                raise BadValue(f"unknown keyword {show(key)}: expected normal, element, scale, "
                           "origin, nodes, hexahedra, box or file")
        except BadValue as bad:
            deck.error(line.number, str(bad))
    if deck.errors:
        return None
    if raw is None:
        deck.error(None, "no mesh: expected 'nodes' and 'hexahedra' blocks, 'box LX LY LZ NX "
                   "NY NZ' or 'file PATH'")
        return None
    if "origin" in seen and sources[0][0] != "box":
        deck.error(seen["origin"], "'origin' applies to a generated 'box' only")
        return None
    with np.errstate(over="ignore", invalid="ignore"):
        nodes = raw.nodes * scale + (origin if sources[0][0] == "box" else 0.0)
    with np.errstate(invalid="ignore"):
        if not np.all(np.abs(nodes) <= MAX_LENGTH):
            deck.error(seen.get("scale", sources[0][1]), f"node coordinates beyond +-"
                       f"{MAX_LENGTH:g} mm (after scaling)")
            return None
    try:
        mesh = HexMesh(nodes, raw.elements, raw.node_ids, raw.element_ids, normal, raw.source)
    except MeshError as error:
        _report_bad_elements(deck, raw, error)
        mesh = None
    if not _no_free_nodes(deck, raw) or mesh is None:  # reported with the bad elements
        return None
    if element == "solid-shell" and zeta_off_normal(mesh.nodes, mesh.elements,
                                                    mesh.normal).size:
        # The solid-shell's zeta runs through the sheet: each element's nodes are reordered
        # (a cyclic change of its axes, the same element) so that it does.
        mesh = HexMesh(mesh.nodes, zeta_along_normal(mesh.nodes, mesh.elements, mesh.normal),
                       mesh.node_ids, mesh.element_ids, mesh.normal, mesh.source)
    return mesh, raw.nodesets, element


def _box(line: Line) -> _RawMesh:
    """``box LX LY LZ NX NY NZ``: HexMesh.box's nodes and elements (its checks of the sizes
    and of the element count, before anything is allocated, are the deck's); the deck adds
    its bound on lengths."""
    w = line.words
    size = [read_float(v, f"the box length L{a}", le=MAX_LENGTH)
            for v, a in zip(w[1:4], "XYZ", strict=True)]
    counts = [read_int(v, f"the element count N{a}") for v, a in zip(w[4:7], "XYZ", strict=True)]
    try:
        box = HexMesh.box(*size, *counts)
    except ValueError as error:  # MeshError is one
        message = str(error)
        for name in ("lx", "ly", "lz", "nx", "ny", "nz"):  # the deck's names of the numbers
            if message.startswith(name + " "):
                message = name.upper() + message[len(name):]
        raise BadValue(message) from None
    return _RawMesh(box.nodes, box.elements, np.arange(1, box.n_nodes + 1),
                    np.arange(1, box.n_elements + 1), None, {}, f"box {' '.join(w[1:7])}")


def _own_mesh(deck: Deck, lines: list[Line], start: int) -> tuple[int, _RawMesh | None]:
    """The 'nodes N' block at lines[start] and the 'hexahedra M' block after it."""
    blocks = {}
    i = start
    for keyword, width, form in (("nodes", 4, "ID X Y Z"), ("hexahedra", 9, "ID N1 ... N8")):
        if i >= len(lines):
            deck.error(deck.last, f"the file ends where '{keyword} COUNT' was expected")
            return i, None
        head = lines[i]
        if head.key != keyword:
            deck.error(head.number, f"expected '{keyword} COUNT', got {show(head.text)}")
            return i, None
        try:
            check_arity(head, f"{keyword} COUNT", 1)
            count = read_int(head.words[1], f"the number of {keyword}", 1, 8 * MAX_ELEMENTS)
        except BadValue as bad:
            deck.error(head.number, str(bad))
            return i + 1, None
        i += 1
        rows: list[list[str]] = []
        numbers: list[int] = []
        while len(rows) < count and i < len(lines) and lines[i].key not in _MESH_KEYS:
            rows.append(lines[i].words)
            numbers.append(lines[i].number)
            i += 1
        if len(rows) < count:
            where = lines[i].number if i < len(lines) else deck.last
            got = f"'{lines[i].key}'" if i < len(lines) else "the end of the file"
            deck.error(where, f"expected {count} lines '{form}' after line {head.number}, got "
                       f"{len(rows)} before {got}")
            return i, None
        bad = [k for k, r in enumerate(rows) if len(r) != width]
        if bad:
            for k in bad[:_MAX_REPORTED]:
                deck.error(numbers[k], f"expected '{form}' ({width} numbers), got "
                           f"{show(' '.join(rows[k]))}")
            return i, None
        blocks[keyword] = (rows, np.array(numbers))
    return i, _own_arrays(deck, blocks)


_MESH_KEYS = ("normal", "scale", "origin", "nodes", "hexahedra", "box", "file")


def _own_arrays(deck: Deck, blocks: dict) -> _RawMesh | None:
    (node_rows, node_lines), (elem_rows, elem_lines) = blocks["nodes"], blocks["hexahedra"]
    ok = True

    def numbers(rows: list[list[str]], lines: NDArray, kind: type, what: str) -> NDArray | None:
        """The rows as an array; on a bad word, an error at its line and None."""
        pattern = NUMBER_PATTERN if kind is float else INT_PATTERN
        if kind is float and all(pattern.fullmatch(word) for row in rows for word in row):
            return np.array(rows, dtype=float)  # non-finite values are refused below
        for row, number in zip(rows, lines, strict=True):
            for word in row:
                try:
                    if not pattern.fullmatch(word):
                        raise ValueError(word)
                    value = float(word) if kind is float else int(word)
                except ValueError:
                    deck.error(int(number), f"expected {what}, got {show(' '.join(row))}")
                    return None
                if kind is not float and abs(value) > MAX_ID:
                    deck.error(int(number), f"{word} is out of range: ids are at most {MAX_ID}")
                    return None
        return np.array(rows, dtype=float if kind is float else np.int64)

    node_ids = numbers([r[:1] for r in node_rows], node_lines, int, "an integer node id")
    coords = numbers([r[1:] for r in node_rows], node_lines, float, "numbers X Y Z")
    elem = numbers(elem_rows, elem_lines, int, "integers ID N1 ... N8")
    if node_ids is None or coords is None or elem is None:
        return None
    node_ids = node_ids[:, 0]
    with np.errstate(invalid="ignore"):
        finite = (np.abs(coords) <= MAX_LENGTH).all(axis=1)
    for k in np.flatnonzero(~finite)[:_MAX_REPORTED]:
        deck.error(int(node_lines[k]), f"expected finite coordinates X Y Z within +-{MAX_LENGTH:g}"
                   " mm, got " + show(" ".join(node_rows[k][1:])))
    ok &= bool(finite.all())
    for ids, lines, what in ((node_ids, node_lines, "node"), (elem[:, 0], elem_lines,
                                                              "element")):
        if (ids < 1).any():
            k = int(np.argmax(ids < 1))
            deck.error(int(lines[k]), f"{what} ids must be >= 1, got {ids[k]}")
            ok = False
        order = np.argsort(ids, kind="stable")
        dup = np.flatnonzero(ids[order][1:] == ids[order][:-1])
        for d in dup[:_MAX_REPORTED]:
            first, again = order[d], order[d + 1]
            deck.error(int(lines[again]), f"{what} {ids[again]} defined twice (first at line "
                       f"{lines[first]})")
            ok = False
    if not ok:
        return None
    if len(elem) > MAX_ELEMENTS:
        deck.error(int(elem_lines[0]), f"{len(elem)} elements: at most {MAX_ELEMENTS}")
        return None
    order = np.argsort(node_ids)
    sorted_ids = node_ids[order]
    refs = elem[:, 1:]
    pos = np.clip(np.searchsorted(sorted_ids, refs), 0, len(sorted_ids) - 1)
    known = sorted_ids[pos] == refs
    for k in np.flatnonzero(~known.all(axis=1))[:_MAX_REPORTED]:
        missing = refs[k][~known[k]][0]
        deck.error(int(elem_lines[k]), f"element {elem[k, 0]} refers to node {missing}, which "
                   "is not in the 'nodes' block")
    if not known.all():
        return None
    return _RawMesh(coords, order[pos], node_ids, elem[:, 0], elem_lines, {}, "mesh.dat",
                    node_lines)


def _mesh_file(deck: Deck, line: Line) -> _RawMesh:
    path = Path(line.words[1])
    if not path.is_absolute():
        path = deck.path.parent / path
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise BadValue(f"expected a mesh file ending in {' or '.join(MESH_SUFFIXES)} (Abaqus input "
                   f"or Gmsh), got {show(line.words[1])}")
    if not path.exists():
        raise BadValue(f"mesh file {path} not found")
    if suffix == ".inp":
        return _inp_file(path)
    # meshio loses the lines and takes what does not fit its counts: the file is checked
    # entry by entry first, each defect named at its line.
    try:
        check_gmsh(path, read_input_file(path, "a mesh file", MESH_LIMIT), hexahedra=True)
    except (InputFileError, GmshFileError) as error:
        raise BadValue(f"mesh file {error}") from None
    except OSError as error:
        raise BadValue(f"cannot read mesh file {path}: {error.strerror or error}") from None
    try:
        import meshio

        data = meshio.read(path)
    except Exception as error:  # meshio raises many types for a bad file
        raise BadValue(f"mesh file {path}: meshio cannot read it ({type(error).__name__}: "
                       f"{error}): expected a Gmsh file of format 2.2 or 4.1 "
                       "(docs/input-format.md)") from None
    solids = {"tetra", "hexahedron", "wedge", "pyramid"}
    other = {}
    hexes = []
    for block in data.cells:
        if block.type == "hexahedron":
            hexes.append(np.asarray(block.data, dtype=np.int64))
        elif block.type.rstrip("0123456789") in solids:
            other[block.type] = other.get(block.type, 0) + len(block.data)
    if other:
        found = ", ".join(f"{n} {t}" for t, n in sorted(other.items()))
        raise BadValue(f"mesh file {path.name} holds {found} cells: only 8-node hexahedra are "
                   "accepted")
    if not hexes:
        raise BadValue(f"mesh file {path.name} holds no hexahedra")
    elements = np.concatenate(hexes)
    if len(elements) > MAX_ELEMENTS:
        raise BadValue(f"mesh file {path.name} has {len(elements)} elements: at most "
                       f"{MAX_ELEMENTS}")
    points = np.asarray(data.points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise BadValue(f"mesh file {path.name} is not three-dimensional")
    if elements.size and (elements.min() < 0 or elements.max() >= len(points)):
        raise BadValue(f"mesh file {path.name} has elements with node indices out of range")
    # Nodes outside the hexahedra (geometry points, lower-dimensional cells) are dropped.
    used = np.unique(elements)
    renumber = np.full(len(points), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    nodesets = {}
    for name, indices in _file_nodesets(data).items():
        kept = renumber[np.asarray(indices, dtype=np.int64)]
        nodesets[name] = kept[kept >= 0]
    return _RawMesh(points[used], renumber[elements], used + 1,
                    np.arange(1, len(elements) + 1), None, nodesets, path.name)


#: Abaqus element types of 8-node hexahedra.
_INP_HEXAHEDRA = ("C3D8", "C3D8H", "C3D8I", "C3D8IH", "C3D8R", "C3D8RH")


def _inp_file(path: Path) -> _RawMesh:
    """An Abaqus input file as the blank's mesh, read by ddpy's .inp reader (the one of
    ``ddpy convert``, :mod:`ddpy.io.inp_mesh`): its hexahedra with their Abaqus node and
    element ids, its node sets (names as bc.dat's, :func:`ddpy.io.inp_mesh.ddpy_name`);
    nodes outside the hexahedra dropped, other solid elements refused at their line."""
    try:
        check_input_file(path, "a mesh file", MESH_LIMIT)
        mesh = read_inp_mesh(path)
        hexes = []
        for ident, (kind, nodes, line) in mesh.elements.items():
            if kind.startswith("C3D") and kind not in _INP_HEXAHEDRA:
                raise DeckError(f"element {ident} is a {kind}: the blank takes 8-node "
                                f"hexahedra ({', '.join(_INP_HEXAHEDRA)})", line.path,
                                line.number)
            if kind in _INP_HEXAHEDRA:
                for n in nodes:
                    if n not in mesh.nodes:
                        raise DeckError(f"element {ident} refers to node {n}, which no *NODE "
                                        "defines", line.path, line.number)
                hexes.append((ident, nodes))
    except (InputFileError, DeckError) as error:
        raise BadValue(f"mesh file {error}") from None
    except OSError as error:
        raise BadValue(f"cannot read mesh file {path}: {error.strerror or error}") from None
    if not hexes:
        raise BadValue(f"mesh file {path.name} holds no hexahedra")
    if len(hexes) > MAX_ELEMENTS:
        raise BadValue(f"mesh file {path.name} has {len(hexes)} elements: at most "
                       f"{MAX_ELEMENTS}")
    node_ids = np.unique([n for _, nodes in hexes for n in nodes]).astype(np.int64)
    connectivity = np.searchsorted(node_ids, np.array([nodes for _, nodes in hexes]))
    nodesets = {}
    for name in mesh.nsets:
        ids = np.array(mesh.node_set(name, mesh.nsets[name][0][1]) if mesh.nsets[name] else [],
                       dtype=np.int64)
        ids = ids[np.isin(ids, node_ids)]
        nodesets[ddpy_name(name, "set")] = np.unique(np.searchsorted(node_ids, ids))
    coords = np.array([mesh.nodes[int(n)][0] for n in node_ids], dtype=float)
    return _RawMesh(coords, connectivity.astype(np.int64), node_ids,
                    np.array([e for e, _ in hexes], dtype=np.int64), None, nodesets, path.name)


def _file_nodesets(data: Any) -> dict[str, NDArray[np.int64]]:
    """Node sets of a mesh file: Abaqus NSETs, and the nodes of each Gmsh physical group."""
    sets: dict[str, NDArray[np.int64]] = {}

    def clean(name: str) -> str:
        text = re.sub(r"[^A-Za-z0-9_.\-]", "_", str(name))[:64]
        return text if text[:1].isalpha() else f"set_{text}"[:64]

    for name, indices in getattr(data, "point_sets", {}).items():
        sets[clean(name)] = np.asarray(indices, dtype=np.int64).ravel()
    physical = getattr(data, "cell_data", {}).get("gmsh:physical")
    if physical is not None:
        for name, (tag, _dim) in getattr(data, "field_data", {}).items():
            members = [np.asarray(b.data)[np.asarray(t) == tag].ravel()
                       for b, t in zip(data.cells, physical, strict=False)
                       if len(t) == len(b.data)]
            nodes = np.unique(np.concatenate(members)) if members else np.zeros(0, np.int64)
            if nodes.size:
                sets[clean(name)] = nodes
    return sets


def _report_bad_elements(deck: Deck, raw: _RawMesh, error: MeshError) -> None:
    """The bad elements HexMesh found, each at its line of the deck (the first few, then how
    many more); a mesh file's at no line, named by the file."""
    bad = error.bad_elements
    if not bad:  # not an element's fault
        deck.error(None, f"{raw.source}: {error}")
        return

    def report(k: int, message: str) -> None:
        if raw.element_lines is not None:
            deck.error(int(raw.element_lines[bad[k].index]), message)
        else:
            deck.error(None, f"{raw.source}: {message}")

    for k in range(min(len(bad), _MAX_REPORTED)):
        report(k, bad[k].message)
    if len(bad) > _MAX_REPORTED:
        report(_MAX_REPORTED, f"... and {len(bad) - _MAX_REPORTED} more bad elements "
               f"({len(bad)} in all)")


def _no_free_nodes(deck: Deck, raw: _RawMesh) -> bool:
    """Whether every node of the own 'nodes' block belongs to an element; else an error at
    the line of each free one (the first few). Mesh files drop their free nodes."""
    if raw.node_lines is None:
        return True
    used = np.zeros(len(raw.node_ids), bool)
    used[raw.elements.ravel()] = True
    for k in np.flatnonzero(~used)[:_MAX_REPORTED]:
        deck.error(int(raw.node_lines[k]), f"node {raw.node_ids[k]} belongs to no element: "
                   "remove it (a free node makes the stiffness singular)")
    return bool(used.all())
