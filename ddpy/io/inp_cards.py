"""The card reader of Abaqus / CalculiX input files: keyword lines with their parameters and
data lines, *INCLUDE followed, every line kept with its file and number.

:func:`read_cards` returns the :class:`Card` list of a file; a defect of the file itself (an
*INCLUDE that cannot be read or includes itself, a keyword line without a keyword, data
before the first keyword) is a :class:`ddpy.io.case.DeckError` naming the file and line.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ddpy._validate import MESH_LIMIT, InputFileError, read_input_file
from ddpy.io.case import DeckError

__all__ = ["Card", "DataLine", "number", "integer", "read_cards"]

#: Nesting depth of *INCLUDE beyond which a file is taken to include itself.
MAX_INCLUDE_DEPTH = 20


@dataclass
class DataLine:
    """One data line: its words (split at commas, stripped, trailing empty ones dropped)."""

    path: Path
    number: int
    words: list[str]

    @property
    def where(self) -> str:
        return f"{self.path}:{self.number}"


@dataclass
class Card:
    """A keyword line (``keyword`` upper case, spaces single; ``params`` upper-case keys,
    values as written, ``''`` for a flag) and the data lines after it."""

    keyword: str
    params: dict[str, str]
    path: Path
    number: int
    data: list[DataLine] = field(default_factory=list)

    @property
    def where(self) -> str:
        return f"{self.path}:{self.number}"

    def error(self, message: str, line: DataLine | None = None) -> DeckError:
        return DeckError(message, line.path if line else self.path,
                         line.number if line else self.number)


def _keyword(text: str) -> tuple[str, dict[str, str]]:
    parts = [p.strip() for p in text[1:].split(",")]
    keyword = re.sub(r"\s+", " ", parts[0]).upper()
    params: dict[str, str] = {}
    for part in parts[1:]:
        if part:
            key, _, value = part.partition("=")
            params[re.sub(r"\s+", " ", key.strip()).upper()] = value.strip()
    return keyword, params


def read_cards(path: str | Path, _depth: int = 0) -> list[Card]:
    """The cards of an input file, those of its *INCLUDE files in their place."""
    path = Path(path)
    try:
        text = read_input_file(path, "an Abaqus input file", MESH_LIMIT).decode("latin-1")
    except InputFileError as error:
        raise DeckError(error.reason, path) from None
    except OSError as error:
        raise DeckError(f"cannot read the input file: {error.strerror or error}", path) \
            from None
    cards: list[Card] = []
    continued = False
    for number, raw in enumerate(text.replace("\r\n", "\n").replace("\r", "\n").split("\n"),
                                 start=1):
        line = raw.strip()
        if not line or line.startswith("**"):
            continue
        if line.startswith("*"):
            keyword, params = _keyword(line)
            if not keyword:
                raise DeckError(f"expected a keyword after '*', got '{line[:60]}'", path, number)
            if keyword == "INCLUDE":
                cards += _include(path, number, params, _depth)
                continue
            cards.append(Card(keyword, params, path, number))
            continued = False
            continue
        if not cards:
            raise DeckError(f"a data line before the first keyword: '{line[:60]}'", path, number)
        words = [w.strip() for w in line.split(",")]
        while words and words[-1] == "":
            words.pop()
        card = cards[-1]
        if continued and card.keyword == "ELEMENT" and card.data:
            card.data[-1].words += words         # the element's nodes go on
        else:
            card.data.append(DataLine(path, number, words))
        continued = line.endswith(",")
    return cards


def _include(path: Path, number: int, params: dict[str, str], depth: int) -> list[Card]:
    name = params.get("INPUT", "")
    if not name:
        raise DeckError("expected '*INCLUDE, INPUT=<file>'", path, number)
    if set(params) != {"INPUT"}:
        other = sorted(set(params) - {"INPUT"})[0]
        raise DeckError(f"parameter {other} of *INCLUDE is not supported: expected INPUT=<file>",
                        path, number)
    target = Path(name.strip('"'))
    if not target.is_absolute():
        target = path.parent / target
    if depth >= MAX_INCLUDE_DEPTH:
        raise DeckError(f"*INCLUDE nested deeper than {MAX_INCLUDE_DEPTH} files: does {target} "
                        "include itself?", path, number)
    if not target.exists():  # a fifo or device is refused, by name, when it is read
        raise DeckError(f"*INCLUDE: no such file {target}", path, number)
    return read_cards(target, depth + 1)


def number(line: DataLine, index: int, what: str) -> float:
    """Word ``index`` of a data line as a finite number, or DeckError at the line."""
    word = line.words[index] if index < len(line.words) else ""
    try:
        value = float(word.replace("d", "e").replace("D", "e"))
    except ValueError:
        value = float("nan")
    if word == "" or value != value or value in (float("inf"), float("-inf")):
        raise DeckError(f"expected a number for {what}, got '{word[:40]}'", line.path,
                        line.number)
    return value


def integer(line: DataLine, index: int, what: str) -> int:
    """Word ``index`` of a data line as a positive integer (an id), or DeckError."""
    word = line.words[index] if index < len(line.words) else ""
    if not re.fullmatch(r"[0-9]+", word) or not 1 <= int(word) <= 2**31 - 1:
        raise DeckError(f"expected a positive integer for {what}, got '{word[:40]}'",
                        line.path, line.number)
    return int(word)
