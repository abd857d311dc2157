"""Results files: synthetic runs written with ResultsWriter, read back with ResultsReader and
with meshio's XDMF reader, also after the writer was killed or never closed."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np
import pytest
from deckutil import EXAMPLES

from ddpy.io.decks import read_case
from ddpy.io.results import LIMITS, Frame, ResultsReader, ResultsWriter, Timings

TOOLS = ("punch", "die")


@pytest.fixture(scope="module")
def mesh():
    return read_case(EXAMPLES / "bending", geometry=False).mesh


def synthetic(mesh, k: int) -> dict:
    """Fields of increment k: a uniform stretch through the thickness and some stresses."""
    n, m = mesh.n_nodes, mesh.n_elements
    u = np.zeros((n, 3))
    u[:, 2] = 0.01 * k * mesh.nodes[:, 2]  # thickness 1 + 0.01 k
    u[:, 0] = 1e-3 * k * mesh.nodes[:, 0]
    stress = np.tile([100.0 * k, 0, 0, 0, 0, 0], (m, 8, 1))
    stress[..., 0] += np.arange(8)  # varies over the Gauss points
    stress[..., 3] = 1.0  # xy
    status = (np.arange(n) % 3).astype(np.int8)
    force = np.outer(status, [0.0, 0.0, -k])
    return {"displacement": u, "stress": stress, "plastic_strain": np.full((m, 8), 0.001 * k),
            "contact_state": status, "contact_force": force,
            "contact_tool": np.where(status > 0, 0, -1)}


def write_run(path: Path, mesh, increments: int = 6, every: int = 3) -> None:
    with ResultsWriter(path, mesh, TOOLS, ("forming", "springback"), title="synthetic",
                       case="examples/bending") as out:
        for k in range(1, increments + 1):
            number = out.increment(
                phase=0, step=0.1, travel=0.1 * k, tool_displacement=[[0, 0, -0.1 * k], [0] * 3],
                tool_force=[[0, 0, 10.0 * k], [0, 0, -10.0 * k]], iterations=3 + k % 2,
                residual_force=1e-5, residual_displacement=2e-5,
                timings=Timings(0.1, 0.02, 0.3, 0.01), nodes_in_contact=[k, 2 * k],
                cutbacks=k % 2, rmin=0.5, limit="strain" if k % 2 else 0,
                residual_history=[[1.0, 1.0], [1e-2, 1e-3], [1e-5, 2e-5]])
            assert number == k
            if k % every == 0:
                frame = out.fields(**synthetic(mesh, k))
                travel = pytest.approx(0.1 * k)  # (the time: the travel over the run)
                assert frame == Frame(k // every, k, 0, travel, travel)


def test_write_and_read_back(tmp_path: Path, mesh) -> None:
    path = tmp_path / "run.h5"
    write_run(path, mesh)
    with ResultsReader(path) as r:
        assert (r.title, r.tools, r.phases, r.units) == ("synthetic", TOOLS,
                                                         ("forming", "springback"), "mm N MPa s")
        assert r.element == "hexahedron"  # the writer's default
        assert r.n_increments == 6
        np.testing.assert_array_equal(r.curve("increment"), np.arange(1, 7))
        np.testing.assert_allclose(r.tool_force("punch")[:, 2], 10.0 * np.arange(1, 7))
        np.testing.assert_allclose(r.tool_displacement("punch")[:, 2], -0.1 * np.arange(1, 7))
        h = r.history()
        np.testing.assert_allclose(h["time_total"], 0.43)
        np.testing.assert_array_equal(h["nodes_in_contact"][:, 1], 2 * np.arange(1, 7))
        assert [LIMITS[c] for c in h["limit"][:2]] == ["strain", "max_increment"]
        it = r.iterations()
        assert len(it["increment"]) == 18 and it["iteration"][:3].tolist() == [1, 2, 3]
        frames = r.frames
        assert [f.increment for f in frames] == [0, 3, 6] and frames[0].time == 0.0
        f6 = r.frame()
        expected = synthetic(mesh, 6)
        np.testing.assert_allclose(f6["displacement"], expected["displacement"])
        np.testing.assert_allclose(f6["coordinates"], mesh.nodes + expected["displacement"])
        np.testing.assert_allclose(r.stress(), np.tile([603.5, 0, 0, 1, 0, 0], (216, 1)))
        np.testing.assert_allclose(f6["stress"], np.tile([603.5, 1, 0, 0, 0, 0], (216, 1)))
        np.testing.assert_allclose(f6["von_mises"], np.sqrt(603.5**2 + 3))
        np.testing.assert_allclose(f6["plastic_strain"], 0.006)
        np.testing.assert_allclose(f6["thickness"], 1.06)
        np.testing.assert_allclose(r.field("thickness", 0), 1.0)
        np.testing.assert_array_equal(f6["contact_tool"], expected["contact_tool"])
        np.testing.assert_allclose(r.nodes, mesh.nodes)
        with pytest.raises(KeyError, match="no tool"):
            r.tool_force("holder")
        with pytest.raises(IndexError):
            r.frame(5)
    with h5py.File(path, "r") as f:  # the file's own layout (docs/results-format.md)
        assert f["fields/000002/stress"].attrs["units"] == "MPa"
        assert f["increments/tool_force"].attrs["units"] == "N"
        assert f.attrs["closed"]
        # The columns grow by blocks while the run writes; a closed file has its rows only.
        assert {d.shape[0] for d in f["increments"].values()} == {6}
        assert {d.shape[0] for d in f["iterations"].values()} == {18}


def test_factorization_and_solve_times_apart(tmp_path: Path, mesh) -> None:
    """LU factorizations and solutions are timed apart; a file written before time_solve
    existed gets the column, zero for its rows, when a run continues in it."""
    path = tmp_path / "run.h5"
    with ResultsWriter(path, mesh, TOOLS) as out:
        for k in range(2):
            out.increment(phase=0, step=0.1, travel=0.1 * (k + 1),
                          tool_displacement=np.zeros((2, 3)), tool_force=np.zeros((2, 3)),
                          iterations=3, residual_force=1e-5, residual_displacement=1e-5,
                          timings=Timings(assembly=0.1, contact=0.02, factorization=0.3,
                                          rest=0.01, solve=0.5))
    with ResultsReader(path) as r:
        h = r.history()
        np.testing.assert_allclose(h["time_solve"], 0.5)
        np.testing.assert_allclose(h["time_factorization"], 0.3)
        np.testing.assert_allclose(h["time_total"], 0.93)

    with h5py.File(path, "r+") as f:  # as an older version wrote it
        del f["increments/time_solve"]
    with ResultsWriter.reopen(path, increments=1, iterations=0, frames=1) as out:
        out.increment(phase=0, step=0.1, travel=0.2, tool_displacement=np.zeros((2, 3)),
                      tool_force=np.zeros((2, 3)), iterations=3, residual_force=1e-5,
                      residual_displacement=1e-5, timings=Timings(solve=0.25))
    with ResultsReader(path) as r:
        np.testing.assert_allclose(r.history()["time_solve"], [0.0, 0.25])


def test_iteration_rows_keep_step_and_switches(tmp_path: Path, mesh) -> None:
    """An iteration row holds its step, what switched and the estimated error (7 columns
    given), -1 for them where only the residuals are given, and a file written before those
    columns existed gets them, -1 for its rows, when a run continues in it."""
    path = tmp_path / "run.h5"
    full = [[1.0, np.inf, 0.0, 0, 0, 0, np.inf], [1e-3, 1e-2, 0.5, 12, 3, 40, 1e-2],
            [1e-6, 1e-5, 1.0, 0, 0, 2, 1e-7]]
    with ResultsWriter(path, mesh, TOOLS) as out:
        for history in (full, [row[:2] for row in full]):
            out.increment(phase=0, step=0.1, travel=0.1, tool_displacement=np.zeros((2, 3)),
                          tool_force=np.zeros((2, 3)), iterations=2, residual_force=1e-6,
                          residual_displacement=1e-5, residual_history=history)
        with pytest.raises(ValueError, match="2 or 7 columns"):
            out.increment(phase=0, step=0.1, travel=0.1, tool_displacement=np.zeros((2, 3)),
                          tool_force=np.zeros((2, 3)), iterations=2, residual_force=1e-6,
                          residual_displacement=1e-5, residual_history=[[1.0, 1.0, 1.0]])
    with ResultsReader(path) as r:
        it = r.iterations()
    np.testing.assert_array_equal(it["step"], [0.0, 0.5, 1.0, -1, -1, -1])
    np.testing.assert_array_equal(it["points_switched"], [0, 12, 0, -1, -1, -1])
    np.testing.assert_array_equal(it["pairs_switched"], [0, 3, 0, -1, -1, -1])
    np.testing.assert_array_equal(it["yield_switched"], [0, 40, 2, -1, -1, -1])
    np.testing.assert_array_equal(it["displacement_error"], [np.inf, 1e-2, 1e-7, -1, -1, -1])

    with h5py.File(path, "r+") as f:  # as an older version wrote it
        for name in ("step", "points_switched", "pairs_switched", "yield_switched",
                     "displacement_error"):
            del f[f"iterations/{name}"]
    with ResultsWriter.reopen(path, increments=1, iterations=3, frames=1) as out:
        out.increment(phase=0, step=0.1, travel=0.2, tool_displacement=np.zeros((2, 3)),
                      tool_force=np.zeros((2, 3)), iterations=2, residual_force=1e-6,
                      residual_displacement=1e-5, residual_history=full)
    with ResultsReader(path) as r:
        it = r.iterations()
    np.testing.assert_array_equal(it["increment"], [1, 1, 1, 2, 2, 2])
    np.testing.assert_array_equal(it["yield_switched"], [-1, -1, -1, 0, 40, 2])
    np.testing.assert_array_equal(it["step"], [-1, -1, -1, 0.0, 0.5, 1.0])
    np.testing.assert_array_equal(it["displacement_error"], [-1, -1, -1, np.inf, 1e-2, 1e-7])


def test_xdmf_read_by_meshio(tmp_path: Path, mesh) -> None:
    meshio = pytest.importorskip("meshio")
    path = tmp_path / "run.h5"
    write_run(path, mesh)
    xdmf = path.with_suffix(".xdmf")
    root = ET.parse(xdmf).getroot()
    assert root.tag == "Xdmf" and root.attrib["Version"] == "3.0"
    with meshio.xdmf.TimeSeriesReader(xdmf) as reader:
        points, cells = reader.read_points_cells()
        np.testing.assert_allclose(points, mesh.nodes)
        assert cells[0].type == "hexahedron"
        np.testing.assert_array_equal(cells[0].data, mesh.elements)
        assert reader.num_steps == 3
        times = []
        for step in range(reader.num_steps):
            t, point_data, cell_data = reader.read_data(step)
            times.append(t)
        expected = synthetic(mesh, 6)
        np.testing.assert_allclose(point_data["displacement"], expected["displacement"])
        np.testing.assert_allclose(point_data["thickness"], 1.06)
        np.testing.assert_array_equal(point_data["contact_state"], expected["contact_state"])
        np.testing.assert_allclose(cell_data["stress"][0][0], [603.5, 1, 0, 0, 0, 0])
        np.testing.assert_allclose(cell_data["plastic_strain"][0], 0.006)
        assert times == pytest.approx([0.0, 0.3, 0.6])  # the punch's travel


def test_writer_checks(tmp_path: Path, mesh) -> None:
    path = tmp_path / "run.h5"
    with ResultsWriter(path, mesh, TOOLS) as out:
        good = dict(phase=0, step=0.1, travel=0.1, tool_displacement=np.zeros((2, 3)),
                    tool_force=np.zeros((2, 3)), iterations=2, residual_force=0.0,
                    residual_displacement=0.0)
        with pytest.raises(ValueError, match=r"tool_force must have shape \(2, 3\)"):
            out.increment(**{**good, "tool_force": np.zeros(3)})
        with pytest.raises(ValueError, match="unknown limit"):
            out.increment(**good, limit="luck")
        out.increment(**good)
        fields = synthetic(mesh, 1)
        with pytest.raises(ValueError, match="displacement must have shape"):
            out.fields(**{**fields, "displacement": np.zeros((3, 3))})
        out.fields(**fields, extra={"layer": np.arange(mesh.n_elements)})
        with pytest.raises(ValueError, match="must exceed the previous frame"):
            out.fields(**fields, time=0.0)
        with pytest.raises(ValueError, match="extra field"):
            out.fields(**fields, time=5.0, extra={"bad": np.zeros(7)})
    with pytest.raises(FileExistsError):
        ResultsWriter(path, mesh, TOOLS)
    case = read_case(EXAMPLES / "bending", geometry=False)
    with ResultsWriter.for_case(tmp_path / "case.h5", case) as out:
        assert out.tools == ("punch", "die") and out.phases == ("forming", "springback")
    with ResultsReader(tmp_path / "case.h5") as r:
        assert r.title == case.title and r.frames[0].increment == 0
    ResultsWriter(path, (mesh.nodes, mesh.elements), TOOLS, overwrite=True).close()
    with pytest.raises(ValueError, match="tools must name"):
        ResultsWriter(tmp_path / "x.h5", mesh, ())
    (tmp_path / "other.h5").write_bytes(Path(path).read_bytes())

    with h5py.File(tmp_path / "plain.h5", "w") as f:
        f["x"] = 1
    with pytest.raises(ValueError, match="not a ddpy results file"):
        ResultsReader(tmp_path / "plain.h5")


WRITER = textwrap.dedent("""
    import os, sys, time
    import numpy as np
    sys.path.insert(0, {tests!r})
    from test_results import synthetic, TOOLS
    from ddpy.io.decks import read_case
    from ddpy.io.results import ResultsWriter
    mesh = read_case({case!r}, geometry=False).mesh
    out = ResultsWriter({path!r}, mesh, TOOLS, ("forming",))
    for k in range(1, {count} + 1):
        out.increment(phase=0, step=0.1, travel=0.1 * k,
                      tool_displacement=[[0, 0, -0.1 * k], [0, 0, 0]],
                      tool_force=[[0, 0, k], [0, 0, -k]], iterations=3, residual_force=1e-5,
                      residual_displacement=1e-5)
        if k % 2 == 0:
            out.fields(**synthetic(mesh, k))
        print(k, flush=True)
    {ending}
""")


def run_writer(tmp_path: Path, count: int, ending: str) -> subprocess.Popen:
    script = WRITER.format(tests=str(Path(__file__).parent), case=str(EXAMPLES / "bending"),
                           path=str(tmp_path / "run.h5"), count=count, ending=ending)
    return subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)


def check_partial(path: Path, mesh, at_least: int) -> None:
    meshio = pytest.importorskip("meshio")
    with ResultsReader(path) as r:
        k = r.n_increments
        assert k >= at_least
        np.testing.assert_allclose(r.tool_force("punch")[:, 2], np.arange(1, k + 1))
        frames = r.frames
        assert [f.increment for f in frames[1:]] == list(range(2, k + 1, 2))[:len(frames) - 1]
        last = frames[-1].increment
        np.testing.assert_allclose(r.field("displacement"), synthetic(mesh, last)["displacement"])
    with meshio.xdmf.TimeSeriesReader(path.with_suffix(".xdmf")) as reader:
        reader.read_points_cells()
        assert reader.num_steps >= 1 + at_least // 2
        t, point_data, _ = reader.read_data(reader.num_steps - 1)
        np.testing.assert_allclose(point_data["displacement"],
                                   synthetic(mesh, last)["displacement"])


def test_killed_writer_leaves_a_readable_file(tmp_path: Path, mesh) -> None:
    process = run_writer(tmp_path, 10_000, "")
    assert process.stdout is not None
    for _ in range(5):
        process.stdout.readline()  # five increments flushed
    process.send_signal(signal.SIGKILL)
    process.wait()
    assert process.returncode == -signal.SIGKILL
    check_partial(tmp_path / "run.h5", mesh, 5)


def test_writer_never_closed(tmp_path: Path, mesh) -> None:
    process = run_writer(tmp_path, 6, "os._exit(0)")  # no close, no atexit, no finalizers
    process.communicate()
    assert process.returncode == 0
    check_partial(tmp_path / "run.h5", mesh, 6)
    with ResultsReader(tmp_path / "run.h5") as r:
        assert r.n_increments == 6
    with h5py.File(tmp_path / "run.h5", "r") as f:
        assert "closed" not in f.attrs


def test_xdmf_read_by_vtk(tmp_path: Path, mesh) -> None:
    """ParaView's XDMF reader (VTK's vtkXdmfReader)."""
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy

    path = tmp_path / "run.h5"
    write_run(path, mesh)
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(path.with_suffix(".xdmf")))
    reader.UpdateInformation()
    info = reader.GetOutputInformation(0)
    times = info.Get(vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS())
    assert times == pytest.approx((0.0, 0.3, 0.6))  # the lead tool's travel, mm
    reader.UpdateTimeStep(times[-1])
    grid = reader.GetOutputDataObject(0)
    assert (grid.GetNumberOfPoints(), grid.GetNumberOfCells()) == (mesh.n_nodes, 216)
    expected = synthetic(mesh, 6)["displacement"]
    np.testing.assert_allclose(vtk_to_numpy(grid.GetPoints().GetData()), mesh.nodes + expected)
    stress = vtk_to_numpy(grid.GetCellData().GetArray("stress"))
    np.testing.assert_allclose(stress[0], [603.5, 1, 0, 1, 0, 0, 0, 0, 0])  # full tensor
    np.testing.assert_allclose(vtk_to_numpy(grid.GetPointData().GetArray("thickness")), 1.06)


def test_files_written_before_the_rename_read_by_the_new_names(tmp_path: Path, mesh) -> None:
    """Files of earlier versions call the nodes' contact states contact_status: the reader
    answers to contact_state for them."""
    path = tmp_path / "run.h5"
    write_run(path, mesh)
    with h5py.File(path, "r+") as f:
        for group in f["fields"].values():
            group.move("contact_state", "contact_status")
    with ResultsReader(path) as r:
        expected = synthetic(mesh, 6)["contact_state"]
        np.testing.assert_array_equal(r.field("contact_state"), expected)
        np.testing.assert_array_equal(r.frame()["contact_state"], expected)
