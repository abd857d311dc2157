"""Write the tool files of the example cases: profiles in the x-z plane (straight segments and
circular arcs) extruded along y into Nagata meshes with exact normals, in the ddpy tool file
format (docs/tool-files.md). Tool models of real cases come from CAD (``ddpy tools build``);
these are small enough to read.

    python examples/make_tools.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def line(p, q, normal, n=1):
    """Points and normals of a straight segment from p to q (x, z), n patches."""
    t = np.linspace(0.0, 1.0, n + 1)[:, None]
    points = (1 - t) * np.array(p, float) + t * np.array(q, float)
    return points, np.repeat(np.array([normal], float), n + 1, axis=0)


def arc(centre, radius, start, stop, n, outward=True):
    """Points and normals of a circular arc (angles in degrees from +x towards +z)."""
    a = np.radians(np.linspace(start, stop, n + 1))
    direction = np.column_stack([np.cos(a), np.sin(a)])
    return np.array(centre, float) + radius * direction, direction if outward else -direction


def profile(*pieces):
    """Join pieces, dropping the repeated first point of each next piece."""
    points, normals = [pieces[0][0]], [pieces[0][1]]
    for p, n in pieces[1:]:
        points.append(p[1:])
        normals.append(n[1:])
    return np.vstack(points), np.vstack(normals)


def write(path: Path, name: str, points, normals, width: float, comment: str) -> None:
    """Extrude the profile over 0 <= y <= width; faces counter-clockwise seen from the normals."""
    k = len(points)
    vertices = [(x, y, z) for y in (0.0, width) for x, z in points]
    normal3 = [(nx, 0.0, nz) for nx, nz in normals]
    faces = []
    for i in range(k - 1):
        quad = [i, i + 1, k + i + 1, k + i]
        a = np.array(vertices[quad[1]]) - np.array(vertices[quad[0]])
        b = np.array(vertices[quad[3]]) - np.array(vertices[quad[0]])
        mid = np.array(normal3[i]) + np.array(normal3[i + 1])
        if np.dot(np.cross(a, b), mid) < 0:
            quad = quad[::-1]
        corner_normals = [v % k for v in quad]
        faces.append(quad + corner_normals + [1])
    fmt = lambda v: " ".join(f"{c:.10g}" if abs(c) > 1e-14 else "0" for c in v)  # noqa: E731
    text = [f"# {comment}", "# written by examples/make_tools.py; units mm", "ddpy-tool 1",
            f"name {name}", "description nagata", "units mm", f"vertices {len(vertices)}"]
    text += [fmt(v) for v in vertices]
    text += [f"normals {len(normal3)}"] + [fmt(n) for n in normal3]
    text += [f"faces {len(faces)}",
             "# 4 vertices, 4 corner normals, CAD face; counter-clockwise seen from the normals"]
    text += [" ".join(str(i) for i in f) for f in faces]
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(text) + "\n")
    print(f"wrote {path}")


def bending() -> None:
    """Unconstrained cylindrical bending, quarter model (a reconstruction of the paper's Fig. 6):
    punch radius 23.5 mm over the blank's top at x = 0; die shoulder radius 4 mm, centre
    29.5 mm from the symmetry plane, under the blank's bottom at z = 0."""
    folder = HERE / "bending" / "tools"
    r, zc = 23.5, 1.0 + 23.5
    points, normals = arc((0.0, zc), r, -90.0, 0.0, 4)
    write(folder / "punch.tool", "punch", points, normals, 20.0,
          "cylindrical punch R 23.5 mm, quarter, 4 Nagata patches per arc, normals down")
    pts, nrm = profile(line((25.5, -20.0), (25.5, -4.0), (-1.0, 0.0), 2),
                       arc((29.5, -4.0), 4.0, 180.0, 90.0, 4),
                       line((29.5, 0.0), (70.0, 0.0), (0.0, 1.0), 2))
    write(folder / "die.tool", "die", pts, nrm, 20.0,
          "open die: inner wall, shoulder R 4 mm (4 Nagata patches), flat; normals up")


def redraw() -> None:
    """A strip drawn through a die under a blank-holder held at a gap, then further without
    the holder (plane strain, half model): die under the blank, holder and punch above."""
    folder = HERE / "strip_draw" / "tools"
    die = profile(line((20.0, -20.0), (20.0, -5.0), (-1.0, 0.0), 2),
                  arc((25.0, -5.0), 5.0, 180.0, 90.0, 3),
                  line((25.0, 0.0), (60.0, 0.0), (0.0, 1.0), 2))
    write(folder / "die.tool", "die", *die, 6.0, "die: wall, shoulder R 5 mm, flange; normals up")
    # The inner edge is rounded as on a real holder: the strip leaves the holder over it.
    # Cut square at x = 25 mm, a Gauss point or node of the strip sliding past the edge
    # dropped its contact force at once, and a holder pressed with a force (its position
    # solved for) saw its reaction jump by a third (docs/theory/contact.md, "The barrier").
    holder = profile(line((60.0, 1.0), (25.0, 1.0), (0.0, -1.0), 2),
                     arc((25.0, 3.0), 2.0, 270.0, 180.0, 3))
    write(folder / "holder.tool", "holder", *holder, 6.0,
          "blank-holder: flat, inner edge R 2 mm; normals down")
    punch = profile(line((0.0, 1.0), (12.0, 1.0), (0.0, -1.0), 2),
                    arc((12.0, 6.0), 5.0, -90.0, 0.0, 3),
                    line((17.0, 6.0), (17.0, 30.0), (1.0, 0.0), 2))
    write(folder / "punch.tool", "punch", *punch, 6.0,
          "punch: flat, corner R 5 mm, side wall; normals out")


if __name__ == "__main__":
    bending()
    redraw()
