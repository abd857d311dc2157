"""Absurd input refused or questioned with its file and line before any numerics (issue 51):
travels far beyond the model, tools moved through each other, tool files of absurd size, a
yield stress not in MPa, tolerances and cut-backs out of range, a phase needing more
increments than a run may take; what ddpy check accepts ddpy run starts (the title, the
number of phases, a case folder's name, every tool's normals); and an error in a forming
phase is one message, in the decks and in the run."""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
from pathlib import Path

import h5py
import pytest

from ddpy.app.cli import main
from ddpy.io.decks import DeckError, read_case
from ddpy.io.results import ResultsReader, ResultsWriter
from ddpy.model.mesh import HexMesh
from tests.deckutil import EXAMPLES, copy_example, edit


def cli(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def errors_of(case: Path) -> list[str]:
    with pytest.raises(DeckError) as caught:
        read_case(case)
    return [str(e) for e in caught.value.errors]


def where(case: Path, deck: str, text: str) -> str:
    """``case/deck:line`` of the first line of ``deck`` that holds ``text``."""
    lines = (case / deck).read_text().split("\n")
    return f"{case / deck}:{next(i for i, x in enumerate(lines) if text in x) + 1}"


def scale_tool_file(path: Path, factors: tuple[float, float, float]) -> None:
    """Multiply the vertex coordinates of a Nagata tool file by ``factors`` (x, y, z)."""
    lines = path.read_text().split("\n")
    at = next(i for i, x in enumerate(lines) if x.split()[:1] == ["vertices"])
    for i in range(at + 1, at + 1 + int(lines[at].split()[1])):
        x = [float(w) * f for w, f in zip(lines[i].split()[:3], factors, strict=True)]
        lines[i] = " ".join(repr(v) for v in x)
    path.write_text("\n".join(lines))


# ------------------------------------------------------------------------ tools and motions


def test_a_travel_far_beyond_the_model_is_refused(tmp_path: Path) -> None:
    # move punch 0 0 -1000 drove the punch through the die for 8,772 increments.
    case = copy_example("bending", tmp_path)
    edit(case, "control.dat", "output_at 7 14 21 28.5", "")
    edit(case, "control.dat", "move      punch  0 0 -28.5", "move punch 0 0 -1000")
    assert errors_of(case) == [
        f"{where(case, 'control.dat', 'move punch')}: phase 'forming': tool 'punch' travels "
        "1000 mm, more than 10 times the extent of the model (the blank and the tools) along "
        "its motion, 44.5 mm; expected a travel of at most 445 mm"]
    edit(case, "control.dat", "move punch 0 0 -1000", "move punch 0 0 -400")
    read_case(case)  # within ten extents: a long stroke, not an absurd one


def test_tools_whose_boxes_pass_each_other_are_questioned(tmp_path: Path) -> None:
    # The die moved up 100 mm while the punch comes down: it ends above the punch.
    case = copy_example("bending", tmp_path)
    assert read_case(case).warnings == ()
    edit(case, "control.dat", "move      punch  0 0 -28.5",
         "move      punch  0 0 -28.5\n  move die 0 0 100")
    assert read_case(case).warnings == (
        f"{where(case, 'control.dat', 'move      punch')}: phase 'forming': the boxes around "
        "tools 'punch' and 'die' end entirely past each other along -z: does one go through "
        "the other?",)


def test_a_tool_moved_through_another_between_tenths_of_its_travel_is_refused(
        tmp_path: Path) -> None:
    # The holder sweeps through the die within the first 7 % of a long motion: the clearance
    # sampled at tenths of the phase saw it nowhere.
    case = copy_example("strip_draw", tmp_path)
    edit(case, "control.dat", "gap    holder die 1.1", "move   holder -590 0 -50")
    errors = errors_of(case)
    assert len(errors) == 1
    assert errors[0].startswith(f"{where(case, 'control.dat', 'move   holder')}: phase 'draw': "
                                "tools 'die' and 'holder' come ")
    assert errors[0].endswith("% of the phase: the motion goes through the blank")


@pytest.mark.parametrize("factor", [1e4, 3e-11])
def test_a_tool_file_of_absurd_size_is_refused(tmp_path: Path, factor: float) -> None:
    """(1e30 is refused before, by the tool file's coordinate bound: test_toolfile.)"""
    case = copy_example("bending", tmp_path)
    scale_tool_file(case / "tools" / "die.tool", (factor, factor, factor))
    errors = errors_of(case)
    assert len(errors) == 1
    assert errors[0].startswith(f"{where(case, 'tools.dat', 'tool die')}: tool 'die' is ")
    assert "mm across (die.tool), the blank 61.9 mm: " in errors[0]
    assert errors[0].endswith("expected a tool within 0.001 to 1000 times the blank's size "
                              "(is its file in other units, or scaled?)")


def test_a_tool_file_of_odd_size_is_questioned(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    scale_tool_file(case / "tools" / "punch.tool", (1.0, 400.0, 1.0))  # 8 m long
    assert read_case(case).warnings == (
        f"{where(case, 'tools.dat', 'tool punch')}: tool 'punch' is 8e+03 mm across "
        "(punch.tool), the blank 61.9 mm: 129 times its size (is its file in other units, or "
        "scaled?)",)


def test_a_tool_facing_away_is_refused_whichever_phase_uses_it(tmp_path: Path) -> None:
    # A tool whose normals all point away from the blank passed the check unless the first
    # phase used it; the run refused it while it built the problem.
    case = copy_example("bending", tmp_path)
    (case / "tools" / "spare.tool").write_text(
        "ddpy-tool 1\nname spare\ndescription nagata\nunits mm\n"
        "vertices 4\n0 0 30\n60 0 30\n60 15 30\n0 15 30\nnormals 1\n0 0 1\n"
        "faces 1\n0 1 2 3 0 0 0 0 1\n")  # a plate above the blank, its normal up
    with (case / "tools.dat").open("a") as out:
        out.write("\ntool spare\n  description nagata\n  file tools/spare.tool\n"
                  "  friction 0.1\n  contact top\nend\n")
    message = (f"{where(case, 'tools.dat', 'tool spare')}: no patch of tool 'spare' faces the "
               "top of the blank: no normal of spare.tool points against the blank's outward "
               "normal (0, 0, 1); expected a tool file whose normals point towards the blank")
    checked, _, check_err = cli(["check", str(case)])
    ran, _, run_err = cli(["run", str(case), "--output", str(tmp_path / "out"),
                           "--stop-after", "0"])
    assert (checked, ran) == (2, 2)
    assert message in check_err.splitlines() and message in run_err.splitlines()


def test_convert_refuses_a_stroke_far_beyond_the_model(tmp_path: Path) -> None:
    for source in (EXAMPLES / "calculix_bending").glob("*.inp"):
        shutil.copy(source, tmp_path)
    inp = tmp_path / "bending.inp"
    text = inp.read_text()
    assert "PUNCH_REF, 3, 3, -6." in text
    inp.write_text(text.replace("PUNCH_REF, 3, 3, -6.", "PUNCH_REF, 3, 3, -1e6"))
    code, _, err = cli(["convert", str(inp), str(tmp_path / "case")])
    assert code == 2
    assert f"{where(tmp_path, 'bending.inp', 'PUNCH_REF, 3, 3, -1e6')}: tool punch moves 1e+06 " \
        "mm in this step, more than 10 times the extent of the model (the blank and the " \
        "tools) along its motion: expected at most 280 mm" in err.splitlines()
    assert not (tmp_path / "case").exists()


def test_convert_raises_an_abaqus_smallest_increment_to_the_decks_limit(tmp_path: Path
                                                                        ) -> None:
    # Abaqus models take 1e-8 of the step and less; the decks refuse below max / 1e6.
    for source in (EXAMPLES / "calculix_bending").glob("*.inp"):
        shutil.copy(source, tmp_path)
    inp = tmp_path / "bending.inp"
    inp.write_text(inp.read_text().replace("0.02, 1.0, 1e-05, 0.02", "0.02, 1.0, 1e-10, 0.02"))
    code, _, err = cli(["convert", str(inp), str(tmp_path / "case")])
    assert code == 0, err
    phase = read_case(tmp_path / "case").phases[0]
    assert phase.min_increment == pytest.approx(phase.max_increment / 1e6)


# --------------------------------------------------------------------------------- values


@pytest.mark.parametrize("line", [
    "hardening swift K 1e-12 eps0 0.0102 n 0.252",       # 3.2e-13 MPa
    "hardening voce Y0 0.5 Q 100 b 10",
    "hardening table 2\n0 0.5\n0.1 200",
])
def test_an_initial_yield_stress_below_1_MPa_is_refused(tmp_path: Path, line: str) -> None:
    case = copy_example("bending", tmp_path)
    edit(case, "material.dat", "hardening          swift   K 645.3  eps0 0.0102  n 0.252",
         line)
    errors = errors_of(case)
    assert len(errors) == 1
    assert errors[0].startswith(f"{where(case, 'material.dat', 'hardening')}: the initial "
                                "yield stress ")
    assert errors[0].endswith(" MPa is below 1 MPa: expected the hardening law in MPa")
    edit(case, "material.dat", line.split("\n")[0], "hardening voce Y0 1 Q 100 b 10")
    if "table" in line:
        edit(case, "material.dat", "0 0.5\n0.1 200\n", "")
    read_case(case)  # 1 MPa is taken


@pytest.mark.parametrize("deck, old, new, message", [
    ("control.dat", "newton_force         1e-3", "newton_force 1e-300",
     "newton_force must lie in [1e-14, 0.1], got 1e-300"),
    ("control.dat", "newton_displacement  1e-3", "newton_displacement 0.5",
     "newton_displacement must lie in [1e-14, 0.1], got 0.5"),
    ("control.dat", "cutback              0.5", "cutback 1e-300",
     "cutback must lie in [0.1, 0.9], got 1e-300"),
    ("control.dat", "cutback              0.5", "cutback 0.99",
     "cutback must lie in [0.1, 0.9], got 0.99"),
    ("control.dat", "rmin_strain          0.02", "rmin_strain 1e-300",
     "rmin_strain must lie in [0.0001, 1), got 1e-300"),
    ("control.dat", "rmin_rotation        1.0", "rmin_rotation 1e-9",
     "rmin_rotation must lie in [0.001, 90] (degrees), got 1e-09"),
    ("control.dat", "cutback              0.5", "cutback 0.5\nmin_increment 1e-300",
     "phase 'forming': min_increment 1e-300 mm over max_increment 0.114 mm: min_fraction (the "
     "smallest increment over the largest) must be at least 1e-06, got 8.77e-300: below, a "
     "failing increment would be cut more than 20 times (by half) before the run stops"),
    ("bc.dat", "tolerance  1e-4", "tolerance 1e-300",
     "tolerance 1e-300 mm is below 1e-06 mm: a node off a plane by the rounding of its "
     "coordinates would not be selected"),
])
def test_tolerances_and_cutbacks_out_of_range_are_refused(
        tmp_path: Path, deck: str, old: str, new: str, message: str) -> None:
    case = edit(copy_example("bending", tmp_path), deck, old, new)
    assert errors_of(case) == [f"{where(case, deck, new.split()[-2])}: {message}"]


def test_a_phase_needing_more_increments_than_a_run_takes_says_how_many(
        tmp_path: Path) -> None:
    # A 1e6 mm stroke in increments of 1e-12 mm: 1e18 of them, not only "the cap".
    case = copy_example("bending", tmp_path)
    edit(case, "control.dat", "output_at 7 14 21 28.5", "")
    edit(case, "control.dat", "move      punch  0 0 -28.5", "move punch 0 0 -1e6")
    edit(case, "control.dat", "max_increment        0.114", "max_increment 1e-12")
    assert errors_of(case) == [
        f"{where(case, 'control.dat', 'max_increment 1e-12')}: phase 'forming': lead tool "
        "'punch': the travel 1e+06 mm in increments of at most 1e-12 mm needs at least "
        "1e+18 increments; a phase may take at most 1,000,000 (expected a larger "
        "max_increment or a shorter travel)"]


# ------------------------------------------------------------------ ddpy check and ddpy run


def test_a_title_the_results_could_not_hold_is_refused_by_both(tmp_path: Path) -> None:
    # HDF5 refused it ("VLEN strings do not support embedded NULLs") after check passed.
    case = copy_example("bending", tmp_path)
    edit(case, "control.dat", "title  Unconstrained", "title  Uncon\x00strained")
    message = (f"{where(case, 'control.dat', 'title  Uncon')}: the title holds a control "
               "character (a NUL byte): expected printable text")
    checked, _, check_err = cli(["check", str(case)])
    ran, _, run_err = cli(["run", str(case), "--output", str(tmp_path / "out")])
    assert (checked, ran) == (2, 2)
    assert check_err.splitlines()[0] == run_err.splitlines()[0] == message


def test_the_results_writer_stores_any_text_and_refuses_too_many_names(tmp_path: Path
                                                                       ) -> None:
    mesh = HexMesh.box(1.0, 1.0, 1.0, 1, 1, 1)
    with ResultsWriter(tmp_path / "a.h5", mesh, ["punch"], ["forming"], title="a\x00b",
                       case=os.fsdecode(b"/cases/c\xff")):
        pass
    read = ResultsReader(tmp_path / "a.h5")
    assert read.title == "a\\x00b"
    read.close()
    with h5py.File(tmp_path / "a.h5", "r") as f:
        assert f.attrs["case"] == "/cases/c\\xff"
    with pytest.raises(ValueError, match="the attribute phases lists 5,000 names; HDF5 holds "
                       "at most about 4,000"):
        ResultsWriter(tmp_path / "b.h5", mesh, ["punch"], [f"p{k}" for k in range(5000)])


def test_a_case_folder_whose_name_is_not_utf8_runs(tmp_path: Path) -> None:
    # Its name goes to the results: h5py refused the undecodable byte after check passed.
    case = Path(os.fsdecode(bytes(tmp_path) + b"/case\xff"))
    shutil.copytree(EXAMPLES / "bending", case)
    assert cli(["check", str(case)])[0] == 0
    code, out, err = cli(["run", str(case), "--output", str(tmp_path / "out"),
                          "--stop-after", "0"])
    assert code == 0, err
    assert "stopped after 0 increments" in out


def test_too_many_phases_are_refused_by_both_at_the_phase_beyond(tmp_path: Path) -> None:
    # 20,000 phases: check took 84 s and printed 20,000 warnings, run failed after 77 s.
    case = copy_example("bending", tmp_path)
    phase = "phase p{k}\n  tools punch die\n  move punch 0 0 -0.01\nend\n"
    (case / "control.dat").write_text("".join(phase.format(k=k) for k in range(20_000)))
    (case / "bc.dat").write_text("symmetry x 0\nsymmetry y 0\n")
    message = (f"{case / 'control.dat'}:{4 * 1000 + 1}: phase 1,001 of 20,000: a case has "
               "at most 1,000 phases")
    checked, _, check_err = cli(["check", str(case)])
    ran, _, run_err = cli(["run", str(case), "--output", str(tmp_path / "out")])
    assert (checked, ran) == (2, 2)
    assert check_err.splitlines()[0] == run_err.splitlines()[0] == message


def test_a_warning_of_every_phase_takes_a_few_lines(tmp_path: Path) -> None:
    case = copy_example("bending", tmp_path)
    phase = "phase p{k}\n  tools punch die\n  move punch 0 0 -0.01\nend\n"
    (case / "control.dat").write_text("max_increment 0.114\n" + "".join(
        phase.format(k=k) for k in range(1000)))
    (case / "bc.dat").write_text("symmetry x 0\nsymmetry y 0\n")
    code, out, _ = cli(["check", str(case)])
    assert code == 0
    warnings = [line for line in out.splitlines() if line.startswith("  warning: ")]
    assert len(warnings) == 4
    assert warnings[-1] == (f"  warning: {case / 'control.dat'}:1: phase 'p3': max_increment "
                            "0.114 mm exceeds the travel 0.01 mm of the lead tool 'punch' (and "
                            "996 more phases whose max_increment exceeds their lead tool's "
                            "travel)")


def test_stop_after_0_prepares_the_run_and_restart_continues_it(tmp_path: Path) -> None:
    out = tmp_path / "out"
    code, text, _ = cli(["run", str(EXAMPLES / "bending"), "--output", str(out),
                         "--stop-after", "0"])
    assert code == 0 and "stopped after 0 increments, 1 frames" in text
    assert json.loads((out / "status.json").read_text())["status"] == "stopped"
    code, text, _ = cli(["run", str(EXAMPLES / "bending"), "--output", str(out), "--restart",
                         "--stop-after", "1"])
    assert code == 0 and "stopped after 1 increments" in text


# ------------------------------------------------------------ an error in a forming phase


@pytest.mark.parametrize("old, new, message", [
    ("tools     punch die", "tools     punch dye",
     "unknown tool 'dye' in phase 'forming': tools.dat defines punch, die"),
    ("move      punch  0 0 -28.5", "move      punch  0 0 0",
     "phase 'forming' moves no tool: expected a 'move TOOL DX DY DZ' with a non-zero "
     "displacement"),
])
def test_an_error_in_a_forming_phase_is_not_followed_by_one_about_springback(
        tmp_path: Path, old: str, new: str, message: str) -> None:
    # The springback phase was said to be the first phase, the forming one being left out.
    case = copy_example("bending", tmp_path)
    edit(case, "control.dat", "output_at 7 14 21 28.5", "")
    edit(case, "control.dat", old, new)
    errors = errors_of(case)
    assert len(errors) == 1 and errors[0].endswith(message)


def test_a_failed_forming_phase_ends_the_run_with_one_message(tmp_path: Path) -> None:
    # The second forming phase cannot converge (one iteration, no cut allowed): the run
    # stops there with its message, keeps the first phase, and starts no springback.
    case = copy_example("strip_draw", tmp_path)
    edit(case, "control.dat", "move   punch  0 0 -10", "move   punch  0 0 -2")
    edit(case, "control.dat", "  rmin_strain    0.01",
         "  rmin_strain    0.01\n  max_iterations 1\n  min_increment  0.1")
    out = tmp_path / "out"
    code, text, err = cli(["run", str(case), "--output", str(out)])
    assert code == 1
    status = json.loads((out / "status.json").read_text())
    assert status["status"] == "failed" and "failed" in status["message"]
    assert [line for line in text.splitlines() if line.startswith("ddpy run:")][-1] == \
        f"ddpy run: failed after {status['increments']} increments, {status['frames']} " \
        f"frames, {status['wall_time']:.1f} s: {status['message']}"
    assert "springback" not in text + err
    read = ResultsReader(out / "results.h5")
    phases = read.history()["phase"]
    assert read.n_increments == status["increments"] > 0 and set(phases.tolist()) == {0}
    assert read.frames[-1].phase == 0 and len(read.frames) >= 2
    read.close()
