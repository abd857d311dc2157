"""The global search never misses: on tool meshes of widely varying element size it returns
the patch that projecting on every patch returns (docs/theory/contact.md, "Closest points").

Meshes are drawn by hypothesis: analytic surfaces (a wavy graph, a sphere cap, a saddle, a
cylinder sector) meshed over their parameter square with cells of sizes up to 100 times
apart in each direction (long thin patches among them), the vertices jittered, each cell
kept as a quadrilateral, split into two triangles or refined into k x k small cells whose
extra vertices its neighbours do not share (a large patch next to many small ones, as
where a coarse and a fine mesh meet); Nagata patches with the analytic normals, facets, or
Bezier patches on the same cells. Query points lie above and below the centre of every
patch, near every vertex and anywhere around the tool.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ddpy.geometry.search import EDGE, INSIDE, NONE, ContactSearch
from ddpy.geometry.shapes import Sphere
from ddpy.geometry.surfaces import BezierSurface, NagataSurface
from ddpy.io.toolfile import read_tool

#: More examples, drawn afresh each run: DDPY_SEARCH_EXAMPLES=2000 pytest tests/test_search_exact.py
EXAMPLES_RUN = int(os.environ.get("DDPY_SEARCH_EXAMPLES", "0"))
DIE = Path(__file__).resolve().parents[1] / "examples" / "bending" / "tools" / "die.tool"

#: An analytic surface over the parameter square: (u, v) (k, 2) -> points, unit normals.
Shape = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def graph(f: Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]], side: float) -> Shape:
    """The graph z = f(x, y) over [0, side]^2, normals up."""

    def shape(uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x, y = side * uv[:, 0], side * uv[:, 1]
        z, fx, fy = f(x, y)
        n = np.column_stack([-fx, -fy, np.ones_like(x)])
        return np.column_stack([x, y, z]), n / np.linalg.norm(n, axis=1, keepdims=True)

    return shape


def wavy(x, y):
    return (3 * np.sin(x / 4) * np.cos(y / 5), 0.75 * np.cos(x / 4) * np.cos(y / 5),
            -0.6 * np.sin(x / 4) * np.sin(y / 5))


def cap(x, y, r=25.0):  # a sphere cap of radius 25 over [0, 20]^2, centred at (10, 10, -r)
    z = np.sqrt(r * r - (x - 10) ** 2 - (y - 10) ** 2)
    return z - r, -(x - 10) / z, -(y - 10) / z


def saddle(x, y):
    return ((x - 10) ** 2 - (y - 10) ** 2) / 30, (x - 10) / 15, -(y - 10) / 15


def cylinder(uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A 120 degree sector of a cylinder of radius 8, 20 long: outward normals."""
    theta = np.radians(-60 + 120 * uv[:, 0])
    n = np.column_stack([np.cos(theta), np.sin(theta), np.zeros(len(uv))])
    return 8 * n + np.outer(20 * uv[:, 1], [0, 0, 1]), n


SHAPES: dict[str, Shape] = {"wavy": graph(wavy, 20.0), "cap": graph(cap, 20.0),
                            "saddle": graph(saddle, 20.0), "cylinder": cylinder}


def breaks(rng: np.random.Generator, cells: int, spread: float) -> np.ndarray:
    """cells + 1 increasing values from 0 to 1, widths up to ``spread`` times apart."""
    widths = np.exp(rng.uniform(0.0, np.log(spread), cells))
    return np.concatenate([[0.0], np.cumsum(widths) / widths.sum()])


def parameter_mesh(rng: np.random.Generator, nu: int, nv: int, spread: float, jitter: float,
                   p_split: float, p_refine: float) -> tuple[np.ndarray, list[list[int]]]:
    """A mesh of the parameter square: (uv (k, 2), faces as lists of 3 or 4 vertex ids,
    counter-clockwise). Cells of a tensor grid whose widths vary up to ``spread`` times in
    each direction; inner vertices moved by up to ``jitter`` of their smaller neighbouring
    widths; a cell is split into two triangles with probability ``p_split``, or refined
    into k x k cells (k = 2..5) with its own vertices with probability ``p_refine``."""
    u, v = breaks(rng, nu, spread), breaks(rng, nv, spread)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    du = np.minimum(np.diff(u, prepend=u[0] - 1)[:, None], np.diff(u, append=u[-1] + 1)[:, None])
    dv = np.minimum(np.diff(v, prepend=v[0] - 1)[None, :], np.diff(v, append=v[-1] + 1)[None, :])
    inner = np.zeros(uu.shape, dtype=bool)
    inner[1:-1, 1:-1] = True
    uu = uu + inner * jitter * du * rng.uniform(-1, 1, uu.shape)
    vv = vv + inner * jitter * dv * rng.uniform(-1, 1, vv.shape)
    uv = [np.column_stack([uu.ravel(), vv.ravel()])]
    ids = np.arange(uu.size).reshape(uu.shape)
    count = uu.size
    faces: list[list[int]] = []
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = ids[i, j], ids[i + 1, j], ids[i + 1, j + 1], ids[i, j + 1]
            draw = rng.uniform()
            if draw < p_split:
                faces += ([[a, b, c], [a, c, d]] if rng.uniform() < 0.5 else
                          [[a, b, d], [b, c, d]])
            elif draw < p_split + p_refine:
                k = int(rng.integers(2, 6))
                s, t = np.meshgrid(np.linspace(0, 1, k + 1), np.linspace(0, 1, k + 1),
                                   indexing="ij")
                s, t = s.ravel()[:, None], t.ravel()[:, None]
                corners = uv[0][[a, b, c, d]]
                # Bilinear map of the cell: its k x k sub-cells have vertices of their own.
                uv.append((1 - s) * (1 - t) * corners[0] + s * (1 - t) * corners[1]
                          + s * t * corners[2] + (1 - s) * t * corners[3])
                sub = count + np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
                count += (k + 1) ** 2
                faces += [[sub[p, q], sub[p + 1, q], sub[p + 1, q + 1], sub[p, q + 1]]
                          for p in range(k) for q in range(k)]
            else:
                faces.append([a, b, c, d])
    return np.vstack(uv), faces


@st.composite
def tools(draw: st.DrawFn) -> tuple[str, NagataSurface | BezierSurface]:
    """A tool surface and a short description of it (shown when an example fails)."""
    name = draw(st.sampled_from(sorted(SHAPES)))
    kind = draw(st.sampled_from(["nagata", "facets", "bezier"]))
    nu, nv = draw(st.integers(1, 8)), draw(st.integers(1, 8))
    spread = draw(st.sampled_from([1.0, 10.0, 100.0]))
    jitter = draw(st.sampled_from([0.0, 0.3]))
    p_split = 0.0 if kind == "bezier" else draw(st.sampled_from([0.0, 0.5, 1.0]))
    p_refine = draw(st.sampled_from([0.0, 0.3]))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    uv, faces = parameter_mesh(rng, nu, nv, spread, jitter, p_split, p_refine)
    shape = SHAPES[name]
    label = (f"{name} {kind} {nu}x{nv} spread {spread} jitter {jitter} split {p_split} "
             f"refine {p_refine} seed {seed}")
    if kind == "bezier":
        return label, bezier_tool(rng, shape, uv, faces)
    x, n = shape(uv)
    table = np.array([f + [-1] * (4 - len(f)) for f in faces])
    return label, NagataSurface(x, n, table, smooth=kind == "nagata")


def bezier_tool(rng: np.random.Generator, shape: Shape, uv: np.ndarray,
                faces: list[list[int]]) -> BezierSurface:
    """A Bezier patch of degree (1..4, 1..4) on every quadrilateral cell: control points on
    the shape at the cell's bilinear parameter grid (neighbours of different degrees leave
    small gaps, which the search does not mind)."""
    nets = []
    for f in faces:
        n, m = (int(d) for d in rng.integers(1, 5, size=2))
        s, t = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, m + 1), indexing="ij")
        s, t = s.ravel()[:, None], t.ravel()[:, None]
        c = uv[f]
        cell = (1 - s) * (1 - t) * c[0] + s * (1 - t) * c[1] + s * t * c[2] + (1 - s) * t * c[3]
        nets.append(shape(cell)[0].reshape(n + 1, m + 1, 3))
    return BezierSurface(nets)


def patch_centres(surface: NagataSurface | BezierSurface) -> tuple[np.ndarray, np.ndarray]:
    """Point and unit normal at the parameter centre of every patch."""
    ids = np.arange(surface.n_patches)
    params = np.full((len(ids), 2), 0.5)
    if isinstance(surface, NagataSurface):
        params[surface.is_triangle] = [2 / 3, 1 / 3]
    points, _, normals = surface.evaluate(ids, params)
    return points, normals


def query_points(rng: np.random.Generator, surface: NagataSurface | BezierSurface,
                 search: ContactSearch) -> np.ndarray:
    """Above and below every patch's centre (by up to its size), near every corner of every
    patch, and anywhere in the tool's box grown by a third."""
    lower, upper = search.patch_boxes()
    size = np.linalg.norm(upper - lower, axis=1)
    centre, normal = patch_centres(surface)
    above = centre + normal * (size * rng.uniform(-0.5, 1.0, len(size)))[:, None]
    if isinstance(surface, NagataSurface):
        corners = surface.vertices
    else:
        corners = surface.evaluate(np.repeat(np.arange(surface.n_patches), 4),
                                   np.tile([[0, 0], [1, 0], [1, 1], [0, 1]],
                                           (surface.n_patches, 1)))[0]
    near = corners + rng.normal(scale=0.2 * size.min(), size=corners.shape)
    lo, hi = lower.min(axis=0), upper.max(axis=0)
    grow = (hi - lo).max() / 3
    anywhere = rng.uniform(lo - grow, hi + grow, size=(200, 3))
    return np.vstack([above, near, anywhere])


def assert_same_as_brute_force(search: ContactSearch, x: np.ndarray,
                               node_normals: np.ndarray | None = None,
                               reach: float | None = None) -> None:
    """The tree search returns brute force's patch, point and status for every point (both
    within ``reach``)."""
    fast = search.project(x, node_normals=node_normals, reach=reach)
    slow = search.project(x, node_normals=node_normals, brute_force=True, reach=reach)
    d_fast = np.linalg.norm(x - fast.point, axis=1)
    d_slow = np.linalg.norm(x - slow.point, axis=1)
    worst = int(np.argmax(d_fast - d_slow))
    assert np.all(d_fast <= d_slow * (1 + 1e-12) + 1e-12), (
        f"{int(np.sum(d_fast > d_slow + 1e-12))} misses, worst at {x[worst].tolist()}: "
        f"patch {fast.patch[worst]} at {d_fast[worst]}, nearest {slow.patch[worst]} at "
        f"{d_slow[worst]}")
    # Both rank the projections the same way, ties by the lower patch: the same answer.
    np.testing.assert_array_equal(fast.patch, slow.patch)
    np.testing.assert_array_equal(fast.status, slow.status)
    np.testing.assert_array_equal(fast.distance, slow.distance)
    # It projects on fewer patches than there are (all of them when the tool is small).
    assert fast.candidates.sum() <= slow.candidates.sum()


@settings(max_examples=EXAMPLES_RUN or 60, deadline=None, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow])
@given(tool=tools(), seed=st.integers(0, 2**32 - 1))
def test_tree_search_returns_the_brute_force_patch(tool, seed: int) -> None:
    _, surface = tool  # hypothesis shows the tool's description when an example fails
    rng = np.random.default_rng(seed)
    search = ContactSearch(surface)
    x = query_points(rng, surface, search)
    assert_same_as_brute_force(search, x)
    # With the orientation filter: random node normals, some of them zero (no filter).
    normals = rng.normal(size=x.shape) * (rng.uniform(size=(len(x), 1)) < 0.8)
    assert_same_as_brute_force(search, x, normals)
    # Within a reach that leaves about half of the points without a patch.
    for node_normals in (None, normals):
        unlimited = search.project(x, node_normals=node_normals, brute_force=True)
        measure = np.linalg.norm(x - unlimited.point, axis=1)
        reach = float(np.median(measure))
        assert_same_as_brute_force(search, x, node_normals, reach)
        assert_reach(search, x, node_normals, reach, unlimited)


def assert_reach(search: ContactSearch, x: np.ndarray, node_normals: np.ndarray | None,
                 reach: float, unlimited) -> None:
    """With ``reach``, a point whose closest point (``unlimited``: without reach) lies within
    it gets that point; one beyond it gets none (a point at the reach up to rounding, where
    either may happen, is left out)."""
    found = search.project(x, node_normals=node_normals, reach=reach)
    measure = np.linalg.norm(x - unlimited.point, axis=1)
    within = (unlimited.status != NONE) & (measure <= reach * (1 - 1e-9))
    beyond = (unlimited.status == NONE) | (measure > reach * (1 + 1e-9))
    np.testing.assert_array_equal(found.patch[within], unlimited.patch[within])
    np.testing.assert_array_equal(found.status[within], unlimited.status[within])
    np.testing.assert_array_equal(found.distance[within], unlimited.distance[within])
    assert np.all(found.status[beyond] == NONE)
    assert np.all(found.patch[beyond] == -1)
    assert np.all(found.candidates <= search.project(x, node_normals=node_normals).candidates)


@settings(max_examples=EXAMPLES_RUN // 2 or 30, deadline=None, derandomize=not EXAMPLES_RUN,
          suppress_health_check=[HealthCheck.too_slow])
@given(tool=tools(), seed=st.integers(0, 2**32 - 1))
def test_patch_boxes_contain_their_patches(tool, seed: int) -> None:
    # The bounds the search relies on: every point of a patch lies in its axis-aligned box
    # and in its box in the patch frame (sampled densely, corners and edges included).
    label, surface = tool
    search = ContactSearch(surface)
    lower, upper = search.patch_boxes()
    axes, frame_lower, frame_upper = search.patch_frame_boxes()
    s, t = np.meshgrid(np.linspace(0, 1, 13), np.linspace(0, 1, 13), indexing="ij")
    uv = np.column_stack([s.ravel(), t.ravel()])
    ids = np.repeat(np.arange(surface.n_patches), len(uv))
    params = np.tile(uv, (surface.n_patches, 1))
    if isinstance(surface, NagataSurface):
        tri = surface.is_triangle[ids]
        params[tri] = np.sort(params[tri], axis=1)[:, ::-1]
    points = surface.evaluate(ids, params)[0]
    assert np.all((points >= lower[ids]) & (points <= upper[ids])), label
    local = np.einsum("kab,kb->ka", axes[ids], points)
    assert np.all((local >= frame_lower[ids]) & (local <= frame_upper[ids])), label
    np.testing.assert_allclose(np.einsum("pab,pcb->pac", axes, axes),
                               np.broadcast_to(np.eye(3), axes.shape), atol=1e-12)


def test_bezier_boxes_are_the_control_net_boxes() -> None:
    # A Bezier patch's box is that of its control net (the core rebuilds the net from the
    # power basis it stores), padded by rounding only.
    rng = np.random.default_rng(7)
    nets = [rng.uniform(-50, 50, size=(n + 1, m + 1, 3)) for n in range(1, 7)
            for m in range(1, 7)]
    search = ContactSearch(BezierSurface(nets))
    lower, upper = search.patch_boxes()
    for p, net in enumerate(nets):
        np.testing.assert_allclose(lower[p], net.reshape(-1, 3).min(axis=0), atol=1e-9)
        np.testing.assert_allclose(upper[p], net.reshape(-1, 3).max(axis=0), atol=1e-9)


def split_die(nx: int, ny: int) -> NagataSurface:
    """The bending example's die with its flat part (x from 29.5 to 70 mm) split into
    nx x ny quadrilaterals, the geometry kept: its new vertices are not the shoulder's."""
    die = read_tool(DIE).surface
    corners = die.vertices[die.faces]
    flat = np.all(corners[:, :, 0] >= 29.5 - 1e-9, axis=1)
    x, y = np.meshgrid(np.linspace(29.5, 70.0, nx + 1), np.linspace(0.0, 20.0, ny + 1),
                       indexing="ij")
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    ids = len(die.vertices) + np.arange(x.size).reshape(nx + 1, ny + 1)
    faces = np.column_stack([ids[:-1, :-1].ravel(), ids[1:, :-1].ravel(),
                             ids[1:, 1:].ravel(), ids[:-1, 1:].ravel()])
    normals = np.concatenate([die.corner_normals[~flat],
                              np.tile([0.0, 0.0, 1.0], (len(faces), 4, 1))])
    return NagataSurface(np.vstack([die.vertices, vertices]), normals,
                         np.vstack([die.faces[~flat], faces]))


@pytest.mark.parametrize("nx, ny", [(1, 20), (8, 8), (20, 1), (1, 1)])
def test_large_shoulder_patch_next_to_small_flat_ones(nx: int, ny: int) -> None:
    # Issue 19: a point over the die's shoulder, 0.472 mm from it and 2 mm from the flat.
    # Split the flat finely and the nearest vertices are all the flat's; the search must
    # still find the shoulder patch (face 4 of the die: the last of its four).
    surface = split_die(nx, ny)
    x = np.array([[27.5, 7.5, 0.0]])
    found = ContactSearch(surface).project(x)
    assert found.patch[0] == 4 and found.status[0] == INSIDE
    # The shoulder is a Nagata quarter circle of radius 4 mm about (29.5, -4): within its
    # shape error of sqrt(2^2 + 4^2) - 4.
    assert found.distance[0] == pytest.approx(np.sqrt(20.0) - 4.0, abs=1e-3)
    assert_same_as_brute_force(ContactSearch(surface), x)
    # Everywhere over the die, split or not, no point misses.
    rng = np.random.default_rng(19)
    points = np.column_stack([rng.uniform(20, 75, 3000), rng.uniform(-2, 22, 3000),
                              rng.uniform(-22, 4, 3000)])
    assert_same_as_brute_force(ContactSearch(surface), points)


def test_far_points_edges_and_a_sphere_centre() -> None:
    # A point beyond the tool's free edge is held on that edge; one far above is projected
    # inside; the centre of a sphere is about as far from every patch, and the search still
    # agrees with brute force there.
    search = ContactSearch(split_die(8, 8))
    found = search.project([[80.0, 10.0, 1.0], [49.75, 10.0, 500.0]])
    assert found.status.tolist() == [EDGE, INSIDE]
    np.testing.assert_allclose(found.point[0], [70.0, 10.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(found.distance[1], 500.0, atol=1e-9)
    for kind in ("quad", "tri"):
        v, n, f = Sphere(10.0).mesh(3, kind=kind)
        for smooth in (True, False):
            sphere = ContactSearch(NagataSurface(v, n, f, smooth=smooth))
            assert_same_as_brute_force(sphere, np.array([[0.0, 0.0, 0.0], [0.1, -0.2, 0.3]]))


@pytest.mark.parametrize("left_out", [0, 5, 13])
def test_a_tree_that_leaves_out_a_patch_fails_the_comparison(left_out: int) -> None:
    # The comparison has teeth: the tree of the split die with one patch's leaf pointing
    # at another patch (so that patch is never projected on) misses points above it.
    surface = split_die(1, 20)
    search = ContactSearch(surface)
    x = query_points(np.random.default_rng(3), surface, search)
    assert_same_as_brute_force(search, x)
    # The core copies the tree at a search's first use: a new search, changed before it.
    search = ContactSearch(surface)
    child = search.arrays.tree_child  # the core's 1-based tree, leaves -(patch + 1)
    child[child == -(left_out + 1)] = -((left_out + 1) % surface.n_patches + 1)
    with pytest.raises(AssertionError, match="misses"):
        assert_same_as_brute_force(search, x)


def test_a_reach_leaves_far_points_without_a_patch() -> None:
    # Issue 19: a node whose nearby patches the facing filter leaves out found a patch 20 to
    # 56 mm away (an EDGE point) and that pair stopped a deep drawing run. Within a reach
    # the search returns brute force's patch; beyond it, none (status NONE).
    surface = split_die(8, 8)
    search = ContactSearch(surface)
    x = np.array([[80.0, 10.0, 1.0], [49.75, 10.0, 500.0], [27.5, 7.5, 0.0]])
    near = search.project(x, reach=20.0)
    assert near.status.tolist() == [EDGE, NONE, INSIDE]
    np.testing.assert_allclose(near.point[0], [70.0, 10.0, 0.0], atol=1e-12)
    assert near.patch[2] == 4  # the shoulder, 0.47 mm away
    brute = search.project(x, reach=20.0, brute_force=True)
    np.testing.assert_array_equal(near.patch, brute.patch)
    np.testing.assert_array_equal(near.distance, brute.distance)
    # Beyond the reach of 5 mm, the free edge (10.05 mm away) is no answer either.
    far = search.project(x, reach=5.0)
    assert far.status.tolist() == [NONE, NONE, INSIDE]
    assert far.patch[:2].tolist() == [-1, -1]
    assert search.project(x, reach=5.0, brute_force=True).status.tolist() == [NONE, NONE,
                                                                              INSIDE]
    # The tree search does not project on any patch beyond the reach; brute force does.
    assert far.candidates[1] == 0 and search.project(x[1:2]).candidates[0] > 0
    # The facing filter: nodes facing +x see only the shoulder (normals towards -x). One
    # 1 mm below the flat is then held on the shoulder's edge 12 mm away, on the far side
    # of its patch (distance -12 mm: a deep penetration to the contact law), and one beyond
    # the free edge 52 mm away; within a reach of 5 mm neither has a patch.
    x = np.vstack([x, [[40.0, 10.0, -1.0]]])
    facing = np.tile([1.0, 0.0, 0.0], (len(x), 1))
    unlimited = search.project(x, node_normals=facing)
    assert unlimited.status.tolist() == [EDGE, EDGE, INSIDE, EDGE]
    assert unlimited.patch.tolist() == [4, 4, 4, 4]
    np.testing.assert_allclose(unlimited.distance[[0, 3]], [-52.05, -12.05], atol=0.01)
    limited = search.project(x, node_normals=facing, reach=5.0)
    assert limited.status.tolist() == [NONE, NONE, INSIDE, NONE]
    assert limited.patch[2] == 4 and limited.distance[2] == unlimited.distance[2]
    assert_same_as_brute_force(search, x, facing, reach=5.0)
    with pytest.raises(ValueError, match="reach"):
        search.project(x, reach=-1.0)
    with pytest.raises(ValueError, match="reach"):
        search.project(x, reach=float("nan"))


@pytest.mark.parametrize("nx, ny", [(1, 20), (8, 8)])
def test_the_bending_example_runs_on_a_die_of_mixed_sizes(nx: int, ny: int,
                                                          tmp_path: Path) -> None:
    # Issue 19: with the die's flat split finely, the former search missed the shoulder
    # under the blank's nodes and the first increment diverged. The geometry is the same,
    # so the run must give the original die's punch forces (the flat is the plane z = 0
    # either way; only round-off in the projections differs).
    import shutil

    from ddpy.app.runner import run_case
    from ddpy.io.decks import read_case
    from ddpy.io.results import ResultsReader
    from ddpy.io.toolfile import ToolModel, write_tool

    forces = []
    for split in (False, True):
        case = tmp_path / f"case{int(split)}"
        shutil.copytree(DIE.parents[1], case)
        if split:
            original = read_tool(DIE)
            write_tool(case / "tools" / "die.tool",
                       ToolModel("die", "nagata", split_die(nx, ny),
                                 np.zeros(split_die(nx, ny).n_patches, dtype=np.int64)))
        outcome = run_case(read_case(case), case / "out", max_increments=6)
        assert outcome.status == "stopped" and outcome.increments == 6
        with ResultsReader(case / "out" / "results.h5") as r:
            forces.append(r.tool_force("punch")[:, 2])
    assert original.surface.n_patches < split_die(nx, ny).n_patches
    np.testing.assert_allclose(forces[1], forces[0], rtol=1e-6, atol=1e-9)
