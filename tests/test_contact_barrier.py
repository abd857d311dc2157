"""The barrier of Gauss-point contact (RigidTool(barrier=...)): each slave node is held at
the depth d_b in the tool by its own Alart-Curnier law, with a multiplier of its own beside
the Gauss points' penalty forces (docs/theory/contact.md, "The barrier")."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from jacobian_check import central_difference_errors
from test_gauss_contact import PENALTY
from test_hold_force import pulled_strip
from test_penetration import PLANE
from test_surface_contact import ELASTIC, dome, nodal_areas

from ddpy.core import parallel
from ddpy.geometry.search import EDGE
from ddpy.geometry.surfaces import NagataSurface
from ddpy.io.decks import DeckError, read_case
from ddpy.model.control import NewtonSettings
from ddpy.model.forming import FormingProblem, RigidTool
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.tool import BARRIER_DEPTH

#: The built-in bending case.
BENDING = Path(__file__).parents[1] / "ddpy" / "cases" / "cylindrical_bending"
#: The blocks' thickness (mm).
THICKNESS = 0.5


def pressed_block(push: float, penalty: float, barrier: float | None = BARRIER_DEPTH,
                  contact: str = "gauss") -> tuple[FormingProblem, RigidTool, object]:
    """A 1 x 1 x 0.5 mm elastic block clamped at its top, its bottom pushed ``push`` mm into
    a plane in four increments (Gauss-point contact, 2 x 2 points per face, or ``contact``)."""
    mesh = HexMesh.box(1.0, 1.0, THICKNESS, 2, 2, 2)
    tool = RigidTool("plane", PLANE, mesh.select(z=0.0), facing=(0, 0, -1), contact=contact,
                     penalty=penalty if contact == "gauss" else None, points=2,
                     barrier=barrier)
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=THICKNESS), "xyz")
    result = problem.run({"plane": (0, 0, push)}, max_increment=push / 4,
                         newton=NewtonSettings(1e-12, 1e-9))
    return problem, tool, result


def test_a_soft_penalty_sinks_no_deeper_than_the_barrier() -> None:
    """A penalty 1,000 times softer than the block, pushed 6 um (1.2 % of its thickness):
    alone it leaves nearly the whole push as depth. With the barrier every slave node stops
    at d_b, to the Newton tolerance, and the block is the block pushed 6 um - d_b onto a
    plane by exact node-to-surface contact: the same displacements and tool force (the
    solid does not see who carries its load), the Gauss points' penalty eps d_b over the
    face and the nodes' own laws the rest."""
    push, eps = 6e-3, ELASTIC.E / THICKNESS / 1000
    _, _, plain = pressed_block(push, eps, barrier=None)
    assert plain.penetration["plane"][-1] > 0.011 * THICKNESS
    problem, tool, result = pressed_block(push, eps)
    d_b = BARRIER_DEPTH * THICKNESS
    assert result.penetration["plane"][-1] == pytest.approx(d_b, rel=1e-6)
    exact, _, reference = pressed_block(push - d_b, eps, contact="node")
    force = result.tool_forces["plane"][-1][2]
    assert force == pytest.approx(reference.tool_forces["plane"][-1][2], rel=1e-7)
    assert force < -1000.0  # 3.5 um over 0.5 mm: about 1,500 MPa on the 1 mm^2 face
    np.testing.assert_allclose(problem.u, exact.u, atol=1e-9)
    # the blank's force on the tool is minus its pairs' (the Gauss points' F and the
    # nodes' own)
    np.testing.assert_allclose(-problem.force.sum(axis=0), result.tool_forces["plane"][-1],
                               rtol=1e-12, atol=1e-12)
    # each node carries the uniform pressure over its share of the bottom
    area = nodal_areas(problem.solid.mesh, tool.slaves)[tool.slaves]
    np.testing.assert_allclose(problem.force[:, 2], -force * area, rtol=1e-6)


def test_a_converged_state_carries_each_nodes_own_force() -> None:
    """The barrier's multiplier is each node's own force, carried as its node point's
    traction: at a converged state with every node at d_b the equations are met with the
    present multipliers (the pairs' forces less the Gauss points', FormingProblem.
    linearization's default), and the next phase, a push of 1e-9 mm more, starts from them:
    its first residual is 8e-5 of the force scale (measured), where a start from the pairs'
    whole forces, which counts the Gauss points' share twice, had 0.39."""
    push, eps = 6e-3, ELASTIC.E / THICKNESS / 1000
    problem, tool, result = pressed_block(push, eps)
    eq = problem.linearization()
    scale = np.abs(result.tool_forces["plane"][-1]).max()
    assert np.abs(eq.residual[:eq.n_free]).max() < 1e-6 * scale
    assert np.abs(eq.residual[eq.n_free:]).max() < 1e-6 * scale
    more = problem.run({"plane": (0, 0, 1e-9)}, max_increment=1e-9,
                       newton=NewtonSettings(1e-8, 1e-6))
    assert more.residuals[0][0] < 1e-3, more.residuals


def test_the_barrier_leaves_a_shallow_press_alone() -> None:
    """A press shallower than d_b: the same answer with and without the barrier (to
    rounding: the barrier's multipliers are unknowns of the system, at zero)."""
    push, eps = 1e-3, ELASTIC.E / THICKNESS
    with_barrier = pressed_block(push, eps)[0].force
    without = pressed_block(push, eps, barrier=None)[0].force
    assert pressed_block(push, eps)[2].penetration["plane"][-1] < BARRIER_DEPTH * THICKNESS
    np.testing.assert_allclose(with_barrier, without, rtol=1e-12)


def test_jacobian_with_the_barrier_matches_central_differences() -> None:
    """The barrier on a curved tool with friction, some nodes held at it (stick and slip),
    one column lifted out: each node's law along its gap from d_b, the normal's change along
    the node (the dome's curvature) and the friction's, and its multiplier beside the
    Gauss points' forces in the equilibrium rows, against central differences."""
    surface = dome()
    lift = float(surface.evaluate([0], [[0.5, 0.5]])[0][0, 2])
    mesh = HexMesh.box(1.0, 1.0, THICKNESS, 3, 3, 2, origin=(-0.5, -0.5, lift))
    tool = RigidTool("dome", surface, mesh.select(z=lift), friction=0.3, facing=(0, 0, -1),
                     contact="gauss", penalty=PENALTY / 50, points=2)
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=lift + THICKNESS), "xyz")
    problem.fix(mesh.select(y=-0.5), "y")
    problem.run({"dome": (0, 0, 8e-3)}, max_increment=2e-3)
    result = problem.run({"dome": (2e-3, 0, 0)}, max_increment=1e-3)
    # nodes held at the barrier's depth
    assert result.penetration["dome"][-1] == pytest.approx(BARRIER_DEPTH * THICKNESS, rel=1e-4)
    u = problem.u.copy()
    u[tool.slaves[mesh.nodes[tool.slaves, 0] < -0.4], 2] += 0.2  # open
    moved = {"dome": problem.position["dome"] + (3e-5, 1e-5, 2e-5)}
    equilibrium, law, state = central_difference_errors(problem, u, problem.force, moved, 3e-5)
    assert 0 in set(state.tolist()) and len(set(state.tolist())) > 1, state
    assert equilibrium <= 1e-7 and law <= 1e-7, (equilibrium, law)


def valley(angle_deg: float) -> NagataSurface:
    """Two flat patches 5 x 10 mm meeting along x = 0, each rising at ``angle_deg`` away
    from it: a valley whose inside (below its bottom line) holds a thin wedge of points
    whose nearest point on the tool is the bottom line, an edge of both patches."""
    rise = 5.0 * np.tan(np.radians(angle_deg))
    s, c = np.sin(np.radians(angle_deg)), np.cos(np.radians(angle_deg))
    vertices = [[-5, -5, rise], [0, -5, 0], [0, 5, 0], [-5, 5, rise],
                [0, -5, 0], [5, -5, rise], [5, 5, rise], [0, 5, 0]]
    normals = [[-s, 0, c]] * 4 + [[s, 0, c]] * 4
    return NagataSurface(vertices, normals, [[0, 1, 2, 3], [4, 5, 6, 7]])


def test_jacobian_with_slaves_on_an_edge_matches_central_differences() -> None:
    """The barrier where slave nodes' nearest point is a patch edge: a block pressed into a
    valley (1 degree each side), friction on, its middle column of nodes on the valley's
    bottom line held at d_b (their normal is the direction from the edge to the node, its
    change (I - n n - a a) / g, a along the edge), against central differences."""
    surface = valley(1.0)
    mesh = HexMesh.box(1.0, 1.0, THICKNESS, 2, 2, 2, origin=(-0.5, -0.5, 0.02))
    tool = RigidTool("valley", surface, mesh.select(z=0.02), friction=0.3, facing=(0, 0, -1),
                     contact="gauss", penalty=PENALTY / 50, points=2)
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.02 + THICKNESS), "xyz")
    problem.run({"valley": (0, 0, 0.036)}, max_increment=4e-3)
    u = problem.u.copy()
    x = mesh.nodes + u
    found = tool.search.project(x[tool.slaves], problem.position["valley"])
    on_edge = (found.status == EDGE) & (-found.distance > 0.999 * BARRIER_DEPTH * THICKNESS)
    assert on_edge.sum() == 3, (found.status, found.distance)  # the middle column
    moved = {"valley": problem.position["valley"] + (3e-5, 1e-5, 2e-5)}
    equilibrium, law, _ = central_difference_errors(problem, u, problem.force, moved, 3e-5)
    assert equilibrium <= 1e-7 and law <= 1e-7, (equilibrium, law)


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan")])
def test_a_barrier_outside_zero_to_one_is_refused(value: float) -> None:
    mesh = HexMesh.box(1.0, 1.0, THICKNESS, 1, 1, 1)
    with pytest.raises(ValueError, match="barrier must be a fraction"):
        RigidTool("plane", PLANE, mesh.select(z=0.0), facing=(0, 0, -1), barrier=value)


@pytest.mark.parametrize("word", ["2", "-0.01", "nan", "deep"])
def test_a_barrier_line_outside_zero_to_one_is_refused_at_its_line(tmp_path: Path,
                                                                  word: str) -> None:
    case = tmp_path / "case"
    shutil.copytree(BENDING, case)
    tools = case / "tools.dat"
    tools.write_text(tools.read_text().replace("\nend", f"\n  barrier {word}\nend", 1))
    line = next(k for k, text in enumerate(tools.read_text().splitlines(), start=1)
                if text.strip().startswith("barrier"))
    with pytest.raises(DeckError) as info:
        read_case(case)
    assert f"tools.dat:{line}:" in str(info.value) and "barrier" in str(info.value)


def test_a_barrier_line_reaches_the_tool(tmp_path: Path) -> None:
    case = tmp_path / "case"
    shutil.copytree(BENDING, case)
    tools = case / "tools.dat"
    tools.write_text(tools.read_text().replace("\nend", "\n  barrier 0.008\nend", 1))
    first = read_case(case).tools[0]
    assert first.barrier == 0.008 and read_case(BENDING).tools[0].barrier == BARRIER_DEPTH
    assert "barrier at 0.008 of the thickness" in read_case(case).summary()
    tools.write_text(tools.read_text().replace("barrier 0.008", "barrier off"))
    off = read_case(case)
    assert off.tools[0].barrier is None
    assert off.summary().count("barrier at") == len(off.tools) - 1


def test_the_barrier_is_on_by_default() -> None:
    """Every Gauss-point tool of a deck or of the API carries the barrier unless it says
    off."""
    assert BARRIER_DEPTH == 0.005
    assert all(t.barrier == BARRIER_DEPTH for t in read_case(BENDING).tools)
    assert RigidTool("plane", PLANE, [0], facing=(0, 0, -1)).barrier == BARRIER_DEPTH


@pytest.mark.parametrize("threads", [1, 2])
def test_a_holder_pressed_with_a_force_settles_on_the_barrier(threads: int) -> None:
    """A 10 x 1 x 1 mm strip between a flat die and a flat holder with a barrier, the holder
    pressed with 500 N (50 MPa), the strip pushed out along x: the penalty alone would sink
    the holder 3 % of the thickness. With the barrier the holder never flies off the
    strip: every increment converges with the holder's reaction 500 N, its slaves held at
    d_b, and the pull Coulomb's 2 mu F."""
    thickness, force, mu = 1.0, 500.0, 0.1
    with parallel.threads(threads):
        problem, result = pulled_strip(mu, force, barrier=BARRIER_DEPTH)
    # (A first trial may be cut where the strip starts afloat, its matrix singular: that
    # is not the barrier's; the holder must hold the force at every increment, to the
    # Newton tolerance, 1e-4 of the force scale.)
    assert result.factors[-1] == pytest.approx(1.0)
    np.testing.assert_allclose(np.asarray(result.tool_forces["holder"])[:, 2], force,
                               rtol=1e-4)
    assert result.tool_forces["holder"][-1][2] == pytest.approx(force, rel=1e-6)
    assert -result.tool_forces["pusher"][-1][0] == pytest.approx(2 * mu * force, rel=5e-3)
    assert result.penetration["holder"][-1] == pytest.approx(BARRIER_DEPTH * thickness,
                                                             rel=1e-6)


@pytest.mark.parametrize(("size", "thickness", "expected"), [
    (2.0, 0.5, 0.25**2 / 2.0),  # flat elements: E t^2 / h below E T / 10
    (0.5, 1.0, 0.1 * 1.0),      # cubes of 0.5 mm: E t^2 / h = E / 2, capped at E T / 10
])
def test_the_barriers_augmentation_is_the_blank_stiffness_capped_at_a_tenth_of_e_t(
        size: float, thickness: float, expected: float) -> None:
    """A Gauss-point tool's barrier takes E t^2 / h, at most E T / 10 (docs/theory/contact.md,
    "The barrier's augmentation"), a node-to-surface tool E t^2 / h, and a tool's own r
    either way; the blanks' numbers by hand: elements size x size x T / 2."""
    mesh = HexMesh.box(8 * size, 8 * size, thickness, 8, 8, 2)
    bottom = mesh.select(z=0.0)
    tools = [RigidTool("gauss", PLANE, bottom, facing=(0, 0, -1)),
             RigidTool("node", PLANE, bottom, contact="node"),
             RigidTool("own", PLANE, bottom, facing=(0, 0, -1), augmentation=123.0)]
    problem = FormingProblem(Solid(mesh, ELASTIC), tools)
    n = bottom.size
    stiffness = ELASTIC.E * (thickness / 2) ** 2 / size
    np.testing.assert_allclose(problem.r[:n], ELASTIC.E * expected, rtol=1e-12)
    np.testing.assert_allclose(problem.r[n:2 * n], stiffness, rtol=1e-12)
    np.testing.assert_allclose(problem.r[2 * n:], 123.0)
