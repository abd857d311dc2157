"""Fit the bending die (the distance of its shoulder from the symmetry plane) to the paper's
contact angles theta_1..4 of its Bezier model, and measure what the clearance does to every
angle of Table 2.

    python benchmarks/cylindrical_bending/fit_die.py --mesh paper --clearances 1.5,1.6
    python benchmarks/cylindrical_bending/fit_die.py --mesh paper --reuse   # report only

(``--reuse`` also keeps a finished run found in fit/ that the runs file lacks.)

The clearance is the horizontal gap between the punch's side (x = its radius) and the inner
edge of the die's shoulder (the shoulder's centre minus its radius): make_case.CLEARANCE.
The paper's Fig. 6, which gives the die, is not in its text, so the die is a reconstruction
either way; this script makes the choice a measured one. For each clearance the benchmark's
Bezier case (its decks, the tools rebuilt for that die) runs into fit/<mesh>/c<clearance>/
(git-ignored); the numbers of every run are kept in
docs/benchmarks/cylindrical_bending_die_fit_runs.json, and the report
docs/benchmarks/cylindrical_bending_die_fit.md gives per clearance theta_1..4, beta_1 and
beta_2 (between the flanges) and the springback, the clearance that fits theta_1..4 to the
paper's Bezier column in least squares (the angles interpolated linearly between the runs),
and the change of every angle per 0.1 mm of clearance between neighbouring runs.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import code_version, load_module  # noqa: E402

bench = load_module(HERE / "run.py", "cylindrical_bending_run")
make_case = bench.make_case

MODEL = "bezier"
DOCS = HERE.parents[1] / "docs" / "benchmarks"
STEM = "cylindrical_bending_die_fit"
ANGLES = ("theta_1", "theta_2", "theta_3", "theta_4", "beta_1", "beta_2", "springback")


def shoulder_x(clearance: float) -> float:
    """The die shoulder's centre (distance from the symmetry plane, mm) for a clearance."""
    return make_case.PUNCH_RADIUS + clearance + make_case.SHOULDER_RADIUS


def angles(numbers: dict[str, Any]) -> dict[str, float]:
    """Table 2's angles of one run in the paper's measures (beta between the flanges)."""
    out = {f"theta_{i + 1}": float(t) for i, t in enumerate(numbers["theta_deg"])}
    out["beta_1"] = bench.between_flanges(numbers["beta1_deg"])
    out["beta_2"] = bench.between_flanges(numbers["beta2_deg"])
    out["springback"] = out["beta_2"] - out["beta_1"]
    return out


def paper_angles(model: str = MODEL) -> dict[str, float]:
    """The paper's column of Table 2 for ``model`` (Bezier by default)."""
    paper = bench.PAPER[model]
    out = {f"theta_{i + 1}": float(t) for i, t in enumerate(paper["theta"])}
    out["beta_1"], out["beta_2"] = float(paper["beta1"]), float(paper["beta2"])
    out["springback"] = out["beta_2"] - out["beta_1"]
    return out


def run_clearance(mesh: str, clearance: float, root: Path) -> dict[str, Any]:
    """Build the tools for the die at ``clearance``, write the Bezier case on ``mesh`` and run
    it; the run's numbers (``run.summary``) with the clearance and the code version."""
    folder = root / f"c{clearance:g}"
    make_case.build_tools(folder / "tools", shoulder_x=shoulder_x(clearance))
    blank = folder / "meshes" / f"{mesh}.msh"
    source = HERE / "meshes" / f"{mesh}.msh"
    blank.parent.mkdir(parents=True, exist_ok=True)
    if source.exists():  # the benchmark's own blank (the paper's is random from gmsh)
        shutil.copyfile(source, blank)
    elif mesh == "paper":
        make_case.paper_mesh(blank)
    else:
        make_case.coarse_mesh(blank)
    case = make_case.write_case(folder / "cases" / mesh / MODEL, MODEL, mesh)
    return kept_numbers(bench.run_case_folder(case, output=folder / "results", verbose=True),
                        clearance)


def kept_numbers(run: Any, clearance: float) -> dict[str, Any]:
    """What the runs file keeps of one run (``run.Run``) at ``clearance``."""
    numbers = bench.summary(MODEL, run)
    return {"clearance_mm": clearance, "shoulder_x_mm": shoulder_x(clearance),
            "code": numbers["code"], "status": numbers["status"],
            "increments": numbers["increments"], "iterations": numbers["iterations"],
            "theta_deg": numbers["theta_deg"], "beta1_deg": numbers["beta1_deg"],
            "beta2_deg": numbers["beta2_deg"]}


def fitted_clearance(runs: list[dict[str, Any]]) -> float | None:
    """The clearance whose theta_1..4, interpolated linearly between the runs, are nearest
    the paper's Bezier column in least squares; None with fewer than two runs."""
    if len(runs) < 2:
        return None
    runs = sorted(runs, key=lambda r: r["clearance_mm"])
    c = np.array([r["clearance_mm"] for r in runs])
    theta = np.array([r["theta_deg"] for r in runs])  # (runs, 4)
    target = np.array(bench.PAPER[MODEL]["theta"])
    grid = np.linspace(c[0], c[-1], 2001)
    cost = sum((np.interp(grid, c, theta[:, i]) - target[i]) ** 2 for i in range(4))
    return float(grid[int(np.argmin(cost))])


def sensitivity(runs: list[dict[str, Any]]) -> list[tuple[float, float, dict[str, float]]]:
    """Per pair of neighbouring runs, the change of every angle per 0.1 mm of clearance."""
    runs = sorted(runs, key=lambda r: r["clearance_mm"])
    out = []
    for a, b in zip(runs[:-1], runs[1:], strict=True):
        dc = b["clearance_mm"] - a["clearance_mm"]
        ga, gb = angles(a), angles(b)
        out.append((a["clearance_mm"], b["clearance_mm"],
                    {k: 0.1 * (gb[k] - ga[k]) / dc for k in ANGLES}))
    return out


def report(mesh: str, runs: list[dict[str, Any]]) -> str:
    """The markdown report of the fit."""
    runs = sorted(runs, key=lambda r: r["clearance_mm"])
    paper = paper_angles()
    codes = sorted({r["code"] for r in runs})
    lines = [
        "# The bending die, fitted to the paper's contact angles",
        "",
        f"Written by `benchmarks/cylindrical_bending/fit_die.py --mesh {mesh}` from its runs "
        f"(Bezier tools, the {mesh} blank, the benchmark's decks otherwise) at code "
        + ", ".join(f"`{c}`" for c in codes) + ".",
        "",
        "The paper's Fig. 6 (the tools' dimensions) is not in its text, so the die is a "
        f"reconstruction: punch radius {make_case.PUNCH_RADIUS:g} mm and shoulder radius "
        f"{make_case.SHOULDER_RADIUS:g} mm as the benchmark gives them, the shoulder's "
        "distance from the symmetry plane chosen here. The clearance is the horizontal gap "
        "between the punch's side and the shoulder's inner edge. theta and beta as in the "
        "benchmark's report (beta between the two flanges).",
        "",
        "| clearance (shoulder at) | status | " + " | ".join(ANGLES) + " |",
        "|---|---|" + "---|" * len(ANGLES),
    ]
    for r in runs:
        a = angles(r)
        lines.append(f"| {r['clearance_mm']:g} mm ({r['shoulder_x_mm']:g}) | {r['status']} | "
                     + " | ".join(f"{a[k]:.1f}" for k in ANGLES) + " |")
    lines.append("| the paper (Bezier) | | " + " | ".join(f"{paper[k]:.1f}" for k in ANGLES)
                 + " |")
    best = fitted_clearance(runs)
    lines += ["", "## The fit", ""]
    if best is None:
        lines.append("One run only: no fit yet.")
    else:
        c = np.array([r["clearance_mm"] for r in runs])
        fitted = {k: float(np.interp(best, c, [angles(r)[k] for r in runs])) for k in ANGLES}
        worst = max(abs(fitted[f"theta_{i}"] - paper[f"theta_{i}"]) for i in range(1, 5))
        lines += [
            f"theta_1..4 nearest the paper's Bezier column at a clearance of **{best:.2f} "
            f"mm** (the shoulder at {shoulder_x(best):.2f} mm), interpolated: "
            + ", ".join(f"{k} {fitted[k]:.1f} ({fitted[k] - paper[k]:+.1f})" for k in ANGLES)
            + f". The largest theta difference there: {worst:.1f} degrees.",
        ]
    lines += ["", "## Sensitivity: the change of each angle per 0.1 mm of clearance", "",
              "| between | " + " | ".join(ANGLES) + " |", "|---|" + "---|" * len(ANGLES)]
    for lo, hi, d in sensitivity(runs):
        lines.append(f"| {lo:g} and {hi:g} mm | " + " | ".join(f"{d[k]:+.2f}" for k in ANGLES)
                     + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mesh", choices=make_case.MESHES, default="coarse")
    parser.add_argument("--clearances", default="",
                        help="comma-separated clearances (mm) to run; the kept runs of other "
                        "clearances stay in the report")
    parser.add_argument("--reuse", action="store_true", help="report from the kept runs only")
    args = parser.parse_args(argv)
    kept_path = DOCS / f"{STEM}_runs.json"

    def load() -> dict[str, Any]:
        return json.loads(kept_path.read_text()) if kept_path.exists() else {}

    def keep(clearance: float, numbers: dict[str, Any]) -> None:
        # Read again right before writing: two runs of this script at once (a clearance
        # each, one thread each) must not lose each other's entry.
        kept = load()
        kept.setdefault(args.mesh, {})[f"{clearance:g}"] = numbers
        kept_path.write_text(json.dumps(kept, indent=1) + "\n")

    if args.reuse:  # a finished run in fit/ that the runs file lacks is read back
        for results in sorted((HERE / "fit" / args.mesh).glob("c*/results/results.h5")):
            clearance = float(results.parents[1].name[1:])
            if f"{clearance:g}" not in load().get(args.mesh, {}):
                keep(clearance, kept_numbers(bench.from_results(results), clearance))
    else:
        for text in (t for t in args.clearances.split(",") if t.strip()):
            clearance = float(text)
            print(f"running clearance {clearance:g} mm ...", file=sys.stderr, flush=True)
            keep(clearance, run_clearance(args.mesh, clearance, HERE / "fit" / args.mesh))
    runs = dict(load().get(args.mesh, {}))
    if not runs:
        parser.error("no runs: give --clearances")
    out = DOCS / (STEM + ("_paper" if args.mesh == "paper" else "") + ".md")
    out.write_text(report(args.mesh, list(runs.values())))
    print(f"wrote {out} (code {code_version()})", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
