"""The tools in the results: each tool's tessellated surface in results.h5, placed at every
frame by its displacement, read back by VTK's own XDMF reader (ParaView's); the time axis is
the lead tools' travel (docs/results-format.md)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import vtk
from test_runner import tiny_case
from vtk.util.numpy_support import vtk_to_numpy

from ddpy.app.runner import RESULTS, run_case
from ddpy.geometry.surfaces import BezierSurface, NagataSurface
from ddpy.geometry.tessellation import MAX_SAG, tessellate
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The tiny strip draw (test_runner): punch, die and a gap-held holder, two forming
    phases of 2.05 and 0.5 mm, springback."""
    base = tmp_path_factory.mktemp("tools")
    outcome = run_case(read_case(tiny_case(base / "case")), base / "out")
    assert outcome.status == "completed", outcome.message
    return base / "out"


def blocks_at(path: Path, time: float) -> dict[str, object]:
    """The blocks VTK's vtkXdmfReader gives at ``time``, by name."""
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(path))
    reader.UpdateTimeStep(time)
    out = reader.GetOutputDataObject(0)
    return {out.GetMetaData(i).Get(vtk.vtkCompositeDataSet.NAME()): out.GetBlock(i)
            for i in range(out.GetNumberOfBlocks())}


def test_vtk_reads_the_tools_placed_at_each_frame(run: Path) -> None:
    xdmf = run / "results.xdmf"
    with ResultsReader(run / RESULTS) as r:
        frames = r.frames
        title = r.title
        step, phase = r.curve("step"), r.curve("phase")
        shown = {t: r.tool_surface(t, 0)[0] for t in r.tools}
        moved = r.curve("tool_displacement")
        increment_field = r.field("increment", 2)
    # Time: the lead tools' travel summed over the run (0.5 and 1 mm frames of the draw, its
    # end at 2.05, the free draw's end 0.5 mm later); springback 1 um after it.
    times = [f.time for f in frames]
    stroke = np.concatenate([[0.0], np.cumsum(step)])
    np.testing.assert_allclose(times[:-1], stroke[[f.increment for f in frames[:-1]]])
    assert times[1] == pytest.approx(0.5) and times[-2] == pytest.approx(2.55)
    assert times[-1] == pytest.approx(2.551) and phase[frames[-1].increment - 1] == 2
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(xdmf))
    reader.UpdateInformation()
    steps = reader.GetOutputInformation(0).Get(
        vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    np.testing.assert_allclose(steps, times, rtol=1e-12)
    # The increment number stays as a field of the blank.
    assert increment_field.tolist() == [frames[2].increment] * len(increment_field)
    for k in (1, 4):  # two frames of the draw: the punch moved on, the die stayed
        blocks = blocks_at(xdmf, times[k])
        assert set(blocks) == {"punch", "die", "holder", title}
        for t, name in enumerate(("punch", "die", "holder")):
            points = vtk_to_numpy(blocks[name].GetPoints().GetData())
            np.testing.assert_allclose(points, shown[name] + moved[frames[k].increment - 1, t],
                                       atol=1e-12)
        assert blocks["punch"].GetNumberOfCells() > 0
        blank = blocks[title]
        increment = vtk_to_numpy(blank.GetCellData().GetArray("increment"))
        assert set(increment.tolist()) == {frames[k].increment}
    assert moved[frames[4].increment - 1, 0, 2] == pytest.approx(-2.05)


def test_smooth_patches_are_cut_finely_enough_to_look_smooth() -> None:
    """A quarter cylinder of radius 10 as one bicubic Bezier patch: cut until every cell's
    sagitta is within MAX_SAG of the patch's size (its points on the surface, within the
    fit's 1e-3 of the circle); a facet is one cell."""
    k = 0.5522847498  # the cubic Bezier quarter circle
    arc = np.array([[10, 0], [10, 10 * k], [10 * k, 10], [0, 10]], dtype=float)
    net = np.zeros((4, 4, 3))
    net[..., :2] = arc[:, None, :]
    net[..., 2] = np.linspace(0.0, 5.0, 4)[None, :]
    points, cells, kinds = tessellate(BezierSurface([net]))
    radius = np.hypot(points[:, 0], points[:, 1])
    np.testing.assert_allclose(radius, 10.0, rtol=3e-4)
    cuts = int(np.sqrt(len(kinds)))
    assert len(kinds) == cuts**2 and cuts >= 10
    # The sagitta of a cell over 90 / cuts degrees is about MAX_SAG of the patch's size
    # (the patch's bulge over cuts^2 estimates it, 5 % short on an arc); one cut fewer
    # would leave it above.
    def sag(cuts: int) -> float:
        return 10.0 * (1.0 - np.cos(np.radians(90.0 / cuts) / 2.0))

    size = np.hypot(10.0 * np.sqrt(2.0), 5.0)
    assert sag(cuts - 1) > MAX_SAG * size and sag(cuts) <= 1.1 * MAX_SAG * size
    square = NagataSurface([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 0, 1]] * 4,
                           [[0, 1, 2, 3]], smooth=False)
    points, cells, kinds = tessellate(square)
    assert len(points) == 4 and kinds.tolist() == [4] and sorted(cells.tolist()) == [0, 1, 2, 3]
