"""Global and local contact search against exact answers and against brute force."""

from __future__ import annotations

import numpy as np
import pytest

from ddpy.core.parallel import threads
from ddpy.geometry.search import EDGE, INSIDE, NONE, ContactSearch
from ddpy.geometry.shapes import Cylinder, Sphere, Torus
from ddpy.geometry.surfaces import BezierSurface, NagataSurface

RNG = np.random.default_rng(20261122)


def model_error(surface, shape, samples: int = 41) -> float:
    """Largest distance from the model to the exact surface, sampled on every patch."""
    s, t = np.meshgrid(np.linspace(0, 1, samples), np.linspace(0, 1, samples), indexing="ij")
    uv = np.column_stack([s.ravel(), t.ravel()])
    ids = np.repeat(np.arange(surface.n_patches), len(uv))
    params = np.tile(uv, (surface.n_patches, 1))
    if isinstance(surface, NagataSurface):  # triangles: fold (s, t) into t <= s
        tri = surface.is_triangle[ids]
        params[tri] = np.sort(params[tri], axis=1)[:, ::-1]
    points, _, _ = surface.evaluate(ids, params)
    return float(np.abs(shape.signed_distance(points)).max())


def bezier_cylinder(radius: float, height: float, parts: int) -> BezierSurface:
    """A cylinder as degree (5, 1) Bezier patches fitted by least squares to the circle."""
    from math import comb

    n = 5
    s = np.linspace(0, 1, 60)
    basis = np.array([[comb(n, i) * x**i * (1 - x) ** (n - i) for i in range(n + 1)] for x in s])
    nets = []
    for k in range(parts):
        angle = 2 * np.pi * (k + s) / parts
        curve = radius * np.column_stack([np.cos(angle), np.sin(angle)])
        # Interpolate the ends exactly (watertight), fit the inner control points.
        ends = np.outer(basis[:, 0], curve[0]) + np.outer(basis[:, -1], curve[-1])
        inner, *_ = np.linalg.lstsq(basis[:, 1:-1], curve - ends, rcond=None)
        ring = np.vstack([curve[0], inner, curve[-1]])
        net = np.zeros((n + 1, 2, 3))
        net[:, 0, :2], net[:, 1, :2], net[:, 1, 2] = ring, ring, height
        nets.append(net)
    return BezierSurface(nets)


def models():
    """(name, surface, exact shape, region sampler) for every description."""
    sphere, cylinder, torus = Sphere(10.0), Cylinder(10.0, 20.0), Torus(10.0, 3.0)
    out = []
    for shape, n, box in ((sphere, 4, 14.0), (cylinder, 4, 14.0), (torus, 3, 15.0)):
        for kind in ("quad", "tri"):
            v, nrm, f = shape.mesh(n, kind=kind)
            for smooth in (True, False):
                name = f"{type(shape).__name__}-{kind}-{'nagata' if smooth else 'facets'}"
                out.append((name, NagataSurface(v, nrm, f, smooth=smooth), shape, box))
    out.append(("Cylinder-bezier", bezier_cylinder(10.0, 20.0, 6), cylinder, 14.0))
    return out


MODELS = models()


def near_points(shape, box: float, k: int) -> np.ndarray:
    """Points within 2 mm of the exact surface (and inside the cylinder's height)."""
    x = RNG.uniform(-box, box, size=(20 * k, 3))
    if isinstance(shape, Cylinder):
        x[:, 2] = RNG.uniform(2.0, 18.0, size=len(x))
    x = x[np.abs(shape.signed_distance(x)) < 2.0]
    return x[:k]


@pytest.mark.parametrize("name, surface, shape, box", MODELS, ids=[m[0] for m in MODELS])
def test_projection_matches_exact_within_shape_error(name, surface, shape, box) -> None:
    error = model_error(surface, shape)
    x = near_points(shape, box, 2000)
    found = ContactSearch(surface).project(x)
    assert (found.status != NONE).all()
    exact = shape.signed_distance(x)
    # The distance to the model differs from the exact one by at most the shape error.
    assert np.abs(found.distance - exact).max() <= 1.05 * error + 1e-9
    # The closest point is an orthogonal projection: x - p is along the normal.
    inside = found.status == INSIDE
    # Smooth models cover every direction; facets of a convex shape leave wedges above
    # their edges where the closest point is on an edge (11 to 20 % here).
    assert inside.mean() > (0.99 if "facets" not in name else 0.7)
    residual = x - found.point
    along = found.distance[:, None] * found.normal
    assert np.abs(residual - along)[inside].max() < 1e-8
    assert found.mean_iterations < 6.0


@pytest.mark.parametrize("name, surface, shape, box", MODELS, ids=[m[0] for m in MODELS])
def test_candidates_never_miss_the_brute_force_answer(name, surface, shape, box) -> None:
    # 10^5 random points over all models together, near and far from the surface.
    x = RNG.uniform(-box, box, size=(100_000 // len(MODELS), 3))
    search = ContactSearch(surface)
    fast = search.project(x)
    slow = search.project(x, brute_force=True)
    d_fast = np.linalg.norm(x - fast.point, axis=1)
    d_slow = np.linalg.norm(x - slow.point, axis=1)
    misses = d_fast > d_slow + 1e-9 * (1.0 + d_slow)
    assert not misses.any(), f"{misses.sum()} misses, worst {np.max(d_fast - d_slow)}"


BEZIER_MODELS = [m for m in MODELS if isinstance(m[1], BezierSurface)]


@pytest.mark.parametrize("name, surface, shape, box", BEZIER_MODELS,
                         ids=[m[0] for m in BEZIER_MODELS])
def test_orientation_filter_never_misses_the_brute_force_answer(name, surface, shape,
                                                                box) -> None:
    # With node normals, a patch counts only where it faces the node. Normals near the
    # horizontal make a cylinder's patches face some nodes only part of the way round:
    # the nearest facing point of a patch, not its nearest point, decides. (Bezier tools
    # rank patches over all of the tool; mesh tools only around the nearest vertices.)
    x = RNG.uniform(-box, box, size=(4000, 3))
    normals = RNG.normal(size=x.shape)
    normals[::2, 2] *= 1e-3  # every other one within a few tenths of a degree of horizontal
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    search = ContactSearch(surface)
    fast = search.project(x, node_normals=normals)
    slow = search.project(x, node_normals=normals, brute_force=True)
    assert ((fast.status == NONE) == (slow.status == NONE)).all()
    hit = slow.status != NONE
    d_fast = np.linalg.norm(x - fast.point, axis=1)[hit]
    d_slow = np.linalg.norm(x - slow.point, axis=1)[hit]
    misses = d_fast > d_slow + 1e-9 * (1.0 + d_slow)
    assert not misses.any(), f"{misses.sum()} misses, worst {np.max(d_fast - d_slow)}"


def unit_square_mesh(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plane z = 0 over [0, m]^2 as m x m unit quads."""
    i, j = np.meshgrid(np.arange(m + 1), np.arange(m + 1), indexing="ij")
    vertices = np.column_stack([i.ravel(), j.ravel(), np.zeros(i.size)]).astype(float)
    ids = np.arange((m + 1) ** 2).reshape(m + 1, m + 1)
    faces = np.column_stack([ids[:-1, :-1].ravel(), ids[1:, :-1].ravel(),
                             ids[1:, 1:].ravel(), ids[:-1, 1:].ravel()])
    return vertices, np.tile([0.0, 0.0, 1.0], (len(vertices), 1)), faces


def test_plane_edges_and_corners_are_inside() -> None:
    v, n, f = unit_square_mesh(4)
    search = ContactSearch(NagataSurface(v, n, f))
    # Above a shared edge, a vertex shared by four patches, and interior points.
    x = np.array([[2.0, 1.5, 0.3], [2.0, 2.0, -0.2], [1.25, 3.75, 1.0], [0.0, 0.0, 0.5]])
    found = search.project(x)
    assert (found.status == INSIDE).all()
    np.testing.assert_allclose(found.distance, x[:, 2], atol=1e-13)
    np.testing.assert_allclose(found.point, np.column_stack([x[:, :2], np.zeros(4)]),
                               atol=1e-13)
    # Beyond the boundary of the whole tool: held on its edge, distance to the edge.
    far = search.project([[5.0, 2.0, 1.0]])
    assert far.status[0] == EDGE
    np.testing.assert_allclose(far.point[0], [4.0, 2.0, 0.0], atol=1e-12)


def test_a_node_in_the_sliver_between_two_patches_that_miss_each_other_lies_on_the_seam() -> None:
    # Two flat patches (z = 0) whose edges miss each other by 4e-4 mm, as Bezier patches
    # fitted to two CAD faces one by one may (the fit's tolerance is 1e-3 mm): a node in
    # the sliver gets its normal distance, continuous with the patches on both sides, not
    # the sliver's half width signed by a normal distance near zero.
    width = 4.0e-4

    def flat(x0: float, x1: float) -> np.ndarray:
        return np.array([[[x0, 0.0, 0.0], [x0, 50.0, 0.0]], [[x1, 0.0, 0.0], [x1, 50.0, 0.0]]])

    search = ContactSearch(BezierSurface([flat(0.0, 50.0), flat(50.0 + width, 100.0)]))
    across = np.linspace(50.0 - 2 * width, 50.0 + 3 * width, 41)
    for z in (0.0, 1.0e-5, -3.0e-5, 2.0e-3):
        found = search.project(np.column_stack([across, np.full(41, 25.0), np.full(41, z)]))
        np.testing.assert_allclose(found.distance, z, atol=1e-12)
        sliver = (across > 50.0 + 1e-6) & (across < 50.0 + width - 1e-6)
        beside = (across < 50.0 - 1e-6) | (across > 50.0 + width + 1e-6)
        assert (found.status[sliver] == EDGE).all() and (found.status[beside] == INSIDE).all()
    # Beyond the tool's own edge the distance stays the Euclidean one.
    off = search.project([[100.5, 25.0, 0.3], [-0.2, 25.0, -0.1]])
    assert off.status.tolist() == [EDGE, EDGE]
    np.testing.assert_allclose(off.distance, [np.hypot(0.5, 0.3), -np.hypot(0.2, 0.1)],
                               atol=1e-12)


def test_convex_crease_between_two_faces() -> None:
    # Two planes meeting at a convex 90 degree crease along the y axis (x = 0, z = 0):
    # the top z = 0 for x <= 0 and the side x = 0 for z <= 0, with per-face normals.
    vertices = np.array([[-2, 0, 0], [0, 0, 0], [0, 2, 0], [-2, 2, 0],
                         [0, 0, -2], [0, 2, -2]], dtype=float)
    faces = np.array([[0, 1, 2, 3], [1, 4, 5, 2]])
    normals = np.zeros((2, 4, 3))
    normals[0] = [0, 0, 1]
    normals[1] = [1, 0, 0]
    search = ContactSearch(NagataSurface(vertices, normals, faces))
    x = np.array([[0.5, 1.0, 0.5],     # outside the convex edge: the crease is closest
                  [-1.0, 1.0, 0.3],    # above the top face
                  [0.4, 1.5, -1.0]])   # beside the side face
    found = search.project(x)
    np.testing.assert_allclose(found.point[0], [0.0, 1.0, 0.0], atol=1e-12)
    assert found.status[0] == EDGE
    # Off the patches the distance is the Euclidean one, signed by the normal's side.
    assert found.distance[0] == pytest.approx(np.sqrt(0.5), abs=1e-12)
    np.testing.assert_allclose(found.point[1:], [[-1.0, 1.0, 0.0], [0.0, 1.5, -1.0]],
                               atol=1e-12)
    assert (found.status[1:] == INSIDE).all()
    np.testing.assert_allclose(found.distance[1:], [0.3, 0.4], atol=1e-12)


def test_a_point_held_on_a_facet_sees_its_plane_past_the_edge() -> None:
    # A roof of two facets meeting at a convex ridge along y (x = 0, z = 0), 10 degrees
    # apart. A point 1 mm past the ridge over the right facet, slightly inside the tool:
    # the search gives the right facet; held on the left one it gets the left facet's plane
    # continued past the ridge (the distance along its normal, status inside), which is what
    # the Newton loop holds a node hopping between the two facets of an edge to.
    drop = 5.0 * np.tan(np.radians(5.0))
    vertices = np.array([[-5, 0, -drop], [0, 0, 0], [0, 2, 0], [-5, 2, -drop],
                         [5, 0, -drop], [5, 2, -drop]], dtype=float)
    faces = np.array([[0, 1, 2, 3], [1, 4, 5, 2]])
    search = ContactSearch(NagataSurface(vertices, [[0, 0, 1.0]] * 6, faces, smooth=False))
    a = np.radians(5.0)
    left, right = np.array([-np.sin(a), 0.0, np.cos(a)]), np.array([np.sin(a), 0.0, np.cos(a)])
    x = np.array([[1.0, 1.0, -0.1], [1.0, 1.0, -0.1]])
    found = search.project(x, held=[-1, 0])
    assert found.patch.tolist() == [1, 0] and (found.status == INSIDE).all()
    np.testing.assert_allclose(found.normal, [right, left], atol=1e-12)
    # Both planes pass through the ridge line, which holds the origin.
    np.testing.assert_allclose(found.distance, [x[0] @ right, x[1] @ left], atol=1e-12)
    with pytest.raises(ValueError, match="held must be"):
        search.project(x, held=[0, 2])


def test_tool_displacement_moves_the_tool() -> None:
    v, n, f = Sphere(10.0).mesh(4)
    search = ContactSearch(NagataSurface(v, n, f))
    x = near_points(Sphere(10.0), 14.0, 200)
    u = np.array([0.3, -1.2, 2.5])
    moved = search.project(x + u, tool_displacement=u)
    still = search.project(x)
    np.testing.assert_allclose(moved.point, still.point + u, atol=1e-12)
    np.testing.assert_allclose(moved.distance, still.distance, atol=1e-12)
    np.testing.assert_array_equal(moved.patch, still.patch)


def test_orientation_filter() -> None:
    v, n, f = unit_square_mesh(2)
    search = ContactSearch(NagataSurface(v, n, f))
    x = [[1.0, 1.0, 0.5], [1.0, 1.0, 0.5]]
    found = search.project(x, node_normals=[[0, 0, -1.0], [0, 0, 1.0]])
    # A node whose own outward normal faces the tool sees it; one facing away does not.
    assert found.status.tolist() == [INSIDE, NONE]
    assert found.patch[1] == -1


def test_same_answer_on_one_and_two_threads() -> None:
    v, n, f = Torus(10.0, 3.0).mesh(3, kind="tri")
    search = ContactSearch(NagataSurface(v, n, f))
    x = RNG.uniform(-15, 15, size=(5000, 3))
    with threads(1):
        one = search.project(x)
    with threads(2):
        two = search.project(x)
    for a, b in zip(one.__dict__.values(), two.__dict__.values(), strict=True):
        np.testing.assert_array_equal(a, b)


def test_bad_input() -> None:
    v, n, f = unit_square_mesh(1)
    search = ContactSearch(NagataSurface(v, n, f))
    with pytest.raises(ValueError, match="points must have shape"):
        search.project([[1.0, 2.0]])
    with pytest.raises(ValueError, match="non-finite"):
        search.project([[np.nan, 0.0, 0.0]])
    with pytest.raises(ValueError, match="node_normals"):
        search.project([[0.0, 0.0, 1.0]], node_normals=[[0.0, 0.0]])
    with pytest.raises(TypeError, match="BezierSurface or NagataSurface"):
        ContactSearch("die.tool")
    with pytest.raises(ValueError, match="max_iterations"):
        ContactSearch(search.surface, max_iterations=0)
    assert search.project(np.zeros((0, 3))).patch.shape == (0,)


def test_orientation_filter_ignores_surfaces_side_on_to_the_node() -> None:
    # A flat sheet's node beside a vertical wall: the wall's normal is perpendicular to the
    # node's, so it cannot be a contact partner, whichever way the node's normal tilts by a
    # thousandth. With the bound at 90 degrees the tilt decided (a punch's bore then closed
    # a flange node 27 mm deep); the wall counts once the node's normal opposes it.
    search = ContactSearch(bezier_cylinder(10.0, 20.0, 6))
    radial = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6), 0.0])  # mid-patch
    up = np.array([0.0, 0.0, 1.0])
    x = np.tile(15.0 * radial + 10.0 * up, (4, 1))
    normals = np.array([up - 1e-3 * radial, up + 1e-3 * radial, -radial, 0.9 * up - radial])
    found = search.project(x, node_normals=normals)
    assert found.status.tolist() == [NONE, NONE, INSIDE, INSIDE]
    np.testing.assert_allclose(found.distance[2:], 5.0, atol=1e-3)
