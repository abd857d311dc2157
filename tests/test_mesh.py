"""The one check of hexahedral elements (ddpy.model.mesh.find_bad_elements) through the
HexMesh constructor: every bad element found at once, each named by its label and fault."""

from __future__ import annotations

import numpy as np
import pytest

import ddpy.model.mesh
from ddpy.model.mesh import (
    MAX_ELEMENTS,
    MIN_SCALED_JACOBIAN,
    HexMesh,
    MeshError,
    corner_scaled_jacobians,
    find_bad_elements,
)

#: A unit cube's nodes as HexMesh.box numbers them (x fastest), and its element.
CUBE_NODES = np.array([[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)])
CUBE = np.array([[0, 1, 3, 2, 4, 5, 7, 6]])
#: Top and bottom faces swapped, and both faces listed clockwise: two ways to invert.
UPSIDE_DOWN = [4, 5, 6, 7, 0, 1, 2, 3]
CLOCKWISE = [0, 3, 2, 1, 4, 7, 6, 5]


def mesh_error(nodes: np.ndarray, elements: np.ndarray, **labels: object) -> MeshError:
    with pytest.raises(MeshError) as info:
        HexMesh(nodes, elements, **labels)
    return info.value


def test_every_bad_element_is_reported_with_its_label() -> None:
    row = HexMesh.box(6.0, 1.0, 1.0, 6, 1, 1)
    elements = row.elements.copy()
    nodes = row.nodes.copy()
    elements[1] = elements[1][UPSIDE_DOWN]
    elements[2, 7] = elements[2, 6]
    elements[4] = elements[4][CLOCKWISE]
    nodes[nodes[:, 0] == 6.0, 0] = 5.0  # the last element squashed flat
    labels = [101, 102, 103, 104, 105, 106]
    error = mesh_error(nodes, elements, element_ids=labels, node_ids=np.arange(len(nodes)) + 1)
    assert [(b.index, b.label, b.fault) for b in error.bad_elements] == [
        (1, 102, "inverted"), (2, 103, "repeated node"), (4, 105, "inverted"),
        (5, 106, "degenerate")]
    assert error.element == 1
    message = str(error)
    assert message.startswith("4 bad elements, the first 3: element 102 is inverted at its "
                              "corner"), message
    assert "; element 103 repeats a node: [3, 4, 11, 10, 17, 18, 25, 25]; element 105 is " \
           "inverted at its corner" in message
    assert "element 106" not in message  # named in bad_elements only
    assert error.bad_elements[3].message.startswith("element 106 is degenerate at its corner")


def test_two_bad_elements_are_both_named() -> None:
    row = HexMesh.box(3.0, 1.0, 1.0, 3, 1, 1)
    elements = row.elements.copy()
    elements[0] = elements[0][CLOCKWISE]
    elements[2] = elements[2][UPSIDE_DOWN]
    message = str(mesh_error(row.nodes, elements))
    assert message.startswith("2 bad elements: element 0 is inverted")
    assert "; element 2 is inverted" in message


def test_inverted_element() -> None:
    error = mesh_error(CUBE_NODES, CUBE[:, CLOCKWISE], element_ids=[7])
    (bad,) = error.bad_elements
    assert (bad.index, bad.label, bad.fault) == (0, 7, "inverted")
    assert str(error) == bad.message == (
        "element 7 is inverted at its corner 0, node 0 (scaled Jacobian -1, det J -0.125), "
        "nodes [0, 2, 3, 1, 4, 6, 7, 5]: expected the first four counter-clockwise seen from "
        "the last four above them")


def test_corner_inverted_where_the_gauss_points_are_not() -> None:
    # det J is positive at the 8 Gauss points (0.178 and more), negative at corner 1.
    nodes = [[0.0, -0.2, -0.5], [0.5, -0.2, 0.3], [1.4, 1.5, -0.4], [-0.4, 1.4, -0.4],
             [-0.3, 0.4, 1.3], [1.2, -0.2, 1.0], [1.4, 1.0, 1.5], [-0.2, 1.3, 1.1]]
    error = mesh_error(nodes, [range(8)])
    assert error.bad_elements[0].fault == "inverted"
    assert str(error).startswith("element 0 is inverted at its corner 1, node 1 (scaled "
                                 "Jacobian -0.187")


def test_gauss_point_inverted_where_the_corners_are_not() -> None:
    # A twisted element: every corner's scaled Jacobian is above 0.18, but det J is
    # negative at Gauss point 0, where the solver integrates.
    nodes = [[0.6, 0.7, 0.7], [0.4, 0.5, -0.6], [0.5, 1.4, -0.5], [0.6, 0.3, 0.4],
             [0.4, -0.4, 1.5], [1.4, 0.0, 0.5], [1.6, 0.9, 0.7], [-0.2, 1.4, 1.6]]
    assert corner_scaled_jacobians(nodes, [range(8)]).min() > 0.18
    error = mesh_error(nodes, [range(8)])
    assert error.bad_elements[0].fault == "inverted"
    assert str(error).startswith("element 0 is inverted at its Gauss point 0, next to corner 0 "
                                 "(det J -0.00524)")


def test_repeated_node() -> None:
    elements = CUBE.copy()
    elements[0, 5] = elements[0, 4]
    error = mesh_error(CUBE_NODES, elements, node_ids=np.arange(8) + 1, element_ids=[3])
    (bad,) = error.bad_elements  # reported once, not also as degenerate
    assert (bad.index, bad.label, bad.fault) == (0, 3, "repeated node")
    assert str(error) == "element 3 repeats a node: [1, 2, 4, 3, 5, 5, 8, 7]"


def test_nearly_flat_corner_is_degenerate() -> None:
    # Corner 0 pulled to the middle of the bottom face: its two bottom edges almost in line.
    # det J is positive everywhere (0.047 at the Gauss points, 2.5e-8 at that corner); the
    # corner's shape is what is wrong, whatever the element's size.
    for scale in (1e-3, 1.0, 1e3):
        nodes = CUBE_NODES.copy()
        nodes[0] = [0.5 - 1e-7, 0.5 - 1e-7, 0.0]
        error = mesh_error(scale * nodes, CUBE)
        assert error.bad_elements[0].fault == "degenerate"
        assert str(error).startswith("element 0 is degenerate at its corner 0, node 0 (scaled "
                                     "Jacobian 3.27e-07")
        assert str(error).endswith("the element is flat or collapsed there")
        nodes[0] = [0.5 - 1e-6, 0.5 - 1e-6, 0.0]  # scaled Jacobian 3.3e-6: accepted
        HexMesh(scale * nodes, CUBE)


def test_element_flattened_to_rounding_is_degenerate() -> None:
    # Its corners are right angles (scaled Jacobian 1); det J is 1e-12 of its size cubed.
    flat = CUBE_NODES * [1.0, 1.0, 1e-12]
    error = mesh_error(flat, CUBE)
    assert str(error).startswith("element 0 is degenerate at its corner 0, node 0 (scaled "
                                 "Jacobian 1, det J 1.25e-13)")


def test_node_indices_out_of_range_are_reported_with_the_rest() -> None:
    row = HexMesh.box(3.0, 1.0, 1.0, 3, 1, 1)
    elements = row.elements.copy()
    elements[0, 0] = 16
    elements[2] = elements[2][UPSIDE_DOWN]
    error = mesh_error(row.nodes, elements)
    assert [(b.index, b.fault) for b in error.bad_elements] == [(0, "node out of range"),
                                                                (2, "inverted")]
    assert "element 0 has node indices [16, 1, 5, 4, 8, 9, 13, 12] outside 0..15" in str(error)


def test_distorted_but_valid_elements_are_accepted() -> None:
    box = HexMesh.box(4.0, 1.0, 1.0, 4, 1, 1)
    nodes = box.nodes.copy()
    top = nodes[:, 2] == 1.0
    nodes[top, 0] += 1.5                         # sheared 56 degrees
    nodes[top & (nodes[:, 1] == 1.0), 1] = 0.3   # tapered: top face narrower at y = 1
    nodes[(nodes[:, 0] == 2.0) & ~top, 0] = 2.7  # bottom of the middle face moved along x
    mesh = HexMesh(nodes, box.elements)
    scaled = corner_scaled_jacobians(mesh.nodes, mesh.elements)
    assert 0.5 < scaled.min() < 0.6 and mesh.volume() == pytest.approx(4.0 * 0.65)
    thin = HexMesh.box(1.0, 1.0, 1e-4, 2, 2, 1)  # aspect ratio 5,000
    assert thin.volume() == pytest.approx(1e-4)
    rng = np.random.default_rng(5)
    box = HexMesh.box(4.0, 3.0, 1.0, 8, 6, 2)
    shaken = box.nodes + 0.3 * 0.5 * rng.uniform(-1, 1, box.nodes.shape)  # 30 % of a size
    assert find_bad_elements(shaken, box.elements) == []
    HexMesh(shaken, box.elements)
    # Some corners are far from square (scaled Jacobian 0.05), yet all are valid.
    assert MIN_SCALED_JACOBIAN < corner_scaled_jacobians(shaken, box.elements).min() < 0.1


def test_a_large_valid_mesh_is_checked_as_a_whole() -> None:
    box = HexMesh.box(20.0, 20.0, 1.0, 40, 40, 4)
    rng = np.random.default_rng(2)
    nodes = box.nodes + 0.1 * np.array([0.5, 0.5, 0.25]) * rng.uniform(-1, 1, box.nodes.shape)
    elements = box.elements.copy()
    flipped = rng.choice(len(elements), 50, replace=False)
    elements[flipped] = elements[flipped][:, UPSIDE_DOWN]
    error = mesh_error(nodes, elements, element_ids=np.arange(len(elements)) + 1)
    assert sorted(b.index for b in error.bad_elements) == sorted(flipped.tolist())
    assert [b.label for b in error.bad_elements] == sorted(flipped + 1)
    assert str(error).startswith("50 bad elements, the first 3: ")


def test_a_box_beyond_the_element_limit_is_refused_before_it_is_built() -> None:
    """HexMesh.box checks its element count against MAX_ELEMENTS, the mesh deck's limit
    (tests/test_decks.py), before it allocates: these 10^10 elements would take 75 GiB and
    end in numpy's MemoryError."""
    with pytest.raises(MeshError, match=rf"the box has 10000000000 elements \(10000 x 10000 x "
                                        rf"100\): at most {MAX_ELEMENTS}$"):
        HexMesh.box(1, 1, 1, 10**4, 10**4, 10**2)


def test_the_constructor_checks_the_element_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    """HexMesh itself holds at most MAX_ELEMENTS (lowered here to keep the test small)."""
    row = HexMesh.box(3.0, 1.0, 1.0, 3, 1, 1)
    monkeypatch.setattr(ddpy.model.mesh, "MAX_ELEMENTS", 2)
    with pytest.raises(MeshError, match="a mesh of 16 nodes and 3 elements: at most .* and 2 "
                                        "elements"):
        HexMesh(row.nodes, row.elements)
    with pytest.raises(MeshError, match="the box has 3 elements"):
        HexMesh.box(3.0, 1.0, 1.0, 3, 1, 1)
    assert HexMesh(row.nodes, row.elements[:2]).n_elements == 2
