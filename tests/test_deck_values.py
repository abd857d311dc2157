"""Each deck value is checked in one place, the model's (docs/architecture.md, "Where a deck
value is checked"): a deck's bad value gives the model's own message with file:line, the same
message the Python API gives; and control.dat's ``tune NAME VALUE`` sets the run's tuning,
whose names, defaults and ranges docs/input-format.md lists."""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable
from pathlib import Path

import pytest
from deckutil import copy_example, edit

from ddpy.geometry.surfaces import NagataSurface
from ddpy.io.decks import DeckError, read_case
from ddpy.model.control import (
    FormingTuning,
    IncrementLimits,
    IncrementTuning,
    NewtonSettings,
    check_max_increment,
    tuning_default,
    tuning_ranges,
)
from ddpy.model.material import ArmstrongFrederick, HardeningTable, Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.tool import RigidTool

DOC = Path(__file__).resolve().parent.parent / "docs" / "input-format.md"
SWIFT = Swift(645.3, 0.0102, 0.252)


def plane_tool(**settings: object) -> RigidTool:
    """A tool under a block, with these contact settings."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 1, 1, 1)
    plane = NagataSurface([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], [[0, 0, 1]] * 4,
                          [[0, 1, 2, 3]])
    return RigidTool("die", plane, mesh.select(z=0.0), facing=(0, 0, -1), **settings)


def api_message(build: Callable[[], object]) -> str:
    with pytest.raises(ValueError) as error:
        build()
    return str(error.value)


def deck_error(tmp_path: Path, deck: str, old: str, new: str, marker: str
               ) -> tuple[DeckError, int]:
    """The one error of the bending example with ``old`` replaced by ``new`` in ``deck``,
    and the number of the line that holds ``marker``."""
    case = edit(copy_example("bending", tmp_path), deck, old, new)
    number = next(k for k, line in enumerate((case / deck).read_text().splitlines(), 1)
                  if marker in line)
    with pytest.raises(DeckError) as error:
        read_case(case, geometry=False)
    assert len(error.value.errors) == 1, str(error.value)
    found = error.value.errors[0]
    assert found.path == case / deck, str(found)
    return found, number


#: (deck, old, new, the text of the line the error is at, the Python API's call, its
#: message with the deck's names: (old, new))
MOVED = [
    ("control.dat", "newton_force         1e-3", "newton_force 1", "newton_force 1",
     lambda: NewtonSettings(force_tolerance=1.0), ("force_tolerance", "newton_force")),
    ("control.dat", "cutback              0.5", "cutback 0.5\nrmin_touch sometimes", "rmin_touch",
     lambda: IncrementLimits(touch="sometimes"), ("touch", "rmin_touch")),
    ("control.dat", "cutback              0.5", "cutback 0.5\nrmin_release 2", "rmin_release",
     lambda: IncrementLimits(release_share=2.0), ("release_share", "rmin_release")),
    ("control.dat", "cutback              0.5", "cutback 0.5\nmin_increment 1", "min_increment",
     lambda: IncrementLimits(min_fraction=1 / 0.114), ("", "")),
    ("control.dat", "max_increment        0.114", "max_increment 1e-12", "max_increment",
     lambda: check_max_increment(1e-12, 28.5), ("", "")),
    ("control.dat", "cutback              0.5", "cutback 0.5\ntune increment.slack 0.9", "tune",
     lambda: IncrementTuning(slack=0.9), ("slack", "increment.slack")),
    ("control.dat", "cutback              0.5", "cutback 0.5\ntune krylov_max 0", "tune",
     lambda: FormingTuning(krylov_max=0), ("", "")),
    ("control.dat", "cutback              0.5", "cutback 0.5\ntune whole_step 1.5", "tune",
     lambda: FormingTuning(whole_step=1.5), ("", "")),
    ("tools.dat", "contact      bottom", "contact      bottom\n  penalty -1", "penalty",
     lambda: plane_tool(penalty=-1.0), ("tool die: ", "")),
    ("tools.dat", "contact      bottom", "contact      bottom\n  points 9", "points",
     lambda: plane_tool(points=9), ("tool die: ", "")),
    ("tools.dat", "contact      bottom", "contact      bottom\n  barrier 2", "barrier",
     lambda: plane_tool(barrier=2.0), ("tool die: ", "")),
    ("tools.dat", "contact      bottom", "contact      bottom\n  augmentation 0", "augmentation",
     lambda: plane_tool(augmentation=0.0), ("tool die: ", "")),
    ("tools.dat", "contact      bottom", "contact      bottom\n  discretization mortar",
     "discretization",
     lambda: plane_tool(contact="mortar"), ("tool die: ", "")),
    ("tools.dat", "friction     0.148\n  contact      bottom",
     "friction     -0.2\n  contact      bottom", "-0.2",
     lambda: plane_tool(friction=-0.2), ("tool die: ", "")),
    ("mesh.dat", "box     60 15 1", "element shell\nbox     60 15 1", "element shell",
     lambda: Solid(HexMesh.box(1.0, 1.0, 1.0, 1, 1, 1),
                   Material(210e3, 0.3, Hill48.von_mises(), SWIFT), element="shell"), ("", "")),
    ("mesh.dat", "box     60 15 1  24", "box     60 15 1  0", "box",
     lambda: HexMesh.box(60.0, 15.0, 1.0, 0, 3, 3), ("nx", "NX")),
    ("material.dat", "E 210000  nu 0.3", "E -1  nu 0.3", "E -1",
     lambda: Material(-1.0, 0.3, Hill48.von_mises(), SWIFT), ("", "")),
    ("material.dat", "E 210000  nu 0.3", "E 210000  nu 0.5", "nu 0.5",
     lambda: Material(210e3, 0.5, Hill48.von_mises(), SWIFT), ("", "")),
    ("material.dat", "n 0.252", "n 1.5", "n 1.5", lambda: Swift(645.3, 0.0102, 1.5), ("", "")),
    ("material.dat", "hardening          swift   K 645.3  eps0 0.0102  n 0.252",
     "hardening table 3\n0 300\n0.1 350\n0.2 340", "0.2 340",
     lambda: HardeningTable((0.0, 0.1, 0.2), (300.0, 350.0, 340.0)), ("", "")),
    ("material.dat", "rolling_direction", "kinematic armstrong-frederick C 50 Xsat 400\n"
     "rolling_direction", "kinematic",
     lambda: Material(210e3, 0.3, Hill48.von_mises(), SWIFT, ArmstrongFrederick(50.0, 400.0)),
     ("", "")),
]


@pytest.mark.parametrize(("deck", "old", "new", "marker", "build", "names"), MOVED)
def test_a_value_checked_by_the_model_gives_its_message_from_the_deck_with_the_line(
        tmp_path: Path, deck: str, old: str, new: str, marker: str,
        build: Callable[[], object], names: tuple[str, str]) -> None:
    message = api_message(build)
    if names[0]:
        assert message.startswith(names[0]), message
        message = names[1] + message[len(names[0]):]
    error, number = deck_error(tmp_path, deck, old, new, marker)
    assert error.line == number, str(error)
    assert message in error.message, (message, error.message)


# -- tune NAME VALUE ---------------------------------------------------------------------

def tuned_case(tmp_path: Path, lines: str) -> Path:
    return edit(copy_example("bending", tmp_path), "control.dat", "cutback              0.5",
                "cutback 0.5\n" + lines)


def test_tune_lines_set_the_runs_tuning_and_the_problem_takes_it(tmp_path: Path) -> None:
    from ddpy.app.runner import build_problem

    case = read_case(tuned_case(tmp_path, "tune increment.release_steps 8\n"
                                          "tune reach_sizes 3\ntune krylov_loose 0.1"),
                     geometry=False)
    expected = FormingTuning(reach_sizes=3.0, krylov_loose=0.1,
                             increment=IncrementTuning(release_steps=8))
    assert case.control.tuning == expected
    assert "tuning (control.dat tune): krylov_loose 0.1, reach_sizes 3, " \
        "increment.release_steps 8" in case.summary()
    assert build_problem(read_case(tuned_case(tmp_path / "b", "tune touch_depth 0.01"))
                         ).tuning == FormingTuning(touch_depth=0.01)


def test_a_deck_without_tune_lines_runs_with_the_default_tuning(tmp_path: Path) -> None:
    from ddpy.app.runner import build_problem

    case = read_case(copy_example("bending", tmp_path))
    assert case.control.tuning == FormingTuning()
    assert build_problem(case).tuning == FormingTuning()
    assert "tuning" not in case.summary()


@pytest.mark.parametrize(("lines", "expected"), [
    ("tune slak 1.1", "unknown tuning name 'slak': expected one of touching, reuse_from, "),
    ("tune krylov_max 2.5", "expected an integer for tune krylov_max, got '2.5'"),
    ("tune reach_sizes big", "expected a number for tune reach_sizes"),
    ("tune reach_sizes", "expected 'tune NAME VALUE'"),
    ("tune increment.slack 1.1\ntune increment.slack 1.2",
     "'tune increment.slack' given twice (first at line"),
    ("tune krylov_loose 1e-3\ntune krylov_tight 1e-2",
     "tune krylov_tight must not exceed krylov_loose (0.001), got 0.01"),
    ("phase extra\n  tune slack 1\nend", "'tune' belongs at the top of control.dat"),
])
def test_tune_errors_name_their_line(tmp_path: Path, lines: str, expected: str) -> None:
    case = tuned_case(tmp_path, lines)
    last = lines.splitlines()[-1 if "phase" not in lines else 1].strip()
    number = next(k for k, line in enumerate((case / "control.dat").read_text().splitlines(), 1)
                  if line.split("#")[0].strip() == last)
    with pytest.raises(DeckError) as error:
        read_case(case, geometry=False)
    found = next(e for e in error.value.errors if e.line == number)
    assert expected in found.message, str(error.value)
    if "unknown" in expected:  # every valid name listed
        assert all(name in found.message for name in tuning_ranges())


def test_every_tuning_field_has_one_range_and_a_tune_name() -> None:
    forming = {f.name for f in dataclasses.fields(FormingTuning)} - {"increment"}
    increment = {f"increment.{f.name}" for f in dataclasses.fields(IncrementTuning)}
    assert set(tuning_ranges()) == forming | increment
    for name, admissible in tuning_ranges().items():  # each default lies in its range
        assert admissible.holds(tuning_default(name)), name


def test_input_format_lists_every_tuning_name_with_its_default_and_range() -> None:
    text = DOC.read_text()
    section = text[text.index("### Tuning"):]
    section = section[:section.index("\n#")]
    rows = re.findall(r"^\| `([a-z_.]+)` \| ([^|]+) \| ([^|]+) \|", section, re.M)
    listed = {name: (default.strip(), values.strip()) for name, default, values in rows}
    assert list(listed) == list(tuning_ranges())
    for name, admissible in tuning_ranges().items():
        default, values = listed[name]
        assert float(default) == pytest.approx(tuning_default(name), rel=1e-12), name
        assert values == admissible.text, name
