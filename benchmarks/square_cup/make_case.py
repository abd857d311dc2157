"""Write the cases of the Numisheet'93 square cup (a square punch draws a square blank under a
blank-holder force; the measured draw-in of the flange at 15 and 40 mm of punch travel).

    python benchmarks/square_cup/make_case.py                   # every material and mesh
    python benchmarks/square_cup/make_case.py --mesh coarse --material aluminium
    python benchmarks/square_cup/make_case.py --default-case    # `ddpy run square-cup`

Writes, next to this script (all generated, git-ignored):

- ``tools/tools.step``: one CAD model of the punch, the die and the blank-holder
  (``ddpy.cad.examples.square_cup_tools``, gmsh's OpenCASCADE kernel) with the dimensions
  of :class:`Dimensions`, a quarter with the square's sides along x and y;
- ``tools/<tool>.<model>.tool``: the tool models built from it by
  ``ddpy.cad.build_tool_models`` (what ``ddpy tools build`` runs), as for the reverse deep
  drawing: Bezier patches; Nagata 3 patches per 90 degrees of arc; facets 6 (coarse) and 12
  (fine) per arc; straight edges and long arcs cut into elements of at most :data:`SIZE` mm;
- ``cases/<material>/<mesh>/<model>/``: the five decks of each case, for the materials
  ``aluminium`` and ``steel``, the blanks ``coarse``, ``medium`` and ``fine`` (structured
  boxes of :data:`DIVISIONS`, written in mesh.dat: no mesh file) and the models
  ``bezier``, ``nagata``, ``facets_coarse`` and ``facets_fine``.

The specification and where each value comes from: :data:`DIMENSION_SOURCES` and
:data:`MATERIAL_SOURCES`.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import asdict, dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import TOOL_FILES, build_tool_model, written_tool_faces  # noqa: E402

MODELS = ("bezier", "nagata", "facets_coarse", "facets_fine")
MESHES = ("coarse", "medium", "fine")
MATERIALS = ("aluminium", "steel")
TOOLS = ("punch", "die", "holder")

#: The published specification of the benchmark (Makinouchi, Nakamachi, Onate and Wagoner
#: (eds.), NUMISHEET'93, Proceedings of the 2nd International Conference on Numerical
#: Simulation of 3-D Sheet Metal Forming Processes, Isehara, Japan, 1993: benchmark A,
#: the square cup), as later papers restate it, e.g. Menezes and Teodosiu, "Three-
#: dimensional numerical simulation of the deep-drawing process using solid finite
#: elements", J. Mater. Process. Technol. 97 (2000) 100-106, which ran it with DD3IMP.
#: The search tools of this project found no stored copy of either text: the values below
#: are those papers' as quoted from them, not checked here against a copy; the report must
#: check them against a copy before it compares with the measurements.
SPECIFICATION = "NUMISHEET'93 benchmark A (square cup), as restated by Menezes and Teodosiu (2000)"


@dataclass(frozen=True)
class Dimensions:
    """The tools, the blank and the process (mm, N). The flat blank lies on 0 <= z <= t,
    its corner at the origin on the cup's axis, its sides along x (the rolling direction)
    and y; the tools are built for the thicker (aluminium) blank: the punch's flat end and
    the blank-holder touch its top, and stand 0.03 mm above the steel blank (the holder,
    force-controlled, is brought onto it; the punch reaches it in its first increment)."""

    punch_half: float = 35.0       #: punch: half of its 70 mm side
    punch_corner: float = 10.0     #: punch: radius of its vertical corners (plan)
    punch_nose: float = 8.0        #: punch: profile radius
    punch_height: float = 50.0     #: punch: height of its walls above the nose
    die_half: float = 37.235       #: die: half of its 74.47 mm opening
    die_corner: float = 12.235     #: die: radius of the opening's corners (plan)
    die_radius: float = 5.0        #: die: profile radius
    die_depth: float = 50.0        #: die: wall below the profile radius
    holder_half: float = 44.235    #: blank-holder: half-width where its flat begins
    holder_edge: float = 2.0       #: blank-holder: radius of its inner edge
    outer_half: float = 105.0      #: die and blank-holder: half-width of their flats
    blank_half: float = 75.0       #: blank: half of its 150 mm side
    travel: float = 40.0           #: punch travel
    output_at: tuple[float, ...] = (15.0, 40.0)   #: where the draw-in was measured
    holder_force: float = 19.6e3   #: blank-holder force on the whole blank, N

    def cad(self, thickness: float) -> dict[str, float]:
        """Keyword arguments of ``square_cup_tools``."""
        values = asdict(self)
        for key in ("blank_half", "travel", "output_at", "holder_force"):
            values.pop(key)
        return {**values, "thickness": thickness}


DIMENSIONS = Dimensions()

#: What each dimension is, and where its value comes from.
DIMENSION_SOURCES: dict[str, tuple[str, str]] = {
    "punch_half": ("punch: half of its 70 mm side", f"{SPECIFICATION}: punch 70 x 70 mm"),
    "punch_corner": ("punch: radius of its vertical corners", f"{SPECIFICATION}: 10 mm"),
    "punch_nose": ("punch: profile radius", f"{SPECIFICATION}: 8 mm"),
    "punch_height": ("punch: height of its walls above the nose",
                     "not a benchmark value: above the 40 mm travel"),
    "die_half": ("die: half of its 74.47 mm opening", f"{SPECIFICATION}: 74.47 x 74.47 mm"),
    "die_corner": ("die: radius of the opening's corners",
                   f"{SPECIFICATION}: 12.235 mm, the punch's 10 mm plus the clearance "
                   "(74.47 - 70) / 2 = 2.235 mm: the corners are concentric with the punch's"),
    "die_radius": ("die: profile radius", f"{SPECIFICATION}: 5 mm"),
    "die_depth": ("die: wall below the profile radius",
                  "not a benchmark value: longer than the travel, so that the cup wall never "
                  "meets the wall's free lower edge"),
    "holder_half": ("blank-holder: half-width where its flat begins",
                    "NOT FOUND (the blank-holder's opening): chosen 2 mm outside the end of "
                    "the die's profile radius (42.235 mm), as for the reverse deep drawing; "
                    "the holder must only cover the flange on the die's flat"),
    "holder_edge": ("blank-holder: radius of its inner edge",
                    "NOT FOUND: rounded so that the flange cannot catch on a sharp edge (the "
                    "reverse deep drawing's medium blank failed on one), 2 mm"),
    "outer_half": ("die and blank-holder: half-width of their flats",
                   "not a benchmark value: their corners (concentric with the die's) reach "
                   "the blank's corner (75, 75) with 9 mm to spare"),
    "blank_half": ("blank: half of its 150 mm side", f"{SPECIFICATION}: 150 x 150 mm"),
    "travel": ("punch travel", f"{SPECIFICATION}: draw-in measured at 15 and 40 mm"),
    "output_at": ("travels of the fields written", f"{SPECIFICATION}: 15 and 40 mm"),
    "holder_force": ("blank-holder force on the whole blank",
                     f"{SPECIFICATION}: 19.6 kN; the quarter model's force line carries a "
                     "quarter, 4,900 N"),
}


@dataclass(frozen=True)
class Sheet:
    """A blank's material: thickness (mm), elasticity (MPa), Lankford coefficients, Swift's
    law Y = K (eps0 + ep)^n (MPa) and Coulomb's friction with the tools."""

    thickness: float
    E: float
    nu: float
    r0: float
    r45: float
    r90: float
    K: float
    eps0: float
    n: float
    friction: float
    name: str


SHEETS = {
    "aluminium": Sheet(0.81, 71e3, 0.33, 0.71, 0.58, 0.70, 576.79, 0.01658, 0.3593, 0.162,
                       "aluminium alloy"),
    "steel": Sheet(0.78, 206e3, 0.3, 1.79, 1.51, 2.27, 565.32, 0.007117, 0.2589, 0.144,
                   "mild steel"),
}

#: Where each material value comes from.
MATERIAL_SOURCES: dict[str, str] = {
    "thickness": f"{SPECIFICATION}: 0.81 mm (aluminium), 0.78 mm (mild steel)",
    "E, nu": f"{SPECIFICATION}: 71 GPa and 0.33 (aluminium), 206 GPa and 0.3 (mild steel)",
    "r0, r45, r90": f"{SPECIFICATION}: 0.71, 0.58, 0.70 (aluminium), 1.79, 1.51, 2.27 (mild "
                    "steel); Hill'48 from them (G + H = 1, L = M = 1.5: the out-of-plane "
                    "shear coefficients are not measured, ddpy's default)",
    "K, eps0, n": f"{SPECIFICATION}: Swift 576.79 (0.01658 + ep)^0.3593 MPa (aluminium), "
                  "565.32 (0.007117 + ep)^0.2589 MPa (mild steel)",
    "friction": f"{SPECIFICATION}: 0.162 (aluminium), 0.144 (mild steel), the same on every "
                "tool",
    "rolling_direction": "along x: the draw-in 'along the rolling direction' is the flange "
                         "edge's on the x axis, 'across' on the y axis",
}

#: The quarter blank's elements along each side (structured, 2 layers of solid-shells).
DIVISIONS = {"coarse": 25, "medium": 50, "fine": 75}
LAYERS = 2
#: Tool models: patches (Nagata) or facets per 90 degrees of arc (the reverse deep
#: drawing's), and the longest element (mm) along straight edges and long arcs.
PER_ARC = {"nagata": 3, "facets_coarse": 6, "facets_fine": 12}
SIZE = {"nagata": 6.0, "facets_coarse": 6.0, "facets_fine": 3.0}
#: Contact side of each tool on the blank (mesh normal +z) and direction towards the blank.
SIDE = {"punch": "top", "die": "bottom", "holder": "top"}
BLANK_SIDE = {"punch": (0, 0, -1), "die": (0, 0, 1), "holder": (0, 0, -1)}
#: Largest increment (mm of punch travel) of each blank.
MAX_INCREMENT = {"coarse": 0.5, "medium": 0.25, "fine": 0.2}


def build_tools(folder: Path = HERE / "tools", dims: Dimensions = DIMENSIONS,
                models: tuple[str, ...] = MODELS) -> dict[str, dict[str, Path]]:
    """Write the CAD model and each tool's model files; return the paths by tool and model."""
    from ddpy.cad.examples import square_cup_tools

    folder.mkdir(parents=True, exist_ok=True)
    step = folder / "tools.step"
    thickness = max(sheet.thickness for sheet in SHEETS.values())
    made = written_tool_faces(step, lambda path: square_cup_tools(path, **dims.cad(thickness)))
    return {tool: {model: build_tool_model(step, folder, tool, model, faces, BLANK_SIDE[tool],
                                           per_arc=PER_ARC.get(model, 0),
                                           size=SIZE.get(model), arc_size=SIZE.get(model))
                   for model in models}
            for tool, faces in made.items()}


CONTROL = """\
# ddpy control deck.  Units mm, N, MPa, s.  Written by benchmarks/square_cup/make_case.py
# The Numisheet'93 square cup, quarter model: the punch draws the blank {travel:g} mm under
# a blank-holder force of {force:g} kN ({quarter:g} N on the quarter).

title  Square cup (Numisheet'93), {material}, {model} tools, {mesh} blank

max_increment  {max_increment:g}     # mm of punch travel
output_every   0       # fields at output_at and at the end
{limits}
phase draw
  type       forming
  tools      punch die holder
  move       punch  0 0 -{travel:g}
  force      holder {quarter:g}       # N, a quarter of the blank-holder force
  lead       punch
  output_at  {output_at}       # the measured draw-in
end
"""

MESH = """\
# ddpy mesh deck: the blank.  Units mm.  Written by make_case.py
# A quarter of the {side:g} x {side:g} x {t:g} mm blank: {n} x {n} x {layers} elements.
normal  z
{element}box     {half:g} {half:g} {t:g}  {n} {n} {layers}
"""

BC = """\
# ddpy boundary deck.  Units mm.  Written by make_case.py
tolerance  1e-4
symmetry   x 0                     # plane x = 0
symmetry   y 0                     # plane y = 0
"""

MATERIAL = """\
# ddpy material deck.  Units MPa.  Written by make_case.py
# The {name} of the Numisheet'93 square cup ({t:g} mm).
elastic            E {E:g}  nu {nu:g}
yield              hill48  r0 {r0:g}  r45 {r45:g}  r90 {r90:g}
hardening          swift   K {K:g}  eps0 {eps0:g}  n {n:g}
rolling_direction  0          # along x
"""

TOOL = """\
tool {tool}
  description  {description}
  file         {prefix}{tool}.{file}.tool
  friction     {friction:g}
  contact      {side}
end
"""


def write_case(folder: Path, material: str, model: str, mesh: str,
               dims: Dimensions = DIMENSIONS, tools_prefix: str = "../../../../tools/",
               limits: dict[str, float] | None = None, element: str | None = None) -> Path:
    """Write the five decks of one case, at ddpy's increment limits and element unless
    ``limits`` (solver settings of control.dat) or ``element`` (mesh.dat's) are given. By
    default the tool files are referred to relatively: the folder must be
    ``<root>/cases/<material>/<mesh>/<model>`` next to ``tools/``."""
    sheet = SHEETS[material]
    file, description = TOOL_FILES[model]
    folder.mkdir(parents=True, exist_ok=True)
    decks = {
        "control.dat": CONTROL.format(
            material=sheet.name, model=model, mesh=mesh, travel=dims.travel,
            force=dims.holder_force / 1e3, quarter=dims.holder_force / 4,
            max_increment=MAX_INCREMENT[mesh],
            limits="".join(f"{key:<15}{value:<8g}# {LIMIT_REASONS[key]}\n"
                           for key, value in (limits or {}).items()),
            output_at=" ".join(f"{s:g}" for s in dims.output_at)),
        "mesh.dat": MESH.format(side=2 * dims.blank_half, half=dims.blank_half,
                                t=sheet.thickness, n=DIVISIONS[mesh], layers=LAYERS,
                                element=f"element {element}     # see make_case.py\n"
                                if element else ""),
        "bc.dat": BC,
        "material.dat": MATERIAL.format(**asdict(sheet), t=sheet.thickness),
        "tools.dat": "# ddpy tools deck.  Units mm.  Written by make_case.py: the "
                     f"{model} model.\n" + "\n".join(
                         TOOL.format(tool=t, description=description, file=file,
                                     prefix=tools_prefix, friction=sheet.friction,
                                     side=SIDE[t]) for t in TOOLS),
    }
    for name, text in decks.items():
        (folder / name).write_text(text)
    return folder


#: Increment limits of the built-in case, looser than ddpy's defaults (rmin_yield 0.1,
#: rmin_rotation 2 degrees), for a run of minutes: at the defaults of the time (rmin_rotation
#: 1 degree, every reloading point landed too) the coarse aluminium case
#: took increments of 0.03 to 0.05 mm, landing the yield front point by point as it crosses
#: the flange (47 increments to 2.3 mm: about 900 to 40 mm), then 0.1 to 0.16 mm as the sheet
#: turns over the die's 5 mm radius (rotation-limited with rmin_yield 0.5); with both loosened
#: the increments are max_increment's 0.5 mm. The benchmark's cases keep the defaults.
DEFAULT_LIMITS = {"rmin_yield": 0.5, "rmin_rotation": 5.0}
#: The built-in case's element: DD3IMP's hexahedron, as the reverse deep drawing's. With
#: the default solid-shell (and DEFAULT_LIMITS) the coarse blank stopped at 22.3 mm of
#: travel: an element of the cup's bottom at the punch's nose (element 833, top layer,
#: initially at x 21-24, y 24-27 mm) inverted at every cut, also with the punch's flat end
#: meshed in fair faces; the hexahedron reached 40 mm (84 increments, 468 iterations).
DEFAULT_ELEMENT = "hexahedron"
LIMIT_REASONS = {"rmin_yield": "fraction of the yield stress (default 0.1), see make_case.py",
                 "rmin_rotation": "degrees (default 2), see make_case.py"}
#: The built-in case ``ddpy run square-cup``: this benchmark's coarse aluminium case with
#: Nagata tools, at DEFAULT_LIMITS.
DEFAULT_CASE = HERE.parents[1] / "ddpy" / "cases" / "square_cup"
DEFAULT_HEADER = """\
# A built-in case of `ddpy run` (`ddpy run square-cup`): the coarse aluminium blank and Nagata
# tools of benchmarks/square_cup, written by its make_case.py --default-case (do not edit
# here: tests/test_square_cup.py checks that the two agree).
"""


def write_default_case(folder: Path = DEFAULT_CASE) -> Path:
    """Write the built-in case into ``folder``: the decks of the coarse aluminium Nagata case
    at DEFAULT_LIMITS with DEFAULT_ELEMENT, the tool files (``tools/<tool>.nagata.tool``)
    beside them (the blank is a box of mesh.dat: no mesh file)."""
    import shutil
    import tempfile

    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        built = build_tools(Path(scratch) / "tools", models=("nagata",))
        (folder / "tools").mkdir(exist_ok=True)
        for tool, paths in built.items():
            shutil.copyfile(paths["nagata"], folder / "tools" / f"{tool}.nagata.tool")
    write_case(folder, "aluminium", "nagata", "coarse", tools_prefix="tools/",
               limits=DEFAULT_LIMITS, element=DEFAULT_ELEMENT)
    for name in ("control.dat", "mesh.dat", "tools.dat", "bc.dat", "material.dat"):
        path = folder / name
        path.write_text(DEFAULT_HEADER + path.read_text())
    return folder


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mesh", choices=(*MESHES, "all"), default="all")
    parser.add_argument("--material", choices=(*MATERIALS, "all"), default="all")
    parser.add_argument("--root", type=Path, default=HERE,
                        help="where tools/ and cases/ go (default: next to this script)")
    parser.add_argument("--default-case", type=Path, nargs="?", const=DEFAULT_CASE,
                        metavar="FOLDER", help="write only the built-in case of `ddpy run "
                        "square-cup` (default folder: ddpy/cases/square_cup)")
    args = parser.parse_args(argv)
    if args.default_case is not None:
        print(write_default_case(args.default_case))
        return 0
    root: Path = args.root
    for tool, paths in build_tools(root / "tools").items():
        print(f"{tool}: " + ", ".join(str(p) for p in paths.values()), file=sys.stderr)
    meshes = MESHES if args.mesh == "all" else (args.mesh,)
    materials = MATERIALS if args.material == "all" else (args.material,)
    for material in materials:
        for mesh in meshes:
            for model in MODELS:
                print(write_case(root / "cases" / material / mesh / model, material, model,
                                 mesh))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
