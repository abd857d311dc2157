"""The same deck for ddpy and CalculiX: the quarter Numisheet 2002 BM-B bending blank of
60 x 6 x 2 elements, written as ddpy cases and, from ddpy's facet cases, as CalculiX decks.

``prepare(root)`` writes, under ``root`` (git-ignored):

- ``meshes/coarse.msh``: benchmarks/cylindrical_bending/make_case.py's ``coarse_mesh`` with
  60 x 6 x 2 solid-shells;
- ``tools/{punch,die}.{nagata,facets}.tool``: that benchmark's tool files (its coarse facets
  are the Nagata mesh read with ``description facets``, its fine facets the ``.facets`` files);
- ``cases/coarse/{nagata,facets_coarse,facets_fine}/``: its case decks (make_case.write_case),
  the material changed to von Mises with the Swift curve sampled as a table (HARDENING), the
  one CalculiX's ``*PLASTIC`` reads: CalculiX has no Hill'48 but through a user material;
- ``ccx/{facets_coarse,facets_fine}/same_deck.inp``: ``ccx_deck`` of each facet case.

``ccx_deck(case)`` writes the CalculiX deck from a ddpy case (ddpy.io.decks.read_case): the
blank's nodes and hexahedra with ddpy's ids as C3D8I, the symmetry planes, each rigid tool as
one C3D8 brick behind each face of its facet model (the face's four vertices, exactly as in
the tool file, are the brick's S2 face; the back face BACK mm behind it), face-to-face
penalty contact (``TYPE=SURFACE TO SURFACE``), the tool motions of the forming phase in one
step at the phase's largest increment and the springback phase as a step without the
contact pairs.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
BENDING = HERE.parent / "cylindrical_bending"
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import load_module  # noqa: E402

make_case = load_module(BENDING / "make_case.py", "bending_make_case")

#: The blank: 60 x 6 x 2 elements of the 60 x 15 x 1 mm quarter.
NX, NY, LAYERS = 60, 6, 2
#: The ddpy models run: Nagata patches, the same mesh flat (the coarse facets) and the fine
#: facets (make_case.FACETS_PER_ARC per 90 degrees of arc).
MODELS = ("nagata", "facets_coarse", "facets_fine")
#: The facet models CalculiX runs, each with the vertices of ddpy's case of that name. The
#: fine facets are the nearest CalculiX comes to the smooth tools: on the punch (radius
#: 23.5 mm) a facet's sagitta is 8 um, on the die's 4 mm shoulder 1.4 um, below ddpy's
#: penetration limit (0.01 mm); the coarse facets' are 0.45 and 0.08 mm.
CCX_MODELS = ("facets_coarse", "facets_fine")
#: The mesh name of the cases (make_case's: its increment limits for the coarse blank).
MESH = "coarse"
#: Brick depth behind a tool face, mm (the brick only carries the face).
BACK = 1.0
#: Swift's curve (make_case's steel) sampled at these plastic strains, the table both codes
#: read: dense where the curve bends most (small strains), to 1 (the bend reaches about 0.1).
TABLE_STRAINS = (0.0, *(float(f"{e:.3g}") for e in np.geomspace(2e-4, 1.0, 39)))
#: make_case's Swift curve of the steel: K (MPa), eps0, n.
SWIFT = (645.3, 0.0102, 0.252)
#: CalculiX's face-to-face penalty: pressure per overclosure (MPa/mm), friction stick slope
#: (MPa/mm). The stick slope is examples/calculix_bending's. Its penalty, 1e5 MPa/mm, stopped
#: CalculiX at 8.38 mm of stroke in every session ("increment size smaller than minimum"),
#: and frictionless as well (8.32 mm); at 1e4 it passed on (measured 2026-12-06). 1e4 MPa/mm
#: holds 100 MPa of contact pressure at 0.01 mm of overclosure, ddpy's 1 % penetration limit.
PENALTY, STICK_SLOPE = 1.0e4, 5000.0
#: The penalty of the sessions before 2026-12-06 (MPa/mm) and the stroke (mm) where CalculiX
#: stopped with it, for the report.
STIFFER_PENALTY, STIFFER_PENALTY_STOP = 1.0e5, 8.38
#: Springs (N/mm) that hold the blank's rigid-body mode along z for CalculiX before the
#: tools grip it; ddpy's convert skips them. They tie the centre line to fixed ground, so
#: the punch also pushes them down: at 1 N/mm (examples/numisheet2002_bending's value) the
#: three carried 3 N per mm of the centre's travel, 21 N at 7 mm of stroke, the whole gap
#: between CalculiX's punch force and ddpy's there (62.1 against 41.0 N). At 1e-3 N/mm they
#: carry under 0.1 N over the stroke; the report gives their largest reaction (the ground
#: nodes' forces, printed in the forming step).
SPRING = 1.0e-3
#: Node and element ids of the tools, reference and ground nodes (the blank keeps ddpy's):
#: small, since CalculiX allocates arrays as long as the largest id.
PUNCH_FIRST, DIE_FIRST, REF_FIRST, GROUND_FIRST = 3001, 4001, 9001, 9101
#: CalculiX reads a number from 20 characters at most.
FIELD = 20
#: The blank's end node, for the springback: x = 60, y = 0, z = 0.
TIP = (make_case.LENGTH, 0.0, 0.0)


def sagitta(radius: float, per_arc: int) -> float:
    """How far a facet's middle lies inside an arc of ``radius`` cut into ``per_arc`` facets
    per 90 degrees (mm)."""
    return radius * (1.0 - np.cos(np.pi / 4.0 / per_arc))


def hardening_table() -> list[tuple[float, float]]:
    """(plastic strain, yield stress) of make_case's Swift curve at TABLE_STRAINS."""
    k, eps0, n = SWIFT
    assert f"K {k}  eps0 {eps0}  n {n}" in make_case.MATERIAL  # the benchmark's steel
    return [(e, float(f"{k * (eps0 + e) ** n:.2f}")) for e in TABLE_STRAINS]


def material_text() -> str:
    """material.dat of the cases: von Mises, the same table as the CalculiX deck."""
    rows = "\n".join(f"  {e:g} {y:g}" for e, y in hardening_table())
    return ("# ddpy material deck.  Units MPa.  Written by benchmarks/calculix_same_deck/"
            "deck.py\n# High strength steel of Numisheet 2002 BM-B, von Mises (CalculiX's "
            "*PLASTIC): Swift's\n# curve K 645.3 eps0 0.0102 n 0.252 sampled, the table of "
            "the CalculiX deck.\nelastic    E 210000  nu 0.3\nyield      vonmises\n"
            f"hardening  table {len(TABLE_STRAINS)}\n{rows}\n")


#: The die's shoulder centre, mm from the symmetry plane: the bending benchmark's die before
#: it was fitted to the paper's contact angles (clearance 2 mm), the die of the kept runs. A
#: comparison of two codes on one deck needs one die, not the paper's, so it stays.
SHOULDER_X = 29.5


def prepare(root: Path, tools: Path = HERE / "tools") -> dict[str, Path]:
    """Write the mesh, tools, ddpy cases and the CalculiX decks under ``root``; return the
    case folder of each model and the deck of each of CCX_MODELS (key "ccx_" + model).
    ``tools``: where the bending benchmark's tool files with this deck's die (SHOULDER_X)
    are, built there by its make_case.build_tools when missing."""
    files = [f"{t}.{m}.tool" for t in ("punch", "die") for m in ("nagata", "facets")]
    if not all((tools / f).is_file() for f in files):
        make_case.build_tools(tools, shoulder_x=SHOULDER_X)
    (root / "tools").mkdir(parents=True, exist_ok=True)
    for file in files:
        shutil.copyfile(tools / file, root / "tools" / file)
    make_case.coarse_mesh(root / "meshes" / f"{MESH}.msh", nx=NX, ny=NY, layers=LAYERS)
    out: dict[str, Path] = {}
    for model in MODELS:
        folder = make_case.write_case(root / "cases" / MESH / model, model, MESH)
        (folder / "material.dat").write_text(material_text())
        out[model] = folder
    for model in CCX_MODELS:
        deck = root / "ccx" / model / "same_deck.inp"
        deck.parent.mkdir(parents=True, exist_ok=True)
        deck.write_text(ccx_deck(out[model]))
        out[f"ccx_{model}"] = deck
    return out


def describe(folder: Path) -> dict[str, object]:
    """What the report states of the case in ``folder``: its blank's elements and nodes, its
    tools' faces, friction, stroke and largest increment."""
    from ddpy.io.decks import read_case
    from ddpy.io.toolfile import read_tool

    case = read_case(folder)
    forming = case.control.phases[0]
    return {"elements": int(case.mesh.n_elements), "nodes": int(case.mesh.n_nodes),
            "faces": {t.name: int(read_tool(t.file).surface.n_patches) for t in case.tools},
            "friction": [float(t.friction) for t in case.tools],
            "stroke": max(float(np.linalg.norm(m.displacement)) for m in forming.motions),
            "max_increment": float(forming.max_increment),
            "springback_increments": int(case.control.phases[1].increments),
            "E": float(case.material.material.E), "nu": float(case.material.material.nu),
            "springs": len(case.boundary.nodesets["centre"].nodes)}


def _lines(ids: list[int], per_line: int = 16) -> list[str]:
    return [", ".join(map(str, ids[i:i + per_line])) for i in range(0, len(ids), per_line)]


def _exact(x: float) -> str:
    """A coordinate as CalculiX reads it back: the shortest text of the same double (repr),
    else (a tiny value such as -8.9e-16 needs 22 characters, a value such as -0.0412... with
    17 digits 21) the most digits that fit in FIELD characters: within 1e-17 mm on these
    tools."""
    text = repr(float(x))
    digits = 17
    while len(text) > FIELD:
        digits -= 1
        text = f"{x:.{digits}g}"
    return text


def tool_bricks(vertices: np.ndarray, faces: np.ndarray, first: int
                ) -> tuple[list[str], list[str], dict[int, int]]:
    """C3D8 bricks behind the quadrilateral faces of a facet model (faces counter-clockwise
    seen from the blank side, as tool files have them): node lines, element lines, and the
    node id of each vertex. Nodes 5-8 of a brick are its face (S2, outward towards the
    blank), 1-4 the same vertices BACK mm behind, along the mean of the faces' normals."""
    if (faces < 0).any():
        raise ValueError("the tool has triangles: the deck writes quadrilateral faces only")
    a, b, c, d = (vertices[faces[:, i]] for i in range(4))
    normal = np.cross(c - a, d - b)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    at_vertex = np.zeros_like(vertices)
    np.add.at(at_vertex, faces.ravel(), np.repeat(normal, 4, axis=0))
    used = np.unique(faces)
    at_vertex[used] /= np.linalg.norm(at_vertex[used], axis=1)[:, None]
    front = {int(v): first + k for k, v in enumerate(used)}
    back = {int(v): first + len(used) + k for k, v in enumerate(used)}
    nodes = [f"{front[v]}, " + ", ".join(_exact(x) for x in vertices[v]) for v in front]
    nodes += [f"{back[v]}, " + ", ".join(_exact(x) for x in vertices[v] - BACK * at_vertex[v])
              for v in back]
    elements = [f"{first + e}, " + ", ".join(str(back[int(v)]) for v in f) + ", "
                + ", ".join(str(front[int(v)]) for v in f) for e, f in enumerate(faces)]
    return nodes, elements, front


def ccx_deck(folder: Path) -> str:
    """The CalculiX deck of the ddpy case in ``folder`` (see the module's docstring)."""
    from ddpy.io.decks import read_case
    from ddpy.io.toolfile import read_tool
    from ddpy.model.material import HardeningTable

    case = read_case(folder)
    mesh, bc = case.mesh, case.boundary
    ids = [int(i) for i in mesh.node_ids]
    hardening = case.material.material.hardening
    if not isinstance(hardening, HardeningTable):
        raise ValueError(f"{folder}: the deck needs a hardening table (CalculiX's *PLASTIC)")
    forming, springback = case.control.phases
    w = ["** Numisheet 2002 BM-B bending, quarter model: the same deck as ddpy's case",
         f"** {folder.name} (benchmarks/calculix_same_deck/deck.py). Units mm, N, MPa.",
         "*HEADING", case.control.title, "*NODE, NSET=BLANK_NODES"]
    w += [f"{n}, " + ", ".join(_exact(x) for x in xyz) for n, xyz in zip(ids, mesh.nodes,
                                                                           strict=True)]
    w.append("*ELEMENT, TYPE=C3D8I, ELSET=BLANK")
    w += [f"{int(e)}, " + ", ".join(str(ids[n]) for n in nodes)
          for e, nodes in zip(mesh.element_ids, mesh.elements, strict=True)]
    # The layers facing the tools: an element's top face (S2, nodes 5-8) on z = thickness,
    # its bottom face (S1, nodes 1-4) on z = 0.
    z = mesh.nodes[:, 2]
    top = [int(e) for e, n in zip(mesh.element_ids, mesh.elements, strict=True)
           if np.allclose(z[n[4:]], z.max())]
    bottom = [int(e) for e, n in zip(mesh.element_ids, mesh.elements, strict=True)
              if np.allclose(z[n[:4]], z.min())]
    w += ["*ELSET, ELSET=BLANK_TOP", *_lines(top), "*ELSET, ELSET=BLANK_BOTTOM",
          *_lines(bottom)]
    sets: dict[str, list[int]] = {}
    for c in bc.constraints:
        if c.symmetry:
            axis = "XYZ"[int(c.components[0])]
            sets[f"{axis}SYM"] = sorted(ids[n] for n in c.nodes)
    for name, ns in bc.nodesets.items():
        sets[name.upper()] = sorted(ids[n] for n in ns.nodes)
    tip = int(np.argmin(np.linalg.norm(mesh.nodes - np.array(TIP), axis=1)))
    sets["TIP"] = [ids[tip]]
    for name, members in sets.items():
        w += [f"*NSET, NSET={name}", *_lines(members)]
    refs = {}
    for k, tool in enumerate(case.tools):
        name = tool.name.upper()
        surface = read_tool(tool.file).surface
        first = (PUNCH_FIRST, DIE_FIRST)[k] if k < 2 else DIE_FIRST + 1000 * (k - 1)
        nodes, elements, _ = tool_bricks(np.asarray(surface.vertices),
                                         np.asarray(surface.faces), first)
        w += [f"** {tool.name}: one brick behind each face of {tool.file.name} "
              f"({len(elements)} faces).", f"*NODE, NSET={name}_NODES", *nodes,
              f"*ELEMENT, TYPE=C3D8, ELSET={name}", *elements]
        ref, rot = REF_FIRST + 2 * k, REF_FIRST + 2 * k + 1
        centre = np.asarray(surface.vertices).mean(axis=0)
        w += ["*NODE", f"{ref}, " + ", ".join(f"{x:.6g}" for x in centre),
              f"{rot}, " + ", ".join(f"{x:.6g}" for x in centre),
              f"*NSET, NSET={name}_REF", str(ref), f"*NSET, NSET={name}_ROT", str(rot)]
        refs[tool.name] = name
    # Springs to fixed ground nodes along z under the centre line (CalculiX only).
    centre = sets.get("CENTRE", [])
    ground = [GROUND_FIRST + j for j in range(len(centre))]
    w += ["** Rigid-body mode along z held by soft springs to ground nodes (ddpy skips them).",
          "*NODE"]
    w += [f"{g}, " + ", ".join(_exact(x) for x in mesh.nodes[ids.index(n)])
          for g, n in zip(ground, centre, strict=True)]
    w += ["*NSET, NSET=GROUND", *_lines(ground), "*ELEMENT, TYPE=SPRING2, ELSET=HOLD"]
    w += [f"{g}, {n}, {g}" for g, n in zip(ground, centre, strict=True)]
    w += ["*SPRING, ELSET=HOLD", "3, 3", f"{SPRING:g}"]
    elastic = case.material.material
    w += ["*MATERIAL, NAME=STEEL", "*ELASTIC", f"{elastic.E:g}, {elastic.nu:g}", "*PLASTIC"]
    w += [f"{y:g}, {e:g}" for e, y in zip(hardening.strains, hardening.stresses, strict=True)]
    w += ["*SOLID SECTION, ELSET=BLANK, MATERIAL=STEEL"]
    for k, tool in enumerate(case.tools):
        name = refs[tool.name]
        w += [f"*SOLID SECTION, ELSET={name}, MATERIAL=STEEL",
              f"*RIGID BODY, ELSET={name}, REF NODE={REF_FIRST + 2 * k}, "
              f"ROT NODE={REF_FIRST + 2 * k + 1}"]
    w += ["*SURFACE, NAME=BLANK_TOP_FACE, TYPE=ELEMENT", "BLANK_TOP, S2",
          "*SURFACE, NAME=BLANK_BOTTOM_FACE, TYPE=ELEMENT", "BLANK_BOTTOM, S1"]
    pairs = []
    for tool in case.tools:
        name = refs[tool.name]
        slave = "BLANK_TOP_FACE" if tool.side == "top" else "BLANK_BOTTOM_FACE"
        w += [f"*SURFACE, NAME={name}_FACE, TYPE=ELEMENT", f"{name}, S2"]
        pairs.append((slave, f"{name}_FACE", tool.friction, name))
    for slave, master, friction, name in pairs:
        w += [f"*CONTACT PAIR, INTERACTION={name}_CONTACT, TYPE=SURFACE TO SURFACE",
              f"{slave}, {master}", f"*SURFACE INTERACTION, NAME={name}_CONTACT",
              "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", f"{PENALTY:g}",
              "*FRICTION", f"{friction:g}, {STICK_SLOPE:g}"]
    w += ["** Symmetry (dofs: CalculiX 2.20 does not read XSYMM on solids); tools' rotations.",
          "*BOUNDARY"]
    w += [f"{axis}SYM, {i + 1}, {i + 1}" for i, axis in enumerate("XYZ") if f"{axis}SYM" in sets]
    w += ["GROUND, 1, 3"] + [f"{refs[t.name]}_ROT, 1, 3" for t in case.tools]
    moves = {m.tool: m.displacement for m in forming.motions}
    travel = max(float(np.linalg.norm(d)) for d in moves.values())
    fraction = forming.max_increment / travel
    w += [f"** {forming.name}: {travel:g} mm of travel, at most {forming.max_increment:g} mm "
          "an increment (ddpy's max_increment).", "*STEP, NLGEOM, INC=10000", "*STATIC",
          f"{fraction:.6g}, 1.0, {1e-3 * fraction:.6g}, {fraction:.6g}", "*BOUNDARY"]
    for tool in case.tools:
        d = moves.get(tool.name, (0.0, 0.0, 0.0))
        w += [f"{refs[tool.name]}_REF, {i + 1}, {i + 1}, {d[i]:g}" for i in range(3)]
    lead = refs[forming.lead] if forming.lead else refs[case.tools[0].name]
    w += [f"*NODE PRINT, NSET={lead}_REF", "U, RF", "*NODE PRINT, NSET=TIP", "U",
          "*NODE PRINT, NSET=GROUND", "RF", "*END STEP"]
    w += [f"** {springback.name}: the contact pairs removed, the centre line held along z "
          "where it is.", "*STEP, NLGEOM, INC=10000", "*STATIC",
          f"{1.0 / springback.increments:g}, 1.0"]
    for slave, master, _, _ in pairs:
        w += ["*MODEL CHANGE, TYPE=CONTACT PAIR, REMOVE", f"{slave}, {master}"]
    w += ["*BOUNDARY, FIXED"]
    w += [f"{name.upper()}, {int(c) + 1}, {int(c) + 1}" for con in bc.constraints
          if springback.name in con.phases for name, ns in bc.nodesets.items()
          if np.array_equal(ns.nodes, con.nodes) for c in con.components]
    w += ["*NODE PRINT, NSET=TIP", "U", "*END STEP"]
    return "\n".join(w) + "\n"


if __name__ == "__main__":
    for what, path in prepare(HERE / "work").items():
        print(f"{what}: {path}")
