"""Gauss-point contact (RigidTool(..., contact="gauss")): a penalty law with Coulomb friction
at the n x n Gauss points of the blank faces that meet a tool, its force spread to the
faces' nodes by the shape functions, in the same Newton loop (docs/theory/contact.md)."""

from __future__ import annotations

import numpy as np
import pytest
from jacobian_check import central_difference_errors
from test_surface_contact import ELASTIC, dome, last_rates, nodal_areas, slide_over_dome

from ddpy.geometry.surfaces import NagataSurface
from ddpy.model.contact import INACTIVE, SLIP, STICK
from ddpy.model.control import NewtonSettings
from ddpy.model.forming import FormingProblem, RigidTool
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.newton import Layout
from ddpy.model.solid import Solid

#: The penalty of these tests (N/mm^3): a 4 um press gives about 200 MPa.
PENALTY = 5e4


def block_on_dome(friction: float, points: int = 2
                  ) -> tuple[FormingProblem, HexMesh, RigidTool]:
    """A 1 x 1 x 0.5 mm block clamped at its top, its bottom on the dome's crest, its side
    y = -0.5 on a symmetry plane, pressed 4 um into the dome, then slid 2 um along x."""
    surface = dome()
    lift = float(surface.evaluate([0], [[0.5, 0.5]])[0][0, 2])
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, lift))
    tool = RigidTool("dome", surface, mesh.select(z=lift), friction=friction,
                     facing=(0, 0, -1), contact="gauss", penalty=PENALTY, points=points)
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=lift + 0.5), "xyz")
    problem.fix(mesh.select(y=-0.5), "y")
    problem.run({"dome": (0, 0, 4e-3)}, max_increment=2e-3)
    problem.run({"dome": (2e-3, 0, 0)}, max_increment=1e-3)
    return problem, mesh, tool


@pytest.mark.parametrize("barrier", [None, 0.005])
def test_multiplier_rows_join_no_nodes(barrier: float | None) -> None:
    """A Gauss-point pair's multiplier is eliminated (lambda = F(x)): its rows of the
    Jacobian hold dC/dlambda only, also the row of a held component (a slave on a
    symmetry plane, whose law is lambda_k = 0). Entries of the patch's nodes there would
    join those nodes to one another through the multiplier, which the mesh's pivot order
    does not see: on the bending benchmark's paper mesh, 410 such pairs took the LU from
    60 to 81 million factor entries and twice the flops. With a barrier the multiplier is
    the slave's own force, whose law rows hold its own node's entries and no other's."""
    surface = dome()
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, 0.0))
    tool = RigidTool("dome", surface, mesh.select(z=0.0), facing=(0, 0, -1),
                     contact="gauss", penalty=PENALTY, barrier=barrier)
    fixed = np.zeros((mesh.n_nodes, 3), dtype=bool)
    fixed[mesh.select(y=-0.5), 1] = True
    layout = Layout(Solid(mesh, ELASTIC), [tool], fixed)
    equations = layout.eqn.reshape(-1, 3)
    assert (equations[layout.node] < 0).any()  # held components
    in_law_rows = (layout.rows >= layout.nf) & (layout.cols < layout.nf)
    if barrier is None:
        assert not in_law_rows.any()
        return
    pair = (layout.rows[in_law_rows] - layout.nf) // 3
    own = equations[layout.node[pair]]
    assert np.all((own == layout.cols[in_law_rows][:, None]).any(axis=1))
    assert in_law_rows.sum() == 3 * (equations[layout.node] >= 0).sum()


@pytest.mark.parametrize("points", [2, 3])
def test_jacobian_with_open_and_slipping_points_matches_central_differences(points: int
                                                                            ) -> None:
    """The Jacobian of Gauss-point contact (the tool's curvature at every point, the
    friction history, slip) against central differences, at a state with open and
    slip pairs on the dome, with 2 x 2 and 3 x 3 points per face; measured 3e-10 of the
    equilibrium block, 1.2e-9 of the law's (without the curvature term 3.3e-5; with the
    tangential penalty's or the slip's pressure term of the wrong sign 1.9 and 0.6)."""
    problem, mesh, tool = block_on_dome(0.3, points)
    assert np.abs(problem.traction).max() > 0.0  # a friction history to start from
    rng = np.random.default_rng(7)
    u = problem.u + 1e-5 * rng.standard_normal(problem.u.shape) * ~problem.fixed
    # the column x = -0.5 lifted off the dome: every point of its faces opens
    u[tool.slaves[mesh.nodes[tool.slaves, 0] < -0.4], 2] += 0.05
    moved = {"dome": problem.position["dome"] + (3e-5, 1e-5, 2e-5)}
    equilibrium, law, state = central_difference_errors(problem, u, problem.force, moved, 3e-5)
    assert {INACTIVE, SLIP} <= set(state.tolist()), state
    assert equilibrium <= 1e-7 and law <= 1e-7, (equilibrium, law)


def test_jacobian_with_sticking_points_matches_central_differences() -> None:
    """Every closed point sticks (the dome moved back by a fraction of the elastic slip),
    a column lifted off (open):
    the stick branch's derivative, curvature and history included (measured 1.1e-10 and
    1.1e-9; without the curvature term 3.3e-5)."""
    problem, mesh, tool = block_on_dome(0.3)
    u = problem.u.copy()
    u[tool.slaves[mesh.nodes[tool.slaves, 0] < -0.4], 2] += 0.05  # open
    moved = {"dome": problem.position["dome"] + (-1e-5, 0, 1e-5)}
    equilibrium, law, state = central_difference_errors(problem, u, problem.force, moved,
                                                        3e-5)
    assert {INACTIVE, STICK} <= set(state.tolist()), state
    assert equilibrium <= 1e-7 and law <= 1e-7, (equilibrium, law)


def test_tool_reaction_is_the_sum_of_the_contact_forces() -> None:
    problem, _, tool = block_on_dome(0.3)
    result = problem.run({"dome": (1e-3, 0, 1e-3)}, max_increment=1e-3)
    total = problem.force.sum(axis=0)
    assert np.abs(total).max() > 1.0
    np.testing.assert_allclose(result.tool_forces["dome"][-1], -total, rtol=1e-12)
    # and the forces are what the Gauss points carry: the blank's equilibrium
    fint, _ = problem.solid.internal_force(problem.u, problem.solid_state)
    free = ~problem.fixed
    lumped = np.zeros_like(fint)
    np.add.at(lumped, tool.slaves, problem.force)
    np.testing.assert_allclose(fint[free], lumped[free], atol=1e-6 * np.abs(total).max())


def irregular_block() -> HexMesh:
    """A 1 x 1 x 0.5 mm block whose columns are irregular quadrilaterals."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, 0.0))
    nodes = mesh.nodes.copy()
    inner = (np.abs(nodes[:, 0]) < 0.4) & (np.abs(nodes[:, 1]) < 0.4)
    rng = np.random.default_rng(3)
    shift = rng.uniform(-0.08, 0.08, (mesh.n_nodes, 2))
    column = np.unique(np.round(mesh.nodes[:, :2], 9), axis=0, return_inverse=True)[1]
    nodes[inner, :2] += shift[column.ravel()][inner]
    return HexMesh(nodes, mesh.elements)


def press_on_plane(mesh: HexMesh, slope: float, points: int
                   ) -> tuple[FormingProblem, RigidTool, object]:
    """The block clamped at its top, pressed onto the plane z = slope x moved up by 1 um
    and 2 slope mm: every point of its bottom faces closed."""
    normal = np.array([-slope, 0.0, 1.0]) / np.hypot(slope, 1.0)
    plane = NagataSurface([[-5, -5, -5 * slope], [5, -5, 5 * slope], [5, 5, 5 * slope],
                           [-5, 5, -5 * slope]], [normal] * 4, [[0, 1, 2, 3]])
    tool = RigidTool("plane", plane, mesh.select(z=0.0), facing=(0, 0, -1), contact="gauss",
                     penalty=PENALTY, points=points)
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    result = problem.run({"plane": (0, 0, 1e-3 + 2 * abs(slope))}, max_increment=1e-3,
                         newton=NewtonSettings(1e-12, 1e-9))
    return problem, tool, result


@pytest.mark.parametrize("points", [2, 4])
def test_uniform_pressure_on_a_plane_patch_test(points: int) -> None:
    """The irregular block pressed onto a plane: every Gauss point sinks as deep, the
    pressure is uniform and each bottom node carries it times int N_a dA (3 x 3 Gauss
    points here), to rounding, with 2 x 2 and 4 x 4 points per face."""
    mesh = irregular_block()
    problem, tool, result = press_on_plane(mesh, 0.0, points)
    area = nodal_areas(mesh, tool.slaves)
    pressure = problem.force[:, 2] / area[tool.slaves]
    assert np.ptp(pressure) <= 1e-9 * pressure.mean(), pressure
    # The penalty's depth d and the block's strain d / 0.5 carry the same stress (series
    # springs): p = eps d, 1e-3 - d the block's shortening.
    depth = -problem.contact_state()[1]
    np.testing.assert_allclose(depth, depth.mean(), rtol=1e-9)
    assert pressure.mean() == pytest.approx(PENALTY * depth.mean(), rel=1e-9)
    assert -result.tool_forces["plane"][-1][2] == pytest.approx(problem.force[:, 2].sum(),
                                                                rel=1e-12)


def test_every_face_rule_integrates_a_linear_pressure_exactly() -> None:
    """Pressed onto a tilted plane, the irregular block's faces sink by a depth bilinear in
    their parameters; with the area element and the shape functions the integrand has
    degree 3 in each parameter, which every Gauss rule from 2 x 2 points on integrates
    exactly. So 2 x 2, 3 x 3 and 5 x 5 points per face give the same solution to the
    Newton tolerance (a point rule whose points and weights were out of order would not:
    the faces are irregular)."""
    mesh = irregular_block()
    forces = [press_on_plane(mesh, 1e-3, n)[0].force for n in (2, 3, 5)]
    assert np.ptp(forces[0][:, 2]) > 0.2 * np.abs(forces[0][:, 2]).max()  # not uniform
    for other in forces[1:]:
        np.testing.assert_allclose(other, forces[0], rtol=0,
                                   atol=1e-8 * np.abs(forces[0]).max())


def test_quadratic_convergence_sliding_with_friction_over_a_curved_tool() -> None:
    """mu = 0.15: the last Newton step of each increment about squares the residual."""
    result = slide_over_dome(0.15, 1e-10, Solid, contact="gauss", penalty=PENALTY)
    assert (result.last.contact_states["dome"] != INACTIVE).any()
    rates = last_rates(result.residuals)
    assert len(rates) >= 4 and np.median(rates) >= 1.6, rates


def test_gauss_contact_needs_a_facing_direction_a_positive_penalty_and_points() -> None:
    mesh = HexMesh.box(1.0, 1.0, 0.5, 1, 1, 1)
    with pytest.raises(ValueError, match="needs facing"):
        RigidTool("plane", dome(), mesh.select(z=0.0), contact="gauss")
    with pytest.raises(ValueError, match="penalty must be > 0"):
        RigidTool("plane", dome(), mesh.select(z=0.0), facing=(0, 0, -1), contact="gauss",
                  penalty=0.0)
    with pytest.raises(ValueError, match=r"points \(Gauss points per direction of a blank "
                       r"face\) must be an integer from 1 to 8"):
        RigidTool("plane", dome(), mesh.select(z=0.0), facing=(0, 0, -1), contact="gauss",
                  points=9)


def corrugated_plane(angle_deg: float, width: float, n: int) -> NagataSurface:
    """n flat facets of ``width`` along x, alternately rising and falling by ``angle_deg``:
    a plane z = 0 corrugated by facet edges every ``width`` mm."""
    x = (np.arange(n + 1) - n / 2) * width
    z = (np.arange(n + 1) % 2) * width * np.tan(np.radians(angle_deg))
    vertices = [[xi, y, zi] for y in (-2.0, 2.0) for xi, zi in zip(x, z, strict=True)]
    i = np.arange(n)
    faces = np.column_stack([i, i + 1, i + n + 2, i + n + 1])
    return NagataSurface(vertices, [[0, 0, 1]] * len(vertices), faces, smooth=False)


def test_an_answer_held_on_facets_stands_only_where_the_search_agrees() -> None:
    """A soft block (E 100 MPa) clamped at its top, pressed 20 um into facets 0.02 mm wide
    and dragged 0.1 mm along x with mu = 0.5 in one increment of at most 9 iterations: its
    points, held on their facets from iteration 3, cross edges as they settle, and the held
    answer is refused by the search. Whatever the loop then does (hold again on the
    search's facets, or go on without the hold), what it returns must meet the equations
    as the search sees them: the residual of the free rows at the answer, evaluated anew
    without any hold, within the force tolerance of the tool's force. (An answer held a
    second time and accepted unchecked left 4e-4 of it.)"""
    soft = Material(100.0, 0.0, Hill48.von_mises(), Swift(1e7, 0.01, 0.0))
    mesh = HexMesh.box(1.0, 1.0, 0.5, 4, 2, 2, origin=(-0.5, -0.5, 0.05))
    # The Gauss points' law alone (barrier=None): pressed 4 % of the block's thickness
    # deep, its nodes would sit in the barrier, on the facets' edges, which is not what
    # this test is about.
    tool = RigidTool("plane", corrugated_plane(5.0, 0.02, 200), mesh.select(z=0.05),
                     facing=(0, 0, -1), contact="gauss", penalty=PENALTY * 100.0 / 210e3,
                     friction=0.5, barrier=None)
    problem = FormingProblem(Solid(mesh, soft), [tool])
    problem.fix(mesh.select(z=0.55), "xyz")
    problem.run({"plane": (0, 0, 0.07)}, max_increment=0.01)
    result = problem.run({"plane": (0.1, 0, 0)}, max_increment=0.1,
                         newton=NewtonSettings(max_iterations=9))
    assert result.cuts == 0 and len(result.iterations) == 1
    equations = problem.linearization()
    free = np.linalg.norm(equations.residual[:equations.n_free])
    assert free <= 1e-4 * np.linalg.norm(result.tool_forces["plane"][-1]), free
