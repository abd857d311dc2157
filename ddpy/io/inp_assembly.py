"""Abaqus/CAE decks with parts and an assembly made flat: the cards of ``*PART`` ...
``*END PART`` placed once per ``*INSTANCE`` (translated, then rotated, as Abaqus defines
it), their ids and names made unique, the assembly's cards resolved against the instances.

:func:`flatten_assembly` takes the cards of :func:`ddpy.io.inp_cards.read_cards` and
returns the cards of the same model written flat, every card and data line keeping the file
and line it came from. A deck without ``*PART``, ``*ASSEMBLY`` and ``*INSTANCE`` comes back
as it is: its ids and names are kept.

Ids. Instance k (1, 2, ... in the order of the ``*INSTANCE`` cards) numbers its nodes and
elements k * 10^d + (the part's id), 10^d the smallest power of ten above every id of the
deck; nodes and elements of the assembly itself (reference points) keep theirs. Names. A
set or surface NAME of a part is ``INSTANCE.NAME`` (Abaqus's own way to name it from the
assembly, e.g. ``STRIP-1.BLANK``); a ``*NSET``/``*ELSET`` of the assembly with
``INSTANCE=`` lists the instance's ids and names; ``INSTANCE.ID`` names one node or element
of an instance anywhere after the part definitions.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ddpy.io.case import DeckError
from ddpy.io.inp_cards import Card, number

__all__ = ["Instance", "flatten_assembly"]

#: Keywords that open and close the blocks of an assembled deck.
_BLOCKS = ("PART", "END PART", "ASSEMBLY", "END ASSEMBLY", "INSTANCE", "END INSTANCE")
#: Parameters of the cards of a part that name a set, surface or element set of the part.
_NAME_PARAMS = {"NODE": ("NSET",), "ELEMENT": ("ELSET",), "NSET": ("NSET",),
                "ELSET": ("ELSET",), "SURFACE": ("NAME",), "SOLID SECTION": ("ELSET",)}
_QUALIFIED_ID = re.compile(r"^(.+)\.([0-9]+)$")


@dataclass
class Instance:
    """An ``*INSTANCE``: its name, its part, where it was defined, the id offset of its
    nodes and elements, its placement x -> R (x + t - a) + a."""

    name: str
    part: str
    card: Card
    offset: int = 0
    rotation: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))
    translation: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    axis_point: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    cards: list[Card] = field(default_factory=list)

    def place(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """Part coordinates -> assembly coordinates."""
        return self.rotation @ (x + self.translation - self.axis_point) + self.axis_point


def _axis_rotation(axis: NDArray[np.float64], degrees: float) -> NDArray[np.float64]:
    """The rotation by ``degrees`` about the unit ``axis`` (right-hand rule)."""
    k = axis / np.linalg.norm(axis)
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    angle = math.radians(degrees)
    return np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * cross @ cross


def _name(card: Card, key: str) -> str:
    name = card.params.get(key, "").strip().strip('"')
    if not name:
        raise card.error(f"*{card.keyword} without {key}=<name>")
    return name


def _placement(instance: Instance) -> None:
    """Read the instance's translation and rotation lines (both optional, in that order)."""
    lines = instance.card.data
    if len(lines) > 2:
        raise DeckError("expected at most two data lines after *INSTANCE (a translation "
                        "'x, y, z', a rotation 'ax, ay, az, bx, by, bz, angle'), got a third",
                        lines[2].path, lines[2].number)
    if lines and lines[0].words:
        if len(lines[0].words) != 3:
            raise DeckError("expected the translation 'x, y, z' on the first data line of "
                            f"*INSTANCE, got {len(lines[0].words)} values", lines[0].path,
                            lines[0].number)
        instance.translation = np.array([number(lines[0], i, "a translation")
                                         for i in range(3)])
    if len(lines) == 2 and lines[1].words:
        line = lines[1]
        if len(line.words) != 7:
            raise DeckError("expected the rotation 'ax, ay, az, bx, by, bz, angle in degrees' "
                            f"(axis through points a and b) on the second data line of "
                            f"*INSTANCE, got {len(line.words)} values", line.path, line.number)
        values = [number(line, i, "a rotation value") for i in range(7)]
        a, b = np.array(values[:3]), np.array(values[3:6])
        if np.linalg.norm(b - a) == 0.0:
            raise DeckError("the rotation axis of *INSTANCE goes through two equal points: "
                            "expected a != b", line.path, line.number)
        instance.axis_point = a
        instance.rotation = _axis_rotation(b - a, values[6])


def _largest_id(cards: list[Card]) -> int:
    largest = 0
    for card in cards:
        if card.keyword in ("NODE", "ELEMENT"):
            for line in card.data:
                if line.words and line.words[0].isdigit():
                    largest = max(largest, int(line.words[0]))
    return largest


class _Flattener:
    def __init__(self) -> None:
        self.errors: list[DeckError] = []
        self.parts: dict[str, tuple[Card, list[Card]]] = {}
        self.instances: dict[str, Instance] = {}

    # -------------------------------------------------------------------- ids and names

    def ident(self, word: str, offset: int) -> str:
        return str(int(word) + offset) if word.isdigit() else word

    def qualified(self, word: str) -> str:
        """``INSTANCE.ID`` -> the flat id; other words as they are."""
        match = _QUALIFIED_ID.match(word)
        if match is None:
            return word
        instance = self.instances.get(match[1].strip('"').upper())
        return str(int(match[2]) + instance.offset) if instance else word

    def item(self, word: str, instance: Instance) -> str:
        """A data word of a part's set: an id offset, a name qualified by the instance."""
        if not word or word.lstrip("-").isdigit():
            return self.ident(word, instance.offset)
        return f"{instance.name}.{word.strip(chr(34))}"

    # ----------------------------------------------------------------- one part's cards

    def place(self, card: Card, instance: Instance) -> Card:
        """A card of a part as the instance's: ids offset, names qualified, nodes placed."""
        params = dict(card.params)
        for key in _NAME_PARAMS.get(card.keyword, ()):
            if key in params:
                params[key] = f"{instance.name}.{params[key].strip(chr(34))}"
        data = []
        for line in card.data:
            words = list(line.words)
            if card.keyword == "NODE" and words:
                xyz = np.array([number(line, i, "a coordinate") if i < len(words) else 0.0
                                for i in (1, 2, 3)])
                placed = instance.place(xyz)
                words = [self.ident(words[0], instance.offset)] + [f"{v:.15g}" for v in placed]
            elif card.keyword == "ELEMENT":
                words = [self.ident(w, instance.offset) for w in words]
            elif card.keyword in ("NSET", "ELSET"):
                if "GENERATE" in params:
                    words = [self.ident(w, instance.offset) for w in words[:2]] + words[2:]
                else:
                    words = [self.item(w, instance) for w in words]
            elif card.keyword == "SURFACE" and words:
                words = [self.item(words[0], instance)] + words[1:]
            data.append(replace(line, words=words))
        return replace(card, params=params, data=data)

    # ---------------------------------------------------------------------- the walk

    def flatten(self, cards: list[Card]) -> list[Card]:
        offset = 10 ** len(str(_largest_id(cards)))
        flat: list[Card] = []
        part: tuple[Card, list[Card]] | None = None
        assembly: Card | None = None
        instance: Instance | None = None
        for card in cards:
            key = card.keyword
            try:
                if key == "PART":
                    if part or assembly:
                        raise card.error("*PART inside a *PART or *ASSEMBLY: expected *END "
                                         f"{'PART' if part else 'ASSEMBLY'} first")
                    name = _name(card, "NAME").upper()
                    if name in self.parts:
                        raise card.error(f"part {name} is defined again (first at "
                                         f"{self.parts[name][0].where})")
                    part = (card, [])
                    self.parts[name] = part
                elif key == "END PART":
                    if part is None:
                        raise card.error("*END PART without *PART")
                    part = None
                elif key == "ASSEMBLY":
                    if part or assembly:
                        raise card.error("*ASSEMBLY inside a *PART or *ASSEMBLY")
                    assembly = card
                elif key == "END ASSEMBLY":
                    if assembly is None or instance is not None:
                        raise card.error("*END ASSEMBLY without *ASSEMBLY" if assembly is None
                                         else f"*END ASSEMBLY inside the *INSTANCE of "
                                         f"{instance.card.where}: expected *END INSTANCE")
                    assembly = None
                elif key == "INSTANCE":
                    if assembly is None or instance is not None:
                        raise card.error("*INSTANCE outside an *ASSEMBLY" if assembly is None
                                         else "*INSTANCE inside an *INSTANCE: expected *END "
                                         "INSTANCE first")
                    instance = self.open(card, offset)
                elif key == "END INSTANCE":
                    if instance is None:
                        raise card.error("*END INSTANCE without *INSTANCE")
                    part_cards = self.parts[instance.part][1] if instance.part in self.parts \
                        else []
                    flat += [self.place(c, instance) for c in part_cards + instance.cards]
                    instance = None
                elif part is not None:
                    part[1].append(card)
                elif instance is not None:
                    instance.cards.append(card)
                else:
                    flat.append(self.resolve(card))
            except DeckError as error:
                self.errors.append(error)
        for name, opened in (("*PART", part and part[0]), ("*ASSEMBLY", assembly),
                             ("*INSTANCE", instance and instance.card)):
            if opened:
                self.errors.append(opened.error(f"{name} is not closed: expected *END "
                                                f"{name[1:]}"))
        if (len(self.instances) + 1) * offset > 2**31 - 1:
            self.errors.append(cards[0].error(
                f"{len(self.instances)} instances of ids up to {offset - 1}: the flat ids "
                "(instance number x 10^d + id) would pass 2^31 - 1"))
        return flat

    def open(self, card: Card, offset: int) -> Instance:
        name = _name(card, "NAME").upper()
        part = _name(card, "PART").upper()
        if name in self.instances:
            raise card.error(f"instance {name} is defined again (first at "
                             f"{self.instances[name].card.where})")
        if part not in self.parts:
            raise card.error(f"no *PART named {part} before this *INSTANCE")
        other = sorted(set(card.params) - {"NAME", "PART"})
        if other:
            raise card.error(f"parameter {other[0]} of *INSTANCE is not supported "
                             "(supported: NAME, PART)")
        instance = Instance(name, part, card, (len(self.instances) + 1) * offset)
        _placement(instance)
        self.instances[name] = instance
        return instance

    def resolve(self, card: Card) -> Card:
        """A card of the assembly or the model: INSTANCE= sets and INSTANCE.ID words."""
        params = {k: self.qualified(v) for k, v in card.params.items()}
        target = params.pop("INSTANCE", None)
        if target is not None:
            instance = self.instances.get(target.strip('"').upper())
            if instance is None:
                raise card.error(f"INSTANCE={target}: no *INSTANCE of that name before this "
                                 "card")
            if card.keyword not in ("NSET", "ELSET"):
                raise card.error(f"INSTANCE= on *{card.keyword}: ddpy reads it on *NSET and "
                                 "*ELSET")
            generate = "GENERATE" in params
            data = [replace(line, words=[self.ident(w, instance.offset) for w in line.words[:2]]
                            + line.words[2:] if generate else
                            [self.item(w, instance) for w in line.words])
                    for line in card.data]
            return replace(card, params=params, data=data)
        data = [replace(line, words=[self.qualified(w) for w in line.words])
                for line in card.data]
        return replace(card, params=params, data=data)


def flatten_assembly(cards: list[Card]) -> tuple[list[Card], list[Instance], list[DeckError]]:
    """The cards of the model written flat, its instances, and the defects found (each at
    its file:line); a deck without parts comes back unchanged."""
    if not any(card.keyword in _BLOCKS for card in cards):
        return cards, [], []
    flattener = _Flattener()
    flat = flattener.flatten(cards)
    return flat, list(flattener.instances.values()), flattener.errors
