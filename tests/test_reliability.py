"""Bad input and faults a user can cause: each ends in a clear message naming the file and
the line (or the option), before any numerics start; legitimate input is not refused."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from ddpy.decks import DeckError, read_case
from tests.deckutil import copy_example, edit

BUILT_IN = Path(__file__).resolve().parents[1] / "ddpy" / "cases" / "cylindrical_bending"


def errors_of(case: Path) -> str:
    with pytest.raises(DeckError) as caught:
        read_case(case)
    return str(caught.value)


def test_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    path = case / "material.dat"
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert read_case(case).material.material.E == 210000.0


@pytest.mark.parametrize("separator", ["\f", "\v", "\u2028", "\x1c", "\x85"])
def test_only_ascii_line_ends_end_a_line(tmp_path: Path, separator: str) -> None:
    # A separator inside a comment stays in the comment, and the line numbers of the errors
    # after it stay those an editor shows.
    case = copy_example("bending", tmp_path)
    edit(case, "material.dat", "# ddpy material deck: the blank.",
         f"# ddpy material deck:{separator}hardening nonsense")
    edit(case, "material.dat", "n 0.252", "n 7")
    message = errors_of(case)
    assert "material.dat:5:" in message and "Swift n must be <= 1" in message
    assert "nonsense" not in message


@pytest.mark.parametrize("word", ["210_000", "２１００００", "0x1p3", "1_0", "1e", ".", "Infinity"])
def test_numbers_follow_the_documented_grammar(tmp_path: Path, word: str) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "material.dat", "E 210000", f"E {word}")
    message = errors_of(case)
    assert "material.dat:3:" in message and "expected a number" in message


def test_numbers_in_mesh_blocks_follow_the_grammar_too(tmp_path: Path) -> None:
    case = copy_example("strip_draw", tmp_path)
    edit(case, "mesh.dat", "\n  1   0  0 0\n", "\n  1   1_0  0 0\n")
    assert "mesh.dat:4: expected numbers X Y Z, got '1_0 0 0'" in errors_of(case)


@pytest.mark.parametrize("version", ["2", "4"])
def test_gmsh_element_count_is_checked(tmp_path: Path, version: str) -> None:
    # meshio reads as many elements as the count says and drops the rest without a word.
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN, case)
    msh = case / "mesh.msh"
    if version == "4":
        meshio = pytest.importorskip("meshio")
        meshio.write(msh, meshio.read(msh), file_format="gmsh", binary=False)
    text = msh.read_text()
    lines = text.split("\n")
    at = lines.index("$Elements")
    header = lines[at + 1].split()
    index = 0 if version == "2" else 1
    header[index] = str(int(header[index]) - 98)
    lines[at + 1] = " ".join(header)
    msh.write_text("\n".join(lines))
    message = errors_of(case)
    assert f"mesh.msh:{at + 2}: $Elements says" in message
