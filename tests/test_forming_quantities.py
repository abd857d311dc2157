"""Forming quantities in the results (docs/results-format.md): thickness and thinning, major
and minor strains of the top, middle and bottom surfaces, nodal plastic strain and contact
pressure, each against a case computed by hand."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ddpy.geometry.surfaces import NagataSurface
from ddpy.io.results import ResultsReader, ResultsWriter
from ddpy.model import (
    FormingProblem,
    FormingResult,
    HexMesh,
    Hill48,
    Material,
    RigidTool,
    Solid,
    Swift,
)
from ddpy.model.forming_quantities import SheetMeasures, nodal_average

#: Elastic to the end of these tests (a yield stress of about 10 GPa).
ELASTIC = Material(210e3, 0.3, Hill48.von_mises(), Swift(1e4, 1.0, 0.0))


def stretched(mesh: HexMesh, stretch: tuple[float, float, float],
              angle_deg: float = 30.0) -> np.ndarray:
    """Displacements of a homogeneous stretch along x, y, z followed by a rigid rotation
    about z (the strains must not see it) and a shift."""
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    x = mesh.nodes @ (rotation @ np.diag(stretch)).T + [3.0, -1.0, 2.0]
    return x - mesh.nodes


def test_a_homogeneously_stretched_blank_has_its_thinning_and_strains(tmp_path: Path) -> None:
    """A 2-layer blank stretched by 1.2 along x and 0.9 along y, its thickness by 1 / 1.08
    (volume kept), then turned: thinning 100 (1 - 1 / 1.08) % at every node, major ln 1.2 and
    minor ln 0.9 on each of the three surfaces of every element, through the results file."""
    mesh = HexMesh.box(4.0, 3.0, 1.0, 4, 3, 2)
    u = stretched(mesh, (1.2, 0.9, 1.0 / 1.08))
    with ResultsWriter(tmp_path / "r.h5", mesh, ["punch"]) as out:
        out.fields(displacement=u, stress=np.zeros((mesh.n_elements, 6)),
                   plastic_strain=np.zeros(mesh.n_elements),
                   contact_state=np.zeros(mesh.n_nodes), contact_force=np.zeros((mesh.n_nodes, 3)))
    with ResultsReader(tmp_path / "r.h5") as r:
        frame = r.frame()
        initial = r.frame(0)
    np.testing.assert_allclose(frame["thinning"], 100.0 * (1.0 - 1.0 / 1.08), rtol=1e-12)
    np.testing.assert_allclose(frame["thickness"], 1.0 / 1.08, rtol=1e-12)
    for surface in ("top", "middle", "bottom"):
        np.testing.assert_allclose(frame[f"major_strain_{surface}"], np.log(1.2), rtol=1e-12)
        np.testing.assert_allclose(frame[f"minor_strain_{surface}"], np.log(0.9), rtol=1e-12)
        np.testing.assert_array_equal(initial[f"major_strain_{surface}"], 0.0)
    np.testing.assert_array_equal(initial["thinning"], 0.0)


def test_bending_strains_differ_between_the_surfaces() -> None:
    """A blank bent to a cylinder of radius 10 about y (mid-surface unstretched): the top
    surface stretched by (10 + t/2) / 10, the bottom shortened by (10 - t/2) / 10, the
    middle not at all, along x; across (y) nothing: major and minor per surface."""
    mesh = HexMesh.box(6.0, 1.0, 1.0, 60, 1, 1)
    radius = 10.0
    angle = mesh.nodes[:, 0] / radius
    r = radius + mesh.nodes[:, 2] - 0.5
    x = np.column_stack([r * np.sin(angle), mesh.nodes[:, 1], r * np.cos(angle)])
    strains = SheetMeasures(mesh.nodes, mesh.elements, mesh.normal).surface_strains(
        x - mesh.nodes)
    # The chord of a 0.1 mm element over the arc: the faces' lengths are chords.
    chord = 2.0 * np.sin(0.05 / radius) * radius / 0.1
    np.testing.assert_allclose(strains["major_top"], np.log(chord * 10.5 / 10.0), rtol=1e-9)
    np.testing.assert_allclose(strains["minor_bottom"], np.log(chord * 9.5 / 10.0),
                               rtol=1e-9)
    np.testing.assert_allclose(strains["major_middle"], 0.0, atol=1e-10)
    np.testing.assert_allclose(strains["minor_middle"], np.log(chord), rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(strains["minor_top"], 0.0, atol=1e-10)
    np.testing.assert_allclose(strains["major_bottom"], 0.0, atol=1e-10)


def test_nodal_plastic_strain_extrapolates_a_linear_field_exactly() -> None:
    """Gauss-point values of a field linear in x, y and z (positive everywhere) come to the
    nodes exact: extrapolated within each element, the same from every element around a
    node."""
    mesh = HexMesh.box(3.0, 2.0, 1.0, 3, 2, 2)
    corner = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                       [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]]) / np.sqrt(3.0)
    x = mesh.nodes[mesh.elements]                                      # (m, 8, 3)
    shape = np.prod(1.0 + corner[:, None, :] * np.array(
        [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
         [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]])[None, :, :], axis=2) / 8.0
    points = np.einsum("pa,mai->mpi", shape, x)                        # Gauss points
    field = lambda p: 0.1 + 0.02 * p[..., 0] + 0.03 * p[..., 1] + 0.05 * p[..., 2]  # noqa: E731
    nodal = nodal_average(mesh.elements, field(points), mesh.n_nodes)
    np.testing.assert_allclose(nodal, field(mesh.nodes), rtol=1e-12)
    # Element values are averaged as they are.
    np.testing.assert_allclose(nodal_average(mesh.elements, np.ones(mesh.n_elements),
                                             mesh.n_nodes), 1.0)


def flat_press(contact: str) -> tuple[FormingProblem, HexMesh, FormingResult]:
    """A 2 x 2 x 0.5 mm quarter blank on a support (its bottom held along z, symmetry planes
    x = 0 and y = 0) pressed by a flat frictionless punch 1 um down: a homogeneous
    compression. Returns the problem, the mesh and the result."""
    mesh = HexMesh.box(2.0, 2.0, 0.5, 4, 4, 2)
    plane = NagataSurface([[-5, -5, 0.5], [5, -5, 0.5], [5, 5, 0.5], [-5, 5, 0.5]],
                          [[0, 0, -1]] * 4, [[0, 3, 2, 1]])
    punch = RigidTool("punch", plane, mesh.select(z=0.5), facing=(0, 0, 1), contact=contact)
    problem = FormingProblem(Solid(mesh, ELASTIC), [punch])
    problem.fix(mesh.select(z=0.0), "z")
    problem.fix(mesh.select(x=0.0), "x")
    problem.fix(mesh.select(y=0.0), "y")
    result = problem.run({"punch": (0, 0, -1e-3)}, max_increment=1e-3, phase="press")
    return problem, mesh, result


@pytest.mark.parametrize("contact", ["gauss", "node", "surface"])
def test_a_flat_punch_presses_with_its_force_over_the_area(contact: str) -> None:
    """Every node under the flat punch carries the pressure force / area, the area that of
    the blank's top face now (it widened a little); the nodes below carry none."""
    problem, mesh, result = flat_press(contact)
    force = float(result.tool_forces["punch"][-1][2])
    x = mesh.nodes + problem.u
    top = mesh.select(z=0.5)
    area = np.ptp(x[top, 0]) * np.ptp(x[top, 1])
    assert area > 4.0  # the Poisson widening
    frame = result.frames[-1]  # the run's end, as problem.fields() gives it
    assert (frame.increment, frame.phase, frame.travel) == (1, "press", pytest.approx(1e-3))
    assert force > 0.0
    np.testing.assert_allclose(frame.contact_pressure[top], force / area, rtol=1e-6)
    np.testing.assert_array_equal(np.delete(frame.contact_pressure, top), 0.0)
    # E times the blank's strain (uniaxial stress): the units are MPa.
    shortening = -problem.u[top, 2].mean()
    assert force / area == pytest.approx(210e3 * shortening / 0.5, rel=1e-2)


def test_a_run_gives_its_fields_as_meshio_meshes_for_a_time_series(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """FormingResult.frames: the fields at the end of each run, as a meshio mesh that a
    TimeSeriesWriter takes (points and cells once, the data per frame) and reads back."""
    import meshio

    problem, mesh, result = flat_press("gauss")
    problem.run({"punch": (0, 0, 1e-3)}, max_increment=1e-3, phase="lift", result=result)
    assert [f.phase for f in result.frames] == ["press", "lift"]
    monkeypatch.chdir(tmp_path)  # (meshio finds the .h5 from the working folder)
    with meshio.xdmf.TimeSeriesWriter("blank.xdmf") as w:
        first = result.frames[0].to_meshio()
        w.write_points_cells(first.points, first.cells)
        for k, frame in enumerate(result.frames):
            m = frame.to_meshio()
            w.write_data(float(k), point_data=m.point_data, cell_data=m.cell_data)
    with meshio.xdmf.TimeSeriesReader("blank.xdmf") as r:
        points, _ = r.read_points_cells()
        data = [r.read_data(k) for k in range(r.num_steps)]
    np.testing.assert_array_equal(points, mesh.nodes)
    top = mesh.select(z=0.5)
    assert data[0][1]["contact_pressure"][top].min() > 0.0
    np.testing.assert_array_equal(data[1][1]["contact_pressure"], 0.0)  # lifted off
    np.testing.assert_allclose(data[0][1]["displacement"], result.frames[0].displacement)
    for name in ("stress", "plastic_strain", "major_strain_top", "minor_strain_bottom"):
        assert data[0][2][name][0].shape[0] == mesh.n_elements
    for name in ("thickness", "thinning", "plastic_strain_nodal"):
        assert data[0][1][name].shape == (mesh.n_nodes,)
