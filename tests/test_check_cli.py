"""``ddpy check CASE``: a summary and exit code 0, or every error as file:line and exit code 2."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from deckutil import EXAMPLES, copy_example, edit, row_mesh_deck


def check(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "ddpy", "check", *args], capture_output=True,
                          text=True)


def test_check_valid_case() -> None:
    result = check(str(EXAMPLES / "bending"))
    assert result.returncode == 0, result.stderr
    assert "216 hexahedra" in result.stdout and "tool punch: nagata" in result.stdout
    assert result.stdout.rstrip().endswith(": ok")


def test_check_errors(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "tools.dat", "friction     0.148", "friction -0.1")
    edit(case, "bc.dat", "fix        centre  z  phase springback", "fix centre")
    result = check(str(case), "--no-geometry")
    assert result.returncode == 2 and result.stdout == ""
    lines = result.stderr.splitlines()
    assert lines[0].startswith(f"{case / 'bc.dat'}:") and "expected 'fix NODESET" in lines[0]
    assert lines[1] == f"{case / 'tools.dat'}:7: friction must be >= 0, got -0.1"
    assert lines[2] == f"{case}: 2 errors"
    assert "not a case folder" in check(str(tmp_path / "none")).stderr


def test_check_reports_every_bad_element(tmp_path: Path) -> None:
    text, lines = row_mesh_deck(4, upside_down=(0, 3), repeated=(1,))
    case = copy_example("bending", tmp_path, mesh=text)
    result = check(str(case), "--no-geometry")
    assert result.returncode == 2 and result.stdout == ""
    errors = result.stderr.splitlines()
    mesh = case / "mesh.dat"
    assert errors[0].startswith(f"{mesh}:{lines[0]}: element 11 is inverted at its corner 0")
    assert errors[1] == f"{mesh}:{lines[1]}: element 12 repeats a node: [2, 3, 8, 7, 12, 13, " \
                        "18, 18]"
    assert errors[2].startswith(f"{mesh}:{lines[3]}: element 14 is inverted at its corner 0")
    assert errors[3] == f"{case}: 3 errors"


@pytest.mark.parametrize(("element", "discretization", "said"), [
    ("solid-shell", "node", "contact discretization node (node-to-surface)"),
    ("hexahedron", "surface", "contact discretization surface (surface-to-surface, 2 x 2 "
     "points per blank face)")])
def test_check_names_the_element_and_the_contact_discretization(
        tmp_path: Path, element: str, discretization: str, said: str) -> None:
    case = copy_example("bending", tmp_path)
    mesh = case / "mesh.dat"
    mesh.write_text(mesh.read_text() + f"element {element}\n")
    edit(case, "tools.dat", "  contact      top", f"  discretization {discretization}\n"
         "  contact      top")
    result = check(str(case))
    assert result.returncode == 0, result.stderr
    assert f", element {element} (8-node " in result.stdout
    assert "tool punch: nagata, punch.tool, friction 0.148, contacts the top of the blank, " \
        f"{said}" in result.stdout
