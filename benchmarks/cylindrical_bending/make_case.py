"""Write the cases of the unconstrained cylindrical bending benchmark (paper Fig. 6-12).

    python benchmarks/cylindrical_bending/make_case.py            # both meshes
    python benchmarks/cylindrical_bending/make_case.py --mesh coarse
    python benchmarks/cylindrical_bending/make_case.py --default-case   # ddpy's built-in case

Writes, next to this script (all generated, git-ignored):

- ``tools/tools.step``: one CAD model of the punch and the open die (ddpy.cad.examples.
  bending_tools, a reconstruction: the paper's Fig. 6 is not in its text);
- ``tools/{punch,die}.{bezier,nagata,facets}.tool``: the tool models built from it by
  ``ddpy.cad.build_tool_models`` (what ``ddpy tools build`` runs): Bezier patches, Nagata
  4 patches per 90 degrees of arc, facets 30 per arc. The paper's coarse facets are the Nagata
  mesh with flat patches (its section "Bilinear facets": c = 0, "keeping the same
  discretization"), so that model reads the Nagata file with ``description facets``;
- ``meshes/<mesh>.msh``: the blank, a quarter 60 x 15 x 1 mm (rolling direction along x):
  ``paper``, unstructured quadrilaterals extruded in 3 layers, as close to the paper's 19,950
  hexahedra as gmsh's recombination gets; ``coarse``, structured, 1 mm along x, 2 layers;
- ``cases/<mesh>/<model>/``: the five decks of each case, for the models ``bezier``,
  ``nagata``, ``facets_coarse`` and ``facets_fine``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
MODELS = ("bezier", "nagata", "facets_coarse", "facets_fine")
MESHES = ("coarse", "paper")
#: The quarter blank, mm (the paper: 120 x 30 x 1 mm, rolling direction along the length).
LENGTH, WIDTH, THICKNESS = 60.0, 15.0, 1.0
PAPER_HEXAHEDRA, LAYERS = 19950, 3
#: Tools (a reconstruction of the paper's Fig. 6, which is not in its text): punch radius, die
#: shoulder radius and the clearance, the horizontal gap between the punch's side and the
#: shoulder's inner edge, which places the shoulder's centre SHOULDER_X from the symmetry
#: plane. The clearance is fitted: fit_die.py --mesh paper ran the Bezier model at 1.6, 1.7
#: and 1.8 mm, and 1.72 mm puts theta_1..4 nearest the paper's Bezier column (within 1.6
#: degrees; docs/benchmarks/cylindrical_bending_die_fit_paper.md).
PUNCH_RADIUS, SHOULDER_RADIUS, CLEARANCE = 23.5, 4.0, 1.72
SHOULDER_X = PUNCH_RADIUS + CLEARANCE + SHOULDER_RADIUS
#: Coarse blank: uniform, 1 mm elements along x (the blank engineers run), 5 mm across y,
#: 2 layers of solid-shells (ddpy's default element and contact: 4 x 4 Gauss points per face
#: against each tool). Measured on the built-in case (benchmarks/mesh_convergence for the
#: von Mises blank): within 1 % of the punch force of a 0.25 mm blank, its chatter below
#: 0.5 %; 6 elements across instead of 3 change the force by at most 0.9 % and take three
#: times as long. (The first coarse blank, graded 1.5 / 3.6 mm hexahedra in 3 layers, was
#: 25-30 % too stiff: the hexahedron locks in bending, docs/theory/solid_shell.md.)
COARSE_X, COARSE_Y, COARSE_LAYERS = 60, 3, 2
#: Tool file of each model and tool, and the description the deck gives it.
TOOL_FILES = {"bezier": ("bezier", "bezier"), "nagata": ("nagata", "nagata"),
              "facets_coarse": ("facets", "nagata"), "facets_fine": ("facets", "facets")}
STROKE, MAX_INCREMENT, FRICTION = 28.5, 0.114, 0.148
#: Springback steps: the tools' forces released at once (a step that does not converge is
#: halved). On the paper blank with Nagata tools, from the end of forming (code 81ca223):
#: 1 step 17 Newton iterations (each a factorization), 20 steps 62, 5 steps 24; beta_2
#: between the flanges 39.982, 39.968 and 39.973 degrees (docs/theory/speed.md).
SPRINGBACK = 1
#: Nagata patches (and coarse facets) and fine facets per 90 degrees of arc (the paper's).
PATCHES_PER_ARC, FACETS_PER_ARC = 4, 30
#: r_min elasto-plastic transition: how far (fraction of the yield stress) an elastic Gauss
#: point may overshoot before the increment is scaled back. The deck default, 0.01, lands the
#: yield front of a bend point by point (thousands of increments of 1e-4 mm on the coarse
#: blank); the paper's DD3IMP needed 338 increments for 250 of full size. Per blank: on the
#: paper's, with 8 Gauss points per 0.37 mm element, the yield front (reverse bending past the
#: punch) crosses a point in almost every increment, and each overshooting point carries a
#: small share of the bending moment. With 0.1 the paper blank's increments from 14 mm on
#: averaged 0.045 mm; restarted at 15.16 mm (the same code), 0.3 took 15 increments and 108
#: iterations to 16.05 mm against 21 and 130 with 0.1.
RMIN_YIELD = {"coarse": 0.1, "paper": 0.3}
#: Augmentation r of the contact law (N/mm) set in the decks of a blank, else the solver's
#: default (ddpy.model.forming.default_augmentation). The default is E t^2 / h of the elements:
#: 7.0e3 on the coarse blank (flat elements) but 6.3e4 on the paper's, whose elements are
#: nearly cubes (0.33 mm thick, 0.37 mm across). With 6.3e4 the paper blank's Newton loop
#: needed 10 to 23 iterations per increment from 7.6 mm of stroke on, and cut increments:
#: nodes grazing the die shoulder flipped between open and closed. Restarted at 8.3 mm,
#: 6.6e3 and 2e4 took 4 to 6; but from the flat start (the blank held by contact alone)
#: 6.6e3 and 1e4 did not converge at any size, 2e4 did (docs/theory/contact.md). Measured
#: again at e335c73 (the barrier, the flat start's restart with the touching pairs open):
#: the decks without the line (the default, 6.3e4) converge from the flat start and give
#: the kept runs' answers (82d6099, with the line) to the digits reported. Nagata: theta
#: 19.11 / 62.72 / 110.03 / 154.10, beta 12.37 / 19.99 degrees, largest force 73.45 N,
#: 253 increments, no cut, all as kept; 564 iterations against 566. Bezier: the same
#: angles and 73.69 N, 254 increments; 573 iterations against 575. Fine facets: the same
#: angles, 75.20 N against 75.21, 255 increments against 254 (2 cuts against 1), 695
#: iterations against 703. The line stays until the four kept paper runs are rerun
#: without it (coarse facets, the long one, not measured; Table 3 like for like).
AUGMENTATION = {"paper": 2e4}
OUTPUT_AT = (7.0, 14.0, 21.0, 28.5)


def build_tools(folder: Path = HERE / "tools", size: float = 5.0,
                shoulder_x: float = SHOULDER_X) -> dict[str, dict[str, Path]]:
    """Write the CAD model and the punch and die tool files, the die's shoulder centred
    ``shoulder_x`` from the symmetry plane; return the paths by tool and model ('bezier',
    'nagata', 'facets')."""
    from ddpy.cad import build_tool_models, gmsh_session, load_cad
    from ddpy.cad.examples import bending_tools

    folder.mkdir(parents=True, exist_ok=True)
    step = folder / "tools.step"
    with gmsh_session():
        import gmsh

        gmsh.clear()
        bending_tools(step, punch_radius=PUNCH_RADIUS, shoulder_radius=SHOULDER_RADIUS,
                      shoulder_x=shoulder_x, thickness=THICKNESS)
        gmsh.clear()
        faces = load_cad(step)
        # The punch lies above the blank (z > thickness), the die below (z <= 0).
        punch = [f for f in faces if gmsh.model.getBoundingBox(2, f)[2] > 0.5 * THICKNESS]
        die = [f for f in faces if f not in punch]
        gmsh.clear()
    return {
        "punch": build_tool_models(step, folder, "punch", patches_per_arc=PATCHES_PER_ARC,
                                   facets_per_arc=FACETS_PER_ARC,
                                   size=size, blank_side=(0, 0, -1), faces=punch),
        "die": build_tool_models(step, folder, "die", patches_per_arc=PATCHES_PER_ARC,
                                 facets_per_arc=FACETS_PER_ARC,
                                 size=size, blank_side=(0, 0, 1), faces=die),
    }


def paper_mesh(path: Path, quads: int = PAPER_HEXAHEDRA // LAYERS, tries: int = 8) -> int:
    """The paper's blank: an unstructured quadrilateral mesh of the 60 x 15 mm quarter (gmsh
    Frontal-Delaunay for quads, Blossom recombination), its size tuned to ``quads``
    quadrilaterals, extruded in 3 layers. Writes a Gmsh file; returns the hexahedra."""
    import gmsh

    from ddpy.cad import gmsh_session

    size = math.sqrt(LENGTH * WIDTH / quads)
    best: tuple[int, float] | None = None
    with gmsh_session():
        for attempt in range(tries + 1):
            if best is not None and attempt == tries:
                size = best[1]  # the closest of the tries, meshed once more to write it
            gmsh.clear()
            occ = gmsh.model.occ
            surface = occ.addRectangle(0, 0, 0, LENGTH, WIDTH)
            occ.synchronize()
            gmsh.option.setNumber("Mesh.Algorithm", 8)
            gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)
            gmsh.option.setNumber("Mesh.MeshSizeMin", size)
            gmsh.option.setNumber("Mesh.MeshSizeMax", size)
            gmsh.model.mesh.setRecombine(2, surface)
            gmsh.model.mesh.generate(2)
            count = sum(len(t) for t in gmsh.model.mesh.getElements(2, surface)[1])
            if best is None or abs(count - quads) < abs(best[0] - quads):
                best = (count, size)
            if attempt == tries or count == quads:
                break
            size *= math.sqrt(count / quads) ** 0.9
        gmsh.clear()
        occ = gmsh.model.occ
        surface = occ.addRectangle(0, 0, 0, LENGTH, WIDTH)
        occ.extrude([(2, surface)], 0, 0, THICKNESS, numElements=[LAYERS], recombine=True)
        occ.synchronize()
        gmsh.model.mesh.setRecombine(2, surface)
        gmsh.option.setNumber("Mesh.MeshSizeMin", best[1] if best else size)
        gmsh.option.setNumber("Mesh.MeshSizeMax", best[1] if best else size)
        gmsh.model.mesh.generate(3)
        hexahedra = sum(len(t) for t in gmsh.model.mesh.getElements(3)[1])
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        path.parent.mkdir(parents=True, exist_ok=True)
        gmsh.write(str(path))
        gmsh.clear()
    return hexahedra


def coarse_mesh(path: Path, nx: int = COARSE_X, ny: int = COARSE_Y,
                layers: int = COARSE_LAYERS) -> int:
    """The coarse blank: structured and uniform, ``nx`` elements along x, ``ny`` across and
    ``layers`` through the thickness. Writes a Gmsh file; returns the hexahedra."""
    import meshio
    import numpy as np

    x = np.linspace(0.0, LENGTH, nx + 1)
    y = np.linspace(0.0, WIDTH, ny + 1)
    z = np.linspace(0.0, THICKNESS, layers + 1)
    nodes = np.stack(np.meshgrid(x, y, z, indexing="ij"), axis=-1).reshape(-1, 3)
    ids = np.arange(nodes.shape[0]).reshape(x.size, y.size, z.size)
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(x.size - 1), np.arange(y.size - 1),
                                              np.arange(z.size - 1), indexing="ij"))
    bottom = [ids[i, j, k], ids[i + 1, j, k], ids[i + 1, j + 1, k], ids[i, j + 1, k]]
    top = [ids[i, j, k + 1], ids[i + 1, j, k + 1], ids[i + 1, j + 1, k + 1],
           ids[i, j + 1, k + 1]]
    hexahedra = np.column_stack(bottom + top)
    path.parent.mkdir(parents=True, exist_ok=True)
    tags = [np.ones(hexahedra.shape[0], dtype=int)]
    mesh = meshio.Mesh(nodes, [("hexahedron", hexahedra)],
                       cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags})
    meshio.write(str(path), mesh, file_format="gmsh22", binary=False)
    return int(hexahedra.shape[0])


CONTROL = """\
# ddpy control deck.  Units mm, N, MPa, s.  Written by benchmarks/cylindrical_bending/make_case.py
# Unconstrained cylindrical bending (Numisheet 2002 benchmark B), quarter model.

title  Unconstrained cylindrical bending, {model} tools, {mesh} blank

max_increment        {max_increment}    # mm of punch travel (paper: 0.114)
rmin_yield           {rmin_yield}     # fraction of the yield stress (see make_case.py)
rmin_strain          0.02
rmin_rotation        1.0
rmin_contact         on
newton_force         1e-3
newton_displacement  1e-3
max_iterations       25
cutback              0.5
output_every         0         # fields only at output_at and at the end of each phase

phase forming
  type      forming
  tools     punch die
  move      punch  0 0 -{stroke}
  lead      punch
  output_at {output_at}          # paper Table 2
end

phase springback
  type            springback
  increments      {springback}      # released at once; a step that fails is halved
  max_iterations  60
end
"""

MESH = """\
# ddpy mesh deck: the blank.  Units mm.  Written by make_case.py
# Quarter of the 120 x 30 x 1 mm strip: 60 x 15 x 1 mm, {what}.
normal  z
file    ../../../meshes/{mesh}.msh
"""

BC = """\
# ddpy boundary deck.  Units mm.  Written by make_case.py
tolerance  1e-4
symmetry   x 0                     # plane x = 0 (the punch's axis plane)
symmetry   y 0                     # plane y = 0 (middle of the width)
nodeset    centre  box 0 0  0 0  -inf inf
fix        centre  z  phase springback     # the blank's free rigid motion along z
"""

MATERIAL = """\
# ddpy material deck.  Units MPa.  Written by make_case.py
# High strength steel of the Numisheet 2002 benchmark B (paper Table 1; E, nu assumed).
elastic            E 210000  nu 0.3
yield              hill48  F 0.254  G 0.397  H 0.603  L 1.5  M 1.5  N 1.689
hardening          swift   K 645.3  eps0 0.0102  n 0.252
rolling_direction  0          # along x, the blank's length
"""

TOOLS = """\
# ddpy tools deck.  Units mm.  Written by make_case.py: the {model} model.
tool punch
  description  {description}
  file         ../../../tools/punch.{file}.tool
  friction     {friction}
  contact      top
{augmentation}end

tool die
  description  {description}
  file         ../../../tools/die.{file}.tool
  friction     {friction}
  contact      bottom
{augmentation}end
"""


def write_case(folder: Path, model: str, mesh: str, stroke: float = STROKE,
               max_increment: float = MAX_INCREMENT, springback: int = SPRINGBACK,
               rmin_yield: float | None = None) -> Path:
    """Write the five decks of one case (the tool and mesh files are referred to relatively:
    the folder must be ``<root>/cases/<mesh>/<model>`` next to ``tools/`` and ``meshes/``)."""
    description, file = TOOL_FILES[model]
    rmin_yield = RMIN_YIELD.get(mesh, 0.1) if rmin_yield is None else rmin_yield
    folder.mkdir(parents=True, exist_ok=True)
    what = {"paper": "unstructured, 3 layers (paper: 19,950 hexahedra)",
            "coarse": "structured, 1 mm along x, 2 layers"}.get(mesh, "")
    at = " ".join(f"{s:g}" for s in OUTPUT_AT if s <= stroke + 1e-9)
    decks = {
        "control.dat": CONTROL.format(model=model, mesh=mesh, max_increment=max_increment,
                                      stroke=f"{stroke:g}", output_at=at, springback=springback,
                                      rmin_yield=f"{rmin_yield:g}"),
        "mesh.dat": MESH.format(mesh=mesh, what=what),
        "bc.dat": BC,
        "material.dat": MATERIAL,
        "tools.dat": TOOLS.format(
            model=model, description=description, file=file, friction=FRICTION,
            augmentation=(f"  augmentation {AUGMENTATION[mesh]:g}    # N/mm, see make_case.py\n"
                          if mesh in AUGMENTATION else "")),
    }
    for name, text in decks.items():
        (folder / name).write_text(text)
    return folder


#: The built-in default case of ``ddpy run``: this benchmark's coarse Nagata case.
DEFAULT_CASE = HERE.parents[1] / "ddpy" / "cases" / "cylindrical_bending"
DEFAULT_HEADER = """\
# The built-in default case of `ddpy run`: the coarse blank and Nagata tools of
# benchmarks/cylindrical_bending, written by its make_case.py --default-case (do not edit
# here: tests/test_cylindrical_bending.py checks that the two agree).
"""


def write_default_case(folder: Path = DEFAULT_CASE, tools: Path | None = None) -> Path:
    """Write the built-in default case into ``folder``: the decks of the coarse Nagata case
    with the mesh (``mesh.msh``) and the tool files (``tools/punch.tool``, ``tools/die.tool``)
    beside them, so that the folder stands alone. ``tools``: a folder of tool files already
    built by ``build_tools`` (default: built here in a temporary folder)."""
    import shutil
    import tempfile

    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        if tools is None:
            tools = Path(scratch) / "tools"
            build_tools(tools)
        (folder / "tools").mkdir(exist_ok=True)
        for tool in ("punch", "die"):
            shutil.copyfile(tools / f"{tool}.nagata.tool", folder / "tools" / f"{tool}.tool")
    coarse_mesh(folder / "mesh.msh")
    write_case(folder, "nagata", "coarse")
    for name in ("control.dat", "mesh.dat", "tools.dat", "bc.dat", "material.dat"):
        path = folder / name
        text = path.read_text()
        text = text.replace("../../../meshes/coarse.msh", "mesh.msh")
        for tool in ("punch", "die"):
            text = text.replace(f"../../../tools/{tool}.nagata.tool", f"tools/{tool}.tool")
        path.write_text(DEFAULT_HEADER + text)
    return folder


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mesh", choices=(*MESHES, "all"), default="all")
    parser.add_argument("--root", type=Path, default=HERE,
                        help="where tools/, meshes/ and cases/ go (default: next to this script)")
    parser.add_argument("--default-case", type=Path, nargs="?", const=DEFAULT_CASE,
                        metavar="FOLDER", help="write only the built-in default case of "
                        "`ddpy run` (default folder: ddpy/cases/cylindrical_bending)")
    args = parser.parse_args(argv)
    if args.default_case is not None:
        print(write_default_case(args.default_case))
        return 0
    root: Path = args.root
    for tool, paths in build_tools(root / "tools").items():
        print(f"{tool}: " + ", ".join(str(p) for p in paths.values()), file=sys.stderr)
    meshes = MESHES if args.mesh == "all" else (args.mesh,)
    for mesh in meshes:
        maker = paper_mesh if mesh == "paper" else coarse_mesh
        count = maker(root / "meshes" / f"{mesh}.msh")
        print(f"mesh {mesh}: {count} hexahedra", file=sys.stderr)
        for model in MODELS:
            print(write_case(root / "cases" / mesh / model, model, mesh))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
