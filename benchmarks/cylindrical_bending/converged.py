"""The converged answer of the built-in bending case: its decks (the benchmark's Nagata tools
and process, Hill'48 steel, ddpy's defaults) on a blank 16 times finer than the built-in one
(240 x 6 x 2 solid-shells: 0.25 mm along the strip, 2.5 mm across), the answer the tests'
small blank is held to (tests/test_cylindrical_bending.py reads it).

    python benchmarks/cylindrical_bending/converged.py          # the 240 x 6 x 2 blank, 1 thread
    python benchmarks/cylindrical_bending/converged.py --blank 240,3,2   # a check blank

Runs into converged/<blank>/ next to this script (git-ignored) and writes the numbers, with
the code and the date, into docs/benchmarks/cylindrical_bending_converged.json (keyed by
blank, merged): the punch force on its 1 mm moving mean at STROKES, beta_1 and beta_2 (one
flange's angle to the vertical, the tests' measure), and the chatter of the force.
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import DOCS, load_module  # noqa: E402

bench = load_module(HERE / "run.py", "cylindrical_bending_run")
make_case = bench.make_case

MODEL = "nagata"
BLANK = (240, 6, 2)
#: Where the force is compared (mm of stroke), on its mean over +-0.5 mm.
STROKES = (3.0, 5.0, 10.0, 20.0)
OUTPUT = DOCS / "cylindrical_bending_converged.json"


def moving_mean(stroke: np.ndarray, force: np.ndarray, at: float) -> float:
    """The force's mean over the 1 mm of stroke around ``at``, on a 0.01 mm grid."""
    fine = np.arange(at - 0.5, at + 0.5 + 1e-9, 0.01)
    return float(np.interp(fine, stroke, force).mean())


def run_blank(blank: tuple[int, int, int]) -> dict[str, object]:
    """Run the built-in case's decks on ``blank`` (nx, ny, layers); its numbers."""
    label = "x".join(str(n) for n in blank)
    root = HERE / "converged" / label
    if not (root / "tools" / "die.nagata.tool").exists():
        make_case.build_tools(root / "tools")
    make_case.coarse_mesh(root / "meshes" / f"{label}.msh", *blank)
    folder = make_case.write_case(root / "cases" / label / MODEL, MODEL, label)
    run = bench.run_case_folder(folder, root / "results", verbose=True)
    numbers = bench.summary(MODEL, run)
    return {
        "blank": list(blank), "code": numbers["code"], "status": numbers["status"],
        "date": datetime.date.today().isoformat(),
        "clearance_mm": make_case.CLEARANCE,
        "strokes": list(STROKES),
        "force_N": [round(moving_mean(run.stroke, run.force, s), 2) for s in STROKES],
        "beta1_deg": round(float(numbers["beta1_deg"]), 2),
        "beta2_deg": round(float(numbers["beta2_deg"]), 2),
        "theta_deg": numbers["theta_deg"],
        "oscillation_rel": numbers["oscillation_rel"],
        "increments": numbers["increments"], "iterations": numbers["iterations"],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--blank", default=",".join(str(n) for n in BLANK),
                        help="elements along, across, layers (default %(default)s)")
    args = parser.parse_args(argv)
    blank = tuple(int(n) for n in args.blank.split(","))
    numbers = run_blank(blank)  # type: ignore[arg-type]
    kept = json.loads(OUTPUT.read_text()) if OUTPUT.exists() else {}
    kept["x".join(str(n) for n in blank)] = numbers
    OUTPUT.write_text(json.dumps(kept, indent=1) + "\n")
    print(json.dumps(numbers, indent=1))
    return 0 if numbers["status"] == "completed" else 1


if __name__ == "__main__":
    raise SystemExit(main())
