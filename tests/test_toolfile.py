"""Tool files: round trips of both formats and a file:line error for every malformed line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ddpy.geometry.surfaces import BezierSurface, NagataSurface
from ddpy.io.toolfile import ToolFileError, ToolModel, read_tool, write_tool

#: A bilinear Bezier patch: the unit square in z = 0.
SQUARE_NET = np.array([[[0.0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]])

NAGATA = """\
# a comment line
ddpy-tool 1
name square   # a trailing comment
description nagata
units mm
vertices 5
0 0 0
1 0 0
1 1 0
0 1 0
2 0 0
normals 2
0 0 1
0 0.6 0.8
faces 2
0 1 2 3  0 0 0 0  7
1 4 2 -1  0 0 1 -1  8
"""

BEZIER = """\
ddpy-tool 1
name plate
description bezier
patches 1
patch 1 1 face 3
0 0 0
0 1 0
1 0 0
1 1 0
"""


def _write(tmp_path: Path, text: str, name: str = "die.tool") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _replace(text: str, line: int, new: str | None) -> str:
    lines = text.splitlines()
    if new is None:
        del lines[line - 1]
    else:
        lines[line - 1] = new
    return "\n".join(lines) + "\n"


def _crease_model() -> ToolModel:
    """Two quads meeting at a 90 degree crease plus a triangle: two normals at crease vertices."""
    vertices = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 0, -1], [1, 1, -1],
                [0.5, 1.5, 0.1]]
    up, side = [0, 0, 1], [1, 0, 0]
    faces = [[0, 1, 2, 3], [1, 4, 5, 2], [3, 2, 6, -1]]
    normals = np.array([[up] * 4, [side] * 4, [up] * 4], dtype=float)
    tilted = np.array([0.0, 0.3, 1.0]) / np.linalg.norm([0.0, 0.3, 1.0])
    normals[2, 2] = tilted
    surface = NagataSurface(vertices, normals, faces)
    return ToolModel("crease", "nagata", surface, [1, 2, 1], "/somewhere/tool.step")


def test_nagata_round_trip_is_exact(tmp_path: Path) -> None:
    model = _crease_model()
    path = write_tool(tmp_path / "crease.nagata.tool", model)
    back = read_tool(path)
    assert (back.name, back.description) == ("crease", "nagata")
    assert back.surface.smooth
    np.testing.assert_array_equal(back.surface.vertices, model.surface.vertices)
    np.testing.assert_array_equal(back.surface.faces, model.surface.faces)
    np.testing.assert_array_equal(back.surface.corner_normals, model.surface.corner_normals)
    np.testing.assert_array_equal(back.surface.coefficients, model.surface.coefficients)
    np.testing.assert_array_equal(back.face_tags, [1, 2, 1])
    assert Path(back.source) == Path("/somewhere/tool.step")
    # One normal per (vertex, normal): 4 up and 4 sideways for the quads (crease vertices 1
    # and 2 carry both), the triangle adds its tilted normal at vertex 2 and vertex 6.
    text = path.read_text()
    assert "normals 9" in text
    # Written again, the text is the same.
    assert write_tool(tmp_path / "again.tool", back).read_text() == text


def test_facets_file_and_facets_of_nagata(tmp_path: Path) -> None:
    facets = _crease_model().facets()
    assert facets.description == "facets" and not facets.surface.smooth
    back = read_tool(write_tool(tmp_path / "crease.facets.tool", facets))
    assert back.description == "facets" and not back.surface.smooth
    np.testing.assert_array_equal(back.surface.coefficients, facets.surface.coefficients)
    assert back.facets() is back
    with pytest.raises(ValueError, match="only a Nagata model"):
        ToolModel("b", "bezier", BezierSurface([SQUARE_NET]), [1]).facets()


def test_bezier_round_trip_is_exact(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    nets = [rng.normal(size=(n + 1, m + 1, 3)) for n, m in [(1, 1), (6, 2), (3, 6)]]
    model = ToolModel("punch", "bezier", BezierSurface(nets), [4, 5, 5])
    back = read_tool(write_tool(tmp_path / "punch.bezier.tool", model))
    assert back.source is None and back.description == "bezier"
    np.testing.assert_array_equal(back.surface.degrees, [[1, 1], [6, 2], [3, 6]])
    np.testing.assert_array_equal(back.surface.control, model.surface.control)
    np.testing.assert_array_equal(back.face_tags, [4, 5, 5])


def test_hand_written_files_read(tmp_path: Path) -> None:
    model = read_tool(_write(tmp_path, NAGATA))
    assert model.n_patches == 2 and model.name == "square"
    np.testing.assert_array_equal(model.face_tags, [7, 8])
    assert model.surface.is_triangle.tolist() == [False, True]
    # Six written digits are enough for a normal: it is normalized on reading.
    six = _replace(NAGATA, 14, "0 0.447214 0.894427")
    normal = read_tool(_write(tmp_path, six)).surface.corner_normals[1, 2]
    assert np.linalg.norm(normal) == pytest.approx(1.0, abs=1e-15)
    bezier = read_tool(_write(tmp_path, BEZIER, "b.tool"))
    points, _, normals = bezier.surface.evaluate([0], [[0.25, 0.5]])
    np.testing.assert_allclose(points, [[0.25, 0.5, 0.0]], atol=1e-15)
    np.testing.assert_allclose(normals, [[0.0, 0.0, 1.0]], atol=1e-15)


NAGATA_ERRORS = [
    (2, "ddpy-tool 2", "expected format version 1"),
    (2, "hello", "expected the first line 'ddpy-tool 1'"),
    (3, "name", "expected a value after 'name'"),
    (3, "name two words", "expected one word after 'name', got 2"),
    (4, "description spline", "expected a description among bezier, nagata, facets"),
    (5, "units inch", "expected 'units mm'"),
    (5, "name again", "'name' given twice"),
    (6, "vertices x", "expected an integer for the number of vertices, got 'x'"),
    (6, "vertices 0", "expected at least one entry in vertices, got 0"),
    (6, "vertices 5 5", "expected 'vertices <count>' (one integer), got 2 values"),
    (6, "vertexes 5", "expected the line 'vertices <count>', got 'vertexes'"),
    (8, "1 0", "expected 3 numbers for a vertex, got 2"),
    (8, "1 0 zero", "expected a number in a vertex, got 'zero'"),
    (8, "1 0 nan", "expected a finite number in a vertex, got 'nan'"),
    (8, "1 0 1e308", "expected a number within +-1e+06 in a vertex, got '1e308'"),
    (12, "normals 3", "expected 3 normals, got 2 before 'faces'"),  # found at line 15
    (14, "0 0.6", "expected 3 numbers for a normal, got 2"),
    (14, "0 0 2", "expected a unit normal, got one of length 2"),
    (14, "0 0 0", "expected a unit normal, got one of length 0"),
    (16, "0 1 2 3  0 0 0 0", "expected 9 integers for a face (4 vertex indices, 4 normal "
     "indices, CAD face tag), got 8"),
    (16, "0 1 2 3  0 0 0 0  x", "expected an integer for a face, got 'x'"),
    (16, "0 1 2 3.5  0 0 0 0  7", "expected an integer for a face, got '3.5'"),
    (16, "0 1 2 9  0 0 0 0  7", "expected vertex indices in 0..4"),
    (16, "0 1 2 -2  0 0 0 0  7", "expected vertex indices in 0..4"),
    (16, "0 1 2 3  0 0 0 5  7", "expected normal indices in 0..1"),
    (16, "0 1 2 -1  0 0 0 0  7", "expected -1 as the fourth vertex and the fourth normal"),
    (16, "0 1 1 3  0 0 0 0  7", "repeats a vertex"),
    (16, "0 3 2 1  0 0 0 0  7", "counter-clockwise seen from the side the normals point to"),
    (11, "1 2 0", None),  # makes face 2 (line 17) a degenerate triangle
]


@pytest.mark.parametrize(("line", "new", "message"), NAGATA_ERRORS)
def test_nagata_errors_name_file_and_line(tmp_path: Path, line: int, new: str,
                                          message: str | None) -> None:
    path = _write(tmp_path, _replace(NAGATA, line, new))
    expected_line = 17 if message is None else 15 if "before 'faces'" in message else line
    with pytest.raises(ToolFileError) as error:
        read_tool(path)
    text = str(error.value)
    assert text.startswith(f"{path}:{expected_line}: "), text
    assert (message or "degenerate") in text


def test_structural_errors(tmp_path: Path) -> None:
    cases = [
        (NAGATA.replace("name square   # a trailing comment\n", ""), 5,
         "the header has no 'name' line"),
        (_replace(NAGATA, 17, None), 16, "the file ends where faces (2 expected) was expected"),
        (NAGATA + "extra 1 2\n", 18, "unexpected 'extra' after the last block"),
        ("# nothing here\n", 1, "the file ends where the first line 'ddpy-tool 1' was expected"),
        (_replace(BEZIER, 3, "description facets"), 4,
         "expected the line 'vertices <count>', got 'patches'"),
        (_replace(BEZIER, 4, "patches 0"), 4, "expected at least one entry in patches"),
        (_replace(BEZIER, 4, "patches 2"), 9, "the file ends where a line 'patch <n> <m> face"),
        (_replace(BEZIER, 5, "patch 7 1 face 3"), 5, "expected a degree n between 1 and 6, got 7"),
        (_replace(BEZIER, 5, "patch 1 0 face 3"), 5, "expected a degree m between 1 and 6, got 0"),
        (_replace(BEZIER, 5, "patch 1 1 3"), 5, "expected 'patch <n> <m> face <CAD face tag>'"),
        (_replace(BEZIER, 5, "patch a 1 face 3"), 5, "expected an integer for the degree n"),
        (_replace(BEZIER, 5, "patch 1 1 face top"), 5, "expected an integer for the CAD face"),
        (_replace(BEZIER, 9, "1 1"), 9, "expected 3 numbers for a control point, got 2"),
        (_replace(BEZIER, 5, "patch 1 2 face 3"), 9,
         "the file ends where control points of patch 0 (6 expected) was expected"),
    ]
    for text, line, message in cases:
        path = _write(tmp_path, text)
        with pytest.raises(ToolFileError) as error:
            read_tool(path)
        assert str(error.value).startswith(f"{path}:{line}: "), str(error.value)
        assert message in str(error.value), str(error.value)


def test_unreadable_file(tmp_path: Path) -> None:
    with pytest.raises(ToolFileError, match="cannot read the tool file"):
        read_tool(tmp_path / "missing.tool")
    with pytest.raises(ToolFileError, match="a directory: expected a regular file as a tool "
                       "file"):
        read_tool(tmp_path)


def test_a_tool_file_beyond_its_size_limit_is_refused(tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    # The limit (1 GB) is what a test cannot write: the check is the same at any limit.
    import ddpy.io.toolfile

    path = _write(tmp_path, NAGATA)
    monkeypatch.setattr(ddpy.io.toolfile, "TOOL_LIMIT", 100)
    with pytest.raises(ToolFileError) as error:
        read_tool(path)
    assert str(error.value) == f"{path}: {path.stat().st_size} bytes: larger than the 100 " \
        "bytes limit for a tool file"


def test_model_checks() -> None:
    surface = BezierSurface([SQUARE_NET])
    with pytest.raises(ValueError, match="description must be one of"):
        ToolModel("a", "nurbs", surface, [1])
    with pytest.raises(ValueError, match="cannot have description 'nagata'"):
        ToolModel("a", "nagata", surface, [1])
    with pytest.raises(ValueError, match="one tag per patch"):
        ToolModel("a", "bezier", surface, [1, 2])
    with pytest.raises(ValueError, match="name must be one word"):
        ToolModel("a b", "bezier", surface, [1])


def test_documented_examples_read(tmp_path: Path) -> None:
    """The examples of docs/tool-files.md are valid tool files."""
    text = (Path(__file__).resolve().parents[1] / "docs" / "tool-files.md").read_text()
    blocks = [b.split("```")[0] for b in text.split("```\n# ddpy tool file")[1:]]
    assert len(blocks) == 2
    kinds = []
    for i, block in enumerate(blocks):
        model = read_tool(_write(tmp_path, "# ddpy tool file" + block, f"ex{i}.tool"))
        kinds.append(model.description)
        assert model.n_patches == 2
        np.testing.assert_array_equal(model.face_tags, [1, 2])
    assert kinds == ["nagata", "bezier"]


def test_a_bezier_patch_collapsed_inside_is_refused(tmp_path: Path) -> None:
    # All control points of the third patch at one point: its normals would be zero. A
    # patch with one edge collapsed (the pole of a disc) keeps its normals inside: accepted.
    u, v = np.meshgrid([0.0, 1.0], [0.0, 1.0], indexing="ij")
    square = np.stack([u, v, np.zeros((2, 2))], axis=-1)
    pole = square.copy()
    pole[0, :] = 0.0  # the edge u = 0 collapsed to the origin
    u, v = np.meshgrid([0.0, 0.5, 1.0], [0.0, 0.5, 1.0], indexing="ij")
    quadratic = np.stack([u, v, np.zeros((3, 3))], axis=-1)
    model = ToolModel("die", "bezier", BezierSurface([square, pole, quadratic]), [1, 2, 3])
    path = write_tool(tmp_path / "die.bezier.tool", model)
    text = path.read_text().split("\n")
    line = next(n for n, x in enumerate(text, start=1) if x.startswith("patch 2 2"))
    text[line:line + 9] = ["0 0 0"] * 9  # BezierSurface refuses such a net: write it by hand
    path.write_text("\n".join(text))
    with pytest.raises(ToolFileError, match=rf"die.bezier.tool:{line}: patch 2 is degenerate"):
        read_tool(path)
    model = ToolModel("die", "bezier", BezierSurface([square, pole]), [1, 2])
    assert read_tool(write_tool(tmp_path / "ok.bezier.tool", model)).surface.n_patches == 2
