"""Benchmark: a strip one element wide bent over a cylindrical punch, per tool description.

The plane-strain section of the paper's unconstrained cylindrical bending (Numisheet 2002,
paper Fig. 9, Table 3; issue 5 item 7): half of a 120 x 1 mm HSS strip (u_x = 0 at x = 0,
every node held in y), pressed by a punch of radius 23.5 mm into an open die whose shoulder
of radius 4 mm is centred 29.5 mm from the symmetry plane (a reconstruction of Fig. 6, as
examples/bending). Punch and die are built as CAD (gmsh) and turned into tool models by
``ddpy.cad.build_tool_models``: Bezier patches, Nagata patches (4 per 90 degrees), coarse and
fine facets (10 and 30 per 90 degrees). Measured per description: the punch force and its
oscillation, Newton iterations per increment, increments, time.

    python benchmarks/strip_bending/run.py                  # writes docs/benchmarks/strip_bending*
    python benchmarks/strip_bending/run.py --stroke 28.5    # the paper's stroke
    python benchmarks/strip_bending/run.py --json           # prints the numbers only
    python benchmarks/strip_bending/run.py --report-only    # the report again from the JSON
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy.cad import build_tool_models, gmsh_session
from ddpy.cad.examples import write_cad
from ddpy.cad.shape_error import shape_error
from ddpy.core.parallel import threads
from ddpy.io.toolfile import ToolModel, read_tool
from ddpy.model.control import IncrementLimits, NewtonSettings
from ddpy.model.forming import FormingError, FormingProblem, RigidTool, blank_stiffness
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "benchmarks"
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmarks' shared module
from bench_common import code_version, computed_at  # noqa: E402

PUNCH_RADIUS, DIE_RADIUS, SHOULDER_X = 23.5, 4.0, 29.5    # mm
HALF_LENGTH, THICK, WIDTH = 60.0, 1.0, 1.0                 # the half strip, one element wide
FRICTION, MAX_INCREMENT, FULL_STROKE = 0.148, 0.114, 28.5  # the paper's
TOOL_Y, LINE_PIECE = (-2.0, 3.0), 5.0                      # tools span y with a margin
HSS = Material(210e3, 0.3, Hill48(F=0.254, G=0.397, H=0.603, L=1.5, M=1.5, N=1.689),
               Swift(K=645.3, eps0=0.0102, n=0.252))
KINDS = {"bezier": "Bezier", "nagata": "Nagata", "facets_coarse": "facets, coarse",
         "facets_fine": "facets, fine"}
PER_ARC = {"nagata": 4, "facets_coarse": 10, "facets_fine": 30}  # pieces per 90 degrees
PAPER = {"bezier": (338, 3994, 94.6), "nagata": (342, 3918, 94.5),    # Table 3, 3-D model:
         "facets_coarse": (517, 4839, 112.1), "facets_fine": (447, 4439, 95.1)}  # inc, it, min
#: The driver's r_min limits but for the elasto-plastic transition: in bending a Gauss point
#: starts to yield in almost every increment, and landing each on the yield surface cuts
#: the increments to a few um of stroke (measured: 511 increments for the first mm).
LIMITS = IncrementLimits(yield_tolerance=None)
#: The Newton loop's convergence: the defaults of a deck that sets nothing.
NEWTON = NewtonSettings()
#: Augmentation r of the contact law (N/mm). The driver's default, E times the element size
#: (1.2e5 N/mm here), makes this run cut increments again and again (measured over the
#: first 1.5 mm with Nagata tools: 62 increments, 716 iterations, 44 cuts; with 100 N/mm:
#: 20 increments, 213 iterations, 3 cuts).
AUGMENTATION = 100.0
WINDOW = 0.5   # mm: half width of the local quadratic fit that smooths the force


# -- tools -------------------------------------------------------------------------------

def _arc_faces(centre: tuple[float, float], radius: float, angles: list[float],
               lines: list[tuple[tuple[float, float], tuple[float, float]]]) -> None:
    """Add to the gmsh model the xz-profile of arcs about ``centre`` through ``angles``
    (degrees, each arc below 180) and straight ``lines``, extruded over TOOL_Y."""
    import gmsh

    occ = gmsh.model.occ
    y0 = TOOL_Y[0]
    c = occ.addPoint(centre[0], y0, centre[1])
    ends = [occ.addPoint(centre[0] + radius * np.cos(np.radians(a)), y0,
                         centre[1] + radius * np.sin(np.radians(a))) for a in angles]
    curves = [occ.addCircleArc(a, c, b) for a, b in zip(ends[:-1], ends[1:], strict=True)]
    for p, q in lines:
        curves.append(occ.addLine(occ.addPoint(p[0], y0, p[1]), occ.addPoint(q[0], y0, q[1])))
    occ.extrude([(1, k) for k in curves], 0, TOOL_Y[1] - TOOL_Y[0], 0)
    occ.synchronize()


def build_tools(folder: Path) -> dict[str, tuple[ToolModel, ToolModel]]:
    """(punch, die) models of every description, from STEP files written in ``folder``:
    the punch's lower half (its crest on the strip's top at x = 0), the die's shoulder and
    land (its top at z = 0, under the strip's bottom from x = 29.5 mm on)."""
    with gmsh_session():
        import gmsh

        gmsh.model.add("punch")
        _arc_faces((0.0, THICK + PUNCH_RADIUS), PUNCH_RADIUS, [-180.0, -90.0, 0.0], [])
        write_cad(folder / "punch.step")
        gmsh.model.add("die")
        _arc_faces((SHOULDER_X, -DIE_RADIUS), DIE_RADIUS, [180.0, 90.0],
                   [((SHOULDER_X, 0.0), (HALF_LENGTH + 10.0, 0.0))])
        write_cad(folder / "die.step")
    models: dict[str, list[ToolModel]] = {kind: [] for kind in KINDS}
    for name, side in (("punch", (0, 0, -1)), ("die", (0, 0, 1))):
        step = folder / f"{name}.step"
        common = {"size": LINE_PIECE, "blank_side": side}
        paths = build_tool_models(step, folder, name, patches_per_arc=PER_ARC["nagata"],
                                  facets_per_arc=PER_ARC["facets_fine"], **common)
        coarse = build_tool_models(step, folder, f"{name}_coarse", models=("facets",),
                                   facets_per_arc=PER_ARC["facets_coarse"], **common)
        for kind, path in (("bezier", paths["bezier"]), ("nagata", paths["nagata"]),
                           ("facets_coarse", coarse["facets"]),
                           ("facets_fine", paths["facets"])):
            models[kind].append(read_tool(path))
    return {kind: (pair[0], pair[1]) for kind, pair in models.items()}


# -- the runs ----------------------------------------------------------------------------

def strip_mesh() -> HexMesh:
    """The half strip: 120 x 1 x 3 hexahedra."""
    return HexMesh.box(HALF_LENGTH, WIDTH, THICK, 120, 1, 3)


def run_description(kind: str, punch: ToolModel, die: ToolModel, stroke: float) -> dict:
    """Form the half strip with one description; the numbers of the run."""
    mesh = strip_mesh()
    tools = [RigidTool("punch", punch.surface, mesh.select(z=THICK), FRICTION, (0, 0, 1),
                       AUGMENTATION),
             RigidTool("die", die.surface, mesh.select(z=0.0), FRICTION, (0, 0, -1),
                       AUGMENTATION)]
    problem = FormingProblem(Solid(mesh, HSS, rolling_direction_deg=0.0), tools)
    problem.fix(mesh.select(x=0.0), "x")         # symmetry plane
    problem.fix(np.arange(mesh.n_nodes), "y")    # plane strain
    error = ""
    wall, cpu = time.perf_counter(), time.process_time()
    try:
        result = problem.run({"punch": (0.0, 0.0, -stroke)}, MAX_INCREMENT, newton=NEWTON,
                             limits=LIMITS)
    except FormingError as failure:
        result, error = failure.result, str(failure)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    problem.close()
    travel = -np.array([d[2] for d in result.tool_displacements["punch"]])
    force = 2.0 * np.array([f[2] for f in result.tool_forces["punch"]]) / WIDTH
    errors = {name: shape_error(model, samples=21) for name, model in
              (("punch", punch), ("die", die))}
    return {
        "kind": kind, "label": KINDS[kind], "error": error,
        "patches": {"punch": punch.n_patches, "die": die.n_patches},
        "shape_um": {n: 1e3 * e.max_distance for n, e in errors.items()},
        "normal_deg": {n: e.max_angle for n, e in errors.items()},
        "stroke": travel.round(7).tolist(), "force": force.round(5).tolist(),
        "iterations": result.iterations, "limited_by": result.limited_by,
        "cuts": result.cuts, "wall_s": wall, "cpu_s": cpu, "timings": result.timings,
        "die_contacts": result.contacts["die"], "punch_contacts": result.contacts["punch"],
    }


def smoothed(stroke: NDArray[np.float64], force: NDArray[np.float64]) -> NDArray[np.float64]:
    """The force smoothed by a local quadratic least-squares fit over +-WINDOW mm."""
    out = np.empty_like(force)
    for i, centre in enumerate(stroke):
        near = np.abs(stroke - centre) <= WINDOW
        coef = np.polyfit(stroke[near] - centre, force[near], min(2, int(near.sum()) - 1))
        out[i] = coef[-1]
    return out


def oscillation(run: dict, lo: float = 1.0) -> dict[str, float]:
    """Past ``lo`` mm (the elastic start and first yield left out), relative to the mean
    force: the RMS deviation of the force from its smoothed curve, and the largest one."""
    s, f = np.array(run["stroke"]), np.array(run["force"])
    keep = s > lo
    if keep.sum() < 8:
        return {"rms": float("nan"), "max": float("nan")}
    deviation = (f - smoothed(s, f))[keep] / f[keep].mean()
    return {"rms": float(np.sqrt(np.mean(deviation**2))), "max": float(np.abs(deviation).max())}


# -- report ------------------------------------------------------------------------------

STYLE = {"bezier": ("tab:blue", "-"), "nagata": ("tab:green", "--"),
         "facets_coarse": ("tab:red", "-"), "facets_fine": ("tab:orange", "-")}


def figures(runs: list[dict], out: Path) -> tuple[float, float]:
    """The force (whole and a zoom on its last 20 %) and the iterations and increment size
    per increment; the zoom's stroke range."""
    from matplotlib.figure import Figure

    reached = min(max(r["stroke"], default=0.0) for r in runs)
    lo, hi = 0.8 * reached, reached
    fig = Figure(figsize=(11, 4.5), layout="constrained")
    whole, zoom = fig.subplots(1, 2, width_ratios=(1.6, 1))
    for r in runs:
        s, f = np.array(r["stroke"]), np.array(r["force"])
        colour, line = STYLE[r["kind"]]
        whole.plot(s, f, color=colour, ls=line, lw=1.1, label=r["label"])
        inside = (s >= lo) & (s <= hi)
        zoom.plot(s[inside], f[inside], color=colour, ls=line, lw=1.0, marker=".", ms=3)
    whole.axvspan(lo, hi, color="0.9", zorder=0)
    whole.set(xlabel="punch stroke [mm]", ylabel="punch force [N per mm of width]",
              title="Punch force (both halves of the strip)")
    whole.legend(loc="upper left")
    zoom.set(xlabel="punch stroke [mm]", title="zoom (dots: increments)")
    for ax in (whole, zoom):
        ax.grid(alpha=0.3)
    fig.savefig(out / "strip_bending_force.png", dpi=110)
    fig = Figure(figsize=(10, 6), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    for r in runs:
        s = np.array(r["stroke"])
        colour, line = STYLE[r["kind"]]
        top.plot(s, r["iterations"], color=colour, ls=line, lw=0.8, label=r["label"])
        bottom.plot(s, np.diff(s, prepend=0.0), color=colour, ls=line, lw=0.8)
    top.set(ylabel="Newton iterations", title="Iterations and size of every increment")
    top.legend(loc="upper left", ncols=4)
    bottom.set(xlabel="punch stroke [mm]", ylabel="increment [mm]", yscale="log")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.savefig(out / "strip_bending_iterations.png", dpi=110)
    return lo, hi


def report(runs: list[dict], meta: dict, out: Path) -> None:
    lo, hi = figures(runs, out)
    table = ["| description | punch / die patches | shape error punch / die [um] | normal "
             "error punch / die [deg] | stroke [mm] | increments | iterations | per "
             "increment | limited by release / touch / yield / strain / cut | cuts | wall "
             "[s] | CPU [s] | force at the end [N/mm] | oscillation RMS [%] | largest [%] |",
             "|---" * 15 + "|"]
    for r in runs:
        n, its = len(r["iterations"]), sum(r["iterations"])
        count = {k: r["limited_by"].count(k) for k in ("release", "touch", "yield", "strain",
                                                        "cut")}
        osc = oscillation(r)
        table.append(
            f"| {r['label']} | {r['patches']['punch']} / {r['patches']['die']} | "
            f"{r['shape_um']['punch']:.3g} / {r['shape_um']['die']:.3g} | "
            f"{r['normal_deg']['punch']:.2g} / {r['normal_deg']['die']:.2g} | "
            f"{max(r['stroke'], default=0):.2f}{' (failed)' if r['error'] else ''} | {n} | "
            f"{its} | {its / max(n, 1):.2f} | " + " / ".join(map(str, count.values()))
            + f" | {r['cuts']} | {r['wall_s']:.0f} | {r['cpu_s']:.0f} | "
            f"{r['force'][-1] if r['force'] else 0:.1f} | {100 * osc['rms']:.2f} | "
            f"{100 * osc['max']:.2f} |")
    by = {r["kind"]: oscillation(r)["rms"] for r in runs}
    smooth = max(by.get("bezier", np.nan), by.get("nagata", np.nan))
    verdict = ", ".join(f"{KINDS[k]} {by[k] / smooth:.2f}" for k in
                        ("facets_coarse", "facets_fine") if k in by)
    # The stroke at the end of each increment that a first touch or a release limited.
    events = {r["label"]: ", ".join(f"{s:.2f} ({why})" for s, why in zip(
        r["stroke"], r["limited_by"], strict=False) if why in ("touch", "release"))
        for r in runs}
    mesh = strip_mesh()
    default_r = blank_stiffness(mesh.nodes, mesh.elements, HSS.E)
    settings = (  # as the runs recorded them (older numbers files did not)
        f"tolerances {meta['newton']['force_tolerance']:g} (force) and "
        f"{meta['newton']['displacement_tolerance']:g} (correction); maximum increment "
        f"{MAX_INCREMENT:g} mm of punch travel (the paper's); the r_min limits first touch, "
        f"release, strain {meta['limits']['strain']:g} and rotation "
        f"{meta['limits']['rotation_deg']:g} degrees" if "newton" in meta else
        f"the tolerances of the code named above; maximum increment {MAX_INCREMENT:g} mm of "
        "punch travel (the paper's); the r_min limits first touch, release, strain and "
        "rotation")
    lines = [
        "# Strip bending: a cylindrical punch and an open die with each tool description",
        "",
        computed_at(meta.get("code") or meta.get("commit", "")),
        "",
        f"Written by `python benchmarks/strip_bending/run.py {meta['argv']}` in "
        f"{meta['total_s']:.0f} s on {meta['machine']}; load "
        f"average {meta['load'][0]:.2f} at the start, {meta['load'][1]:.2f} at the end (a "
        "shared machine: wall times are upper bounds, CPU times are the process's). The "
        "numbers are in `strip_bending.json`; `--report-only` rewrites this page from it.",
        "",
        "## What runs",
        "",
        f"* The half strip x in [0, {HALF_LENGTH:g}] mm, {THICK:g} mm thick, one element of "
        f"{WIDTH:g} mm across: 120 x 1 x 3 hexahedra (0.5 x 1 x 0.33 mm); u_x = 0 on x = 0 "
        "(symmetry), every node held in y (plane strain). HSS of the paper (Table 1): E = 210 "
        "GPa, nu = 0.3, Hill'48 F = 0.254, G = 0.397, H = 0.603, L = M = 1.5, N = 1.689, "
        "Swift K = 645.3 MPa, eps0 = 0.0102, n = 0.252.",
        f"* Punch: cylinder of radius {PUNCH_RADIUS:g} mm, its crest on the strip's top at "
        f"x = 0, moved down by {meta['stroke']:g} mm (the paper's full stroke is "
        f"{FULL_STROKE:g} mm; this stroke keeps the four runs within minutes on the 2 shared "
        f"cores). Die: shoulder of radius {DIE_RADIUS:g} mm centred at x = {SHOULDER_X:g} mm "
        "and a flat land under the strip from there on, no bottom. Both touch the strip at "
        "zero gap with no force at the start; nothing else holds it in z. The paper's drawing "
        "is not in its text: these are the dimensions of `examples/bending` (a reconstruction).",
        f"* Coulomb friction mu = {FRICTION:g}; augmentation r = {AUGMENTATION:g} N/mm (the "
        "driver's default when it was set, E times the element size, cut increment after "
        "increment here; the driver's default now, E t^2 / h of the elements, would be "
        f"{default_r:.2g} N/mm); {settings}, not the elasto-plastic transition (a Gauss "
        "point starts to yield in almost every increment of a bend, and landing each on the "
        "yield surface cut the increments short "
        "at commit 2aad867, before the limit left out points within its tolerance of the "
        "surface).",
        f"* Tool models from CAD by `build_tool_models` (size {LINE_PIECE:g} mm along straight "
        "edges and across): Bezier patches fitted to each CAD face within 1 um; Nagata "
        f"patches {PER_ARC['nagata']} per 90 degrees with exact CAD normals; facets "
        f"{PER_ARC['facets_coarse']} (coarse) and {PER_ARC['facets_fine']} (fine, as the "
        "paper's) per 90 degrees. Shape and normal errors against the CAD on 21 x 21 points "
        "per patch (`ddpy.cad.shape_error`).",
        "* Force oscillation: the punch force (both halves, per mm of width) minus its "
        f"smoothed curve (a local quadratic least-squares fit over +-{WINDOW:g} mm of "
        "stroke), past 1 mm of stroke, relative to the mean force there: its RMS and its "
        "largest value.",
        "",
        "## Results",
        "",
        *table,
        "",
        f"RMS oscillation of the facets over the larger of Bezier's and Nagata's: {verdict} "
        "(above 1: the facets oscillate more). The increments limited by a first touch or a "
        "release (a node meeting or leaving a tool inside the increment) end at (stroke, "
        "mm): "
        + "; ".join(f"{label} {text or 'none'}" for label, text in events.items()) + "."
        if verdict and np.isfinite(smooth) else "",
        "",
        "![punch force](strip_bending_force.png)",
        "",
        f"The zoom shows {lo:.2f} to {hi:.2f} mm of stroke, every increment a dot.",
        "",
        "![iterations](strip_bending_iterations.png)",
        "",
        "Limited by: how many increments each r_min limit shortened (the others ran at the "
        "maximum increment or grew back to it by doubling). Time split of the Newton loop "
        "(`FormingResult.timings`, s): " + "; ".join(
            f"{r['label']}: " + ", ".join(f"{k} {v:.1f}" for k, v in r["timings"].items())
            for r in runs) + ".",
        "",
        "The paper's effort for the full 3-D quarter model to 28.5 mm (Table 3): " + "; ".join(
            f"{KINDS[k]} {n} increments, {i} iterations ({i / n:.1f} per increment), {m:g} "
            "min" for k, (n, i, m) in PAPER.items()) + ".",
        *[f"\n{r['label']} stopped: `{r['error']}`." for r in runs if r["error"]],
    ]
    (out / "strip_bending.md").write_text("\n".join(lines) + "\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stroke", type=float, default=10.0,
                        help=f"punch stroke in mm, at most {FULL_STROKE} (default 10)")
    parser.add_argument("--kinds", nargs="+", default=list(KINDS), choices=list(KINDS))
    parser.add_argument("--threads", type=int, default=1, help="core threads (default 1)")
    parser.add_argument("--json", action="store_true", help="print the numbers only")
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the report and figures from OUT/strip_bending.json")
    parser.add_argument("--out", type=Path, default=DOCS)
    args = parser.parse_args(argv)
    if args.report_only:
        saved = json.loads((args.out / "strip_bending.json").read_text())
        report(saved["runs"], saved["meta"], args.out)
        return 0
    if not 0.0 < args.stroke <= FULL_STROKE:
        parser.error(f"--stroke must lie in (0, {FULL_STROKE}]")
    if args.threads < 1:
        parser.error("--threads must be at least 1")
    start, load = time.perf_counter(), os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp, threads(args.threads):
        models = build_tools(Path(tmp))
        runs = []
        for kind in args.kinds:
            runs.append(run_description(kind, *models[kind], args.stroke))
            r = runs[-1]
            print(f"{r['label']}: {max(r['stroke'], default=0):.2f} mm, "
                  f"{len(r['iterations'])} increments, {sum(r['iterations'])} iterations, "
                  f"{r['wall_s']:.0f} s", file=sys.stderr)
    meta = {"argv": " ".join(sys.argv[1:] if argv is None else argv), "stroke": args.stroke,
            "total_s": time.perf_counter() - start, "load": (load, os.getloadavg()[0]),
            "code": code_version(), "newton": asdict(NEWTON), "limits": asdict(LIMITS),
            "machine": f"{os.cpu_count()} CPUs ({platform.machine()}), {args.threads} core "
                       f"thread(s), Python {platform.python_version()}"}
    if args.json:
        json.dump({"meta": meta, "runs": runs}, sys.stdout, indent=1)
        print()
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "strip_bending.json").write_text(json.dumps({"meta": meta, "runs": runs}))
    report(runs, meta, args.out)
    print(f"wrote {args.out / 'strip_bending.md'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
