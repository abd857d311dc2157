"""Surface meshes of CAD faces for tool models (gmsh), with a structured mesher of our own.

Edges are divided by angle (curved) or length (straight). Faces bounded by four distinct edges
get gmsh's transfinite mesh. Faces that gmsh cannot mesh as transfinite but whose boundary
runs along their parameter rectangle (surfaces of revolution closed on a seam, spheres with a
pole: the punch and die walls of deep drawing) get a structured grid built here, by Coons
interpolation in the parameter plane between the nodes gmsh put on their edges, so the mesh
stays conforming. Other faces are meshed unstructured by gmsh.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

__all__ = ["MeshPlan", "element_array", "grid_mesh", "point_text", "prepare_mesh"]

SIDES = ("bottom", "right", "top", "left")   # v = v0, u = u1, v = v1, u = u0
OPPOSITE = {"bottom": "top", "top": "bottom", "left": "right", "right": "left"}


@dataclass
class MeshPlan:
    """Divisions per edge, faces meshed by gmsh as transfinite, faces gridded here."""

    divisions: dict[int, int] = field(default_factory=dict)
    transfinite: list[int] = field(default_factory=list)
    #: face -> side -> (curve tag, which parametrization of a seam); curve 0: a degenerate side
    grids: dict[int, dict[str, tuple[int, int]]] = field(default_factory=dict)


def point_text(x: NDArray[np.float64]) -> str:
    """A point for a message, '(x, y, z)', rounding off coordinates that are noise."""
    x = np.where(np.abs(x) <= 1e-9 * max(1.0, float(np.abs(x).max())), 0.0, x)
    return "(" + ", ".join(f"{v:.6g}" for v in x) + ")"


def curve_shape(curve: int) -> tuple[float, float]:
    """(turning angle in radians, length) of a curve, from 129 samples."""
    import gmsh

    lo, hi = gmsh.model.getParametrizationBounds(1, curve)
    t = np.linspace(lo[0], hi[0], 129)
    x = np.asarray(gmsh.model.getValue(1, curve, t)).reshape(-1, 3)
    length = float(np.linalg.norm(np.diff(x, axis=0), axis=1).sum())
    d = np.asarray(gmsh.model.getDerivative(1, curve, t)).reshape(-1, 3)
    norm = np.linalg.norm(d, axis=1)
    if length == 0.0 or not np.all(norm > 0.0):
        return 0.0, length
    tangent = d / norm[:, None]
    cosines = np.clip(np.einsum("ij,ij->i", tangent[1:], tangent[:-1]), -1.0, 1.0)
    return float(np.arccos(cosines).sum()), length


def _side_of(uv: NDArray[np.float64], lo: NDArray[np.float64],
             hi: NDArray[np.float64]) -> list[str]:
    """The sides of the parameter rectangle that all points ``uv`` lie on."""
    eps = 1e-7 * np.maximum(hi - lo, 1e-12)
    tests = {"left": np.abs(uv[:, 0] - lo[0]) <= eps[0],
             "right": np.abs(uv[:, 0] - hi[0]) <= eps[0],
             "bottom": np.abs(uv[:, 1] - lo[1]) <= eps[1],
             "top": np.abs(uv[:, 1] - hi[1]) <= eps[1]}
    return [side for side, ok in tests.items() if ok.all()]


def _param_sides(face: int, curves: list[int],
                 degenerate: set[int]) -> dict[str, tuple[int, int]] | None:
    """Sides of the parameter rectangle made by the face's edges, or None if they are not."""
    import gmsh

    lo, hi = (np.asarray(b, dtype=np.float64) for b in gmsh.model.getParametrizationBounds(2, face))
    sides: dict[str, tuple[int, int]] = {}
    pending = []
    for curve in dict.fromkeys(curves):
        if curve in degenerate:
            pending.append(curve)
            continue
        a, b = (float(x[0]) for x in gmsh.model.getParametrizationBounds(1, curve))
        t = np.linspace(a, b, 5)
        for which in (0, 1) if curves.count(curve) == 2 else (0,):
            uv = np.asarray(gmsh.model.reparametrizeOnSurface(1, curve, t, face, which))
            found = _side_of(uv.reshape(-1, 2), lo, hi)
            if len(found) != 1 or found[0] in sides:
                return None
            sides[found[0]] = (curve, which)
    for curve in pending:   # a degenerate edge (a pole) takes the side left over
        free = [s for s in SIDES if s not in sides]
        a = float(gmsh.model.getParametrizationBounds(1, curve)[0][0])
        uv = np.asarray(gmsh.model.reparametrizeOnSurface(1, curve, [a], face)).reshape(-1, 2)
        if len(free) != 1 or free[0] not in _side_of(uv, lo, hi):
            return None
        sides[free[0]] = (0, 0)
    if len(sides) != 4 or sum(c == 0 for c, _ in sides.values()) > 2:
        return None
    if any(c == 0 and sides[OPPOSITE[s]][0] == 0 for s, (c, _) in sides.items()):
        return None
    return sides


def prepare_mesh(faces: list[int], per_arc: int, element: str, size: float | None,
                 arc_size: float | None = None) -> MeshPlan:
    """Set the gmsh mesh constraints of the faces; what is left to :func:`grid_mesh`.

    Curved edges get ``per_arc`` elements per 90 degrees of turning, and elements of at most
    ``arc_size`` (mm) if given: along the circumference of a large surface of revolution the
    turning angle alone leaves long elements. Straight edges get elements of at most
    ``size``, one without it."""
    import gmsh

    boundary: dict[int, list[int]] = {}
    shape: dict[int, tuple[float, float]] = {}
    for face in faces:
        curves = [abs(c) for _, c in gmsh.model.getBoundary([(2, face)], combined=False,
                                                            oriented=True)]
        boundary[face] = curves
        for c in curves:
            if c not in shape:
                shape[c] = curve_shape(c)
    scale = max((s[1] for s in shape.values()), default=1.0)
    plan = MeshPlan()
    degenerate = {c for c, (_, length) in shape.items() if length <= 1e-9 * scale}
    for c, (angle, length) in shape.items():
        if c in degenerate:
            continue
        if angle > 1e-6:  # curved: by the angle, and by the length given arc_size
            n = max(1, int(np.ceil(per_arc * angle / (np.pi / 2) - 1e-6)))
            if arc_size is not None:
                n = max(n, int(np.ceil(length / arc_size - 1e-6)))
            plan.divisions[c] = n
        else:             # straight: by the size, one element without it
            plan.divisions[c] = 1 if size is None else max(1, int(np.ceil(length / size - 1e-6)))
    pairs = []
    for f, cs in boundary.items():
        if len(set(cs)) == 4 and not degenerate & set(cs):
            plan.transfinite.append(f)
            pairs += [(cs[0], cs[2]), (cs[1], cs[3])]
        elif (sides := _param_sides(f, cs, degenerate)) is not None:
            plan.grids[f] = sides
            pairs += [(sides[a][0], sides[b][0]) for a, b in (("bottom", "top"), ("left", "right"))
                      if sides[a][0] and sides[b][0]]
    changed = True
    while changed:  # opposite edges of a structured face need the same division
        changed = False
        for a, b in pairs:
            if plan.divisions[a] != plan.divisions[b]:
                plan.divisions[a] = plan.divisions[b] = max(plan.divisions[a], plan.divisions[b])
                changed = True
    for c, n in plan.divisions.items():
        gmsh.model.mesh.setTransfiniteCurve(c, n + 1)
    for f in faces:
        if f in plan.transfinite:
            gmsh.model.mesh.setTransfiniteSurface(f)
        if element == "quad" and f not in plan.grids:
            gmsh.model.mesh.setRecombine(2, f)
    # Frontal-Delaunay, recombined into quadrilaterals by Blossom. Not the quad-oriented
    # variant (8): gmsh 4.15 crashes with it near the pole of a sphere.
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 4 * per_arc)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size if size is not None else 1e22)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    # Only the selected faces are meshed by gmsh, and the edges of the gridded ones.
    gmsh.model.setVisibility(gmsh.model.getEntities(), 0)
    gmsh.model.setVisibility([(2, f) for f in faces if f not in plan.grids], 1, recursive=True)
    gmsh.model.setVisibility([(1, c) for f in plan.grids for c in boundary[f]], 1,
                             recursive=True)
    gmsh.option.setNumber("Mesh.MeshOnlyVisible", 1)
    return plan


def _side_nodes(face: int, curve: int, which: int, along: int
                ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """Node tags and face parameters of an edge's mesh, ordered by parameter ``along``."""
    import gmsh

    tags, _, t = gmsh.model.mesh.getNodes(1, curve, includeBoundary=False,
                                          returnParametricCoord=True)
    a, b = (float(x[0]) for x in gmsh.model.getParametrizationBounds(1, curve))
    ends = [abs(p) for _, p in gmsh.model.getBoundary([(1, curve)], combined=False,
                                                      oriented=False)]
    if len(ends) != 2:
        raise ValueError(f"its edge {curve} has {len(ends)} end points")
    start = np.asarray(gmsh.model.getValue(1, curve, [a]))
    first = np.asarray(gmsh.model.getValue(0, ends[0], []))
    if np.linalg.norm(first - start) > np.linalg.norm(np.asarray(
            gmsh.model.getValue(0, ends[1], [])) - start):
        ends.reverse()
    end_tags = [int(gmsh.model.mesh.getNodes(0, p)[0][0]) for p in ends]
    all_tags = np.concatenate([[end_tags[0]], np.asarray(tags, dtype=np.int64), [end_tags[1]]])
    params = np.concatenate([[a], np.asarray(t, dtype=np.float64), [b]])
    uv = np.asarray(gmsh.model.reparametrizeOnSurface(1, curve, params, face, which))
    uv = uv.reshape(-1, 2)
    order = np.argsort(uv[:, along], kind="stable")
    return all_tags[order], uv[order]


def grid_mesh(face: int, sides: dict[str, tuple[int, int]], element: str, first_tag: int
              ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64],
                         NDArray[np.int64]]:
    """A structured mesh of a face from the nodes on its edges: (tags, coords, uv, elements).

    New interior nodes are numbered from ``first_tag``; elements are (m, 4), -1 last for a
    triangle (where a side collapses to a pole). Raises ValueError if the edges disagree.
    """
    import gmsh

    nodes: dict[str, tuple[NDArray[np.int64], NDArray[np.float64]]] = {}
    for side, (curve, which) in sides.items():
        if curve:
            nodes[side] = _side_nodes(face, curve, which, 0 if side in ("bottom", "top") else 1)
    for side, (curve, _) in sides.items():
        if curve:
            continue
        # A pole: one node, the parameters running between the neighbouring sides' ends.
        if side in ("bottom", "top"):
            end = 0 if side == "bottom" else -1
            left, right = nodes["left"], nodes["right"]
            count = len(nodes[OPPOSITE[side]][0])
            f = np.linspace(0.0, 1.0, count)[:, None]
            nodes[side] = (np.full(count, left[0][end]), (1 - f) * left[1][end] + f * right[1][end])
        else:
            end = 0 if side == "left" else -1
            bottom, top = nodes["bottom"], nodes["top"]
            count = len(nodes[OPPOSITE[side]][0])
            f = np.linspace(0.0, 1.0, count)[:, None]
            nodes[side] = (np.full(count, bottom[0][end]),
                           (1 - f) * bottom[1][end] + f * top[1][end])
    for side, (curve, _) in sides.items():
        if curve == 0:  # a pole must have one normal (a sphere's), not a cone's apex
            normals = np.asarray(gmsh.model.getNormal(face, nodes[side][1].ravel()))
            normals = normals.reshape(-1, 3)
            if np.ptp(normals, axis=0).max() > 1e-6 or not np.allclose(
                    np.linalg.norm(normals, axis=1), 1.0):
                x = np.asarray(gmsh.model.getValue(2, face, nodes[side][1][0]))
                raise ValueError(f"the surface normal is undefined at {point_text(x)} (a "
                                 "singular point such as a cone apex): split the face")
    lo, hi = (np.asarray(b, dtype=np.float64) for b in gmsh.model.getParametrizationBounds(2, face))
    tol = 1e-7 * np.maximum(hi - lo, 1e-12)
    for side, (_, side_uv) in nodes.items():
        k = 0 if side in ("bottom", "top") else 1
        if abs(side_uv[0, k] - lo[k]) > tol[k] or abs(side_uv[-1, k] - hi[k]) > tol[k]:
            raise ValueError(f"the nodes of its {side} edge do not span its parameter range")
    (bt, buv), (tt, tuv) = nodes["bottom"], nodes["top"]
    (lt, luv), (rt, ruv) = nodes["left"], nodes["right"]
    n, m = len(bt) - 1, len(lt) - 1
    if len(tt) != n + 1 or len(rt) != m + 1:
        raise ValueError("opposite edges have different numbers of nodes")
    corners = (bt[0] == lt[0], bt[-1] == rt[0], tt[0] == lt[-1], tt[-1] == rt[-1])
    if not all(corners):
        raise ValueError("its edges do not meet at the corners of its parameter rectangle")
    s = np.linspace(0.0, 1.0, n + 1)[:, None, None]
    t = np.linspace(0.0, 1.0, m + 1)[None, :, None]
    uv = ((1 - t) * buv[:, None] + t * tuv[:, None] + (1 - s) * luv[None] + s * ruv[None]
          - (1 - s) * (1 - t) * buv[0] - s * (1 - t) * buv[-1]
          - (1 - s) * t * tuv[0] - s * t * tuv[-1])
    grid = np.empty((n + 1, m + 1), dtype=np.int64)
    grid[1:-1, 1:-1] = first_tag + np.arange((n - 1) * (m - 1)).reshape(n - 1, m - 1)
    grid[:, 0], grid[:, -1], grid[0, :], grid[-1, :] = bt, tt, lt, rt
    uv[:, 0], uv[:, -1], uv[0, :], uv[-1, :] = buv, tuv, luv, ruv
    tags, first = np.unique(grid.ravel(), return_index=True)
    flat_uv = uv.reshape(-1, 2)[first]
    coord = np.asarray(gmsh.model.getValue(2, face, flat_uv.ravel())).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    quads = np.stack([grid[i, j], grid[i + 1, j], grid[i + 1, j + 1], grid[i, j + 1]], -1)
    quads = quads.reshape(-1, 4)
    if element == "tri":
        tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        cells = [list(dict.fromkeys(c)) for c in tris.tolist()]
    else:
        cells = [list(dict.fromkeys(c)) for c in quads.tolist()]
    cells = [c + [-1] * (4 - len(c)) for c in cells if len(c) >= 3]
    return tags, coord, flat_uv, np.array(cells, dtype=np.int64)


def element_array(types: list[int], connectivity: list[NDArray]) -> NDArray[np.int64]:
    """gmsh's triangles and quadrangles as (m, 4) vertex tags, -1 last for a triangle."""
    blocks = []
    for kind, conn in zip(types, connectivity, strict=True):
        conn = np.asarray(conn, dtype=np.int64)
        if kind == 3:      # 4-node quadrangle
            blocks.append(conn.reshape(-1, 4))
        elif kind == 2:    # 3-node triangle
            tri = conn.reshape(-1, 3)
            blocks.append(np.column_stack([tri, np.full(len(tri), -1)]))
        else:
            raise ValueError(f"gmsh made elements of type {kind}: expected linear triangles "
                             "and quadrangles")
    return np.concatenate(blocks) if blocks else np.zeros((0, 4), dtype=np.int64)
