"""Every shipped example and built-in case runs to its end through ``ddpy run``, and its
answer is sane.

- ``examples/strip_draw`` and ``examples/calculix_bending`` (through ``ddpy run
  bending.inp``, converted first) whole: a few seconds each on one thread;
- ``examples/bending`` and the built-in cylindrical bending (``ddpy run``) over the first
  quarter of their punch travel (7.1 of 28.5 mm) and springback: whole, each takes about a
  minute on one thread;
- the built-in deep drawing (``ddpy run deep-drawing``) as its smaller variant (one layer
  of solid-shells), whole, in tests/test_reverse_deep_drawing.py, which checks the same of
  it (its tolerances with assert_converged_within_tolerances below).

Each run: completed; every converged increment's recorded residual and correction within
its phase's tolerances (a loop that accepts an increment on one criterion alone, or
records another measure than the one it judged, shows here); the lead tool pushed back
against its motion, its largest force within a factor 2 below and 5 above a plastic
bending estimate (measured: 1.8 times it for the bendings, 3.1 for the strip, which is
bent and unbent over two radii and drawn with friction); the blank's volume kept to 1 %
(plastic flow keeps it and elastic strains change it by about 1e-3, but the solid-shell's
nodes lose 0.4 % of the strip's volume by the end, up to 2.5 % in the elements wrapped
around the 5 mm radii; the hexahedron keeps it to 1e-4 there).
"""

from __future__ import annotations

import re
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from ddpy.app.cli import main
from ddpy.app.runner import BUILT_IN_CASES, RESULTS
from ddpy.io.case import Phase
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader
from ddpy.studies.drawing import hexahedron_volumes

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@dataclass(frozen=True)
class Example:
    """A case to run: its folder (or .inp file inside it), the fraction of its travel run,
    and the lever (mm) of its plastic bending estimate of the lead tool's force,
    sigma_0 w t^2 / (4 lever): the die shoulder's distance from the punch axis for a
    bending (the moment over the half span), the die radius for the strip drawn over it."""

    source: Path
    inp: str | None = None
    fraction: float = 1.0
    lever: float = 1.0


CASES = {
    "examples/bending": Example(EXAMPLES / "bending", fraction=0.25, lever=29.5),
    "examples/strip_draw": Example(EXAMPLES / "strip_draw", lever=5.0),
    "examples/calculix_bending": Example(EXAMPLES / "calculix_bending", inp="bending.inp",
                                         lever=14.0),
    "cylindrical-bending": Example(BUILT_IN_CASES["cylindrical-bending"], fraction=0.25,
                                   lever=29.5),
}


def shorten(case: Path, fraction: float) -> None:
    """Every tool motion of control.dat times ``fraction``; output_at travels dropped (the
    phase ends still write fields)."""
    control = case / "control.dat"
    text = control.read_text()

    def scaled(m: re.Match[str]) -> str:
        return m.group(1) + " ".join(f"{fraction * float(v):.6g}" for v in m.group(2).split())

    text = re.sub(r"(?m)^(\s*move\s+\S+\s+)(\S+\s+\S+\s+\S+)", scaled, text)
    control.write_text(re.sub(r"(?m)^\s*output_at\b.*\n", "", text))


def assert_converged_within_tolerances(history: dict[str, NDArray], phases: Sequence[Phase],
                                       name: str = "") -> None:
    """Every increment of a run's ``history`` (ResultsReader.history) recorded a residual and
    a correction within the tolerances of its phase: the measures the loop judged
    convergence on (a loop that accepts an increment on one criterion alone, or records
    another measure than the one it judged, shows here)."""
    phase = history["phase"]
    force = np.array([phases[p].newton.force_tolerance for p in phase])
    displacement = np.array([phases[p].newton.displacement_tolerance for p in phase])
    worst = np.argmax(history["residual_force"] / force)
    assert history["residual_force"][worst] <= force[worst], (name, int(worst))
    worst = np.argmax(history["residual_displacement"] / displacement)
    assert history["residual_displacement"][worst] <= displacement[worst], (name, int(worst))


def run_example(name: str, folder: Path) -> dict[str, Any]:
    """Run the case ``name`` in ``folder`` with ``ddpy run`` on one thread; the numbers the
    tests check."""
    example = CASES[name]
    case = folder / "case"
    shutil.copytree(example.source, case)
    if example.inp is not None:
        code = main(["run", str(case / example.inp), "--output", str(folder / "out"),
                     "--threads", "1"])
        case = case / f"{Path(example.inp).stem}_case"
    else:
        if example.fraction < 1.0:
            shorten(case, example.fraction)
        code = main(["run", str(case), "--output", str(folder / "out"), "--threads", "1"])
    decks = read_case(case)
    with ResultsReader(folder / "out" / RESULTS) as r:
        history = r.history()
        phases = history["phase"]
        elements = r.elements
        volumes = [float(hexahedron_volumes(x, elements).sum())
                   for x in (r.nodes, r.field("coordinates", r.frames[-1].index))]
        forming = [k for k, p in enumerate(decks.phases) if not p.is_springback]
        lead = decks.phases[forming[0]].lead
        assert lead is not None
        motion = decks.phases[forming[0]].displacement(lead)
        # The force on the lead tool along its motion: negative where the blank resists.
        along = r.tool_force(lead)[np.isin(phases, forming)] @ (motion / np.linalg.norm(motion))
    mesh = decks.mesh.nodes
    return {
        "code": code, "phases": phases, "along": along, "history": history,
        "case": decks,
        "estimate": (decks.material.material.hardening.initial_yield_stress
                     * np.ptp(mesh[:, 1]) * np.ptp(mesh[:, 2]) ** 2 / (4.0 * example.lever)),
        "volumes": volumes,
        "n_phases": len(decks.phases),
    }


@pytest.fixture(scope="module", params=sorted(CASES))
def run(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
        ) -> dict[str, Any]:
    return {"name": request.param,
            **run_example(request.param, tmp_path_factory.mktemp("example"))}


def test_it_runs_every_phase_to_its_end(run: dict[str, Any]) -> None:
    assert run["code"] == 0, run["name"]
    assert set(run["phases"]) == set(range(run["n_phases"])), run["name"]


def test_every_increment_converged_within_its_phase_tolerances(run: dict[str, Any]) -> None:
    assert_converged_within_tolerances(run["history"], run["case"].phases, run["name"])


def test_the_lead_tool_is_pushed_back_with_a_force_of_the_estimated_order(
        run: dict[str, Any]) -> None:
    along = run["along"]
    assert along.max() <= 1e-6 * np.abs(along).max(), run["name"]  # never pulled along
    peak = -along.min()
    assert run["estimate"] / 2.0 <= peak <= 5.0 * run["estimate"], (run["name"], peak,
                                                                    run["estimate"])


def test_the_blank_keeps_its_volume(run: dict[str, Any]) -> None:
    initial, last = run["volumes"]
    assert abs(last / initial - 1.0) < 1e-2, (run["name"], last / initial)
