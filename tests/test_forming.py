"""Frictional contact with rigid tools in the single Newton loop (ddpy.model.forming), with
DD3IMP's discretization: node-to-surface contact on the mean-dilatation hexahedron, which
stay selectable beside the defaults (Gauss-point contact: tests/test_gauss_contact.py; the
solid-shell: tests/test_solid_shell.py)."""

from __future__ import annotations

from dataclasses import replace
from functools import partial
from math import comb

import numpy as np
import pytest
from jacobian_check import central_difference_errors

from ddpy.geometry.surfaces import BezierSurface, NagataSurface
from ddpy.model import forming
from ddpy.model.contact import SLIP, STICK
from ddpy.model.control import (
    FormingTuning,
    IncrementLimits,
    IncrementTuning,
    NewtonSettings,
    next_step,
)
from ddpy.model.forming import FormingError, FormingProblem
from ddpy.model.forming import RigidTool as _RigidTool
from ddpy.model.material import Hill48, Material, Swift, yield_landing
from ddpy.model.mesh import HexMesh, largest_rotation
from ddpy.model.solid import Solid as _Solid
from ddpy.model.solid import material_props
from ddpy.model.static import SolidResult, StaticProblem

Solid = partial(_Solid, element="hexahedron")
RigidTool = partial(_RigidTool, contact="node")

#: Elastic in practice (yield stress 1e7 MPa), no Poisson effect: the analytic answers hold.
ELASTIC = Material(210e3, 0.0, Hill48.von_mises(), Swift(1e7, 0.01, 0.0))


def plane_tool(height: float = 0.0, up: bool = True) -> NagataSurface:
    """A 10 x 10 mm plane at z = height facing up (a die) or down (a punch, a holder)."""
    corners = [[-5, -5, height], [5, -5, height], [5, 5, height], [-5, 5, height]]
    if not up:
        corners.reverse()
    return NagataSurface(corners, [[0, 0, 1 if up else -1]] * 4, [[0, 1, 2, 3]])


def block_on_plane(friction: float) -> tuple[FormingProblem, HexMesh]:
    """A 1 x 1 x 0.5 mm block clamped at its top, its bottom resting on a plane tool."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, 0.0))
    tool = RigidTool("plane", plane_tool(), mesh.select(z=0.0), friction=friction,
                     facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    return problem, mesh


def test_block_sticks_below_and_slips_above_coulomb() -> None:
    mu = 0.2
    problem, mesh = block_on_plane(mu)
    bottom = mesh.select(z=0.0)
    result = problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3)
    normal = -result.tool_forces["plane"][-1][2]
    # Uniaxial compression by 2 per mil with nu = 0: the Kirchhoff stress E ln(stretch) on
    # the logarithmic strain gives the nominal force N = -E ln(stretch) / stretch A.
    stretch = 1.0 - 2e-3
    assert normal == pytest.approx(-210e3 * np.log(stretch) / stretch, rel=1e-9)
    # A small sideways move: every bottom node sticks and travels with the tool.
    result = problem.run({"plane": (2e-5, 0, 0)}, max_increment=2e-5, result=result)
    tangential = abs(result.tool_forces["plane"][-1][0])
    assert 0.0 < tangential < mu * normal
    np.testing.assert_allclose(problem.u[bottom, 0], 2e-5, rtol=1e-9)
    assert (result.last.contact_states["plane"] == STICK).all()
    # A large one: every node slips and the friction force is mu N exactly.
    result = problem.run({"plane": (2e-3, 0, 0)}, max_increment=5e-4, result=result,
                         newton=NewtonSettings(1e-11, 1e-6))
    force = result.tool_forces["plane"][-1]
    assert (result.last.contact_states["plane"] == SLIP).all()
    # Every node slips: its tangential force is mu times its normal force...
    node = problem.force
    np.testing.assert_allclose(np.hypot(node[:, 0], node[:, 1]), mu * node[:, 2], rtol=1e-9)
    # ...so the tool feels mu N (the slip directions spread by a few microradians).
    assert abs(force[0]) == pytest.approx(mu * abs(force[2]), rel=1e-5)
    assert force[0] < 0  # the block holds the tool back: friction opposes the motion
    assert (problem.u[bottom, 0] < 2e-3 + 2e-5 - 1e-6).all()


@pytest.mark.parametrize("contact", ["node", "surface", "gauss"])
def test_friction_on_the_blank_follows_a_sliding_tool(contact: str) -> None:
    """A block clamped at its top, pressed onto a plane tool that then slides along
    (4, -2, 0) um, for every contact discretization: every face of the block slips, and the
    friction force on the blank (minus the tool's reaction) opposes its slip relative to the
    tool, so it points along the tool's motion, at mu times the normal force. Its size alone
    would not tell a slip of the wrong sign: |Ft| = mu Fz either way."""
    mu = 0.2
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, 0.0))
    options = {"penalty": 5e4} if contact == "gauss" else {}
    tool = _RigidTool("plane", plane_tool(), mesh.select(z=0.0), friction=mu,
                      facing=(0, 0, -1), contact=contact, **options)
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    result = problem.run({"plane": (0, 0, 4e-3)}, max_increment=2e-3)
    motion = np.array([4e-3, -2e-3, 0.0])
    result = problem.run({"plane": tuple(motion)}, max_increment=1e-3, result=result,
                         newton=NewtonSettings(1e-11, 1e-6))
    assert (result.last.contact_states["plane"] == SLIP).all()
    on_blank = -result.tool_forces["plane"][-1]
    assert on_blank[2] > 1.0  # pressed: the tool pushes the blank up
    tangential = on_blank[:2]
    along = motion[:2] / np.linalg.norm(motion[:2])
    assert tangential @ along == pytest.approx(mu * on_blank[2], rel=1e-3), on_blank
    across = tangential[0] * along[1] - tangential[1] * along[0]
    assert abs(across) <= 1e-3 * np.linalg.norm(tangential), on_blank


def test_tool_reaction_equals_contact_forces_and_supports() -> None:
    problem, mesh = block_on_plane(0.3)
    result = problem.run({"plane": (4e-4, 0, 1e-3)}, max_increment=5e-4)
    fint, _ = problem.solid.internal_force(problem.u, problem.solid_state)
    # The tool's force is minus the sum of the contact forces on the slaves...
    slaves = problem.tools[0].slaves
    np.testing.assert_allclose(result.tool_forces["plane"][-1], -problem.force.sum(axis=0))
    # ...which balance the blank's internal forces there, and the supports take the rest.
    np.testing.assert_allclose(problem.force, fint[slaves], atol=1e-8 * np.abs(fint).max())
    supports = fint[mesh.select(z=0.5)].sum(axis=0)
    np.testing.assert_allclose(supports, result.tool_forces["plane"][-1],
                               atol=1e-8 * np.abs(supports).max())


def cylinder_crest(kind: str, segments: int, radius: float = 10.0) -> BezierSurface | NagataSurface:
    """The top of a cylinder of axis y (crest z = 0 at x = 0), 60 degrees around the crest,
    as Nagata patches, facets or degree-5 Bezier patches fitted to the circle."""
    phi = np.radians(np.linspace(-30.0, 30.0, segments + 1))
    if kind == "bezier":
        n, s = 5, np.linspace(0.0, 1.0, 50)
        basis = np.array([[comb(n, i) * t**i * (1 - t) ** (n - i) for i in range(n + 1)]
                          for t in s])
        nets = []
        for a, b in zip(phi[:-1], phi[1:], strict=True):
            angle = a + s * (b - a)
            arc = np.column_stack([radius * np.sin(angle), radius * (np.cos(angle) - 1.0)])
            ends = np.outer(basis[:, 0], arc[0]) + np.outer(basis[:, -1], arc[-1])
            inner, *_ = np.linalg.lstsq(basis[:, 1:-1], arc - ends, rcond=None)
            ring = np.vstack([arc[0], inner, arc[-1]])
            net = np.zeros((n + 1, 2, 3))
            net[:, :, 0] = ring[:, :1]
            net[:, :, 2] = ring[:, 1:]
            net[:, 0, 1], net[:, 1, 1] = -3.0, 3.0
            nets.append(net)
        return BezierSurface(nets)
    rim = np.column_stack([radius * np.sin(phi), radius * (np.cos(phi) - 1.0)])
    normal = np.column_stack([np.sin(phi), np.cos(phi)])
    m = segments + 1
    vertices = np.vstack([np.column_stack([rim[:, 0], np.full(m, y), rim[:, 1]])
                          for y in (-3.0, 3.0)])
    normals = np.vstack([np.column_stack([normal[:, 0], np.zeros(m), normal[:, 1]])] * 2)
    i = np.arange(segments)
    faces = np.column_stack([i, i + 1, i + 1 + m, i + m])  # counter-clockwise from above
    return NagataSurface(vertices, normals, faces, smooth=kind == "nagata")


def slide_over_cylinder(kind: str, segments: int) -> tuple[np.ndarray, list[int]]:
    """A 4 mm block clamped at its top, pressed 30 um into the crest, which then slides 2 mm
    under it: the normal force every 0.02 mm of the slide, and the iterations."""
    mesh = HexMesh.box(4.0, 1.0, 0.5, 32, 1, 2, origin=(-2.0, -0.5, 0.0))
    tool = RigidTool("cylinder", cylinder_crest(kind, segments), mesh.select(z=0.0),
                     facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    result = problem.run({"cylinder": (-1.0, 0, 0)}, max_increment=1.0)   # no contact yet
    result = problem.run({"cylinder": (0, 0, 0.03)}, max_increment=0.015, result=result)
    start = len(result.factors)
    result = problem.run({"cylinder": (2.0, 0, 0)}, max_increment=0.02, result=result)
    force = -np.array(result.tool_forces["cylinder"][start:])[:, 2]
    slide = np.array(result.tool_displacements["cylinder"][start:])[:, 0] + 1.0
    # Increments stopped at a first touch fall between: compare on one grid of positions.
    return np.interp(np.linspace(0.02, 2.0, 100), slide, force), result.iterations[start:]


@pytest.fixture(scope="module")
def slides() -> dict[str, tuple[np.ndarray, list[int]]]:
    return {"bezier": slide_over_cylinder("bezier", 4), "nagata": slide_over_cylinder("nagata", 8),
            "facets-16": slide_over_cylinder("facets", 16),
            "facets-32": slide_over_cylinder("facets", 32)}


def test_force_over_a_cylinder_smooth_tools_against_facets(slides) -> None:
    reference = slides["bezier"][0]  # shape error 1e-7 mm: the exact cylinder
    error = {name: np.abs(force - reference).mean() / reference.mean()
             for name, (force, _) in slides.items()}
    # Nagata with 8 patches on 60 degrees gives the Bezier force within 0.2 %.
    assert error["nagata"] < 2e-3, error
    # Facets flatten the crest: the force is far off and converges as the facets refine
    # (measured: 14.5 % with 16, 3.8 % with 32 facets; order 2 like the shape error).
    assert error["facets-16"] > 0.1 and error["facets-32"] < error["facets-16"] / 3, error
    # The force oscillates as facet vertices pass under the nodes: the RMS of its second
    # difference (relative) is about 3 times that of the smooth tools (whose own comes from
    # the nodes of the blank passing over the crest), and falls with refinement.
    wiggle = {name: np.std(np.diff(force, 2)) / force.mean()
              for name, (force, _) in slides.items()}
    assert wiggle["facets-16"] > 2 * max(wiggle["nagata"], wiggle["bezier"]), wiggle
    assert wiggle["facets-32"] < wiggle["facets-16"], wiggle


def test_whole_steps_that_change_contact_states_save_iterations_not_answers(
        slides, monkeypatch) -> None:
    # The crest sliding under the block: contact passes from node to node, and a whole
    # step that changes those pairs' states fails the monotonicity test by their rows
    # alone. Taking it when it halves the residual (the default) saves iterations; the
    # equations, and so the forces to the Newton tolerance, are the same.
    force, iterations = slides["nagata"]
    default = FormingTuning()
    monkeypatch.setattr(forming, "FormingTuning", lambda: replace(default, whole_step=0.0))
    force_test_only, iterations_test_only = slide_over_cylinder("nagata", 8)
    assert sum(iterations) < sum(iterations_test_only)
    np.testing.assert_allclose(force, force_test_only, rtol=0.0, atol=1e-6 * force.max())


def test_newton_converges_quadratically_while_sliding() -> None:
    problem, mesh = block_on_plane(0.2)
    result = problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3)
    result = problem.run({"plane": (1e-3, 0, 0)}, max_increment=1e-3, result=result)
    history = result.residuals[-1]
    # Stick to slip inside one increment; the last steps square the residual.
    tail = [r for r in history if r > 1e-9 * history[0]]
    rates = [np.log(tail[i + 1] / tail[0]) / np.log(tail[i] / tail[0]) for i in
             range(1, len(tail) - 1)]
    assert len(tail) >= 3
    assert max(tail[-1] / tail[-2] ** 2, 0) < 1e3 / history[0], history
    assert rates[-1] > 1.6, (rates, history)


def test_the_start_of_an_increment_is_second_order_on_a_smooth_path() -> None:
    # A compressible elastic block (nu = 0.3) clamped at its top, pressed 10 % by a
    # frictionless plane: every pair stays closed, and the large-strain path is smooth and
    # curved in the travel (the block bulges). The first Newton correction from the start
    # measures the start's error. On this smooth path the start takes the rate's change
    # (ddpy.model.start: the last increment's own starts fit its answer with the change),
    # so it misses by O(h^3): relative to the increment's motion (O(h)) a quarter as the
    # increment halves. The last rate alone would halve it (O(h^2)); a start at the
    # converged state would leave it unchanged.
    material = Material(210e3, 0.3, Hill48.von_mises(), Swift(1e7, 0.01, 0.0))
    errors = []
    for h in (0.005, 0.0025):
        mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, 0.0))
        tool = RigidTool("plane", plane_tool(), mesh.select(z=0.0), facing=(0, 0, -1))
        problem = FormingProblem(Solid(mesh, material), [tool])
        problem.fix(mesh.select(z=0.5), "xyz")
        result = problem.run({"plane": (0, 0, 0.1)}, max_increment=h)
        assert set(result.limited_by) == {"max"}
        errors.append(np.median([rel[1].correction for rel in result.convergence[3:]]))
    assert 3.0 < errors[0] / errors[1] < 5.0, errors


def test_first_touch_and_strain_limit_set_the_increments() -> None:
    # The block hangs 0.1 mm above the plane; a 0.25 mm increment would push it 0.15 mm
    # through: the increment stops where the first (every) node touches.
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2, origin=(-0.5, -0.5, 0.1))
    tool = RigidTool("plane", plane_tool(), mesh.select(z=0.1), facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.6), "xyz")
    limits = IncrementLimits(strain=0.01)
    result = problem.run({"plane": (0, 0, 0.105)}, max_increment=0.25, limits=limits)
    assert result.limited_by[0] == "touch"
    assert result.tool_displacements["plane"][0][2] == pytest.approx(0.1, rel=2e-3)
    # Every bottom node is caught in contact, pressed only by the 1e-3 landing margin.
    assert result.contacts["plane"][0] == 9
    assert abs(result.tool_forces["plane"][0][2]) < 1e-3 * 210e3 * 0.1 / 0.5 * 1.5
    # Then 5 um into a 0.5 mm block: 1 % strain, at the limit; a 0.05 mm push would be 10 %.
    result = problem.run({"plane": (0, 0, 0.05)}, max_increment=0.05, limits=limits,
                         result=result)
    assert "strain" in result.limited_by
    steps = np.diff([0.1] + [d[2] for d in result.tool_displacements["plane"][1:]])
    # Uniaxial strain e has the equivalent strain sqrt(2/3) e: 1 % is a 6.1 um step at the
    # start; the Green-Lagrange increment of the block, already squeezed by up to 10 %,
    # is up to 10 % smaller than the step over the height.
    assert steps.max() <= 1.05 * 0.01 / np.sqrt(2.0 / 3.0) * 0.5 / 0.9


def test_a_gap_below_a_hundredth_of_an_element_counts_as_touching() -> None:
    # A block 0.5 % of its element size above the plane (the paper bending punch's Nagata
    # patches lay about that far from the blank): no increment lands it, the first one
    # takes the whole step; with the old 1e-3 the first increment was that sliver of a gap.
    gap = 5e-3 * HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2).element_size()

    def pressed(limits: IncrementLimits):
        mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2, origin=(-0.5, -0.5, gap))
        tool = RigidTool("plane", plane_tool(), mesh.select(z=gap), facing=(0, 0, -1))
        problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
        problem.fix(mesh.select(z=gap + 0.5), "xyz")
        return problem.run({"plane": (0, 0, 0.01)}, max_increment=0.005, limits=limits)

    default = pressed(IncrementLimits())
    assert default.limited_by[0] == "max"
    assert default.contacts["plane"][0] == 9
    old = pressed(IncrementLimits(touch_gap=1e-3))
    assert old.limited_by[0] == "touch"
    assert old.tool_displacements["plane"][0][2] == pytest.approx(gap, rel=2e-3)


def test_first_touch_lands_a_new_contact_zone_and_lets_its_front_join_inside() -> None:
    # A block whose bottom slopes 0.02 mm per mm over its 2 mm: its node rows hang 0.1,
    # 0.11, ..., 0.14 mm above a plane pushed up by 0.16 mm. Landing every node ends an
    # increment at each row; "new" lands the first row only (a new contact zone) and lets
    # the next rows, each next to a row in contact, close inside the increments.
    def pressed(touch: str):
        box = HexMesh.box(2.0, 1.0, 0.5, 4, 1, 1, origin=(0.0, -0.5, 0.1))
        bottom = box.select(z=0.1)
        nodes = box.nodes.copy()
        nodes[bottom, 2] += 0.02 * nodes[bottom, 0]
        mesh = HexMesh(nodes, box.elements)
        tool = RigidTool("plane", plane_tool(), bottom, facing=(0, 0, -1))
        problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
        problem.fix(box.select(z=0.6), "xyz")
        limits = IncrementLimits(strain=0.5, rotation_deg=90.0, touch=touch)
        return problem.run({"plane": (0, 0, 0.16)}, max_increment=0.25, limits=limits)

    every, new = pressed("every"), pressed("new")
    landed = [d[2] for d, why in zip(every.tool_displacements["plane"], every.limited_by,
                                     strict=True) if why == "touch"]
    # One landing per row (the later rows a little later than 0.11, 0.12, ...: the pressed
    # block bends up).
    assert len(landed) == 5 and landed[0] == pytest.approx(0.1, rel=2e-3)
    assert np.all(np.diff(landed) > 0.005)
    assert new.limited_by.count("touch") == 1
    assert new.tool_displacements["plane"][0][2] == pytest.approx(0.1, rel=2e-3)
    # The same end: every bottom node in contact, the same force (elastic, frictionless:
    # path-independent, to the Newton loop's force tolerance).
    assert new.contacts["plane"][-1] == every.contacts["plane"][-1] == 10
    assert new.tool_forces["plane"][-1][2] == pytest.approx(
        every.tool_forces["plane"][-1][2], rel=1e-4)


def test_springback_of_an_elastic_block_returns_it() -> None:
    problem, mesh = block_on_plane(0.2)
    problem.run({"plane": (3e-4, 0, 1e-3)}, max_increment=5e-4)
    assert np.abs(problem.u).max() > 1e-4
    problem.springback(increments=3)
    # Elastic, still clamped at the top: every node comes back.
    np.testing.assert_allclose(problem.u, 0.0, atol=1e-12)


def test_blank_holder_held_at_a_fixed_gap() -> None:
    # A die plane at z = 0 under the block's bottom, a holder plane at z = 2 above its top
    # (facing down); the holder is set 0.5 mm from the die, i.e. pressing the 0.5 mm block
    # not at all, then follows the die as the die moves.
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 1, origin=(-0.5, -0.5, 0.0))
    holder_surface = plane_tool(2.0, up=False)
    die = RigidTool("die", plane_tool(), mesh.select(z=0.0), facing=(0, 0, -1))
    holder = RigidTool("holder", holder_surface, mesh.select(z=0.5), facing=(0, 0, 1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [die, holder])
    problem.fix(mesh.select(x=-0.5), "xyz")
    result = problem.run({"die": (0, 0, 0.01)}, max_increment=0.01,
                         gaps={"holder": ("die", 0.499, (0, 0, 1))})
    # Set at the gap (1.501 mm down), then carried up with the die by 0.01 mm.
    np.testing.assert_allclose(result.tool_displacements["holder"][-1], [0, 0, -1.491],
                               atol=1e-9)
    with pytest.raises(ValueError, match="cannot also be moved"):
        problem.run({"holder": (0, 0, 1.0)}, max_increment=0.1,
                    gaps={"holder": ("die", 0.5, (0, 0, 1))})


def test_a_lifted_tool_lets_go_of_the_blank_in_steps() -> None:
    # A block clamped at its side between a die below and a punch above that presses it
    # 1 um. The next phase lifts the punch off: its forces become nodal loads brought to
    # zero in IncrementTuning.release_steps steps before the phase's first increment, whose
    # iterations they join (lifting it in one go leaves the blank out of balance by the whole force,
    # which no cut of that increment makes smaller). The block, elastic, comes back.
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 1, origin=(-0.5, -0.5, 0.0))
    top = plane_tool(0.5, up=False)
    die = RigidTool("die", plane_tool(), mesh.select(z=0.0), facing=(0, 0, -1))
    punch = RigidTool("punch", top, mesh.select(z=0.5), facing=(0, 0, 1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [die, punch])
    problem.fix(mesh.select(x=-0.5), "xy")
    pressed = problem.run({"punch": (0, 0, -1e-3)}, max_increment=1e-3)
    force = pressed.tool_forces["punch"][-1][2]
    assert force > 1.0  # the block pushes the punch up (the tool's reaction)
    assert pressed.tool_forces["die"][-1][2] == pytest.approx(-force, rel=1e-9)
    lifted = problem.run({}, max_increment=1.0, active=["die"])
    assert len(lifted.factors) == 1
    # One iteration at least per release step, then the (empty) increment's own.
    assert len(lifted.residuals[0]) >= IncrementTuning().release_steps + 1, lifted.residuals
    assert np.abs(lifted.tool_forces["punch"][-1]).max() == 0.0
    assert np.abs(lifted.tool_forces["die"][-1]).max() < 1e-6 * abs(force)
    np.testing.assert_allclose(problem.u[:, 2], 0.0, atol=1e-9)


def faceted_groove(angle_deg: float) -> NagataSurface:
    """Two facets meeting in a valley along x (y = 0, z = 0), each rising from it by half
    the angle: a concave facet edge, as the facets around the axis of a faceted die bore
    are to the cup inside it."""
    rise = 5.0 * np.tan(np.radians(angle_deg / 2))
    vertices = [[-10, -5, rise], [10, -5, rise], [10, 0, 0], [-10, 0, 0], [10, 5, rise],
                [-10, 5, rise]]
    return NagataSurface(vertices, [[0, 0, 1]] * 6, [[0, 1, 2, 3], [3, 2, 4, 5]],
                         smooth=False)


def test_a_node_hopping_between_two_facets_is_held_on_one() -> None:
    # A block clamped at its top is pressed 0.05 mm into a groove of two facets 4 degrees
    # apart (friction 0.1); its middle row of bottom nodes lands on the valley, where
    # each facet's force pushes the node onto the other one. Without the hold that
    # increment hops between the facets for 25 iterations and is cut; held on its facet
    # from iteration 8 (ddpy_forming_newton), it converges in 10, the search agreeing.
    mesh = HexMesh.box(1.0, 2.0, 0.5, 2, 2, 2, origin=(-0.5, -1.0, 0.2))
    tool = RigidTool("groove", faceted_groove(4.0), mesh.select(z=0.2), facing=(0, 0, -1),
                     friction=0.1)
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.7), "xyz")
    result = problem.run({"groove": (0, 0, 0.25)}, max_increment=0.05)
    assert result.cuts == 0 and max(result.iterations) <= 12, (result.cuts,
                                                              result.iterations)
    # The valley row touches: the groove carries the block's whole push.
    assert result.contacts["groove"][-1] == 9
    assert result.tool_forces["groove"][-1][2] < 0.0


def test_frictionless_cylinder_into_a_plate_gives_the_hertz_pressure() -> None:
    # Plane strain: a rigid cylinder (R 10 mm, Nagata, 64 patches on 80 degrees) pressed
    # 20 um into a 2 x 6 x 4 mm elastic plate (half model, x = 0 symmetry), 0.1 mm
    # elements. Hertz (line contact): a = sqrt(4 P R / (pi E*)), p = p0 sqrt(1 - x^2/a^2),
    # p0 = 2 P / (pi a), with P the force per unit length, which the run gives.
    young, nu, radius, h = 210e3, 0.3, 10.0, 0.1
    material = Material(young, nu, Hill48.von_mises(), Swift(1e7, 0.01, 0.0))
    mesh = HexMesh.box(6.0, h, 4.0, 60, 1, 40, origin=(0.0, 0.0, -4.0))
    phi = np.radians(np.linspace(-40.0, 40.0, 65))
    m = phi.size
    rim = np.column_stack([radius * np.sin(phi), radius * (1.0 - np.cos(phi))])
    normal = np.column_stack([np.sin(phi), -np.cos(phi)])  # outward of the cylinder: down
    vertices = np.vstack([np.column_stack([rim[:, 0], np.full(m, y), rim[:, 1]])
                          for y in (-1.0, 1.0)])
    normals = np.vstack([np.column_stack([normal[:, 0], np.zeros(m), normal[:, 1]])] * 2)
    i = np.arange(m - 1)
    cylinder = NagataSurface(vertices, normals, np.column_stack([i + m, i + 1 + m, i + 1, i]))
    top = mesh.select(z=0.0)
    problem = FormingProblem(Solid(mesh, material),
                             [RigidTool("cylinder", cylinder, top, facing=(0, 0, 1))])
    problem.fix(mesh.select(x=0.0), "x")
    problem.fix(np.arange(mesh.n_nodes), "y")
    problem.fix(mesh.select(z=-4.0), "z")
    result = problem.run({"cylinder": (0, 0, -0.02)}, max_increment=0.01)
    load = 2.0 * result.tool_forces["cylinder"][-1][2] / h  # both halves, per unit length
    half_width = np.sqrt(4.0 * load * radius / (np.pi * young / (1.0 - nu**2)))
    peak = 2.0 * load / (np.pi * half_width)
    x = mesh.nodes[top, 0]
    columns = np.unique(x)
    force = np.array([-problem.force[x == c, 2].sum() for c in columns])
    width = np.where((columns == 0.0) | (columns == 6.0), h / 2, h)
    pressure = force / (width * h)
    inside = columns < 0.8 * half_width
    hertz = peak * np.sqrt(1.0 - (columns[inside] / half_width) ** 2)
    assert inside.sum() >= 3
    np.testing.assert_allclose(pressure[inside], hertz, rtol=0.05)
    # The contact ends within one element of a.
    last = columns[force > 1e-9 * force.max()].max()
    assert abs(last - half_width) < h


def test_increment_lands_on_the_yield_surface() -> None:
    # A steel block (Y0 = 645.3 * 0.0102^0.252 = 203 MPa, nu = 0: uniaxial stress) squeezed
    # by 2 um steps: the first step that would yield stops where the block reaches Y0.
    steel = Material(210e3, 0.0, Hill48.von_mises(), Swift(645.3, 0.0102, 0.252))
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2, origin=(-0.5, -0.5, 0.0))
    tool = RigidTool("plane", plane_tool(), mesh.select(z=0.0), facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, steel), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    result = problem.run({"plane": (0, 0, 6e-3)}, max_increment=2e-3,
                         limits=IncrementLimits(yield_tolerance=0.02))
    first_yield = result.limited_by.index("yield")
    force = -result.tool_forces["plane"][first_yield][2]
    y0 = 645.3 * 0.0102**0.252
    assert y0 <= force <= 1.02 * y0
    assert result.tool_displacements["plane"][-1][2] == pytest.approx(6e-3)


def test_yield_landing_skips_points_at_the_surface_and_reloading() -> None:
    # Uniaxial stress in one Gauss point under a step that would overshoot the yield stress
    # by 50 %: from 0.5 Y the step is cut to reach Y (r = 0.5 / 1.0 of the way, plus half the
    # tolerance); from 0.9996 Y (a point a tiny unloading left just inside the surface) it is
    # not cut at all, instead of being cut to ~1e-3 again and again.
    steel = Material(210e3, 0.0, Hill48.von_mises(), Swift(645.3, 0.0102, 0.252))
    props = material_props(steel)
    y0 = 645.3 * 0.0102**0.252

    def landing(sigma: float, strain: float, ep: float = 0.0) -> float:
        stress, increment = np.zeros((8, 6)), np.zeros((8, 6))
        stress[:, 0], increment[:, 0] = sigma, strain
        return yield_landing(props, stress, np.full(8, ep), increment, 0.01)

    de = 1.0 * y0 / 210e3
    assert landing(0.5 * y0, de) == pytest.approx(0.5 * 1.005, rel=1e-6)
    assert landing(0.9996 * y0, de) == 1.0
    # A point that yielded before (ep 0.05, Y = 318 MPa) and unloaded to half its yield
    # stress reloads without a landing; its first yielding was landed.
    y = 645.3 * (0.0102 + 0.05)**0.252
    assert landing(0.5 * y, 1.0 * y / 210e3, ep=0.05) == 1.0


def test_springback_supports_only_the_rigid_modes() -> None:
    # Steel squeezed between the plane and the clamp, yielding; the clamp is released and
    # the block springs back with a 3-2-1 set of supports found automatically.
    steel = Material(210e3, 0.3, Hill48.von_mises(), Swift(645.3, 0.0102, 0.252))
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2, origin=(-0.5, -0.5, 0.0))
    tool = RigidTool("plane", plane_tool(), mesh.select(z=0.0), facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, steel), [tool])
    top = mesh.select(z=0.5)
    problem.fix(top, "xyz")
    problem.run({"plane": (0, 0, 5e-3)}, max_increment=1e-3)
    assert problem.solid_state.ep.max() > 1e-3
    problem.release(top)
    assert problem.free_rigid_modes() == 6
    before = problem.u.copy()
    problem.springback(increments=2)
    assert problem.free_rigid_modes() == 0
    assert int(problem.fixed.sum()) == 6  # 3 + 2 + 1 dofs, nothing more
    # The tool forces are gone: the block is in equilibrium with no load, so the
    # supports carry nothing; it springs back by the elastic part only.
    fint, _ = problem.solid.internal_force(problem.u, problem.solid_state)
    assert np.abs(fint).max() < 1e-6 * 203.0
    assert 0.0 < np.abs(problem.u - before).max() < 2e-3


def test_rotation_increment_and_a_tool_inside_the_blank() -> None:
    problem, mesh = block_on_plane(0.0)
    angle = np.radians(2.0)
    x = mesh.nodes
    rotated = x @ np.array([[np.cos(angle), np.sin(angle), 0], [-np.sin(angle), np.cos(angle), 0],
                            [0, 0, 1.0]])
    # A rigid rotation by a small angle: the increment's rotation is its tangent-ish angle.
    assert largest_rotation(x, mesh.elements, rotated - x) == pytest.approx(np.sin(angle),
                                                                          rel=1e-9)
    # A phase that starts with the tool 0.3 mm inside the 0.5 mm block is refused.
    problem.position["plane"] = np.array([0.0, 0.0, 0.3])
    with pytest.raises(ValueError, match="starts inside the blank"):
        problem.run({"plane": (0, 0, 0.1)}, max_increment=0.05)


@pytest.mark.parametrize("kind", ["nagata", "bezier"])
def test_quadratic_convergence_sliding_with_friction_over_a_curved_tool(kind: str) -> None:
    # The curvature term of the tangent at work: nodes slip over a cylinder crest.
    mesh = HexMesh.box(2.0, 1.0, 0.5, 8, 2, 2, origin=(-1.0, -0.5, 0.0))
    tool = RigidTool("cylinder", cylinder_crest(kind, 8 if kind == "nagata" else 4),
                     mesh.select(z=0.0), friction=0.15, facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    result = problem.run({"cylinder": (0, 0, 0.02)}, max_increment=0.02)
    result = problem.run({"cylinder": (0.2, 0, 0)}, max_increment=0.05, result=result,
                         newton=NewtonSettings(1e-12, 1e-6))
    assert (result.last.contact_states["cylinder"] == SLIP).sum() >= 3
    rates = []
    for history in result.residuals[-3:]:
        tail = [r for r in history if r > 1e-13 * history[0]]
        if len(tail) >= 3:
            rates.append(np.log(tail[-1] / tail[-2]) / np.log(tail[-2] / tail[-3]))
    assert rates and max(rates) > 1.7, (rates, result.residuals[-3:])


#: The release limit at its strictest: every node's release limits (no share exempts a
#: node), and an increment is redone at a release as often as it takes.
STRICT_RELEASE = IncrementLimits(release_share=0.0, release_redos=None)


def lift_off(max_increment: float, limits: IncrementLimits = STRICT_RELEASE
             ) -> tuple[list[float], list[str], list[int], float]:
    """The clamped block pressed 1 mm / 1000 onto the plane, then the plane lowered by 2 um:
    the plane's height after each increment of the lift, what limited it, the nodes in
    contact, and the element size."""
    problem, _ = block_on_plane(0.3)
    result = problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3)
    start = len(result.factors)
    result = problem.run({"plane": (0, 0, -2e-3)}, max_increment=max_increment,
                         limits=limits, result=result)
    heights = [float(d[2]) for d in result.tool_displacements["plane"][start - 1:]]
    return heights, result.limited_by[start:], result.contacts["plane"][start:], problem.size


@pytest.mark.parametrize("max_increment", [7e-4, 1.5e-3])
def test_release_of_the_nodes_ends_an_increment(max_increment: float) -> None:
    # Elastic (nu = 0) and clamped at its top, the block lets go of the plane exactly when
    # the plane passes z = 0, its undeformed bottom. The increment in which every node is
    # released ends within the last 5 % of itself past that point (release tolerance 0.05):
    # mid-phase from the pressure trend of the last increment (7e-4), in the first
    # increment of the phase by interpolating the augmented pressure (1.5e-3).
    heights, limited_by, contacts, _ = lift_off(max_increment)
    k = contacts.index(0)
    assert k >= 1 and contacts[k - 1] == 16
    assert limited_by[k] == "release", limited_by
    before, after = heights[k], heights[k + 1]
    assert before > 0.0 >= after > -0.05 * (before - after), (before, after)
    # The plane then goes on at the nominal increment.
    assert heights[-1] == pytest.approx(-1e-3)
    # Without the release limit the increment runs far past the release.
    heights, limited_by, contacts, _ = lift_off(max_increment,
                                                replace(STRICT_RELEASE, release=None))
    k = contacts.index(0)
    assert "release" not in limited_by
    assert heights[k + 1] < -0.1 * (heights[k] - heights[k + 1])


def test_release_redos_are_capped() -> None:
    # In the first increment of the phase the release is seen only after the increment,
    # which is redone to end just past it. With no redo allowed the increment is accepted
    # with the release inside it, as without the release limit.
    for redos, limited in ((1, True), (None, True), (0, False)):
        heights, limited_by, contacts, _ = lift_off(
            1.5e-3, replace(STRICT_RELEASE, release_redos=redos))
        k = contacts.index(0)
        assert (limited_by[k] == "release") is limited, (redos, limited_by)
        before, after = heights[k], heights[k + 1]
        assert (after > -0.05 * (before - after)) is limited, (redos, before, after)
        assert heights[-1] == pytest.approx(-1e-3)
    with pytest.raises(ValueError, match="release_redos must lie in 0.."):
        IncrementLimits(release_redos=-1)


def test_release_of_nodes_with_a_small_share_of_the_force_does_not_limit() -> None:
    # The 16 nodes under the clamped block carry 1/16 of the force on average, the corner
    # ones less. A share of 1 exempts every node (as no release limit); a share below the
    # smallest node's exempts none (as the strict limit).
    problem, _ = block_on_plane(0.3)
    problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3)
    pressure = problem.force[:, 2]
    shares = pressure / pressure.sum()
    assert shares.min() > 0.0 and shares.max() < 0.2, shares
    for share, limited in ((1.0, False), (0.5 * shares.min(), True)):
        heights, limited_by, contacts, _ = lift_off(
            7e-4, replace(STRICT_RELEASE, release_share=share))
        assert ("release" in limited_by) is limited, (share, limited_by)
        assert contacts[-1] == 0 and heights[-1] == pytest.approx(-1e-3)


def test_a_block_held_only_by_contact_solves_from_the_start() -> None:
    # A block lying on a die plane (zero gap, no force) with nothing else holding it: every
    # rigid mode is free. A punch plane 0.05 mm above comes down and squeezes it by 1 um.
    # The open nodes on the die would leave the tangent singular in the first iterations;
    # the closed predictor takes nodes lying on a tool as in contact, so the first Newton
    # step is a full one and the answer is the uniaxial one (nu = 0, stick on both faces).
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2, origin=(-0.5, -0.5, 0.0))
    above = NagataSurface([[-5, -5, 0.55], [-5, 5, 0.55], [5, 5, 0.55], [5, -5, 0.55]],
                          [[0, 0, -1]] * 4, [[0, 1, 2, 3]])
    die = RigidTool("die", plane_tool(), mesh.select(z=0.0), friction=0.2, facing=(0, 0, -1))
    punch = RigidTool("punch", above, mesh.select(z=0.5), friction=0.2, facing=(0, 0, 1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [die, punch])
    assert problem.free_rigid_modes() == 6
    result = problem.run({"punch": (0, 0, -0.051)}, max_increment=0.1)
    assert result.cuts == 0 and result.limited_by == ["touch", "max"]
    for history in result.residuals:
        assert history[1] < 1e-2 * history[0], history   # a full first step
    stretch = 1.0 - 1e-3 / 0.5
    squeeze = -210e3 * np.log(stretch) / stretch   # Hencky, nu = 0: nominal stress
    assert -result.tool_forces["die"][-1][2] == pytest.approx(squeeze, rel=1e-9)
    assert result.tool_forces["punch"][-1][2] == pytest.approx(squeeze, rel=1e-9)
    assert np.abs(problem.u[:, :2]).max() < 1e-12   # no rigid drift in the plane


def test_bad_contact_input_is_refused_before_the_run() -> None:
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, 0.0))
    with pytest.raises(ValueError, match="tool plane has no slave nodes"):
        RigidTool("plane", plane_tool(), [], facing=(0, 0, -1))
    with pytest.raises(ValueError, match="tool plane: friction must be >= 0, got -0.1"):
        RigidTool("plane", plane_tool(), mesh.select(z=0.0), friction=-0.1)
    with pytest.raises(ValueError, match="no patch faces its slave nodes"):
        RigidTool("plane", plane_tool(), mesh.select(z=0.0), facing=(0, 0, 1))
    with pytest.raises(ValueError, match="release must lie in"):
        IncrementLimits(release=1.0)
    # A tool deeper in the blank than the strain limit times the element size (0.02 x
    # 0.303 mm here) is refused before any numerics; a slight overlap is not.
    problem, mesh = block_on_plane(0.0)
    problem.position["plane"] = np.array([0.0, 0.0, 0.01])
    with pytest.raises(ValueError, match="plane starts inside the blank: slave node .* is "
                                         "0.01 mm deep"):
        problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3)
    assert not problem.u.any()
    problem.position["plane"] = np.array([0.0, 0.0, 0.005])
    problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3)
    # So is a blank-holder placed by its gap inside the blank.
    holder = NagataSurface([[-5, -5, 2], [-5, 5, 2], [5, 5, 2], [5, -5, 2]],
                           [[0, 0, -1]] * 4, [[0, 1, 2, 3]])
    block = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 1, origin=(-0.5, -0.5, 0.0))
    problem = FormingProblem(Solid(block, ELASTIC), [
        RigidTool("die", plane_tool(), block.select(z=0.0), facing=(0, 0, -1)),
        RigidTool("holder", holder, block.select(z=0.5), facing=(0, 0, 1))])
    problem.fix(block.select(x=-0.5), "xyz")
    with pytest.raises(ValueError, match="holder starts inside the blank"):
        problem.run({"die": (0, 0, 0.01)}, max_increment=0.01,
                    gaps={"holder": ("die", 0.3, (0, 0, 1))})


@pytest.mark.parametrize("linear_solver, single", [("auto", 0), ("reuse", 0), ("reuse", 1)])
def test_springback_of_a_bent_strip_converges_quadratically(linear_solver: str,
                                                            single: int) -> None:
    # With "reuse" the forming's Newton solves by GMRES on older factors; springback solves
    # exactly all the same (on the bending paper mesh the older factors made 16 iterations of
    # each step, 3 without them); with single-precision factors (``single``) by GMRES on
    # them to 1e-8. A steel strip (half of a symmetric one: u_x = 0 at x = 0, u_y = 0 at y = 0, the
    # centre line held in z) bent as a cantilever by a tip load well into the plastic range, then
    # released. The unloading is elastic and its tangent exact, so Newton converges quadratically;
    # the residual norm is a poor measure of progress for it (a step that bends the strip right
    # leaves a large membrane residual of second order), and backtracking on that norm crept along
    # at 1/16 steps (24 to 31 iterations per step).
    solid, bent, tip = _bent_strip()
    shapes = {}
    for increments in (1, 5):
        problem = _released_strip(solid, bent, linear_solver, single)
        result = problem.springback(increments, NewtonSettings(1e-8, 1e-8))
        # exact solves: with single factors by GMRES on them, else directly
        assert (result.krylov_iterations > 0) == bool(single)
        assert problem.solid_state.ep.max() == bent.state.ep.max()  # elastic unloading
        shapes[increments] = problem.u
        assert max(result.iterations) <= (8 if increments == 1 else 5), result.iterations
        # The rate on the corrections (relative to the step's motion), the measure of the
        # error; a step after the first starts from the last one's rate, where the
        # residual, of second order in the bending, is no scale for it.
        checked = 0
        for iterations in result.convergence:
            e = np.array([it.correction for it in iterations[1:]])
            for now, after in zip(e[:-1], e[1:], strict=True):
                if now < 0.02 and after > 1e-8:  # quadratic above round-off
                    assert after <= 10.0 * now**2, e
                    checked += 1
        assert checked >= (1 if increments == 1 else 3)  # the rate is seen
    # Elastic unloading does not depend on the steps (up to the rotating frame's path
    # dependence): the strip springs back by 0.28 mm at its tip.
    np.testing.assert_allclose(shapes[1], shapes[5], atol=1e-6)
    springback = bent.displacements[-1][tip, 2] - shapes[5][tip, 2]
    assert springback.min() > 0.1


def test_the_error_the_convergence_test_judges_bounds_the_true_error() -> None:
    # The bent strip released in one step, the residual test loose (0.1) so that the
    # displacement test decides: the accepted iterate's distance from the converged shape
    # (the same step at 1e-10) is within the error the test estimated from its last two
    # corrections, and that within the tolerance; the estimate is never above the last
    # correction, and at 1e-2 it is what accepted an iterate whose correction was above.
    solid, bent, _ = _bent_strip()
    reference = _released_strip(solid, bent)
    reference.springback(1, NewtonSettings(1e-10, 1e-10))
    motion = np.linalg.norm(reference.u - bent.displacements[-1])
    for tolerance in (1e-2, 1e-4):
        problem = _released_strip(solid, bent)
        last = problem.springback(1, NewtonSettings(0.1, tolerance)).convergence[-1][-1]
        true_error = np.linalg.norm(problem.u - reference.u) / motion
        assert true_error <= last.error <= tolerance, (true_error, last)
        assert last.error <= last.correction
        if tolerance == 1e-2:
            assert last.correction > tolerance, last


def _bent_strip() -> tuple[_Solid, SolidResult, np.ndarray]:
    """A steel strip (half of a symmetric one: u_x = 0 at x = 0, u_y = 0 at y = 0, the centre
    line held in z) bent as a cantilever by a tip load well into the plastic range: the solid,
    the static run, its tip nodes."""
    steel = Material(210e3, 0.3, Hill48.von_mises(), Swift(645.3, 0.0102, 0.252))
    mesh = HexMesh.box(20.0, 2.0, 1.0, 20, 1, 2)
    centre, tip = mesh.select(x=0.0, y=0.0), mesh.select(x=20.0)
    solid = Solid(mesh, steel)
    static = StaticProblem(solid)
    static.fix(mesh.select(x=0.0), "x")
    static.fix(mesh.select(y=0.0), "y")
    static.fix(centre, "z")
    static.load(tip, np.tile([0.0, 0.0, 35.0 / tip.size], (tip.size, 1)))
    bent = static.solve(increments=8, newton=NewtonSettings(1e-10, 1e-8))
    assert bent.state is not None and bent.state.ep.max() > 0.1
    return solid, bent, tip


def _released_strip(solid: _Solid, bent: SolidResult, linear_solver: str = "auto",
                    single_factors: int = 0) -> FormingProblem:
    """The bent strip as a forming problem with a tool far away, ready to spring back
    (``single_factors``: FormingTuning's)."""
    mesh = solid.mesh
    far = NagataSurface([[-5, -5, -50], [50, -5, -50], [50, 5, -50], [-5, 5, -50]],
                        [[0, 0, 1]] * 4, [[0, 1, 2, 3]])
    problem = FormingProblem(solid, [RigidTool("far", far, mesh.select(z=0.0),
                                               facing=(0, 0, -1))],
                             linear_solver=linear_solver,
                             tuning=FormingTuning(single_factors=single_factors))
    problem.u, problem.solid_state = bent.displacements[-1].copy(), bent.state
    problem.fix(mesh.select(x=0.0), "x")
    problem.fix(mesh.select(y=0.0), "y")
    problem.fix(mesh.select(x=0.0, y=0.0), "z")
    return problem


def test_a_springback_step_that_fails_is_halved() -> None:
    # The strip above released in one step needs up to 8 iterations (the test above): allowed 4,
    # the step fails and is halved until its pieces converge (twice: a quarter of the release
    # takes 4); the steps grow back after each one, and the shape is that of 5 equal steps
    # (elastic unloading). With no halving allowed the same step stops the springback, with
    # its reason.
    solid, bent, _ = _bent_strip()
    reference = _released_strip(solid, bent)
    reference.springback(5, NewtonSettings(1e-8, 1e-8))
    problem = _released_strip(solid, bent)
    # (2 halvings allowed: the step that converges is the smallest, and grows from there.)
    result = problem.springback(1, NewtonSettings(1e-8, 1e-8, max_iterations=4), max_cuts=2)
    assert result.cuts == 2 and result.sizes[0] == 0.25
    assert result.factors[-1] == 1.0
    np.testing.assert_allclose(np.diff(result.factors, prepend=0.0), result.sizes)
    assert max(result.sizes[1:]) > min(result.sizes)  # grown back after the halvings
    np.testing.assert_allclose(problem.u, reference.u, atol=1e-6)
    # The cut is the deck's cutback, the growth the increment policy's regrow (2): an
    # eighth's cut lands on 1/8 in one cut where halving took two to 1/4, and grows by
    # doubling.
    eighth = _released_strip(solid, bent).springback(
        1, NewtonSettings(1e-8, 1e-8, max_iterations=4, cutback=0.125), max_cuts=4)
    assert eighth.cuts == 1
    np.testing.assert_array_equal(eighth.sizes, [0.125, 0.25, 0.5, 0.125])
    with pytest.raises(FormingError, match="springback step to 1 of the release failed"):
        _released_strip(solid, bent).springback(1, NewtonSettings(1e-8, 1e-8, max_iterations=4),
                                         max_cuts=0)


def test_next_increment_tries_the_nominal_size_again_after_a_limit() -> None:

    # Touch, release and yield are found before or in the first iteration: back to nominal
    # unless the rates predict a strain or rotation limit.
    for reason in ("touch", "release", "yield", "max"):
        assert next_step(0.01, 0.1, reason, 0.05, 0.01) == (0.1, "max")
        assert next_step(0.01, 0.1, reason, 0.2, 0.1) == (pytest.approx(0.045), "strain")
    # A strain or rotation limit is seen only after convergence: the next size is
    # predicted from this increment's rate, to 90 % of the limit.
    step, reason = next_step(0.05, 0.1, "strain", 1.0, 0.5)
    assert step == pytest.approx(0.045) and reason == "strain"
    step, reason = next_step(0.05, 0.1, "max", 0.2, 1.5)
    assert step == pytest.approx(0.03) and reason == "rotation"
    # After a cut (divergence) the size at most doubles per increment.
    assert next_step(0.01, 0.1, "cut", 0.1, 0.1) == (0.02, "regrow")
    assert next_step(0.04, 0.1, "regrow", 0.1, 0.1) == (0.08, "regrow")
    assert next_step(0.08, 0.1, "regrow", 0.1, 0.1) == (0.1, "max")


def test_contact_filter_follows_the_blank_surface_as_it_turns() -> None:
    # The slaves' outward normals come from the blank's faces in the current configuration:
    # turned 90 degrees about y, the bottom of a block faces -x (a sheet wrapped over a die
    # shoulder onto its wall), and the plane z = 0 (normal +z) no longer opposes it: no
    # slave finds a patch. The fixed facing (0, 0, -1) would still pair them with it.
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2, origin=(-0.5, -0.5, 0.05))
    bottom = mesh.select(z=0.05)
    tool = RigidTool("plane", plane_tool(), bottom, facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])

    def gaps(x: np.ndarray) -> np.ndarray:
        return problem.contact_state(u=x - mesh.nodes)[1]

    assert np.allclose(gaps(mesh.nodes), 0.05)
    turn = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # about y
    turned = (mesh.nodes - [0.0, 0.0, 1.0]) @ turn.T + [0.0, 0.0, 1.0]
    assert np.isinf(gaps(turned)).all()


def test_a_newton_step_stops_where_free_nodes_would_enter_a_tool() -> None:
    # The block hangs 0.1 mm above the plane, its bottom nodes free (no contact). A step
    # moving every free node 1 mm down may go only until they are FormingTuning.penetration
    # element sizes deep; a step moving them up, or a node already in contact, is not limited.
    # (The core's Newton loop applies this limit to the first trial of every step.)
    from ddpy import _core
    from ddpy.model.contact import INACTIVE
    PENETRATION, MIN_STEP = FormingTuning().penetration, FormingTuning().min_step

    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2, origin=(-0.5, -0.5, 0.1))
    tool = RigidTool("plane", plane_tool(), mesh.select(z=0.1), facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.6), "xyz")
    state, gap, normal = problem.contact_state()
    assert (state == INACTIVE).all() and np.allclose(gap, 0.1)
    pair_node = np.concatenate([t.slaves for t in problem.tools]).astype(np.int32)
    on = np.ones(pair_node.size, dtype=np.int32)
    down = np.zeros((mesh.n_nodes, 3))
    down[~problem.fixed[:, 2], 2] = -1.0

    def step(du: np.ndarray, states: np.ndarray) -> float:
        return _core.penetration_step(du.ravel(), pair_node, on, states, gap,
                                      normal.ravel(), PENETRATION * problem.size, MIN_STEP)

    assert step(down, state) == pytest.approx(0.1 + PENETRATION * problem.size)
    assert step(-down, state) == 1.0
    closed = np.full_like(state, 2)  # every pair in contact (slip): the tangent sees the tool
    assert step(down, closed) == 1.0
    # A step of 1 km still moves: the shortest fraction is FormingTuning.min_step.
    assert step(1e6 * down, state) == MIN_STEP


def test_nodes_at_a_tools_edge_keep_their_contact_state_through_the_first_increment(
) -> None:
    # The first increment of the built-in bending case with DD3IMP's discretization
    # (hexahedra, node-to-surface contact): the blank's side nodes at y = 0 and 10 lie on
    # the die's edges, and its Poisson contraction moves them off by rounding-sized
    # amounts. Their gap there is the normal distance (a seam within 1e-5 of the tool's
    # size, docs/theory/contact.md): the increment converges as a smooth one, in 6
    # iterations with no line search that every step length fails. With the Euclidean
    # distance signed by a normal distance near zero, those nodes flipped between closed
    # and open: 13 iterations, 2 of them on the line search's fallback.
    from ddpy.app.runner import DEFAULT_CASE, build_problem
    from ddpy.io.decks import read_case

    case = read_case(DEFAULT_CASE)
    case = replace(case, element="hexahedron",
                   tools=[replace(t, discretization="node") for t in case.tools])
    phase = case.phases[0]
    problem = build_problem(case)
    for nodes, component in zip(*case.boundary.constrained(phase.name), strict=True):
        problem.fix([nodes], int(component))
    motion = {m.tool: phase.displacement(m.tool) for m in phase.motions}
    result = problem.run(motion, phase.max_increment, active=phase.tools,
                         newton=phase.newton, limits=phase.limits,
                         on_increment=lambda progress: True)  # one increment
    assert len(result.factors) == 1 and result.cuts == 0
    assert result.fallbacks == 0 and result.newton_iterations <= 8
    assert result.convergence[0][-1].residual <= phase.newton.force_tolerance


def test_jacobian_of_the_combined_equations_matches_central_differences() -> None:
    """The Jacobian the Newton loop factorizes, blank and contact together (material,
    geometric, tool-curvature and friction terms), against central differences of the
    residual over every unknown, at a point with stick, slip and open pairs on a curved
    tool: every entry within 1e-7 of the largest entry of its rows' block, equilibrium or
    contact law (h = 1e-5 of the unknown's scale; measured 5e-10 and 6e-9)."""
    normals = [[-0.05, -0.05, 1], [0.05, -0.05, 1], [0.05, 0.05, 1], [-0.05, 0.05, 1]]
    dome = NagataSurface([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]],
                         np.array(normals) / np.linalg.norm(normals, axis=1)[:, None],
                         [[0, 1, 2, 3]])
    lift = float(dome.evaluate([0], [[0.5, 0.5]])[0][0, 2])  # the top of the dome
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, lift))
    tool = RigidTool("dome", dome, mesh.select(z=lift), friction=0.3, facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=lift + 0.5), "xyz")
    problem.run({"dome": (2e-4, 0, 4e-3)}, max_increment=1e-3)
    rng = np.random.default_rng(7)
    u = problem.u + 1e-5 * rng.standard_normal(problem.u.shape) * ~problem.fixed
    force = problem.force * (1.0 + 0.5 * rng.standard_normal(problem.force.shape))
    force[::4] = 0.0  # some pairs without force, lifted off the dome: open
    u[tool.slaves[::4], 2] += 5e-3
    force[1::4, 0] = force[1::4, 2]  # beyond the friction cone (mu = 0.3): slip
    moved = {"dome": problem.position["dome"] + (3e-5, 1e-5, 2e-5)}
    # Equilibrium rows (N/mm, N) and contact-law rows (mm, N/r) each against their own size.
    equilibrium, law, state = central_difference_errors(problem, u, force, moved, 1e-5)
    assert {0, 1, 2} <= set(state.tolist()), state  # open, stick and slip pairs
    assert equilibrium <= 1e-7 and law <= 1e-7, (equilibrium, law)
