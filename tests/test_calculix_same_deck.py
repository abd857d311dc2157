"""benchmarks/calculix_same_deck's deck writer: the CalculiX deck written from ddpy's case has
the blank of 60 x 6 x 2 C3D8I, tools whose faces are the facet model's vertices, and reads
back through ``ddpy convert`` to the same blank; the .sta reader counts what CalculiX did.
No CalculiX and no forming run here."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks" / "calculix_same_deck"
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_common import load_module  # noqa: E402

deck = load_module(BENCH / "deck.py", "calculix_same_deck_deck")


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The cases and the deck, the bending benchmark's tools built in a temporary folder."""
    root = tmp_path_factory.mktemp("same_deck")
    return deck.prepare(root, tools=root / "bending_tools")


def _cards(text: str) -> dict[str, list[list[str]]]:
    """Data lines of each '*KEYWORD, PARAMS' card (the keyword line as key; repeated cards
    joined), comments skipped."""
    cards: dict[str, list[list[str]]] = {}
    key = ""
    for line in text.splitlines():
        if line.startswith("**"):
            continue
        if line.startswith("*"):
            key = line.upper()
            cards.setdefault(key, [])
        elif key:
            cards[key].append([w.strip() for w in line.split(",")])
    return cards


def test_the_deck_has_the_blank_of_60_x_6_x_2_c3d8i(written: dict[str, Path]) -> None:
    cards = _cards(written["ccx_facets_coarse"].read_text())
    blank = cards["*ELEMENT, TYPE=C3D8I, ELSET=BLANK"]
    assert len(blank) == 60 * 6 * 2
    assert len(cards["*NODE, NSET=BLANK_NODES"]) == 61 * 7 * 3
    for layer in ("BLANK_TOP", "BLANK_BOTTOM"):
        assert sum(len(line) for line in cards[f"*ELSET, ELSET={layer}"]) == 60 * 6
    assert [w[:2] for w in cards["*CONTACT PAIR, INTERACTION=PUNCH_CONTACT, TYPE=SURFACE TO "
                                 "SURFACE"]] == [["BLANK_TOP_FACE", "PUNCH_FACE"]]
    friction = [float(w[0]) for k, v in cards.items() if k == "*FRICTION" for w in v]
    assert friction == [0.148, 0.148]
    boundary = cards["*BOUNDARY"]
    assert ["PUNCH_REF", "3", "3", "-28.5"] in boundary


def test_the_springs_hold_a_negligible_share_of_the_punch_force(
        written: dict[str, Path]) -> None:
    # The springs tie the centre line to fixed ground, and the punch pushes the centre down
    # by up to its stroke: all of them at full stroke must hold under 0.5 % of the least
    # punch force past the first mm (ddpy's kept Nagata run; at 1 N/mm they held 21 N at
    # 7 mm, a third of CalculiX's force there).
    cards = _cards(written["ccx_facets_coarse"].read_text())
    springs = len(cards["*ELEMENT, TYPE=SPRING2, ELSET=HOLD"])
    stiffness = float(cards["*SPRING, ELSET=HOLD"][1][0])  # the line after the dofs
    kept = json.loads((ROOT / "docs" / "benchmarks" / "calculix_same_deck_runs.json")
                      .read_text())["runs"]["nagata"]
    stroke, force = np.asarray(kept["stroke"]), np.asarray(kept["force"])
    assert springs * stiffness * stroke.max() < 0.005 * force[stroke >= 1.0].min()


def _tool_faces(text: str, tool: str) -> np.ndarray:
    """The S2 faces (nodes 5-8) of a tool's bricks as coordinates, (faces, 4, 3)."""
    cards = _cards(text)
    nodes = {int(w[0]): [float(x) for x in w[1:4]] for k, v in cards.items()
             if k.startswith("*NODE") for w in v if len(w) == 4}
    bricks = cards[f"*ELEMENT, TYPE=C3D8, ELSET={tool.upper()}"]
    return np.array([[nodes[int(n)] for n in b[5:9]] for b in bricks])


@pytest.mark.parametrize("facets", ["facets_coarse", "facets_fine"])
@pytest.mark.parametrize("tool", ["punch", "die"])
def test_the_tool_faces_are_the_facet_models_vertices(written: dict[str, Path],
                                                      tool: str, facets: str) -> None:
    """Each brick's working face is one face of the facet case's tool file, vertex for vertex,
    in its order (counter-clockwise seen from the blank: S2 faces the blank)."""
    from ddpy.io.decks import read_case
    from ddpy.io.toolfile import read_tool

    case = read_case(written[facets])
    model = next(t for t in case.tools if t.name == tool)
    assert model.description == "facets"
    surface = read_tool(model.file).surface
    expected = np.asarray(surface.vertices)[np.asarray(surface.faces)]
    faces = _tool_faces(written[f"ccx_{facets}"].read_text(), tool)
    assert faces.shape == expected.shape
    # the same doubles, but for numbers that need more than CalculiX's 20 characters (a tiny
    # value with its exponent, or 17 digits after "-0.0"): their last digits dropped
    assert np.abs(faces - expected).max() <= 1e-17
    # the brick lies behind its face: S2's outward normal points to the blank's side
    back = 1 if tool == "die" else -1
    normal = np.cross(faces[:, 2] - faces[:, 0], faces[:, 3] - faces[:, 1])
    assert (np.sign(normal[:, 2]) * back >= 0).all()


def test_ddpy_convert_reads_the_deck_back_to_the_same_blank(written: dict[str, Path],
                                                            tmp_path: Path) -> None:
    from ddpy.app.convert import convert_inp
    from ddpy.io.decks import read_case

    conversion = convert_inp(written["ccx_facets_coarse"], tmp_path / "case")
    case = read_case(written["nagata"])
    back = conversion.model
    assert back.element_type == "C3D8I"
    ids = [int(i) for i in case.mesh.node_ids]
    assert sorted(back.nodes) == ids
    assert np.array_equal(np.array([back.nodes[i] for i in ids]), case.mesh.nodes)
    elements = {int(e): [ids[n] for n in nodes] for e, nodes in
                zip(case.mesh.element_ids, case.mesh.elements, strict=True)}
    assert {e: list(n) for e, n in back.elements.items()} == elements
    assert [t.name for t in back.tools] == ["punch", "die"]
    assert [t.friction for t in back.tools] == [0.148, 0.148]
    assert [p.kind for p in back.phases] == ["forming", "springback"]
    assert any("SPRING2" in note for note in conversion.notes)  # skipped, as ddpy needs
    converted = read_case(tmp_path / "case")
    assert converted.material.material.hardening == case.material.material.hardening


def test_the_sta_reader_counts_increments_iterations_and_cut_attempts() -> None:
    run = load_module(BENCH / "run.py", "calculix_same_deck_run")
    text = """SUMMARY OF JOB INFORMATION
  STEP      INC     ATT  ITRS     TOT TIME     STEP TIME      INC TIME
     1          1     1U   60  0.000000E+00  0.000000E+00  0.400000E-02
     1          1     2    22  0.400000E-02  0.400000E-02  0.400000E-02
     1          2     1     3  0.800000E-02  0.800000E-02  0.400000E-02
     2          1     1     5  0.105000E+01  0.500000E-01  0.500000E-01
"""
    steps = run.read_sta(text)
    assert steps[1] == {"increments": 2, "iterations": 25, "all_iterations": 85, "cuts": 1}
    assert steps[2] == {"increments": 1, "iterations": 5, "all_iterations": 5, "cuts": 0}


def test_the_dat_reader_takes_the_punch_force_of_the_forming_step(tmp_path: Path) -> None:
    run = load_module(BENCH / "run.py", "calculix_same_deck_run")
    block = (" {what} ({comp}) for set {s} and time  {t:.7E}\n\n"
             "      9001  {a:.6E} {b:.6E} {c:.6E}\n\n")
    text = "".join(
        block.format(what="displacements", comp="vx,vy,vz", s="PUNCH_REF", t=t, a=0.0, b=0.0,
                     c=-28.5 * t) + block.format(what="forces", comp="fx,fy,fz",
                                                 s="PUNCH_REF", t=t, a=0.1, b=0.0,
                                                 c=-100.0 * t)
        for t in (0.5, 1.0))
    text += block.format(what="displacements", comp="vx,vy,vz", s="TIP", t=2.0, a=0.0, b=0.0,
                         c=3.25)
    # The springs' ground nodes, two of them: their reactions summed, at the forming times.
    text += "".join(
        f" forces (fx,fy,fz) for set GROUND and time  {t:.7E}\n\n"
        f"      9101  0.000000E+00  0.000000E+00  {0.01 * t:.6E}\n"
        f"      9102  0.000000E+00  0.000000E+00  {0.02 * t:.6E}\n\n" for t in (0.5, 1.0))
    (tmp_path / "same_deck.dat").write_text(text)
    numbers = run.read_ccx(tmp_path)
    assert numbers["stroke"] == [0.0, 14.25, 28.5]
    assert numbers["force"] == [0.0, 50.0, 100.0]
    assert numbers["tip_z_sprung"] == 3.25 and numbers["sprung_complete"]
    assert numbers["spring_force"] == [0.0, 0.015, 0.03]
    assert "at most 0.03 N (at 28.50 mm of stroke, 0.03 % of the punch force" in \
        run.spring_note(numbers)


def test_the_curve_gap_compares_from_1_mm_to_a_window_short_of_the_end() -> None:
    # A curve 2 % above its reference up to 5 mm, then 50 % above it (the reference's
    # forced last increments): only the first part is compared, to 1 mm short of the end.
    run = load_module(BENCH / "run.py", "calculix_same_deck_run")
    stroke = np.linspace(0.0, 6.0, 61)
    reference = {"stroke": stroke.tolist(), "force": (10.0 + stroke).tolist()}
    scale = np.where(stroke <= 5.0 + 1e-9, 1.02, 1.5)
    largest, rms, end = run.curve_gap(
        {"stroke": stroke.tolist(), "force": ((10.0 + stroke) * scale).tolist()}, reference)
    assert end == pytest.approx(5.0)
    assert largest == pytest.approx(0.02) and rms == pytest.approx(0.02)
    assert run.curve_gap({"stroke": [0.0, 1.5], "force": [0.0, 1.0]}, reference)[2] == 0.0
