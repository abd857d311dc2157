"""Benchmark: time per Newton iteration of a forming run, split by where it goes.

Runs the first increments of the cylindrical bending case through ``ddpy.app.runner.run_case``
(what ``ddpy run CASE --stop-after N`` does) on two meshes: the built-in coarse case (Nagata
tools) and the paper's blank (Nagata tools; its case is written by
benchmarks/cylindrical_bending/make_case.py when missing). Each mesh and
thread count runs in its own process with OMP_NUM_THREADS and OPENBLAS_NUM_THREADS set.
The parts are timed by wrapping, in the worker only, the functions that do them:

- assembly: ``Solid.assemble`` (Fortran solid_assemble and its Python wrapper);
- contact: ``FormingProblem._contact`` (search, Alart-Curnier law, Jacobian blocks), of
  which search: ``ContactSearch.project``;
- factorization and solve: ``MumpsSolver.factorize`` and ``MumpsSolver.solve``;
- writing: ``ResultsWriter.increment``, ``ResultsWriter.fields`` and the checkpoints;
- set-up: case reading, problem, pattern and MUMPS analysis (once per run, not per
  iteration);
- rest: the remainder of the run's wall time (the Newton loop's Python, residual and
  Jacobian blocks, increment control).

Per iteration = over the Newton corrections of all trials, rejected increments included, as
the results file counts them; a run without that count (before the solver solved some
corrections with older factors) factorized once per correction, so its factorizations are
that count. The numbers of every ``--label`` are kept in forming_iteration.json;
the page shows them all (e.g. ``before`` from a checkout of the code before a change).

    python benchmarks/forming_iteration/run.py --label after [--threads 1 2]
        [--coarse-increments 20] [--paper-increments 2] [--meshes coarse paper]

writes docs/benchmarks/forming_iteration.md and forming_iteration.json.
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "benchmarks"
BENDING = ROOT / "benchmarks" / "cylindrical_bending"
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmarks' shared module
from bench_common import code_version, computed_at  # noqa: E402

PARTS = ("assembly", "contact", "search", "factorization", "solve", "writing")
#: The target: the paper's Newton iterations of the Nagata model (its Table 3) in this many
#: minutes.
PAPER_ITERATIONS, TARGET_MIN = 3918, 30.0
#: What the labels of the present page compare (edit with the labels); {flops} is filled
#: from the numbers (one factorization of the paper mesh, first label -> MULTIPLIERS).
MULTIPLIERS = "multipliers first"
CHANGES = """The labels: main at 13394ca; "after (prof)", the branch that (1) assembles the
Jacobian values in place into two buffers kept by the forming layout (before: a new array of
all the entries per evaluation, and a copy of the tangent into it; page faults and the copy
were the "rest"), (2) offers each candidate patch of the contact
search once, at its nearest grid point found by squared distances (before: every grid point
was offered to the sorted candidate list, with gfortran's scaled norm2 each), same
candidates, and (3) keeps the search's 1-based index arrays in ContactSearch instead of
making them on every call (results bitwise the same); "multipliers first", main at 4dcfc4f:
the element kernel reworked (docs/building.md) and the contact multipliers eliminated
before the displacements in the nested-dissection pivot order (in a separator they widened
every front{flops}). Its runs also
carry the session's changes of the contact law's default augmentation and of the increment
control, so their iteration counts differ; the time per iteration is the comparison.{later}

What dominates on the paper mesh is still MUMPS: its LU, one per iteration until the solver
solved some corrections with older factors (then also its solves, for GMRES; the share of
each run in the findings). The {target:.2f} s per iteration of the target is out of reach
with it, and the iterations per increment (in the findings below; the paper's DD3IMP needed
11.5) weigh as much: contact states of a band of nodes grazing the punch flip between
iterations (docs/benchmarks/cylindrical_bending.md). Outside MUMPS the assembly (Fortran
element kernel) leads."""


def cpu_busy() -> float:
    """CPU seconds all processes have used since boot (/proc/stat)."""
    with open("/proc/stat") as stat:
        fields = [int(v) for v in stat.readline().split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields) - idle) / os.sysconf("SC_CLK_TCK")


def case_folder(mesh: str) -> Path:
    if mesh == "coarse":
        from ddpy.app.runner import DEFAULT_CASE
        return Path(DEFAULT_CASE)
    folder = BENDING / "cases" / "paper" / "nagata"
    if not (folder / "control.dat").is_file():
        subprocess.run([sys.executable, str(BENDING / "make_case.py"), "--mesh", "paper"],
                       check=True)
    return folder


def worker(mesh: str, increments: int) -> dict[str, Any]:
    """One run in this process (threads from the environment); seconds per part."""
    from ddpy.app import runner
    from ddpy.core.linalg import MumpsSolver
    from ddpy.geometry.search import ContactSearch
    from ddpy.io import checkpoint
    from ddpy.io.decks import read_case
    from ddpy.io.results import ResultsWriter
    from ddpy.model.forming import FormingProblem
    from ddpy.model.solid import Solid

    spent = dict.fromkeys((*PARTS, "prepare"), 0.0)
    first: list[float] = []
    count = {"factorizations": 0}

    def timed(owner: Any, name: str, part: str) -> None:
        original = getattr(owner, name)

        @functools.wraps(original)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            tick = time.perf_counter()
            try:
                return original(*args, **kwargs)
            finally:
                spent[part] += time.perf_counter() - tick
                if name == "factorize":
                    count["factorizations"] += 1

        setattr(owner, name, wrapper)

    timed(Solid, "assemble", "assembly")
    timed(FormingProblem, "_contact", "contact")
    timed(ContactSearch, "project", "search")
    timed(MumpsSolver, "solve", "solve")
    timed(ResultsWriter, "increment", "writing")
    timed(ResultsWriter, "fields", "writing")
    timed(runner, "write_checkpoint", "writing")
    timed(FormingProblem, "_prepare", "prepare")
    factorize = MumpsSolver.factorize
    mumps: dict[str, float] = {}

    def factorize_once(self: MumpsSolver, values: Any) -> None:
        factorize(self, values)
        if not mumps:  # flops and fill of the first factorization
            stats = self.statistics()
            mumps.update(n=self.n, nnz=self.nnz, flops=stats["flops"],
                         factor_entries=stats["factor_entries"])

    MumpsSolver.factorize = factorize_once  # type: ignore[method-assign]
    timed(MumpsSolver, "factorize", "factorization")
    original_run = FormingProblem.run

    def run(*args: Any, **kwargs: Any) -> Any:
        first.append(time.perf_counter())
        return original_run(*args, **kwargs)

    FormingProblem.run = run  # type: ignore[method-assign]
    assert runner.write_checkpoint is not checkpoint.write_checkpoint

    busy, cpu0, start = cpu_busy(), time.process_time(), time.perf_counter()
    case = read_case(case_folder(mesh))
    hexahedra = case.mesh.n_elements
    with tempfile.TemporaryDirectory() as output:
        outcome = runner.run_case(case, output, max_increments=increments, overwrite=True)
        wall = time.perf_counter() - start
        cpu = time.process_time() - cpu0
        other = max(cpu_busy() - busy - cpu, 0.0) / wall
        from ddpy.io.results import ResultsReader
        with ResultsReader(Path(output) / runner.RESULTS) as results:
            history = results.history()
            iterations = int(history["iterations"].sum())
            corrections = {key: int(history[key].sum()) for key in
                           ("newton_iterations", "krylov_iterations") if key in history}
    from ddpy.core.parallel import max_threads
    setup = first[0] - start + spent.pop("prepare")
    return {"mesh": mesh, "code": code_version(), "hexahedra": hexahedra,
            "threads": max_threads(), "increments": outcome.increments,
            "iterations": iterations, "wall": wall, "cpu": cpu, "setup": setup,
            "other_cpus": other, "mumps": mumps, **corrections, **count, **spent}


def measure(mesh: str, threads: int, increments: int) -> dict[str, Any]:
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), OPENBLAS_NUM_THREADS=str(threads))
    out = subprocess.run([sys.executable, __file__, "--worker", mesh, str(increments)],
                         env=env, check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def corrections(r: dict[str, Any]) -> int:
    """The Newton corrections of a run, rejected trials included: as its results file
    counted them, else its factorizations (one per correction before the solver reused
    older factors)."""
    return int(r.get("newton_iterations") or r["factorizations"])


def split(r: dict[str, Any]) -> dict[str, float]:
    """Seconds per iteration (Newton correction): assembly, contact (search within),
    factorization + solve, writing, rest."""
    n = max(corrections(r), 1)
    loop = r["wall"] - r["setup"]
    known = r["assembly"] + r["contact"] + r["factorization"] + r["solve"] + r["writing"]
    return {"assembly": r["assembly"] / n, "contact": r["contact"] / n,
            "search": r["search"] / n, "factorization": r["factorization"] / n,
            "solve": r["solve"] / n, "writing": r["writing"] / n,
            "rest": max(loop - known, 0.0) / n, "total": loop / n}


HEADER = ("| code | mesh | threads | assembly | contact (search) | factorization | solve | "
          "writing | rest | **per iteration** | non-MUMPS | iterations | factorizations | "
          "increments | set-up (s) | other CPUs |\n|---|---|---|---|---|---|---|---|---|---|---|"
          "---|---|---|---|---|")


def report(numbers: dict[str, Any]) -> str:
    rows = []
    for label, runs in numbers["labels"].items():
        for r in runs:
            s = split(r)
            mumps = s["factorization"] + s["solve"]
            rows.append(
                f"| {label} | {r['mesh']} | {r['threads']} | {s['assembly']:.4f} | "
                f"{s['contact']:.4f} ({s['search']:.4f}) | {s['factorization']:.4f} | "
                f"{s['solve']:.4f} | {s['writing']:.4f} | {s['rest']:.4f} | "
                f"**{s['total']:.4f}** | {s['total'] - mumps:.4f} | {corrections(r)} | "
                f"{r['factorizations']} | "
                f"{r['increments']} | {r['setup']:.1f} | {r['other_cpus']:.2f} |")
    note_text = "\n".join(f"- {line}" for line in findings(numbers))
    code = computed_at(code_version(), {label: runs[0].get("code", "") if runs else ""
                                        for label, runs in numbers["labels"].items()})
    return f"""# Benchmark: time per Newton iteration of a forming run

{code}

`benchmarks/forming_iteration/run.py` (written by it; {numbers['machine']}, 2 cores shared
with other work: single timings scatter by tens of percent, "other CPUs" says how many of
the 2 cores other processes used on average during the run, from /proc/stat).

The cylindrical bending case (Nagata tools) through `ddpy.app.runner.run_case`, its first
increments: **coarse** = the built-in case (`ddpy run`{size(numbers, "coarse", ", ")}),
**paper** = the paper's blank from
`benchmarks/cylindrical_bending/make_case.py`{size(numbers, "paper", " (", ")")}.
Seconds per Newton iteration (per Newton correction, rejected increments included; the
runs that do not count their corrections factorized once per correction, so there it is per
factorization; the others solve some corrections with older factors and GMRES, in "solve"):

- assembly: `Solid.assemble` (Fortran solid_assemble: internal forces, consistent tangent,
  return mapping, written into the MUMPS values; and its Python wrapper);
- contact: `FormingProblem._contact`, the search of both tools (in brackets) with the
  Alart-Curnier law and its Jacobian blocks;
- factorization, solve: MUMPS (`MumpsSolver.factorize`, `.solve`);
- writing: results (HDF5 increments and fields) and checkpoints;
- rest: everything else in the loop (residual, Jacobian assembly of the blocks, line search
  bookkeeping, increment control, Python);
- non-MUMPS: per iteration minus factorization and solve. Set-up (case, pattern, MUMPS
  analysis) is once per run, not in the iteration.

{HEADER}
{chr(10).join(rows)}

{changes(numbers)}

Findings (computed from the table):

{note_text}
"""


def size(numbers: dict[str, Any], mesh: str, before: str, after: str = "") -> str:
    """The size of a mesh's problem as its latest run recorded it, between ``before`` and
    ``after`` ("" when no run of it recorded one): hexahedra, unknowns with the contact
    forces, Jacobian entries."""
    runs = [r for runs in numbers["labels"].values() for r in runs if r["mesh"] == mesh]
    if not runs:
        return ""
    r = runs[-1]
    parts = [f"{r['hexahedra']:,} hexahedra"] if "hexahedra" in r else []
    if r.get("mumps"):
        parts += [f"{r['mumps']['n']:,} unknowns with the contact forces",
                  f"{r['mumps']['nnz']:,} Jacobian entries, LU"]
    return f"{before}{', '.join(parts)}{after}" if parts else ""


def changes(numbers: dict[str, Any]) -> str:
    """CHANGES with its numbers from the runs: the flops of one factorization of the paper
    mesh, first label -> MULTIPLIERS, and the labels measured after it."""
    labels = numbers["labels"]

    def flops(label: str) -> float | None:
        return next((r["mumps"]["flops"] for r in labels.get(label, [])
                     if r["mesh"] == "paper" and r.get("mumps")), None)

    first = flops(next(iter(labels), ""))
    then = flops(MULTIPLIERS)
    later = list(labels)[list(labels).index(MULTIPLIERS) + 1:] if MULTIPLIERS in labels else []
    return CHANGES.format(
        flops=(f": one factorization of the paper mesh {first:.2g} -> {then:.2g} flops"
               if first and then else ""),
        later="".join(f' "{label}": the code named at the top, with '
                      + ", ".join(sorted({f"{r['threads']} thread(s)" for r in labels[label]}))
                      + "." for label in later),
        target=60.0 * TARGET_MIN / PAPER_ITERATIONS)


def findings(numbers: dict[str, Any]) -> list[str]:
    """Lines of the findings: MUMPS share, before/after, the 0.45 s target."""
    lines = []
    labels = list(numbers["labels"])
    for label, runs in numbers["labels"].items():
        for r in runs:
            s = split(r)
            mumps = s["factorization"] + s["solve"]
            biggest = max(("assembly", "contact", "writing", "rest"), key=lambda k: s[k])
            text = (f"{label}, {r['mesh']}, {r['threads']} thread(s): MUMPS (factorization "
                    f"and solve) {100 * mumps / s['total']:.0f} % of the iteration; of the "
                    f"rest, {biggest} leads ({s[biggest]:.4f} s)")
            m = r.get("mumps")
            if m:
                text += (f"; the LU of {m['n']:,} unknowns and {m['nnz']:,} entries takes "
                         f"{m['flops']:.3g} flops and {m['factor_entries']:,} factor entries")
            text += (f"; {corrections(r) / max(r['increments'], 1):.1f} iterations per "
                     f"converged increment (rejected increments included)")
            lines.append(text + ".")
    if len(labels) >= 2:
        first, last = numbers["labels"][labels[0]], numbers["labels"][labels[-1]]
        for a in first:
            b = next((r for r in last if (r["mesh"], r["threads"]) == (a["mesh"], a["threads"])),
                     None)
            if b is None:
                continue
            sa, sb = split(a), split(b)
            na = sa["total"] - sa["factorization"] - sa["solve"]
            nb = sb["total"] - sb["factorization"] - sb["solve"]
            lines.append(
                f"{a['mesh']}, {a['threads']} thread(s), {labels[0]} -> {labels[-1]}: outside "
                f"MUMPS {na:.4f} -> {nb:.4f} s per iteration ({na / max(nb, 1e-12):.2f} times "
                f"faster); contact {sa['contact']:.4f} -> {sb['contact']:.4f}, rest "
                f"{sa['rest']:.4f} -> {sb['rest']:.4f}, assembly {sa['assembly']:.4f} -> "
                f"{sb['assembly']:.4f}.")
    for r in numbers["labels"][labels[-1]]:
        if r["mesh"] == "paper":
            s = split(r)
            lines.append(
                f"Target (the paper's {PAPER_ITERATIONS:,} iterations, Nagata, in "
                f"{TARGET_MIN:g} minutes: {60.0 * TARGET_MIN / PAPER_ITERATIONS:.2f} s per "
                f"iteration), {labels[-1]}, paper, {r['threads']} thread(s): "
                f"{s['total']:.2f} s per iteration, "
                f"{s['total'] * PAPER_ITERATIONS / 3600:.1f} h for {PAPER_ITERATIONS:,}; "
                f"without MUMPS {s['total'] - s['factorization'] - s['solve']:.2f} s.")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worker", nargs=2, metavar=("MESH", "INCREMENTS"),
                        help=argparse.SUPPRESS)
    parser.add_argument("--label", default="after")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--meshes", nargs="+", default=["coarse", "paper"],
                        choices=["coarse", "paper"])
    parser.add_argument("--coarse-increments", type=int, default=20)
    parser.add_argument("--paper-increments", type=int, default=2)
    parser.add_argument("--json", type=Path, default=DOCS / "forming_iteration.json")
    parser.add_argument("--markdown", type=Path, default=DOCS / "forming_iteration.md")
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the page from the JSON, measure nothing")
    args = parser.parse_args(argv)
    if args.worker:
        print(json.dumps(worker(args.worker[0], int(args.worker[1]))))
        return 0
    numbers = json.loads(args.json.read_text()) if args.json.is_file() else {"labels": {}}
    if args.report_only:
        args.markdown.write_text(report(numbers))
        return 0
    numbers["machine"] = f"{platform.machine()}, {os.cpu_count()} cores"
    runs = []
    for mesh in args.meshes:
        n = args.coarse_increments if mesh == "coarse" else args.paper_increments
        for threads in args.threads:
            r = measure(mesh, threads, n)
            runs.append(r)
            s = split(r)
            print(f"{args.label} {mesh} {threads} thread(s): "
                  + ", ".join(f"{k} {v:.4f}" for k, v in s.items()), flush=True)
    numbers["labels"][args.label] = runs
    args.json.write_text(json.dumps(numbers, indent=1) + "\n")
    args.markdown.write_text(report(numbers))
    return 0


if __name__ == "__main__":
    sys.exit(main())
