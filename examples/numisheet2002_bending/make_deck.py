"""Write bending.inp: the unconstrained cylindrical bending of the Numisheet 2002 benchmark
(the blank and tools of ddpy's built-in case, benchmarks/cylindrical_bending) as a CalculiX
deck. Run from this folder: python make_deck.py.

Quarter model (symmetry x = 0 and y = 0) of the 120 x 30 x 1 mm strip: 60 x 15 x 1 mm, 30 x 3 x
2 C3D8I. The punch (radius 23.5 mm) and the open die (shoulder radius 4 mm at x = 29.5 mm) are
CalculiX rigid bodies of one layer of C3D8 bricks behind their working faces. Nothing holds
the blank along z before the tools grip it, so four SPRING2 elements of SPRING N/mm tie its
centre line to fixed ground nodes along z, as a CalculiX model of this benchmark does: they
hold the rigid-body mode. The punch pushes the centre down with them, so they take SPRING N
per mm of its travel out of the punch force: at 1 N/mm, 114 N at the end of the 28.5 mm
stroke, more than the force itself; at 1e-3 N/mm about 0.1 N. Von Mises with the Swift curve of the
benchmark's steel sampled as a *PLASTIC table (the deck has no Hill'48: CalculiX's needs an
*ORIENTATION and an anisotropic yield card ddpy does not read).
"""

from __future__ import annotations

import math
from pathlib import Path

HERE = Path(__file__).resolve().parent
#: Stiffness of the springs under the centre line, N/mm (the module's docstring says why so
#: soft).
SPRING = 1e-3
LENGTH, WIDTH, THICKNESS = 60.0, 15.0, 1.0
NX, NY, NZ = 30, 3, 2
PUNCH_RADIUS, SHOULDER_RADIUS, SHOULDER_X = 23.5, 4.0, 29.5
STROKE, FRICTION = 28.5, 0.148
TOOL_Y = (-5.0, 20.0)
BACK = 0.5            # brick depth behind a working face
K, EPS0, N = 645.3, 0.0102, 0.252


def _brick(front: list[tuple[float, float]], normals: list[tuple[float, float]],
           first_node: int, first_element: int) -> tuple[list[str], list[str]]:
    """Bricks behind a profile of (x, z) points (the working face, normals towards the
    blank), extruded along y over TOOL_Y: nodes 1-4 at the back, 5-8 on the working face."""
    nodes, elements = [], []
    ident = {}
    n = first_node
    for k, ((x, z), (nx, nz)) in enumerate(zip(front, normals, strict=True)):
        for side, depth in ((0, BACK), (1, 0.0)):
            for j, y in enumerate(TOOL_Y):
                ident[k, side, j] = n
                nodes.append(f"{n}, {x - depth * nx:.6f}, {y:.6f}, {z - depth * nz:.6f}")
                n += 1
    e = first_element
    for k in range(len(front) - 1):
        back = [ident[k, 0, 0], ident[k + 1, 0, 0], ident[k + 1, 0, 1], ident[k, 0, 1]]
        face = [ident[k, 1, 0], ident[k + 1, 1, 0], ident[k + 1, 1, 1], ident[k, 1, 1]]
        # Nodes 1-4 counter-clockwise seen from the working face: a positive volume.
        (x0, z0), (x1, z1) = front[k], front[k + 1]
        tangent, normal = (x1 - x0, z1 - z0), normals[k]
        if tangent[0] * normal[1] - tangent[1] * normal[0] < 0:   # (t x y) . n along y
            back, face = back[::-1], face[::-1]
        elements.append(f"{e}, " + ", ".join(map(str, back + face)))
        e += 1
    return nodes, elements


def _arc(cx: float, cz: float, r: float, a0: float, a1: float, count: int, inward: bool
         ) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    points, normals = [], []
    for i in range(count + 1):
        a = math.radians(a0 + (a1 - a0) * i / count)
        points.append((cx + r * math.cos(a), cz + r * math.sin(a)))
        s = -1.0 if inward else 1.0
        normals.append((s * math.cos(a), s * math.sin(a)))
    return points, normals


def _lines(ids: list[int]) -> list[str]:
    """A set's members, at most 16 a line (CalculiX 2.20 refuses longer lines)."""
    return [", ".join(map(str, ids[i:i + 16])) for i in range(0, len(ids), 16)]


def deck() -> str:
    w: list[str] = []
    w += ["** Numisheet 2002 benchmark B, unconstrained cylindrical bending: a CalculiX deck",
          "** written by make_deck.py for ddpy (docs/abaqus-import.md). Units mm, N, MPa.",
          "** Quarter model; SPRING2 elements hold the blank's rigid-body mode along z.",
          "*HEADING", "Numisheet 2002 unconstrained cylindrical bending, quarter model",
          "** The blank: node id 1 + i + 31 (j + 4 k).", "*NODE, NSET=BLANK_NODES"]
    ident = {}
    for k in range(NZ + 1):
        for j in range(NY + 1):
            for i in range(NX + 1):
                n = 1 + i + (NX + 1) * (j + (NY + 1) * k)
                ident[i, j, k] = n
                w.append(f"{n}, {LENGTH * i / NX:.6g}, {WIDTH * j / NY:.6g}, "
                         f"{THICKNESS * k / NZ:.6g}")
    w.append("*ELEMENT, TYPE=C3D8I, ELSET=BLANK")
    e = 0
    for k in range(NZ):
        for j in range(NY):
            for i in range(NX):
                e += 1
                c = [ident[i, j, k], ident[i + 1, j, k], ident[i + 1, j + 1, k],
                     ident[i, j + 1, k]]
                c += [ident[a, b, k + 1] for a, b in ((i, j), (i + 1, j), (i + 1, j + 1),
                                                      (i, j + 1))]
                w.append(f"{e}, " + ", ".join(map(str, c)))
    layer = NX * NY
    w += ["*ELSET, ELSET=BLANK_TOP, GENERATE", f"{e - layer + 1}, {e}, 1",
          "*ELSET, ELSET=BLANK_BOTTOM, GENERATE", f"1, {layer}, 1", "*NSET, NSET=XSYM"]
    w += _lines([ident[0, j, k] for k in range(NZ + 1) for j in range(NY + 1)])
    w += ["*NSET, NSET=YSYM"]
    w += _lines([ident[i, 0, k] for k in range(NZ + 1) for i in range(NX + 1)])
    w += ["*NSET, NSET=CENTRE"]
    w += _lines([ident[0, j, k] for j in range(NY + 1) for k in range(NZ + 1)])
    # The punch: a quarter cylinder from its lowest line (x = 0) up to x = R.
    zc = THICKNESS + PUNCH_RADIUS
    front, normals = _arc(0.0, zc, PUNCH_RADIUS, -90.0, 0.0, 24, inward=True)
    nodes, elements = _brick(front, normals, 5001, 5001)
    w += ["** The punch: radius 23.5 mm, its lowest line on the blank (z = 1).",
          "*NODE, NSET=PUNCH_NODES", *nodes, "*ELEMENT, TYPE=C3D8, ELSET=PUNCH", *elements]
    # The die: its inner wall, the shoulder, the flat top out to x = 70.
    inner = SHOULDER_X - SHOULDER_RADIUS
    wall = [(inner, -SHOULDER_RADIUS - 20.0 + 5.0 * i) for i in range(4)]
    arc, arc_normals = _arc(SHOULDER_X, -SHOULDER_RADIUS, SHOULDER_RADIUS, 180.0, 90.0, 12,
                            inward=False)
    flat = [(SHOULDER_X + 5.0 * i, 0.0) for i in range(1, 9)]
    front = wall + arc + flat
    normals = [(-1.0, 0.0)] * len(wall) + arc_normals + [(0.0, 1.0)] * len(flat)
    nodes, elements = _brick(front, normals, 6001, 6001)
    w += ["** The die: open, shoulder radius 4 mm at x = 29.5 mm, its top at z = 0.",
          "*NODE, NSET=DIE_NODES", *nodes, "*ELEMENT, TYPE=C3D8, ELSET=DIE", *elements]
    w += ["** Reference nodes of the rigid tools (a translation and a rotation node each).",
          "*NODE", f"9001, 0.0, 0.0, {zc:g}", f"9002, 0.0, 0.0, {zc:g}",
          f"9003, {SHOULDER_X:g}, 0.0, -4.0", f"9004, {SHOULDER_X:g}, 0.0, -4.0",
          "*NSET, NSET=PUNCH_REF", "9001", "*NSET, NSET=PUNCH_ROT", "9002",
          "*NSET, NSET=DIE_REF", "9003", "*NSET, NSET=DIE_ROT", "9004"]
    # The springs: the centre line's bottom nodes tied to ground nodes along z.
    centre = [ident[0, j, 0] for j in range(NY + 1)]
    w += ["** Rigid-body mode along z held by soft springs to fixed ground nodes.", "*NODE"]
    w += [f"{9100 + j}, 0.0, {WIDTH * j / NY:.6g}, 0.0" for j in range(NY + 1)]
    w += ["*NSET, NSET=GROUND", ", ".join(str(9100 + j) for j in range(NY + 1)),
          "*ELEMENT, TYPE=SPRING2, ELSET=HOLD"]
    w += [f"{9100 + j}, {n}, {9100 + j}" for j, n in enumerate(centre)]
    w += ["*SPRING, ELSET=HOLD", "3, 3", f"{SPRING:g}"]
    strains = [0.0, 0.005, 0.01, 0.02, 0.04, 0.07, 0.1, 0.15, 0.2, 0.3, 0.5, 1.0]
    w += ["** High strength steel of the benchmark: Swift K (eps0 + ep)^n, sampled.",
          "*MATERIAL, NAME=HSS", "*ELASTIC", "210000., 0.3", "*PLASTIC"]
    w += [f"{K * (EPS0 + ep) ** N:.2f}, {ep:g}" for ep in strains]
    w += ["*SOLID SECTION, ELSET=BLANK, MATERIAL=HSS",
          "*SOLID SECTION, ELSET=PUNCH, MATERIAL=HSS",
          "*SOLID SECTION, ELSET=DIE, MATERIAL=HSS",
          "*RIGID BODY, ELSET=PUNCH, REF NODE=9001, ROT NODE=9002",
          "*RIGID BODY, ELSET=DIE, REF NODE=9003, ROT NODE=9004",
          "*SURFACE, NAME=BLANK_TOP_FACE, TYPE=ELEMENT", "BLANK_TOP, S2",
          "*SURFACE, NAME=BLANK_BOTTOM_FACE, TYPE=ELEMENT", "BLANK_BOTTOM, S1",
          "*SURFACE, NAME=PUNCH_FACE, TYPE=ELEMENT", "PUNCH, S2",
          "*SURFACE, NAME=DIE_FACE, TYPE=ELEMENT", "DIE, S2",
          "*CONTACT PAIR, INTERACTION=LUBRICATED, TYPE=NODE TO SURFACE",
          "BLANK_TOP_FACE, PUNCH_FACE", "BLANK_BOTTOM_FACE, DIE_FACE",
          "*SURFACE INTERACTION, NAME=LUBRICATED",
          "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", "1.E6",
          "*FRICTION", f"{FRICTION:g}, 10000.",
          "** Symmetry (dofs 1 and 2: CalculiX does not read XSYMM on solids); tools held.",
          "*BOUNDARY", "XSYM, 1, 1", "YSYM, 2, 2", "GROUND, 1, 3", "PUNCH_ROT, 1, 3",
          "DIE_REF, 1, 3", "DIE_ROT, 1, 3",
          "** Forming: the punch goes down 28.5 mm, at most 0.114 mm an increment.",
          "*STEP, NLGEOM, INC=2000", "*STATIC", "0.004, 1.0, 1e-05, 0.004", "*BOUNDARY",
          "PUNCH_REF, 1, 2, 0.", f"PUNCH_REF, 3, 3, {-STROKE:g}", "*NODE PRINT, NSET=PUNCH_REF",
          "U, RF", "*END STEP",
          "** Springback: the contact pairs removed, the centre held in z where it is.",
          "*STEP, NLGEOM, INC=1000", "*STATIC", "0.05, 1.0",
          "*MODEL CHANGE, TYPE=CONTACT PAIR, REMOVE", "BLANK_TOP_FACE, PUNCH_FACE",
          "*MODEL CHANGE, TYPE=CONTACT PAIR, REMOVE", "BLANK_BOTTOM_FACE, DIE_FACE",
          "*BOUNDARY, FIXED", "CENTRE, 3, 3", "*NODE PRINT, NSET=CENTRE", "U", "*END STEP"]
    return "\n".join(w) + "\n"


if __name__ == "__main__":
    (HERE / "bending.inp").write_text(deck())
