"""Input decks: every keyword, the validated model, and the error messages (file:line)."""

from __future__ import annotations

import math
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from deckutil import (
    EXAMPLES,
    UPSIDE_DOWN,
    copy_example,
    edit,
    install_toolfile,
    row_mesh_deck,
)

from ddpy.io.case import HoldGap, Move, rigid_body_modes_free
from ddpy.io.decks import DeckError, parse_case, read_case
from ddpy.model.control import IncrementLimits, NewtonSettings
from ddpy.model.material import Hill48, Swift, Voce
from ddpy.model.mesh import MAX_ELEMENTS

BUILT_IN = Path(__file__).resolve().parents[1] / "ddpy" / "cases" / "cylindrical_bending"


def error_of(case: Path, geometry: bool = False) -> DeckError:
    with pytest.raises(DeckError) as info:
        read_case(case, geometry=geometry)
    return info.value


def line_of(case: Path, deck: str, text: str) -> int:
    lines = (case / deck).read_text().splitlines()
    return next(k for k, line in enumerate(lines, start=1) if text in line)


# ----------------------------------------------------------------------------------- examples


def test_bending_example_model() -> None:
    case = read_case(EXAMPLES / "bending")
    assert case.title.startswith("Unconstrained cylindrical bending")
    forming, springback = case.phases
    assert forming.kind == "forming" and forming.tools == ("punch", "die")
    assert forming.motions == (Move("punch", (0.0, 0.0, -28.5), forming.motions[0].origin),)
    assert forming.motions[0].origin.endswith("control.dat:21")
    assert forming.lead == "punch" and forming.travel == pytest.approx(28.5)
    assert forming.max_increment == 0.114 and forming.min_increment == pytest.approx(0.114e-3)
    assert forming.output_at == (7.0, 14.0, 21.0, 28.5) and forming.output_every == 25
    # min_fraction is min_increment over max_increment, to rounding
    assert forming.limits.min_fraction == pytest.approx(1e-3, rel=1e-12)
    assert replace(forming.limits, min_fraction=1e-3) == IncrementLimits(0.02, 1.0, 0.1, True)
    assert forming.newton == NewtonSettings(1e-3, 1e-3, 25, 0.5)
    np.testing.assert_array_equal(forming.displacement("die"), [0, 0, 0])
    assert springback.is_springback and springback.increments == 1 and springback.tools == ()
    mesh = case.mesh
    assert (mesh.n_nodes, mesh.n_elements) == (25 * 4 * 4, 24 * 3 * 3)
    assert mesh.normal == (0.0, 0.0, 1.0) and mesh.elements.dtype == np.int32
    assert not mesh.nodes.flags.writeable
    np.testing.assert_allclose(mesh.thickness(), 1.0)
    mat = case.material.material
    assert mat.E == 210000 and mat.nu == 0.3 and mat.hardening == Swift(645.3, 0.0102, 0.252)
    assert mat.yield_criterion == Hill48(F=0.254, G=0.397, H=0.603, L=1.5, M=1.5, N=1.689)
    punch, die = case.tools
    assert (punch.name, punch.description, punch.friction, punch.side) == (
        "punch", "nagata", 0.148, "top")
    assert punch.file == EXAMPLES / "bending" / "tools" / "punch.tool"
    assert die.facing == (0.0, 0.0, -1.0) and die.augmentation is None
    np.testing.assert_allclose(mesh.nodes[punch.contact_nodes(mesh), 2], 1.0)
    np.testing.assert_allclose(mesh.nodes[die.contact_nodes(mesh), 2], 0.0)
    # constraints: symmetry x, y always; the centre line in z only in springback
    nodes, comps = case.boundary.constrained("forming")
    assert set(comps.tolist()) == {0, 1}
    np.testing.assert_allclose(mesh.nodes[nodes[comps == 0], 0], 0.0)
    nodes, comps = case.boundary.constrained("springback")
    centre = mesh.nodes[nodes[comps == 2]]
    np.testing.assert_allclose(centre[:, :2], 0.0)
    assert len(centre) == 4
    assert rigid_body_modes_free(mesh.nodes, case.boundary.dofs("springback")) == []
    assert rigid_body_modes_free(mesh.nodes, case.boundary.dofs("forming")) == [
        "translation along z"]
    assert "punch by (0, 0, -28.5)" in case.summary() and case.warnings == ()


def test_strip_draw_example_model() -> None:
    case = read_case(EXAMPLES / "strip_draw")
    draw, free, back = case.phases
    assert isinstance(draw.motion("holder"), HoldGap)
    assert draw.motion("holder") == HoldGap("holder", "die", 1.1, draw.motion("holder").origin)
    np.testing.assert_array_equal(draw.displacement("holder"), [0, 0, 0])  # follows the die
    assert draw.max_increment == 0.2 and draw.min_increment == pytest.approx(2e-4)
    assert free.tools == ("punch", "die") and free.max_increment == 0.1
    assert free.limits.strain == 0.01 and draw.limits.strain == 0.02
    assert back.increments == 4
    assert case.tool("punch").description == "facets"
    assert case.tool("die").augmentation == 1e4 and case.tool("punch").augmentation is None
    assert case.tool("die").side.startswith("surface facing")
    mat = case.material
    assert isinstance(mat.material.hardening, Voce)
    assert mat.material.yield_criterion.r0 == pytest.approx(1.73)
    np.testing.assert_allclose(mat.axes((0, 0, 1)), [[0, 1, 0], [-1, 0, 0], [0, 0, 1]],
                               atol=1e-15)
    sets = case.boundary.nodesets
    np.testing.assert_array_equal(sets["middle"].nodes, sets["corner"].nodes)
    assert case.mesh.node_ids[sets["corner"].nodes].tolist() == [1, 22, 43, 64, 85, 106]
    nodes, comps = case.boundary.constrained("draw")
    assert np.count_nonzero(comps == 1) == 126  # plane strain on every node


def test_geometry_checks_accept_examples(monkeypatch) -> None:
    install_toolfile(monkeypatch)
    for name in ("bending", "strip_draw"):
        case = read_case(EXAMPLES / name)
        assert case.tool("punch").model().surface.n_patches >= 4


def test_parse_case_from_texts() -> None:
    folder = EXAMPLES / "bending"
    texts = {p.name: p.read_text() for p in folder.glob("*.dat")}
    case = parse_case(texts, folder, geometry=False)
    assert case.mesh.n_elements == 216
    with pytest.raises(DeckError, match="missing"):
        parse_case({"control.dat": texts["control.dat"]}, folder)


# ----------------------------------------------------------------------------------- files


def test_missing_folder_and_files(tmp_path: Path) -> None:
    assert "not a case folder" in str(error_of(tmp_path / "nope"))
    case = copy_example("bending", tmp_path)
    (case / "bc.dat").unlink()
    (case / "tools.dat").unlink()
    error = error_of(case)
    assert len(error.errors) == 2 and error.line is None
    assert str(error).startswith(f"{case / 'bc.dat'}: missing")


def test_binary_deck(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    (case / "material.dat").write_bytes(b"elastic \xff\xfe E 1")
    assert "not UTF-8" in str(error_of(case))


def test_several_errors_collected(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "tools.dat", "friction     0.148", "friction     -0.1")
    edit(case, "material.dat", "nu 0.3", "nu 0.7")
    edit(case, "control.dat", "cutback              0.5", "cutback 2")
    error = error_of(case)
    assert len(error.errors) == 3
    text = str(error)
    assert f"tools.dat:{line_of(case, 'tools.dat', '-0.1')}: friction must be >= 0, got -0.1" \
        in text
    assert "Poisson's ratio nu must lie in (-1, 0.5), got 0.7" in text
    assert "cutback must lie in [0.1, 0.9], got 2" in text
    assert error.path == case / "control.dat"  # the first, in reading order


# ----------------------------------------------------------------------------------- control

CONTROL_ERRORS = [
    ("tools     punch die", "tools     punch die press", "unknown tool 'press' in phase"),
    ("tools     punch die", "tools     punch", "moves tool"),  # die not active: fine; see next
    ("move      punch  0 0 -28.5", "move      punch  0 0 -28.5\n  move die 0 0 0", None),
    ("move      punch  0 0 -28.5", "move punch 0 0 0", "moves no tool"),
    ("move      punch  0 0 -28.5", "move punch 0 0", "expected 'move TOOL DX DY DZ'"),
    ("move      punch  0 0 -28.5", "move punch 0 0 nan", "expected a finite number"),
    ("move      punch  0 0 -28.5", "move punch 0 0 1e999", "expected a finite number"),
    ("move      punch  0 0 -28.5", "move punch 0 0 -28.5\n  move punch 0 0 -1",
     "already has a motion"),
    ("lead      punch", "lead      die", "lead tool 'die' must be a tool that moves"),
    ("output_at 7 14 21 28.5", "output_at 7 14 21 30", "beyond the travel 28.5 mm"),
    ("output_at 7 14 21 28.5", "output_at 7 21 14", "must increase strictly"),
    ("type      forming", "type      stamping", "expected the phase type among forming"),
    ("type      forming", "type forming\n  increments 3", "'increments' applies to springback"),
    ("max_increment        0.114", "max_increment -1", "max_increment must be > 0, got -1"),
    ("max_increment        0.114", "max_increment 0.114\nmin_increment 1",
     "min_increment 1 mm over max_increment 0.114 mm: min_fraction (the smallest increment "
     "over the largest) must be at most 1, got 8.77"),
    ("rmin_contact         on", "rmin_contact maybe", "expected rmin_contact among on, off"),
    ("rmin_contact         on", "rmin_contact on\nrmin_touch sometimes",
     "rmin_touch must be one of new, every, got 'sometimes'"),
    ("rmin_contact         on", "rmin_contact on\nrmin_release 2",
     "rmin_release must lie in [0, 1], got 2"),
    ("rmin_rotation        1.0", "rmin_rotation 120",
     "rmin_rotation must lie in [0.001, 90] (degrees)"),
    ("rmin_contact         on", "rmin_contact on\nrmin_release_redos -1",
     "rmin_release_redos must lie in 0..1,000,000 or be off"),
    ("rmin_contact         on", "rmin_contact on\nrmin_release_redos 1.5",
     "expected an integer for rmin_release_redos"),
    ("newton_force         1e-3", "newton_force 0",
     "newton_force must lie in [1e-14, 0.1], got 0"),
    ("max_iterations       25", "max_iterations 2.5", "expected an integer for max_iterations"),
    ("max_iterations       25", "max_iterations 0",
     "max_iterations must be an integer in 1..1000, got 0"),
    ("output_every         25", "output_every 25\noutput_every 5", "given twice (first at line"),
    ("title  Unconstrained", "titel  Unconstrained", "unknown keyword 'titel' at the top"),
    ("  type        springback", "  type springback\n  tools punch",
     "is a springback phase: the tools are removed, so 'tools' does not apply"),
    ("  type        springback", "  type springback\n  move punch 0 0 1", "'move' does not"),
    ("  increments  1", "  increments 0", "increments must be >= 1"),
    ("phase springback", "phase forming", "phase 'forming' defined twice"),
    ("phase forming", "phase 2nd", "expected a name for the phase"),
    ("end\n\nphase springback", "\nphase springback", "is not closed: expected 'end' before the"),
    ("  increments  1\nend", "  increments  1\nend\nend", "'end' without a 'phase NAME'"),
    ("  move      punch", "  gap punch punch 1\n  move      punch", "cannot keep a gap to itself"),
    ("  move      punch", "  gap die punch 0.9\n  move      punch", "gap 0.9 mm is smaller than"),
    ("  move      punch", "  gap punch die 1.2\n  move      punch", "already has a motion"),
    ("  output_at", "  move punch 0 0 1\n  output_at", "already has a motion at line"),
]


@pytest.mark.parametrize(("old", "new", "expected"), CONTROL_ERRORS)
def test_control_errors(tmp_path: Path, old: str, new: str, expected: str | None) -> None:
    case = edit(copy_example("bending", tmp_path), "control.dat", old, new)
    if expected is None:
        read_case(case, geometry=False)  # a fixed die moved, a punch moved up: legal
        return
    if expected == "moves tool":
        expected = "moves tool 'punch'"
        edit(case, "control.dat", "tools     punch", "tools     die")
    error = error_of(case)
    assert expected in str(error), str(error)
    assert error.path == case / "control.dat" and error.line is not None


def test_control_gap_rules(tmp_path: Path) -> None:
    case = copy_example("strip_draw", tmp_path)
    edit(case, "control.dat", "gap    holder die 1.1", "gap holder punch 1.1")
    assert "touch the same side of the blank" in str(error_of(case))
    case = copy_example("strip_draw", tmp_path / "b")
    edit(case, "control.dat", "gap    holder die 1.1", "gap holder die 0.5")
    assert "gap 0.5 mm is smaller than the blank thickness 1 mm" in str(error_of(case))
    case = copy_example("strip_draw", tmp_path / "c")
    edit(case, "control.dat", "gap    holder die 1.1", "gap holder press 1.1")
    assert "gap partner 'press' is an unknown tool" in str(error_of(case))
    case = copy_example("strip_draw", tmp_path / "d")
    edit(case, "control.dat", "tools  punch die holder", "tools punch die holder\n  tools die")
    assert "'tools' given twice" in str(error_of(case))


def test_control_springback_first_and_rigid_modes(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "bc.dat", "fix        centre  z  phase springback", "")
    error = error_of(case)
    assert f"control.dat:{line_of(case, 'control.dat', 'phase springback')}: springback phase " \
        "'springback' removes the tools" in str(error)
    assert "(translation along z)" in str(error)
    (case / "control.dat").write_text("phase back\n type springback\nend\n")
    assert "is a springback phase: there is nothing to release" in str(error_of(case))
    (case / "control.dat").write_text("# nothing\n")
    assert "no phase" in str(error_of(case))


def test_control_defaults(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    (case / "control.dat").write_text("phase only\n tools punch die\n move punch 0 0 -20\nend\n"
                                      "phase springback\n type springback\nend\n")
    c = read_case(case)
    p = c.phases[0]
    assert p.max_increment == pytest.approx(0.2) and p.min_increment == pytest.approx(2e-4)
    assert replace(p.limits, min_fraction=1e-3) == IncrementLimits()
    assert p.newton == NewtonSettings() and p.output_every == 10
    assert p.lead == "punch" and c.title == "bending"
    # The release redo cap: a count, or off (no cap), at the top or in a phase.
    (case / "control.dat").write_text("rmin_release_redos off\nphase only\n tools punch die\n"
                                      " move punch 0 0 -20\n rmin_release_redos 3\nend\n"
                                      "phase springback\n type springback\nend\n")
    c = read_case(case)
    assert c.phases[0].limits.release_redos == 3 and c.phases[1].limits.release_redos is None


def test_warnings(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "control.dat", "max_increment        0.114", "max_increment 50")
    edit(case, "tools.dat", "friction     0.148", "friction 1.5")
    edit(case, "control.dat", "tools     punch die", "tools     punch")
    warnings = read_case(case, geometry=False).warnings
    assert any("max_increment 50 mm exceeds the travel 28.5 mm" in w for w in warnings)
    assert any("friction coefficient 1.5 is above 1" in w for w in warnings)
    assert any("tool 'die' is active in no phase" in w for w in warnings)


# ----------------------------------------------------------------------------------- mesh

OWN_MESH = """normal z
nodes 8
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 0 0 1
6 1 0 1
7 1 1 1
8 0 1 1
hexahedra 1
10 1 2 3 4 5 6 7 8
"""

MESH_ERRORS = [
    ("nodes 8", "nodes 9", "expected 9 lines 'ID X Y Z' after line 2, got 8 before 'hexahedra'",
     11),
    ("hexahedra 1", "hexahedra 2", "expected 2 lines 'ID N1 ... N8' after line 11, got 1 before "
     "the end of the file", 12),
    ("3 1 1 0", "3 1 1", "expected 'ID X Y Z' (4 numbers), got '3 1 1'", 5),
    ("3 1 1 0", "3 1 one 0", "expected numbers X Y Z, got '1 one 0'", 5),
    ("3 1 1 0", "3 1 1 inf", "expected finite coordinates", 5),
    ("3 1 1 0", "2 1 1 0", "node 2 defined twice (first at line 4)", 5),
    ("3 1 1 0", "0 1 1 0", "node ids must be >= 1, got 0", 5),
    ("10 1 2 3 4 5 6 7 8", "10 1 2 3 4 5 6 7 9", "element 10 refers to node 9, which is not", 12),
    ("10 1 2 3 4 5 6 7 8", "10 1 2 3 4 5 6 7 0", "element 10 refers to node 0, which is not", 12),
    ("10 1 2 3 4 5 6 7 8", "10 1 2 3 4 -1 6 7 8", "element 10 refers to node -1, which is not",
     12),
    ("10 1 2 3 4 5 6 7 8", "10 1 2 3 4 5 6 7 7", "element 10 repeats a node", 12),
    ("10 1 2 3 4 5 6 7 8", "10 1 4 3 2 5 8 7 6", "element 10 is inverted at its corner 0", 12),
    ("10 1 2 3 4 5 6 7 8", "10 1 2 3 4 5 6 7 8.0", "expected integers ID N1 ... N8", 12),
    ("8 0 1 1\n", "8 0 1 1\n9 5 5 5\n", "expected 'hexahedra COUNT', got '9 5 5 5'", 11),
    ("normal z", "normal w", "expected the sheet normal among x, y, z", 1),
    ("normal z", "normal z\nbox 1 1 1 1 1 1", "'nodes' conflicts with 'box' at line 2", 3),
    ("normal z", "normal z\norigin 1 2 3", "'origin' applies to a generated 'box' only", 2),
    ("normal z", "normal z\nscale 1e308\nscale 2", "'scale' given twice", 3),
    ("normal z", "normal z\nsize 3", "unknown keyword 'size': expected normal", 2),
    ("normal z", "normal z\nelement shell", "element must be one of 'hexahedron', "
     "'solid-shell', got 'shell'", 2),
    ("normal z", "normal z\nelement", "expected 'element hexahedron | solid-shell'", 2),
    ("normal z", "element solid-shell\nnormal z\nelement hexahedron", "'element' given twice "
     "(first at line 1)", 3),
]


@pytest.mark.parametrize(("old", "new", "expected", "line"), MESH_ERRORS)
def test_mesh_errors(tmp_path: Path, old: str, new: str, expected: str, line: int | None
                     ) -> None:
    case = copy_example("bending", tmp_path, mesh=OWN_MESH.replace(old, new, 1))
    error = error_of(case)
    assert expected in str(error), str(error)
    if line is not None:
        assert (error.path.name, error.line) == ("mesh.dat", line)


def test_mesh_element(tmp_path: Path) -> None:
    """The blank's element: the solid-shell by default, the hexahedron when asked for, and
    the runner's Solid takes it; the hexahedron takes any node order, the solid-shell
    reorders each element so that its zeta edges run through the sheet."""
    from ddpy.app.runner import build_problem
    from ddpy.io.results import ResultsReader, ResultsWriter

    assert read_case(EXAMPLES / "bending", geometry=False).element == "solid-shell"
    case = copy_example("bending", tmp_path)
    edit(case, "mesh.dat", "normal  z ", "element hexahedron\nnormal  z ")
    read = read_case(case, geometry=False)
    assert read.element == "hexahedron"
    assert build_problem(read).solid.element == "hexahedron"
    ResultsWriter.for_case(tmp_path / "run.h5", read).close()  # the results say so
    with ResultsReader(tmp_path / "run.h5") as results:
        assert results.element == "hexahedron"
    sideways = OWN_MESH.replace("10 1 2 3 4 5 6 7 8", "10 1 4 8 5 2 3 7 6")  # zeta along x
    case = copy_example("bending", tmp_path / "b", mesh=sideways)
    edit(case, "bc.dat", "nodeset    centre  box 0 0  0 0  -inf inf", "nodeset centre ids 1-8")
    edit(case, "control.dat", "output_at 7 14 21 28.5", "")
    edit(case, "mesh.dat", "normal z", "normal z\nelement hexahedron")
    hexahedron = read_case(case, geometry=False)
    assert hexahedron.element == "hexahedron"
    assert list(hexahedron.mesh.elements[0]) == [0, 3, 7, 4, 1, 2, 6, 5]  # as given
    edit(case, "mesh.dat", "normal z\nelement hexahedron", "normal z")
    # The solid-shell reorders the element so that its zeta edges run through the sheet:
    # the same nodes, the bottom face N1-N4 (z = 0) first, a positive volume.
    mesh = read_case(case, geometry=False).mesh
    bottom, top = mesh.nodes[mesh.elements[0, :4], 2], mesh.nodes[mesh.elements[0, 4:], 2]
    assert sorted(mesh.elements[0]) == list(range(8))
    assert np.ptp(bottom) == 0.0 and np.ptp(top) == 0.0 and top[0] > bottom[0]
    assert mesh.jacobians().min() > 0.0


def test_mesh_unused_node(tmp_path: Path) -> None:
    text = OWN_MESH.replace("nodes 8", "nodes 9").replace("hexahedra", "9 5 5 5\nhexahedra")
    error = error_of(copy_example("bending", tmp_path, mesh=text))
    assert "mesh.dat:11: node 9 belongs to no element" in str(error)


def test_mesh_bad_elements_each_at_its_line(tmp_path: Path) -> None:
    text, lines = row_mesh_deck(5, upside_down=(1, 4), repeated=(2,))
    error = error_of(copy_example("bending", tmp_path, mesh=text))
    assert [(e.path.name, e.line) for e in error.errors] == [
        ("mesh.dat", lines[1]), ("mesh.dat", lines[2]), ("mesh.dat", lines[4])]
    assert error.errors[0].message.startswith("element 12 is inverted at its corner 0, node 14 "
                                              "(scaled Jacobian -1, det J -0.125), nodes [14, "
                                              "15, 21, 20, 2, 3, 9, 8]: expected the first four")
    assert error.errors[1].message == "element 13 repeats a node: [3, 4, 10, 9, 15, 16, 22, 22]"
    assert error.errors[2].message.startswith("element 15 is inverted at its corner 0")
    assert str(error).splitlines()[1] == f"{tmp_path / 'bending' / 'mesh.dat'}:{lines[2]}: " \
        "element 13 repeats a node: [3, 4, 10, 9, 15, 16, 22, 22]"


def test_mesh_many_bad_elements_first_five_then_a_count(tmp_path: Path) -> None:
    text, lines = row_mesh_deck(9, upside_down=tuple(range(1, 9)))
    error = error_of(copy_example("bending", tmp_path, mesh=text))
    assert [e.line for e in error.errors] == lines[1:7]
    assert [e.message.split(" is ")[0] for e in error.errors[:5]] == [
        f"element {label}" for label in range(12, 17)]
    assert error.errors[5].message == "... and 3 more bad elements (8 in all)"


def test_mesh_distorted_element_accepted(tmp_path: Path) -> None:
    text = OWN_MESH.replace("7 1 1 1", "7 1.6 1.3 0.6").replace("2 1 0 0", "2 1.4 -0.3 0.2")
    case = copy_example("bending", tmp_path, mesh=text)
    edit(case, "bc.dat", "nodeset    centre  box 0 0  0 0  -inf inf", "nodeset centre ids 1-8")
    edit(case, "control.dat", "output_at 7 14 21 28.5", "")
    mesh = read_case(case, geometry=False).mesh  # the example's tools do not fit this blank
    assert mesh.element_ids.tolist() == [10] and mesh.nodes[6].tolist() == [1.6, 1.3, 0.6]


def test_own_mesh_and_normal(tmp_path: Path) -> None:
    text = OWN_MESH.replace("normal z", "normal -z\nscale 2")
    case = copy_example("bending", tmp_path, mesh=text)
    edit(case, "bc.dat", "nodeset    centre  box 0 0  0 0  -inf inf", "nodeset centre ids 1-8")
    edit(case, "control.dat", "output_at 7 14 21 28.5", "")
    c = read_case(case, geometry=False)  # the example's tools do not fit this blank
    assert c.mesh.normal == (0.0, 0.0, -1.0) and c.mesh.node_ids.tolist() == list(range(1, 9))
    assert c.mesh.element_ids.tolist() == [10] and c.mesh.nodes.max() == 2.0
    np.testing.assert_allclose(c.mesh.nodes[c.tool("punch").contact_nodes(c.mesh), 2], 0.0)
    np.testing.assert_allclose(c.mesh.thickness(), 2.0)
    # ddpy run takes the sheet normal along z only: ddpy check refuses the others at once.
    edit(case, "mesh.dat", "normal -z", "normal -y")
    assert f"mesh.dat:{line_of(case, 'mesh.dat', 'normal -y')}: a sheet normal along y is " \
        "not supported yet" in str(error_of(case))


def test_mesh_box_limits(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path, mesh="box 1 1 1 1000 1000 1000\n")
    assert f"mesh.dat:1: the box has 1000000000 elements (1000 x 1000 x 1000): at most " \
        f"{MAX_ELEMENTS}" in str(error_of(case))  # HexMesh.box's limit, the one check
    case = copy_example("bending", tmp_path / "e", mesh="box 1 -1 1 1 1 1\n")
    assert "mesh.dat:1: LY must be positive, got -1.0" in str(error_of(case))
    case = copy_example("bending", tmp_path / "b", mesh="box 1 1 1 1 1\n")
    assert "expected 'box LX LY LZ NX NY NZ'" in str(error_of(case))
    case = copy_example("bending", tmp_path / "d", mesh="box 10 10 10 1 1 1\nscale 1e308\n")
    assert "mesh.dat:2: node coordinates beyond +-1e+06 mm" in str(error_of(case))
    case = copy_example("bending", tmp_path / "c", mesh="normal z\n")
    assert "mesh.dat: no mesh" in str(error_of(case))


def test_mesh_files(tmp_path: Path) -> None:
    meshio = pytest.importorskip("meshio")
    case = copy_example("bending", tmp_path)
    box = read_case(EXAMPLES / "bending").mesh
    extra = np.vstack([box.nodes, [[99.0, 99.0, 99.0]]])  # a node outside the hexahedra
    data = meshio.Mesh(extra, [("hexahedron", box.elements)],
                       point_sets={"centre nodes": np.flatnonzero(
                           (box.nodes[:, 0] == 0) & (box.nodes[:, 1] == 0))})
    meshio.write(case / "blank.inp", data)
    (case / "mesh.dat").write_text("normal z\nfile blank.inp\n")
    edit(case, "bc.dat", "nodeset    centre  box 0 0  0 0  -inf inf", "")
    edit(case, "bc.dat", "fix        centre", "fix centre_nodes")
    c = read_case(case)
    assert c.mesh.n_nodes == box.n_nodes and c.mesh.source == "blank.inp"
    np.testing.assert_allclose(c.mesh.nodes, box.nodes)
    assert c.boundary.nodesets["centre_nodes"].nodes.size == 4
    edit(case, "bc.dat", "symmetry   x 0", "nodeset centre_nodes plane x 0")
    assert "node set 'centre_nodes' defined twice (first at blank.inp" in str(error_of(case))
    meshio.write(case / "tet.msh", meshio.Mesh(box.nodes[:4], [("tetra", [[0, 1, 2, 3]])]),
                 file_format="gmsh22", binary=False)
    (case / "mesh.dat").write_text("file tet.msh\n")
    assert "tet.msh:13: element 1 is of type 4 (4-node tetra): the blank takes 8-node " \
        "hexahedra" in str(error_of(case))
    (case / "mesh.dat").write_text("file none.inp\n")
    assert "mesh.dat:1: mesh file" in str(error_of(case)) and "not found" in str(error_of(case))
    (case / "mesh.dat").write_text("file blank.vtu\n")
    assert "ending in .inp or .msh" in str(error_of(case))
    (case / "bad.inp").write_text("*NODE\n1, a, b\n")
    (case / "mesh.dat").write_text("file bad.inp\n")
    assert "bad.inp:2: expected a number for a coordinate, got 'a'" in str(error_of(case))


def test_mesh_file_bad_elements_named_by_the_file(tmp_path: Path) -> None:
    meshio = pytest.importorskip("meshio")
    case = copy_example("bending", tmp_path)
    box = read_case(EXAMPLES / "bending").mesh
    elements = box.elements.copy()
    elements[[2, 40]] = elements[[2, 40]][:, UPSIDE_DOWN]
    elements[7, 7] = elements[7, 6]
    meshio.write(case / "blank.inp", meshio.Mesh(box.nodes, [("hexahedron", elements)]))
    (case / "mesh.dat").write_text("normal z\nfile blank.inp\n")
    error = error_of(case)
    assert [(e.line, e.message.split(" ")[:3]) for e in error.errors] == [
        (None, ["blank.inp:", "element", "3"]), (None, ["blank.inp:", "element", "8"]),
        (None, ["blank.inp:", "element", "41"])]
    assert str(error).splitlines()[1].endswith("mesh.dat: blank.inp: element 8 repeats a node: "
                                               "[8, 9, 34, 33, 108, 109, 134, 134]")


@pytest.mark.parametrize("old, new, message", [
    ("11,11,12,37,36,111,112,137,136", "11,11,12,0,36,111,112,137,136",
     "expected a positive integer for a node id, got '0'"),
    ("11,11,12,37,36,111,112,137,136", "11,11,12,37,36,111,112,137,9999",
     "element 11 refers to node 9999, which no *NODE defines"),
    ("11,11,12,37,36,111,112,137,136", "11,11,12,37,36",
     "element 11 has 4 nodes: a C3D8RH element has 8 (was its type or a node changed?)"),
    ("11,11,12,37,36,111,112,137,136", "1_1,11,12,37,36,111,112,137,136",
     "expected a positive integer for the element id, got '1_1'"),
    ("11,11,12,37,36,111,112,137,136", "11,11,12,37,-36,111,112,137,136",
     "expected a positive integer for a node id, got '-36'"),
    ("12,12,13,38,37,112,113,138,137", "11,12,13,38,37,112,113,138,137",
     "element 11 is defined again (first at"),
])
def test_abaqus_blank_checked_at_the_element_line(tmp_path: Path, old: str, new: str,
                                                  message: str) -> None:
    # meshio wired these silently (its element lines are one stream) or failed with a bare
    # KeyError; each is refused at the element's line.
    meshio = pytest.importorskip("meshio")
    case = copy_example("bending", tmp_path)
    box = read_case(EXAMPLES / "bending").mesh
    meshio.write(case / "blank.inp", meshio.Mesh(box.nodes, [("hexahedron", box.elements)]))
    (case / "mesh.dat").write_text("normal z\nfile blank.inp\n")
    line = line_of(case, "blank.inp", old)
    edit(case, "blank.inp", old, new)
    error = error_of(case)
    assert len(error.errors) == 1
    assert str(error).startswith(f"{case}/mesh.dat:2: mesh file {case}/blank.inp:{line}: "
                                 f"{message}"), str(error)


def test_abaqus_blank_of_other_solids_refused_at_the_element_line(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    (case / "blank.inp").write_text("*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n"
                                    "*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n")
    (case / "mesh.dat").write_text("file blank.inp\n")
    assert str(error_of(case)).endswith("blank.inp:7: element 1 is a C3D4: the blank takes "
                                        "8-node hexahedra (C3D8, C3D8H, C3D8I, C3D8IH, C3D8R, "
                                        "C3D8RH)")


def test_gmsh_hexahedron_made_a_second_order_quad_is_refused(tmp_path: Path) -> None:
    # Type 16 (8-node quad) has a hexahedron's node count: meshio dropped the element.
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN, case)
    text = (case / "mesh.msh").read_text().replace("\n1 5 2 1 1 1 13 16 4 2 14 17 5\n",
                                                   "\n1 16 2 1 1 1 13 16 4 2 14 17 5\n")
    (case / "mesh.msh").write_text(text)
    line = line_of(case, "mesh.msh", "1 16 2 1 1")
    assert f"mesh.msh:{line}: element 1 is of type 16 (8-node quad), not a vertex, edge or " \
        "face of 8-node hexahedra" in str(error_of(case))


def test_gmsh_quad_among_the_hexahedra_is_refused(tmp_path: Path) -> None:
    # A hexahedron given as a quadrangle (its type and node count changed): meshio dropped
    # it and left a hole in the blank.
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN, case)
    text = (case / "mesh.msh").read_text().replace("\n5 5 2 1 1 7 19 22 10 8 20 23 11\n",
                                                   "\n5 3 2 1 1 7 19 22 10\n")
    (case / "mesh.msh").write_text(text)
    line = line_of(case, "mesh.msh", "5 3 2 1 1")
    assert f"mesh.msh:{line}: element 5 is of type 3 (4-node quad) among the hexahedra of " \
        "entity 1 (from line 741 to line 1100)" in str(error_of(case))


def test_meshio_failures_name_the_file_and_what_was_expected(tmp_path: Path) -> None:
    case = tmp_path / "case"
    shutil.copytree(BUILT_IN, case)
    text = (case / "mesh.msh").read_text().replace("$EndMeshFormat\n", "$EndMeshFormat\n"
                                                   "$PhysicalNames\nx\n$EndPhysicalNames\n")
    (case / "mesh.msh").write_text(text)
    message = str(error_of(case))
    assert f"mesh file {case}/mesh.msh: meshio cannot read it (" in message
    assert message.endswith("expected a Gmsh file of format 2.2 or 4.1 (docs/input-format.md)")


# ----------------------------------------------------------------------------------- bc

BC_ERRORS = [
    ("fix        centre  z  phase springback", "fix centre", "expected 'fix NODESET COMPONENTS"),
    ("fix        centre  z  phase springback", "fix centre w",
     "expected components among x, y, z"),
    ("fix        centre  z  phase springback", "fix centre zz", "expected components"),
    ("fix        centre  z  phase springback", "fix centre z phase", "expected 'fix NODESET"),
    ("fix        centre  z  phase springback", "fix centre z phase later",
     "unknown phase 'later': control.dat defines forming, springback"),
    ("fix        centre  z  phase springback", "fix center z", "unknown node set 'center'"),
    ("symmetry   x 0 ", "symmetry x 1", "symmetry plane x = 1 holds no node of the mesh"),
    ("symmetry   x 0 ", "symmetry w 0", "expected the symmetry axis among x, y, z"),
    ("symmetry   x 0 ", "symmetry x edge", "unknown node set 'edge'"),
    ("symmetry   x 0 ", "symmetry x", "expected 'symmetry AXIS VALUE|NODESET'"),
    ("-inf inf ", "-inf 5 ", None),
    ("box 0 0  0 0  -inf inf", "box 70 80 0 0 -inf inf", "selects no node"),
    ("box 0 0  0 0  -inf inf", "box 1 0 0 0 -inf inf", "box bounds of x: min 1 > max 0"),
    ("box 0 0  0 0  -inf inf", "box 0 0 0 0 nan inf", "expected a finite number"),
    ("box 0 0  0 0  -inf inf", "box 0 0 0 0", "expected 'nodeset NAME box XMIN XMAX"),
    ("box 0 0  0 0  -inf inf", "ids 1 26 501", "node 501 is not in the mesh"),
    ("box 0 0  0 0  -inf inf", "ids 1-100000", "list more nodes than the mesh has (400)"),
    ("box 0 0  0 0  -inf inf", "ids 5-2", "expected a range FIRST-LAST with 1 <= FIRST"),
    ("box 0 0  0 0  -inf inf", "ids 1.5", "expected a node id or a range"),
    ("box 0 0  0 0  -inf inf", "ids", "expected 'nodeset NAME ids ID...'"),
    ("box 0 0  0 0  -inf inf", "sphere 1", "expected the node set kind among ids, box, plane"),
    ("box 0 0  0 0  -inf inf", "plane x 3.3", "selects no node"),
    ("box 0 0  0 0  -inf inf", "plane q 0", "expected the plane axis among x, y, z"),
    ("tolerance  1e-4", "tolerance 0", "the tolerance must be > 0"),
    ("tolerance  1e-4", "tolerance 1e-4\nfixed centre z", "unknown keyword 'fixed'"),
    ("nodeset    centre", "nodeset centre plane x 0\nnodeset    centre",
     "node set 'centre' defined twice (first at line"),
]


@pytest.mark.parametrize(("old", "new", "expected"), BC_ERRORS)
def test_bc_errors(tmp_path: Path, old: str, new: str, expected: str | None) -> None:
    case = edit(copy_example("bending", tmp_path), "bc.dat", old, new)
    if expected is None:
        read_case(case, geometry=False)
        return
    error = error_of(case)
    assert expected in str(error), str(error)
    assert error.path.name == "bc.dat" and error.line is not None


def test_bc_message_format(tmp_path: Path) -> None:
    case = edit(copy_example("bending", tmp_path), "bc.dat", "fix        centre  z  phase "
                "springback", "fix centre")
    number = line_of(case, "bc.dat", "fix centre")
    assert str(error_of(case)) == (f"{case / 'bc.dat'}:{number}: expected 'fix NODESET "
                                   "COMPONENTS [phase PHASE...]', got 'fix centre'")


def test_bc_symmetry_on_node_set_and_all(tmp_path: Path) -> None:
    case = edit(copy_example("bending", tmp_path), "bc.dat", "symmetry   x 0",
                "nodeset xsym plane x 0\nsymmetry x xsym\nfix xsym all phase springback")
    c = read_case(case, geometry=False)
    labels = [k.label for k in c.boundary.constraints]
    assert "symmetry x on xsym" in labels and "fix xsym xyz" in labels


# ----------------------------------------------------------------------------------- material

MATERIAL_ERRORS = [
    ("nu 0.3", "nu 0.5", "Poisson's ratio nu must lie in (-1, 0.5), got 0.5"),
    ("E 210000", "E -1", "Young's modulus E must be positive, got -1"),
    ("E 210000", "E 2e6", "Young's modulus E must be <= 1e+06, got 2e6"),
    ("E 210000", "", "missing E: expected 'elastic E VALUE nu VALUE'"),
    ("E 210000", "E 1 E 2", "E given twice"),
    ("E 210000", "E", "keys and values in pairs"),
    ("E 210000", "G 3 E 1", "unknown key 'G' in 'elastic E VALUE nu VALUE'"),
    ("N 1.689", "", "missing N: expected 'yield hill48 F VALUE"),
    ("F 0.254  G 0.397  H 0.603", "F -1 G -1 H 0.603",
     "do not define a convex yield surface"),
    ("L 1.5", "L 0", "Hill48 L must be positive"),
    ("N 1.689", "N 1e6", "Hill'48 N = 1e+06 above 100"),
    ("F 0.254", "F 250", "Hill'48 F = 250 above 100"),
    ("hill48 ", "hill ", "expected the yield criterion among vonmises, hill48"),
    ("n 0.252", "n 1.5", "Swift exponent n must lie in [0, 1], got 1.5"),
    ("eps0 0.0102", "eps0 0", "Swift eps0 must be positive"),
    ("swift ", "voce ", "unknown key 'K' in 'hardening voce"),
    ("swift ", "power ", "expected the hardening law among swift, voce"),
    ("rolling_direction  0", "rolling_direction 400", "must be <= 360"),
    ("rolling_direction  0", "rolling_direction", "expected 'rolling_direction ANGLE'"),
    ("rolling_direction  0", "density 7.8e-9", "unknown keyword 'density'"),
    ("elastic  ", "# elastic  ", "no 'elastic' line"),
    ("yield              hill48", "# yield", "no 'yield' line"),
    ("hardening          swift", "# hardening", "no 'hardening' line"),
    ("hardening          swift", "hardening voce Y0 1 Q 1 b 1\nhardening swift",
     "'hardening' given twice"),
]


@pytest.mark.parametrize(("old", "new", "expected"), MATERIAL_ERRORS)
def test_material_errors(tmp_path: Path, old: str, new: str, expected: str) -> None:
    case = edit(copy_example("bending", tmp_path), "material.dat", old, new)
    error = error_of(case)
    assert expected in str(error), str(error)
    assert error.path.name == "material.dat"


@pytest.mark.parametrize(("line", "check"), [
    ("yield vonmises", lambda m: m.yield_criterion == Hill48.von_mises()),
    ("yield hill48 r0 2 r45 1 r90 1.5",
     lambda m: math.isclose(m.yield_criterion.r90, 1.5)
     and m.yield_criterion.G + m.yield_criterion.H == pytest.approx(1)),
    ("yield hill48 F 0.5 G 0.5 H 0.5 N 1.5", lambda m: m.yield_criterion.L == 1.5),
])
def test_material_yield_forms(tmp_path: Path, line: str, check) -> None:
    case = edit(copy_example("bending", tmp_path), "material.dat",
                "yield              hill48  F 0.254  G 0.397  H 0.603  L 1.5  M 1.5  N 1.689",
                line)
    assert check(read_case(case, geometry=False).material.material)


@pytest.mark.parametrize(("line", "warned"), [
    ("yield hill48 r0 2 r45 1 r90 1.5", None),
    ("yield hill48 r0 20 r45 1 r90 1.5", "r0 = 20"),
    ("yield hill48 r0 2 r45 1 r90 0.05", "r90 = 0.05"),
    ("yield hill48 F 0.5 G 0.5 H 0.5 N 1.5", None),
    ("yield hill48 F 0.01 G 0.5 H 0.5 N 1.5", "r90 = 50"),
])
def test_material_implausible_r_values_are_warned_about(tmp_path: Path, line: str,
                                                        warned: str | None) -> None:
    case = edit(copy_example("bending", tmp_path), "material.dat",
                "yield              hill48  F 0.254  G 0.397  H 0.603  L 1.5  M 1.5  N 1.689",
                line)
    warnings = [w for w in read_case(case, geometry=False).warnings if "Lankford" in w]
    if warned is None:
        assert warnings == []
    else:
        assert len(warnings) == 1 and warned in warnings[0]
        assert "material.dat:" in warnings[0]


def test_material_axes() -> None:
    from ddpy.io.case import BlankMaterial

    mat = read_case(EXAMPLES / "bending", geometry=False).material.material
    axes = BlankMaterial(mat, 30.0).axes((0.0, 0.0, 1.0))
    np.testing.assert_allclose(axes[0], [math.cos(math.pi / 6), 0.5, 0], atol=1e-15)
    np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(BlankMaterial(mat, 0.0).axes((1.0, 0, 0))[0], [0, 1, 0])
    assert np.linalg.det(BlankMaterial(mat, 10.0).axes((0, -1.0, 0))) == pytest.approx(1)


# ----------------------------------------------------------------------------------- tools

TOOL_ERRORS = [
    ("friction     0.148", "friction     -0.1", "friction must be >= 0, got -0.1"),
    ("friction     0.148", "friction     0.1 0.2", "expected 'friction MU'"),
    ("contact      top", "", "tool 'punch' has no 'contact' (a tool with no contact partner)"),
    ("contact      top", "contact side", "expected the contact side among top, bottom, facing"),
    ("contact      top", "contact facing 0 0 0", "must be a non-zero finite vector"),
    ("contact      top", "contact facing 1 1 1", "has no contact partner: no boundary face"),
    ("contact      top", "contact facing 1 0", "expected 'contact facing NX NY NZ'"),
    ("contact      top", "contact top 1", "expected 'contact top'"),
    ("file         tools/punch.tool", "file tools/press.tool", "press.tool not found"),
    ("file         tools/punch.tool", "", "tool 'punch' has no 'file'"),
    ("description  nagata ", "description nurbs ", "expected the description among bezier"),
    ("tool punch", "tool 1punch", "expected a name for the tool"),
    ("tool die", "tool punch", "tool 'punch' defined twice (first at line 4)"),
    ("end\n\ntool die", "\ntool die", "tool 'punch' is not closed"),
    ("tool punch", "friction 0.1\ntool punch", "'friction' belongs inside a tool"),
    ("tool punch", "toll punch", "unknown keyword 'toll' at the top of tools.dat"),
    ("contact      top", "contact top\n  speed 3", "unknown keyword 'speed' in a tool"),
    ("contact      top", "contact top\n  contact bottom", "'contact' given twice"),
    ("contact      top", "contact top\n  augmentation 0",
     "augmentation must be > 0 (N/mm, the contact law's r), got 0"),
    ("contact      top", "contact top\n  discretization mortar",
     "discretization must be one of node, surface, gauss, got 'mortar'"),
    ("contact      top", "contact top\n  discretization",
     "expected 'discretization node|surface|gauss'"),
    ("contact      top", "contact top\n  penalty -1", "penalty must be > 0 (N/mm^3), got -1"),
    ("contact      top", "contact top\n  points 9",
     "points (Gauss points per direction of a blank face) must be an integer from 1 to 8, "
     "got 9"),
    ("contact      top", "contact top\n  points 2.5", "expected an integer for the Gauss points"),
    ("contact      top", "contact top\n  discretization node\n  discretization surface",
     "'discretization' given twice"),
]


@pytest.mark.parametrize(("old", "new", "expected"), TOOL_ERRORS)
def test_tool_errors(tmp_path: Path, old: str, new: str, expected: str) -> None:
    case = edit(copy_example("bending", tmp_path), "tools.dat", old, new)
    error = error_of(case)
    assert expected in str(error), str(error)
    assert error.path.name == "tools.dat" and error.line is not None


def test_contact_discretization(tmp_path: Path) -> None:
    """discretization surface selects surface-to-surface contact for that tool, node
    node-to-surface; gauss, the default, Gauss-point contact; a bad value is reported at its
    line of tools.dat."""
    from ddpy.app.runner import build_problem

    case = edit(copy_example("bending", tmp_path), "tools.dat", "contact      bottom",
                "contact      bottom\n  discretization surface")
    read = read_case(case)
    assert (read.tool("punch").discretization, read.tool("die").discretization) == (
        "gauss", "surface")
    assert "die: nagata, die.tool, friction 0.148, contacts the bottom of the blank, " \
        "contact discretization surface (surface-to-surface" in read.summary()
    problem = build_problem(read)
    assert [t.contact for t in problem.tools] == ["gauss", "surface"]
    edit(case, "tools.dat", "contact      top", "contact      top\n  discretization node")
    assert [t.contact for t in build_problem(read_case(case)).tools] == ["node", "surface"]
    assert "contacts the top of the blank, contact discretization node (node-to-surface)" \
        in read_case(case).summary()
    edit(case, "tools.dat", "discretization surface", "discretization edges")
    number = line_of(case, "tools.dat", "discretization edges")
    assert str(error_of(case)).startswith(f"{case / 'tools.dat'}:{number}: ")


def test_gauss_contact_its_penalty_and_points(tmp_path: Path) -> None:
    """discretization gauss selects Gauss-point contact; penalty sets its penalty (N/mm^3),
    by default 8 sigma_0 T / h^2 (ddpy.model.forming.default_penalty); points its Gauss
    points per face direction, by default 4."""
    from ddpy.app.runner import build_problem

    case = edit(copy_example("bending", tmp_path), "tools.dat", "contact      bottom",
                "contact      bottom\n  discretization gauss\n  penalty 150\n  points 3")
    read = read_case(case)
    assert (read.tool("die").discretization, read.tool("die").penalty) == ("gauss", 150.0)
    assert "contacts the bottom of the blank, contact discretization gauss (Gauss-point " \
        "contact, 3 x 3 points per blank face), penalty 150 N/mm^3" in read.summary()
    problem = build_problem(read)
    assert [t.contact for t in problem.tools] == ["gauss", "gauss"]
    assert [t.points for t in problem.tools] == [4, 3]
    assert problem.penalty[1] == 150.0
    edit(case, "tools.dat", "  penalty 150\n  points 3\n", "")
    problem = build_problem(read_case(case))
    assert problem.penalty[1] > 0.0
    assert problem.tools[1].points == 4


def test_tool_friction_message(tmp_path: Path) -> None:
    case = edit(copy_example("bending", tmp_path), "tools.dat", "friction     0.148",
                "friction -0.1")
    number = line_of(case, "tools.dat", "friction -0.1")
    assert str(error_of(case)) == f"{case / 'tools.dat'}:{number}: friction must be >= 0, got -0.1"


def test_no_tools(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path, tools="# none\n")
    assert "tools.dat: no tool" in str(error_of(case))


def test_tool_files_read(tmp_path: Path, monkeypatch) -> None:
    install_toolfile(monkeypatch)
    case = copy_example("bending", tmp_path)
    (case / "tools" / "punch.tool").write_text("ddpy-tool 1\nname punch\n")
    error = error_of(case, geometry=True)
    assert "tools.dat:6: cannot read tool file" in str(error)
    case = edit(copy_example("bending", tmp_path / "b"), "tools.dat", "description  nagata",
                "description  facets")
    c = read_case(case)
    assert c.tool("punch").model().description == "facets"


# ----------------------------------------------------------------------------------- geometry


def test_geometry_tool_starts_inside(tmp_path: Path, monkeypatch) -> None:
    install_toolfile(monkeypatch)
    case = edit(copy_example("bending", tmp_path), "mesh.dat", "origin  0 0 0", "origin 0 0 0.5")
    error = error_of(case, geometry=True)
    assert str(error).startswith(f"{case / 'tools.dat'}:4: tool 'punch' starts inside the blank"
                                 ": node 301 at (0, 0, 1.5) is 0.5 mm behind its surface")
    read_case(case, geometry=False)  # without the geometry checks it passes


def test_geometry_motion_through_blank(tmp_path: Path, monkeypatch) -> None:
    install_toolfile(monkeypatch)
    case = edit(copy_example("strip_draw", tmp_path), "control.dat", "move   punch  0 0 -10",
                "move punch 10 0 -10")
    error = error_of(case, geometry=True)
    assert f"control.dat:{line_of(case, 'control.dat', 'move punch 10')}: phase 'draw': tools " \
        "'punch' and 'die'" in str(error)
    assert "the motion goes through the blank" in str(error) and len(error.errors) == 1


def test_geometry_normals_away(tmp_path: Path, monkeypatch) -> None:
    install_toolfile(monkeypatch)
    case = copy_example("bending", tmp_path)
    path = case / "tools" / "punch.tool"
    lines = path.read_text().splitlines()
    start = lines.index("normals 5")
    for k in range(start + 1, start + 6):
        lines[k] = " ".join(str(-float(w)) for w in lines[k].split())
    faces = lines.index("faces 4")
    for k in range(faces + 2, faces + 6):
        w = lines[k].split()
        lines[k] = " ".join(w[3::-1] + w[7:3:-1] + w[8:])
    path.write_text("\n".join(lines) + "\n")
    assert "the normals of tool 'punch' point away from the blank" in str(
        error_of(case, geometry=True))
