"""ddpy convert: Abaqus / CalculiX forming models to case folders (docs/abaqus-import.md).

The example deck's round trip (mesh, material, tools, phases against the deck's numbers),
malformed variants refused at their file:line, *INCLUDE, an Abaqus deck with R3D4 tools and
symmetry by type, and the command line."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from ddpy.app.cli import main
from ddpy.app.convert import convert_inp
from ddpy.io.case import DeckError
from ddpy.io.decks import read_case
from ddpy.io.inp_model import read_inp
from ddpy.io.toolfile import read_tool
from ddpy.model.material import HardeningTable

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "calculix_bending"
FILES = ("bending.inp", "blank.inp", "punch.inp", "die.inp")


@pytest.fixture
def deck(tmp_path: Path) -> Path:
    """A copy of the example deck and its included meshes."""
    for name in FILES:
        shutil.copy(EXAMPLE / name, tmp_path / name)
    return tmp_path / "bending.inp"


def _nodes(path: Path) -> dict[int, tuple[float, ...]]:
    """The *NODE lines of a file, read independently of the importer."""
    nodes, inside = {}, False
    for line in path.read_text().splitlines():
        if line.startswith("*"):
            inside = line.upper().startswith("*NODE") and "PRINT" not in line.upper()
        elif inside and line.strip() and not line.startswith("**"):
            words = line.split(",")
            nodes[int(words[0])] = tuple(float(w) for w in words[1:4])
    return nodes


def _edit(path: Path, old: str, new: str) -> int:
    """Replace the first ``old`` in the file; return the (1-based) line it was on."""
    text = path.read_text()
    at = text.index(old)
    path.write_text(text[:at] + new + text[at + len(old):])
    return text[:at].count("\n") + 1


def test_the_example_meshes_are_make_mesh_s() -> None:
    # The example's mesh files are written by its make_mesh.py: the committed ones must be
    # what it writes (edit the script, not the meshes).
    import importlib.util

    spec = importlib.util.spec_from_file_location("calculix_make_mesh",
                                                  EXAMPLE / "make_mesh.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    for name, text in (("blank.inp", module.blank()), ("punch.inp", module.punch()),
                       ("die.inp", module.die())):
        assert (EXAMPLE / name).read_text() == text, name


def test_example_round_trip(deck: Path, tmp_path: Path) -> None:
    case_dir = tmp_path / "case"
    done = convert_inp(deck, case_dir)
    assert main(["check", str(case_dir)]) == 0
    case = read_case(case_dir)
    # Mesh: the blank's 186 nodes at the deck's coordinates, its 60 C3D8I as solid-shells.
    nodes = _nodes(EXAMPLE / "blank.inp")
    mesh = case.mesh
    assert mesh.n_nodes == 186 and mesh.n_elements == 60
    np.testing.assert_array_equal(mesh.node_ids, sorted(nodes))
    np.testing.assert_allclose(mesh.nodes, [nodes[i] for i in sorted(nodes)])
    assert case.element == "solid-shell"
    assert tuple(mesh.normal) == (0.0, 0.0, 1.0)
    assert mesh.elements[0].tolist() == [mesh.index([n])[0] for n in (1, 2, 33, 32, 63, 64,
                                                                         95, 94)]
    # Material: E, nu and the *PLASTIC table (stress, strain) as (strain, stress).
    material = case.material.material
    assert (material.E, material.nu) == (210000.0, 0.3)
    assert material.hardening == HardeningTable((0.0, 0.02, 0.05, 0.1, 0.2, 0.5),
                                                (200.0, 260.0, 300.0, 340.0, 380.0, 440.0))
    np.testing.assert_allclose(material.yield_stress([0.01, 0.35, 1.0]), [230.0, 410.0, 440.0])
    # Tools: the S2 faces of the tool bricks, friction, the blank side from the slave surface.
    punch, die = case.tool("punch"), case.tool("die")
    assert (punch.friction, punch.side, punch.discretization) == (0.1, "top", "surface")
    assert (die.friction, die.side, die.discretization) == (0.1, "bottom", "surface")
    assert punch.description == "facets" and punch.file.name == "punch.facets.tool"
    model = read_tool(case_dir / "tools" / "punch.facets.tool")
    assert model.surface.n_patches == 8                     # 6 on the radius, 2 on the flank
    assert read_tool(case_dir / "tools" / "die.nagata.tool").surface.n_patches == 12
    punch_nodes = _nodes(EXAMPLE / "punch.inp")
    front = {xyz for n, xyz in punch_nodes.items() if n % 2 == 0}    # the working face
    vertices = {tuple(v) for v in np.round(model.surface.vertices, 9)}
    assert vertices == {tuple(np.round(v, 9)) for v in front}
    # Phases: the forming step moves the punch 6 mm down, largest increment 0.02 of it; the
    # release step is a springback in 0.25 steps of the period.
    forming, springback = case.phases
    assert (forming.name, forming.kind, forming.tools) == ("step1", "forming", ("punch", "die"))
    np.testing.assert_allclose(forming.displacement("punch"), [0.0, 0.0, -6.0])
    assert forming.max_increment == pytest.approx(0.12)
    assert forming.min_increment == pytest.approx(6e-5)
    assert (springback.kind, springback.increments) == ("springback", 4)
    # Boundary: x symmetry, plane strain, the centre held in the release step only.
    bc = case.boundary
    assert sorted(bc.nodesets) == ["centre", "xsym", "ysym"]
    xsym = mesh.node_ids[bc.nodesets["xsym"].nodes]
    assert sorted(xsym.tolist()) == [n for n, xyz in nodes.items() if xyz[0] == 0.0]
    held = {(c.label, c.components, c.phases) for c in bc.constraints}
    assert held == {("fix xsym x", (0,), ()), ("fix ysym y", (1,), ()),
                    ("fix centre z", (2,), ("step2",))}
    assert any(f.endswith("*NODE PRINT") for f in done.notes)


def test_nagata_tools_name_the_nagata_files(deck: Path, tmp_path: Path) -> None:
    convert_inp(deck, tmp_path / "case", tools="nagata")
    case = read_case(tmp_path / "case")
    assert [t.description for t in case.tools] == ["nagata", "nagata"]
    assert case.tool("die").file.name == "die.nagata.tool"


@pytest.mark.parametrize(("file", "old", "new", "message", "below"), [
    ("bending.inp", "*MATERIAL, NAME=STEEL", "*ORIENTATION, NAME=O\n1., 0., 0., 0., 1., 0.\n"
     "*MATERIAL, NAME=STEEL", "keyword *ORIENTATION is not supported: write the rolling "
     "direction in material.dat", 0),
    ("blank.inp", "*ELEMENT, TYPE=C3D8I", "*ELEMENT, TYPE=C3D20R",
     "element type C3D20R is not supported: expected TYPE= C3D8, C3D8R, C3D8I", 0),
    ("blank.inp", "1, 1, 2, 33, 32, 63, 64, 95, 94", "1, 1, 2, 33, 32, 63, 64, 95, 9999",
     "node 9999 of element 1 is not defined", 0),
    ("blank.inp", "2, 1, 0, 0", "2, 1.0.0, 0, 0", "expected a number for a coordinate, got "
     "'1.0.0'", 0),
    ("bending.inp", "*STEP, NLGEOM, INC=1000", "*STEP, NLGEOM, INC=1000, PERTURBATION",
     "parameter PERTURBATION of *STEP is not supported", 0),
    ("bending.inp", "*PLASTIC\n200., 0.0", "*PLASTIC\n200., 0.01",
     "the table's first plastic strain must be 0", 1),
    ("bending.inp", "*BOUNDARY, FIXED\nCENTRE, 3, 3", "*BOUNDARY\nCENTRE, 3, 3",
     "expected *BOUNDARY, FIXED", 1),
    ("bending.inp", "0.1, 5000.", "-0.1, 5000.", "friction must be >= 0, got -0.1", 0),
])
def test_malformed_decks_are_refused_at_their_line(deck: Path, file: str, old: str, new: str,
                                                   message: str, below: int) -> None:
    """Each refused at the line it is on (``below``: lines below the start of ``old``)."""
    line = _edit(deck.parent / file, old, new) + below
    with pytest.raises(DeckError) as caught:
        read_inp(deck)
    error = caught.value.errors[0]
    assert message in error.message, str(caught.value)
    assert error.path == deck.parent / file
    assert error.line == line, str(caught.value)


def test_every_defect_is_reported(deck: Path) -> None:
    _edit(deck, "*MATERIAL, NAME=STEEL", "*ORIENTATION, NAME=O\n*MATERIAL, NAME=STEEL")
    _edit(deck, "*STEP, NLGEOM, INC=1000", "*STEP, NLGEOM, INC=1000, PERTURBATION")
    with pytest.raises(DeckError) as caught:
        read_inp(deck)
    assert len(caught.value.errors) == 2
    assert "*ORIENTATION" in str(caught.value) and "PERTURBATION" in str(caught.value)


def test_include(deck: Path, tmp_path: Path) -> None:
    # A missing file: refused at the *INCLUDE line.
    line = _edit(deck, "*INCLUDE, INPUT=die.inp", "*INCLUDE, INPUT=nowhere/die.inp")
    with pytest.raises(DeckError) as caught:
        read_inp(deck)
    assert (caught.value.path, caught.value.line) == (deck, line)
    assert "no such file" in caught.value.message
    # Nested and in a subfolder, relative to the including file.
    (tmp_path / "nowhere").mkdir()
    (tmp_path / "nowhere" / "die.inp").write_text("*INCLUDE, INPUT=../die.inp\n")
    model = read_inp(deck)
    assert [t.name for t in model.tools] == ["punch", "die"]
    # A file including itself.
    (tmp_path / "die.inp").write_text("*INCLUDE, INPUT=nowhere/die.inp\n")
    with pytest.raises(DeckError, match="include itself"):
        read_inp(deck)


ABAQUS = """*HEADING
Flat punch on a flat die, R3D4 tools
*NODE
1, 0, 0, 0
2, 2, 0, 0
3, 2, 2, 0
4, 0, 2, 0
5, 0, 0, 1
6, 2, 0, 1
7, 2, 2, 1
8, 0, 2, 1
*ELEMENT, TYPE=C3D8R, ELSET=BLANK
1, 1, 2, 3, 4, 5, 6, 7, 8
*NSET, NSET=SYM_X, GENERATE
1, 5, 4
*NSET, NSET=SYM_X
8, 4
*NSET, NSET=SYM_Y
1, 2, 5, 6
*NODE
101, -1, -1, 1.001
102, 3, -1, 1.001
103, 3, 3, 1.001
104, -1, 3, 1.001
201, -1, -1, -0.001
202, 3, -1, -0.001
203, 3, 3, -0.001
204, -1, 3, -0.001
900, 0, 0, 2
901, 0, 0, -1
*ELEMENT, TYPE=R3D4, ELSET=PUNCH
11, 101, 102, 103, 104
*ELEMENT, TYPE=R3D4, ELSET=DIE
21, 201, 202, 203, 204
*MATERIAL, NAME=AL
*ELASTIC
70000., 0.33
*PLASTIC
100., 0.
150., 0.1
*DENSITY
2.7e-9
*SOLID SECTION, ELSET=BLANK, MATERIAL=AL
*RIGID BODY, ELSET=PUNCH, REF NODE=900
*RIGID BODY, ELSET=DIE, REF NODE=901
*SURFACE, NAME=TOP
BLANK, S2
*SURFACE, NAME=BOTTOM
BLANK, S1
*SURFACE, NAME=PUNCH_S
PUNCH, SNEG
*SURFACE, NAME=DIE_S
DIE
*CONTACT PAIR, INTERACTION=FRIC
TOP, PUNCH_S
BOTTOM, DIE_S
*SURFACE INTERACTION, NAME=FRIC
*FRICTION
0.15
*BOUNDARY
SYM_X, XSYMM
SYM_Y, YSYMM
901, ENCASTRE
900, 4, 6
*STEP, NAME=Press, NLGEOM=YES
*STATIC
0.1, 1.
*BOUNDARY
900, 1, 2
900, 3, 3, -0.1
*OUTPUT, FIELD
*NODE OUTPUT
U, RF
*END STEP
"""


def test_abaqus_r3d4_deck(tmp_path: Path) -> None:
    path = tmp_path / "flat.inp"
    path.write_text(ABAQUS)
    model = read_inp(path)
    assert model.title == "Flat punch on a flat die, R3D4 tools"
    assert model.element_type == "C3D8R" and model.normal == "z"
    assert model.hardening == [(0.0, 100.0), (0.1, 150.0)]
    punch, die = model.tools
    assert (punch.name, punch.side, punch.friction, punch.discretization) == \
        ("punch", "top", 0.15, "node")
    assert punch.faces == [[104, 103, 102, 101]]           # SNEG: turned over
    assert die.faces == [[201, 202, 203, 204]] and die.side == "bottom"
    assert model.nodesets == {"sym_x": [1, 4, 5, 8], "sym_y": [1, 2, 5, 6]}
    assert model.constraints == [("sym_x", "x", ()), ("sym_y", "y", ())]
    (phase,) = model.phases
    assert (phase.name, phase.kind, phase.moves) == ("press", "forming",
                                                     {"punch": (0.0, 0.0, -0.1)})
    assert any("*DENSITY" in n for n in model.ignored)
    assert any("*NODE OUTPUT" in n for n in model.ignored)
    assert any("rotations of blank nodes" in n for n in model.ignored)
    convert_inp(path, tmp_path / "case")
    case = read_case(tmp_path / "case")
    assert case.element == "hexahedron"
    assert case.material.material.hardening.stresses == (100.0, 150.0)


@pytest.mark.parametrize(("old", "new", "message"), [
    ("900, 3, 3, -0.1\n", "", "tool punch (REF NODE 900) has no *BOUNDARY on dof 3"),
    ("900, 4, 6\n", "900, 4, 4, 0.1\n", "a rotation of tool punch"),
    ("*STEP, NAME=Press, NLGEOM=YES", "*STEP, NAME=Press", "the first *STEP without NLGEOM"),
    ("SYM_Y, YSYMM", "SYM_Y, 2, 2, 0.5", "a displacement of 0.5 on blank nodes"),
    ("*ELASTIC\n70000., 0.33", "*ELASTIC\n70000., 0.33, 20.", "expected one data line 'E, nu'"),
    ("TOP, PUNCH_S\n", "PUNCH_S, TOP\n", "the slave surface PUNCH_S is not on the blank"),
    ("DIE\n*CONTACT", "DIE, S3\n*CONTACT", "expected SPOS or SNEG for the R3D4 element"),
])
def test_abaqus_refusals(tmp_path: Path, old: str, new: str, message: str) -> None:
    path = tmp_path / "flat.inp"
    assert old in ABAQUS
    path.write_text(ABAQUS.replace(old, new, 1))
    with pytest.raises(DeckError) as caught:
        read_inp(path)
    assert message in str(caught.value)
    assert caught.value.path == path and caught.value.line is not None


def test_convert_command(deck: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["convert", str(deck), str(tmp_path / "case")]) == 0
    out = capsys.readouterr().out
    assert "ignored: " in out and "*NODE PRINT" in out and ": ok" in out
    # An occupied folder needs --force.
    assert main(["convert", str(deck), str(tmp_path / "case")]) == 2
    assert "not empty" in capsys.readouterr().err
    assert main(["convert", str(deck), str(tmp_path / "case"), "--force", "--tools",
                 "nagata"]) == 0
    _edit(deck, "*MATERIAL, NAME=STEEL", "*ORIENTATION, NAME=O\n*MATERIAL, NAME=STEEL")
    assert main(["convert", str(deck), str(tmp_path / "other")]) == 2
    err = capsys.readouterr().err
    assert f"{deck}:26: keyword *ORIENTATION is not supported" in err
    assert not (tmp_path / "other").exists()


def test_run_converts_beside_the_file(deck: Path, tmp_path: Path, monkeypatch:
                                      pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(deck), "--threads", "1", "--stop-after", "2"]) == 0
    assert (tmp_path / "bending_case" / "tools.dat").is_file()
    assert (tmp_path / "results" / "bending_case" / "results.h5").is_file()


def test_run_reuses_the_case_only_while_the_input_file_is_unchanged(
        deck: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    case = tmp_path / "bending_case"
    assert main(["convert", str(deck), str(case)]) == 0
    # An edit of the case is the user's: ddpy run MODEL.inp runs the case as it is.
    control = case / "control.dat"
    control.write_text(control.read_text() + "# edited by hand\n")
    capsys.readouterr()
    run = ["run", str(deck), "--threads", "1", "--stop-after", "1"]
    assert main([*run, "--output", str(tmp_path / "r1")]) == 0
    assert "as it is now: running it" in capsys.readouterr().out
    assert control.read_text().endswith("# edited by hand\n")
    # Other options than the conversion's: refused, the case left alone.
    assert main([*run, "--tools", "nagata", "--output", str(tmp_path / "r2")]) == 2
    assert "was converted with --tools facets" in capsys.readouterr().err
    # An included file changed: refused as ddpy convert refuses an occupied folder.
    _edit(deck.parent / "die.inp", "** The die", "** The die, edited")
    assert main([*run, "--output", str(tmp_path / "r3")]) == 2
    err = capsys.readouterr().err
    assert f"{deck} changed since {case} was converted from it" in err and "--force" in err
    assert control.read_text().endswith("# edited by hand\n")
    assert not (tmp_path / "r3").exists()


MATERIAL = """elastic E 210000 nu 0.3
yield vonmises
hardening table 3   # plastic strain, yield stress
  0 200
  0.1 250
  0.3 280
"""


@pytest.mark.parametrize(("old", "new", "line", "message"), [
    ("0.3 280", "0.3 x", 6, "expected a number for the yield stress Y"),
    ("0.1 250", "0.1 150", 5, "softening is not supported"),
    ("0 200", "0.01 200", 4, "the table's first plastic strain must be 0"),
    ("0.3 280", "0.05 280", 6, "must be above the one before"),
    ("table 3", "table 0", 3, "the number of points of the table must be >= 1"),
    ("  0.3 280\n", "", None, "the deck ends inside the hardening table of line 3"),
])
def test_material_deck_hardening_table(tmp_path: Path, old: str, new: str, line: int | None,
                                       message: str) -> None:
    """material.dat's 'hardening table COUNT' and its COUNT lines 'EP Y': the values by hand,
    and each defect at its line."""
    from ddpy.io.decks.lines import Deck
    from ddpy.io.decks.material import _parse_material

    good = _parse_material(Deck(tmp_path / "material.dat", MATERIAL))
    assert good is not None
    np.testing.assert_allclose(good.material.yield_stress([0.0, 0.05, 0.2, 0.3, 2.0]),
                               [200.0, 225.0, 265.0, 280.0, 280.0])
    deck = Deck(tmp_path / "material.dat", MATERIAL.replace(old, new))
    assert _parse_material(deck) is None
    assert message in deck.errors[0].message
    assert deck.errors[0].line == line


#: MATERIAL with a perfectly plastic plateau: 250 MPa from ep = 0.1 on (lines 5 to 7).
PLATEAU = MATERIAL.replace("table 3", "table 4").replace("  0.3 280\n", "  0.3 250\n  0.5 250\n")


def test_material_deck_accepts_a_plateau_and_refuses_a_decrease_at_its_line(
        tmp_path: Path) -> None:
    """Tabulated hardening may stay level (a perfectly plastic stretch: equal stresses on
    rows that follow each other) but never fall: a decrease is refused at its row's line.
    Through the whole case: the table's reader, HardeningTable and the core's check."""
    case = tmp_path / "case"
    shutil.copytree(ROOT / "examples" / "bending", case)
    (case / "material.dat").write_text(PLATEAU)
    material = read_case(case).material.material
    assert material.hardening == HardeningTable((0.0, 0.1, 0.3, 0.5),
                                                (200.0, 250.0, 250.0, 250.0))
    np.testing.assert_allclose(material.hardening_curve([0.05, 0.2, 0.4, 2.0]),
                               [[225.0, 250.0, 250.0, 250.0], [500.0, 0.0, 0.0, 0.0]])
    # On the plateau the return mapping lands on 250 MPa: uniaxial strain far beyond yield.
    stress, ep, _, plastic = material.update(np.zeros(6), 0.2, [0.05, -0.025, -0.025, 0, 0, 0])
    assert plastic and ep > 0.2
    assert stress[0] - stress[1] == pytest.approx(250.0, rel=1e-10)
    (case / "material.dat").write_text(PLATEAU.replace("0.5 250", "0.5 249.99"))
    with pytest.raises(DeckError) as caught:
        read_case(case)
    error = caught.value.errors[0]
    assert (error.path.name, error.line) == ("material.dat", 7), str(caught.value)
    assert "yield stress 4 of the table (249.99) is below the one before (250): softening" \
        in error.message


def test_plastic_card_accepts_a_plateau_and_refuses_a_decrease_at_its_line(deck: Path
                                                                           ) -> None:
    """*PLASTIC likewise: a row at the stress of the row before is a perfectly plastic
    stretch, accepted; one below it is refused at its line."""
    line = _edit(deck, "300., 0.05", "260., 0.05")
    model = read_inp(deck)
    assert model.hardening[:4] == [(0.0, 200.0), (0.02, 260.0), (0.05, 260.0), (0.1, 340.0)]
    _edit(deck, "260., 0.05", "259.9, 0.05")
    with pytest.raises(DeckError) as caught:
        read_inp(deck)
    error = caught.value.errors[0]
    assert (error.path, error.line) == (deck, line), str(caught.value)
    assert "yield stress 3 of the table (259.9) is below the one before (260)" in error.message


def test_rigid_body_by_node_set(tmp_path: Path) -> None:
    """CalculiX's form: *RIGID BODY, NSET= names the tool's nodes."""
    path = tmp_path / "flat.inp"
    path.write_text(ABAQUS.replace("*RIGID BODY, ELSET=PUNCH, REF NODE=900",
                                   "*NSET, NSET=PUNCH_N\n101, 102, 103, 104\n"
                                   "*RIGID BODY, NSET=PUNCH_N, REF NODE=900"))
    model = read_inp(path)
    assert [t.name for t in model.tools] == ["punch_n", "die"]
    assert model.phases[0].moves == {"punch_n": (0.0, 0.0, -0.1)}


CAE_DECK = Path(__file__).parent / "data" / "cae_bending.inp"


def _tool_points(path: Path) -> np.ndarray:
    lines = path.read_text().splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("vertices"))
    count = int(lines[at].split()[1])
    return np.array([[float(v) for v in line.split()] for line in lines[at + 1:at + 1 + count]])


def test_cae_deck_of_parts_and_instances_converts_and_runs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """tests/data/cae_bending.inp, as Abaqus/CAE writes a model: two parts, a punch and a die
    that are two instances of one rigid part (the die's turned over by its rotation line),
    sets named through their instance, tabular amplitudes on the tools' motions."""
    case = tmp_path / "case"
    assert main(["convert", str(CAE_DECK), str(case)]) == 0
    capsys.readouterr()
    # The strip is the first instance: its node k is 1000 + k (docs/abaqus-import.md).
    mesh = (case / "mesh.dat").read_text()
    assert "\n  1001 0 0 0\n" in mesh and "\n  1078 12 2 1\n" in mesh
    assert "nodeset  strip-1.xsym  ids 1001 1014 1027 1040 1053 1066" in \
        (case / "bc.dat").read_text()
    # The die: the roller translated by (-8, 0, 0), then turned 180 degrees about y: its
    # nose up at x = 8, z = 0, the rest of it below and to either side.
    die = _tool_points(case / "tools" / "die.facets.tool")
    assert np.isclose(die[:, 2].max(), 0.0, atol=1e-9)
    np.testing.assert_allclose(die[np.argmax(die[:, 2]), [0, 2]], [8.0, 0.0], atol=1e-9)
    assert die[:, 2].min() == pytest.approx(-3.0) and die[:, 0].min() == pytest.approx(5.0)
    punch = _tool_points(case / "tools" / "punch.facets.tool")
    assert punch[:, 2].min() == pytest.approx(1.0) and punch[:, 0].max() == pytest.approx(3.0)
    # The die's amplitude starts at half the step: two phases, the die rising in the second.
    control = (case / "control.dat").read_text()
    assert "phase bend_1" in control and "phase bend_2" in control
    first, second = control.split("phase bend_2")
    assert "move   punch  0 0 -1\n" in first and "move   die" not in first.split("bend_1")[1]
    assert "move   punch  0 0 -1\n" in second and "move   die  0 0 0.5\n" in second
    assert main(["run", str(case), "--threads", "1", "--output", str(tmp_path / "out")]) == 0
    assert "completed" in capsys.readouterr().out


def test_an_unsupported_keyword_is_reported_once_with_its_lines(tmp_path: Path) -> None:
    deck = tmp_path / "cae.inp"
    text = CAE_DECK.read_text().replace(
        "*End Part", "*Orientation, name=Ori-1\n1., 0., 0., 0., 1., 0.\n*End Part")
    deck.write_text(text)
    lines = [i + 1 for i, line in enumerate(text.splitlines()) if line.startswith("*Orient")]
    with pytest.raises(DeckError) as caught:
        read_inp(deck)
    assert len(caught.value.errors) == 1, str(caught.value)
    error = caught.value.errors[0]
    assert (error.path, error.line) == (deck, lines[0])
    assert f"keyword *ORIENTATION is not supported (also at {deck}:{lines[1]}): write the " \
        "rolling direction in material.dat" in error.message
    assert "*HEADING" not in error.message


@pytest.mark.parametrize(("old", "new", "message"), [
    ("          0.,           0.,           0.,           0.,           1.,           0., 180.",
     "          0.,           0.,           0.,           0.,           0.,           0., 180.",
     "the rotation axis of *INSTANCE goes through two equal points"),
    ("*Instance, name=Die-1, part=Roller", "*Instance, name=Die-1, part=Wheel",
     "no *PART named WHEEL before this *INSTANCE"),
    ("*Rigid Body, ref node=Die-1.Roller-RefPt_", "*Rigid Body, ref node=Die-2.Roller-RefPt_",
     "no node set named DIE-2.ROLLER-REFPT_"),
    ("*Boundary, amplitude=Late", "*Boundary, amplitude=Later",
     "AMPLITUDE=LATER: no *AMPLITUDE of that name before this card"),
    ("0.,              0.,             0.5,              0.,              1.,              1.",
     "0.,              1.,             0.5,              0.,              1.,              1.",
     "AMPLITUDE=LATE puts tool die at 0.5 mm along z at the start of the step, where it is at"),
])
def test_cae_deck_defects_are_refused_at_their_line(tmp_path: Path, old: str, new: str,
                                                    message: str) -> None:
    deck = tmp_path / "cae.inp"
    deck.write_text(CAE_DECK.read_text())
    line = _edit(deck, old, new)
    with pytest.raises(DeckError) as caught:
        read_inp(deck)
    error = caught.value.errors[0]
    assert message in error.message, str(caught.value)
    assert error.path == deck
    if "AMPLITUDE=LATE " not in message:
        assert error.line == line, str(caught.value)


NUMISHEET = Path(__file__).resolve().parents[1] / "examples" / "numisheet2002_bending"
#: The springs' stiffness in its deck (N/mm; make_deck.py's SPRING).
SPRING_STIFFNESS = 1e-3


def test_numisheet_2002_calculix_deck_with_springs_converts_and_runs(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """examples/numisheet2002_bending/bending.inp: the benchmark's CalculiX deck, whose
    SPRING2 elements hold the blank's rigid-body mode along z until the tools grip it."""
    deck = tmp_path / "bending.inp"
    shutil.copy(NUMISHEET / "bending.inp", deck)
    spring = deck.read_text().splitlines().index("*ELEMENT, TYPE=SPRING2, ELSET=HOLD") + 1
    case = tmp_path / "case"
    assert main(["convert", str(deck), str(case)]) == 0
    out = capsys.readouterr().out
    assert f"ignored: {deck}:{spring}: 4 SPRING2 element(s), skipped" in out
    assert (f"ignored: {deck}:{spring + 5}: *SPRING (its elements are skipped): stiffness "
            f"{SPRING_STIFFNESS:g} each") in out
    # The ground nodes are not the blank's; the blank is the 30 x 3 x 2 hexahedra.
    mesh = (case / "mesh.dat").read_text()
    assert "nodes 372\n" in mesh and "hexahedra 180\n" in mesh and "\n  9100 " not in mesh
    assert "move   punch  0 0 -28.5" in (case / "control.dat").read_text()
    assert main(["run", str(case), "--threads", "1", "--stop-after", "3", "--output",
                 str(tmp_path / "out")]) == 0
    assert "stopped after 3 increments" in capsys.readouterr().out


def test_a_spring_between_blank_nodes_is_refused(tmp_path: Path) -> None:
    deck = tmp_path / "bending.inp"
    shutil.copy(NUMISHEET / "bending.inp", deck)
    line = _edit(deck, "9100, 1, 9100", "9100, 1, 2")
    with pytest.raises(DeckError) as caught:
        read_inp(deck)
    error = caught.value.errors[0]
    assert (error.path, error.line) == (deck, line)
    assert "a SPRING2 element between blank nodes 1, 2: it would carry load" in error.message


@pytest.mark.parametrize(("model", "mesh_file", "names"), [
    ("bending.inp", "blank.inp", ("xsym", "ysym", "centre")),
    ("cae", "cae", ("strip-1.xsym", "strip-1.ysym", "strip-1.centre"))])
def test_mesh_file_and_convert_keep_the_same_ids_and_set_names(
        deck: Path, tmp_path: Path, model: str, mesh_file: str, names: tuple[str, ...]) -> None:
    """mesh.dat's 'file X.inp' reads the blank as ddpy convert does: Abaqus node and
    element ids (an assembly's numbered by instance), node sets named as bc.dat names them."""
    source = CAE_DECK if model == "cae" else deck
    converted = read_case(convert_inp(source, tmp_path / "converted").folder)
    case = tmp_path / "file"
    shutil.copytree(tmp_path / "converted", case)
    text = (case / "mesh.dat").read_text()
    path = CAE_DECK if mesh_file == "cae" else deck.parent / mesh_file
    (case / "mesh.dat").write_text(text[:text.index("nodes ")] + f"file {path}\n")
    bc = (case / "bc.dat").read_text().splitlines()
    # The file's node sets stand for the converted ones: same names, same nodes.
    (case / "bc.dat").write_text("\n".join(x for x in bc if not x.startswith("nodeset")) + "\n")
    from_file = read_case(case)
    np.testing.assert_array_equal(from_file.mesh.node_ids, converted.mesh.node_ids)
    np.testing.assert_array_equal(from_file.mesh.element_ids, converted.mesh.element_ids)
    np.testing.assert_allclose(from_file.mesh.nodes, converted.mesh.nodes)
    for name in names:
        np.testing.assert_array_equal(from_file.boundary.nodesets[name].nodes,
                                      converted.boundary.nodesets[name].nodes)


def test_tool_mesh_of_an_assembly_is_the_tool_convert_writes(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """ddpy tools build reads an .inp file as ddpy convert does: the die instance of the CAE
    deck, turned over by its rotation, gives the same faces on both paths."""
    assert main(["convert", str(CAE_DECK), str(tmp_path / "case")]) == 0
    assert main(["tools", "build", str(CAE_DECK), "--groups", "Die-1.Face", "--out",
                 str(tmp_path / "built")]) == 0
    capsys.readouterr()
    converted = _tool_points(tmp_path / "case" / "tools" / "die.facets.tool")
    built = _tool_points(tmp_path / "built" / "cae_bending.facets.tool")
    np.testing.assert_allclose(np.unique(built, axis=0), np.unique(converted, axis=0),
                               atol=1e-9)


@pytest.mark.parametrize(("ramp", "moves"), [
    # Down 2.5 mm by half the step, then back up 0.5 mm while the die rises.
    ("0., 0., 0.5, 1.25, 1., 1.", [{"punch": (0, 0, -2.5)},
                                   {"punch": (0, 0, 0.5), "die": (0, 0, 0.5)}]),
    # The punch's speed changes at 0.25 (no new phase for that) and it dwells from 0.5.
    ("0., 0., 0.25, 0.75, 0.5, 1., 1., 1.", [{"punch": (0, 0, -2.0)}, {"die": (0, 0, 0.5)}]),
    # In total time (one step of period 1 before nothing: the same as step time).
    ("0., 0., 1., 1.", [{"punch": (0, 0, -1.0)},
                        {"punch": (0, 0, -1.0), "die": (0, 0, 0.5)}]),
])
def test_amplitudes_make_one_phase_per_straight_stretch(tmp_path: Path, ramp: str,
                                                        moves: list[dict]) -> None:
    deck = tmp_path / "cae.inp"
    text = CAE_DECK.read_text().replace(
        "*Amplitude, name=Ramp\n             0.,              0.,              1.,"
        "              1.", f"*Amplitude, name=Ramp\n{ramp}")
    if ramp == "0., 0., 1., 1.":
        text = text.replace("*Amplitude, name=Ramp", "*Amplitude, name=Ramp, time=TOTAL TIME")
    deck.write_text(text)
    model = read_inp(deck)
    forming = [p for p in model.phases if p.kind == "forming"]
    assert [p.moves for p in forming] == moves
    assert [p.name for p in forming] == ["bend_1", "bend_2"]
