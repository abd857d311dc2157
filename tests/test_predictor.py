"""The start of an increment clear of the barriers (ddpy.model.predictor.clear_of_barriers):
a slave node of a barrier tool carried past the end of the barrier's ramp comes back along
the tool's normal to the middle of the ramp, with its whole column through the thickness
(docs/theory/contact.md, "A start clear of the barrier")."""

from __future__ import annotations

import numpy as np
import pytest
from test_penetration import PLANE
from test_surface_contact import dome

from ddpy.geometry.surfaces import NagataSurface
from ddpy.model.mesh import HexMesh, through_thickness_columns
from ddpy.model.newton import contact_faces
from ddpy.model.predictor import clear_of_barriers
from ddpy.model.tool import BARRIER_DEPTH, BARRIER_WIDTH, RigidTool

THICKNESS = 0.5
#: Where the barrier starts and where its ramp ends (mm) on this blank.
START = BARRIER_DEPTH * THICKNESS
END = START + BARRIER_WIDTH * THICKNESS


def blank() -> tuple[HexMesh, np.ndarray]:
    """A 1 x 1 x 0.5 mm blank in two layers and the bottom node of each node's column."""
    mesh = HexMesh.box(1.0, 1.0, THICKNESS, 2, 2, 2)
    bottom, _ = through_thickness_columns(mesh.nodes, mesh.elements, (0, 0, 1))
    return mesh, bottom


def depths(tool: RigidTool, x: np.ndarray, where: np.ndarray) -> np.ndarray:
    """Depth (mm, > 0 inside) of the slave nodes of ``tool`` at positions x."""
    return -tool.search.project(x[tool.slaves], where).distance


@pytest.mark.parametrize("surface", [PLANE, dome()], ids=["plane", "dome"])
def test_nodes_past_the_ramp_come_back_to_its_middle_with_their_columns(surface) -> None:
    """The bottom nodes sunk to depths on both sides of the ramp's end: those past it end
    at d_b + w / 2 (to rounding on the plane; on the dome, whose normal turns, to within the
    move's second-order term), those short of it stay where they were; every column keeps
    its length and the nodes of one column move alike."""
    mesh, bottom = blank()
    tool = RigidTool("tool", surface, mesh.select(z=0.0), facing=(0, 0, -1), contact="gauss")
    where = np.zeros(3)
    lift = float(-tool.search.project(mesh.nodes[tool.slaves], where).distance.min())
    sink = np.array([0.02, END * 1.2, END * 0.8, START * 0.5, 0.0, 0.01, 0.3 * END, 0.05,
                     0.002])[: tool.slaves.size]
    guess = np.zeros_like(mesh.nodes)
    guess[:, 2] = lift  # the blank's bottom on the surface's highest point
    for column_bottom, down in zip(tool.slaves, sink, strict=True):
        guess[bottom == column_bottom, 2] -= down
    before = depths(tool, mesh.nodes + guess, where)
    start, moved = clear_of_barriers(guess, mesh.nodes, [tool], contact_faces([tool], mesh),
                                     {"tool": where}, THICKNESS, bottom, reach=1.0)
    after = depths(tool, mesh.nodes + start, where)
    past = before > END
    assert moved == past.sum() > 0
    tolerance = 1e-12 if surface is PLANE else 1e-6
    np.testing.assert_allclose(after[past], START + 0.5 * (END - START), atol=tolerance)
    np.testing.assert_array_equal(after[~past], before[~past])
    shift = start - guess
    np.testing.assert_array_equal(shift, shift[bottom])
    x, y = mesh.nodes + guess, mesh.nodes + start
    columns = np.linalg.norm(x - x[bottom], axis=1)
    np.testing.assert_allclose(np.linalg.norm(y - y[bottom], axis=1), columns, atol=1e-15)


def test_only_gauss_point_tools_with_a_barrier_move_the_start() -> None:
    """A node sunk 0.02 mm (eight times past the ramp's end) stays where the start put it
    when its tool has no barrier or node-to-surface contact; the start is returned as it
    came."""
    mesh, bottom = blank()
    guess = np.zeros_like(mesh.nodes)
    guess[:, 2] = -0.02
    for tool in (RigidTool("tool", PLANE, mesh.select(z=0.0), facing=(0, 0, -1),
                           contact="gauss", barrier=None),
                 RigidTool("tool", PLANE, mesh.select(z=0.0))):
        start, moved = clear_of_barriers(guess, mesh.nodes, [tool],
                                         contact_faces([tool], mesh), {"tool": np.zeros(3)},
                                         THICKNESS, bottom, reach=1.0)
        assert moved == 0 and start is guess


def test_a_column_squeezed_between_two_tools_takes_both_moves() -> None:
    """The blank sunk 0.02 mm into a plane below and 0.03 mm into one above (the same
    plane turned over, lowered onto the top): each column moves by the sum of its two
    moves, up by 0.02 - d_m and down by 0.03 - d_m (d_m the ramp's middle)."""
    mesh, bottom = blank()
    top = mesh.select(z=THICKNESS)
    below = RigidTool("below", PLANE, mesh.select(z=0.0), facing=(0, 0, -1), contact="gauss")
    flipped = NagataSurface(PLANE.vertices, [[0, 0, -1]] * 4, [[0, 3, 2, 1]])
    above = RigidTool("above", flipped, top, facing=(0, 0, 1), contact="gauss")
    guess = np.zeros_like(mesh.nodes)
    guess[:, 2] = -0.02
    where = {"below": np.zeros(3), "above": np.array([0.0, 0.0, THICKNESS - 0.05])}
    start, moved = clear_of_barriers(guess, mesh.nodes, [below, above],
                                     contact_faces([below, above], mesh), where, THICKNESS,
                                     bottom, reach=1.0)
    middle = START + 0.5 * (END - START)
    assert moved == 2 * top.size
    np.testing.assert_allclose(start[:, 2] - guess[:, 2], (0.02 - middle) - (0.03 - middle),
                               atol=1e-12)


def test_only_patches_facing_the_blank_count() -> None:
    """A tool 0.05 mm thick (a plate: its top faces the blank, its bottom faces away) with
    the blank sunk 0.04 mm into it: the nearest patch is the bottom one, 0.01 mm away, but
    it faces away from the blank, so the blank comes back up to the middle of the top's
    ramp (without the facing filter it went down, out through the bottom)."""
    mesh, bottom = blank()
    corners = [[-5, -5], [5, -5], [5, 5], [-5, 5]]
    plate = NagataSurface([[x, y, 0.0] for x, y in corners] + [[x, y, -0.05] for x, y in corners],
                          [[0, 0, 1]] * 4 + [[0, 0, -1]] * 4, [[0, 1, 2, 3], [4, 7, 6, 5]])
    tool = RigidTool("plate", plate, mesh.select(z=0.0), facing=(0, 0, -1), contact="gauss")
    guess = np.zeros_like(mesh.nodes)
    guess[:, 2] = -0.04
    start, moved = clear_of_barriers(guess, mesh.nodes, [tool], contact_faces([tool], mesh),
                                     {"plate": np.zeros(3)}, THICKNESS, bottom, reach=1.0)
    assert moved == tool.slaves.size
    np.testing.assert_allclose(start[:, 2], -START - 0.5 * (END - START), atol=1e-12)
