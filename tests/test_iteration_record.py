"""What each Newton iteration records beside its residuals (ddpy.model.newton.Iteration): the
step's length and what changed since the previous iterate, the contact points whose
pressure turned on or off, the pairs whose state changed and the integration points that
turned from elastic to plastic or back; and the results file's iteration rows."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_runner import tiny_case

from ddpy.app.runner import RESULTS, run_case
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader
from ddpy.model.control import NewtonSettings
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.static import StaticProblem

#: Yields at 200 MPa, about 1e-3 of strain.
STEEL = Material(200e3, 0.3, Hill48.von_mises(), Swift(500.0, 0.01, 0.2))


@pytest.mark.parametrize("element", ["hexahedron", "solid-shell"])
def test_a_homogeneous_stretch_yields_every_point_in_the_first_correction(element: str
                                                                           ) -> None:
    """A block stretched uniformly by 1 % in one increment from the elastic start: the
    start is unstrained, the first correction (the elastic tangent's exact answer for a
    homogeneous field) takes every one of the 8 points of each element past yield at once,
    and the later corrections keep them plastic."""
    mesh = HexMesh.box(4.0, 2.0, 1.0, 2, 1, 1)
    problem = StaticProblem(Solid(mesh, STEEL, element=element))
    x = mesh.nodes
    problem.fix(np.flatnonzero(x[:, 0] == 0), "x")
    problem.fix(np.flatnonzero(x[:, 1] == 0), "y")
    problem.fix(np.flatnonzero(x[:, 2] == 0), "z")
    problem.fix(np.flatnonzero(x[:, 0] == 4.0), "x", lambda t: 0.04 * t)
    result = problem.solve(increments=1, newton=NewtonSettings(1e-10, 1e-10),
                           predictor="elastic")
    iterations = result.convergence[0]
    assert len(iterations) >= 3  # plastic: more than one correction
    start, first, *later = iterations
    assert (start.step, start.yield_switched) == (0.0, 0)
    assert first.yield_switched == 8 * mesh.n_elements
    assert all(it.yield_switched == 0 for it in later)
    assert all(it.points_switched == it.pairs_switched == 0 for it in iterations)  # no tools
    assert all(0.0 < it.step <= 1.0 for it in iterations[1:])


def test_the_results_file_records_each_iterations_step_and_switches(tmp_path: Path) -> None:
    """The strip drawn over a die with a holder (three phases, springback): every iteration
    row carries its step and switches; the start rows none; contact and yield switches
    happen while the strip is drawn, and none in the springback's last rows."""
    case = read_case(tiny_case(tmp_path / "case"))
    outcome = run_case(case, tmp_path / "out", threads=1)
    assert outcome.status == "completed", outcome.message
    with ResultsReader(tmp_path / "out" / RESULTS) as results:
        rows = results.iterations()
        phase = results.curve("phase").astype(int)
    start = rows["iteration"] == 1
    for name in ("step", "points_switched", "pairs_switched", "yield_switched"):
        assert np.all(rows[name][start] == 0), name
    assert np.all((rows["step"][~start] > 0.0) & (rows["step"][~start] <= 1.0))
    assert rows["yield_switched"].sum() > 0
    assert rows["points_switched"].sum() + rows["pairs_switched"].sum() > 0
    counts = np.stack([rows[name] for name in ("points_switched", "pairs_switched",
                                               "yield_switched")])
    assert counts.min() >= 0
    # the springback's last increment: tools gone, the blank settled
    last = rows["increment"] == len(phase)
    assert np.all(counts[:2, last] == 0)
