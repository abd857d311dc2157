"""Checks of array arguments before they reach the core (clear errors, never a crash), and
the lines of an input file as its reader numbers them."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


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
