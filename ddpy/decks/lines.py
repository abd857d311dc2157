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

from ddpy._validate import input_lines
from ddpy.case import DeckError

#: Largest length a deck may give (mm): displacements, gaps, increments, box sizes.
MAX_LENGTH = 1e6
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_.\-]{0,63}")
_INT = re.compile(r"[+-]?[0-9]+")
#: The numbers of the decks (docs/input-format.md): decimal with an optional exponent, in
#: ASCII digits; float() alone would also take '210_000', full-width digits and 'nan'.
_NUMBER = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?|[+-]?(inf|nan)",
                     re.ASCII)


class _Bad(Exception):
    """A defect in the line being read; the deck loop records it with the line number."""


@dataclass
class _Line:
    number: int
    words: list[str]
    text: str

    @property
    def key(self) -> str:
        return self.words[0]


class _Deck:
    """The meaningful lines of one deck ('#' starts a comment), its errors and warnings."""

    def __init__(self, path: Path, text: str) -> None:
        self.path = path
        self.lines: list[_Line] = []
        self.errors: list[DeckError] = []
        self.warnings: list[str] = []
        raw_lines = input_lines(text)
        self.last = len(raw_lines)
        for number, raw in enumerate(raw_lines, start=1):
            content = raw.split("#", 1)[0].strip()
            if content:
                self.lines.append(_Line(number, content.split(), content))

    def where(self, line: int | None) -> str:
        return f"{self.path}:{line}" if line is not None else str(self.path)

    def error(self, line: int | None, message: str) -> None:
        self.errors.append(DeckError(message, self.path, line))

    def warn(self, line: int | None, message: str) -> None:
        self.warnings.append(f"{self.where(line)}: {message}")


def _guard(deck: _Deck, line: _Line | int | None, action: Callable[[], Any]) -> Any:
    """Run ``action``; record a _Bad it raises at ``line`` and return None."""
    try:
        return action()
    except _Bad as bad:
        deck.error(line.number if isinstance(line, _Line) else line, str(bad))
        return None


# ------------------------------------------------------------------------- words and values


def _show(text: str, limit: int = 60) -> str:
    text = text if len(text) <= limit else text[: limit - 3] + "..."
    return f"'{text}'"


def _arity(line: _Line, form: str, low: int, high: int | None = None) -> None:
    """Require low..high words after the keyword (high None: exactly low; -1: no limit)."""
    n = len(line.words) - 1
    high = low if high is None else high
    if n < low or (high >= 0 and n > high):
        raise _Bad(f"expected '{form}', got {_show(line.text)}")


def _float(word: str, what: str, *, gt: float | None = None, ge: float | None = None,
           lt: float | None = None, le: float | None = None, allow_inf: bool = False) -> float:
    if not _NUMBER.fullmatch(word):
        raise _Bad(f"expected a number for {what} (decimal, e.g. 0.114, -28.5 or 1e-4), got "
                   f"{_show(word)}")
    value = float(word)
    if math.isnan(value) or (math.isinf(value) and not allow_inf):
        raise _Bad(f"expected a finite number for {what}, got {_show(word)}")
    for bound, ok, sign in ((gt, lambda b: value > b, ">"), (ge, lambda b: value >= b, ">="),
                            (lt, lambda b: value < b, "<"), (le, lambda b: value <= b, "<=")):
        if bound is not None and not ok(bound):
            raise _Bad(f"{what} must be {sign} {bound:g}, got {word}")
    return value


def _int(word: str, what: str, low: int | None = None, high: int | None = None) -> int:
    if not _INT.fullmatch(word):
        raise _Bad(f"expected an integer for {what}, got {_show(word)}")
    value = int(word)
    if low is not None and value < low:
        raise _Bad(f"{what} must be >= {low}, got {value}")
    if high is not None and value > high:
        raise _Bad(f"{what} must be <= {high}, got {value}")
    return value


def _name(word: str, what: str) -> str:
    if not _NAME.fullmatch(word):
        raise _Bad(f"expected a name for {what} (a letter, then letters, digits, '_', '.' or "
                   f"'-', at most 64), got {_show(word)}")
    return word


def _choice(word: str, what: str, choices: tuple[str, ...]) -> str:
    if word not in choices:
        raise _Bad(f"expected {what} among {', '.join(choices)}, got {_show(word)}")
    return word


def _vector(words: list[str], what: str, limit: float | None = None
            ) -> tuple[float, float, float]:
    x, y, z = (_float(w, what) if limit is None else _float(w, what, ge=-limit, le=limit)
               for w in words)
    return (x, y, z)


def _unit(words: list[str], what: str) -> tuple[float, float, float]:
    v = np.array(_vector(words, what))
    v = v / max(float(np.abs(v).max()), 1e-300)
    length = float(np.linalg.norm(v))
    if not length > 0 or not math.isfinite(length):
        raise _Bad(f"{what} must be a non-zero finite vector, got {' '.join(words)}")
    return tuple(float(c) for c in v / length)  # type: ignore[return-value]


def _pairs(line: _Line, start: int, keys: tuple[str, ...], required: tuple[str, ...],
           form: str) -> dict[str, str]:
    """``KEY VALUE`` pairs after word ``start``: each key once, all required ones present."""
    words = line.words[start:]
    if len(words) % 2:
        raise _Bad(f"expected '{form}' (keys and values in pairs), got {_show(line.text)}")
    values: dict[str, str] = {}
    for key, value in zip(words[::2], words[1::2], strict=True):
        if key not in keys:
            raise _Bad(f"unknown key {_show(key)} in '{form}': expected {', '.join(keys)}")
        if key in values:
            raise _Bad(f"{key} given twice")
        values[key] = value
    missing = [k for k in required if k not in values]
    if missing:
        raise _Bad(f"missing {', '.join(missing)}: expected '{form}'")
    return values


def _once(deck: _Deck, seen: dict[str, int], line: _Line, key: str | None = None) -> bool:
    """Record ``key`` (default the line's keyword) as given; error and False when repeated."""
    key = key or line.key
    if key in seen:
        deck.error(line.number, f"'{key}' given twice (first at line {seen[key]})")
        return False
    seen[key] = line.number
    return True
