"""Tool files: plain-text Bezier, Nagata and facet tool models (units mm).

Two formats share one header (``docs/tool-files.md`` has the full description and examples):

- ``description nagata`` or ``description facets``: a surface mesh; vertices, unit normals and
  faces of 3 or 4 vertices, each face naming its four corner normals (so a vertex on a crease
  carries one normal per CAD face) and the CAD face it was meshed from;
- ``description bezier``: Bezier patches of degree <= 6 by their Bernstein control nets, each
  with the CAD face it was fitted to.

:func:`read_tool` checks every line before it builds the surface and names the file and line of
any error; :func:`write_tool` writes a :class:`ToolModel` back (numbers round-trip exactly).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy._validate import (
    MAX_LENGTH,
    TOOL_LIMIT,
    InputFileError,
    input_lines,
    read_input_file,
)
from ddpy.geometry.surfaces import MAX_BEZIER_DEGREE, BezierSurface, NagataSurface

__all__ = ["DESCRIPTIONS", "ToolFileError", "ToolModel", "read_tool", "write_tool"]

#: Format version written in the first line, ``ddpy-tool 1``.
FORMAT_VERSION = 1
DESCRIPTIONS = ("bezier", "nagata", "facets")
#: Normals in a file may be off unit length by this much (6 written digits); they are
#: normalized on reading. Anything further is refused.
NORMAL_LENGTH_TOL = 1.0e-4
_KEYWORDS = ("vertices", "normals", "faces", "patches", "patch")


class ToolFileError(ValueError):
    """A tool file that cannot be read: the message starts with ``file:line:``."""


@dataclass
class ToolModel:
    """A rigid tool described by one surface, as read from or written to a tool file.

    ``face_tags[p]`` is the CAD face patch ``p`` was built from (0 when unknown); ``source``
    the CAD file (a path; relative paths in a file are relative to that file's folder).
    """

    name: str
    description: str
    surface: BezierSurface | NagataSurface
    face_tags: NDArray[np.int64]
    source: str | None = None

    def __post_init__(self) -> None:
        if self.description not in DESCRIPTIONS:
            raise ValueError(f"description must be one of {DESCRIPTIONS}, got "
                             f"{self.description!r}")
        is_bezier = isinstance(self.surface, BezierSurface)
        if is_bezier != (self.description == "bezier"):
            raise ValueError(f"a {type(self.surface).__name__} cannot have description "
                             f"{self.description!r}")
        if not is_bezier and self.surface.smooth != (self.description == "nagata"):
            raise ValueError(f"description {self.description!r} needs smooth="
                             f"{self.description == 'nagata'} on the Nagata surface")
        if not _is_token(self.name):
            raise ValueError(f"name must be one word without '#', got {self.name!r}")
        self.face_tags = np.asarray(self.face_tags, dtype=np.int64).reshape(-1)
        if self.face_tags.shape != (self.surface.n_patches,):
            raise ValueError(f"face_tags must have one tag per patch ({self.surface.n_patches}),"
                             f" got {self.face_tags.shape[0]}")

    @property
    def n_patches(self) -> int:
        """Number of patches (Bezier patches, Nagata patches or facets)."""
        return self.surface.n_patches

    def facets(self) -> ToolModel:
        """The same mesh as flat facets (every Nagata edge coefficient zero)."""
        if self.description == "facets":
            return self
        if self.description != "nagata":
            raise ValueError("only a Nagata model has a facet version (same mesh, c = 0)")
        s = self.surface
        assert isinstance(s, NagataSurface)
        flat = NagataSurface(s.vertices, s.corner_normals, s.faces, smooth=False)
        return ToolModel(self.name, "facets", flat, self.face_tags.copy(), self.source)


# ----------------------------------------------------------------------------------- writing


def write_tool(path: str | os.PathLike[str], model: ToolModel) -> Path:
    """Write ``model`` to ``path`` in the format of its description; return the path."""
    path = Path(path)
    lines = [f"# ddpy tool file ({model.description}), units mm: see docs/tool-files.md",
             f"ddpy-tool {FORMAT_VERSION}", f"name {model.name}",
             f"description {model.description}", "units mm"]
    if model.source is not None:
        source = str(model.source)
        if os.path.isabs(source):
            try:
                source = os.path.relpath(source, path.resolve().parent)
            except ValueError:  # another drive on Windows
                pass
        lines.append(f"source {source}")
    if isinstance(model.surface, BezierSurface):
        lines += _bezier_lines(model.surface, model.face_tags)
    else:
        lines += _nagata_lines(model.surface, model.face_tags)
    path.write_text("\n".join(lines) + "\n")
    return path


def _num(x: float) -> str:
    """Shortest text that reads back as the same float; -0.0 written as 0."""
    text = repr(float(x))
    return "0" if text in ("0.0", "-0.0") else text.removesuffix(".0")


def _row(values: NDArray[np.float64]) -> str:
    return " ".join(_num(v) for v in values)


def _bezier_lines(surface: BezierSurface, tags: NDArray[np.int64]) -> list[str]:
    lines = [f"patches {surface.n_patches}",
             "# patch <n> <m> face <CAD face>, then the (n+1)(m+1) control points P_ij:",
             "# i = 0..n along u, j = 0..m along v, j varying fastest"]
    for p in range(surface.n_patches):
        n, m = (int(d) for d in surface.degrees[p])
        net = surface.control[p, : m + 1, : n + 1].transpose(1, 0, 2)
        lines.append(f"patch {n} {m} face {int(tags[p])}")
        lines += [_row(point) for point in net.reshape(-1, 3)]
    return lines


def _nagata_lines(surface: NagataSurface, tags: NDArray[np.int64]) -> list[str]:
    faces = surface.faces
    corners = np.where(faces < 0, faces[:, :1], faces)
    # One normal per distinct (vertex, normal) pair, in order of first use: a crease vertex
    # keeps one normal per CAD face.
    keys = np.column_stack([corners.ravel().astype(np.float64),
                            surface.corner_normals.reshape(-1, 3)])
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    normals = keys[first[order], 1:]
    face_normals = rank[inverse.reshape(-1)].reshape(-1, 4)
    face_normals[surface.is_triangle, 3] = -1
    lines = [f"vertices {len(surface.vertices)}"]
    lines += [_row(x) for x in surface.vertices]
    lines.append(f"normals {len(normals)}")
    lines += [_row(n) for n in normals]
    lines += [f"faces {len(faces)}",
              "# 4 vertices (-1 last for a triangle), 4 corner normals, CAD face;"
              " counter-clockwise seen from the normal side, indices from 0"]
    lines += [" ".join(str(int(i)) for i in (*faces[f], *face_normals[f], tags[f]))
              for f in range(len(faces))]
    return lines


# ----------------------------------------------------------------------------------- reading


class _Lines:
    """The meaningful lines of a file: (line number, words), comments and blanks skipped."""

    def __init__(self, path: Path, text: str) -> None:
        self.path = path
        self._lines: list[tuple[int, list[str], str]] = []
        raw_lines = input_lines(text)
        for number, raw in enumerate(raw_lines, start=1):
            content = raw.split("#", 1)[0].strip()
            if content:
                self._lines.append((number, content.split(), content))
        self._next = 0
        self.last_line = len(raw_lines)

    def error(self, line: int, message: str) -> ToolFileError:
        return ToolFileError(f"{self.path}:{line}: {message}")

    def peek(self) -> tuple[int, list[str], str] | None:
        return self._lines[self._next] if self._next < len(self._lines) else None

    def take(self, what: str) -> tuple[int, list[str], str]:
        line = self.peek()
        if line is None:
            raise self.error(self.last_line, f"the file ends where {what} was expected")
        self._next += 1
        return line

    def block(self, keyword: str) -> tuple[int, int]:
        """The line ``keyword <count>``: (line number, count)."""
        number, words, _ = self.take(f"the line '{keyword} <count>'")
        if words[0] != keyword:
            raise self.error(number, f"expected the line '{keyword} <count>', got '{words[0]}'")
        if len(words) != 2:
            raise self.error(number, f"expected '{keyword} <count>' (one integer), got "
                             f"{len(words) - 1} values")
        count = _int(self, number, words[1], f"the number of {keyword}")
        if count < 1:
            raise self.error(number, f"expected at least one entry in {keyword}, got {count}")
        if count > len(self._lines) - self._next:  # also before allocating for them
            raise self.error(self.last_line, f"the file ends where {keyword} ({count} "
                             "expected) was expected")
        return number, count

    def rows(self, count: int, what: str) -> Iterator[tuple[int, list[str]]]:
        for i in range(count):
            number, words, _ = self.take(f"{what} ({count} expected)")
            if words[0] in _KEYWORDS:
                raise self.error(number, f"expected {count} {what}, got {i} before "
                                 f"'{words[0]}'")
            yield number, words


def _int(lines: _Lines, number: int, word: str, what: str) -> int:
    try:
        return int(word)
    except ValueError:
        raise lines.error(number, f"expected an integer for {what}, got '{word}'") from None


def _floats(lines: _Lines, number: int, words: list[str], what: str) -> list[float]:
    if len(words) != 3:
        raise lines.error(number, f"expected 3 numbers for {what}, got {len(words)}")
    values = []
    for word in words:
        try:
            value = float(word)
        except ValueError:
            raise lines.error(number, f"expected a number in {what}, got '{word}'") from None
        if not math.isfinite(value):
            raise lines.error(number, f"expected a finite number in {what}, got '{word}'")
        if abs(value) > MAX_LENGTH:  # beyond, squared distances overflow: not a tool in mm
            raise lines.error(number, f"expected a number within +-{MAX_LENGTH:g} in {what}, "
                              f"got '{word}'")
        values.append(value)
    return values


def read_tool(path: str | os.PathLike[str]) -> ToolModel:
    """Read a tool file; raise :class:`ToolFileError` (``file:line: ...``) on any defect."""
    path = Path(path)
    try:
        text = read_input_file(path, "a tool file", TOOL_LIMIT).decode("utf-8")
    except InputFileError as error:
        raise ToolFileError(str(error)) from None
    except UnicodeDecodeError as error:
        raise ToolFileError(f"{path}: not UTF-8 text (byte {error.start}): expected a "
                            "plain-text tool file") from None
    except OSError as error:
        raise ToolFileError(f"{path}: cannot read the tool file: {error.strerror or error}"
                            ) from None
    lines = _Lines(path, text)
    header = _read_header(lines)
    if header["description"] == "bezier":
        surface, tags = _read_bezier(lines)
    else:
        surface, tags = _read_nagata(lines, smooth=header["description"] == "nagata")
    extra = lines.peek()
    if extra is not None:
        raise lines.error(extra[0], f"unexpected '{extra[1][0]}' after the last block: expected"
                          " the end of the file")
    source = header.get("source")
    if source is not None and not os.path.isabs(source):
        source = os.path.normpath(path.parent / source)
    return ToolModel(header["name"], header["description"], surface, tags, source)


def _read_header(lines: _Lines) -> dict[str, str]:
    number, words, _ = lines.take("the first line 'ddpy-tool 1'")
    if words[0] != "ddpy-tool":
        raise lines.error(number, f"expected the first line 'ddpy-tool {FORMAT_VERSION}' (not a "
                          f"ddpy tool file?), got '{words[0]}'")
    if words[1:] != [str(FORMAT_VERSION)]:
        raise lines.error(number, f"expected format version {FORMAT_VERSION} ('ddpy-tool "
                          f"{FORMAT_VERSION}'), got '{' '.join(words[1:])}'")
    header: dict[str, str] = {}
    keys = ("name", "description", "units", "source")
    while (line := lines.peek()) is not None and line[1][0] in keys:
        number, words, content = lines.take("a header line")
        key = words[0]
        if key in header:
            raise lines.error(number, f"'{key}' given twice in the header")
        value = content[len(key):].strip()
        if not value:
            raise lines.error(number, f"expected a value after '{key}'")
        if key in ("name", "description", "units") and len(words) != 2:
            raise lines.error(number, f"expected one word after '{key}', got {len(words) - 1}")
        if key == "description" and value not in DESCRIPTIONS:
            raise lines.error(number, f"expected a description among {', '.join(DESCRIPTIONS)},"
                              f" got '{value}'")
        if key == "units" and value != "mm":
            raise lines.error(number, f"expected 'units mm' (tool files are in mm), got '{value}'")
        header[key] = value
    for key in ("name", "description"):
        if key not in header:
            where = line[0] if line is not None else lines.last_line
            raise lines.error(where, f"the header has no '{key}' line: expected '{key} ...' "
                              "before the first block")
    return header


def _read_bezier(lines: _Lines) -> tuple[BezierSurface, NDArray[np.int64]]:
    _, count = lines.block("patches")
    nets, tags, patch_lines = [], [], []
    for _ in range(count):
        number, words, _ = lines.take(f"a line 'patch <n> <m> face <tag>' ({count} patches)")
        patch_lines.append(number)
        if words[0] != "patch" or len(words) != 5 or words[3] != "face":
            raise lines.error(number, "expected 'patch <n> <m> face <CAD face tag>', got "
                              f"'{' '.join(words)}'")
        n = _int(lines, number, words[1], "the degree n")
        m = _int(lines, number, words[2], "the degree m")
        for degree, which in ((n, "n"), (m, "m")):
            if not 1 <= degree <= MAX_BEZIER_DEGREE:
                raise lines.error(number, f"expected a degree {which} between 1 and "
                                  f"{MAX_BEZIER_DEGREE}, got {degree}")
        tags.append(_int(lines, number, words[4], "the CAD face tag"))
        points = [_floats(lines, k, w, "a control point")
                  for k, w in lines.rows((n + 1) * (m + 1), f"control points of patch {len(nets)}")]
        nets.append(np.array(points).reshape(n + 1, m + 1, 3))
    try:
        surface = BezierSurface(nets)
    except ValueError as error:  # a degenerate patch (BezierSurface checks its tangents)
        match = re.match(r"patch (\d+)", str(error))
        if match is None:
            raise ToolFileError(f"{lines.path}: {error}") from None
        raise lines.error(patch_lines[int(match.group(1))], str(error)) from None
    return surface, np.array(tags, dtype=np.int64)


def _read_nagata(lines: _Lines, smooth: bool) -> tuple[NagataSurface, NDArray[np.int64]]:
    _, n_vertices = lines.block("vertices")
    vertices = np.array([_floats(lines, k, w, "a vertex")
                         for k, w in lines.rows(n_vertices, "vertices")])
    _, n_normals = lines.block("normals")
    normals = np.empty((n_normals, 3))
    for i, (k, w) in enumerate(lines.rows(n_normals, "normals")):
        normal = np.array(_floats(lines, k, w, "a normal"))
        length = float(np.linalg.norm(normal))
        if abs(length - 1.0) > NORMAL_LENGTH_TOL:
            raise lines.error(k, f"expected a unit normal, got one of length {length:.6g}")
        # Normals written by ddpy read back bit for bit; shorter ones are normalized.
        normals[i] = normal if abs(length - 1.0) < 1e-12 else normal / length
    _, n_faces = lines.block("faces")
    faces = np.empty((n_faces, 4), dtype=np.int64)
    face_normals = np.empty((n_faces, 4), dtype=np.int64)
    tags = np.empty(n_faces, dtype=np.int64)
    face_lines = np.empty(n_faces, dtype=np.int64)
    for f, (k, words) in enumerate(lines.rows(n_faces, "faces")):
        if len(words) != 9:
            raise lines.error(k, "expected 9 integers for a face (4 vertex indices, 4 normal "
                              f"indices, CAD face tag), got {len(words)}")
        values = [_int(lines, k, w, "a face") for w in words]
        faces[f], face_normals[f], tags[f] = values[:4], values[4:8], values[8]
        face_lines[f] = k
        _check_face(lines, k, faces[f], face_normals[f], n_vertices, n_normals)
    corner = normals[np.where(face_normals < 0, face_normals[:, :1], face_normals)]
    try:
        surface = NagataSurface(vertices, corner, faces, smooth=smooth)
    except ValueError as error:  # degenerate face or a face ordered against its normals
        match = re.match(r"face (\d+)", str(error))
        if match is None:
            raise ToolFileError(f"{lines.path}: {error}") from None
        raise lines.error(int(face_lines[int(match.group(1))]), str(error)) from None
    return surface, tags


def _check_face(lines: _Lines, number: int, vertices: NDArray[np.int64],
                normals: NDArray[np.int64], n_vertices: int, n_normals: int) -> None:
    triangle = vertices[3] == -1
    if triangle != (normals[3] == -1):
        raise lines.error(number, "expected -1 as the fourth vertex and the fourth normal "
                          "together (a triangle), or neither")
    used = slice(0, 3 if triangle else 4)
    for values, count, what in ((vertices, n_vertices, "vertex"), (normals, n_normals, "normal")):
        bad = [int(i) for i in values[used] if not 0 <= i < count]
        if bad:
            raise lines.error(number, f"expected {what} indices in 0..{count - 1} (-1 only "
                              f"fourth, for a triangle), got {bad[0]}")
    if len(set(vertices[used].tolist())) != len(vertices[used]):
        raise lines.error(number, f"face {vertices.tolist()} repeats a vertex")


def _is_token(text: str) -> bool:
    return bool(text) and len(text.split()) == 1 and "#" not in text
