"""The mesh of an Abaqus / CalculiX input file: nodes, elements, node and element sets and
element-based surfaces, read by one reader for every path that takes an .inp file (``ddpy
convert`` and ``ddpy run MODEL.inp``, mesh.dat's ``file X.inp``, tool meshes).

Ids are Abaqus's own: a flat deck's node and element ids are kept everywhere; a deck of
parts and an assembly is made flat first (:mod:`ddpy.io.inp_assembly`, which says how its
instances' ids are made unique). Names are upper case (Abaqus's names are case-insensitive),
a part's as ``INSTANCE.NAME``. Every defect is a :class:`ddpy.io.case.DeckError` at its
file:line.
"""

from __future__ import annotations

import re
from pathlib import Path

from ddpy.io.case import DeckError
from ddpy.io.inp_assembly import flatten_assembly
from ddpy.io.inp_cards import Card, DataLine, integer, number, read_cards

__all__ = ["NODE_COUNTS", "STABILIZING_TYPES", "MeshReader", "ddpy_name", "element_nodes",
           "read_inp_mesh"]

#: Nodes of the element types whose count ddpy checks (others: any count).
NODE_COUNTS = {"C3D8": 8, "C3D8R": 8, "C3D8I": 8, "C3D8H": 8, "C3D8IH": 8, "C3D8RH": 8,
               "C3D20": 20, "C3D20R": 20, "C3D4": 4, "C3D10": 10, "C3D6": 6, "C3D15": 15,
               "R3D4": 4, "R3D3": 3, "S4": 4, "S4R": 4, "S3": 3, "S3R": 3, "M3D4": 4,
               "M3D3": 3, "SPRING1": 1, "SPRING2": 2, "SPRINGA": 2, "DASHPOT1": 1,
               "DASHPOT2": 2, "DASHPOTA": 2}
#: Elements that only hold rigid-body modes of a static model (springs and dashpots): ddpy
#: skips them (the blank is held by its constraints and its contact with the tools).
STABILIZING_TYPES = ("SPRING1", "SPRING2", "SPRINGA", "DASHPOT1", "DASHPOT2", "DASHPOTA")


_NAME = re.compile(r"[^A-Za-z0-9_.\-]")


def ddpy_name(name: str, prefix: str = "s") -> str:
    """An Abaqus name as a ddpy name (lower case, other characters '_', a letter first):
    how a set is named in bc.dat, by ``ddpy convert`` and mesh.dat's ``file X.inp`` alike."""
    text = _NAME.sub("_", name).lower()[:64]
    return text if text[:1].isalpha() else f"{prefix}_{text}"[:64]


def element_nodes(kind: str) -> int | None:
    """The node count of an element type, or None where ddpy does not check it."""
    return NODE_COUNTS.get(kind)


class MeshReader:
    """Nodes, elements, sets and surfaces of the cards, each with the line that defined it;
    defects collected in ``errors``. ``read`` skips the cards of other keywords (a subclass
    maps them)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.errors: list[DeckError] = []
        self.ignored: list[str] = []
        self.nodes: dict[int, tuple[tuple[float, float, float], DataLine]] = {}
        self.elements: dict[int, tuple[str, list[int], DataLine]] = {}
        #: Springs and dashpots skipped: (type, node ids, line).
        self.stabilizers: list[tuple[str, list[int], DataLine]] = []
        #: Each element's *ELEMENT card, numbered from 1 in the file's order.
        self.blocks: dict[int, int] = {}
        self._block = 0
        self.nsets: dict[str, list[tuple[str, DataLine]]] = {}
        self.elsets: dict[str, list[tuple[str, DataLine]]] = {}
        self.surfaces: dict[str, tuple[list[tuple[str, str, DataLine]], Card]] = {}

    def fail(self, error: DeckError) -> None:
        self.errors.append(error)

    def read(self, cards: list[Card]) -> None:
        """Read the mesh cards; a defect of one is recorded and the next card read."""
        for card in cards:
            try:
                if card.keyword in ("NODE", "ELEMENT", "NSET", "ELSET", "SURFACE"):
                    getattr(self, "_" + card.keyword.lower())(card)
            except DeckError as error:
                self.fail(error)

    @staticmethod
    def _name(card: Card, key: str) -> str:
        name = card.params.get(key, "").strip('"').upper()
        if not name:
            raise card.error(f"*{card.keyword} without {key}=<name>")
        return name

    def _node(self, card: Card, *_: object) -> None:
        nset = card.params.get("NSET", "").strip('"').upper()
        for line in card.data:
            try:
                ident = integer(line, 0, "the node id")
                if not 3 <= len(line.words) <= 4:
                    raise DeckError(f"expected '<node id>, <x>, <y>, <z>', got "
                                    f"'{', '.join(line.words)[:60]}'", line.path, line.number)
                xyz = tuple(number(line, i, "a coordinate") if i < len(line.words) else 0.0
                            for i in (1, 2, 3))
                if ident in self.nodes:
                    raise DeckError(f"node {ident} is defined again (first at "
                                    f"{self.nodes[ident][1].where})", line.path, line.number)
                self.nodes[ident] = (xyz, line)  # type: ignore[assignment]
                if nset:
                    self.nsets.setdefault(nset, []).append((str(ident), line))
            except DeckError as error:
                self.fail(error)

    def _element(self, card: Card, *_: object) -> None:
        kind = card.params.get("TYPE", "").upper()
        if not kind:
            raise card.error("*ELEMENT without TYPE=<element type>")
        count = element_nodes(kind)
        elset = card.params.get("ELSET", "").strip('"').upper()
        stabilizing = kind in STABILIZING_TYPES
        self._block += 1
        for line in card.data:
            try:
                ident = integer(line, 0, "the element id")
                if count is not None and len(line.words) != count + 1:
                    raise DeckError(f"element {line.words[0]} has {len(line.words) - 1} nodes:"
                                    f" a {kind} element has {count} (was its type or a node "
                                    "changed?)", line.path, line.number)
                if len(line.words) < 2:
                    raise DeckError("expected '<element id>, <node ids>'", line.path,
                                    line.number)
                nodes = [integer(line, i, "a node id") for i in range(1, len(line.words))]
                if stabilizing:
                    self.stabilizers.append((kind, nodes, line))
                    continue
                if ident in self.elements:
                    raise DeckError(f"element {ident} is defined again (first at "
                                    f"{self.elements[ident][2].where})", line.path, line.number)
                self.elements[ident] = (kind, nodes, line)
                self.blocks[ident] = self._block
                if elset:
                    self.elsets.setdefault(elset, []).append((str(ident), line))
            except DeckError as error:
                self.fail(error)
        if stabilizing and card.data:
            self.ignored.append(f"{card.where}: {len(card.data)} {kind} element(s), skipped: "
                                "they only hold rigid-body modes, and ddpy's blank is held by "
                                "its constraints and the tools")

    def _set(self, card: Card, sets: dict[str, list[tuple[str, DataLine]]], key: str) -> None:
        name = self._name(card, key)
        items = sets.setdefault(name, [])
        for line in card.data:
            if "GENERATE" in card.params:
                if not 2 <= len(line.words) <= 3:
                    raise DeckError("expected '<first>, <last>[, <step>]' (GENERATE)",
                                    line.path, line.number)
                first, last = integer(line, 0, "the first id"), integer(line, 1, "the last id")
                inc = integer(line, 2, "the step") if len(line.words) == 3 else 1
                if last < first:
                    raise DeckError(f"GENERATE from {first} to {last}: the last id is below "
                                    "the first", line.path, line.number)
                items += [(str(i), line) for i in range(first, last + 1, inc)]
            else:
                items += [(w.strip('"').upper(), line) for w in line.words if w]

    def _nset(self, card: Card, *_: object) -> None:
        self._set(card, self.nsets, "NSET")

    def _elset(self, card: Card, *_: object) -> None:
        self._set(card, self.elsets, "ELSET")

    def _surface(self, card: Card, *_: object) -> None:
        name = self._name(card, "NAME")
        if card.params.get("TYPE", "ELEMENT").upper() != "ELEMENT":
            self.surfaces[name] = ([], card)     # node-based: no faces
            return
        items = []
        for line in card.data:
            if not 1 <= len(line.words) <= 2:
                raise DeckError("expected '<element or element set>[, <face>]'", line.path,
                                line.number)
            face = line.words[1].upper() if len(line.words) == 2 else ""
            items.append((line.words[0].strip('"').upper(), face, line))
        self.surfaces[name] = (items, card)

    # ------------------------------------------------------------------ resolving names

    def node_set(self, name: str, line: DataLine, seen: tuple[str, ...] = ()) -> list[int]:
        """The node ids of a node id or a node set (nested sets followed)."""
        if name.isdigit():
            return [int(name)]
        if name not in self.nsets or name in seen:
            raise DeckError(f"no node set named {name}", line.path, line.number)
        ids: list[int] = []
        for item, at in self.nsets[name]:
            ids += self.node_set(item, at, (*seen, name))
        return ids

    def element_set(self, name: str, line: DataLine, seen: tuple[str, ...] = ()) -> list[int]:
        """The element ids of an element id or an element set (nested sets followed)."""
        if re.fullmatch(r"[0-9]+", name):
            return [int(name)]
        if name not in self.elsets or name in seen:
            raise DeckError(f"no element set named {name}", line.path, line.number)
        ids: list[int] = []
        for item, at in self.elsets[name]:
            ids += self.element_set(item, at, (*seen, name))
        return ids


def read_inp_mesh(path: str | Path) -> MeshReader:
    """The mesh of an input file (its includes followed, its assembly made flat); raises
    DeckError listing every defect."""
    path = Path(path)
    cards, _, errors = flatten_assembly(read_cards(path))
    reader = MeshReader(path)
    reader.errors += errors
    reader.read(cards)
    if reader.errors:
        raise DeckError.collect(reader.errors)
    return reader
