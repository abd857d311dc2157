"""The line reader shared by the decks and their value grammar: comments and blank lines
dropped, keywords and words split, numbers, integers, names, choices, vectors and
``KEY VALUE`` pairs checked, each defect worded ``expected ..., got ...`` with its line.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ddpy._validate import MAX_LENGTH as MAX_LENGTH  # the decks' readers take it from here
from ddpy._validate import NUMBER_PATTERN, input_lines
from ddpy.io.case import DeckError

NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_.\-]{0,63}")
INT_PATTERN = re.compile(r"[+-]?[0-9]+")


class BadValue(Exception):
    """A defect in the line being read; the deck loop records it with the line number."""


@dataclass
class Line:
    number: int
    words: list[str]
    text: str

    @property
    def key(self) -> str:
        return self.words[0]


class Deck:
    """The meaningful lines of one deck ('#' starts a comment), its errors and warnings."""

    def __init__(self, path: Path, text: str) -> None:
        self.path = path
        self.lines: list[Line] = []
        self.errors: list[DeckError] = []
        self.warnings: list[str] = []
        raw_lines = input_lines(text)
        self.last = len(raw_lines)
        for number, raw in enumerate(raw_lines, start=1):
            content = raw.split("#", 1)[0].strip()
            if content:
                self.lines.append(Line(number, content.split(), content))

    def where(self, line: int | None) -> str:
        return f"{self.path}:{line}" if line is not None else str(self.path)

    def error(self, line: int | None, message: str) -> None:
        self.errors.append(DeckError(message, self.path, line))

    def warn(self, line: int | None, message: str) -> None:
        self.warnings.append(f"{self.where(line)}: {message}")


def guard(deck: Deck, line: Line | int | None, action: Callable[[], Any]) -> Any:
    """Run ``action``; record a BadValue it raises at ``line`` and return None."""
    try:
        return action()
    except BadValue as bad:
        deck.error(line.number if isinstance(line, Line) else line, str(bad))
        return None


# ------------------------------------------------------------------------- words and values


def show(text: str, limit: int = 60) -> str:
    text = text if len(text) <= limit else text[: limit - 3] + "..."
    return f"'{text}'"


def check_arity(line: Line, form: str, low: int, high: int | None = None) -> None:
    """Require low..high words after the keyword (high None: exactly low; -1: no limit)."""
    n = len(line.words) - 1
    high = low if high is None else high
    if n < low or (high >= 0 and n > high):
        raise BadValue(f"expected '{form}', got {show(line.text)}")


def read_float(word: str, what: str, *, gt: float | None = None, ge: float | None = None,
           lt: float | None = None, le: float | None = None, allow_inf: bool = False) -> float:
    if not NUMBER_PATTERN.fullmatch(word):
        raise BadValue(f"expected a number for {what} (decimal, e.g. 0.114, -28.5 or 1e-4), got "
                   f"{show(word)}")
    value = float(word)
    if math.isnan(value) or (math.isinf(value) and not allow_inf):
        raise BadValue(f"expected a finite number for {what}, got {show(word)}")
    for bound, ok, sign in ((gt, lambda b: value > b, ">"), (ge, lambda b: value >= b, ">="),
                            (lt, lambda b: value < b, "<"), (le, lambda b: value <= b, "<=")):
        if bound is not None and not ok(bound):
            raise BadValue(f"{what} must be {sign} {bound:g}, got {word}")
    return value


def read_int(word: str, what: str, low: int | None = None, high: int | None = None) -> int:
    if not INT_PATTERN.fullmatch(word):
        raise BadValue(f"expected an integer for {what}, got {show(word)}")
    value = int(word)
    if low is not None and value < low:
        raise BadValue(f"{what} must be >= {low}, got {value}")
    if high is not None and value > high:
        raise BadValue(f"{what} must be <= {high}, got {value}")
    return value


def read_name(word: str, what: str) -> str:
    if not NAME_PATTERN.fullmatch(word):
        raise BadValue(f"expected a name for {what} (a letter, then letters, digits, '_', '.' or "
                   f"'-', at most 64), got {show(word)}")
    return word


def read_choice(word: str, what: str, choices: tuple[str, ...]) -> str:
    if word not in choices:
        raise BadValue(f"expected {what} among {', '.join(choices)}, got {show(word)}")
    return word


def read_vector(words: list[str], what: str, limit: float | None = None
            ) -> tuple[float, float, float]:
    x, y, z = (read_float(w, what) if limit is None else read_float(w, what, ge=-limit, le=limit)
               for w in words)
    return (x, y, z)


def read_unit(words: list[str], what: str) -> tuple[float, float, float]:
    v = np.array(read_vector(words, what))
    v = v / max(float(np.abs(v).max()), 1e-300)
    length = float(np.linalg.norm(v))
    if not length > 0 or not math.isfinite(length):
        raise BadValue(f"{what} must be a non-zero finite vector, got {' '.join(words)}")
    return tuple(float(c) for c in v / length)  # type: ignore[return-value]


def read_pairs(line: Line, start: int, keys: tuple[str, ...], required: tuple[str, ...],
           form: str) -> dict[str, str]:
    """``KEY VALUE`` pairs after word ``start``: each key once, all required ones present."""
    words = line.words[start:]
    if len(words) % 2:
        raise BadValue(f"expected '{form}' (keys and values in pairs), got {show(line.text)}")
    values: dict[str, str] = {}
    for key, value in zip(words[::2], words[1::2], strict=True):
        if key not in keys:
            raise BadValue(f"unknown key {show(key)} in '{form}': expected {', '.join(keys)}")
        if key in values:
            raise BadValue(f"{key} given twice")
        values[key] = value
    missing = [k for k in required if k not in values]
    if missing:
        raise BadValue(f"missing {', '.join(missing)}: expected '{form}'")
    return values


def first_time(deck: Deck, seen: dict[str, int], line: Line, key: str | None = None) -> bool:
    """Record ``key`` (default the line's keyword) as given; error and False when repeated."""
    key = key or line.key
    if key in seen:
        deck.error(line.number, f"'{key}' given twice (first at line {seen[key]})")
        return False
    seen[key] = line.number
    return True
