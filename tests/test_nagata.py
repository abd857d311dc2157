"""Nagata patches and facets (docs/theory/surfaces.md), checked through their defining
properties."""

from __future__ import annotations

import numpy as np
import pytest

from ddpy.geometry.surfaces import NAGATA_DEGENERATE_RATIO, NagataSurface, nagata_edge_coefficient

RADIUS = 10.0
TRIANGLE_CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
QUAD_CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
# Edges of a face: (index of start corner, index of end corner, parameters along the edge).
TRIANGLE_EDGES = [
    (0, 1, lambda s: np.stack([s, 0 * s], 1)),  # zeta = 0: x00 -> x10
    (1, 2, lambda s: np.stack([1 + 0 * s, s], 1)),  # eta = 1: x10 -> x11
    (0, 2, lambda s: np.stack([s, s], 1)),  # diagonal eta = zeta: x00 -> x11
]
QUAD_EDGES = [
    (0, 1, lambda s: np.stack([s, 0 * s], 1)),  # eta = 0: x00 -> x10
    (1, 2, lambda s: np.stack([1 + 0 * s, s], 1)),  # xi = 1: x10 -> x11
    (3, 2, lambda s: np.stack([s, 1 + 0 * s], 1)),  # eta = 1: x01 -> x11
    (0, 3, lambda s: np.stack([0 * s, s], 1)),  # xi = 0: x00 -> x01
]


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def reference_coefficient(x0, x1, n0, n1, ratio=NAGATA_DEGENERATE_RATIO):
    """The paper's Nagata edge coefficient, written out for one edge, with the degenerate rule of
    docs/theory/surfaces.md (straight when |c| > ratio |d| tan(phi / 2))."""
    d = x1 - x0
    a = n0 @ n1
    if 1.0 - a * a <= 0.0 or a <= -0.5:  # parallel, or a fold of 120 degrees or more
        return np.zeros(3)
    c = ((n0 @ d + a * (n1 @ d)) * n0 - (a * (n0 @ d) + n1 @ d) * n1) / (1.0 - a * a)
    phi = np.arccos(np.clip(a, -1.0, 1.0))
    if np.linalg.norm(c) > ratio * np.linalg.norm(d) * np.tan(phi / 2):
        return np.zeros(3)
    return c


def random_cells(rng, n_cells: int, perturb: bool):
    """Independent triangles and quadrilaterals near a sphere of radius 10, counter-clockwise.

    Returns vertices, vertex normals and faces (triangles first, then quads). With ``perturb``
    the vertices leave the sphere and the normals are tilted off the radial direction.
    """
    vertices, normals, faces = [], [], []
    for cell in range(n_cells):
        corners = TRIANGLE_CORNERS if cell < n_cells // 2 else QUAD_CORNERS
        centre = unit(rng.normal(size=3))
        e1 = unit(np.cross(centre, rng.normal(size=3)))
        e2 = np.cross(centre, e1)  # e1 x e2 = centre: counter-clockwise seen from outside
        size = rng.uniform(2.0, 4.0)
        local = (corners - 0.5 + rng.uniform(-0.15, 0.15, corners.shape)) * size
        points = RADIUS * unit(RADIUS * centre + local[:, :1] * e1 + local[:, 1:] * e2)
        cell_normals = points / RADIUS
        if perturb:
            points = points + rng.normal(scale=0.005 * size, size=points.shape)
            cell_normals = unit(cell_normals + rng.normal(scale=0.01, size=points.shape))
        index = list(range(len(vertices), len(vertices) + len(corners)))
        faces.append(index + [-1] * (4 - len(corners)))
        vertices.extend(points)
        normals.extend(cell_normals)
    return np.array(vertices), np.array(normals), np.array(faces)


@pytest.fixture(scope="module", params=[False, True], ids=["sphere", "perturbed"])
def cells(request):
    rng = np.random.default_rng(1234 if request.param else 4321)
    vertices, normals, faces = random_cells(rng, 40, request.param)
    return NagataSurface(vertices, normals, faces), vertices, normals, faces


def face_corners(face):
    return (TRIANGLE_CORNERS, TRIANGLE_EDGES) if face[3] == -1 else (QUAD_CORNERS, QUAD_EDGES)


def corner_queries(faces):
    """(patch ids, parameters, vertex indices) of every corner of every face."""
    ids, params, index = [], [], []
    for f, face in enumerate(faces):
        corners, _ = face_corners(face)
        ids += [f] * len(corners)
        params.append(corners)
        index += list(face[: len(corners)])
    return np.array(ids), np.concatenate(params), np.array(index)


def edge_queries(faces, s):
    """(patch ids, parameters, start and end vertex) of every face edge sampled at s.

    One row per edge and sample, in edge order: rows reshape to (edges, len(s)).
    """
    ids, params, start, end = [], [], [], []
    for f, face in enumerate(faces):
        _, edges = face_corners(face)
        for a, b, along in edges:
            ids += [f] * s.size
            params.append(along(s))
            start.append(face[a])
            end.append(face[b])
    return np.array(ids), np.concatenate(params), np.array(start), np.array(end)


def test_triangle_and_quad_flags(cells):
    surface, _, _, faces = cells
    assert surface.n_patches == len(faces)
    np.testing.assert_array_equal(surface.is_triangle, faces[:, 3] == -1)
    assert surface.is_triangle.sum() == 20


def test_patches_interpolate_vertices_and_normals(cells):
    surface, vertices, normals, faces = cells
    ids, params, index = corner_queries(faces)
    points, derivs, patch_normals = surface.evaluate(ids, params)
    np.testing.assert_allclose(points, vertices[index], rtol=0, atol=1e-12 * RADIUS)
    np.testing.assert_allclose(patch_normals, normals[index], rtol=0, atol=1e-10)
    # the tangents at a corner lie in that corner's tangent plane
    np.testing.assert_allclose(np.einsum("kax,kx->ka", derivs, normals[index]), 0.0,
                               atol=1e-12 * RADIUS)


def test_edges_are_nagata_curves(cells):
    surface, vertices, normals, faces = cells
    s = np.linspace(0.0, 1.0, 11)
    ids, params, i, j = edge_queries(faces, s)
    c = nagata_edge_coefficient(vertices[i], vertices[j], normals[i], normals[j])
    assert np.all(np.linalg.norm(c, axis=1) > 0.0)  # every edge here is curved
    d = vertices[j] - vertices[i]
    expected = (vertices[i, None] + s[None, :, None] * (d - c)[:, None]
                + s[None, :, None] ** 2 * c[:, None])
    points, _, _ = surface.evaluate(ids, params)
    np.testing.assert_allclose(points.reshape(expected.shape), expected, rtol=0,
                               atol=1e-12 * RADIUS)


# --- the edge coefficient -------------------------------------------------------------------


def random_edges(rng, m: int):
    """m random edges whose end normals are at least about 8 degrees from (anti)parallel."""
    x0 = rng.normal(size=(m, 3))
    x1 = x0 + rng.normal(size=(m, 3))
    n0 = unit(rng.normal(size=(m, 3)))
    n1 = unit(n0 + rng.normal(scale=0.5, size=(m, 3)))
    keep = 1.0 - np.abs(np.einsum("kx,kx->k", n0, n1)) > 1e-2  # c is ill-conditioned near 0
    return x0[keep], x1[keep], n0[keep], n1[keep]


def test_edge_coefficient_matches_closed_formula():
    # Random edges are not from a surface: switch the degenerate rule off (ratio 1e300).
    x0, x1, n0, n1 = random_edges(np.random.default_rng(1), 200)
    c = nagata_edge_coefficient(x0, x1, n0, n1, degenerate_ratio=1e300)
    assert c.shape == (len(x0), 3) and len(x0) > 150
    expected = np.array([reference_coefficient(*edge, ratio=np.inf)
                         for edge in zip(x0, x1, n0, n1, strict=True)])
    assert np.all(np.linalg.norm(expected, axis=1) > 0.0)
    scale = np.linalg.norm(expected, axis=1, keepdims=True) + np.linalg.norm(x1 - x0, axis=1,
                                                                             keepdims=True)
    assert np.all(np.abs(c - expected) < 1e-12 * scale)
    # single edges give (3,) vectors
    single = nagata_edge_coefficient(x0[0], x1[0], n0[0], n1[0], degenerate_ratio=1e300)
    assert single.shape == (3,)
    np.testing.assert_allclose(single, c[0], rtol=1e-14, atol=0)


def test_edge_coefficient_is_symmetric_under_reversal():
    x0, x1, n0, n1 = random_edges(np.random.default_rng(2), 200)
    forward = nagata_edge_coefficient(x0, x1, n0, n1, degenerate_ratio=1e300)
    backward = nagata_edge_coefficient(x1, x0, n1, n0, degenerate_ratio=1e300)
    scale = np.abs(forward).max(axis=1, keepdims=True)
    assert np.all(np.abs(backward - forward) <= 1e-12 * scale)


def test_edge_tangents_lie_in_end_tangent_planes():
    x0, x1, n0, n1 = random_edges(np.random.default_rng(3), 200)
    c = nagata_edge_coefficient(x0, x1, n0, n1, degenerate_ratio=1e300)
    d = x1 - x0
    scale = np.linalg.norm(c, axis=1) + np.linalg.norm(d, axis=1)
    assert np.all(np.abs(np.einsum("kx,kx->k", n0, d - c)) < 1e-12 * scale)
    assert np.all(np.abs(np.einsum("kx,kx->k", n1, d + c)) < 1e-12 * scale)


def rotated(n0: np.ndarray, axis: np.ndarray, one_minus_cos: float) -> np.ndarray:
    """n0 turned about ``axis`` (orthogonal to n0) by the angle with 1 - cos = one_minus_cos."""
    angle = np.arccos(1.0 - one_minus_cos)
    return np.cos(angle) * n0 + np.sin(angle) * np.cross(axis, n0)


@pytest.mark.parametrize("sign", [1.0, -1.0], ids=["parallel", "antiparallel"])
def test_edge_coefficient_degenerate_rule(sign):
    x0, x1 = np.zeros(3), np.array([1.0, 0.3, 0.2])  # n . d != 0: the formula would blow up
    n0 = np.array([0.0, 0.0, 1.0])
    axis = np.array([0.0, 1.0, 0.0])
    assert np.all(nagata_edge_coefficient(x0, x1, n0, sign * n0) == 0.0)
    # Nearly parallel normals on an edge not perpendicular to them: straight.
    for angle in (1e-9, 1e-5, 1e-3, 0.01):
        n1 = sign * rotated(n0, axis, angle)
        assert np.all(nagata_edge_coefficient(x0, x1, n0, n1) == 0.0), angle
    # The same normals on a big enough angle: the formula, whose |c| is far above |d|.
    n1 = rotated(n0, axis, 0.5)
    c = nagata_edge_coefficient(x0, x1, n0, n1)
    np.testing.assert_allclose(c, reference_coefficient(x0, x1, n0, n1), rtol=1e-12)
    assert np.linalg.norm(c) > 0.1


@pytest.mark.parametrize("angle_deg", [0.01, 0.1, 0.5, 5.0, 30.0, 90.0])
def test_circular_edge_keeps_its_curvature_at_any_angle(angle_deg):
    # A circular arc of any opening: c = |d| tan(phi / 2), perpendicular to d. Nearly
    # parallel normals on a smooth edge are not degenerate (a torus top, a large die radius).
    phi = np.radians(angle_deg)
    x0, x1 = np.array([1.0, 0, 0]), np.array([np.cos(phi), np.sin(phi), 0])
    c = nagata_edge_coefficient(x0, x1, x0, x1)
    d = np.linalg.norm(x1 - x0)
    assert np.linalg.norm(c) == pytest.approx(d * np.tan(phi / 2), rel=1e-6)
    assert abs(c @ (x1 - x0)) < 1e-12


def test_edge_coefficient_custom_ratio():
    # An edge tilted out of the normals' symmetric position (z = -tan 0.1 would be the arc):
    # its coefficient is a few times that of the arc with the same normal angle.
    x0, x1 = np.zeros(3), np.array([1.0, 0.0, -0.06])
    n0 = np.array([0.0, 0.0, 1.0])
    n1 = np.array([np.sin(0.2), 0.0, np.cos(0.2)])
    c = reference_coefficient(x0, x1, n0, n1, ratio=np.inf)
    ratio = np.linalg.norm(c) / (np.linalg.norm(x1 - x0) * np.tan(0.1))
    assert 1.5 < ratio < 8.0
    np.testing.assert_allclose(nagata_edge_coefficient(x0, x1, n0, n1), c, rtol=1e-12)
    assert np.all(nagata_edge_coefficient(x0, x1, n0, n1, degenerate_ratio=1.0) == 0.0)


def test_edge_coefficient_of_straight_and_circular_edges():
    # normals parallel and orthogonal to the chord: a straight line
    c = nagata_edge_coefficient([0, 0, 0], [2.0, 0, 0], [0, 0, 1.0], [0, 0, 1.0])
    np.testing.assert_array_equal(c, 0.0)
    # an arc of the unit circle with radial normals: c lies in the circle's plane, symmetric
    # about the bisector, and the curve's midpoint is much closer to the circle than the chord's
    theta = 0.4
    x0, x1 = np.array([1.0, 0, 0]), np.array([np.cos(theta), np.sin(theta), 0])
    c = nagata_edge_coefficient(x0, x1, x0, x1)
    assert c[2] == 0.0
    np.testing.assert_allclose(c @ (x1 - x0), 0.0, atol=1e-15)
    mid = x0 + 0.5 * (x1 - x0 - c) + 0.25 * c
    chord_error = 1.0 - np.cos(theta / 2)
    assert abs(np.linalg.norm(mid) - 1.0) < chord_error / 50


# --- meshes of several faces -----------------------------------------------------------------


def sphere_grid(rng, smooth: bool = True, perturb: bool = False):
    """A 4 x 4 grid on a sphere cap: quads, and triangle pairs in the cells of one diagonal."""
    t = np.linspace(-2.0, 2.0, 5)
    x, y = np.meshgrid(t, t, indexing="ij")  # x[i, j]: vertex i * 5 + j
    points = RADIUS * unit(np.stack([x, y, RADIUS + 0 * x], -1).reshape(-1, 3))
    normals = points / RADIUS
    if perturb:
        points = points + rng.normal(scale=0.01, size=points.shape)
        normals = unit(normals + rng.normal(scale=0.01, size=points.shape))
    faces = []
    for i in range(4):
        for j in range(4):
            v00, v10, v11, v01 = 5 * i + j, 5 * (i + 1) + j, 5 * (i + 1) + j + 1, 5 * i + j + 1
            # Triangles are listed with their highest vertex index last: the library rejects
            # other rotations (see test_triangle_vertex_rotation_is_accepted).
            if i == j:
                faces += [[v00, v10, v11, -1], [v01, v00, v11, -1]]
            elif i + j == 3:
                faces += [[v01, v10, v11, -1], [v01, v00, v10, -1]]  # the other diagonal
            else:
                faces.append([v00, v10, v11, v01])
    return NagataSurface(points, normals, np.array(faces), smooth=smooth), points, normals


@pytest.mark.parametrize("rotation", [0, 1, 2])
def test_triangle_vertex_rotation_is_accepted(rotation):
    # A cyclic rotation of a triangle's vertex list is the same counter-clockwise triangle.
    normals = unit(np.array([[0.0, 0, RADIUS], [2, 0, RADIUS], [2, 2, RADIUS]]))
    vertices = RADIUS * normals
    face = np.roll([0, 1, 2], rotation)
    surface = NagataSurface(vertices, normals, [[*face, -1]])
    points, _, patch_normals = surface.evaluate([0, 0, 0], TRIANGLE_CORNERS)
    np.testing.assert_allclose(points, vertices[face], atol=1e-14)
    np.testing.assert_allclose(patch_normals, normals[face], atol=1e-12)


def edge_samples(surface: NagataSurface, s: np.ndarray):
    """{(i, j): [points along i -> j (i < j) from every face holding that edge]}."""
    ids, params, start, end = edge_queries(surface.faces, s)
    points = surface.evaluate(ids, params)[0].reshape(-1, s.size, 3)
    samples: dict[tuple[int, int], list[np.ndarray]] = {}
    for i, j, along in zip(start, end, points, strict=True):
        key = (int(i), int(j)) if i < j else (int(j), int(i))
        samples.setdefault(key, []).append(along if i < j else along[::-1])
    return samples


@pytest.mark.parametrize("perturb", [False, True], ids=["sphere", "perturbed"])
def test_shared_edges_are_watertight(perturb):
    surface, _, _ = sphere_grid(np.random.default_rng(5), perturb=perturb)
    shared = 0
    for points in edge_samples(surface, np.linspace(0.0, 1.0, 17)).values():
        for other in points[1:]:
            np.testing.assert_allclose(other, points[0], rtol=0, atol=1e-12 * RADIUS)
            shared += 1
    assert shared == 24 + 8  # interior grid edges plus the diagonals inside split cells


@pytest.mark.parametrize("smooth", [True, False], ids=["nagata", "facet"])
@pytest.mark.parametrize("perturb", [False, True], ids=["sphere", "perturbed"])
def test_derivatives_match_finite_differences(perturb, smooth):
    rng = np.random.default_rng(6)
    surface, _, _ = sphere_grid(rng, smooth=smooth, perturb=perturb)
    ids = np.repeat(np.arange(surface.n_patches), 10)
    uv = rng.uniform(0.0, 1.0, size=(ids.size, 2))
    uv[surface.is_triangle[ids], 1] *= uv[surface.is_triangle[ids], 0]  # zeta <= eta
    h = 1e-6
    _, derivs, _ = surface.evaluate(ids, uv)
    second = surface.second_derivatives(ids, uv)
    fd_points, fd_derivs = [], []
    for a in range(2):
        step = np.zeros(2)
        step[a] = h
        plus, d_plus, _ = surface.evaluate(ids, uv + step)
        minus, d_minus, _ = surface.evaluate(ids, uv - step)
        fd_points.append((plus - minus) / (2 * h))
        fd_derivs.append((d_plus - d_minus) / (2 * h))
    scale = RADIUS
    for a in range(2):
        np.testing.assert_allclose(derivs[:, a], fd_points[a], rtol=0, atol=1e-7 * scale)
    np.testing.assert_allclose(second[:, 0], fd_derivs[0][:, 0], rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(second[:, 1], fd_derivs[0][:, 1], rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(second[:, 1], fd_derivs[1][:, 0], rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(second[:, 2], fd_derivs[1][:, 1], rtol=0, atol=1e-6 * scale)
    if smooth:  # the patches really are curved, so the checks above are not vacuous
        assert np.abs(second[:, [0, 2]]).max() > 1e-2


def test_normals_are_unit_cross_product():
    rng = np.random.default_rng(7)
    surface, _, _ = sphere_grid(rng, perturb=True)
    ids = np.repeat(np.arange(surface.n_patches), 10)
    uv = rng.uniform(0.0, 1.0, size=(ids.size, 2))
    _, derivs, normals = surface.evaluate(ids, uv)
    np.testing.assert_allclose(normals, unit(np.cross(derivs[:, 0], derivs[:, 1])), atol=1e-14)


# --- facets -----------------------------------------------------------------------------------


def test_quad_facet_is_bilinear_interpolation():
    rng = np.random.default_rng(8)
    x = np.array([[0.0, 0, 0], [1, 0, 0.3], [1.2, 1.1, -0.2], [-0.1, 0.9, 0.1]])
    x += rng.uniform(-0.05, 0.05, size=x.shape)
    surface = NagataSurface(x, unit(rng.normal(0, 0.1, (4, 3)) + [0, 0, 1]), [[0, 1, 2, 3]],
                            smooth=False)
    uv = rng.uniform(-0.2, 1.2, size=(100, 2))
    xi, eta = uv[:, :1], uv[:, 1:]
    expected = ((1 - xi) * (1 - eta) * x[0] + xi * (1 - eta) * x[1] + xi * eta * x[2]
                + (1 - xi) * eta * x[3])
    ids = np.zeros(100, dtype=int)
    points, derivs, _ = surface.evaluate(ids, uv)
    np.testing.assert_allclose(points, expected, rtol=0, atol=1e-14)
    np.testing.assert_allclose(derivs[:, 0], (1 - eta) * (x[1] - x[0]) + eta * (x[2] - x[3]),
                               rtol=0, atol=1e-14)
    np.testing.assert_allclose(derivs[:, 1], (1 - xi) * (x[3] - x[0]) + xi * (x[2] - x[1]),
                               rtol=0, atol=1e-14)
    second = surface.second_derivatives(ids, uv)
    np.testing.assert_array_equal(second[:, 0], 0.0)
    np.testing.assert_array_equal(second[:, 2], 0.0)
    np.testing.assert_allclose(second[:, 1], np.broadcast_to(x[2] - x[1] - x[3] + x[0],
                                                             (100, 3)), rtol=0, atol=1e-15)


def test_triangle_facet_is_flat():
    rng = np.random.default_rng(9)
    x = np.array([[0.2, -0.1, 1.0], [2.0, 0.3, 0.5], [1.5, 1.7, 1.4]])
    plane = unit(np.cross(x[1] - x[0], x[2] - x[0]))
    normals = unit(plane + rng.normal(scale=0.2, size=(3, 3)))  # curved normals are ignored
    surface = NagataSurface(x, normals, [[0, 1, 2, -1]], smooth=False)
    uv = rng.uniform(0.0, 1.0, size=(100, 2))
    uv[:, 1] *= uv[:, 0]
    ids = np.zeros(100, dtype=int)
    points, _, patch_normals = surface.evaluate(ids, uv)
    np.testing.assert_allclose((points - x[0]) @ plane, 0.0, atol=1e-14)
    np.testing.assert_allclose(patch_normals, np.broadcast_to(plane, (100, 3)), atol=1e-14)
    np.testing.assert_array_equal(surface.second_derivatives(ids, uv), 0.0)
    # linear: the centroid maps to the centroid of the vertices (eta, zeta) = (2/3, 1/3)
    centroid, _, _ = surface.evaluate([0], [[2 / 3, 1 / 3]])
    np.testing.assert_allclose(centroid[0], x.mean(axis=0), atol=1e-14)


# --- creases ----------------------------------------------------------------------------------


def test_crease_with_face_corner_normals():
    # A floor (normal about +z) and a wall (normal about -y) meet at a 90 degree crease along
    # y = 1, z = 0. Each is a piece of a cylinder of radius 3 along x, tangent to the crease
    # planes at the crease, with exact normals: the crease vertices 2, 3 carry two normals.
    sag = 3.0 - np.sqrt(8.0)
    vertices = np.array([[0.0, 0, sag], [1, 0, sag], [1, 1, 0], [0, 1, 0],
                         [1, 1 - sag, 1], [0, 1 - sag, 1]])
    faces = np.array([[0, 1, 2, 3], [3, 2, 4, 5]])
    up, inward = np.array([0.0, 0, 1]), np.array([0.0, -1, 0])
    normals = np.empty((2, 4, 3))
    normals[0, 2:] = up
    normals[0, :2] = unit(np.array([0.0, 1, 3]) - vertices[0] * [0, 1, 1])  # towards the axis
    normals[1, :2] = inward
    normals[1, 2:] = unit(np.array([0.0, -2, 0]) - vertices[4] * [0, 1, 1])
    surface = NagataSurface(vertices, normals, faces)

    for f in range(2):
        points, _, patch_normals = surface.evaluate(np.full(4, f), QUAD_CORNERS)
        np.testing.assert_allclose(points, vertices[faces[f]], atol=1e-14)
        np.testing.assert_allclose(patch_normals, normals[f], atol=1e-12)
    # the shared edge 3 -> 2 is straight and common: floor eta = 1, wall eta = 0
    s = np.linspace(0.0, 1.0, 11)
    floor, _, floor_normals = surface.evaluate(np.zeros(11, dtype=int),
                                               np.stack([s, np.ones(11)], 1))
    wall, _, wall_normals = surface.evaluate(np.ones(11, dtype=int),
                                             np.stack([s, np.zeros(11)], 1))
    straight = vertices[3] + np.outer(s, vertices[2] - vertices[3])
    np.testing.assert_allclose(floor, straight, atol=1e-14)
    np.testing.assert_allclose(wall, straight, atol=1e-14)
    np.testing.assert_allclose(floor_normals, np.broadcast_to(up, (11, 3)), atol=1e-12)
    np.testing.assert_allclose(wall_normals, np.broadcast_to(inward, (11, 3)), atol=1e-12)
    # the faces are curved (close to their cylinders) away from the crease
    mid, _, _ = surface.evaluate([0, 1], [[0.0, 0.5], [0.0, 0.5]])  # on the edges xi = 0
    chords = (vertices[[0, 3]].mean(axis=0), vertices[[3, 5]].mean(axis=0))
    assert np.linalg.norm(mid[0] - chords[0]) > 1e-2
    assert np.linalg.norm(mid[1] - chords[1]) > 1e-2
    axes = (np.array([1.0, 3]), np.array([-2.0, 0]))  # (y, z) of the two cylinder axes
    for point, axis in zip(mid, axes, strict=True):
        assert abs(np.linalg.norm(point[1:] - axis) - 3.0) < 1e-3


def test_crease_triangle_ignores_fourth_corner_normal():
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0]])
    normals = np.zeros((1, 4, 3))
    normals[0, :3] = [0, 0, 1]
    normals[0, 3] = [7.0, 7.0, 7.0]  # not even a unit vector: the fourth row of a triangle
    surface = NagataSurface(vertices, normals, [[0, 1, 2, -1]])
    points, _, patch_normals = surface.evaluate([0, 0], [[0.5, 0.2], [0.9, 0.8]])
    np.testing.assert_allclose(points[:, 2], 0.0, atol=1e-15)
    np.testing.assert_allclose(patch_normals, [[0, 0, 1], [0, 0, 1]], atol=1e-15)


# --- accuracy sanity check --------------------------------------------------------------------


def cylinder_strip(parts: int, smooth: bool) -> NagataSurface:
    """A quarter of the cylinder y^2 + z^2 = 1, 0 <= x <= 1, with exact normals."""
    theta = np.linspace(0.0, np.pi / 2, parts + 1)
    ring = np.stack([0 * theta, np.cos(theta), np.sin(theta)], 1)
    vertices = np.concatenate([ring, ring + [1.0, 0, 0]])
    normals = np.concatenate([ring, ring]) * [0, 1, 1]
    k = parts + 1
    faces = [[i, i + 1, k + i + 1, k + i] for i in range(parts)]  # xi along theta, eta along x
    return NagataSurface(vertices, normals, np.array(faces), smooth=smooth)


def test_cylinder_nagata_beats_facets():
    rng = np.random.default_rng(10)
    errors = {}
    for smooth in (True, False):
        surface = cylinder_strip(4, smooth)
        ids = np.repeat(np.arange(4), 200)
        uv = rng.uniform(0.0, 1.0, size=(ids.size, 2))
        points, _, normals = surface.evaluate(ids, uv)
        radius = np.hypot(points[:, 1], points[:, 2])
        exact_normal = np.stack([0 * radius, points[:, 1] / radius, points[:, 2] / radius], 1)
        angle = np.arccos(np.clip(np.einsum("kx,kx->k", normals, exact_normal), -1, 1))
        errors[smooth] = np.abs(radius - 1.0).max(), angle.max()
    (nagata_radius, nagata_angle), (facet_radius, facet_angle) = errors[True], errors[False]
    assert facet_radius > 1e-2  # 1 - cos(11.25 degrees) = 0.019
    assert nagata_radius < facet_radius / 20
    assert nagata_angle < facet_angle / 10
