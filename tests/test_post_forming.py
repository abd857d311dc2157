"""``ddpy post``'s forming results: the forming limit curve (Keeler-Brazier, or material.dat's
table), the forming limit diagram's margin in summary.md, the model's fraction and the full
part's force, and the data of increments.png."""

from __future__ import annotations

import csv
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_runner import tiny_case

from ddpy.app.post import increment_panels, load_run
from ddpy.app.runner import RESULTS, run_case
from ddpy.io.decks import DeckError, read_case
from ddpy.io.results import ResultsReader, ResultsWriter
from ddpy.model.forming_limits import FormingLimitCurve

#: A flat forming limit of 0.006 in major strain: the tiny run's strains (about 0.0044 and
#: 0.0077 at the top faces of its two columns) lie on both sides of it.
LOW_LIMIT = 0.006
FLAT_TABLE = (f"forming_limit table 2   # MINOR MAJOR\n  -0.5 {LOW_LIMIT}\n"
              f"  {LOW_LIMIT} {LOW_LIMIT}\n")


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "ddpy", *args], capture_output=True,
                          text=True)


@pytest.fixture(scope="module")
def low_limit_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The tiny case (a half model: symmetry x 0) run to the end, with the flat, low
    forming limit table in its material.dat."""
    base = tmp_path_factory.mktemp("fld")
    case = tiny_case(base / "case")
    with open(case / "material.dat", "a") as deck:
        deck.write(FLAT_TABLE)
    assert run_case(read_case(case), base / "out").status == "completed"
    return base / "out"


# ------------------------------------------------------------------- the forming limit curve


def test_keeler_brazier_curve_against_hand_values() -> None:
    """FLC0 = (23.3 + 14.13 t) n / 0.21 % engineering major strain (t at most 3 mm); left of
    plane strain a line of constant thinning in logarithmic strains, right of it a slope of
    0.6 in engineering strains. By hand:
    n 0.2, t 1: FLC0 = 37.43 x 0.2 / 0.21 = 35.6476 %, ln 1.356476 = 0.304890; at minor
    -0.2 major 0.504890; at minor 0.2 (engineering 0.221403) 0.356476 + 0.132842 =
    0.489318, ln = 0.398318.
    n 0.15, t 4 (taken as 3): FLC0 = 65.69 x 0.15 / 0.21 = 46.9214 %, ln = 0.384728; at
    -0.2 0.584728; at 0.2 0.469214 + 0.132842 = 0.602056, ln = 0.471288."""
    for n, t, flc0, values in ((0.2, 1.0, 0.356476, (0.504890, 0.304890, 0.398318)),
                               (0.15, 4.0, 0.469214, (0.584728, 0.384728, 0.471288))):
        curve = FormingLimitCurve.keeler_brazier(n, t)
        assert curve.flc0 == pytest.approx(flc0, abs=1e-6)
        np.testing.assert_allclose(curve.major_limit([-0.2, 0.0, 0.2]), values, atol=2e-6)
    curve = FormingLimitCurve.keeler_brazier(0.2, 1.0)
    # A point 0.05 below the curve at plane strain, one on the band's edge and one above.
    np.testing.assert_allclose(curve.margin([0.254890, 0.304890 + 0.01], [0.0, 0.0]),
                               [0.05, -0.01], atol=1e-6)
    assert list(curve.zone([0.1, 0.254890, 0.31], [0.0, 0.0, 0.0])) == [0, 1, 2]


def test_default_curve_is_keeler_brazier_from_the_case(tmp_path: Path) -> None:
    """Without a table the results record Keeler-Brazier's curve from the hardening
    exponent (Voce's by its two-point slope between 10 and 20 % plastic strain: Y0 160, Q
    250, b 8 give ln(359.526 / 297.668) / ln 2 = 0.27239) and the blank's thickness (1 mm)."""
    case = read_case(tiny_case(tmp_path / "case"))
    ResultsWriter.for_case(tmp_path / "r.h5", case).close()
    with ResultsReader(tmp_path / "r.h5") as r:
        curve = r.forming_limit()
    assert curve is not None and curve.kind == "keeler-brazier"
    assert curve.n == pytest.approx(0.272393, abs=1e-5)
    assert curve.thickness == pytest.approx(1.0)


MINOR_MAJOR = "forming_limit table 3\n  -0.3 0.6\n  0.0 0.3\n  0.3 0.45\n"


def test_forming_limit_table_is_read_from_material_dat(tmp_path: Path) -> None:
    case = tiny_case(tmp_path / "case")
    with open(case / "material.dat", "a") as deck:
        deck.write(MINOR_MAJOR)
    curve = read_case(case).material.forming_limit
    assert curve is not None and curve.kind == "table"
    assert curve.minor == (-0.3, 0.0, 0.3) and curve.major == (0.6, 0.3, 0.45)
    # Linear between the points, constant beyond the ends.
    np.testing.assert_allclose(curve.major_limit([-0.5, -0.15, 0.1, 0.6]),
                               [0.6, 0.45, 0.35, 0.45])
    assert "material.dat:6" in curve.describe()


@pytest.mark.parametrize(("old", "new", "line", "message"), [
    ("0.0 0.3", "0.0 x", 8, "expected a number for the major strain"),
    ("0.0 0.3", "-0.4 0.3", 8, "must be above the one before"),
    ("0.0 0.3", "0.0 0", 8, "the major strain of point 2 must be > 0, got 0"),
    ("0.3 0.45", "0.3 0.2", 9, "the major strain 0.2 of point 3 is below its minor strain 0.3"),
    ("0.3 0.45", "0.3 0.45 1", 9, "MINOR MAJOR"),
    ("  0.3 0.45\n", "", None, "the deck ends inside the forming limit table of line 6"),
    ("table 3", "table 1", 6, "must be >= 2"),
    ("table 3", "keeler 3", 6, "the forming limit curve"),
])
def test_forming_limit_table_errors_name_file_and_line(
        tmp_path: Path, old: str, new: str, line: int | None, message: str) -> None:
    case = tiny_case(tmp_path / "case")
    with open(case / "material.dat", "a") as deck:
        deck.write(MINOR_MAJOR.replace(old, new))
    with pytest.raises(DeckError) as info:
        read_case(case)
    error = info.value.errors[0]
    assert error.path is not None and error.path.name == "material.dat"
    assert error.line == line
    assert message in error.message


# ------------------------------------------------------------------ the forming limit diagram


def test_summary_marks_elements_above_the_curve_failed(low_limit_run: Path,
                                                      tmp_path: Path) -> None:
    """With a flat limit L the margin of an element is L minus the largest major strain of
    its top, middle and bottom faces: elements above L are failed, and summary.md names the
    element with the smallest margin."""
    done = cli("post", str(low_limit_run), "--output", str(tmp_path))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "fld.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "thinning.png").read_bytes()[:4] == b"\x89PNG"
    with ResultsReader(low_limit_run / RESULTS) as r:
        fields, ids = r.frame(-1), r.element_ids
    major = np.max([fields[f"major_strain_{s}"] for s in ("top", "middle", "bottom")], axis=0)
    margin = LOW_LIMIT - major
    failed = int((margin <= 0).sum())
    assert 0 < failed < len(major)  # the limit splits the blank
    summary = (tmp_path / "summary.md").read_text()
    counts = re.search(r"(\d+) safe, (\d+) marginal, (\d+) failed", summary)
    assert counts is not None and int(counts.group(3)) == failed
    assert sum(int(c) for c in counts.groups()) == len(major)
    worst = re.search(r"smallest margin to the forming limit curve: ([-0-9.e+]+) .*element "
                      r"(\d+), (\w+) face.*: (\w+)$", summary, re.MULTILINE)
    assert worst is not None
    assert float(worst.group(1)) == pytest.approx(margin.min(), rel=1e-3)
    assert int(worst.group(2)) == ids[int(np.argmin(margin))]
    assert worst.group(4) == "failed"
    # Within the default band of 0.1 every element below the limit is marginal; with a
    # band of 0.001 those more than 0.001 below it are safe.
    assert int(counts.group(1)) == 0
    narrow = cli("post", str(low_limit_run), "--output", str(tmp_path / "narrow"),
                 "--fld-margin", "0.001")
    assert narrow.returncode == 0, narrow.stderr
    counts = re.search(r"(\d+) safe, (\d+) marginal, (\d+) failed",
                       (tmp_path / "narrow" / "summary.md").read_text())
    assert counts is not None
    assert [int(c) for c in counts.groups()] == [int((margin >= 0.001).sum()), int(
        ((margin > 0) & (margin < 0.001)).sum()), failed]
    assert int(counts.group(1)) > 0
    bad = cli("post", str(low_limit_run), "--fld-margin", "-0.1")
    assert bad.returncode == 2 and "--fld-margin" in bad.stderr


# ----------------------------------------------------------------------- the model's fraction


@pytest.mark.parametrize(("bc_edit", "axes", "name", "copies"), [
    (("symmetry  x 0", "symmetry  x 0\nsymmetry  y 0"), "xy", "quarter", 4),
    (None, "x", "half", 2),
    (("symmetry  x 0", "nodeset   xmid  plane x 0\nfix       xmid  x"), "", "full", 1),
])
def test_fraction_comes_from_the_symmetry_planes(tmp_path: Path, bc_edit: tuple[str, str] | None,
                                                 axes: str, name: str, copies: int) -> None:
    """A quarter (planes x and y), a half (plane x: the strip) and a full model (the same
    plane held by a 'fix', not a symmetry plane): the results record the planes' axes and
    load_run names the fraction."""
    case = tiny_case(tmp_path / "case")
    if bc_edit is not None:
        text = (case / "bc.dat").read_text()
        assert bc_edit[0] in text
        (case / "bc.dat").write_text(text.replace(bc_edit[0], bc_edit[1], 1))
    ResultsWriter.for_case(tmp_path / "r.h5", read_case(case)).close()
    with ResultsReader(tmp_path / "r.h5") as r:
        assert r.symmetry == axes
    fraction = load_run(tmp_path / "r.h5").fraction
    assert fraction[0] == copies and fraction[1].startswith(f"{name} model")


def test_force_tables_give_the_full_part(low_limit_run: Path, tmp_path: Path) -> None:
    """The strip is a half model: phases.csv gives the full part's force, twice the model's,
    and summary.md says so."""
    assert cli("post", str(low_limit_run), "--output", str(tmp_path)).returncode == 0
    with open(tmp_path / "phases.csv") as f:
        rows = list(csv.DictReader(f))
    for row in rows:
        assert float(row["max_force_full_part_N"]) == pytest.approx(
            2 * float(row["max_force_N"]))
    assert float(rows[0]["max_force_N"]) > 0
    summary = (tmp_path / "summary.md").read_text()
    assert "a half model (symmetry planes normal to x): the full part's force is 2 x" in summary


# ----------------------------------------------------------------------------- increments.png


def test_increment_panels_mark_phases_and_set_springback_apart(low_limit_run: Path) -> None:
    """The tiny run: its draw increments, those of the free draw, 4 springback steps. The
    log axis holds the forming steps (all > 0), the springback steps are drawn apart, and
    each phase spans its increments."""
    run = load_run(low_limit_run)
    panels = increment_panels(run)
    draw, free = int(np.sum(run.phase == 0)), int(np.sum(run.phase == 1))
    forming = draw + free
    assert draw > 1 and free > 1 and int(np.sum(run.phase == 2)) == 4
    assert panels.spans == (("draw", 1, draw, True), ("free_draw", draw + 1, forming, True),
                            ("springback", forming + 1, forming + 4, False))
    np.testing.assert_array_equal(panels.forming_number, np.arange(1, forming + 1))
    np.testing.assert_array_equal(panels.springback_number,
                                  np.arange(forming + 1, forming + 5))
    assert (panels.forming_step > 0).all()
    np.testing.assert_allclose(panels.forming_step, run.step[:forming])
    np.testing.assert_array_equal(panels.iterations, run.iterations)
