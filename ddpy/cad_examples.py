"""Small CAD models built with gmsh's OpenCASCADE, for the benchmark, tests and examples.

Each function adds the faces to the current gmsh model (inside :func:`ddpy.cad.gmsh_session`)
and, given a path, writes them as STEP (or IGES, BREP by the suffix).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ddpy.cad import quiet

__all__ = ["bending_tools", "cylinder_segment", "cylindrical_punch", "die_profile", "sphere_patch",
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
                  shoulder_radius: float = 4.0, shoulder_x: float = 29.5,
                  thickness: float = 1.0, die_end: float = 70.0, wall_depth: float = 20.0,
                  width: tuple[float, float] = (-5.0, 20.0)) -> dict[str, list[int]]:
    """The tools of the unconstrained cylindrical bending benchmark (Numisheet 2002 B),
    quarter model, as reconstructed in design.md (the paper's Fig. 6 is not in its text).

    Symmetry planes x = 0 and y = 0; the flat blank lies on 0 <= z <= ``thickness``. The punch
    is a quarter cylinder of radius ``punch_radius``, axis along y through x = 0,
    z = thickness + punch_radius, from its lowest line (x = 0, z = thickness) up to x =
    punch_radius. The open die (no bottom) is an inner wall x = shoulder_x - shoulder_radius
    from z = -shoulder_radius - wall_depth up to the shoulder, a quarter cylinder of radius
    ``shoulder_radius`` centred at (shoulder_x, -shoulder_radius), and a flat top z = 0 out to
    x = ``die_end``. Every face spans ``width`` along y. Returns the face tags by tool
    ({"punch": [...], "die": [wall, shoulder, flat]}).
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
