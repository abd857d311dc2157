"""Surface-to-surface contact (RigidTool(..., contact="surface")): every slave node's gap,
normal and slip averaged over the Gauss points of the blank faces around it, in the same
Alart-Curnier law and Newton loop as node-to-surface contact (docs/theory/contact.md)."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from jacobian_check import central_difference_errors

from ddpy.core.handles import CoreRefusal
from ddpy.geometry.surfaces import NagataSurface
from ddpy.model.contact import INACTIVE, SLIP, STICK
from ddpy.model.control import IncrementLimits, NewtonSettings
from ddpy.model.forming import FormingProblem, FormingResult, RigidTool
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.newton import CoreProblem, Layout, ToolPack
from ddpy.model.solid import Solid as _Solid

#: Elastic in practice (yield stress 1e7 MPa), no Poisson effect: the analytic answers hold.
ELASTIC = Material(210e3, 0.0, Hill48.von_mises(), Swift(1e7, 0.01, 0.0))

#: These cases were measured with the mean-dilatation hexahedron (DD3IMP's element).
Solid = partial(_Solid, element="hexahedron")


def dome() -> NagataSurface:
    """One Nagata patch, 10 x 10 mm, a shallow dome (corner normals tilted by 0.07 rad)."""
    normals = np.array([[-0.05, -0.05, 1], [0.05, -0.05, 1], [0.05, 0.05, 1], [-0.05, 0.05, 1]])
    return NagataSurface([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]],
                         normals / np.linalg.norm(normals, axis=1)[:, None], [[0, 1, 2, 3]])


def block_on_dome(friction: float) -> tuple[FormingProblem, HexMesh, RigidTool]:
    """A 1 x 1 x 0.5 mm block clamped at its top, its bottom on the dome's crest, its side
    y = -0.5 on a symmetry plane (the slaves there hold their y component), pressed 4 um
    into the dome while the dome moves by 0.2 um sideways."""
    surface = dome()
    lift = float(surface.evaluate([0], [[0.5, 0.5]])[0][0, 2])  # the top of the dome
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, lift))
    tool = RigidTool("dome", surface, mesh.select(z=lift), friction=friction,
                     facing=(0, 0, -1), contact="surface")
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=lift + 0.5), "xyz")
    problem.fix(mesh.select(y=-0.5), "y")
    problem.run({"dome": (2e-4, 0, 4e-3)}, max_increment=1e-3)
    return problem, mesh, tool


def test_the_patch_of_a_pair_is_the_nodes_of_its_faces() -> None:
    mesh = HexMesh.box(2.0, 1.0, 0.5, 2, 1, 1)
    bottom = mesh.select(z=0.0)
    node = RigidTool("plane", dome(), bottom, facing=(0, 0, -1), contact="node")
    surface = RigidTool("plane", dome(), bottom, facing=(0, 0, -1), contact="surface")
    for tool, sizes in ((node, [1] * 6), (surface, [4, 6, 4, 4, 6, 4])):
        layout = Layout(Solid(mesh, ELASTIC), [tool], np.zeros((mesh.n_nodes, 3), bool))
        assert sorted(np.diff(layout.patch_first).tolist()) == sorted(sizes)
        for p, a in enumerate(layout.node):
            patch = layout.patch_node[layout.patch_first[p]:layout.patch_first[p + 1]]
            assert a in patch and set(patch) <= set(bottom.tolist())
            # every node of the patch is within one element of the pair's node
            assert np.abs(mesh.nodes[patch] - mesh.nodes[a]).max() <= 1.0 + 1e-12


def test_the_core_refuses_a_patch_that_misses_a_face_node() -> None:
    problem, _, _ = block_on_dome(0.0)
    mesh = problem.solid.mesh
    pack = ToolPack(problem.tools, mesh)
    layout = Layout(problem.solid, problem.tools, problem.fixed)  # the layout as built fits
    first = layout.patch_first[1]
    # the first pair's patch loses one of its face nodes to another node of the blank
    stranger = int(np.setdiff1d(np.arange(mesh.n_nodes), layout.patch_node[:first])[0])
    layout.patch_node[first - 1] = stranger
    with pytest.raises(CoreRefusal, match="tool dome's contact.*out of order"):
        CoreProblem(problem.solid, layout, pack)


def test_jacobian_of_frictionless_surface_contact_matches_central_differences() -> None:
    """The Jacobian with surface-to-surface contact (weighted gaps and normals, the tool's
    curvature at every Gauss point, held components on a symmetry plane) against central
    differences, at a point with open and closed pairs on a curved tool: within 1e-7 of
    each block (measured 2e-10 and 3e-9; without the curvature term 8e-5)."""
    problem, _, tool = block_on_dome(0.0)
    rng = np.random.default_rng(7)
    u = problem.u + 1e-5 * rng.standard_normal(problem.u.shape) * ~problem.fixed
    force = problem.force * (1.0 + 0.5 * rng.standard_normal(problem.force.shape))
    force[::4] = 0.0  # some pairs without force, lifted off the dome: open
    u[tool.slaves[::4], 2] += 5e-3
    moved = {"dome": problem.position["dome"] + (3e-5, 1e-5, 2e-5)}
    equilibrium, law, state = central_difference_errors(problem, u, force, moved, 3e-5)
    assert {INACTIVE, SLIP} <= set(state.tolist()), state  # frictionless closed: "slip"
    assert equilibrium <= 1e-7 and law <= 1e-7, (equilibrium, law)


def test_jacobian_with_friction_stick_and_slip_matches_central_differences() -> None:
    """With friction (mu = 0.3): the weighted slip and the friction terms of stick and slip
    pairs, against central differences (measured 2e-10 and 3e-9)."""
    problem, _, tool = block_on_dome(0.3)
    rng = np.random.default_rng(7)
    u = problem.u + 1e-5 * rng.standard_normal(problem.u.shape) * ~problem.fixed
    force = problem.force * (1.0 + 0.5 * rng.standard_normal(problem.force.shape))
    force[::4] = 0.0  # open
    u[tool.slaves[::4], 2] += 5e-3
    force[1::4, 0] = force[1::4, 2]  # beyond the friction cone (mu = 0.3): slip
    moved = {"dome": problem.position["dome"] + (3e-5, 1e-5, 2e-5)}
    equilibrium, law, state = central_difference_errors(problem, u, force, moved, 3e-5)
    assert {INACTIVE, STICK, SLIP} <= set(state.tolist()), state
    assert equilibrium <= 1e-7 and law <= 1e-7, (equilibrium, law)


def test_a_symmetry_plane_through_the_slaves_gives_the_full_model() -> None:
    """Half of a block symmetric about y = 0, held in y there, pressed into the dome and
    slid along x with friction: the slaves on the plane (whose faces lie on one side only)
    carry half the forces of the full model's, as the mirror image of their faces would
    give them (the held component left out of their normal and slip)."""
    surface = dome()
    lift = float(surface.evaluate([0], [[0.5, 0.5]])[0][0, 2])
    forces = []
    for width, cells, origin in ((1.0, 4, -0.5), (0.5, 2, 0.0)):
        mesh = HexMesh.box(1.0, width, 0.5, 4, cells, 2, origin=(-0.5, origin, lift))
        slaves = mesh.select(z=lift)
        tool = RigidTool("dome", surface, slaves, friction=0.2, facing=(0, 0, -1),
                         contact="surface")
        problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
        problem.fix(mesh.select(z=lift + 0.5), "xyz")
        if origin == 0.0:
            problem.fix(mesh.select(y=0.0), "y")
        problem.run({"dome": (0, 0, 4e-3)}, max_increment=2e-3)
        problem.run({"dome": (2e-3, 0, 0)}, max_increment=1e-3)
        keep = np.abs(mesh.nodes[slaves, 1]) <= 1e-12  # the slaves on y = 0
        order = np.argsort(mesh.nodes[slaves[keep], 0])
        forces.append(problem.force[keep][order])
    assert np.abs(forces[0]).max() > 1.0
    np.testing.assert_allclose(2.0 * forces[1], forces[0], atol=1e-9 * np.abs(forces[0]).max())


def nodal_areas(mesh: HexMesh, nodes: np.ndarray) -> np.ndarray:
    """int N_a dA over the boundary faces whose corners are all in ``nodes``, per node of
    the mesh, by 3 x 3 Gauss points (exact: a bilinear shape function times a Jacobian
    linear in each parameter)."""
    faces = mesh.boundary_faces()
    faces = faces[np.isin(faces, nodes).all(axis=1)]
    area = np.zeros(mesh.n_nodes)
    points, weights = np.polynomial.legendre.leggauss(3)
    sign = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]])
    for xi, wx in zip(points, weights, strict=True):
        for eta, wy in zip(points, weights, strict=True):
            shape = 0.25 * (1 + sign[:, 0] * xi) * (1 + sign[:, 1] * eta)
            dxi = 0.25 * sign[:, 0] * (1 + sign[:, 1] * eta)
            deta = 0.25 * sign[:, 1] * (1 + sign[:, 0] * xi)
            x = mesh.nodes[faces]
            jac = np.linalg.norm(np.cross(np.einsum("q,fqk->fk", dxi, x),
                                          np.einsum("q,fqk->fk", deta, x)), axis=1)
            np.add.at(area, faces, wx * wy * jac[:, None] * shape[None, :])
    return area


def test_uniform_pressure_on_a_plane_patch_test() -> None:
    """A block whose columns are irregular quadrilaterals, clamped at its top, pressed
    uniformly onto a plane: the stress is uniform, and each bottom node carries the
    pressure times its area, int N_a dA (computed here with 3 x 3 Gauss points), to
    rounding; its weighted gap is the plane's offset, the same at every node."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, 0.0))
    nodes = mesh.nodes.copy()
    inner = (np.abs(nodes[:, 0]) < 0.4) & (np.abs(nodes[:, 1]) < 0.4)
    rng = np.random.default_rng(3)
    shift = rng.uniform(-0.08, 0.08, (mesh.n_nodes, 2))
    # the same shift along each column (same x, y): the columns stay vertical prisms
    column = np.unique(np.round(mesh.nodes[:, :2], 9), axis=0, return_inverse=True)[1]
    nodes[inner, :2] += shift[column.ravel()][inner]
    mesh = HexMesh(nodes, mesh.elements)
    plane = NagataSurface([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], [[0, 0, 1]] * 4,
                          [[0, 1, 2, 3]])
    bottom = mesh.select(z=0.0)
    tool = RigidTool("plane", plane, bottom, facing=(0, 0, -1), contact="surface")
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    result = problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3)
    # Nodal areas int N_a dA of the bottom faces, 3 x 3 Gauss points (exact: bilinear
    # shape function times a Jacobian linear in each parameter).
    area = nodal_areas(mesh, bottom)
    pressure = problem.force[:, 2] / area[tool.slaves]
    assert np.ptp(pressure) <= 1e-9 * pressure.mean(), pressure
    # Uniaxial compression by 2 per mil with nu = 0: the nominal stress -E ln(s) / s.
    stretch = 1.0 - 2e-3
    assert pressure.mean() == pytest.approx(-210e3 * np.log(stretch) / stretch, rel=1e-9)
    assert -result.tool_forces["plane"][-1][2] == pytest.approx(pressure.mean(), rel=1e-9)
    state, gap, normal = problem.contact_state()
    assert (state != INACTIVE).all()
    np.testing.assert_allclose(normal, np.tile([0.0, 0.0, 1.0], (bottom.size, 1)), atol=1e-14)
    assert np.ptp(gap) <= 1e-15, gap


def residual_rates(history: list[float]) -> list[float]:
    """log(r_k+1 / r_k) / log(r_k / r_k-1) over the residuals above 1e-9 N (a hundred times
    the rounding floor of these runs' residuals, about 1e-11 N)."""
    tail = [r for r in history if r > 1e-9]
    return [np.log(tail[k + 1] / tail[k]) / np.log(tail[k] / tail[k - 1])
            for k in range(1, len(tail) - 1)]


def slide_over_dome(friction: float, force_tolerance: float = 1e-12, solid: type = Solid,
                    **contact: object) -> FormingResult:
    """A 2 x 1 x 0.5 mm block clamped at its top pressed 20 um into the dome, then 20 um
    more while the dome slides 0.2 mm under it, with ``contact`` the tool's contact options
    (surface-to-surface by default) and ``solid`` its Solid: the run, with the residual
    norms of every increment."""
    surface = dome()
    lift = float(surface.evaluate([0], [[0.5, 0.5]])[0][0, 2])
    mesh = HexMesh.box(2.0, 1.0, 0.5, 8, 2, 2, origin=(-1.0, -0.5, lift))
    tool = RigidTool("dome", surface, mesh.select(z=lift), friction=friction,
                     facing=(0, 0, -1), **({"contact": "surface"} | contact))
    problem = FormingProblem(solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=lift + 0.5), "xyz")
    tight = NewtonSettings(force_tolerance, 1e-6)
    # Every touching node lands (DD3IMP's r_min), down to gaps of 1e-3 element sizes:
    # each increment then ends with the contact set it converged with, and its last
    # steps show the tangent's rate.
    every = IncrementLimits(touch="every", touch_gap=1e-3)
    result = problem.run({"dome": (0, 0, 0.02)}, max_increment=0.02, newton=tight,
                         limits=every)
    return problem.run({"dome": (0.2, 0, 0.02)}, max_increment=0.05, result=result,
                       newton=tight, limits=every)


def last_rates(histories: list[list[float]]) -> list[float]:
    """The order of the last Newton step above the floor of every increment that has one."""
    return [rates[-1] for rates in map(residual_rates, histories) if rates]


def test_quadratic_convergence_pressing_onto_a_curved_tool() -> None:
    """Frictionless: the last Newton step of each increment squares the residual (order
    about 2; measured 1.3 to 4.0, median 2.2, over 10 increments)."""
    result = slide_over_dome(0.0)
    assert (result.last.contact_states["dome"] != INACTIVE).all()
    rates = last_rates(result.residuals)
    assert len(rates) >= 8 and np.median(rates) >= 1.8, rates


def test_quadratic_convergence_sliding_with_friction_over_a_curved_tool() -> None:
    """mu = 0.15, every pair slipping by the end: the last Newton steps are about quadratic
    as with node-to-surface contact on the same problem (measured: median order 1.85 over
    12 increments, 1.84 with node-to-surface; below 2 where stick and slip still switch in
    the last steps)."""
    result = slide_over_dome(0.15)
    assert (result.last.contact_states["dome"] != INACTIVE).all()
    rates = last_rates(result.residuals)
    assert len(rates) >= 8 and np.median(rates) >= 1.6 and max(rates) >= 2.0, rates


def test_surface_contact_needs_a_facing_direction() -> None:
    mesh = HexMesh.box(1.0, 1.0, 0.5, 1, 1, 1)
    with pytest.raises(ValueError, match="needs facing"):
        RigidTool("plane", dome(), mesh.select(z=0.0), contact="surface")
    with pytest.raises(ValueError, match="discretization must be one of node, surface"):
        RigidTool("plane", dome(), mesh.select(z=0.0), facing=(0, 0, -1), contact="mortar")
