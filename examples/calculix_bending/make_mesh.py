"""Write the meshes of the CalculiX bending example: blank.inp (the strip), punch.inp and
die.inp (the rigid tools, one layer of C3D8 bricks behind their working faces, which CalculiX
runs; ddpy reads their *SURFACE). Run from this folder: python make_mesh.py.

Units mm. Half of a 60 x 2 x 1 mm strip (symmetry at x = 0, plane strain in y), bent by a
punch of radius 4 mm over a die of shoulder radius 3 mm whose opening is 22 mm wide.
"""

from __future__ import annotations

import math
from pathlib import Path

HERE = Path(__file__).resolve().parent
LENGTH, WIDTH, THICKNESS = 30.0, 2.0, 1.0
NX, NY, NZ = 30, 1, 2
PUNCH_RADIUS, DIE_RADIUS, DIE_EDGE = 4.0, 3.0, 11.0
ARC_SEGMENTS = 6                   # per 90 degrees of each tool's radius
BACK = 0.5                         # depth of the tool bricks behind the working face
TOOL_Y = (-1.0, 3.0)


def blank() -> str:
    lines = ["** The blank: half of a 60 x 2 x 1 mm strip, C3D8I, node id 1 + i + 31 (j + 2 k).",
             "*NODE, NSET=BLANK_NODES"]
    ident = {}
    for k in range(NZ + 1):
        for j in range(NY + 1):
            for i in range(NX + 1):
                n = 1 + i + (NX + 1) * (j + (NY + 1) * k)
                ident[i, j, k] = n
                lines.append(f"{n}, {LENGTH * i / NX:.6g}, {WIDTH * j / NY:.6g}, "
                             f"{THICKNESS * k / NZ:.6g}")
    lines.append("*ELEMENT, TYPE=C3D8I, ELSET=BLANK")
    e = 0
    for k in range(NZ):
        for j in range(NY):
            for i in range(NX):
                e += 1
                c = [ident[i, j, k], ident[i + 1, j, k], ident[i + 1, j + 1, k],
                     ident[i, j + 1, k]]
                c += [ident[a, b, k + 1] for a, b in ((i, j), (i + 1, j), (i + 1, j + 1),
                                                      (i, j + 1))]
                lines.append(f"{e}, " + ", ".join(map(str, c)))
    top = [e for e in range(1, NX * NY * NZ + 1) if e > NX * NY * (NZ - 1)]
    lines += ["*ELSET, ELSET=BLANK_TOP_EL, GENERATE", f"{top[0]}, {top[-1]}, 1",
              "*ELSET, ELSET=BLANK_BOT_EL, GENERATE", f"1, {NX * NY}, 1",
              "*NSET, NSET=XSYM"]
    lines += [", ".join(str(ident[0, j, k]) for j in range(NY + 1)) for k in range(NZ + 1)]
    lines += ["*NSET, NSET=YSYM"]
    row = [ident[i, j, k] for k in range(NZ + 1) for j in (0, NY) for i in range(NX + 1)]
    lines += [", ".join(map(str, row[s:s + 8])) for s in range(0, len(row), 8)]  # ccx: <= 16
    lines += ["*NSET, NSET=CENTRE", ", ".join(str(ident[0, j, 0]) for j in range(NY + 1))]
    return "\n".join(lines) + "\n"


def profile(points: list[tuple[float, float, float, float]], name: str, first_node: int,
            first_element: int) -> str:
    """A tool brick layer under a profile of (x, z, nx, nz) points (n towards the blank)."""
    lines = [f"*NODE, NSET={name}_NODES"]
    ids = {}
    n = first_node
    for p, (x, z, nx, nz) in enumerate(points):
        for q, y in enumerate(TOOL_Y):
            for layer, depth in ((0, BACK), (1, 0.0)):
                ids[p, q, layer] = n
                xb, zb = (round(v, 9) + 0.0 for v in (x - depth * nx, z - depth * nz))
                lines.append(f"{n}, {xb:.9g}, {y:.9g}, {zb:.9g}")
                n += 1
    lines.append(f"*ELEMENT, TYPE=C3D8, ELSET={name}")
    e = first_element
    for p in range(len(points) - 1):
        x0, z0, nx, nz = points[p]
        x1, z1 = points[p + 1][:2]
        # (tangent along the profile) x (+y) . n > 0: counter-clockwise seen from the blank.
        turn = (-(z1 - z0)) * nx + (x1 - x0) * nz
        quad = [(p, 0), (p + 1, 0), (p + 1, 1), (p, 1)] if turn > 0 else \
            [(p, 0), (p, 1), (p + 1, 1), (p + 1, 0)]
        nodes = [ids[a, b, 0] for a, b in quad] + [ids[a, b, 1] for a, b in quad]
        lines.append(f"{e}, " + ", ".join(map(str, nodes)))
        e += 1
    return "\n".join(lines) + "\n"


def punch() -> str:
    z0 = THICKNESS + PUNCH_RADIUS
    pts = []
    for s in range(ARC_SEGMENTS + 1):
        a = -math.pi / 2 + (math.pi / 2) * s / ARC_SEGMENTS
        pts.append((PUNCH_RADIUS * math.cos(a), z0 + PUNCH_RADIUS * math.sin(a),
                    math.cos(a), math.sin(a)))
    pts += [(PUNCH_RADIUS, z0 + 5.0 * s, 1.0, 0.0) for s in (1, 2)]
    text = "** The punch: radius 4 mm, touching the blank's top at x = 0.\n"
    return text + profile(pts, "PUNCH", 1001, 1001)


def die() -> str:
    cx, cz = DIE_EDGE + DIE_RADIUS, -DIE_RADIUS
    pts = [(DIE_EDGE, cz - 10.0 + 5.0 * s, -1.0, 0.0) for s in (0, 1)]
    for s in range(ARC_SEGMENTS + 1):
        a = math.pi - (math.pi / 2) * s / ARC_SEGMENTS
        pts.append((cx + DIE_RADIUS * math.cos(a), cz + DIE_RADIUS * math.sin(a),
                    math.cos(a), math.sin(a)))
    pts += [(cx + 5.0 * s, 0.0, 0.0, 1.0) for s in (1, 2, 3, 4)]
    text = "** The die: shoulder radius 3 mm, opening 22 mm, top at z = 0.\n"
    return text + profile(pts, "DIE", 2001, 2001)


if __name__ == "__main__":
    for name, text in (("blank.inp", blank()), ("punch.inp", punch()), ("die.inp", die())):
        (HERE / name).write_text(text)
        print(f"wrote {HERE / name}")
