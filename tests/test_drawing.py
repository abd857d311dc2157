"""ddpy.studies.drawing against analytic cases: volumes of boxes and distorted hexahedra, a cylinder
cup's height and flange, radial sections, force balance and penetration."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ddpy.studies.drawing import (
    contact_force_balance,
    cup_height,
    element_centroids,
    hexahedron_volumes,
    penetration,
    plane_section,
    rim_nodes,
    rim_radius,
    volume_change,
)

#: The unit cube's corners in Gmsh / C3D8 order.
CUBE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                 [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float)


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation matrix."""
    k = axis / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


def test_box_volume() -> None:
    box = CUBE * [2.0, 3.0, 0.5] + [10.0, -4.0, 7.0]
    assert hexahedron_volumes(box, [range(8)])[0] == pytest.approx(3.0, rel=1e-14)


def test_sheared_and_rotated_box_keeps_its_volume() -> None:
    # A linear map x -> R S x with a shear S (det 1) and a rotation R keeps the volume.
    shear = np.array([[1.0, 0.7, -0.3], [0.0, 1.0, 0.4], [0.0, 0.0, 1.0]])
    rotation = _rotation(np.array([1.0, 2.0, -0.5]), 0.83)
    box = CUBE * [2.0, 3.0, 0.5]
    moved = box @ (rotation @ shear).T + [1.0, 2.0, 3.0]
    assert hexahedron_volumes(moved, [range(8)])[0] == pytest.approx(3.0, rel=1e-13)
    assert volume_change(box, moved, [range(8)]) == pytest.approx(0.0, abs=1e-13)


def test_trilinear_hexahedron_volume_is_exact() -> None:
    # Moving one corner of a box a by d along x makes the map x = a X + d X Y Z, y = b Y,
    # z = c Z on the unit cube: det J = (a + d Y Z) b c, integral a b c + d b c / 4.
    a, b, c, d = 2.0, 3.0, 0.5, 0.8
    hexa = CUBE * [a, b, c]
    hexa[6, 0] += d
    assert hexahedron_volumes(hexa, [range(8)])[0] == pytest.approx(a * b * c + d * b * c / 4,
                                                                    rel=1e-14)
    # A warped top face (corner 6 up by d): z = c Z + d X Y Z, det J = a b (c + d X Y).
    warped = CUBE * [a, b, c]
    warped[6, 2] += d
    assert hexahedron_volumes(warped, [range(8)])[0] == pytest.approx(a * b * (c + d / 4),
                                                                      rel=1e-14)


def test_volumes_of_a_mesh_and_an_inverted_element() -> None:
    nodes = np.vstack([CUBE, CUBE[4:] + [0, 0, 1]])
    elements = np.array([range(8), [4, 5, 6, 7, 8, 9, 10, 11]])
    assert hexahedron_volumes(nodes, elements).tolist() == pytest.approx([1.0, 1.0])
    inverted = CUBE[[4, 5, 6, 7, 0, 1, 2, 3]]
    assert hexahedron_volumes(inverted, [range(8)])[0] == pytest.approx(-1.0)
    doubled = nodes * [1.0, 1.0, 2.0]
    assert volume_change(nodes, doubled, elements) == pytest.approx(1.0)
    with pytest.raises(ValueError):
        hexahedron_volumes(nodes, [range(4)])


def _cup(depth: float, radius: float, flange: float, thickness: float,
         n: int = 24) -> np.ndarray:
    """Points of a flanged cylinder cup (axis z): a bottom disc at z = -depth, a wall of
    ``radius`` up to z = 0, a flange out to ``flange``, both surfaces ``thickness`` apart."""
    angles = np.linspace(0.0, math.pi / 2, n)
    ring = np.column_stack([np.cos(angles), np.sin(angles)])
    points = []
    for side in (0.0, thickness):
        for r in np.linspace(0.0, radius, 6):
            points += [[*(r * xy), -depth - thickness + side] for xy in ring]
        for z in np.linspace(-depth, 0.0, 8):
            points += [[*((radius + side) * xy), z] for xy in ring]
        for r in np.linspace(radius + thickness, flange, 5):
            points += [[*(r * xy), side] for xy in ring]
    return np.array(points)


def test_cup_height_and_flange_radius() -> None:
    depth, radius, flange, thickness = 40.0, 50.0, 62.5, 0.98
    cup = _cup(depth, radius, flange, thickness)
    assert cup_height(cup) == pytest.approx(depth + 2 * thickness)
    # The flange's edge: the points at the largest radius.
    flat = np.column_stack([np.hypot(cup[:, 0], cup[:, 1]), np.zeros(len(cup)),
                            np.zeros(len(cup))])
    edge = rim_nodes(flat, flange)
    assert edge.size == 2 * 24
    mean, low, high = rim_radius(cup, edge)
    assert (mean, low, high) == pytest.approx((flange, flange, flange))
    # Ears: an oval edge has its smallest and largest radii.
    oval = cup[edge] * [1.1, 0.9, 1.0]
    assert rim_radius(oval, np.arange(len(oval)))[1:] == pytest.approx((0.9 * flange,
                                                                        1.1 * flange))
    assert cup_height(cup[:, [2, 0, 1]], axis=0) == pytest.approx(depth + 2 * thickness)


def test_plane_section_orders_by_radius() -> None:
    points = np.array([[3.0, 0.0, 0.0], [1.0, 0.2, 5.0], [2.0, 0.0, 1.0], [1.5, 0.9, 0.0]])
    radius, values = plane_section(points, [30.0, 10.0, 20.0, 15.0], band=0.5)
    assert radius == pytest.approx([math.hypot(1.0, 0.2), 2.0, 3.0])
    assert values.tolist() == [10.0, 20.0, 30.0]
    centroids = element_centroids(CUBE, [range(8)])
    assert centroids[0] == pytest.approx([0.5, 0.5, 0.5])


def test_contact_force_balance() -> None:
    force = np.array([[0.0, 0.0, -2.0], [1.0, 0.0, -3.0], [0.0, 0.0, 4.0], [0, 0, 0]])
    tool = np.array([1, 1, 0, -1])
    balance = contact_force_balance([-1.0, 0.0, 5.0], force, tool, 1)
    assert balance.nodes == 2
    assert balance.nodal_sum == pytest.approx([1.0, 0.0, -5.0])
    assert balance.mismatch == pytest.approx(0.0)
    off = contact_force_balance([-1.0, 0.0, 4.0], force, tool, 1)
    assert off.mismatch == pytest.approx(1.0)
    assert off.relative == pytest.approx(1.0 / math.hypot(1.0, 4.0))
    assert contact_force_balance([0, 0, 0], force, tool, 3).relative == 0.0


def test_penetration_into_a_plane_tool() -> None:
    from ddpy.geometry.search import ContactSearch
    from ddpy.geometry.surfaces import NagataSurface

    # A flat square tool at z = 0 facing +z, moved up by 0.25.
    plane = NagataSurface([[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0]], [[0, 0, 1]] * 4,
                          [[0, 1, 2, 3]])
    search = ContactSearch(plane)
    points = np.array([[1.0, 1.0, 0.5], [2.0, 2.0, 0.1], [3.0, 1.0, 0.2], [9.0, 9.0, -5.0]])
    found = penetration(points, search, (0.0, 0.0, 0.25))
    assert found.depth == pytest.approx(0.15)
    assert found.node == 1 and found.inside == 2
    # Beyond the tool's edge, a point below its plane is not inside it.
    assert penetration(points, search, nodes=[3]).depth == 0.0
    assert penetration(points, search, nodes=[0]).node == -1


def test_siebel_force_by_hand() -> None:
    """Siebel's terms one by one, against the arithmetic written out: a 100 mm mean
    diameter cup from a 170 mm disc, 1 mm, flow stresses 300 / 400 MPa, mu 0.1 over a
    quarter turn, one 8 mm radius, 10 kN on the holder."""
    from ddpy.studies.drawing import siebel_force

    ideal = 1.1 * 300.0 * math.log(1.7)
    holder = 2 * 0.1 * 10e3 / (math.pi * 170.0 * 1.0)
    bend = 400.0 * 1.0 / 16.0
    expected = math.pi * 100.0 * (math.exp(0.1 * math.pi / 2) * (ideal + holder) + bend)
    got = siebel_force(170.0, 100.0, 1.0, 300.0, 400.0, 0.1, (8.0,), math.pi / 2, 10e3)
    assert got == pytest.approx(expected, rel=1e-12)
    # without friction, bending and holder: the ideal drawing force alone
    assert siebel_force(170.0, 100.0, 1.0, 300.0, 400.0, 0.0, (), 0.0) == pytest.approx(
        math.pi * 100.0 * ideal, rel=1e-12)
    with pytest.raises(ValueError, match="reduce"):
        siebel_force(90.0, 100.0, 1.0, 300.0, 400.0, 0.1, (8.0,), 1.0)


def test_siebel_force_of_a_reverse_redraw_by_hand() -> None:
    """A reverse redraw's wall turns half a turn over a 7 mm nose before the drawing zone,
    without tension: the nose brings in its bending and unbending, 400 / 28 MPa each,
    the first under the friction of the half turn; the drawing zone's stress is added
    and then carried a quarter turn over a 5 mm die edge."""
    from ddpy.studies.drawing import siebel_force

    mu, half_bend = 0.15, 400.0 * 1.0 / 28.0
    incoming = half_bend * math.exp(mu * math.pi) + half_bend
    ideal = 1.1 * 300.0 * math.log(100.0 / 74.0)
    expected = math.pi * 74.0 * (math.exp(mu * math.pi / 2) * (incoming + ideal)
                                 + 400.0 / 10.0)
    got = siebel_force(100.0, 74.0, 1.0, 300.0, 400.0, mu, (5.0,), math.pi / 2,
                       entry=((7.0, math.pi),))
    assert got == pytest.approx(expected, rel=1e-12)
    # Entered without friction, the nose adds its full bending, k_b s / (2 r), and no more.
    frictionless = siebel_force(100.0, 74.0, 1.0, 300.0, 400.0, 0.0, (), 0.0,
                                entry=((7.0, math.pi),))
    assert frictionless == pytest.approx(math.pi * 74.0 * (ideal + 2 * half_bend), rel=1e-12)
    with pytest.raises(ValueError, match="entry"):
        siebel_force(100.0, 74.0, 1.0, 300.0, 400.0, mu, (5.0,), 1.0, entry=((7.0, -1.0),))


def test_tensile_limit_is_the_largest_engineering_stress_of_the_swift_curve() -> None:
    """Considere's strain n - eps0 gives the top of K (eps0 + e)^n exp(-e), found here by
    a dense search instead (the paper's DDQ steel)."""
    from ddpy.studies.drawing import swift_stress, tensile_limit

    k, eps0, n = 568.3, 0.0059, 0.233
    e = np.linspace(0.0, 1.0, 200_001)
    engineering = k * (eps0 + e) ** n * np.exp(-e)
    assert tensile_limit(k, eps0, n) == pytest.approx(engineering.max(), rel=1e-9)
    # A wall in plane strain, its major stress c times the equivalent one: the load per
    # initial section c K (eps0 + e)^n exp(-e / c).
    c = 1.32
    plane = c * k * (eps0 + e) ** n * np.exp(-e / c)
    assert tensile_limit(k, eps0, n, ratio=c) == pytest.approx(plane.max(), rel=1e-9)
    with pytest.raises(ValueError, match="ratio"):
        tensile_limit(k, eps0, n, ratio=0.0)
    assert swift_stress(0.0, k, eps0, n) == pytest.approx(k * eps0**n)
