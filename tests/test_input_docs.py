"""docs/input-format.md: its worked example is the real examples/bending folder, and every
keyword the parser knows is documented."""

from __future__ import annotations

import re
from pathlib import Path

from deckutil import EXAMPLES

from ddpy.io import decks

DOC = Path(__file__).resolve().parent.parent / "docs" / "input-format.md"


def test_worked_example_is_the_example_folder() -> None:
    text = DOC.read_text()
    blocks = re.findall(r"`examples/bending/(\w+\.dat)`\n\n```\n(.*?)```", text, re.S)
    assert sorted(name for name, _ in blocks) == sorted(decks.DECKS)
    for name, body in blocks:
        assert body == (EXAMPLES / "bending" / name).read_text(), name


def test_every_keyword_documented() -> None:
    text = DOC.read_text()
    documented = set(re.findall(r"`([a-z_0-9]+)`", text))
    keywords = {"title", "tune", "phase", "end", "tool", "description", "file", "friction",
                "contact", "normal", "element", "box", "origin", "nodes", "hexahedra", "scale",
                "tolerance", "nodeset",
                "symmetry", "fix", "elastic", "yield", "hardening", "rolling_direction", "ids",
                "plane", "top", "bottom", "facing", "vonmises", "forming", "springback"}
    keywords |= set(decks._SETTINGS) | set(decks._PHASE_KEYS) | set(decks._TOOL_KEYS)
    assert keywords - documented == set()
