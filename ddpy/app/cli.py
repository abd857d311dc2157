"""The ``ddpy`` command."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ddpy import __version__
from ddpy.app.cli_run import add_post, add_run


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


def _info(args: argparse.Namespace) -> int:
    from ddpy.core.parallel import max_threads

    print(f"ddpy {__version__}")
    print(f"core threads (OpenMP): {max_threads()}")
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


def _tools_build(args: argparse.Namespace) -> int:
    from ddpy.cad import CadError, build_tool_models

    models = [m.strip() for m in args.models.split(",") if m.strip()]
    try:
        paths = build_tool_models(
            args.cad, args.out, args.name or Path(args.cad).stem,
            patches_per_arc=args.patches_per_arc, facets_per_arc=args.facets_per_arc,
            element=args.element, size=args.size, arc_size=args.arc_size,
            blank_side=args.blank_side,
            blank_point=args.blank_point, bezier_tol=args.bezier_tol,
            bezier_angle_tol=args.bezier_angle_tol, faces=args.faces, models=models)
    except (CadError, ValueError) as error:
        return _fail("tools build", error, 2)  # the CAD file or an option
    except OSError as error:  # the output folder: permissions, space
        where = error.filename or args.out
        print(f"ddpy tools build: error: {where}: {error.strerror or error}", file=sys.stderr)
        return 1
    for path in paths.values():
        print(path)
    return 0


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
    tools = commands.add_parser("tools", help="tool models from CAD (Bezier, Nagata, facets) "
                                "and their shape error")
    group = tools.add_subparsers(dest="tools_command", metavar="TOOLS_COMMAND", required=True)
    build = group.add_parser(
        "build", help="write <name>.nagata.tool, <name>.facets.tool and <name>.bezier.tool",
        description="Read a CAD file (STEP, IGES, BREP) and write Nagata, facet and Bezier tool "
        "files (docs/tool-files.md). Densities count patches per 90 degrees of arc. Give "
        "negative vectors with '=', e.g. --blank-side=0,0,-1.")
    build.add_argument("cad", metavar="CAD", help="STEP, IGES or BREP file")
    build.add_argument("--name", help="tool name (default: the CAD file's stem)")
    build.add_argument("--out", default=".", metavar="DIR", help="output folder (default: .)")
    build.add_argument("--patches-per-arc", type=int, default=4, metavar="N",
                       help="Nagata patches per 90 degrees along curved edges (default 4)")
    build.add_argument("--facets-per-arc", type=int, default=30, metavar="N",
                       help="facets per 90 degrees along curved edges (default 30)")
    build.add_argument("--element", choices=("quad", "tri"), default="quad")
    build.add_argument("--size", type=float, metavar="MM",
                       help="largest element along straight edges (default: one element)")
    build.add_argument("--arc-size", type=float, metavar="MM",
                       help="largest element along curved edges too, e.g. around a large "
                       "surface of revolution (default: by the angle only)")
    build.add_argument("--blank-side", type=_triple, default=(0.0, 0.0, 1.0), metavar="X,Y,Z",
                       help="direction towards the blank (default 0,0,1)")
    build.add_argument("--blank-point", type=_triple, metavar="X,Y,Z",
                       help="a point on the blank side (instead of --blank-side)")
    build.add_argument("--bezier-tol", type=float, default=1.0e-3, metavar="MM",
                       help="largest Bezier deviation from the CAD (default 0.001 mm)")
    build.add_argument("--bezier-angle-tol", type=float, default=0.01, metavar="DEG",
                       help="largest Bezier normal error (default 0.01 degrees)")
    build.add_argument("--faces", type=_int_list, metavar="TAGS",
                       help="CAD faces to use, e.g. 1,2,5 (default: all)")
    build.add_argument("--models", default="nagata,facets,bezier", metavar="LIST",
                       help="models to write (default nagata,facets,bezier)")
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
                       "cylindrical-bending, deep-drawing")
    check.add_argument("--no-geometry", action="store_true",
                       help="skip the checks of the tool positions against the blank")
    check.set_defaults(handler=_check)

    _add_tools(commands)
    add_run(commands)
    add_post(commands)

    info = commands.add_parser("info", help="version, threads and linked libraries")
    info.set_defaults(handler=_info)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``ddpy`` console command."""
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
