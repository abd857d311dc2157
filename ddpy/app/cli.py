"""The ``ddpy`` command."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from ddpy import __version__
from ddpy.app.cli_run import add_post, add_run
from ddpy.cad.surface_mesh import DEFAULT_MERGE_TOL
from ddpy.geometry.mesh_normals import DEFAULT_CREASE_ANGLE, DEFAULT_ESTIMATOR, ESTIMATORS


def _accuracy(args: argparse.Namespace) -> int:
    from ddpy.studies import accuracy

    result = accuracy.arc_accuracy_study()
    if args.json:
        print(json.dumps(accuracy.summary(result), indent=2))
    else:
        print(accuracy.format_table(result))
    if args.figures:
        for path in accuracy.plot_figures(result, Path(args.figures)):
            print(f"wrote {path}", file=sys.stderr)
    return 0


def _check(args: argparse.Namespace) -> int:
    from ddpy.app.runner import case_folder
    from ddpy.io.decks import DeckError, read_case

    try:
        case = read_case(case_folder(args.case), geometry=not args.no_geometry)
    except DeckError as error:
        for e in error.errors:
            print(e, file=sys.stderr)
        count = len(error.errors)
        print(f"{args.case}: {count} error{'s' if count > 1 else ''}", file=sys.stderr)
        return 2
    print(case.summary())
    if not args.no_geometry:
        try:
            import ddpy.io.toolfile  # noqa: F401
        except ImportError:
            print("  note: ddpy.io.toolfile is not available: tool files not read, geometry "
                  "checks skipped")
    print(f"{args.case}: ok" + (f", {len(case.warnings)} warning(s)" if case.warnings else ""))
    return 0


def _convert(args: argparse.Namespace) -> int:
    from ddpy.app.convert import convert_command

    out = convert_command(args.model, args.case, args.tools, args.element, args.force)
    return 0 if out is not None else 2


def _info(args: argparse.Namespace) -> int:
    from ddpy.core import mpi
    from ddpy.core.parallel import max_threads

    print(f"ddpy {__version__}")
    print(f"core threads (OpenMP): {max_threads()}")
    if mpi.parallel_build():
        print(f"sparse solver: MUMPS (parallel, MPI: {mpi.world()[1]} process(es))")
    else:
        print("sparse solver: MUMPS (sequential)")
    return 0


def _triple(text: str) -> tuple[float, float, float]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 3:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z (three numbers), got '{text}'")
    return values  # type: ignore[return-value]


def _int_list(text: str) -> list[int]:
    try:
        return [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected integers separated by commas, got '{text}'")\
            from None


def _fail(command: str, error: Exception, code: int = 1) -> int:
    print(f"ddpy {command}: error: {error}", file=sys.stderr)
    return code


#: `tools build` options that only a CAD file takes, with their defaults, and those that
#: only a mesh takes (None: not given).
_CAD_OPTIONS = {"patches_per_arc": 4, "facets_per_arc": 30, "element": "quad",
                "bezier_tol": 1.0e-3, "bezier_angle_tol": 0.01}
_MESH_OPTIONS = ("normals", "crease_angle", "merge_tol", "groups", "cad")


def _option(name: str) -> str:
    return "--" + name.replace("_", "-")


def _tools_build(args: argparse.Namespace) -> int:
    from ddpy.cad import CadError, build_tool_models
    from ddpy.cad.mesh_tools import build_mesh_tool_models, is_cad_file

    models = None if args.models is None else \
        [m.strip() for m in args.models.split(",") if m.strip()]
    name = args.name or Path(args.file).stem
    try:
        if is_cad_file(args.file):
            given = [o for o in _MESH_OPTIONS if getattr(args, o) is not None]
            if given:
                raise ValueError(f"{_option(given[0])} applies to a mesh file (STL, .inp, "
                                 f".msh, ...), not to the CAD file {args.file}")
            options = {k: v if getattr(args, k) is None else getattr(args, k)
                       for k, v in _CAD_OPTIONS.items()}
            paths = build_tool_models(
                args.file, args.out, name, size=args.size, arc_size=args.arc_size,
                blank_side=args.blank_side, blank_point=args.blank_point, faces=args.faces,
                models=models or ["nagata", "facets", "bezier"], **options)
        else:
            given = [o for o in (*_CAD_OPTIONS, "size", "arc_size")
                     if getattr(args, o) is not None]
            if given:
                raise ValueError(f"{_option(given[0])} sets how a CAD file is meshed: a mesh "
                                 f"file ({args.file}) is used as it is")
            if args.faces is not None and args.cad is None:
                raise ValueError("--faces selects faces of the CAD given by --cad")
            if args.cad is not None and (args.normals or args.crease_angle):
                raise ValueError(f"{'--normals' if args.normals else '--crease-angle'} sets "
                                 "the normals estimated from the mesh: with --cad they come "
                                 "from the CAD")
            extra = {k: v for k, v in (("estimator", args.normals),
                                       ("crease_angle", args.crease_angle),
                                       ("merge_tol", args.merge_tol)) if v is not None}
            paths = build_mesh_tool_models(
                args.file, args.out, name, models=models or ["nagata", "facets"],
                blank_side=args.blank_side, blank_point=args.blank_point,
                groups=args.groups, cad=args.cad, cad_faces=args.faces, **extra)
    except (CadError, ValueError) as error:
        return _fail("tools build", error, 2)  # the CAD or mesh file, or an option
    except OSError as error:  # the output folder: permissions, space
        where = error.filename or args.out
        print(f"ddpy tools build: error: {where}: {error.strerror or error}", file=sys.stderr)
        return 1
    for path in paths.values():
        print(path)
    return 0


def _name_list(text: str) -> list[str]:
    names = [v.strip() for v in text.split(",") if v.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected names separated by commas, got '{text}'")
    return names


def _tools_error(args: argparse.Namespace) -> int:
    from ddpy.cad import CadError
    from ddpy.cad.shape_error import plot_shape_error, shape_error
    from ddpy.io.toolfile import read_tool

    rows = []
    try:
        for file in args.tools:
            result = shape_error(read_tool(file), args.cad, samples=args.samples)
            rows.append({"file": file, **result.summary()})
            if args.png:
                Path(args.png).mkdir(parents=True, exist_ok=True)
                png = plot_shape_error(result, Path(args.png) / (Path(file).name + ".png"))
                print(f"wrote {png}", file=sys.stderr)
    except (CadError, ValueError) as error:
        return _fail("tools error", error)
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(f"{'tool file':40s} {'patches':>8s} {'max |d| um':>11s} {'mean |d| um':>12s} "
          f"{'max angle deg':>14s}")
    for row in rows:
        print(f"{row['file']:40s} {row['patches']:8d} {row['max_distance_um']:11.4g} "
              f"{row['mean_distance_um']:12.4g} {row['max_angle_deg']:14.4g}")
    return 0


def _add_tools(commands: argparse._SubParsersAction) -> None:
    tools = commands.add_parser("tools", help="tool models from CAD or meshes (Bezier, Nagata,"
                                " facets) and their shape error")
    group = tools.add_subparsers(dest="tools_command", metavar="TOOLS_COMMAND", required=True)
    build = group.add_parser(
        "build", help="write <name>.nagata.tool, <name>.facets.tool (and <name>.bezier.tool "
        "from CAD)",
        description="Read a CAD file (STEP, IGES, BREP) and write Nagata, facet and Bezier tool "
        "files, or a tool surface mesh (STL, Abaqus/CalculiX .inp, Gmsh .msh, or what meshio "
        "reads) and write Nagata and facet tool files with normals estimated from the mesh "
        "or taken from --cad (docs/tool-files.md, docs/mesh-tools.md). Densities count "
        "patches per 90 degrees of arc. Give negative vectors with '=', e.g. "
        "--blank-side=0,0,-1.")
    build.add_argument("file", metavar="FILE", help="CAD file (STEP, IGES, BREP) or tool mesh "
                       "(STL, .inp, .msh, ...)")
    build.add_argument("--name", help="tool name (default: the file's stem)")
    build.add_argument("--out", default=".", metavar="DIR", help="output folder (default: .)")
    build.add_argument("--blank-side", type=_triple, default=(0.0, 0.0, 1.0), metavar="X,Y,Z",
                       help="direction towards the blank (default 0,0,1)")
    build.add_argument("--blank-point", type=_triple, metavar="X,Y,Z",
                       help="a point on the blank side (instead of --blank-side)")
    build.add_argument("--faces", type=_int_list, metavar="TAGS",
                       help="CAD faces to use, e.g. 1,2,5 (default: all)")
    build.add_argument("--models", metavar="LIST",
                       help="models to write (default nagata,facets,bezier from CAD, "
                       "nagata,facets from a mesh)")
    cad = build.add_argument_group("CAD files")
    cad.add_argument("--patches-per-arc", type=int, metavar="N",
                     help="Nagata patches per 90 degrees along curved edges (default 4)")
    cad.add_argument("--facets-per-arc", type=int, metavar="N",
                     help="facets per 90 degrees along curved edges (default 30)")
    cad.add_argument("--element", choices=("quad", "tri"), help="default quad")
    cad.add_argument("--size", type=float, metavar="MM",
                     help="largest element along straight edges (default: one element)")
    cad.add_argument("--arc-size", type=float, metavar="MM",
                     help="largest element along curved edges too, e.g. around a large "
                     "surface of revolution (default: by the angle only)")
    cad.add_argument("--bezier-tol", type=float, metavar="MM",
                     help="largest Bezier deviation from the CAD (default 0.001 mm)")
    cad.add_argument("--bezier-angle-tol", type=float, metavar="DEG",
                     help="largest Bezier normal error (default 0.01 degrees)")
    mesh = build.add_argument_group("mesh files")
    mesh.add_argument("--normals", choices=ESTIMATORS, metavar="ESTIMATOR",
                      help=f"vertex normal estimator: {', '.join(ESTIMATORS)} (default "
                      f"{DEFAULT_ESTIMATOR}, docs/mesh-tools.md)")
    mesh.add_argument("--crease-angle", type=float, metavar="DEG",
                      help="edges whose faces meet at more than this angle are creases "
                      f"(default {DEFAULT_CREASE_ANGLE:g})")
    mesh.add_argument("--merge-tol", type=float, metavar="REL",
                      help="vertices closer than this fraction of the median edge length are "
                      f"one (default {DEFAULT_MERGE_TOL:g})")
    mesh.add_argument("--groups", type=_name_list, metavar="NAMES",
                      help="keep only these groups: STL solids, Abaqus *SURFACE or element set "
                      "names, Gmsh physical names (default: every face)")
    mesh.add_argument("--cad", metavar="CAD",
                      help="the CAD file the mesh was made from: normals from its exact "
                      "surfaces instead of estimated (--faces selects its faces)")
    build.set_defaults(handler=_tools_build)

    error = group.add_parser("error", help="shape error of tool files against their CAD",
                             description="Distance and normal errors of tool files against "
                             "the CAD they were built from (paper Fig. 8).")
    error.add_argument("tools", nargs="+", metavar="TOOL", help="tool files")
    error.add_argument("--cad", help="CAD file (default: the 'source' of each tool file)")
    error.add_argument("--samples", type=int, default=9, metavar="N",
                       help="samples per patch direction (default 9)")
    error.add_argument("--png", metavar="DIR", help="also write error maps (PNG) here")
    error.add_argument("--json", action="store_true", help="print the numbers as JSON")
    error.set_defaults(handler=_tools_error)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ddpy",
        description="Implicit finite elements for sheet metal forming with Bezier, Nagata and "
        "faceted tool surfaces.",
    )
    parser.add_argument("--version", action="version", version=f"ddpy {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the Python traceback of an unexpected error")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

    accuracy = commands.add_parser(
        "accuracy",
        help="arc accuracy study: linear against Nagata interpolation (paper Fig. 3 and 4)",
    )
    accuracy.add_argument("--json", action="store_true", help="print the numbers as JSON")
    accuracy.add_argument("--figures", metavar="DIR", help="also write the figures (PNG) here")
    accuracy.set_defaults(handler=_accuracy)

    check = commands.add_parser(
        "check", help="validate a case folder: print its summary, or every error as file:line "
        "(exit code 2)")
    check.add_argument("case", metavar="CASE", help="the case folder (control.dat, mesh.dat, "
                       "bc.dat, material.dat, tools.dat), or a built-in case: "
                       "cylindrical-bending, deep-drawing, square-cup")
    check.add_argument("--no-geometry", action="store_true",
                       help="skip the checks of the tool positions against the blank")
    check.set_defaults(handler=_check)

    convert = commands.add_parser(
        "convert", help="an Abaqus / CalculiX forming model (.inp) to a case folder",
        description="Read an Abaqus or CalculiX input file (the supported subset: "
        "docs/abaqus-import.md), write a ddpy case folder and check it. What cannot be mapped "
        "is refused with its file:line (exit code 2); what is ignored is listed.")
    convert.add_argument("model", metavar="MODEL.inp", help="the input file")
    convert.add_argument("case", nargs="?", metavar="CASE",
                         help="the case folder to write (default: MODEL_case beside the file)")
    convert.add_argument("--tools", choices=("facets", "nagata"), default="facets",
                         help="the tools of tools.dat: the faces as given (facets, the "
                         "default) or Nagata patches smoothed over them (both files are "
                         "written)")
    convert.add_argument("--element", choices=("hexahedron", "solid-shell"),
                         help="the blank's element (default: solid-shell for C3D8I, "
                         "hexahedron for C3D8 and C3D8R)")
    convert.add_argument("--force", action="store_true",
                         help="write into a folder that is not empty")
    convert.set_defaults(handler=_convert)

    _add_tools(commands)
    add_run(commands)
    add_post(commands)

    info = commands.add_parser("info", help="version, threads and linked libraries")
    info.set_defaults(handler=_info)
    return parser


def _mpi_rank() -> int:
    """Under an MPI launcher with several processes: start MPI and return this process's
    rank (docs/mpi.md); 0 otherwise. Ranks > 0 serve rank 0's solver calls in ``main``."""
    from ddpy.core import mpi

    if mpi.launched_size() < 2:
        return 0
    return mpi.start()


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``ddpy`` console command. Under ``mpirun -n N`` rank 0 runs the
    command and ranks > 0 take their part in its MUMPS calls (docs/mpi.md)."""
    from ddpy.core import mpi

    try:
        rank = _mpi_rank()
    except mpi.MpiError as error:
        if os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")) == "0":
            print(f"ddpy: error: {error}", file=sys.stderr)
        return 2
    if rank > 0:
        mpi.serve()
        return 0
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return int(args.handler(args))
    except MemoryError as error:  # a model too large for this machine, at any stage
        detail = f" ({error})" if str(error) else ""
        print(f"ddpy {args.command}: error: out of memory{detail}: the model needs more "
              "memory than this machine has free; use a coarser mesh or a larger machine",
              file=sys.stderr)
        return 1
    except Exception as error:  # a defect of ddpy itself: one line, the traceback on demand
        if args.debug:
            raise
        print(f"ddpy {args.command}: internal error: {type(error).__name__}: {error} (please "
              "report it; 'ddpy --debug ...' shows where it happened)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
