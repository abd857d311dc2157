"""The ``ddpy`` command."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ddpy import __version__


def _accuracy(args: argparse.Namespace) -> int:
    from ddpy import accuracy

    result = accuracy.arc_accuracy_study()
    if args.json:
        print(json.dumps(accuracy.summary(result), indent=2))
    else:
        print(accuracy.format_table(result))
    if args.figures:
        for path in accuracy.plot_figures(result, Path(args.figures)):
            print(f"wrote {path}", file=sys.stderr)
    return 0


def _info(args: argparse.Namespace) -> int:
    from ddpy.parallel import max_threads

    print(f"ddpy {__version__}")
    print(f"core threads (OpenMP): {max_threads()}")
    print("sparse solver: MUMPS (sequential)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ddpy",
        description="Implicit finite elements for sheet metal forming with Bezier, Nagata and "
        "faceted tool surfaces.",
    )
    parser.add_argument("--version", action="version", version=f"ddpy {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")

    accuracy = commands.add_parser(
        "accuracy",
        help="arc accuracy study: linear against Nagata interpolation (paper Fig. 3 and 4)",
    )
    accuracy.add_argument("--json", action="store_true", help="print the numbers as JSON")
    accuracy.add_argument("--figures", metavar="DIR", help="also write the figures (PNG) here")
    accuracy.set_defaults(handler=_accuracy)

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
    return int(args.handler(args))


if __name__ == "__main__":
    raise SystemExit(main())
