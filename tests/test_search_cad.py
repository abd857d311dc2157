"""Contact search on tool models built from CAD: the plane-fillet-cylinder die of
ddpy.cad.examples, meshed by ddpy.cad, against its exact (analytic) profile."""

from __future__ import annotations

import numpy as np
import pytest

from ddpy.cad import build_tool_models, gmsh_session
from ddpy.cad.examples import die_profile
from ddpy.geometry.search import INSIDE, ContactSearch
from ddpy.io.toolfile import read_tool

LAND, FILLET, RADIUS, WIDTH = 20.0, 4.0, 23.5, 30.0
RNG = np.random.default_rng(3)


def exact_profile(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance (positive on the blank side, above) and outward normal of the die."""
    x, z = points[:, 0], points[:, 2]
    candidates = []
    # Land: z = 0, -LAND <= x <= 0, normal +z.
    px = np.clip(x, -LAND, 0.0)
    candidates.append((np.column_stack([px, np.zeros_like(x)]), np.tile([0.0, 1.0], (len(x), 1))))
    # Arcs: (centre, radius, start angle, end angle, outward sign): convex fillet, concave wall.
    for cx, cz, r, a0, a1, sign in ((0.0, -FILLET, FILLET, 0.0, 90.0, 1.0),
                                    (FILLET + RADIUS, -FILLET, RADIUS, 180.0, 270.0, -1.0)):
        angle = np.degrees(np.arctan2(z - cz, x - cx)) % 360.0
        angle = np.clip(angle, a0, a1)
        direction = np.column_stack([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
        candidates.append((np.column_stack([cx, cz]) + r * direction, sign * direction))
    xz = np.column_stack([x, z])
    distances = np.array([np.linalg.norm(xz - p, axis=1) for p, _ in candidates])
    best = distances.argmin(axis=0)
    foot = np.array([c[0] for c in candidates])[best, np.arange(len(x))]
    normal = np.array([c[1] for c in candidates])[best, np.arange(len(x))]
    side = np.sign(np.einsum("ij,ij->i", xz - foot, normal))
    normal3 = np.column_stack([normal[:, 0], np.zeros(len(x)), normal[:, 1]])
    return side * distances.min(axis=0), normal3


@pytest.fixture(scope="module")
def die_models(tmp_path_factory) -> dict[str, object]:
    folder = tmp_path_factory.mktemp("die")
    with gmsh_session():
        die_profile(folder / "die.step", LAND, FILLET, RADIUS, WIDTH)
    paths = build_tool_models(folder / "die.step", folder, "die", patches_per_arc=4,
                              facets_per_arc=30, blank_side=(0.0, 0.0, 1.0))
    return {kind: read_tool(path) for kind, path in paths.items()}


def shape_error(surface, samples: int = 21) -> tuple[float, float]:
    """Max distance and normal-angle (degrees) error of a model, sampled on every patch."""
    s, t = np.meshgrid(np.linspace(0, 1, samples), np.linspace(0, 1, samples), indexing="ij")
    uv = np.column_stack([s.ravel(), t.ravel()])
    ids = np.repeat(np.arange(surface.n_patches), len(uv))
    params = np.tile(uv, (surface.n_patches, 1))
    if hasattr(surface, "is_triangle"):
        tri = surface.is_triangle[ids]
        params[tri] = np.sort(params[tri], axis=1)[:, ::-1]
    points, _, normals = surface.evaluate(ids, params)
    distance, exact_normal = exact_profile(points)
    cosine = np.clip(np.einsum("ij,ij->i", normals, exact_normal), -1.0, 1.0)
    return float(np.abs(distance).max()), float(np.degrees(np.arccos(cosine)).max())


def points_above_die(k: int) -> np.ndarray:
    """Points within 2 mm of the die, away from its ends along y."""
    x = np.column_stack([RNG.uniform(-LAND + 1, FILLET + RADIUS - 1, 20 * k),
                         RNG.uniform(2.0, WIDTH - 2.0, 20 * k),
                         RNG.uniform(-FILLET - RADIUS, 2.0, 20 * k)])
    distance, _ = exact_profile(x)
    return x[np.abs(distance) < 2.0][:k]


@pytest.mark.parametrize("kind", ["bezier", "nagata", "facets"])
def test_projection_on_cad_tool_within_shape_error(die_models, kind: str) -> None:
    model = die_models[kind]
    error, angle = shape_error(model.surface)
    x = points_above_die(3000)
    found = ContactSearch(model.surface).project(x)
    exact, _ = exact_profile(x)
    assert np.abs(found.distance - exact).max() <= 1.05 * error + 1e-9
    inside = found.status == INSIDE
    assert inside.mean() > (0.99 if kind != "facets" else 0.9)
    # The model's normal at each projection agrees with the exact normal there within the
    # model's normal error.
    _, normal_there = exact_profile(found.point)
    cosine = np.clip(np.einsum("ij,ij->i", found.normal, normal_there), -1.0, 1.0)
    assert np.degrees(np.arccos(cosine))[inside].max() <= 1.05 * angle + 1e-6
    # The paper's shape errors: fine facets about 9 um and 1.5 degrees, Nagata below 0.1 deg.
    if kind == "nagata":
        assert error < 5e-3 and angle < 0.1
    if kind == "facets":
        assert 5e-3 < error < 1e-2 and 1.3 < angle < 1.6
    brute = ContactSearch(model.surface).project(x, brute_force=True)
    fast_d = np.linalg.norm(x - found.point, axis=1)
    assert (fast_d <= np.linalg.norm(x - brute.point, axis=1) + 1e-9).all()


def test_orientation_filter_finds_the_fillet_where_it_meets_the_wall(die_models) -> None:
    # Blank nodes facing down onto the die, their normals within a few tenths of a degree of
    # -z. Where the fillet meets the vertical wall its normal is horizontal, so for nodes
    # beside the wall the fillet's nearest point faces away from some of them while the rest
    # of the fillet faces them: it must stay a candidate (a Bezier punch lost its nose this
    # way and closed the blank's rim on a flat 42 mm away).
    x = points_above_die(3000)
    x[:, 0] = RNG.uniform(FILLET - 1.0, FILLET + 6.0, len(x))
    normals = RNG.normal(size=x.shape) * 1e-3
    normals[:, 2] = -1.0
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    search = ContactSearch(die_models["bezier"].surface)
    fast = search.project(x, node_normals=normals)
    brute = search.project(x, node_normals=normals, brute_force=True)
    np.testing.assert_array_equal(fast.status == 0, brute.status == 0)
    fast_d = np.linalg.norm(x - fast.point, axis=1)
    assert (fast_d <= np.linalg.norm(x - brute.point, axis=1) + 1e-9).all()
