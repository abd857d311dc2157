"""Unconstrained cylindrical bending (Numisheet 2002 B): the paper's Fig. 8, 9, 12, Tables 2, 3.

Runs the four tool models (Bezier, Nagata, coarse facets, fine facets) on one blank mesh and
writes docs/benchmarks/cylindrical_bending.md (cylindrical_bending_paper.md with --mesh paper)
with its figures, next to the paper's values.

    python benchmarks/cylindrical_bending/run.py                  # coarse blank (minutes)
    python benchmarks/cylindrical_bending/run.py --mesh paper     # 20,010 hexahedra (hours)
    python benchmarks/cylindrical_bending/run.py --json           # print the numbers only
    python benchmarks/cylindrical_bending/run.py --reuse          # report from saved runs
    python benchmarks/cylindrical_bending/run.py --mesh paper --restart   # continue them

The cases are written first by make_case.py (tools, meshes, decks) when missing; each case
runs through the case runner (``ddpy run``) into results/<mesh>/<model>/ (git-ignored), which
``--reuse`` reads back. Every report also keeps the numbers and curves of its runs, with the
code version and date of each, in docs/benchmarks/<report>_runs.json (merged: a model not
run keeps its entry); ``--reuse`` takes a model without results/ from there, so the paper
mesh's runs, hours each, may come from different sessions (the report says which code
made each).
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ddpy.model.control import IncrementLimits
from ddpy.studies.bending import contact_angle, force_oscillation, line_angle

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import (  # noqa: E402
    DOCS,
    code_version,
    computed_at,
    cores,
    deepest_per_tool,
    load_module,
    record_code,
    recorded_code,
    restart_plan,
    runs_file,
)
from bench_common import table_row as _row  # noqa: E402

make_case = load_module(HERE / "make_case.py", "bending_make_case")
MODELS: tuple[str, ...] = make_case.MODELS
LABELS = {"bezier": "Bezier", "nagata": "Nagata", "facets_coarse": "Faceted-coarse",
          "facets_fine": "Faceted-fine"}
#: The paper's Table 2 (theta_1..4 at 7, 14, 21, 28.5 mm; beta_1, beta_2) and Table 3.
PAPER = {
    "bezier": {"theta": [18.4, 60.9, 109.4, 155.3], "beta1": 20.7, "beta2": 35.2,
               "increments": 338, "iterations": 3994, "cpu_min": 94.6},
    "nagata": {"theta": [18.4, 61.7, 110.4, 155.7], "beta1": 20.7, "beta2": 35.0,
               "increments": 342, "iterations": 3918, "cpu_min": 94.5},
    "facets_coarse": {"theta": [20.0, 56.7, 106.5, 155.9], "beta1": 20.7, "beta2": 33.6,
                      "increments": 517, "iterations": 4839, "cpu_min": 112.1},
    "facets_fine": {"theta": [19.7, 62.9, 112.5, 155.6], "beta1": 20.8, "beta2": 34.9,
                    "increments": 447, "iterations": 4439, "cpu_min": 95.1},
}
#: The punch's axis at the start (make_case's geometry): x = 0, z = thickness + radius.
AXIS0 = np.array([0.0, 0.0, make_case.THICKNESS + make_case.PUNCH_RADIUS])
#: Force oscillation: moving quadratic over 1 mm of stroke, from 1 mm on (the first
#: millimetre is the elastic-plastic transition, a real bend in the curve).
WINDOW, START = 1.0, 1.0
#: The free flange for beta: material initially beyond this x, past the die shoulder.
FLANGE_X = 45.0
#: Degrees of arc of one coarse facet (a Nagata patch made flat) and of one fine facet.
COARSE_FACET = 90.0 / make_case.PATCHES_PER_ARC
FINE_FACET = 90.0 / make_case.FACETS_PER_ARC


@dataclass
class Run:
    """What the report needs of one run (quarter model; forces in N on the quarter)."""

    stroke: np.ndarray            # punch travel after each forming increment, mm
    force: np.ndarray             # punch force (the blank pushing it up), N
    sizes: np.ndarray             # increment sizes, mm of punch travel
    iterations: np.ndarray        # Newton iterations per increment
    cuts: int
    theta: list[float]            # at make_case.OUTPUT_AT
    shape_formed: np.ndarray      # (n, 3) node positions at the end of forming
    shape_sprung: np.ndarray      # (n, 3) after springback
    initial: np.ndarray           # (n, 3) initial node positions
    wall_s: float
    springback_iterations: int = 0
    status: str = "completed"
    limits: dict[str, int] | None = None  # what limited the forming increments, counted
    #: by what ended each forming increment: increments, accepted iterations, Newton
    #: corrections of all its trials (0 where not recorded) and wall time, s
    effort_by_limit: dict[str, list[float]] | None = None
    #: nodes in contact with each tool, mean over the forming increments
    contact_nodes: dict[str, float] | None = None
    #: the deepest slave node in each tool at any converged forming increment, mm (the
    #: solver's record; None: not recorded)
    penetration_mm: dict[str, float] | None = None
    #: wall time of the whole run (forming and springback) by part, s: assembly, contact,
    #: linear (factorizations, solves, GMRES), rest
    times: dict[str, float] | None = None
    factorizations: int = 0
    krylov_iterations: int = 0
    all_iterations: int = 0       # Newton iterations of the whole run, springback included
    #: Newton corrections and residual evaluations of all trials of the forming, the
    #: rejected ones and the line search included (0: not recorded)
    newton_iterations: int = 0
    evaluations: int = 0
    threads: int = 0              # OpenMP threads of the run (0: not recorded)
    peak_memory_mb: float | None = None  # the run's peak resident memory (None: not recorded)
    #: code version (git describe) and date of the run; numbers of a run kept in the runs
    #: file (no shapes): summary() returns them as they are
    code: str = ""
    date: str = ""
    #: the deck's rmin_release_redos (None: no cap; runs recorded before the cap had none)
    release_redos: int | None = None
    #: the dates the run was continued on from its checkpoint (a run made at once: none)
    continued: list[str] = field(default_factory=list)
    kept: dict[str, Any] = field(default_factory=dict)


def from_results(path: Path, output_at: tuple[float, ...] = make_case.OUTPUT_AT) -> Run:
    """Read one run back from its results file (docs/results-format.md): the curves, the
    contact angles from the frames at the strokes of Table 2 (``output_at`` in the decks),
    the shapes at the end of forming and after springback."""
    from ddpy.io.results import ResultsReader

    with ResultsReader(path) as r:
        history = r.history()
        forming = history["phase"] == 0
        punch = r.tools.index("punch")
        stroke = history["travel"][forming]
        force = r.tool_force("punch")[forming][:, 2]  # the blank pushes the punch up
        frames = r.frames
        theta = []
        for at in output_at:
            frame = next((f for f in frames if f.phase == 0 and abs(f.travel - at) < 1e-6),
                         None)
            if frame is None:  # a run that stopped before this stroke
                theta.append(float("nan"))
                continue
            fields = r.frame(frame.index)
            tool_disp = r.tool_displacement("punch")[frame.increment - 1]
            theta.append(contact_angle(fields["coordinates"], fields["contact_tool"] == punch,
                                       AXIS0 + tool_disp))
        formed = max((f for f in frames if f.phase == 0), key=lambda f: f.increment)
        sprung = frames[-1] if frames[-1].phase == 1 else None
        status = "completed" if sprung is not None else "partial"
        effort = _effort_by_limit(history, forming)
        return Run(stroke=stroke, force=force, sizes=history["step"][forming],
                   iterations=history["iterations"][forming],
                   cuts=int(history["cutbacks"][forming].sum()), theta=theta,
                   shape_formed=r.field("coordinates", formed.index),
                   shape_sprung=r.field("coordinates", sprung.index) if sprung else
                   np.full_like(r.nodes, np.nan), initial=r.nodes,
                   wall_s=float(history["time_total"].sum()),
                   springback_iterations=int(history["iterations"][~forming].sum()),
                   status=status, limits={k: e[0] for k, e in effort.items()},
                   effort_by_limit=effort,
                   contact_nodes={tool: round(float(np.mean(
                       history["nodes_in_contact"][forming][:, i])), 1)
                       for i, tool in enumerate(r.tools)},
                   penetration_mm=deepest_per_tool(history, forming, r.tools),
                   times=_times(history),
                   factorizations=int(history.get("factorizations", np.zeros(1)).sum()),
                   krylov_iterations=int(history.get("krylov_iterations",
                                                     np.zeros(1)).sum()),
                   all_iterations=int(history["iterations"].sum()),
                   newton_iterations=_forming_sum(history, "newton_iterations", forming),
                   evaluations=_forming_sum(history, "evaluations", forming),
                   threads=r.threads, peak_memory_mb=r.peak_memory_mb,
                   **recorded_code(path.parent))


def _effort_by_limit(history: dict[str, np.ndarray], forming: np.ndarray
                     ) -> dict[str, list[float]]:
    """Per limit that ended a forming increment: increments, accepted iterations, Newton
    corrections of all trials (rejected ones included; 0 where not recorded), wall time."""
    from ddpy.io.results import LIMITS

    codes = np.asarray(history["limit"], dtype=int)
    out = {}
    for code in np.unique(codes[forming]):
        mask = forming & (codes == code)
        out[LIMITS[int(code)]] = [
            int(mask.sum()), int(history["iterations"][mask].sum()),
            _forming_sum(history, "newton_iterations", mask),
            round(float(history["time_total"][mask].sum()), 1)]
    return out


def _depth(depths: dict[str, float] | None, tool: str) -> str:
    """One tool's deepest node as the report gives it."""
    if not depths or tool not in depths:
        return "not recorded"
    return f"{depths[tool]:.2g} ({100 * depths[tool] / make_case.THICKNESS:.2g} %)"


def _forming_sum(history: dict[str, np.ndarray], name: str, forming: np.ndarray) -> int:
    """A counter over the forming increments (0 in a file that does not record it)."""
    return int(history[name][forming].sum()) if name in history else 0


#: The parts of an iteration's time that add up to it (Table 3).
PARTS = ("assembly", "contact", "linear", "rest")


def _times(history: dict[str, np.ndarray]) -> dict[str, float]:
    """Wall time of a run by part, s: PARTS, linear being the LU factorizations and the
    solutions with the factors (GMRES included); with these two apart as factorization and
    solve when the results file has them (time_solve, since 2026-11-25)."""
    part = {key: float(history[f"time_{key}"].sum())
            for key in ("assembly", "contact", "factorization", "rest")}
    out = {"assembly": part["assembly"], "contact": part["contact"],
           "linear": part["factorization"], "rest": part["rest"]}
    if "time_solve" in history:
        solve = float(history["time_solve"].sum())
        out.update(linear=part["factorization"] + solve, factorization=part["factorization"],
                   solve=solve)
    return out


def _per_iteration(numbers: dict[str, Any]) -> tuple[dict[str, float], float]:
    """A run's seconds per iteration by part (PARTS) and their sum."""
    per = {k: v for k, v in numbers["per_iteration_s"].items() if k in PARTS}
    return per, sum(per.values())


#: What a run says about time (Table 3, the target), kept from a run alone on the machine.
TIMING = ("wall_s", "threads", "code", "date", "increments", "iterations", "per_iteration_s",
          "factorizations", "krylov_iterations")


def timed_alone(numbers: dict[str, Any], earlier: dict[str, Any] | None,
                n_cores: int) -> dict[str, Any] | None:
    """The wall time of a model's run alone on the machine: this run's when it completed with
    a thread per core (docs/running.md: runs that share the cores take one thread each);
    else ``earlier``'s (the runs file's record) when that run took the same path, the same
    increments and iterations: the path does not depend on the threads, so it was the same
    computation; else None."""
    if numbers["threads"] >= n_cores and numbers["status"].startswith("completed"):
        return {key: numbers[key] for key in TIMING}
    if earlier and (earlier["increments"], earlier["iterations"]) == \
            (numbers["increments"], numbers["iterations"]):
        return earlier
    return None


def keep_runs(path: Path, numbers: dict[str, dict[str, Any]], runs: dict[str, Run]) -> None:
    """Merge the numbers and curves of ``runs`` into the runs file ``path``."""
    kept = json.loads(path.read_text()) if path.exists() else {}
    for model, run in runs.items():
        kept[model] = {"numbers": numbers[model],
                       "curves": {"stroke": np.round(run.stroke, 6).tolist(),
                                  "force": np.round(run.force, 5).tolist(),
                                  "sizes": np.round(run.sizes, 8).tolist(),
                                  "iterations": np.asarray(run.iterations).tolist()}}
    path.write_text(json.dumps(kept, indent=1) + "\n")


def kept_runs(path: Path) -> dict[str, Run]:
    """The runs of the runs file ``path`` by model (none when it does not exist)."""
    if not path.exists():
        return {}
    empty = np.zeros((0, 3))
    runs = {}
    for model, entry in json.loads(path.read_text()).items():
        curves, numbers = entry["curves"], entry["numbers"]
        runs[model] = Run(
            stroke=np.array(curves["stroke"]), force=np.array(curves["force"]),
            sizes=np.array(curves["sizes"]), iterations=np.array(curves["iterations"]),
            cuts=numbers["cuts"], theta=numbers["theta_deg"], shape_formed=empty,
            shape_sprung=empty, initial=empty, wall_s=numbers["wall_s"],
            status=numbers["status"], code=numbers.get("code", ""),
            date=numbers.get("date", ""), release_redos=numbers.get("release_redos"),
            kept=numbers)
    return runs


def deck_numbers(folder: Path) -> dict[str, Any]:
    """What a run's numbers keep of its deck: the discretization (element and contact) and
    the forming phase's Newton tolerance on the force (``newton_force``), which sets how
    closely two runs' forces can agree."""
    from ddpy.io.decks import read_case

    deck = read_case(folder, geometry=False)
    return {"discretization": ", ".join(
                [deck.element, *sorted({t.discretization for t in deck.tools})]).replace(
                    "gauss", "Gauss-point").replace("node", "node-to-surface"),
            "newton_force": deck.phases[0].newton.force_tolerance}


def run_case_folder(folder: Path, output: Path | None = None, verbose: bool = False,
                    max_increments: int | None = None, restart: bool = False) -> Run:
    """Run one case folder with the case runner (``ddpy run``) into ``output`` (default:
    results/<mesh>/<model> next to this script) and read back what the report needs. A run
    stopped after ``max_increments`` or failed is read as far as it got (``Run.status``);
    ``restart`` continues the run saved there from its last checkpoint."""
    from ddpy.app.runner import Progress, run_case
    from ddpy.io.decks import read_case

    output = output or HERE / "results" / folder.parent.name / folder.name

    def progress(p: Progress) -> None:
        if p.increment % 50 == 0:
            print(f"  {folder.name}: {p.phase} increment {p.increment}, travel "
                  f"{p.travel:.3f} of {p.phase_travel:g} mm", file=sys.stderr, flush=True)

    case = read_case(folder)
    record_code(output, code_version(), restart,
                release_redos=case.phases[0].limits.release_redos)
    outcome = run_case(case, output, overwrite=not restart, restart=restart,
                       progress=progress if verbose else None, max_increments=max_increments)
    run = from_results(outcome.results, case.phases[0].output_at)
    if not restart:  # a continued run: the increments' times of all its parts
        run.wall_s = outcome.wall_time
    run.status = outcome.status + (f": {outcome.message}" if outcome.message else "")
    return run


def betas(run: Run) -> tuple[float, float]:
    """beta_1, beta_2: angle to the vertical (the punch's direction) of the free flange (the
    material initially at x >= FLANGE_X, beyond the die shoulder) after forming and after
    springback, fitted through all its nodes (every layer)."""
    flange = run.initial[:, 0] >= FLANGE_X - 1e-9
    sprung = run.shape_sprung[flange]
    return (line_angle(run.shape_formed[flange], along=2, up=0),
            line_angle(sprung, along=2, up=0) if np.isfinite(sprung).all() else float("nan"))


def between_flanges(one_flange: float) -> float:
    """The paper's beta (its Fig. 11): the angle between the two flanges of the whole strip,
    twice the angle of one flange to the vertical (``betas``), the other half of the
    strip being its mirror image about the symmetry plane x = 0."""
    return 2.0 * one_flange


def tangent_bound(theta: float) -> float:
    """The largest angle to the vertical (degrees) one flange can have at full stroke with
    the contact angle theta (degrees): between the punch and the die shoulder the bending
    moment has one sign, so the flange stands steeper than the sheet's tangent at its last
    contact with the punch, which is 90 - theta / 2 from the vertical."""
    return 90.0 - theta / 2.0


def beta_reading(numbers: dict[str, dict[str, Any]], theta_step: float
                 ) -> tuple[list[str], str]:
    """Why the paper's beta is the angle between the two flanges, from the paper's own
    Table 2 and from the runs: the table's rows (per model: the statics bound on one flange,
    the paper's and ddpy's beta_1 against it, the springback each reading gives against the
    paper's) and the verdict they support. ddpy's theta comes from nodes, ``theta_step``
    degrees apart on the blank: theta is uncertain by half a step, its bound (theta / 2)
    by a quarter."""
    rows = []
    fits_one, fits_between, ours_within, ratio_one, ratio_between = [], [], [], [], []
    for m in (m for m in MODELS if m in numbers):
        paper, n = PAPER[m], numbers[m]
        bound_paper = tangent_bound(paper["theta"][-1])
        bound = tangent_bound(n["theta_deg"][-1])
        spring = n["beta2_deg"] - n["beta1_deg"]
        paper_spring = paper["beta2"] - paper["beta1"]
        fits_one.append(paper["beta1"] <= bound_paper)
        fits_between.append(paper["beta1"] / 2 <= bound_paper)
        ours_within.append(n["beta1_deg"] <= bound + theta_step / 4)
        ratio_one.append(spring / paper_spring)
        ratio_between.append(between_flanges(spring) / paper_spring)
        rows.append(
            f"| {LABELS[m]} | {bound_paper:.1f} | {paper['beta1']:.1f} | "
            f"{'yes' if fits_one[-1] else 'no'} | {'yes' if fits_between[-1] else 'no'} | "
            f"{bound:.1f} +- {theta_step / 4:.1f} | {n['beta1_deg']:.1f} | "
            f"{'yes' if ours_within[-1] else 'no'} | "
            f"{spring:.1f} / {between_flanges(spring):.1f} | {paper_spring:.1f} |")
    if not rows:
        return rows, ""
    which = ("only as the angle between the two flanges" if all(fits_between)
             and not any(fits_one) else "as one flange's angle too" if all(fits_one)
             else "in some models only")
    verdict = (
        f"The paper's beta_1 keeps the bound {which}; ddpy's one-flange beta_1 keeps its "
        f"own bound in {sum(ours_within)} of {len(rows)} models. ddpy's springback is "
        f"{min(ratio_one):.2f} to {max(ratio_one):.2f} times the paper's read as one "
        f"flange, {min(ratio_between):.2f} to {max(ratio_between):.2f} times read between "
        "the flanges.")
    return rows, verdict


def summary(model: str, run: Run) -> dict[str, Any]:
    """The numbers of one run."""
    if run.kept:
        return run.kept
    beta1, beta2 = betas(run)
    osc = (force_oscillation(run.stroke, run.force, WINDOW, start=START)
           if run.stroke.size and run.stroke[-1] >= START + WINDOW else float("nan"))
    late = (force_oscillation(run.stroke, run.force, WINDOW, start=20.0)
            if run.stroke.size and run.stroke[-1] >= 21.0 else float("nan"))
    return {
        "model": model,
        "status": run.status,
        "code": run.code,
        "date": run.date,
        "release_redos": run.release_redos,
        "stroke_mm": round(float(run.stroke[-1]), 3) if run.stroke.size else 0.0,
        "theta_deg": [round(t, 2) for t in run.theta],
        "beta1_deg": round(beta1, 2),
        "beta2_deg": round(beta2, 2),
        "increments": int(run.stroke.size),
        "iterations": int(run.iterations.sum()),
        "cuts": int(run.cuts),
        "springback_iterations": run.springback_iterations,
        "wall_s": round(run.wall_s, 1),
        "threads": run.threads,
        "max_force_N": round(float(run.force.max()), 2),
        "oscillation_N": round(osc, 4),
        "oscillation_after_20mm_N": round(late, 4),
        "oscillation_rel": round(osc / float(np.mean(np.abs(run.force))), 6),
        "full_size_increments": int(np.sum(run.sizes >= 0.999 * make_case.MAX_INCREMENT)),
        "factorizations": run.factorizations,
        "krylov_iterations": run.krylov_iterations,
        # the run's peak memory, MB
        "peak_memory_mb": (round(run.peak_memory_mb, 1) if run.peak_memory_mb is not None
                           else None),
        "newton_iterations_all": run.newton_iterations,
        "evaluations": run.evaluations,
        # seconds per Newton iteration of the whole run (springback included), by part
        "per_iteration_s": {part: round(t / max(run.all_iterations, 1), 4)
                            for part, t in (run.times or {}).items()},
        "limited_by": run.limits or {},
        "effort_by_limit": run.effort_by_limit or {},
        "contact_nodes": run.contact_nodes or {},
        "penetration_mm": run.penetration_mm,
        "end_xz_mm": [round(float(v), 2) for v in
                      run.shape_formed[run.initial[:, 0] >= make_case.LENGTH - 1e-9]
                      .mean(axis=0)[[0, 2]]],
    }


def shape_errors(tools: Path) -> dict[str, dict[str, dict[str, Any]]]:
    """Shape error of the four models of each tool against the CAD (paper Fig. 8), with the
    maps of the Nagata and fine facet dies. Returns {tool: {model: summary}}."""
    from ddpy.cad.shape_error import plot_shape_error, shape_error
    from ddpy.io.toolfile import read_tool

    out: dict[str, dict[str, dict[str, Any]]] = {}
    for tool in ("die", "punch"):
        nagata = read_tool(tools / f"{tool}.nagata.tool")
        models = {"bezier": read_tool(tools / f"{tool}.bezier.tool"), "nagata": nagata,
                  "facets_coarse": nagata.facets(),
                  "facets_fine": read_tool(tools / f"{tool}.facets.tool")}
        out[tool] = {}
        for name, model in models.items():
            error = shape_error(model, tools / "tools.step")
            out[tool][name] = error.summary()
            if tool == "die" and name in ("nagata", "facets_fine"):
                png = plot_shape_error(error, DOCS / f"cylindrical_bending_die_{name}.png")
                out[tool][name]["png"] = png.name
    return out


def theta_resolution(mesh: str) -> float:
    """The step (degrees) in which theta moves on ``mesh``'s blank: twice the arc between
    node columns over the punch; the paper's blank is unstructured, its spacing the square
    root of a layer's area per element."""
    spacing = (make_case.LENGTH / make_case.COARSE_X if mesh != "paper" else np.sqrt(
        make_case.LENGTH * make_case.WIDTH * make_case.LAYERS / make_case.PAPER_HEXAHEDRA))
    return float(2 * np.degrees(spacing / (make_case.PUNCH_RADIUS + make_case.THICKNESS)))


#: The paper's Nagata and Bezier angles agree within this many degrees (its Table 2: 1.0
#: at most). ddpy's theta comes from nodes, and a node column that reaches the punch in one
#: run and not yet in the other moves it by one step of its resolution: theta is held to
#: this plus that step.
SAME_ANGLES = 1.0


def claims(numbers: dict[str, dict[str, Any]], theta_step: float = 0.0
           ) -> list[tuple[str, bool, str]]:
    """The issue's claims, each with whether it holds here and the numbers behind it;
    ``theta_step``: the step in which theta moves on the blank (theta_resolution)."""
    out = []
    if {"facets_coarse", "facets_fine", "nagata", "bezier"} <= set(numbers):
        osc = {m: numbers[m]["oscillation_N"] for m in numbers}
        holds = min(osc["facets_coarse"], osc["facets_fine"]) > max(osc["nagata"], osc["bezier"])
        out.append(("Facets oscillate more than the smooth descriptions (RMS deviation of the "
                    "punch force from its moving quadratic)", holds,
                    ", ".join(f"{LABELS[m]} {osc[m]:.3g} N" for m in MODELS)))
        refined = osc["facets_fine"] < osc["facets_coarse"]
        out.append(("Refining the facets reduces the oscillation", refined,
                    f"coarse {osc['facets_coarse']:.3g} N, fine {osc['facets_fine']:.3g} N"))
    if {"nagata", "bezier"} <= set(numbers):
        n, b = numbers["nagata"], numbers["bezier"]
        theta = [abs(x - y) for x, y in zip(n["theta_deg"], b["theta_deg"], strict=True)]
        beta = [between_flanges(abs(n[k] - b[k])) for k in ("beta1_deg", "beta2_deg")]
        theta_limit = SAME_ANGLES + theta_step
        out.append((f"Nagata gives Bezier's angles (beta_1, beta_2 within {SAME_ANGLES:g} "
                    f"degree; theta_1..4 within {SAME_ANGLES:g} degree plus one step of its "
                    "resolution on the blank)",
                    max(theta) <= theta_limit and max(beta) <= SAME_ANGLES,
                    f"largest difference of theta {max(theta):.2f} degrees, held to "
                    f"{theta_limit:.2f} (one step of theta on this blank: {theta_step:.2f}); "
                    f"of beta {max(beta):.2f} degrees"))
    if {"nagata", "facets_coarse"} <= set(numbers):
        n, f = numbers["nagata"], numbers["facets_coarse"]
        holds = f["increments"] > n["increments"] and f["iterations"] > n["iterations"]
        out.append(("Coarse facets need more increments and iterations than Nagata", holds,
                    f"increments {f['increments']} against {n['increments']}, iterations "
                    f"{f['iterations']} against {n['iterations']}"))
    return out


def plot_force(runs: dict[str, Run], path: Path, zoom: tuple[float, float]) -> Path:
    """Punch force against stroke, with a zoom (paper Fig. 9)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (full, detail) = plt.subplots(1, 2, figsize=(11, 4.2))
    for model, run in runs.items():
        for ax in (full, detail):
            ax.plot(run.stroke, run.force, lw=0.9, label=LABELS[model])
    inside = np.concatenate([r.force[(r.stroke >= zoom[0]) & (r.stroke <= zoom[1])]
                             for r in runs.values()])
    if inside.size:
        pad = 0.05 * max(float(np.ptp(inside)), 1e-9)
        detail.set_ylim(float(inside.min()) - pad, float(inside.max()) + pad)
    detail.set_xlim(*zoom)
    for ax, title in ((full, "punch force"), (detail, f"zoom {zoom[0]:g}-{zoom[1]:g} mm")):
        ax.set_xlabel("punch stroke [mm]")
        ax.set_ylabel("punch force, quarter model [N]")
        ax.set_title(title)
        ax.grid(alpha=0.3)
    full.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_increments(runs: dict[str, Run], path: Path) -> Path:
    """Increment size against stroke (paper Fig. 12)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.2))
    for model, run in runs.items():
        ax.plot(run.stroke, run.sizes, ".", ms=3, label=LABELS[model])
    ax.axhline(make_case.MAX_INCREMENT, color="k", lw=0.6, ls="--")
    ax.set_yscale("log")
    ax.set_xlabel("punch stroke [mm]")
    ax.set_ylabel("increment size [mm]")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def one_lu_s(per_iteration: dict[str, float], factorizations: int, iterations: int
             ) -> float | None:
    """The mean time of one LU of a run: the factorizations' time per iteration times the
    run's iterations (forming and springback) over its factorizations; None where the run
    did not record them apart."""
    if "factorization" not in per_iteration or not factorizations:
        return None
    return per_iteration["factorization"] * iterations / factorizations


def _one_lu(n: dict[str, Any]) -> float | None:
    """one_lu_s of a run's numbers."""
    return one_lu_s(n["per_iteration_s"], n["factorizations"],
                    n["iterations"] + n["springback_iterations"])


def _seconds(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def alone_time(numbers: dict[str, Any]) -> str:
    """Table 3's cell for the wall time of a run alone on the machine."""
    timed = numbers.get("timed_alone")
    if not timed:
        return "not measured"
    return f"{timed['wall_s'] / 60:.1f} min ({timed['threads']}, {timed['code'] or '?'})"


#: The discretization of a run kept without one: every run kept before the defaults became
#: the solid-shell and Gauss-point contact used DD3IMP's.
OLD_DISCRETIZATION = "hexahedron, node-to-surface"
#: The contact discretizations as the report names them.
DISCRETIZATIONS = {"gauss": "Gauss-point contact (4 x 4 points per blank face, the default "
                            "penalty)", "node": "node-to-surface contact",
                   "surface": "surface-to-surface contact"}


def report(mesh: str, hexahedra: int, numbers: dict[str, dict[str, Any]],
           shape: dict[str, dict[str, dict[str, Any]]], figures: dict[str, Path],
           threads: int, code: str = "", element: str = "solid-shell",
           contact: str = DISCRETIZATIONS["gauss"],
           baseline: dict[str, Any] | None = None) -> str:
    """The markdown report; ``code``: the code version that wrote it (its runs name
    their own); ``element`` and ``contact``: the discretization the decks ask for;
    ``baseline``: the runs at DD3IMP's discretization to compare with (baseline_file)."""
    models = [m for m in MODELS if m in numbers]
    # On the coarse blank theta moves in steps of the node spacing over the punch.
    spacing = make_case.LENGTH / make_case.COARSE_X
    arc = np.degrees(spacing / (make_case.PUNCH_RADIUS + make_case.THICKNESS))
    # A fine facet's chord off its arc, R (1 - cos(half its angle)), in um.
    sag = 1e3 * (1.0 - np.cos(np.radians(FINE_FACET / 2)))
    strokes = ", ".join(f"{s:g}" for s in make_case.OUTPUT_AT[:-1]) + \
        f" and {make_case.OUTPUT_AT[-1]:g}"
    n_cores = cores()
    head = _row(["", *[f"{LABELS[m]} ddpy" for m in models], *["paper" for _ in models]])
    lines = [
        "# Unconstrained cylindrical bending (paper Fig. 8-12, Tables 2-3)",
        "",
        computed_at(code, {LABELS[m]: numbers[m].get("code", "") for m in models}),
        "",
        "Written by `benchmarks/cylindrical_bending/run.py"
        + (" --mesh paper" if mesh == "paper" else "") + "`; the cases by `make_case.py` "
        "next to it. Numisheet 2002 benchmark B, quarter model: HSS (Swift, Hill'48), "
        f"friction {make_case.FRICTION}, stroke {make_case.STROKE} mm, max increment "
        f"{make_case.MAX_INCREMENT} mm, then springback. Deck settings of this blank "
        f"(make_case.py says why): rmin_yield {make_case.RMIN_YIELD.get(mesh, 0.1):g}, "
        + (f"contact augmentation {make_case.AUGMENTATION[mesh]:g} N/mm."
           if mesh in make_case.AUGMENTATION else "contact augmentation the solver's default "
           "(E t^2 / h of the elements)."),
        "",
        "**The tools are a reconstruction** (the paper's Fig. 6 is not in its text): "
        f"punch radius {make_case.PUNCH_RADIUS} mm; open die, shoulders of radius "
        f"{make_case.SHOULDER_RADIUS} mm centred {make_case.SHOULDER_X} mm from the symmetry "
        "plane, flat tops beyond, an inner wall below, no bottom. One STEP model "
        "(`ddpy.cad.examples.bending_tools`), four tool models built from it "
        f"(`ddpy.cad.build_tool_models`): Bezier patches; Nagata, {make_case.PATCHES_PER_ARC} "
        "patches per 90 degrees of arc; coarse facets, the Nagata mesh with flat patches (the "
        "paper's section *Bilinear facets*: c = 0, same discretization); fine facets, "
        f"{make_case.FACETS_PER_ARC} per arc. Straight edges: elements of at most 5 mm.",
        "",
        f"Blank: **{mesh}** mesh, {hexahedra} elements ({element}) in "
        f"{make_case.LAYERS if mesh == 'paper' else make_case.COARSE_LAYERS} layers; "
        f"{contact} with both tools"
        + (f" (the paper: {make_case.PAPER_HEXAHEDRA:,}, unstructured)." if mesh == "paper"
           else f" (structured, {make_case.COARSE_X} elements along x, {make_case.COARSE_Y} "
           f"across; the paper: {make_case.PAPER_HEXAHEDRA:,} "
           "unstructured). Contact angles come from nodes: on this mesh they move in steps "
           f"of the node spacing over the punch, {arc:.1f} degrees of arc ({2 * arc:.1f} "
           "degrees of theta)."),
        f"Report written on {threads} thread(s); each run's threads are in Table 3 (a run "
        f"alone on the {n_cores} cores with {n_cores} threads, or several at once with 1 "
        f"thread each); wall times are this machine's ({platform.machine()}, {n_cores} "
        "cores). A run that shared the cores does not "
        "time its model: Table 3's *wall time alone* is that of a run alone with a thread "
        "per core, of this run or of an earlier one kept in the runs file that took the same "
        "path (the same increments and iterations; the path does not depend on the threads).",
        "",
        "## Contact angles and springback (Table 2)",
        "",
        "theta: the angle, at the punch's axis, between the two contact points with the "
        "punch farthest from the centreline (twice the angle of the farthest node in contact "
        f"in the quarter model, `ddpy.studies.bending.contact_angle`), at {strokes} mm. "
        "beta, as the paper measures it (its Fig. 11, not in its text): the angle between "
        "the two flanges of the whole strip, beta_1 at the end of forming, beta_2 after "
        "springback; here twice the angle to the vertical (the punch's direction) of one "
        f"free flange (the material initially at x >= {FLANGE_X:g} mm, beyond the die "
        "shoulder; a line fitted through its nodes, `ddpy.studies.bending.line_angle`), "
        "which the table gives too. Why the angle between the flanges, and not one flange's "
        "angle to the vertical (the reading of this report before), is checked below the "
        "table on the paper's own numbers.",
        "",
        head,
        _row(["---"] * (1 + 2 * len(models))),
    ]
    for i in range(len(make_case.OUTPUT_AT)):
        lines.append(_row([f"theta_{i + 1} ({make_case.OUTPUT_AT[i]:g} mm)",
                           *[f"{numbers[m]['theta_deg'][i]:.1f}" for m in models],
                           *[f"{PAPER[m]['theta'][i]:.1f}" for m in models]]))
    theta_step = theta_resolution(mesh)
    reading_rows, reading_verdict = beta_reading(numbers, theta_step)
    for key in ("beta1", "beta2"):
        lines.append(_row([key.replace("beta", "beta_") + ", between the flanges",
                           *[f"{between_flanges(numbers[m][key + '_deg']):.1f}"
                             for m in models],
                           *[f"{PAPER[m][key]:.1f}" for m in models]]))
    lines.append(_row(["springback beta_2 - beta_1, between the flanges",
                       *[f"{between_flanges(numbers[m]['beta2_deg'] - numbers[m]['beta1_deg']):.1f}"
                         for m in models],
                       *[f"{PAPER[m]['beta2'] - PAPER[m]['beta1']:.1f}" for m in models]]))
    for key in ("beta1", "beta2"):
        lines.append(_row([key.replace("beta", "beta_") + ", one flange to the vertical",
                           *[f"{numbers[m][key + '_deg']:.1f}" for m in models],
                           *[f"({PAPER[m][key] / 2:.1f})" for m in models]]))
    lines += [
        "",
        "(In parentheses: half the paper's beta, its one-flange angle under this reading.)",
        "",
        "**The reading of beta, checked.** Between the punch and the die shoulder the "
        "bending moment has one sign, so at full stroke a flange stands steeper than the "
        "sheet's tangent at its last contact with the punch, 90 - theta_4 / 2 degrees from "
        "the vertical. The paper's own theta_4 bounds its one-flange angle so. Below, the "
        "paper's beta_1 against that bound read both ways, ddpy's against its own (its "
        "theta moves in steps of the node spacing, so its bound by a quarter step either "
        "way), and the springback read the same two ways against the paper's:",
        "",
        "| model | the paper's bound 90 - theta_4 / 2 | the paper's beta_1 | beta_1 within "
        "it as one flange | as between the flanges (half of it) | ddpy's bound | ddpy's "
        "beta_1, one flange | within it | ddpy's springback, one flange / between the "
        "flanges | the paper's springback |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *reading_rows,
        "",
        reading_verdict,
        "",
        *die_fit(mesh, numbers),
    ]
    lines += [
        "",
        "## Computational effort (Table 3) and increment size (Fig. 12)",
        "",
        head,
        _row(["---"] * (1 + 2 * len(models))),
        _row(["run", *[numbers[m]["status"] for m in models], *["completed" for _ in models]]),
        _row(["stroke reached [mm]", *[numbers[m]["stroke_mm"] for m in models],
              *[make_case.STROKE for _ in models]]),
        _row(["increments", *[numbers[m]["increments"] for m in models],
              *[PAPER[m]["increments"] for m in models]]),
        _row(["iterations", *[numbers[m]["iterations"] for m in models],
              *[PAPER[m]["iterations"] for m in models]]),
        _row(["increments at the maximum size", *[numbers[m]["full_size_increments"]
                                                 for m in models], *["" for _ in models]]),
        _row(["cut increments", *[numbers[m]["cuts"] for m in models], *["" for _ in models]]),
        _row(["wall time of this run", *[f"{numbers[m]['wall_s']:.0f} s" for m in models],
              *[f"{PAPER[m]['cpu_min']} min" for m in models]]),
        _row(["threads", *[numbers[m]["threads"] or "?" for m in models],
              *["4 cores" for _ in models]]),
        _row(["wall time alone (threads, code)", *[alone_time(numbers[m]) for m in models],
              *["" for _ in models]]),
        _row(["code, date", *[f"{numbers[m].get('code') or '?'}, {numbers[m].get('date') or '?'}"
                              for m in models], *["" for _ in models]]),
        _row(["element, contact", *[numbers[m].get("discretization", OLD_DISCRETIZATION)
                                    for m in models], *["" for _ in models]]),
        _row(["redos at a release, most per increment (`rmin_release_redos`)",
              *[_redos(numbers[m].get("release_redos")) for m in models],
              *["" for _ in models]]),
        _row(["LU factorizations", *[numbers[m]["factorizations"] for m in models],
              *["" for _ in models]]),
        _row(["GMRES iterations (older factors)", *[numbers[m]["krylov_iterations"]
                                                   for m in models], *["" for _ in models]]),
        _row(["Newton corrections of all trials (rejected increments included, forming)",
              *[numbers[m].get("newton_iterations_all") or "?" for m in models],
              *["" for _ in models]]),
        _row(["residual evaluations (line search included, forming)",
              *[numbers[m].get("evaluations") or "?" for m in models], *["" for _ in models]]),
        "",
        "",
        "Time per Newton iteration (whole run, springback included; wall time of each part "
        "over the run's iterations, s; linear = LU factorizations, and solutions with the "
        "factors, GMRES with older factors included, docs/theory/linear-solver.md; the two "
        "apart where the results file has them):",
        "",
        _row(["", *[LABELS[m] for m in models]]),
        _row(["---"] * (1 + len(models))),
        *[_row([label, *[_seconds(numbers[m]["per_iteration_s"].get(part)) for m in models]])
          for part, label in (("assembly", "assembly"), ("contact", "contact search"),
                              ("linear", "linear"), ("factorization", "- LU factorizations"),
                              ("solve", "- solutions"), ("rest", "rest"))],
        _row(["**per iteration**", *[f"**{_per_iteration(numbers[m])[1]:.3f}**"
                                     for m in models]]),
        _row(["one LU factorization (mean over the run)",
              *[_seconds(_one_lu(numbers[m])) for m in models]]),
        _row(["per iteration / one LU",
              *[f"{_per_iteration(numbers[m])[1] / _one_lu(numbers[m]):.2f}"
                if _one_lu(numbers[m]) else "not recorded" for m in models]]),
        _row(["peak memory of the run (MB)",
              *[f"{numbers[m]['peak_memory_mb']:.0f}" if numbers[m].get("peak_memory_mb")
                else "not recorded" for m in models]]),
        "",
        *target(mesh, numbers),
        f"![increment size]({figures['increments'].name})",
        "",
        *(against_dd3imp(numbers, baseline) if baseline else []),
        "## Punch force (Fig. 9)",
        "",
        f"![punch force]({figures['force'].name})",
        "",
        "Oscillation: root mean square deviation of the punch force from a moving quadratic "
        f"over {WINDOW:g} mm of stroke (`ddpy.studies.bending.force_oscillation`), from "
        f"{START:g} mm on (before, the elastic-plastic transition bends the curve for real).",
        "",
        _row(["", *[LABELS[m] for m in models]]),
        _row(["---"] * (1 + len(models))),
        _row(["largest force, quarter [N]", *[f"{numbers[m]['max_force_N']:.1f}"
                                               for m in models]]),
        _row(["oscillation [N]", *[f"{numbers[m]['oscillation_N']:.3g}" for m in models]]),
        _row(["oscillation after 20 mm [N]", *[f"{numbers[m]['oscillation_after_20mm_N']:.3g}"
                                                for m in models]]),
        _row(["oscillation / mean force", *[f"{100 * numbers[m]['oscillation_rel']:.2g} %"
                                             for m in models]]),
        "",
        "The deepest slave node of the blank in each tool at any converged forming increment "
        "(the solver's record, `increments/penetration` of the results; the penetration "
        f"limit is 1 % of the {make_case.THICKNESS:g} mm thickness):",
        "",
        _row(["", *[LABELS[m] for m in models]]),
        _row(["---"] * (1 + len(models))),
        *[_row([f"deepest in the {tool} [mm] (/ thickness)",
                *[_depth(numbers[m].get("penetration_mm"), tool) for m in models]])
          for tool in ("punch", "die")],
        "",
        "## Shape error of the die models (Fig. 8)",
        "",
        "`ddpy.cad.shape_error` against the STEP model, 9 x 9 samples per patch.",
        "",
        _row(["tool", "model", "patches", "max |d| [um]", "mean |d| [um]",
              "max normal error [deg]"]),
        _row(["---"] * 6),
    ]
    for tool, rows in shape.items():
        for m, row in rows.items():
            lines.append(_row([tool, LABELS[m], row["patches"], f"{row['max_distance_um']:.3g}",
                               f"{row['mean_distance_um']:.3g}",
                               f"{row['max_angle_deg']:.3g}"]))
    lines += ["", "The paper (Fig. 8, die profile): 9 um and about 1.5 degrees for the fine "
              f"facets, below 0.1 degree for Nagata. A chord of {FINE_FACET:g} degrees "
              f"({make_case.FACETS_PER_ARC} per 90) deviates from an arc of radius R by "
              f"R (1 - cos {FINE_FACET / 2:g} deg): "
              f"{sag * make_case.SHOULDER_RADIUS:.2g} um on the "
              f"{make_case.SHOULDER_RADIUS:g} mm shoulder, {sag * make_case.PUNCH_RADIUS:.2g} "
              f"um on the {make_case.PUNCH_RADIUS:g} mm punch; the paper's 9 um matches the "
              "punch's radius.", ""]
    for m in ("nagata", "facets_fine"):
        if "png" in shape.get("die", {}).get(m, {}):
            lines += [f"![{LABELS[m]} die]({shape['die'][m]['png']})", ""]
    lines += ["## The claims of the paper", ""]
    partial = [LABELS[m] for m in models if not numbers[m]["status"].startswith("completed")]
    # A claim on runs that stopped short says nothing; one on completed runs alone stands.
    step = theta_resolution(mesh)
    checked = {c[0]: c for c in claims({m: n for m, n in numbers.items()
                                        if n["status"].startswith("completed")}, step)}
    for text, _, _ in claims(numbers, step):
        if text not in checked:
            lines.append(f"- {text}: **not checked** (runs not completed: "
                         f"{', '.join(partial)}).")
            continue
        _, holds, detail = checked[text]
        lines.append(f"- {text}: **{'holds' if holds else 'does not hold'}** ({detail}).")
    missing = [LABELS[m] for m in MODELS if m not in numbers]
    if missing:
        lines.append(f"- Not in this report: {', '.join(missing)}; the claims that compare "
                     "with them are not checked here.")
    lines += ["", *findings(numbers, mesh), ""]
    return "\n".join(lines)


#: Issue target on the paper's mesh: Nagata under 30 minutes on 2 cores, no more iterations
#: than the paper's.
TARGET_MIN = 30.0


def target(mesh: str, numbers: dict[str, dict[str, Any]]) -> list[str]:
    """The paper-mesh target for the Nagata model: met or not, and what dominates. The time
    is that of a run alone on the machine (``timed_alone``)."""
    if mesh != "paper" or "nagata" not in numbers:
        return []
    n = numbers["nagata"]
    timed = n.get("timed_alone")
    head = (f"**Target (Nagata, paper mesh): under {TARGET_MIN:g} minutes on 2 cores and no "
            f"more than {PAPER['nagata']['iterations']} Newton iterations: ")
    done = n["status"].startswith("completed")
    source = timed or n
    per, total = _per_iteration(source)
    lead = max(per, key=per.get) if per else "linear"
    split = source["per_iteration_s"]
    apart = (f": LU factorizations {100 * split['factorization'] / max(total, 1e-12):.0f} %, "
             f"solutions {100 * split['solve'] / max(total, 1e-12):.0f} %"
             if lead == "linear" and "solve" in split else "")
    # The mean time of one LU: the factorizations' time over the run's iterations (forming
    # and springback: the same path as this run's) over the factorizations.
    one = one_lu_s(split, source.get("factorizations", n["factorizations"]),
                   n["iterations"] + n["springback_iterations"])
    lu = f"; one LU of this blank took {one:.2f} s on average" if one is not None else ""
    dominates = (
        f"What dominates an iteration: {lead}, "
        f"{100 * per.get(lead, 0.0) / max(total, 1e-12):.0f} %{apart} "
        f"({n['factorizations']} LU factorizations and {n['krylov_iterations']} GMRES "
        f"iterations with older factors{lu}).")
    if timed is None:
        return [head + "not judged** (" + n["status"] + f"; this run took {n['threads']} "
                "thread(s) and shared the cores with other runs, and no run alone with a "
                "thread per core took its path; run `run.py --mesh paper --models nagata` "
                "alone). " + dominates, ""]
    minutes = timed["wall_s"] / 60.0
    met = done and minutes < TARGET_MIN and n["iterations"] <= PAPER["nagata"]["iterations"]
    everything = n["iterations"] + n["springback_iterations"]
    return [
        head + f"{'met' if met else 'not met'}** ({n['status']}; {minutes:.1f} min alone "
        f"with {timed['threads']} threads at {timed['code'] or '?'}, {n['iterations']} "
        f"forming iterations; the paper: {PAPER['nagata']['cpu_min']} min on a 4-core "
        "i7-2600K). " + dominates,
        ""] + ([] if met or not done else [
            f"What would remove it: at this run's {total:.2f} s per iteration the target allows "
            f"{60.0 * TARGET_MIN / max(total, 1e-12):.0f} iterations, and at its "
            f"{everything} iterations (springback included) "
            f"{60.0 * TARGET_MIN / max(everything, 1):.2f} s per iteration. Both "
            "levers are open: fewer iterations where the contact line on the punch and the die "
            "shoulders passes from one node column to the next (pairs that flip between open "
            "and slip for several iterations; an augmentation r per node, docs/theory/"
            "contact.md), and cheaper GMRES iterations (each is one MUMPS solve, which reads "
            "the factors at a fraction of the memory bandwidth a dense product reaches on "
            "this machine, docs/theory/linear-solver.md). Measured there and short of it: "
            "METIS's pivot order (fewer factor entries and flops, not enough), a symmetric "
            "LDL^T preconditioner (the solve reads as much, GMRES needs more iterations after "
            "each factorization), a low-rank update of the factors for the "
            "contact rows (the solid's rows drift as much), block low-rank and single-"
            "precision factors.", ""])


#: The paper's Table 2 as the die is fitted to match it: theta_1..4 and beta_1 within this
#: many degrees of the paper's Bezier and Nagata columns, the springback within this fraction.
ANGLE_TOLERANCE, SPRINGBACK_TOLERANCE = 2.0, 0.15


def _listed(items: list[str]) -> str:
    """``items`` as prose: "a", "a and b", "a, b and c"."""
    return " and ".join([", ".join(items[:-1]), items[-1]] if len(items) > 1 else items)


def die_fit(mesh: str, numbers: dict[str, dict[str, Any]],
            runs: list[dict[str, Any]] | None = None) -> list[str]:
    """The section on the fitted die: what was fitted and from which runs (``runs``, by
    default fit_die.py's kept runs on the paper blank), what 0.1 mm of clearance does to every
    angle and, on the paper blank, whether the Bezier and Nagata runs meet the paper's
    Table 2 and why an angle misses."""
    fit = load_module(HERE / "fit_die.py", "cylindrical_bending_fit_die")
    if runs is None:
        kept_path = DOCS / f"{fit.STEM}_runs.json"
        runs = list(json.loads(kept_path.read_text()).get("paper", {}).values()) \
            if kept_path.exists() else []
    lines = [
        "### The die, fitted to theta", "",
        "Of the die's dimensions only the shoulder's distance from the symmetry plane is "
        f"chosen here (punch radius {make_case.PUNCH_RADIUS:g} mm and shoulder radius "
        f"{make_case.SHOULDER_RADIUS:g} mm as the benchmark gives them): the clearance "
        "between the punch's side and the shoulder's inner edge is "
        f"**{make_case.CLEARANCE:g} mm**, the shoulder's centre at {make_case.SHOULDER_X:g} "
        "mm. It is fitted to theta: `fit_die.py --mesh paper` ran the Bezier model on the "
        "paper blank at " + _listed([f"{r['clearance_mm']:g}" for r in sorted(
            runs, key=lambda r: r["clearance_mm"])]) + " mm and took the clearance whose "
        "theta_1..4, interpolated, are nearest the paper's Bezier column in least squares "
        "(its report: "
        "[cylindrical_bending_die_fit_paper.md](cylindrical_bending_die_fit_paper.md)). "
        "beta and the springback are not fitted.", ""]
    slopes = fit.sensitivity(runs)
    if slopes:
        lines += ["What 0.1 mm more clearance does to every angle (degrees; beta between the "
                  "flanges), from those runs:", "",
                  _row(["between", *fit.ANGLES]), _row(["---"] * (1 + len(fit.ANGLES)))]
        lines += [_row([f"{lo:g} and {hi:g} mm", *[f"{d[k]:+.2f}" for k in fit.ANGLES]])
                  for lo, hi, d in slopes]
        lines.append("")
    checked = [m for m in ("bezier", "nagata")
               if m in numbers and numbers[m]["status"].startswith("completed")]
    if mesh != "paper" or not checked:
        return lines
    lines += [f"On this blank, against the paper's column of the same model (within "
              f"{ANGLE_TOLERANCE:g} degrees for theta and beta_1, "
              f"{100 * SPRINGBACK_TOLERANCE:.0f} % for the springback):", "",
              _row(["model", *fit.ANGLES]), _row(["---"] * (1 + len(fit.ANGLES)))]
    misses: dict[str, list[str]] = {}
    for m in checked:
        ours = fit.angles(numbers[m])
        paper = fit.paper_angles(m)
        cells = []
        for k in fit.ANGLES:
            if k == "beta_2":
                cells.append(f"{ours[k] - paper[k]:+.1f}")
                continue
            off = ours[k] - paper[k]
            ok = (abs(off) <= SPRINGBACK_TOLERANCE * paper[k] if k == "springback"
                  else abs(off) <= ANGLE_TOLERANCE)
            if not ok:
                misses.setdefault(k, []).append(LABELS[m])
            cells.append((f"{100 * off / paper[k]:+.0f} %" if k == "springback"
                          else f"{off:+.1f}") + ("" if ok else " (misses)"))
        lines.append(_row([LABELS[m], *cells]))
    lines.append("")
    lines.append("(beta_2 is not held to a tolerance of its own: it is beta_1 plus the "
                 "springback.)" if not misses else
                 "Missed: " + "; ".join(f"{k} ({', '.join(v)})" for k, v in misses.items())
                 + ". (beta_2 is beta_1 plus the springback, so it follows them.)")
    if "beta_1" in misses and slopes:
        # A flange lying straight along the tangent from the punch to the shoulder has
        # theta_4 + beta_1 = 180 (beta between the flanges): the clearance moves the two
        # against each other, so their sum tells what no clearance can change.
        per_mm = {k: 10.0 * float(np.mean([d[k] for _, _, d in slopes])) for k in fit.ANGLES}
        m = checked[0]
        ours, paper = fit.angles(numbers[m]), PAPER[m]
        gap = paper["beta1"] - ours["beta_1"]
        shift = gap / per_mm["beta_1"]
        theta_4 = ours["theta_4"] + shift * per_mm["theta_4"]
        sum_ours, sum_paper = ours["theta_4"] + ours["beta_1"], paper["theta"][3] + paper["beta1"]
        sum_per_mm = per_mm["theta_4"] + per_mm["beta_1"]
        lines += ["", (
            f"Why beta_1 misses: the die has one free dimension here, and it is spent on "
            f"theta. beta_1 grows by {per_mm['beta_1']:.1f} degrees per mm of clearance, "
            f"theta_4 falls by {-per_mm['theta_4']:.1f}; bringing the {LABELS[m]} beta_1 "
            f"onto the paper's ({gap:+.1f} degrees) would take "
            f"{make_case.CLEARANCE + shift:.2f} mm, where theta_4 would be {theta_4:.1f}, "
            f"{theta_4 - paper['theta'][3]:+.1f} degrees off the paper's "
            f"{paper['theta'][3]:g}. The sum theta_4 + beta_1 says why: a flange lying "
            "straight along the tangent from the punch to the shoulder has a sum of 180 "
            f"degrees. ddpy's is {sum_ours:.1f}, the paper's {sum_paper:.1f}: the paper's "
            f"flange is turned {sum_ours - sum_paper:.1f} degrees further than ddpy's off "
            "that tangent, and the clearance moves the sum by only "
            f"{sum_per_mm:+.1f} degrees per mm. So the paper's die differs in a dimension "
            "its text does not give (Fig. 6 is missing: the shoulder radius or the die's "
            "shape beyond the shoulder, which bend the flange), or its beta is read off "
            "another stretch of the flange (Fig. 11, also missing). The springback, "
            "beta_2 - beta_1, depends little on the die "
            f"({per_mm['springback']:+.2f} degrees per mm) and is the comparison of the "
            "material and the element that the missing figures leave standing.")]
    return [*lines, ""]


def baseline_file(stem: str) -> Path:
    """The runs kept at DD3IMP's discretization, the baseline the defaults are compared
    with: {"about": what they are, "kept_at": the commit, "clearance_mm": the die's,
    "runs": {model: numbers}}."""
    return DOCS / f"{stem}_dd3imp.json"


def against_dd3imp(numbers: dict[str, dict[str, Any]], baseline: dict[str, Any]
                   ) -> list[str]:
    """The section comparing each model's run with its run at DD3IMP's discretization
    (``baseline``, baseline_file's content): what the defaults changed."""
    models = [m for m in MODELS if m in numbers and m in baseline["runs"]]
    if not models:
        return []
    if baseline["clearance_mm"] != make_case.CLEARANCE:  # another die: not comparable
        return ["## The defaults against DD3IMP's discretization", "",
                "Not compared here: the runs kept at DD3IMP's discretization are of a "
                f"die with a clearance of {baseline['clearance_mm']:g} mm, this report's of "
                f"{make_case.CLEARANCE:g} mm. The comparison on one die stands in this "
                f"report as it was at commit {baseline['kept_at']} and after, until the die "
                "was fitted.", ""]

    def pair(before: float, now: float, form: str, relative: bool = True) -> str:
        change = (f"{100 * (now - before) / before:+.0f} %" if relative and before
                  else f"{now - before:+.2f}")
        return f"{before:{form}} / {now:{form}} ({change})"

    def per_it(n: dict[str, Any]) -> float:
        return n["wall_s"] / max(n["iterations"] + n.get("springback_iterations", 0), 1)

    lines = ["## The defaults against DD3IMP's discretization", "",
             baseline["about"] + " Each cell: that run / this report's run (change); a "
             "wall time is of a run as it was made (its threads in Table 3 and below), "
             "and so is the time per iteration (wall time over forming and springback "
             "iterations).", "",
             _row(["", *[LABELS[m] for m in models]]), _row(["---"] * (1 + len(models)))]
    old, new = baseline["runs"], numbers
    rows = [
        ("element, contact", lambda m: f"{OLD_DISCRETIZATION} / "
         f"{new[m].get('discretization', OLD_DISCRETIZATION)}"),
        ("increments", lambda m: pair(old[m]["increments"], new[m]["increments"], "d")),
        ("increments at the maximum size",
         lambda m: pair(old[m]["full_size_increments"], new[m]["full_size_increments"], "d")),
        ("forming iterations", lambda m: pair(old[m]["iterations"], new[m]["iterations"],
                                              "d")),
        ("largest punch force [N]", lambda m: pair(old[m]["max_force_N"],
                                                   new[m]["max_force_N"], ".1f")),
        ("oscillation / mean force [%]", lambda m: pair(
            100 * old[m]["oscillation_rel"], 100 * new[m]["oscillation_rel"], ".2f", False)),
        *[(f"theta_{i + 1} [deg]", lambda m, i=i: pair(
            old[m]["theta_deg"][i], new[m]["theta_deg"][i], ".1f", False))
          for i in range(len(make_case.OUTPUT_AT))],
        ("beta_1 [deg]", lambda m: pair(old[m]["beta1_deg"], new[m]["beta1_deg"], ".2f",
                                        False)),
        ("beta_2 [deg]", lambda m: pair(old[m]["beta2_deg"], new[m]["beta2_deg"], ".2f",
                                        False)),
        ("wall time [s] (threads)", lambda m: f"{old[m]['wall_s']:.0f} ({old[m]['threads']}) "
         f"/ {new[m]['wall_s']:.0f} ({new[m]['threads']})"),
        ("wall time per iteration [s]", lambda m: pair(per_it(old[m]), per_it(new[m]),
                                                       ".3g")),
    ]
    for label, cell in rows:
        lines.append(_row([label, *[cell(m) for m in models]]))
    return [*lines, ""]


def _polygon_angles(numbers: dict[str, dict[str, Any]]) -> list[str]:
    """The coarse facets' contact angles when they fall on the punch polygon's vertices."""
    if "facets_coarse" not in numbers:
        return []
    theta = [t for t in numbers["facets_coarse"]["theta_deg"] if np.isfinite(t)]
    facet = 90.0 / make_case.PATCHES_PER_ARC
    if not theta or max(abs(t / (2 * facet) - round(t / (2 * facet))) for t in theta) \
            > 1.0 / (2 * facet):  # more than a degree off the vertices
        return []
    paper = ", ".join(f"{t:g}" for t in PAPER["facets_coarse"]["theta"])
    return [
        "- Coarse facets, theta " + ", ".join(f"{t:g}" for t in theta) + " degrees (the "
        f"paper: {paper}): the punch of {make_case.PATCHES_PER_ARC} flat facets per 90 "
        f"degrees is a polygon with vertices {facet:g} degrees apart from its bottom line, "
        "and the bent sheet spans each facet as a chord, touching it at the vertices only; "
        f"theta, twice the angle of the farthest node in contact, moves in steps of "
        f"{2 * facet:g} degrees" + (": 0 at 7 mm, where the sheet touches the bottom "
                                    "vertex alone" if theta[0] < 1.0 else "") + ". "
        "The paper's coarse-facet angles do not fall on such steps: its punch mesh (not in "
        "its text) had other vertices."]


def _redos(cap: int | None) -> str:
    """The release redo cap of a run as the report states it."""
    return "no cap" if cap is None else str(cap)


#: What each limit that ends a forming increment means (docs/theory/contact.md, "Increment
#: control"), in the order the report lists them.
LIMIT_MEANING = {
    "max_increment": "at the largest size of the deck",
    "contact_touch": "shortened to land a node that opens a new contact zone on its tool",
    "contact_release": "shortened at a node that leaves its tool carrying a share of its "
                       "force",
    "yield": "shortened to land points of the blank on the yield surface",
    "strain": "shortened by the largest strain increment",
    "rotation": "shortened by the largest rotation increment",
    "output": "shortened to end at a stroke of an output frame (Table 2's strokes)",
    "phase_end": "shortened to end at the full stroke",
    "cutback": "cut after a failed trial, or regrowing after one",
}


def increment_limits(numbers: dict[str, dict[str, Any]]) -> list[str]:
    """What set the forming increments, per model: the increments each limit ended."""
    parts, seen = [], set()
    for model in MODELS:
        limits = numbers.get(model, {}).get("limited_by")
        if not limits:
            continue
        seen |= {k for k, v in limits.items() if v}
        total = sum(limits.values())
        at_max = limits.get("max_increment", 0)
        parts.append(f"{LABELS[model]}: {at_max} of {total} at the largest size ("
                     f"{at_max / max(total, 1):.0%})" + "".join(
                         f", {limits[k]} {k}" for k in LIMIT_MEANING
                         if k != "max_increment" and limits.get(k)))
    if not parts:
        return []
    return ["- What set the forming increments: " + "; ".join(parts) + ". The limits: "
            + "; ".join(f"{k}, {LIMIT_MEANING[k]}" for k in LIMIT_MEANING if k in seen)
            + "."]


def release_effort(numbers: dict[str, dict[str, Any]]) -> list[str]:
    """Where the forming's Newton work and time went, by the limit that ended the
    increments: the share of the increments redone at a release (docs/theory/contact.md)."""
    parts = []
    for model in MODELS:
        effort = numbers.get(model, {}).get("effort_by_limit", {})
        if not effort or not numbers[model].get("newton_iterations_all"):
            continue  # a run without the counters of rejected trials
        release = effort.get("contact_release", [0, 0, 0, 0.0])
        wall = sum(e[3] for e in effort.values())
        rejected = sum(e[2] - e[1] for e in effort.values())
        cap = numbers[model].get("release_redos")
        parts.append(
            f"{LABELS[model]} ({_redos(cap)}" + (" redo" if cap == 1 else " redos"
                                                  if cap is not None else "") + "): "
            f"{release[0]} of {sum(e[0] for e in effort.values())} "
            f"increments ended at a release, and took {release[3] / max(wall, 1e-9):.0%} of "
            f"the forming's wall time; their trials made {release[2]} Newton corrections "
            f"for {release[1]} accepted ({release[2] - release[1]} of the "
            f"{rejected} corrections of rejected trials)")
    if not parts:
        return []
    share = IncrementLimits().release_share  # the decks leave rmin_release at its default
    if not any(numbers[m]["effort_by_limit"].get("contact_release", [0])[0]
               for m in MODELS if numbers.get(m, {}).get("effort_by_limit")):
        return [f"- No forming increment ended at a release (a node in contact at the start "
                f"of an increment that carries more than `rmin_release`, {share:.0%}, of its "
                "tool's normal force and is free at the end; docs/theory/contact.md), in any "
                "run."]
    contact = "; ".join(
        f"{LABELS[m]}: " + ", ".join(f"{t} {c:g}" for t, c in numbers[m]["contact_nodes"].items())
        for m in MODELS if numbers.get(m, {}).get("contact_nodes"))
    contact = "nodes in contact, mean over the forming: " + contact if contact else \
        "the nodes in contact are counted in the results"
    caps = {numbers[m].get("release_redos") for m in MODELS if m in numbers}
    mixed = (" The runs differ in this setting (Table 3), and the increments and iterations "
             "compared between them include it." if len(caps) > 1 else "")
    return ["- Increments ended at a release (a node in contact at the start of an "
            f"increment that carries more than `rmin_release`, {share:.0%}, of its tool's "
            "normal force and is free at the end; the increment is shortened ahead when the "
            "pressure trend of the last one predicts it, and redone shorter when the release "
            "is seen only after it has converged, up to `rmin_release_redos` times; "
            "docs/theory/contact.md): " + "; ".join(parts) + ". A node leaves a facet where "
            f"the sheet passes its edge (the normal turns by {COARSE_FACET:g} degrees there on "
            "the coarse facets), and every node of the unstructured blank passes it at its own "
            "stroke; "
            "the tools' forces rest on few nodes (" + contact + "), so most of these "
            "releases carry more than the share. With no cap, one increment was often redone "
            "several times, each redo finding another node released earlier; with the "
            f"default, {_redos(IncrementLimits().release_redos)}, a release seen only after the "
            "increment is accepted inside it." + mixed]


def findings(numbers: dict[str, dict[str, Any]], mesh: str = "coarse") -> list[str]:
    """What the numbers say beyond the claims: where the sheet's end went, and the cause of
    a claim that does not hold."""
    out = ["## Findings", ""]
    short = {m: n["stroke_mm"] for m, n in numbers.items()
             if not n["status"].startswith("completed")}
    if short:  # what a partial run says about the end of the process would mislead
        return out + [
            "- Not all runs are complete (stroke reached: " + ", ".join(
                f"{LABELS[m]} {s:g} mm" for m, s in short.items()) + "); the findings wait "
            "for them. Continue them from their checkpoints with `run.py --mesh " + mesh
            + " --restart`, then write this report with `--reuse`."]
    if {"nagata", "bezier"} <= set(numbers) and mesh == "coarse":
        n, b = numbers["nagata"], numbers["bezier"]
        diffs = [x - y for x, y in zip(n["theta_deg"], b["theta_deg"], strict=True)]
        step = theta_resolution(mesh)
        if max(abs(d) for d in diffs) > 1.0:
            out.append(
                "- Nagata against Bezier, theta differences " + ", ".join(
                    f"{d:+.1f}" for d in diffs) + f" degrees: theta comes from nodes, and on "
                f"this blank it moves in steps of {step:.1f} degrees (node columns "
                f"{make_case.LENGTH / make_case.COARSE_X:g} mm apart over the "
                "punch); a difference of one step is one node column that touches the punch "
                "in one run and not yet in the other at that stroke. beta_1 and beta_2 "
                "(between the flanges), fitted through the flange's nodes, differ by "
                f"{between_flanges(abs(n['beta1_deg'] - b['beta1_deg'])):.2f} and "
                f"{between_flanges(abs(n['beta2_deg'] - b['beta2_deg'])):.2f} degrees.")
    if "nagata" in numbers and numbers["nagata"].get("end_xz_mm"):
        n, paper = numbers["nagata"], PAPER["nagata"]
        x, z = n["end_xz_mm"]
        b1, b2 = between_flanges(n["beta1_deg"]), between_flanges(n["beta2_deg"])
        off = 100.0 * ((b2 - b1) / (paper["beta2"] - paper["beta1"]) - 1.0)
        out.append(
            f"- The blank's end (x = {make_case.LENGTH:g} mm at the start) ends forming at "
            f"x = {x:g} mm, z = {z:g} mm (Nagata): the flange has turned up about the die "
            f"shoulder: the flanges stand beta_1 = {b1:.2f} degrees apart, {b2:.2f} after "
            f"springback (the paper: {paper['beta1']:.1f} and {paper['beta2']:.1f}). At full "
            "stroke the "
            "flange lies along the tangent from the punch to the shoulder, so beta_1 is set by "
            "the tools; the die here is a reconstruction fitted to the paper's theta on the "
            f"paper blank (Table 2's last section), and theta_4 is {n['theta_deg'][-1]:.1f} "
            f"against the paper's {paper['theta'][-1]:g} degrees. The springback between "
            f"the flanges, {b2 - b1:.1f} degrees against the "
            f"paper's {paper['beta2'] - paper['beta1']:.1f} ({off:+.0f} %): the reconstructed "
            "tools" + (", " if mesh == "coarse" else " and ") + "the assumed elastic "
            "constants (E, nu are lost from the paper's text)" + (
                f" and this mesh of {make_case.COARSE_X} elements along the strip all bear "
                "on it." if mesh == "coarse" else " bear on it (the blank is the paper's)."))
    if {"nagata", "facets_coarse"} <= set(numbers):
        n, f = numbers["nagata"], numbers["facets_coarse"]
        if not (f["increments"] > n["increments"] and f["iterations"] > n["iterations"]):
            per = {m: numbers[m]["iterations"] / max(numbers[m]["increments"], 1)
                   for m in ("nagata", "facets_coarse")}
            ln, lf = n.get("limited_by", {}), f.get("limited_by", {})
            counts = (
                f"- Coarse facets against Nagata: {per['facets_coarse']:.1f} against "
                f"{per['nagata']:.1f} iterations per increment, {f['cuts']} against "
                f"{n['cuts']} cut increments; increments ended by a release "
                f"{lf.get('contact_release', 0)} against {ln.get('contact_release', 0)}, by "
                f"a first touch {lf.get('contact_touch', 0)} against "
                f"{ln.get('contact_touch', 0)}, by the yield limit "
                f"{lf.get('yield', 0)} against {ln.get('yield', 0)}.")
            out.append(counts if mesh != "coarse" else counts[:-1] + (
                ": the difference is in the increments the r_min control shortens. Nodes "
                "of the sheet that wraps the smooth "
                "punch touch it and lift off again as the wrap proceeds; on a flat facet of "
                f"{COARSE_FACET:g} degrees the sheet touches at the facet's corners only "
                f"(theta_1 = {f['theta_deg'][0]:g} degrees at {make_case.OUTPUT_AT[0]:g} mm"
                + (": the centre node alone" if f["theta_deg"][0] < 1.0 else "") + "), so "
                "fewer nodes touch and release. The paper's runs (fine blank) had the opposite; on "
                "this coarse blank the events of the blank's own nodes dominate."))
    if mesh != "coarse":
        out += _polygon_angles(numbers)
        out += increment_limits(numbers)
        out += release_effort(numbers)
    if {"bezier", "nagata", "facets_fine"} <= set(numbers):
        osc = {m: numbers[m]["oscillation_N"] for m in numbers}
        if osc["facets_fine"] <= max(osc["bezier"], osc["nagata"]) and mesh == "coarse":
            out.append(
                f"- Fine facets against the smooth models: oscillation {osc['facets_fine']:.3g} "
                f"N against {osc['bezier']:.3g} (Bezier) and {osc['nagata']:.3g} N (Nagata). "
                "On this blank the punch force jumps each time a node column ("
                f"{make_case.LENGTH / make_case.COARSE_X:g} mm apart) reaches the "
                "punch, with every description (Fig. 9 here); the deviation from the smoothed "
                f"curve measures these jumps first, and {FINE_FACET:g}-degree facets add "
                f"little to them. The coarse facets ({COARSE_FACET:g} degrees) oscillate "
                f"{osc['facets_coarse'] / osc['nagata']:.1f} times as much as Nagata.")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mesh", choices=make_case.MESHES, default="coarse")
    parser.add_argument("--models", default=",".join(MODELS),
                        help="comma-separated among " + ", ".join(MODELS))
    parser.add_argument("--json", action="store_true", help="print the numbers only")
    parser.add_argument("--max-increments", type=int, default=1500, metavar="N",
                        help="stop a run after N increments, report it as far as it got "
                        "(default 1500; 0: no limit)")
    parser.add_argument("--reuse", action="store_true",
                        help="report from the runs saved in results/, else kept in the "
                        "report's runs file (no new run)")
    parser.add_argument("--restart", action="store_true",
                        help="continue the runs saved in results/ from their checkpoints "
                        "(a run stopped or cut off; a completed one is read back)")
    args = parser.parse_args(argv)
    from ddpy.core.parallel import max_threads

    models = [m.strip() for m in args.models.split(",") if m.strip()]
    if set(models) - set(MODELS):
        parser.error(f"--models must be among {', '.join(MODELS)}")
    case_root = HERE / "cases" / args.mesh
    if not all((case_root / m / "control.dat").exists() for m in models) or \
            not (HERE / "tools" / "tools.step").exists():
        make_case.main(["--mesh", args.mesh])
    stem = "cylindrical_bending" + ("_paper" if args.mesh == "paper" else "")
    stored = kept_runs(runs_file(stem))  # also the earlier timings alone
    kept = stored if args.reuse else {}
    saved_runs = {m: HERE / "results" / args.mesh / m / "results.h5" for m in models}
    plan = restart_plan(saved_runs) if args.restart and not args.reuse else {}
    runs: dict[str, Run] = {}
    for model in models:
        saved = saved_runs[model]
        if args.reuse and saved.exists():
            runs[model] = from_results(saved)
            continue
        if model in kept:
            runs[model] = kept[model]
            continue
        if plan.get(model) == "read":
            runs[model] = from_results(saved)
            continue
        if plan.get(model) == "continue":
            print(f"continuing {args.mesh}/{model} ...", file=sys.stderr, flush=True)
            runs[model] = run_case_folder(case_root / model, verbose=True, restart=True,
                                          max_increments=args.max_increments or None)
            continue
        print(f"running {args.mesh}/{model} ...", file=sys.stderr, flush=True)
        runs[model] = run_case_folder(case_root / model, verbose=True,
                                      max_increments=args.max_increments or None)
        print(f"  {runs[model].stroke.size} increments, {runs[model].wall_s:.0f} s",
              file=sys.stderr, flush=True)
    numbers = {m: summary(m, r) for m, r in runs.items()}
    from ddpy.io.decks import read_case

    for model, run in runs.items():
        if not run.kept:  # a kept run's numbers hold their own record
            record = stored[model].kept.get("timed_alone") if model in stored else None
            numbers[model]["timed_alone"] = timed_alone(numbers[model], record, cores())
            numbers[model].update(deck_numbers(case_root / model))
    if args.json:
        print(json.dumps({"mesh": args.mesh, "models": numbers,
                          "claims": [{"claim": c, "holds": h, "detail": d}
                                     for c, h, d in claims(numbers, theta_resolution(
                                         args.mesh))]}, indent=2))
        return 0
    DOCS.mkdir(parents=True, exist_ok=True)
    keep_runs(runs_file(stem), numbers, {m: r for m, r in runs.items() if not r.kept})
    figures = {"force": plot_force(runs, DOCS / f"{stem}_force.png", (20.0, 24.0)),
               "increments": plot_increments(runs, DOCS / f"{stem}_increments.png")}
    shape = shape_errors(HERE / "tools")
    case = read_case(case_root / models[0], geometry=False)
    contact = {t.discretization for t in case.tools}
    baseline = baseline_file(stem)
    text = report(args.mesh, case.mesh.n_elements, numbers, shape, figures, max_threads(),
                  code_version(), element=case.element,
                  contact=DISCRETIZATIONS[contact.pop()] if len(contact) == 1 else "mixed",
                  baseline=json.loads(baseline.read_text()) if baseline.exists() else None)
    out = DOCS / f"{stem}.md"
    out.write_text(text)
    print(f"wrote {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
