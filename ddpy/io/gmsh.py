"""Gmsh ``.msh`` files checked entry by entry before meshio reads them: the blank's mesh file
(:mod:`ddpy.io.decks.mesh`) and tool meshes (:mod:`ddpy.cad.surface_mesh`).

meshio reads as many entries as a count says and ignores the rest, takes any word Python's
``int`` takes (``1_0`` is 10), wires a node tag 0 to the file's last node, reads an element
whose type was changed with the node count of its new type (a hexahedron made a quadrangle
is dropped from a volume mesh) and fails on an unknown type or a missing node with a bare
``KeyError`` or ``IndexError``. :func:`check_gmsh` refuses each of these first, naming the
file and the line (ASCII files) or the entry (binary files); formats 2.x and 4.1.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy._validate import NUMBER_PATTERN

__all__ = ["GMSH_TYPES", "HEXAHEDRON", "MAX_NODE_TAG", "GmshFileError", "check_gmsh"]

#: Gmsh element types meshio reads: (meshio's name, node count).
GMSH_TYPES: dict[int, tuple[str, int]] = {
    1: ("line", 2), 2: ("triangle", 3), 3: ("quad", 4), 4: ("tetra", 4), 5: ("hexahedron", 8),
    6: ("wedge", 6), 7: ("pyramid", 5), 8: ("line3", 3), 9: ("triangle6", 6), 10: ("quad9", 9),
    11: ("tetra10", 10), 12: ("hexahedron27", 27), 13: ("wedge18", 18), 14: ("pyramid14", 14),
    15: ("vertex", 1), 16: ("quad8", 8), 17: ("hexahedron20", 20), 18: ("wedge15", 15),
    19: ("pyramid13", 13), 21: ("triangle10", 10), 23: ("triangle15", 15),
    25: ("triangle21", 21), 26: ("line4", 4), 27: ("line5", 5), 28: ("line6", 6),
    29: ("tetra20", 20), 30: ("tetra35", 35), 31: ("tetra56", 56), 36: ("quad16", 16),
    37: ("quad25", 25), 38: ("quad36", 36), 42: ("triangle28", 28), 43: ("triangle36", 36),
    44: ("triangle45", 45), 45: ("triangle55", 55), 46: ("triangle66", 66), 47: ("quad49", 49),
    48: ("quad64", 64), 49: ("quad81", 81), 50: ("quad100", 100), 51: ("quad121", 121),
    62: ("line7", 7), 63: ("line8", 8), 64: ("line9", 9), 65: ("line10", 10),
    66: ("line11", 11), 71: ("tetra84", 84), 72: ("tetra120", 120), 73: ("tetra165", 165),
    74: ("tetra220", 220), 75: ("tetra286", 286), 90: ("wedge40", 40), 91: ("wedge75", 75),
    92: ("hexahedron64", 64), 93: ("hexahedron125", 125), 94: ("hexahedron216", 216),
    95: ("hexahedron343", 343), 96: ("hexahedron512", 512), 97: ("hexahedron729", 729),
    98: ("hexahedron1000", 1000), 106: ("wedge126", 126), 107: ("wedge196", 196),
    108: ("wedge288", 288), 109: ("wedge405", 405), 110: ("wedge550", 550),
}
#: The blank's element: the 8-node hexahedron.
HEXAHEDRON = 5
#: Elements of lower dimension a mesh of 8-node hexahedra may hold: point, line, triangle,
#: quadrangle.
_FIRST_ORDER = (15, 1, 2, 3)
#: Largest node tag: meshio holds a table as long as the largest tag (8 bytes each).
MAX_NODE_TAG = 100_000_000
#: Largest element tag.
MAX_ELEMENT_TAG = 2**31 - 1

_NODE_COUNT = np.full(max(GMSH_TYPES) + 1, -1, dtype=np.int64)
_DIMENSION = np.full(max(GMSH_TYPES) + 1, -1, dtype=np.int64)
for _type, (_name, _count) in GMSH_TYPES.items():
    _NODE_COUNT[_type] = _count
    _DIMENSION[_type] = {"vertex": 0, "line": 1, "triangle": 2, "quad": 2}.get(
        _name.rstrip("0123456789"), 3)

# Byte classes of the ASCII sections, in order: what may be in a number's words.
_BLANK, _NEWLINE, _DIGIT, _SIGN, _OTHER, _BAD = range(6)
_INTEGER_BYTES = np.full(256, _BAD, dtype=np.uint8)
_INTEGER_BYTES[[32, 9, 13]] = _BLANK
_INTEGER_BYTES[10] = _NEWLINE
_INTEGER_BYTES[48:58] = _DIGIT
_INTEGER_BYTES[[43, 45]] = _SIGN
_NUMBER_BYTES = _INTEGER_BYTES.copy()
_NUMBER_BYTES[list(b".eEinfa")] = _OTHER  # the rest of the grammar: numpy's parse tells
#: An integer word of a Gmsh file (at most 15 digits: exact in int64 and float64).
_INTEGER = re.compile(r"[+-]?[0-9]{1,15}", re.ASCII)


class GmshFileError(ValueError):
    """A Gmsh file refused by :func:`check_gmsh`: the message starts with ``file:line:`` (an
    ASCII file) or ``file:`` and names the entry (a binary file)."""


def describe(gmsh_type: int) -> str:
    """'type 3 (4-node quad)' of a type of GMSH_TYPES."""
    name, count = GMSH_TYPES[gmsh_type]
    return f"type {gmsh_type} ({count}-node {name.rstrip('0123456789')})"


@dataclass
class _Places:
    """Where the entries of a section are: their lines (ASCII) or their order (binary)."""

    path: Path
    section: str
    lines: NDArray[np.int64] | None

    def label(self, k: int) -> str:
        """'line 12' or '$Elements entry 3'."""
        return f"line {self.lines[k]}" if self.lines is not None else \
            f"{self.section} entry {k + 1}"

    def place(self, k: int) -> str:
        """'file:12' or 'file: $Elements entry 3'."""
        return f"{self.path}:{self.lines[k]}" if self.lines is not None else \
            f"{self.path}: {self.section} entry {k + 1}"


@dataclass
class _Nodes:
    tags: NDArray[np.int64]
    coordinates: NDArray[np.float64]
    where: _Places


@dataclass
class _Elements:
    ids: NDArray[np.int64]
    types: NDArray[np.int64]
    #: The elementary entity of each element where its dimension is not given (format 2;
    #: -1: unknown or not needed): the blank's check of elements among its hexahedra.
    entities: NDArray[np.int64]
    groups: list[tuple[NDArray[np.int64], NDArray[np.int64]]]  # (entries, their node tags)
    where: _Places


def check_gmsh(path: str | Path, data: bytes, hexahedra: bool = False) -> None:
    """Check the bytes of Gmsh file ``path``; raise :class:`GmshFileError` at the first
    defect. With ``hexahedra`` (the blank) every 3-D element must be an 8-node hexahedron,
    every other one first-order, and none of them among the hexahedra of its entity."""
    path = Path(path)
    head = data[:4096].lstrip()
    if not head.startswith(b"$MeshFormat"):
        raise GmshFileError(f"{path}:1: expected '$MeshFormat' (a Gmsh file starts with it)")
    start = data.index(b"$MeshFormat")
    end = data.find(b"\n", start)
    second = data.find(b"\n", end + 1)
    words = data[end + 1:second if second >= 0 else len(data)].decode("latin-1").split()
    line = data[:end + 1].count(b"\n") + 1
    if len(words) != 3 or words[1] not in ("0", "1") or words[2] not in ("4", "8"):
        raise GmshFileError(f"{path}:{line}: expected 'VERSION FILE-TYPE DATA-SIZE' (e.g. "
                            f"'4.1 0 8' or '2.2 0 8'), got '{' '.join(words)[:60]}'")
    version, binary = words[0], words[1] == "1"
    if version not in ("2", "2.0", "2.1", "2.2", "4.1"):
        raise GmshFileError(f"{path}:{line}: Gmsh format {version[:20]} is not read: expected "
                            "2.2 or 4.1 (Gmsh: File > Export, or -format msh22 / msh41)")
    v2 = version.startswith("2")
    if binary:
        nodes, elements = _Binary(path, data, second + 1, v2, int(words[2])).read()
    else:
        sections = _ascii_sections(path, data.decode("latin-1"))
        nodes = (_nodes_v2 if v2 else _nodes_v41)(path, sections["Nodes"][1])
        elements = (_elements_v2 if v2 else _elements_v41)(path, sections["Elements"][1])
    _check_tags(nodes.tags, nodes.where, "node", MAX_NODE_TAG)
    _check_tags(elements.ids, elements.where, "element", MAX_ELEMENT_TAG)
    finite = np.isfinite(nodes.coordinates).all(axis=1)
    if not finite.all():
        k = int(np.argmin(finite))
        raise GmshFileError(f"{nodes.where.place(k)}: node {nodes.tags[k]} has a coordinate "
                            "that is not a finite number")
    _check_references(nodes, elements)
    if hexahedra:
        _check_hexahedra(elements)


# -------------------------------------------------------------------------------- ASCII


@dataclass
class _Lines:
    """Consecutive entry lines of a section (blank lines dropped) and their line numbers."""

    path: Path
    texts: list[str]
    numbers: NDArray[np.int64]

    def __len__(self) -> int:
        return len(self.texts)

    def part(self, start: int, stop: int) -> _Lines:
        return _Lines(self.path, self.texts[start:stop], self.numbers[start:stop])

    def fail(self, k: int, message: str) -> GmshFileError:
        return GmshFileError(f"{self.path}:{self.numbers[k]}: {message}")

    def expected(self, k: int, form: str) -> GmshFileError:
        return self.fail(k, f"expected {form}, got '{self.texts[k].strip()[:60]}'")

    def places(self, section: str) -> _Places:
        return _Places(self.path, section, self.numbers)


_MARKER = re.compile(r"^[ \t]*\$(\w+)[ \t\r]*$", re.M)


def _ascii_sections(path: Path, text: str) -> dict[str, tuple[int, _Lines]]:
    """The $Nodes and $Elements sections: (the line of the section's name, its lines)."""
    markers = []
    line, at = 1, 0
    for match in _MARKER.finditer(text):
        line += text.count("\n", at, match.start())
        at = match.start()
        markers.append((match.group(1), line, match.end()))
    sections: dict[str, tuple[int, _Lines]] = {}
    i = 0
    while i < len(markers):
        name, opened, body_start = markers[i]
        close = next((j for j in range(i + 1, len(markers)) if markers[j][0] == f"End{name}"),
                     None)
        if name not in ("Nodes", "Elements"):
            i = i + 1 if close is None else close + 1
            continue
        if name in sections:
            raise GmshFileError(f"{path}:{opened}: a second ${name} section (the first at line "
                                f"{sections[name][0]})")
        inner = next((j for j in range(i + 1, len(markers))
                      if not markers[j][0].startswith("End")), None)
        if close is None or (inner is not None and inner < close):
            raise GmshFileError(f"{path}:{opened}: the ${name} section has no $End{name}" + (
                f" before ${markers[inner][0]} at line {markers[inner][1]}" if inner is not None
                else ""))
        body_end = text.rfind("\n", 0, text.rfind("$", 0, markers[close][2]))
        body = text[body_start:body_end]
        texts = body.split("\n")[1:]
        numbers = np.arange(opened + 1, opened + 1 + len(texts), dtype=np.int64)
        if "\n\n" in body or "\n\r" in body or re.search(r"\n[ \t]", body) or \
                (texts and not texts[-1].strip()):  # blank lines? meshio skips some of them
            keep = [k for k, t in enumerate(texts) if t.strip()]
            texts, numbers = [texts[k] for k in keep], numbers[keep]
        if not texts:
            raise GmshFileError(f"{path}:{opened}: the ${name} section is empty: expected its "
                                "count")
        sections[name] = (opened, _Lines(path, texts, numbers))
        i = close + 1
    for name in ("Nodes", "Elements"):
        if name not in sections:
            raise GmshFileError(f"{path}: no ${name} section: expected a Gmsh mesh with nodes "
                                "and elements")
    return sections


def _words(lines: _Lines, integers: bool, form: str
           ) -> tuple[NDArray[np.float64] | NDArray[np.int64], NDArray[np.int64]]:
    """The numbers of the lines, flat, and how many each line holds; every word an integer
    ``[+-]DIGITS`` (at most 15 digits) or, without ``integers``, a number of the decks'
    grammar (NUMBER_PATTERN). Checked on the bytes at once: Python would take a line at a
    time far slower than meshio reads the file."""
    text = "\n".join(lines.texts)
    kind = (_INTEGER_BYTES if integers else _NUMBER_BYTES)[
        np.frombuffer(text.encode("latin-1"), dtype=np.uint8)]
    newlines = np.flatnonzero(kind == _NEWLINE)
    edges = np.diff((kind > _NEWLINE).view(np.int8), prepend=np.int8(0), append=np.int8(0))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    del edges
    line_of = np.searchsorted(newlines, starts)
    counts = np.bincount(line_of, minlength=len(lines)).astype(np.int64)
    bad = kind == _BAD
    if integers:  # a sign only first in a word, before a digit; at most 15 digits
        signs = np.flatnonzero(kind == _SIGN)
        if signs.size:
            first = np.zeros(len(kind), dtype=bool)
            first[starts] = True
            bad[signs[~first[signs]]] = True
            bad[signs[kind[np.minimum(signs + 1, len(kind) - 1)] != _DIGIT]] = True
        long = np.flatnonzero(ends - starts > 16)
        where = [int(line_of[long[0]])] if long.size else []
    else:
        where = []
    if bad.any():
        where.append(int(np.searchsorted(newlines, np.argmax(bad))))
    values = np.zeros(0)
    if not where:
        with warnings.catch_warnings():  # numpy warns or raises where it stops: found below
            warnings.simplefilter("ignore", DeprecationWarning)
            try:
                values = np.fromstring(text, dtype=np.int64 if integers else np.float64,
                                       sep=" ")
            except ValueError:
                values = np.zeros(0)
        if len(values) != len(starts):
            pattern = _INTEGER if integers else NUMBER_PATTERN
            bad_line = next((k for k, t in enumerate(lines.texts)
                             if not all(pattern.fullmatch(w) for w in t.split())), None)
            if bad_line is not None:
                where.append(bad_line)
            else:  # words numpy alone stops at: a word at a time
                values = np.array(text.split(), dtype=np.int64 if integers else np.float64)
    if where:
        raise lines.expected(min(where), form)
    return values, counts


def _counts(lines: _Lines, k: int, words: int, form: str) -> list[int]:
    """Line k: ``words`` integers >= 0 (a count or a block's header)."""
    values = lines.texts[k].split()
    if len(values) != words or not all(_INTEGER.fullmatch(w) and w[0] not in "+-"
                                       for w in values):
        raise lines.expected(k, form)
    return [int(w) for w in values]


def _mismatch(lines: _Lines, name: str, expected: int, found: int) -> GmshFileError:
    return lines.fail(0, f"${name} says {expected} entries, the section holds {found}")


def _rows(lines: _Lines, width: int, form: str, integers: bool) -> NDArray:
    """The lines as rows of ``width`` numbers."""
    values, counts = _words(lines, integers, form)
    wrong = np.flatnonzero(counts != width)
    if wrong.size:
        raise lines.expected(int(wrong[0]), form)
    return values.reshape(-1, width)


def _entries_v2(lines: _Lines, name: str, what: str) -> _Lines:
    """The entry lines of a format-2 section whose first line gives their count."""
    (count,) = _counts(lines, 0, 1, what)
    entries = lines.part(1, len(lines))
    if len(entries) != count:
        raise _mismatch(lines, name, count, len(entries))
    return entries


def _nodes_v2(path: Path, lines: _Lines) -> _Nodes:
    entries = _entries_v2(lines, "Nodes", "the number of nodes")
    form = "'TAG X Y Z' (a node tag >= 1 and 3 numbers)"
    values = _rows(entries, 4, form, integers=False)
    tags = values[:, 0]
    integral = (tags == np.floor(tags)) & (tags < 2**53)
    if not integral.all():
        raise entries.expected(int(np.argmin(integral)), form)
    return _Nodes(tags.astype(np.int64), values[:, 1:], entries.places("$Nodes"))


def _elements_v2(path: Path, lines: _Lines) -> _Elements:
    entries = _entries_v2(lines, "Elements", "the number of elements")
    form = "'TAG TYPE NTAGS TAGS... NODES...' (integers)"
    flat, lengths = _words(entries, True, form)
    short = np.flatnonzero(lengths < 3)
    if short.size:
        raise entries.expected(int(short[0]), form)
    offsets = np.concatenate(([0], np.cumsum(lengths)[:-1]))
    ids, types, ntags = flat[offsets], flat[offsets + 1], flat[offsets + 2]
    known = (types >= 0) & (types < len(_NODE_COUNT))
    counts = np.where(known, _NODE_COUNT[np.where(known, types, 0)], -1)
    wrong = (counts < 0) | (ntags < 0) | (lengths != 3 + ntags + counts)
    if wrong.any():
        k = int(np.argmax(wrong))
        if counts[k] < 0:
            raise entries.fail(k, f"element {ids[k]} has type {types[k]}, not a Gmsh element "
                                  "type (5 is the 8-node hexahedron)")
        if ntags[k] < 0:
            raise entries.fail(k, f"element {ids[k]} gives {ntags[k]} tags")
        raise entries.fail(k, f"element {ids[k]} of {describe(int(types[k]))} with {ntags[k]} "
                              f"tags has 3 + {ntags[k]} + {counts[k]} = "
                              f"{3 + ntags[k] + counts[k]} numbers, the line holds "
                              f"{lengths[k]}: was its type or a node changed?")
    entities = np.where(ntags >= 2, flat[np.minimum(offsets + 4, len(flat) - 1)], -1)
    groups = []
    for n in np.unique(counts):
        rows = np.flatnonzero(counts == n)
        ends = offsets[rows] + lengths[rows]
        groups.append((rows, flat[ends[:, None] - n + np.arange(n)]))
    return _Elements(ids, types, entities, groups, entries.places("$Elements"))


def _nodes_v41(path: Path, lines: _Lines) -> _Nodes:
    blocks, count, _, _ = _counts(lines, 0, 4, "'NUMBLOCKS NUMNODES MINTAG MAXTAG'")
    tags, coordinates, numbers = [], [], []
    row = 1
    for b in range(blocks):
        if row >= len(lines):
            raise lines.fail(0, f"$Nodes says {blocks} blocks, the section holds {b}")
        dim, _, parametric, n = _counts(lines, row, 4, "'DIM ENTITY PARAMETRIC COUNT' (a "
                                        "block of nodes)")
        if row + 1 + 2 * n > len(lines):
            raise lines.fail(row, f"the block says {n} nodes (their tags, then their "
                                  "coordinates), the section ends first")
        tag_lines = lines.part(row + 1, row + 1 + n)
        tags.append(_rows(tag_lines, 1, "a node tag (an integer >= 1)", True)[:, 0])
        width = 3 + (dim if parametric else 0)
        xyz = _rows(lines.part(row + 1 + n, row + 1 + 2 * n), width,
                    f"{width} numbers (the node's coordinates)", False)
        finite = np.isfinite(xyz).all(axis=1)
        if not finite.all():
            raise lines.part(row + 1 + n, row + 1 + 2 * n).expected(
                int(np.argmin(finite)), "finite coordinates")
        coordinates.append(xyz[:, :3])
        numbers.append(tag_lines.numbers)  # the tags' lines name the nodes
        row += 1 + 2 * n
    found = sum(len(t) for t in tags)
    if found != count or row != len(lines):
        raise _mismatch(lines, "Nodes", count, found + (len(lines) - row))
    return _Nodes(_join(tags), np.concatenate(coordinates) if coordinates else
                  np.zeros((0, 3)), _Places(path, "$Nodes", _join(numbers)))


def _elements_v41(path: Path, lines: _Lines) -> _Elements:
    blocks, count, _, _ = _counts(lines, 0, 4, "'NUMBLOCKS NUMELEMENTS MINTAG MAXTAG'")
    ids, types, groups, numbers = [], [], [], []
    row, read = 1, 0
    for b in range(blocks):
        if row >= len(lines):
            raise lines.fail(0, f"$Elements says {blocks} blocks, the section holds {b}")
        dim, _, kind, n = _counts(lines, row, 4, "'DIM ENTITY TYPE COUNT' (a block of "
                                  "elements)")
        if kind not in GMSH_TYPES:
            raise lines.fail(row, f"the block has elements of type {kind}, not a Gmsh element "
                                  "type (5 is the 8-node hexahedron)")
        if _DIMENSION[kind] != dim:
            raise lines.fail(row, f"the block of a {dim}-D entity holds elements of "
                                  f"{describe(kind)}, of dimension {_DIMENSION[kind]}: was its "
                                  "type changed?")
        if row + 1 + n > len(lines):
            raise lines.fail(row, f"the block says {n} elements, the section ends first")
        entries = lines.part(row + 1, row + 1 + n)
        width = 1 + GMSH_TYPES[kind][1]
        form = f"'TAG NODES...' ({width} integers) for an element of {describe(kind)}"
        values, counts = _words(entries, True, form)
        wrong = np.flatnonzero(counts != width)
        if wrong.size == n and np.all(counts == counts[0]):  # all of them: the block's type
            raise lines.fail(row, f"the block's elements, of {describe(kind)}, have {width} "
                                  f"integers each, its lines hold {counts[0]}: was the block's "
                                  "type changed?")
        if wrong.size:
            raise entries.expected(int(wrong[0]), form)
        values = values.reshape(-1, width)
        groups.append((np.arange(read, read + n), values[:, 1:]))
        ids.append(values[:, 0])
        types.append(np.full(n, kind, dtype=np.int64))
        numbers.append(entries.numbers)
        row += 1 + n
        read += n
    if read != count or row != len(lines):
        raise _mismatch(lines, "Elements", count, read + (len(lines) - row))
    return _Elements(_join(ids), _join(types), np.full(read, -1, dtype=np.int64), groups,
                     _Places(path, "$Elements", _join(numbers)))


# ------------------------------------------------------------------------------- binary


class _Binary:
    """The $Nodes and $Elements sections of a binary file, read as meshio reads them."""

    def __init__(self, path: Path, data: bytes, position: int, v2: bool, size: int) -> None:
        self.path, self.data, self.v2 = path, data, v2
        self.size_t = np.dtype("u8" if size == 8 else "u4")
        # The file's byte order, by the integer 1 written after the format line.
        one = np.frombuffer(data, np.int32, 1, position) if len(data) >= position + 4 else []
        if len(one) != 1 or one[0] != 1:
            raise GmshFileError(f"{path}: the binary $MeshFormat does not hold the integer 1 "
                                "(written with another byte order?)")
        self.position = position + 4

    def fail(self, message: str) -> GmshFileError:
        return GmshFileError(f"{self.path}: {message}")

    def take(self, dtype: np.dtype | type, count: int, where: str) -> NDArray:
        dtype = np.dtype(dtype)
        if count < 0 or self.position + count * dtype.itemsize > len(self.data):
            raise self.fail(f"the file ends inside {where}")
        values = np.frombuffer(self.data, dtype, count, self.position)
        self.position += count * dtype.itemsize
        return values

    def line(self) -> str:
        end = self.data.find(b"\n", self.position)
        end = len(self.data) if end < 0 else end
        text = self.data[self.position:end].decode("latin-1").strip()
        self.position = end + 1
        return text

    def read(self) -> tuple[_Nodes, _Elements]:
        found: dict[str, object] = {}
        while self.position < len(self.data):
            text = self.line()
            if not text.startswith("$") or text.startswith("$End"):
                continue
            name = text[1:]
            if name in ("Nodes", "Elements"):
                if name in found:
                    raise self.fail(f"a second ${name} section")
                if self.v2:
                    found[name] = self.nodes_v2() if name == "Nodes" else self.elements_v2()
                else:
                    found[name] = self.nodes_v41() if name == "Nodes" else self.elements_v41()
            end = self.data.find(f"$End{name}".encode(), self.position)
            if end < 0:
                raise self.fail(f"the ${name} section has no $End{name}")
            self.position = end
        for name in ("Nodes", "Elements"):
            if name not in found:
                raise self.fail(f"no ${name} section: expected a Gmsh mesh with nodes and "
                                "elements")
        return found["Nodes"], found["Elements"]  # type: ignore[return-value]

    def count(self, what: str) -> int:
        text = self.line()
        if not re.fullmatch(r"[0-9]{1,15}", text):
            raise self.fail(f"expected the number of {what}, got '{text[:60]}'")
        return int(text)

    def places(self, section: str) -> _Places:
        return _Places(self.path, section, None)

    def nodes_v2(self) -> _Nodes:
        count = self.count("nodes")
        record = np.dtype([("tag", np.int32), ("x", np.float64, 3)])
        values = self.take(record, count, "$Nodes")
        return _Nodes(values["tag"].astype(np.int64), values["x"].astype(np.float64),
                      self.places("$Nodes"))

    def elements_v2(self) -> _Elements:
        total = self.count("elements")
        ids, types, entities, groups = [], [], [], []
        read = 0
        while read < total:
            kind, n, ntags = (int(v) for v in self.take(np.int32, 3, "$Elements"))
            if kind not in GMSH_TYPES:
                raise self.fail(f"$Elements entry {read + 1}: a block of elements of type "
                                f"{kind}, not a Gmsh element type (5 is the 8-node hexahedron)")
            if n <= 0 or ntags < 0 or read + n > total:
                raise self.fail(f"$Elements entry {read + 1}: a block header of {n} elements "
                                f"with {ntags} tags, {total - read} elements left of {total}")
            width = 1 + ntags + GMSH_TYPES[kind][1]
            values = self.take(np.int32, n * width, "$Elements").reshape(n, width)
            values = values.astype(np.int64)
            ids.append(values[:, 0])
            types.append(np.full(n, kind, dtype=np.int64))
            entities.append(values[:, 2] if ntags >= 2 else np.full(n, -1, dtype=np.int64))
            groups.append((np.arange(read, read + n), values[:, 1 + ntags:]))
            read += n
        return _Elements(_join(ids), _join(types), _join(entities), groups,
                         self.places("$Elements"))

    def nodes_v41(self) -> _Nodes:
        blocks, count = (int(v) for v in self.take(self.size_t, 4, "$Nodes")[:2])
        tags, coordinates = [], []
        for _ in range(blocks):
            dim, _, parametric = (int(v) for v in self.take(np.int32, 3, "$Nodes"))
            (n,) = (int(v) for v in self.take(self.size_t, 1, "$Nodes"))
            tags.append(self.take(self.size_t, n, "$Nodes").astype(np.int64))
            width = 3 + (dim if parametric else 0)
            coordinates.append(self.take(np.float64, n * width, "$Nodes").reshape(n, width)
                               [:, :3])
        found = sum(len(t) for t in tags)
        if found != count:
            raise self.fail(f"$Nodes says {count} entries, its blocks hold {found}")
        return _Nodes(_join(tags), np.concatenate(coordinates) if coordinates else
                      np.zeros((0, 3)), self.places("$Nodes"))

    def elements_v41(self) -> _Elements:
        blocks, count = (int(v) for v in self.take(self.size_t, 4, "$Elements")[:2])
        ids, types, groups = [], [], []
        read = 0
        for b in range(blocks):
            dim, _, kind = (int(v) for v in self.take(np.int32, 3, "$Elements"))
            (n,) = (int(v) for v in self.take(self.size_t, 1, "$Elements"))
            if kind not in GMSH_TYPES:
                raise self.fail(f"$Elements block {b + 1}: elements of type {kind}, not a Gmsh "
                                "element type (5 is the 8-node hexahedron)")
            if _DIMENSION[kind] != dim:
                raise self.fail(f"$Elements block {b + 1}: the block of a {dim}-D entity holds "
                                f"elements of {describe(kind)}, of dimension "
                                f"{_DIMENSION[kind]}: was its type changed?")
            width = 1 + GMSH_TYPES[kind][1]
            values = self.take(self.size_t, n * width, "$Elements").reshape(n, width)
            values = values.astype(np.int64)  # a tag beyond int64 turns negative: refused
            ids.append(values[:, 0])
            types.append(np.full(n, kind, dtype=np.int64))
            groups.append((np.arange(read, read + n), values[:, 1:]))
            read += n
        if read != count:
            raise self.fail(f"$Elements says {count} entries, its blocks hold {read}")
        return _Elements(_join(ids), _join(types), np.full(read, -1, dtype=np.int64), groups,
                         self.places("$Elements"))


def _join(arrays: list[NDArray[np.int64]]) -> NDArray[np.int64]:
    return np.concatenate(arrays) if arrays else np.zeros(0, np.int64)


# ------------------------------------------------------------------------------- checks


def _check_tags(tags: NDArray[np.int64], where: _Places, what: str, high: int) -> None:
    """Tags within 1..high, each once (the first defect in the file's order)."""
    wrong = (tags < 1) | (tags > high)
    if wrong.any():
        k = int(np.argmax(wrong))
        raise GmshFileError(f"{where.place(k)}: {what} tag {tags[k]} is out of range: expected "
                            f"1 to {high}")
    order = np.argsort(tags, kind="stable")
    repeated = np.flatnonzero(tags[order][1:] == tags[order][:-1])
    if repeated.size:
        again = int(order[repeated + 1].min())
        first = int(order[np.searchsorted(tags[order], tags[again])])
        raise GmshFileError(f"{where.place(again)}: {what} {tags[again]} is defined again "
                            f"(first at {where.label(first)})")


def _check_references(nodes: _Nodes, elements: _Elements) -> None:
    """Every node an element names is in $Nodes (the first offending element in the file)."""
    known_tags = np.sort(nodes.tags)
    worst: tuple[int, int] | None = None  # (entry, the missing node)
    for entries, refs in elements.groups:
        if not refs.size:
            continue
        if known_tags.size:
            at = np.clip(np.searchsorted(known_tags, refs), 0, len(known_tags) - 1)
            known = known_tags[at] == refs
        else:
            known = np.zeros(refs.shape, dtype=bool)
        bad = np.flatnonzero(~known.all(axis=1))
        if bad.size and (worst is None or entries[bad[0]] < worst[0]):
            row = int(bad[0])
            worst = (int(entries[row]), int(refs[row][~known[row]][0]))
    if worst is not None:
        k, node = worst
        hint = " (node tags start at 1)" if node < 1 else ""
        raise GmshFileError(f"{elements.where.place(k)}: element {elements.ids[k]} refers to node "
                            f"{node}, which is not in $Nodes{hint}")


def _check_hexahedra(elements: _Elements) -> None:
    """The blank: 3-D elements are 8-node hexahedra; elements of lower dimension (whose nodes
    may make node sets) are first-order points, lines, triangles and quadrangles, the
    vertices, edges and faces of such hexahedra; and none sits among the hexahedra of its
    entity. A hexahedron whose type was changed fails one of these: meshio would drop it."""
    dims = _DIMENSION[elements.types]
    solid = (dims == 3) & (elements.types != HEXAHEDRON)
    if solid.any():
        k = int(np.argmax(solid))
        raise GmshFileError(f"{elements.where.place(k)}: element {elements.ids[k]} is of "
                            f"{describe(int(elements.types[k]))}: the blank takes 8-node "
                            "hexahedra (type 5) only")
    higher = (dims < 3) & ~np.isin(elements.types, _FIRST_ORDER)
    if higher.any():
        k = int(np.argmax(higher))
        raise GmshFileError(f"{elements.where.place(k)}: element {elements.ids[k]} is of "
                            f"{describe(int(elements.types[k]))}, not a vertex, edge or face "
                            "of 8-node hexahedra (the blank's elements of lower dimension are "
                            "of type 15, 1, 2 or 3): was its type changed?")
    hexes = np.flatnonzero((elements.types == HEXAHEDRON) & (elements.entities >= 0))
    if not hexes.size:
        return
    entities = elements.entities[hexes]
    for entity in np.unique(entities):
        members = hexes[entities == entity]
        low, high = members[0], members[-1]
        inside = np.arange(low, high + 1)
        stray = inside[(elements.types[inside] != HEXAHEDRON)
                       & (elements.entities[inside] == entity)]
        if stray.size:
            k = int(stray[0])
            where = elements.where
            raise GmshFileError(f"{where.place(k)}: element {elements.ids[k]} is of "
                                f"{describe(int(elements.types[k]))} among the hexahedra of "
                                f"entity {entity} (from {where.label(int(low))} to "
                                f"{where.label(int(high))}): the blank takes 8-node hexahedra "
                                "(type 5); was its type changed?")
