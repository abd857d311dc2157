"""Mesh convergence of the bending blank: which blank gives the converged answer, per element
and contact discretization.

The quarter blank of the cylindrical bending benchmark (60 x 15 x 1 mm, Nagata tools of
benchmarks/cylindrical_bending, von Mises Swift steel, friction 0.148, largest increment
0.1 mm: the case an engineer with a 1 mm blank runs) meshed with structured hexahedra of
length h = 2, 1, 0.5, 0.25 mm along the bend, 6 across the width and 1 to 4 layers, with
each element (the mean-dilatation hexahedron, the solid-shell) and each contact treatment
of the tools (node-to-surface, DD3IMP's; Gauss-point, ddpy's default, the blank's faces
integrated against the tool; surface-to-surface and other settings on request). Writes
docs/benchmarks/mesh_convergence.md with its figures:

    python benchmarks/mesh_convergence/run.py                      # every run missing
    python benchmarks/mesh_convergence/run.py --lengths 2,1 --layers 1,2 --jobs 2
    python benchmarks/mesh_convergence/run.py --reuse              # report from kept runs
    python benchmarks/mesh_convergence/run.py --json               # print the numbers only

Each run is ``ddpy run CASE --threads 1`` in its own process (``--jobs`` at a time) into
results/<label>/ (git-ignored); its numbers and force curve are kept in
docs/benchmarks/mesh_convergence_runs.json with the code that made them, so runs made in
different sessions add up. A run that fails is reported as far as it got.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import (  # noqa: E402
    DOCS,
    code_version,
    computed_at,
    load_module,
    runs_file,
)
from bench_common import table_row as _row  # noqa: E402

bending_case = load_module(HERE.parent / "cylindrical_bending" / "make_case.py",
                           "bending_make_case")
bending_run = load_module(HERE.parent / "cylindrical_bending" / "run.py", "bending_run")

LENGTHS = (2.0, 1.0, 0.5, 0.25)       # element length along the bend, mm
LAYERS = (1, 2, 3, 4)
ACROSS = 6                            # elements across the 15 mm width
ELEMENTS = ("hexahedron", "solid-shell")
#: The contact treatments: "gauss" is ddpy's default (Gauss-point contact, 4 x 4 points per
#: blank face, the default penalty); "-pN" sets the penalty N N/mm^3 (the default penalty is
#: drawing's; light bending on a coarse blank wants the bound 12 q R / h^3 of
#: docs/theory/contact.md, about 190 N/mm^3 here) and "-nK" K x K points per face.
#: "surface" (surface-to-surface with a multiplier per Gauss point) is selectable but not in
#: the default matrix: Gauss-point contact is the same integration of the blank's faces with
#: the multipliers eliminated, at a fraction of the cost (docs/theory/contact.md).
CONTACTS = ("node", "gauss", "surface", "gauss-n2", "gauss-p100-n2")
MATRIX = ("node", "gauss")            # the treatments run when none is asked for
STROKES = (1.0, 3.0, 5.0, 10.0, 20.0)  # punch travel of the force table, mm
MAX_INCREMENT, FRICTION = 0.1, 0.148
#: The die's shoulder centre, mm from the symmetry plane: the bending benchmark's die before
#: it was fitted to the paper's contact angles (clearance 2 mm), the die of the kept runs. A
#: convergence study needs one die for all its blanks, not the paper's, so it stays.
SHOULDER_X = 29.5
#: Chatter: RMS of the force about its moving mean over WINDOW mm of stroke, from
#: CHATTER_FROM mm to the end of forming, over the mean force there (the issue's measure).
WINDOW, CHATTER_FROM = 1.0, 3.0
#: The goals (the issue): the 1 mm, 2-layer blank within these of the converged values.
GOAL_FORCE, GOAL_ANGLE, GOAL_CHATTER = 0.03, 0.5, 0.01
STEM = "mesh_convergence"

MESH = """\
# ddpy mesh deck.  Units mm.  Written by benchmarks/mesh_convergence/run.py
normal   z
element  {element}
box      {length:g} {width:g} {thickness:g}  {nx} {ny} {nz}
origin   0 0 0
"""

MATERIAL = """\
# ddpy material deck.  Units MPa.  Von Mises Swift steel (Numisheet 2002 BM-B hardening).
elastic            E 210000  nu 0.3
yield              vonmises
hardening          swift   K 645.3  eps0 0.0102  n 0.252
"""

TOOLS = """\
# ddpy tools deck.  Units mm.  Nagata tools of benchmarks/cylindrical_bending.
tool punch
  description     nagata
  file            {tools}/punch.nagata.tool
  friction        {friction}
  contact         top
  discretization  {contact}
{penalty}end

tool die
  description     nagata
  file            {tools}/die.nagata.tool
  friction        {friction}
  contact         bottom
  discretization  {contact}
{penalty}end
"""

BC = """\
# ddpy boundary deck.  Units mm.
tolerance  1e-4
symmetry   x 0
symmetry   y 0
nodeset    centre  box 0 0  0 0  -inf inf
fix        centre  z  phase springback
"""


@dataclass(frozen=True)
class Blank:
    """One run: element length, layers, element and contact."""

    length: float
    layers: int
    element: str
    contact: str

    @property
    def label(self) -> str:
        return f"h{self.length:g}_l{self.layers}_{self.element}_{self.contact}"

    @property
    def along(self) -> int:
        return int(round(bending_case.LENGTH / self.length))

    @property
    def size(self) -> str:
        return f"{self.along} x {ACROSS} x {self.layers}"


def write_case(blank: Blank, root: Path, tools: Path) -> Path:
    """The five decks of one run's case folder."""
    folder = root / "cases" / blank.label
    folder.mkdir(parents=True, exist_ok=True)
    decks = {
        # The bending benchmark's control deck (its Table 2 frames bar the end's).
        "control.dat": bending_case.CONTROL.format(
            model="nagata", mesh=blank.label, max_increment=MAX_INCREMENT,
            stroke=f"{bending_case.STROKE:g}", output_at=f"{bending_case.STROKE:g}",
            springback=20, rmin_yield="0.1"),
        "mesh.dat": MESH.format(element=blank.element, length=bending_case.LENGTH,
                                width=bending_case.WIDTH, thickness=bending_case.THICKNESS,
                                nx=blank.along, ny=ACROSS, nz=blank.layers),
        "material.dat": MATERIAL,
        "tools.dat": TOOLS.format(tools=os.path.relpath(tools, folder), friction=FRICTION,
                                  contact=blank.contact.split("-")[0],
                                  penalty=contact_options(blank.contact)),
        "bc.dat": BC,
    }
    for name, text in decks.items():
        (folder / name).write_text(text)
    return folder


def contact_options(contact: str) -> str:
    """The tool deck's lines for a treatment's options: "-pN" the penalty N (N/mm^3), "-nK"
    K x K Gauss points per blank face."""
    lines = ""
    for option in contact.split("-")[1:]:
        key = {"p": "penalty", "n": "points"}[option[0]]
        lines += f"  {key:<16}{option[1:]}\n"
    return lines


def run_blank(blank: Blank, root: Path, tools: Path, timeout: float) -> dict[str, Any]:
    """Run one blank in its own process (1 thread) and return its numbers and curve."""
    folder = write_case(blank, root, tools)
    output = root / "results" / blank.label
    command = [sys.executable, "-m", "ddpy", "run", str(folder), "--threads", "1",
               "--output", str(output), "--overwrite"]
    start = time.perf_counter()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
        message = done.stderr.strip().splitlines()[-2:] if done.returncode else []
    except subprocess.TimeoutExpired:
        message = [f"stopped after {timeout:g} s (--timeout)"]
    wall = time.perf_counter() - start
    results = output / "results.h5"
    if not results.exists():
        return {"blank": blank.__dict__, "status": "no results: " + " ".join(message),
                "code": code_version(), "wall_s": round(wall, 1), "curve": {}}
    return numbers_of(blank, results, wall, " ".join(message))


def numbers_of(blank: Blank, results: Path, wall: float, message: str = "") -> dict[str, Any]:
    """What the report needs of one run's results file."""
    run = bending_run.from_results(results, output_at=())
    s, f = run.stroke, run.force
    beta1, beta2 = bending_run.betas(run) if run.stroke.size else (float("nan"),) * 2
    late = s >= CHATTER_FROM
    chatter = float("nan")
    if s.size and s[-1] >= CHATTER_FROM + WINDOW and late.sum() > 3:
        from ddpy.studies.bending import force_oscillation
        rms = force_oscillation(s, f, WINDOW, order=0, start=CHATTER_FROM)
        chatter = rms / float(np.mean(np.abs(f[late])))
    force_at = [float(np.interp(a, s, f)) if s.size and s[-1] >= a - 1e-9 else float("nan")
                for a in STROKES]
    complete = run.status == "completed"
    return {
        "blank": blank.__dict__,
        "status": "completed" if complete else
        f"partial at {s[-1] if s.size else 0.0:.2f} mm" + (f": {message}" if message else ""),
        "code": code_version(),
        "stroke_mm": round(float(s[-1]), 3) if s.size else 0.0,
        "force_N": [round(v, 3) for v in force_at],
        "beta1_deg": round(beta1, 3), "beta2_deg": round(beta2, 3),
        "chatter": round(chatter, 5),
        "increments": int(s.size),
        "iterations": int(run.iterations.sum()),
        "cuts": int(run.cuts),
        "wall_s": round(wall, 1),
        "curve": {"stroke": np.round(s, 5).tolist(), "force": np.round(f, 4).tolist()},
    }


def kept() -> dict[str, dict[str, Any]]:
    path = runs_file(STEM)
    return json.loads(path.read_text()) if path.exists() else {}


def reference(runs: dict[str, dict[str, Any]]) -> dict[str, Any] | None:
    """The converged values: the completed run of the finest blank (shortest elements, then
    most layers), preferring the solid-shell (free of locking at any aspect) and the
    default Gauss-point contact (whose chatter, the smallest, least disturbs the moving
    mean); with the spread of the other completed runs on that blank, which bounds how far
    from converged the reference itself is."""
    done = [r for r in runs.values() if r["status"] == "completed"]
    if not done:
        return None
    finest = min(done, key=lambda r: (r["blank"]["length"], -r["blank"]["layers"],
                                      r["blank"]["element"] != "solid-shell",
                                      r["blank"]["contact"] != "gauss"))
    same = [r for r in done if r["blank"]["length"] == finest["blank"]["length"]
            and r["blank"]["layers"] == finest["blank"]["layers"]]
    others = {Blank(**r["blank"]).label: (
        max(abs(a - b) / abs(b) for a, b in zip(mean_forces(r), mean_forces(finest),
                                                 strict=True)),
        max(abs(r["beta1_deg"] - finest["beta1_deg"]),
            abs(r["beta2_deg"] - finest["beta2_deg"]))) for r in same if r is not finest}
    return {**finest, "label": Blank(**finest["blank"]).label, "others": others}


def mean_forces(run: dict[str, Any]) -> list[float]:
    """The run's punch force at STROKES on its moving mean over WINDOW mm (the chatter
    taken out; where it did not get there, nan)."""
    curve = run.get("curve") or {}
    s, f = np.asarray(curve.get("stroke", [])), np.asarray(curve.get("force", []))
    if s.size < 4:
        return [float("nan")] * len(STROKES)
    from ddpy.studies.bending import smooth_curve
    mean = smooth_curve(s, f, WINDOW, order=0)
    return [float(np.interp(a, s, mean)) if s[-1] >= a - 1e-9 else float("nan")
            for a in STROKES]


def errors(run: dict[str, Any], ref: dict[str, Any]) -> dict[str, float]:
    """A run's largest relative error of the mean force over STROKES (where it got there)
    and its angle errors, against the reference."""
    f = [abs(a - b) / abs(b) for a, b in zip(mean_forces(run), mean_forces(ref), strict=True)
         if np.isfinite(a)]
    return {"force": max(f) if f else float("nan"),
            "beta1": abs(run["beta1_deg"] - ref["beta1_deg"]),
            "beta2": abs(run["beta2_deg"] - ref["beta2_deg"])}


def _pct(v: float) -> str:
    return "-" if not np.isfinite(v) else f"{100 * v:.1f} %"


def _deg(v: float) -> str:
    return "-" if not np.isfinite(v) else f"{v:.2f}"


def plot(runs: dict[str, dict[str, Any]], path: Path) -> Path:
    """Punch force against stroke, 2 layers, each element length; one panel per element
    and contact."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kinds = [(e, c) for e in ELEMENTS for c in CONTACTS
             if any(r["blank"]["element"] == e and r["blank"]["contact"] == c
                    for r in runs.values())]
    fig, axes = plt.subplots(1, max(len(kinds), 1), figsize=(4.2 * max(len(kinds), 1), 3.6),
                             sharey=True, squeeze=False)
    for ax, (element, contact) in zip(axes[0], kinds, strict=False):
        for r in sorted(runs.values(), key=lambda r: -r["blank"]["length"]):
            b = r["blank"]
            if (b["element"], b["contact"], b["layers"]) != (element, contact, 2) or \
                    not r["curve"]:
                continue
            ax.plot(r["curve"]["stroke"], r["curve"]["force"], lw=0.8,
                    label=f"h = {b['length']:g} mm")
        ax.set_title(f"{element}, {contact} contact, 2 layers", fontsize=9)
        ax.set_xlabel("punch travel (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0][0].set_ylabel("punch force, quarter (N)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _contact_rank(contact: str) -> tuple[int, str]:
    """Where a treatment comes in the tables: CONTACTS' order, others after it."""
    return (CONTACTS.index(contact) if contact in CONTACTS else len(CONTACTS), contact)


#: The blanks each element and treatment of the matrix is run on: every element length
#: with 2 layers, every number of layers at 1 mm (the goal's blank is at the crossing).
STAR = tuple(sorted({(h, 2) for h in LENGTHS} | {(1.0, n) for n in LAYERS},
                    key=lambda b: (-b[0], b[1])))


def coverage(runs: dict[str, dict[str, Any]]) -> list[str]:
    """Per element and treatment of the matrix, the blanks of STAR without a completed
    run (absent or stopped)."""
    out = []
    for element in ELEMENTS:
        for contact in MATRIX:
            done = {(r["blank"]["length"], r["blank"]["layers"]) for r in runs.values()
                    if r["status"] == "completed" and r["blank"]["element"] == element
                    and r["blank"]["contact"] == contact}
            missing = [b for b in STAR if b not in done]
            out.append(f"- {element}, {contact}: "
                       + ("every blank completed" if not missing else "not completed: "
                          + ", ".join(f"h = {h:g} mm with {n} layer(s)" for h, n in missing))
                       + f" ({len(done)} blanks completed in all).")
    return out


def _holds(run: dict[str, Any], ref: dict[str, Any]) -> bool:
    e = errors(run, ref)
    return (e["force"] <= GOAL_FORCE and max(e["beta1"], e["beta2"]) <= GOAL_ANGLE
            and run["chatter"] <= GOAL_CHATTER)


def _findings(runs: dict[str, dict[str, Any]], ref: dict[str, Any]) -> list[str]:
    """Per element, contact treatment of the matrix and element length: the errors and
    chatter by layers; then, per element and treatment, the blanks that meet the goal."""
    out = []
    for element in ELEMENTS:
        for contact in MATRIX:
            name = {"node": "node-to-surface", "gauss": "Gauss-point"}[contact]
            done = [r for r in runs.values() if r["status"] == "completed" and
                    r["blank"]["element"] == element and r["blank"]["contact"] == contact
                    and Blank(**r["blank"]).label != ref["label"]]
            for h in LENGTHS:
                at = sorted((r for r in done if r["blank"]["length"] == h),
                            key=lambda r: r["blank"]["layers"])
                if not at:
                    continue
                out.append(
                    f"- {element}, h = {h:g} mm, {name} contact: largest force error "
                    + ", ".join(f"{_pct(errors(r, ref)['force'])} with "
                                f"{r['blank']['layers']} layer(s)" for r in at)
                    + "; angle error " + ", ".join(
                        _deg(max(errors(r, ref)["beta1"], errors(r, ref)["beta2"]))
                        for r in at)
                    + " degrees; chatter " + ", ".join(_pct(r["chatter"]) for r in at) + ".")
            if done:
                good = sorted((Blank(**r["blank"]) for r in done if _holds(r, ref)),
                              key=lambda b: (-b.length, b.layers))
                out.append(
                    f"- So the {element} with {name} contact meets the goal (force "
                    f"{100 * GOAL_FORCE:g} %, angles {GOAL_ANGLE:g} degrees, chatter "
                    f"{100 * GOAL_CHATTER:g} %) on "
                    + (", ".join(f"h = {b.length:g} mm with {b.layers} layer(s)" for b in good)
                       if good else "none of its completed blanks") + ".")
    return out


def report(runs: dict[str, dict[str, Any]], code: str) -> str:
    ref = reference(runs)
    lines = [
        "# Mesh convergence of the bending blank",
        "",
        "Written by `benchmarks/mesh_convergence/run.py`; every number below is computed "
        "by it from the runs kept in `mesh_convergence_runs.json`. "
        + computed_at(code, {label: r["code"] for label, r in runs.items()}),
        "",
        f"The quarter blank {bending_case.LENGTH:g} x {bending_case.WIDTH:g} x "
        f"{bending_case.THICKNESS:g} mm of the cylindrical bending benchmark, its Nagata tools "
        f"(punch radius {bending_case.PUNCH_RADIUS:g} mm, die shoulder radius "
        f"{bending_case.SHOULDER_RADIUS:g} mm centred {SHOULDER_X:g} mm from the symmetry "
        f"plane: the die before it was fitted), von Mises Swift steel, friction {FRICTION:g}, "
        f"punch travel {bending_case.STROKE:g} mm in increments of at most "
        f"{MAX_INCREMENT:g} mm, then springback. Structured hexahedra of length h along the "
        f"bend, {ACROSS} across the width, 1 to 4 layers; each run alone in a process on one "
        "thread (two runs at a time on the machine's two cores, so times carry the other "
        "run's load). Chatter: the RMS of the punch force about its moving mean over "
        f"{WINDOW:g} mm of stroke, from {CHATTER_FROM:g} mm to the end of forming, over the "
        "mean force there. Forces F(s) are read on that moving mean (the chatter, "
        "reported apart, taken out), and so are the force errors. beta_1, beta_2: the free "
        "flange's angle to the punch's direction after forming and after springback. "
        "Contact: node (node-to-surface, DD3IMP's), surface (surface-to-surface), gauss "
        "(Gauss-point contact as ddpy runs it by default: 4 x 4 points per face, the default "
        "penalty); -nK with K x K points per face, -pN with the penalty N N/mm^3.",
        "",
    ]
    lines += ["The matrix: each element with node-to-surface and Gauss-point contact on "
              "every element length with 2 layers and every number of layers at 1 mm "
              "(the goal's blank is at the crossing); other blanks and settings where a "
              "run was made. Not completed of that design:", "", *coverage(runs), ""]
    if ref is None:
        return "\n".join(lines + ["No run has completed yet.", ""])
    lines += [
        "## The converged values",
        "",
        f"The reference is the finest blank that completed, `{ref['label']}` "
        f"({Blank(**ref['blank']).size} hexahedra): force "
        + ", ".join(f"{v:.2f} N at {s:g} mm" for v, s in zip(mean_forces(ref), STROKES,
                                                              strict=True))
        + f"; beta_1 {ref['beta1_deg']:.2f} and beta_2 {ref['beta2_deg']:.2f} degrees. "
        + ("The other runs on the same blank differ from it by at most "
           + "; ".join(f"{_pct(f)} in force and {a:.2f} degrees in angle (`{label}`)"
                       for label, (f, a) in ref["others"].items())
           + ": how far the reference itself may be from converged (a run of the other "
           "element carries that element's own error)."
           if ref["others"] else "No other element or contact completed on that blank, "
           "so its own distance from the converged answer is not measured here."),
        "",
    ]
    goal = [r for r in runs.values() if r["blank"]["length"] == 1.0 and
            r["blank"]["layers"] == 2 and r["status"] == "completed"]
    if goal:
        lines += ["## The goal: the 1 mm, 2-layer blank", "",
                  f"Within {100 * GOAL_FORCE:g} % of the converged force at every stroke, "
                  f"{GOAL_ANGLE:g} degrees of the converged angles, chatter at most "
                  f"{100 * GOAL_CHATTER:g} %:", "",
                  _row(["element", "contact", "largest force error", "beta_1 error",
                        "beta_2 error", "chatter", "holds"]),
                  _row(["---"] * 7)]
        for r in goal:
            e = errors(r, ref)
            holds = _holds(r, ref)
            lines.append(_row([r["blank"]["element"], r["blank"]["contact"], _pct(e["force"]),
                               _deg(e["beta1"]), _deg(e["beta2"]), _pct(r["chatter"]),
                               "yes" if holds else "no"]))
        lines.append("")
    findings = _findings(runs, ref)
    if findings:
        lines += ["## What it shows", "",
                  "Against the reference (forces on the moving mean, the largest error over "
                  "the strokes of the table; angle error the larger of beta_1's and "
                  "beta_2's):", "", *findings, ""]
    lines += ["## Every run", "",
              _row(["element", "contact", "h (mm)", "hexahedra"]
                   + [f"F({s:g}) N" for s in STROKES]
                   + ["beta_1", "beta_2", "force error", "angle error", "chatter",
                      "increments", "iterations", "cuts", "time (s)", "status"]),
              _row(["---"] * (4 + len(STROKES) + 10))]
    order = sorted(runs.values(), key=lambda r: (ELEMENTS.index(r["blank"]["element"]),
                                                 _contact_rank(r["blank"]["contact"]),
                                                 -r["blank"]["length"], r["blank"]["layers"]))
    for r in order:
        b = Blank(**r["blank"])
        e = errors(r, ref) if r.get("force_N") else {"force": np.nan, "beta1": np.nan,
                                                      "beta2": np.nan}
        lines.append(_row(
            [b.element, b.contact, f"{b.length:g}", b.size]
            + [("-" if not np.isfinite(v) else f"{v:.2f}") for v in mean_forces(r)]
            + [_deg(r.get("beta1_deg", np.nan)), _deg(r.get("beta2_deg", np.nan)),
               _pct(e["force"]), _deg(max(e["beta1"], e["beta2"])),
               _pct(r.get("chatter", np.nan)), r.get("increments", 0),
               r.get("iterations", 0), r.get("cuts", 0), r["wall_s"],
               r["status"].split(":")[0]]))
    stopped = [r for r in order if r["status"] != "completed"]
    if stopped:
        lines += ["", "Runs that did not complete, and why (their last cut's message):", ""]
        lines += [f"- {Blank(**r['blank']).label}: {r['status'].split('   ')[-1].strip()}"
                  for r in stopped]
    lines += ["", f"![punch force, 2 layers]({STEM}_force.png)", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])

    def listed(text: str, kind: type, allowed: tuple | None = None) -> list:
        values = [kind(v) for v in text.split(",") if v.strip()]
        if allowed is not None and set(values) - set(allowed):
            parser.error(f"{text}: each must be one of {', '.join(map(str, allowed))}")
        return values

    parser.add_argument("--lengths", default=",".join(f"{h:g}" for h in LENGTHS))
    parser.add_argument("--layers", default=",".join(map(str, LAYERS)))
    parser.add_argument("--elements", default=",".join(ELEMENTS))
    parser.add_argument("--contacts", default=",".join(MATRIX),
                        help="treatments among node, surface, gauss, each optionally with "
                        "-pN (penalty) and -nK (points) (default: %(default)s)")
    parser.add_argument("--jobs", type=int, default=2, help="runs at a time (1 thread each)")
    parser.add_argument("--timeout", type=float, default=3600.0,
                        help="seconds after which a run is stopped and reported partial")
    parser.add_argument("--again", action="store_true",
                        help="run again the blanks already kept")
    parser.add_argument("--reuse", action="store_true", help="no run: report the kept runs")
    parser.add_argument("--collect", action="store_true",
                        help="no run: keep the results found in results/ of the blanks "
                        "asked for that have none kept (runs stopped before they ended)")
    parser.add_argument("--json", action="store_true", help="print the numbers only")
    args = parser.parse_args(argv)
    for contact in listed(args.contacts, str):
        try:
            assert contact.split("-")[0] in ("node", "surface", "gauss")
            contact_options(contact)
        except (AssertionError, KeyError, IndexError):
            parser.error(f"{contact}: expected node, surface or gauss, each optionally "
                         "followed by -pN (penalty) and -nK (points), as in gauss-p100-n4")
    blanks = [Blank(h, n, e, c) for e in listed(args.elements, str, ELEMENTS)
              for c in listed(args.contacts, str)
              for h in listed(args.lengths, float) for n in listed(args.layers, int)]
    runs = kept()
    if args.collect:
        for blank in blanks:
            results = HERE / "results" / blank.label / "results.h5"
            if blank.label in runs or not results.exists():
                continue
            from ddpy.io.results import ResultsReader
            with ResultsReader(results) as r:
                wall = float(r.history()["time_total"].sum())
            runs[blank.label] = numbers_of(blank, results, wall,
                                           "stopped before it ended (--collect)")
            print(f"{blank.label}: collected, {runs[blank.label]['status']}", file=sys.stderr)
        runs_file(STEM).write_text(json.dumps(runs, indent=1) + "\n")
    elif not args.reuse:
        todo = [b for b in blanks if args.again or b.label not in runs]
        tools = HERE / "tools"
        if todo and not (tools / "die.nagata.tool").exists():
            bending_case.build_tools(tools, shoulder_x=SHOULDER_X)
        todo.sort(key=lambda b: b.along * b.layers)  # the cheap ones first
        with ThreadPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
            for blank, numbers in zip(todo, pool.map(
                    lambda b: run_blank(b, HERE, tools, args.timeout), todo), strict=True):
                print(f"{blank.label}: {numbers['status']}, {numbers['wall_s']} s",
                      file=sys.stderr, flush=True)
                runs = kept()  # another process may have added runs meanwhile
                runs[blank.label] = numbers
                runs_file(STEM).write_text(json.dumps(runs, indent=1) + "\n")
    if args.json:
        print(json.dumps({k: {n: v for n, v in r.items() if n != "curve"}
                          for k, r in runs.items()}, indent=1))
        return 0
    plot(runs, DOCS / f"{STEM}_force.png")
    (DOCS / f"{STEM}.md").write_text(report(runs, code_version()))
    print(f"wrote {DOCS / (STEM + '.md')}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
