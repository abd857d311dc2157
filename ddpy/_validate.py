"""Checks of array arguments before they reach the core (clear errors, never a crash), input
files checked before they are read (a regular file within its kind's size limit), and the lines
of an input file as its reader numbers them."""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Largest length a deck may give (mm): displacements, gaps, increments, box sizes; and the
#: largest coordinate of a tool file or tool mesh (beyond, squared distances overflow).
MAX_LENGTH = 1e6
#: The numbers of the decks (docs/input-format.md) and of the files ddpy checks word by word:
#: decimal with an optional exponent, in ASCII digits; float() alone would also take
#: '210_000', full-width digits and 'nan'.
NUMBER_PATTERN = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?|[+-]?(inf|nan)",
                            re.ASCII)
#: Size limits of input files (bytes), checked before reading (docs/input-format.md,
#: docs/tool-files.md, docs/mesh-tools.md). They stop a file that never ends (/dev/zero, a
#: fifo held open) or a wrong file from being read for minutes into memory; each is far
#: above what its kind needs. A deck other than mesh.dat: the shipped ones are a few kB, and
#: 16 MB holds a node set listing two million ids.
DECK_LIMIT = 16 * 2**20
#: mesh.dat and the blank's mesh files: room for the largest mesh a deck accepts (5,000,000
#: hexahedra, about 0.7 GB as an ASCII Gmsh file).
MESH_LIMIT = 2**30
#: Tool files, tool meshes (STL, Abaqus, Gmsh, ...) and CAD files: a tool of several million
#: faces is a few hundred MB.
TOOL_LIMIT = 2**30


class InputFileError(ValueError):
    """An input file refused before reading: not a regular file, larger than its limit, or
    unreadable. ``reason`` is the message without the path."""

    def __init__(self, path: str | os.PathLike[str], reason: str) -> None:
        super().__init__(f"{path}: {reason}")
        self.path = Path(path)
        self.reason = reason


def _kind_of(mode: int) -> str:
    for test, kind in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a fifo (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return kind
    return "not a regular file"


def _size_text(size: float) -> str:
    for unit in ("bytes", "kB", "MB", "GB"):
        if size < 1024 or unit == "GB":
            return f"{size:.0f} {unit}" if unit == "bytes" else f"{size:.3g} {unit}"
        size /= 1024
    raise AssertionError  # not reached


def check_input_file(path: str | os.PathLike[str], what: str, limit: int) -> int:
    """The size of input file ``path`` (``what``: 'a deck', 'a tool file', ...) after checking,
    with os.stat and before anything reads it, that it is a regular file (a symbolic link
    counts by its target) of at most ``limit`` bytes; else :class:`InputFileError`.
    FileNotFoundError when it does not exist."""
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise
    except OSError as error:
        raise InputFileError(path, f"cannot read {what}: {error.strerror or error}") \
            from None
    if not stat.S_ISREG(info.st_mode):
        kind = _kind_of(info.st_mode)
        target = os.path.realpath(path) if os.path.islink(path) else None
        shown = f"a link to {target}, {kind}" if target else kind
        raise InputFileError(path, f"{shown}: expected a regular file as {what}")
    if info.st_size > limit:
        raise InputFileError(path, f"{_size_text(info.st_size)}: larger than the "
                             f"{_size_text(limit)} limit for {what}")
    return int(info.st_size)


def read_input_file(path: str | os.PathLike[str], what: str, limit: int) -> bytes:
    """The bytes of input file ``path``, checked first by :func:`check_input_file`; the file
    is opened without blocking and checked again on the open file (it may have been replaced
    meanwhile), and never read beyond ``limit`` bytes."""
    check_input_file(path, what, limit)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    except FileNotFoundError:
        raise
    except OSError as error:
        raise InputFileError(path, f"cannot read {what}: {error.strerror or error}") \
            from None
    with os.fdopen(fd, "rb") as handle:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise InputFileError(path, f"{_kind_of(info.st_mode)}: expected a regular file "
                                 f"as {what}")
        data = handle.read(limit + 1)
    if len(data) > limit:
        raise InputFileError(path, f"larger than the {_size_text(limit)} limit for {what}")
    return data


def float_array(value: ArrayLike, name: str, shape: tuple[int | None, ...]) -> NDArray[np.float64]:
    """``value`` as a C-contiguous float64 array of ``shape`` (None: any length), all finite."""
    array = np.asarray(value)
    if array.dtype == object or not (
        np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)
    ):
        raise TypeError(f"{name} must be an array of real numbers, got dtype {array.dtype}")
    check_shape(array, name, shape)
    array = np.ascontiguousarray(array, dtype=np.float64)
    if not np.all(np.isfinite(array)):
        bad = np.argwhere(~np.isfinite(array))[0]
        raise ValueError(f"{name} has a non-finite value at index {tuple(int(i) for i in bad)}")
    return array


def int_array(value: ArrayLike, name: str, shape: tuple[int | None, ...]) -> NDArray[np.int32]:
    """``value`` as a C-contiguous int32 array of ``shape``; floats are refused."""
    array = np.asarray(value)
    if array.size == 0 and array.dtype == np.float64:
        array = array.astype(np.int64)  # an empty list arrives as float64
    if not np.issubdtype(array.dtype, np.integer):
        raise TypeError(f"{name} must be an array of integers, got dtype {array.dtype}")
    check_shape(array, name, shape)
    info = np.iinfo(np.int32)
    if array.size and (array.min() < info.min or array.max() > info.max):
        raise ValueError(f"{name} has values beyond the 32-bit integer range")
    return np.ascontiguousarray(array, dtype=np.int32)


def check_shape(array: np.ndarray, name: str, shape: tuple[int | None, ...]) -> None:
    """Raise ValueError unless ``array`` has ``shape`` (None matches any length)."""
    expected = "(" + ", ".join("k" if s is None else str(s) for s in shape) + ")"
    if array.ndim != len(shape) or any(
        s is not None and s != n for s, n in zip(shape, array.shape, strict=True)
    ):
        raise ValueError(f"{name} must have shape {expected}, got {array.shape}")


def input_lines(text: str) -> list[str]:
    """The lines of a deck or tool file. Only ASCII line ends end a line: str.splitlines also
    splits at form feeds and Unicode separators, so a comment holding one would turn the rest
    into live text and shift every later line number. A UTF-8 byte order mark is not
    content."""
    lines = text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n").split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    return lines
