"""Every increment a run accepts met its phase's convergence tolerances, as its results file
records them: the built-in cases and the shipped examples, each over a short travel.

A convergence test that accepts an increment on one criterion alone (the force residual or
the correction) leaves every other test of the Newton loop standing; the recorded residuals
show it (docs/results-format.md: what convergence is judged on)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from ddpy.app.runner import BUILT_IN_CASES, RESULTS, run_case
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: Every case folder shipped: the built-in cases and the examples with decks.
CASES = {**{name: path for name, path in BUILT_IN_CASES.items()},
         **{p.parent.name: p.parent for p in sorted(EXAMPLES.glob("*/control.dat"))}}
#: Longest tool motion of a phase here (mm): a few increments of each phase, contact made.
TRAVEL = 0.1
#: Most increments of a springback phase here.
SPRINGBACK_INCREMENTS = 4
MOVE = re.compile(r"(?m)^(\s*move\s+\S+)\s+(\S+)\s+(\S+)\s+(\S+)")


def shortened(source: Path, folder: Path) -> Path:
    """A copy of the case whose every tool motion is cut to at most TRAVEL mm (the same
    direction), whose springback takes at most SPRINGBACK_INCREMENTS increments and whose
    fields are written at the phase ends only."""
    case = folder / source.name
    shutil.copytree(source, case)
    control = case / "control.dat"
    text = re.sub(r"(?m)^\s*output_at\b.*$", "", control.read_text())
    text = re.sub(r"(?m)^(\s*increments\s+)(\d+)",
                  lambda m: f"{m.group(1)}{min(int(m.group(2)), SPRINGBACK_INCREMENTS)}", text)

    def cut(match: re.Match[str]) -> str:
        motion = np.array([float(match.group(k)) for k in (2, 3, 4)])
        motion *= min(1.0, TRAVEL / float(np.linalg.norm(motion)))
        return f"{match.group(1)}  {motion[0]:.6g} {motion[1]:.6g} {motion[2]:.6g}"

    control.write_text(MOVE.sub(cut, text))
    return case


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_accepted_increment_met_its_phases_tolerances(name: str, tmp_path: Path
                                                            ) -> None:
    case = read_case(shortened(CASES[name], tmp_path))
    outcome = run_case(case, tmp_path / "out", threads=1)
    assert outcome.status == "completed", outcome.message
    with ResultsReader(tmp_path / "out" / RESULTS) as results:
        phase = results.curve("phase").astype(int)
        force, correction = results.curve("residual_force"), results.curve("residual_displacement")
        rows = results.iterations()
        iterations = results.curve("iterations").astype(int)
    assert set(phase) == set(range(len(case.phases)))  # every phase ran
    assert iterations.sum() > len(phase)  # Newton had work to do: the checks have a say
    force_tolerance = np.array([case.phases[p].newton.force_tolerance for p in phase])
    correction_tolerance = np.array([case.phases[p].newton.displacement_tolerance
                                     for p in phase])
    assert np.all(force <= force_tolerance), (force / force_tolerance).max()
    assert np.all(correction <= correction_tolerance), (correction / correction_tolerance).max()
    # The last Newton row of each increment is what the increment records: the residual and
    # the error the test judged (the correction, or less once whole steps contract).
    last = np.flatnonzero(np.diff(rows["increment"], append=np.inf) != 0)
    np.testing.assert_array_equal(rows["increment"][last], np.arange(1, len(phase) + 1))
    np.testing.assert_array_equal(rows["residual_force"][last], force)
    np.testing.assert_array_equal(rows["displacement_error"][last], correction)
    assert np.all(rows["displacement_error"][last] <= rows["residual_displacement"][last])
