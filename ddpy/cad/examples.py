"""Small CAD models built with gmsh's OpenCASCADE, for the benchmark, tests and examples.

Each function adds the faces to the current gmsh model (inside :func:`ddpy.cad.gmsh_session`)
and, given a path, writes them as STEP (or IGES, BREP by the suffix).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ddpy.cad import quiet

__all__ = ["bending_tools", "cylinder_segment", "cylindrical_punch", "die_profile",
           "reverse_drawing_tools", "sphere_patch", "square_cup_tools", "sweep_profile",
           "write_cad"]


def write_cad(path: str | os.PathLike[str] | None) -> Path | None:
    """Write the current gmsh model's geometry to ``path`` (format by suffix), if given."""
    import gmsh

    if path is None:
        return None
    gmsh.model.occ.synchronize()
    with quiet():
        gmsh.write(str(path))
    return Path(path)


def die_profile(path: str | os.PathLike[str] | None = None, land: float = 20.0,
                fillet: float = 4.0, radius: float = 23.5, width: float = 30.0) -> list[int]:
    """The plane-fillet-cylinder tool: a die-like profile in the xz-plane extruded along y.

    A flat land z = 0 for -land <= x <= 0, a convex fillet of radius ``fillet`` turning down
    by 90 degrees, then a concave quarter cylinder of radius ``radius`` turning back to
    horizontal (its axis along y through x = fillet + radius, z = -fillet). All joints are
    tangent. The blank lies above (+z). Returns the face tags (land, fillet, cylinder).
    """
    import gmsh

    occ = gmsh.model.occ
    centre_x = fillet + radius
    p0, p1 = occ.addPoint(-land, 0, 0), occ.addPoint(0, 0, 0)
    c1, p2 = occ.addPoint(0, 0, -fillet), occ.addPoint(fillet, 0, -fillet)
    c2, p3 = occ.addPoint(centre_x, 0, -fillet), occ.addPoint(centre_x, 0, -fillet - radius)
    curves = [occ.addLine(p0, p1), occ.addCircleArc(p1, c1, p2), occ.addCircleArc(p2, c2, p3)]
    out = occ.extrude([(1, c) for c in curves], 0, width, 0)
    occ.synchronize()
    write_cad(path)
    return [t for d, t in out if d == 2]


def _keep_faces(volume: int, kind: str) -> list[int]:
    """Copy the faces of ``kind`` (e.g. 'Cylinder') of a solid, delete the solid."""
    import gmsh

    occ = gmsh.model.occ
    occ.synchronize()
    faces = [t for _, t in gmsh.model.getBoundary([(3, volume)], oriented=False)
             if gmsh.model.getType(2, t) == kind]
    copies = occ.copy([(2, t) for t in faces])
    occ.remove([(3, volume)], recursive=True)
    occ.synchronize()
    return [t for _, t in copies]


def cylinder_segment(path: str | os.PathLike[str] | None = None, radius: float = 10.0,
                     length: float = 20.0, angle: float = np.pi / 2) -> list[int]:
    """A cylindrical face: axis z from the origin, ``length`` long, ``angle`` of arc from +x."""
    import gmsh

    volume = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, length, radius, angle=angle)
    faces = _keep_faces(volume, "Cylinder")
    write_cad(path)
    return faces


def sphere_patch(path: str | os.PathLike[str] | None = None, radius: float = 10.0,
                 latitudes: tuple[float, float] = (0.2, 1.0),
                 longitude: float = 1.0) -> list[int]:
    """A spherical face centred at the origin between two latitudes (radians), over
    ``longitude`` radians from +x."""
    import gmsh

    volume = gmsh.model.occ.addSphere(0, 0, 0, radius, angle1=latitudes[0],
                                      angle2=latitudes[1], angle3=longitude)
    faces = _keep_faces(volume, "Sphere")
    write_cad(path)
    return faces


def cylindrical_punch(path: str | os.PathLike[str] | None = None, radius: float = 48.0,
                      fillet: float = 8.0, height: float = 32.0) -> list[int]:
    """A cylindrical punch of deep drawing, nose down at z = 0: a flat disc of radius
    ``radius - fillet``, a toroidal fillet and a cylindrical wall ``height`` high, all full
    revolutions about z (faces closed on a seam). The blank lies below (-z). Returns the
    face tags (disc, fillet, wall)."""
    import gmsh

    occ = gmsh.model.occ
    inner = radius - fillet
    p0, p1 = occ.addPoint(0, 0, 0), occ.addPoint(inner, 0, 0)
    centre, p2 = occ.addPoint(inner, 0, fillet), occ.addPoint(radius, 0, fillet)
    p3 = occ.addPoint(radius, 0, fillet + height)
    curves = [occ.addLine(p0, p1), occ.addCircleArc(p1, centre, p2), occ.addLine(p2, p3)]
    out = occ.revolve([(1, c) for c in curves], 0, 0, 0, 0, 0, 1, 2 * np.pi)
    occ.synchronize()
    write_cad(path)
    return [t for d, t in out if d == 2]


def bending_tools(path: str | os.PathLike[str] | None = None, punch_radius: float = 23.5,
                  shoulder_radius: float = 4.0, shoulder_x: float = 29.22,
                  thickness: float = 1.0, die_end: float = 70.0, wall_depth: float = 20.0,
                  width: tuple[float, float] = (-5.0, 20.0)) -> dict[str, list[int]]:
    """The tools of the unconstrained cylindrical bending benchmark (Numisheet 2002 B),
    quarter model, a reconstruction (the paper's Fig. 6 is not in its text).

    Symmetry planes x = 0 and y = 0; the flat blank lies on 0 <= z <= ``thickness``. The punch
    is a quarter cylinder of radius ``punch_radius``, axis along y through x = 0,
    z = thickness + punch_radius, from its lowest line (x = 0, z = thickness) up to x =
    punch_radius. The open die (no bottom) is an inner wall x = shoulder_x - shoulder_radius
    from z = -shoulder_radius - wall_depth up to the shoulder, a quarter cylinder of radius
    ``shoulder_radius`` centred at (shoulder_x, -shoulder_radius), and a flat top z = 0 out to
    x = ``die_end``. Every face spans ``width`` along y. Returns the face tags by tool
    ({"punch": [...], "die": [wall, shoulder, flat]}).
    The default shoulder_x is the benchmark's die, fitted to the paper's contact angles
    (a clearance of 1.72 mm between the punch's side and the shoulder).
    """
    import gmsh

    occ = gmsh.model.occ
    y0, y1 = width
    zc = thickness + punch_radius
    bottom, centre = occ.addPoint(0, y0, thickness), occ.addPoint(0, y0, zc)
    side = occ.addPoint(punch_radius, y0, zc)
    punch = [occ.addCircleArc(bottom, centre, side)]
    inner = shoulder_x - shoulder_radius
    w0, w1 = occ.addPoint(inner, y0, -shoulder_radius - wall_depth), \
        occ.addPoint(inner, y0, -shoulder_radius)
    c, top = occ.addPoint(shoulder_x, y0, -shoulder_radius), occ.addPoint(shoulder_x, y0, 0)
    end = occ.addPoint(die_end, y0, 0)
    die = [occ.addLine(w0, w1), occ.addCircleArc(w1, c, top), occ.addLine(top, end)]
    faces: dict[str, list[int]] = {}
    for name, curves in (("punch", punch), ("die", die)):
        out = occ.extrude([(1, k) for k in curves], 0, y1 - y0, 0)
        faces[name] = [t for d, t in out if d == 2]
    occ.synchronize()
    write_cad(path)
    return faces


#: A profile piece in the (r, z) half-plane: ("line", (r0, z0), (r1, z1)) or
#: ("arc", (r0, z0), (rc, zc), (r1, z1)) from its start through its centre to its end.
Piece = tuple


def revolve_profiles(profiles: dict[str, list[Piece]], angles: tuple[float, ...]
                     ) -> dict[str, list[int]]:
    """Revolve profiles drawn in the (r, z) half-plane about the z axis through ``angles``
    (degrees from +x towards +y, increasing; more than two split every face at the ones
    between). Returns the face tags by profile name."""
    import gmsh

    occ = gmsh.model.occ
    if len(angles) < 2 or any(b <= a for a, b in zip(angles, angles[1:], strict=False)):
        raise ValueError(f"angles must increase, got {angles}")
    faces: dict[str, list[int]] = {}
    for name, pieces in profiles.items():
        faces[name] = []
        for start, stop in zip(np.radians(angles[:-1]), np.radians(angles[1:]), strict=True):
            faces[name] += _revolve(pieces, float(start), float(stop))
    occ.synchronize()
    return faces


def _revolve(pieces: list[Piece], start: float, stop: float) -> list[int]:
    """The faces of one profile revolved from ``start`` to ``stop`` (radians)."""
    import gmsh

    occ = gmsh.model.occ
    points: dict[tuple[float, float], int] = {}

    def point(rz: tuple[float, float]) -> int:
        key = (round(float(rz[0]), 12), round(float(rz[1]), 12))
        if key not in points:
            points[key] = occ.addPoint(key[0], 0.0, key[1])
        return points[key]

    curves = []
    for piece in pieces:
        if piece[0] == "line":
            curves.append(occ.addLine(point(piece[1]), point(piece[2])))
        elif piece[0] == "arc":
            curves.append(occ.addCircleArc(point(piece[1]), point(piece[2]),
                                           point(piece[3])))
        else:
            raise ValueError(f"profile piece must be a line or an arc, got {piece[0]!r}")
    dim_tags = [(1, c) for c in curves]
    occ.rotate(dim_tags, 0, 0, 0, 0, 0, 1, start)
    out = occ.revolve(dim_tags, 0, 0, 0, 0, 0, 1, stop - start)
    return [t for d, t in out if d == 2]


def _disc_sector(radius: float, z: float, angles: tuple[float, float, float]) -> list[int]:
    """A flat disc sector at height ``z`` between the outer two of ``angles`` (degrees), in
    three four-sided faces (an inner quadrilateral and two pieces of the rim, split at the
    middle angle) so that every face can be one Bezier patch and a structured mesh."""
    import gmsh

    occ = gmsh.model.occ
    a0, a1, a2 = np.radians(angles)
    inner, corner = 0.5 * radius, 0.6 * radius
    centre = occ.addPoint(0, 0, z)

    def at(r: float, a: float) -> int:
        return occ.addPoint(r * np.cos(a), r * np.sin(a), z)

    p0, p1, p2 = at(inner, a0), at(corner, a1), at(inner, a2)
    q0, q1, q2 = at(radius, a0), at(radius, a1), at(radius, a2)
    lines = {k: occ.addLine(*k) for k in ((centre, p0), (p0, p1), (p1, p2), (p2, centre),
                                          (p0, q0), (p1, q1), (p2, q2))}
    arcs = [occ.addCircleArc(q0, centre, q1), occ.addCircleArc(q1, centre, q2)]
    loops = [[lines[(centre, p0)], lines[(p0, p1)], lines[(p1, p2)], lines[(p2, centre)]],
             [lines[(p0, q0)], arcs[0], -lines[(p1, q1)], -lines[(p0, p1)]],
             [lines[(p1, q1)], arcs[1], -lines[(p2, q2)], -lines[(p1, p2)]]]
    return [occ.addPlaneSurface([occ.addCurveLoop(loop)]) for loop in loops]


def reverse_drawing_tools(path: str | os.PathLike[str] | None = None, *, thickness: float = 0.98,
                          die_bore: float = 51.25, die_shoulder: float = 8.0,
                          die_outer: float = 90.0, die_depth: float = 50.0,
                          punch1_radius: float = 50.0, punch1_nose: float = 6.0,
                          punch1_edge: float = 4.0, punch1_bore: float = 37.75,
                          punch1_height: float = 70.0, holder1_gap: float = 1.13,
                          holder1_edge: float = 3.0, holder1_inner: float = 61.25,
                          punch2_radius: float = 36.5, punch2_nose: float = 5.0,
                          punch2_height: float = 50.0, punch2_start: float = -42.0,
                          holder2_inner: float = 38.0, holder2_outer: float = 48.0,
                          holder2_edge: float = 2.0, holder2_top: float = -40.42,
                          angles: tuple[float, float] = (-3.0, 93.0),
                          split: bool = False) -> dict[str, list[int]]:
    """The five tools of the reverse deep drawing of a cylindrical cup (Numisheet'99
    benchmark C), quarter model, as surfaces of revolution about z. The dimensions are a
    reconstruction (docs/benchmarks/reverse_deep_drawing.md): the benchmark's drawing is not
    in the paper.

    The flat blank lies on 0 <= z <= ``thickness``, centred on the axis. Stage 1: punch 1
    (above, hollow) draws it into die 1 (below) while blank-holder 1 (above, a flat annulus
    over the die's flat from ``holder1_inner`` out, ``holder1_gap`` above it, its inner edge
    rounded by ``holder1_edge``) holds the flange. Stage 2: punch 2 (below,
    its flat end at ``punch2_start``) pushes the cup's bottom up through punch 1's bore; punch
    1's end ring and its inner edge of radius ``punch1_edge`` are die 2, and blank-holder 2
    (below, its flat top at ``holder2_top``) holds the bottom's annulus against that ring.

    Faces span ``angles`` (degrees about z, a little beyond the quarter so that the blank's
    symmetry planes lie inside them); with ``split``, every face is split at the middle angle
    into two halves (punch 2's always is). Returns the face tags by tool: die1 (bore wall,
    shoulder, flat), holder1 (inner edge, flat), punch1 (bore wall, inner edge, end ring,
    outer nose, outer wall), holder2 (inner wall, inner edge, flat, outer edge, outer
    wall), punch2 (its flat end in three four-sided faces, then nose and wall, each in two
    halves); with ``split``, the other tools' faces of the first half, then the second's.
    """
    import gmsh

    t = thickness
    shoulder_r = die_bore + die_shoulder
    edge_r, nose_r = punch1_bore + punch1_edge, punch1_radius - punch1_nose
    if not (0.0 < die_shoulder and shoulder_r < die_outer and 0.0 < punch1_edge
            and 0.0 < holder1_edge < holder1_inner - punch1_radius
            and shoulder_r <= holder1_inner < die_outer
            and 0.0 < punch1_nose and edge_r < nose_r and punch1_radius < die_bore
            and 0.0 < punch2_nose < punch2_radius < punch1_bore
            and punch2_radius < holder2_inner and 2 * holder2_edge < holder2_outer - holder2_inner
            and holder1_gap > t):
        raise ValueError("reverse drawing tools: the dimensions do not fit together")
    flat2 = punch2_radius - punch2_nose
    h_in, h_out, f = holder2_inner, holder2_outer, holder2_edge
    profiles: dict[str, list[Piece]] = {
        "die1": [("line", (die_bore, -die_shoulder - die_depth), (die_bore, -die_shoulder)),
                 ("arc", (die_bore, -die_shoulder), (shoulder_r, -die_shoulder), (shoulder_r, 0.0)),
                 ("line", (shoulder_r, 0.0), (die_outer, 0.0))],
        "holder1": [("arc", (holder1_inner - holder1_edge, holder1_gap + holder1_edge),
                     (holder1_inner, holder1_gap + holder1_edge), (holder1_inner, holder1_gap)),
                    ("line", (holder1_inner, holder1_gap), (die_outer, holder1_gap))],
        "punch1": [("line", (punch1_bore, t + punch1_height), (punch1_bore, t + punch1_edge)),
                   ("arc", (punch1_bore, t + punch1_edge), (edge_r, t + punch1_edge), (edge_r, t)),
                   ("line", (edge_r, t), (nose_r, t)),
                   ("arc", (nose_r, t), (nose_r, t + punch1_nose),
                    (punch1_radius, t + punch1_nose)),
                   ("line", (punch1_radius, t + punch1_nose), (punch1_radius, t + punch1_height))],
        "punch2": [("arc", (flat2, punch2_start), (flat2, punch2_start - punch2_nose),
                    (punch2_radius, punch2_start - punch2_nose)),
                   ("line", (punch2_radius, punch2_start - punch2_nose),
                    (punch2_radius, punch2_start - punch2_height))],
        "holder2": [("line", (h_in, holder2_top - 2 * f), (h_in, holder2_top - f)),
                    ("arc", (h_in, holder2_top - f), (h_in + f, holder2_top - f),
                     (h_in + f, holder2_top)),
                    ("line", (h_in + f, holder2_top), (h_out - f, holder2_top)),
                    ("arc", (h_out - f, holder2_top), (h_out - f, holder2_top - f),
                     (h_out, holder2_top - f)),
                    ("line", (h_out, holder2_top - f), (h_out, holder2_top - 2 * f))],
    }
    punch2 = profiles.pop("punch2")
    # Punch 2's flat end reaches the axis: a disc sector in four-sided faces, the rest split
    # at the same middle angle so that the faces meet edge to edge.
    halves = (angles[0], 0.5 * (angles[0] + angles[1]), angles[1])
    faces = revolve_profiles(profiles, halves if split else angles)
    faces["punch2"] = (_disc_sector(flat2, punch2_start, halves)
                       + revolve_profiles({"punch2": punch2}, halves)["punch2"])
    gmsh.model.occ.synchronize()
    write_cad(path)
    return faces


def sweep_profile(pieces: list[Piece], centre: float, margin: float) -> list[int]:
    """Sweep a profile around the quarter of a rounded square, the tools of a square cup.

    The profile is drawn in the (r, z) half-plane, r measured outwards from the centre of
    the square's corner arc at (``centre``, ``centre``) (a plan corner radius r, a
    half-width ``centre`` + r). It is extruded along the side x = ``centre`` + r from y =
    -``margin`` to ``centre``, revolved about the vertical axis through the corner's centre
    from 0 to 90 degrees (in two halves, split at 45), and extruded along the side y =
    ``centre`` + r back to x = -``margin``, beyond the symmetry planes so that they lie
    inside the faces. Returns the face tags: side x, the two corner halves, side y."""
    import gmsh

    occ = gmsh.model.occ

    def curves(place: Callable[[float, float], tuple[float, float, float]]
               ) -> list[tuple[int, int]]:
        points: dict[tuple[float, float], int] = {}

        def point(rz: tuple[float, float]) -> int:
            key = (round(float(rz[0]), 12), round(float(rz[1]), 12))
            if key not in points:
                points[key] = occ.addPoint(*place(*key))
            return points[key]

        made = []
        for piece in pieces:
            if piece[0] == "line":
                made.append(occ.addLine(point(piece[1]), point(piece[2])))
            elif piece[0] == "arc":
                made.append(occ.addCircleArc(point(piece[1]), point(piece[2]), point(piece[3])))
            else:
                raise ValueError(f"profile piece must be a line or an arc, got {piece[0]!r}")
        return [(1, c) for c in made]

    c = centre
    faces = [t for d, t in occ.extrude(curves(lambda r, z: (c + r, -margin, z)), 0, c + margin, 0)
             if d == 2]
    for start in (0.0, 0.25 * np.pi):
        corner = curves(lambda r, z: (c + r, c, z))
        occ.rotate(corner, c, c, 0, 0, 0, 1, start)
        faces += [t for d, t in occ.revolve(corner, c, c, 0, 0, 0, 1, 0.25 * np.pi) if d == 2]
    faces += [t for d, t in occ.extrude(curves(lambda r, z: (c, c + r, z)), -(c + margin), 0, 0)
              if d == 2]
    return faces


def _rounded_flat(centre: float, radius: float, z: float, margin: float) -> list[int]:
    """The flat end of a square punch in the quarter x, y >= -``margin``: the rounded square
    of half-width ``centre`` + ``radius`` (corner arc of ``radius`` about (``centre``,
    ``centre``)) at height ``z``, in eight four-sided faces of fair shape, so that each is
    one Bezier patch and a structured mesh: the square up to ``centre``, two strips along
    each side (split at half the radius), and the corner's quarter disc as an inner
    quadrilateral and two pieces of the rim split at 45 degrees, meeting the corner's two
    swept halves edge to edge (the disc sector of the reverse drawing's punch 2)."""
    import gmsh

    occ = gmsh.model.occ
    c, a, m = centre, radius, margin
    points: dict[tuple[float, float], int] = {}

    def point(x: float, y: float) -> int:
        key = (round(float(x), 12), round(float(y), 12))
        if key not in points:
            points[key] = occ.addPoint(key[0], key[1], z)
        return points[key]

    lines: dict[tuple[int, int], int] = {}

    def line(p: int, q: int) -> int:
        if (q, p) in lines:
            return -lines[(q, p)]
        if (p, q) not in lines:
            lines[(p, q)] = occ.addLine(p, q)
        return lines[(p, q)]

    def quad(*corners: tuple[float, float]) -> int:
        tags = [point(*x) for x in corners]
        loop = [line(tags[i], tags[(i + 1) % 4]) for i in range(4)]
        return occ.addPlaneSurface([occ.addCurveLoop(loop)])

    h, d = 0.5 * a, 0.6 * a / np.sqrt(2.0)
    faces = [quad((-m, -m), (c, -m), (c, c), (-m, c)),
             quad((c, -m), (c + h, -m), (c + h, c), (c, c)),
             quad((c + h, -m), (c + a, -m), (c + a, c), (c + h, c)),
             quad((-m, c), (c, c), (c, c + h), (-m, c + h)),
             quad((-m, c + h), (c, c + h), (c, c + a), (-m, c + a)),
             quad((c, c), (c + h, c), (c + d, c + d), (c, c + h))]
    centre_tag = occ.addPoint(c, c, z)
    q0, q1, q2 = point(c + a, c), point(c + a / np.sqrt(2.0), c + a / np.sqrt(2.0)), point(c, c + a)
    p0, p1, p2 = point(c + h, c), point(c + d, c + d), point(c, c + h)
    arcs = [occ.addCircleArc(q0, centre_tag, q1), occ.addCircleArc(q1, centre_tag, q2)]
    for loop in ([line(p0, q0), arcs[0], line(q1, p1), line(p1, p0)],
                 [line(p1, q1), arcs[1], line(q2, p2), line(p2, p1)]):
        faces.append(occ.addPlaneSurface([occ.addCurveLoop(loop)]))
    return faces


def square_cup_tools(path: str | os.PathLike[str] | None = None, *, thickness: float = 0.81,
                     punch_half: float = 35.0, punch_corner: float = 10.0,
                     punch_nose: float = 8.0, punch_height: float = 50.0,
                     die_half: float = 37.235, die_corner: float = 12.235,
                     die_radius: float = 5.0, die_depth: float = 50.0,
                     holder_half: float = 44.235, holder_edge: float = 2.0,
                     outer_half: float = 105.0, holder_gap: float = 0.0,
                     margin: float = 3.0) -> dict[str, list[int]]:
    """The punch, die and blank-holder of a square cup drawing (the Numisheet'93 square cup,
    benchmarks/square_cup), quarter model, the square's sides along x and y.

    The flat blank lies on 0 <= z <= ``thickness``, its corner at the origin on the cup's
    axis. The punch (above): a square of half-width ``punch_half``, plan corner radius
    ``punch_corner``, nose radius ``punch_nose``, its flat end at z = ``thickness``, its
    walls ``punch_height`` high above the nose. The die (below): an opening of half-width
    ``die_half`` with plan corner radius ``die_corner``, its profile radius ``die_radius``
    from the flat z = 0 down to a wall ``die_depth`` deep, the flat reaching
    ``outer_half``. The blank-holder (above): a flat ``holder_gap`` above the blank from
    ``holder_half`` (its corners concentric with the die's) to ``outer_half``, its inner
    edge rounded by ``holder_edge``. Every face reaches ``margin`` beyond the symmetry
    planes x = 0 and y = 0. Returns the face tags by tool: punch (its flat end in eight
    faces, then nose and wall swept), die (wall, profile radius, flat), holder (edge,
    flat), each swept face as :func:`sweep_profile` gives them.
    """
    import gmsh

    t = thickness
    punch_c, die_c = punch_half - punch_corner, die_half - die_corner
    flat = punch_corner - punch_nose
    holder_r = holder_half - die_c
    if not (t > 0.0 and 0.0 < punch_nose < punch_corner and punch_c > 0.0 and die_c > 0.0
            and punch_half + t <= die_half and die_radius > 0.0 and punch_height > 0.0
            and die_depth > 0.0 and 0.0 < holder_edge
            and die_corner + die_radius <= holder_r - holder_edge
            and holder_half < outer_half and holder_gap >= 0.0 and 0.0 < margin < punch_c):
        raise ValueError("square cup tools: the dimensions do not fit together")
    outer_die = outer_half - die_c
    shoulder = die_corner + die_radius
    lift = t + holder_gap
    profiles: dict[str, list[Piece]] = {
        "punch": [("arc", (flat, t), (flat, t + punch_nose), (punch_corner, t + punch_nose)),
                  ("line", (punch_corner, t + punch_nose),
                   (punch_corner, t + punch_nose + punch_height))],
        "die": [("line", (die_corner, -die_radius - die_depth), (die_corner, -die_radius)),
                ("arc", (die_corner, -die_radius), (shoulder, -die_radius), (shoulder, 0.0)),
                ("line", (shoulder, 0.0), (outer_die, 0.0))],
        "holder": [("arc", (holder_r - holder_edge, lift + holder_edge),
                    (holder_r, lift + holder_edge), (holder_r, lift)),
                   ("line", (holder_r, lift), (outer_die, lift))],
    }
    faces = {"punch": _rounded_flat(punch_c, flat, t, margin)
             + sweep_profile(profiles["punch"], punch_c, margin),
             "die": sweep_profile(profiles["die"], die_c, margin),
             "holder": sweep_profile(profiles["holder"], die_c, margin)}
    gmsh.model.occ.synchronize()
    write_cad(path)
    return faces
