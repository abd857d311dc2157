"""Benchmark: time per Newton correction of a forming run, before and after a change.

One invocation measures two checkouts of ddpy, ``--before`` (the code before a change) and
``--after`` (default: this checkout), each a git checkout with its own built ``.venv``, on
two meshes of the cylindrical bending case (Nagata tools):

- coarse: each checkout's built-in case (``<checkout>/ddpy/cases/cylindrical_bending``),
  its first ``--coarse-increments`` (20) increments;
- paper: the paper's blank (``--paper-case``; default
  benchmarks/cylindrical_bending/cases/paper/nagata of this checkout, written by
  benchmarks/cylindrical_bending/make_case.py --mesh paper and git-ignored, so a new
  worktree passes the folder of a checkout that has it; never written here), its first
  ``--paper-increments`` (2) increments.

A measurement is ``<checkout>/.venv/bin/python -m ddpy run CASE --stop-after N --threads T
--output TMP`` in a subprocess (OMP_NUM_THREADS and OPENBLAS_NUM_THREADS = T, started in an
empty folder so that each checkout's python imports its own ddpy). The time split is the one
the run writes per increment into results.h5 (``increments/time_assembly``, ``time_contact``,
``time_factorization``, ``time_solve``, ``time_rest``, ``time_total``, the code timing its
own parts; nothing is wrapped here), summed over the increments and divided by the Newton
corrections of all trials, rejected ones included (``newton_iterations``; a file without
that column counts ``factorizations``, one per correction before the solver reused older
factors). Share outside MUMPS = 1 - (factorization + solve) / total. The work counts are the
same file's (``newton_iterations``, ``factorizations``, ``krylov_iterations``,
``evaluations``, ``iterations``, ``cutbacks``).

Before and after alternate (before, after, after, before, ...) so that drift of the shared
machine hits both alike; each is measured ``--repeats`` times (the paper mesh
``--paper-repeats``) and the try with the smaller total is kept (every try's total is in
the JSON). The two took the same path on a mesh when every increment's counts above are
equal and its steps too (the page says where they first differ otherwise).

    python benchmarks/forming_iteration/run.py --before CHECKOUT [--after CHECKOUT]
        [--paper-case FOLDER] [--meshes coarse paper] [--threads 1] [--repeats 2]
        [--paper-repeats 2] [--coarse-increments 20] [--paper-increments 2]
    python benchmarks/forming_iteration/run.py --report-only   # the page from the JSON

writes docs/benchmarks/forming_iteration.json (the numbers of this invocation only: before
and after are measured in one run) and forming_iteration.md.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import h5py
import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "benchmarks"
PAPER_CASE = ROOT / "benchmarks" / "cylindrical_bending" / "cases" / "paper" / "nagata"
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmarks' shared module
from bench_common import CODE_PATHS, code_version, computed_at  # noqa: E402

SIDES = ("before", "after")
#: The time split of results.h5 (increments/time_<part>), in the order of the table.
PARTS = ("assembly", "contact", "factorization", "solve", "rest")
#: The work counts of results.h5 (increments/<count>).
COUNTS = ("newton_iterations", "factorizations", "krylov_iterations", "evaluations",
          "iterations", "cutbacks")
#: Per-increment columns kept to compare the two paths: the counts and these.
PATH_COLUMNS = (*COUNTS, "step")
#: The target: the paper's Newton iterations of the Nagata model (its Table 3) in this many
#: minutes.
PAPER_ITERATIONS, TARGET_MIN = 3918, 30.0
#: What the before/after of the Newton loop's move into the core are (another comparison
#: gives its own with --compared FILE; the code commits between them are listed from git
#: on the page).
COMPARED = """**Before** runs the forming Newton loop in Python: per evaluation the solid's assembly
is one core call, the contact three core calls per tool (search, second derivatives, law)
with numpy gathering the pairs' rows and Jacobian blocks; GMRES on older factors, the
penetration limit and the line search are numpy, MUMPS goes through its wrapper. **After**
evaluates every tool's contact in one core call (`forming_contact`) and runs each increment
trial as one core call (`forming_increment`, fortran/solver/ddpy_forming_newton.f90) that
evaluates, solves, searches the line and tests convergence; Python keeps the increment
control and the output. Both time their parts themselves. The before code's results file
leaves one piece out of its increments' time: the numpy gather of each evaluation's
residual and Jacobian values, which it timed but subtracted when it recorded the increment
(its `time_total` is the sum of the parts, as in after). The runner's wall time holds it,
with the set-up and the writing (row "run wall time - increments' total" and the notes)."""


def cpu_busy() -> float:
    """CPU seconds all processes have used since boot (/proc/stat)."""
    with open("/proc/stat") as stat:
        fields = [int(v) for v in stat.readline().split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields) - idle) / os.sysconf("SC_CLK_TCK")


def children_cpu() -> float:
    """CPU seconds of this process's finished children."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def git(checkout: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["git", "-C", str(checkout), *args], capture_output=True, text=True)


def checkout_code(checkout: Path) -> str:
    """bench_common.code_version() of another checkout; stops when it is none."""
    code = code_version(checkout)
    if not code:
        sys.exit(f"{checkout}: not a git checkout")
    return code


def between(before: Path, after: Path) -> list[str]:
    """The commits of ``after`` since ``before`` that change the code (ddpy, fortran and the
    build; not benchmarks or docs): short hash and the subject's first clause, oldest
    first; empty when ``before`` is not an ancestor of ``after``."""
    commit = git(before, "rev-parse", "HEAD").stdout.strip()
    log = git(after, "log", "--reverse", "--format=%h %s", f"{commit}..HEAD", "--",
              *(p for p in CODE_PATHS if not p.startswith("benchmarks")))
    if not commit or log.returncode != 0:
        return []
    lines = []
    for line in log.stdout.splitlines():
        short, _, subject = line.partition(" ")
        clause = subject.split(": ", 1)[0] if ": " in subject[:120] else subject
        lines.append(f"{short} {clause if len(clause) <= 120 else clause[:117] + '...'}")
    return lines


def code_commit(checkout: dict[str, Any]) -> str:
    """", its code (ddpy, fortran, the build) as of commit X" for a checkout's recorded
    stamp when its last code commit is an older one; "" when the same or unknown."""
    stamp = checkout["code"].removesuffix("-dirty")
    last = git(Path(checkout["path"]), "log", "-1", "--format=%h", stamp, "--",
               *(p for p in CODE_PATHS if not p.startswith("benchmarks")))
    commit = last.stdout.strip()
    if last.returncode != 0 or not commit or commit.startswith(stamp) or \
            stamp.startswith(commit):
        return ""
    return f"; its code (ddpy, fortran, the build) as of `{commit}`"


def python_of(checkout: Path) -> Path:
    """The checkout's python, checked to import the checkout's own ddpy."""
    python = checkout / ".venv" / "bin" / "python"
    if not python.is_file():
        sys.exit(f"{checkout}: no .venv/bin/python (run its setup.sh)")
    with tempfile.TemporaryDirectory() as empty:
        where = subprocess.run([str(python), "-c", "import ddpy; print(ddpy.__file__)"],
                               cwd=empty, env=environment(1), capture_output=True, text=True)
    module = Path(where.stdout.strip() or "?").resolve()
    if where.returncode != 0 or checkout.resolve() not in module.parents:
        sys.exit(f"{python} imports ddpy from {module}, not from {checkout}: "
                 f"{where.stderr.strip()[-500:]}")
    return python


def environment(threads: int) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env.update(OMP_NUM_THREADS=str(threads), OPENBLAS_NUM_THREADS=str(threads))
    return env


def folder_digest(folder: Path) -> str:
    """SHA-256 over the names and contents of a folder's files (a case and its tools)."""
    digest = hashlib.sha256()
    for path in sorted(p for p in folder.rglob("*") if p.is_file()):
        digest.update(str(path.relative_to(folder)).encode() + b"\0")
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def case_of(mesh: str, checkout: Path, paper_case: Path) -> Path:
    if mesh == "coarse":
        return checkout / "ddpy" / "cases" / "cylindrical_bending"
    return paper_case


def read_results(path: Path) -> dict[str, Any]:
    """What one run wrote into its results.h5: sums of the time split and the counts, the
    per-increment columns of its path, the mesh size and the runner's wall time."""
    with h5py.File(path, "r") as f:
        inc = f["increments"]
        n = int(inc.attrs["count"])
        sums = {part: float(np.sum(inc[f"time_{part}"][:n])) for part in (*PARTS, "total")
                if f"time_{part}" in inc}
        counts = {key: int(np.sum(inc[key][:n])) for key in COUNTS if key in inc}
        columns = {key: inc[key][:n].tolist() for key in PATH_COLUMNS if key in inc}
        forces = inc["tool_force"][:n].tolist() if "tool_force" in inc else None
        mesh = f["mesh"]
        return {"increments": n, "time": sums, "counts": counts, "columns": columns,
                "tool_force": forces,
                "missing": [k for k in (*(f"time_{p}" for p in (*PARTS, "total")), *COUNTS)
                            if k not in inc],
                "hexahedra": int(mesh["elements"].shape[0]),
                "nodes": int(mesh["nodes"].shape[0]),
                "run_wall": float(f.attrs.get("wall_time", np.nan)),
                "threads": int(f.attrs.get("threads", 0)),
                "message": str(f.attrs.get("message", ""))}


def measure(python: Path, case: Path, increments: int, threads: int) -> dict[str, Any]:
    """One run of ``python -m ddpy run`` in a subprocess; its results and wall time."""
    with tempfile.TemporaryDirectory() as tmp:
        command = [str(python), "-m", "ddpy", "run", str(case), "--stop-after",
                   str(increments), "--threads", str(threads), "--output", f"{tmp}/out"]
        busy, cpu, start = cpu_busy(), children_cpu(), time.perf_counter()
        done = subprocess.run(command, cwd=tmp, env=environment(threads), capture_output=True,
                              text=True)
        wall = time.perf_counter() - start
        mine = children_cpu() - cpu
        other = max(cpu_busy() - busy - mine, 0.0) / wall
        if done.returncode != 0:
            sys.exit(f"{' '.join(command)} failed ({done.returncode}):\n"
                     f"{done.stderr[-2000:]}")
        return {**read_results(Path(tmp) / "out" / "results.h5"), "wall": wall, "cpu": mine,
                "other_cpus": other}


def corrections(r: dict[str, Any]) -> int:
    """The Newton corrections of a run, rejected trials included: as its results file
    counted them, else its factorizations (one per correction before the solver reused
    older factors)."""
    return int(r["counts"].get("newton_iterations") or r["counts"]["factorizations"])


def per_correction(r: dict[str, Any]) -> dict[str, float]:
    """Seconds per correction of each part, the total, outside MUMPS and the runner's wall
    time; the share outside MUMPS (fraction)."""
    n = max(corrections(r), 1)
    t = r["time"]
    s = {part: t.get(part, 0.0) / n for part in PARTS}
    s["total"] = t["total"] / n
    s["outside"] = s["total"] - s["factorization"] - s["solve"]
    s["share_outside"] = 1.0 - (t.get("factorization", 0.0) + t.get("solve", 0.0)) / t["total"]
    s["run_wall"] = r["run_wall"] / n
    s["gap"] = r["run_wall"] - t["total"]
    s["cpu"] = r["cpu"] / n
    s["waited"] = max(r["wall"] - r["cpu"], 0.0)
    return s


def compare_paths(a: dict[str, Any], b: dict[str, Any]) -> dict[str, Any]:
    """Whether two runs took the same path: the increments' counts and steps equal. Where
    not, the first increment and column that differ. Also the largest relative differences
    of the steps and tool forces."""
    ca, cb = a["columns"], b["columns"]
    common = [k for k in PATH_COLUMNS if k in ca and k in cb]
    first = None
    for i in range(max(a["increments"], b["increments"])):
        for key in common:
            va = ca[key][i] if i < len(ca[key]) else None
            vb = cb[key][i] if i < len(cb[key]) else None
            if va != vb:
                first = {"increment": i + 1, "column": key, "before": va, "after": vb}
                break
        if first:
            break

    def relative(x: Any, y: Any) -> float | None:
        if x is None or y is None:
            return None
        x, y = np.asarray(x, float), np.asarray(y, float)
        if x.shape != y.shape:
            return None
        scale = max(float(np.max(np.abs(x), initial=0.0)), 1e-300)
        return float(np.max(np.abs(x - y), initial=0.0)) / scale

    return {"same": first is None, "columns": common, "first_difference": first,
            "step": relative(ca.get("step"), cb.get("step")),
            "tool_force": relative(a.get("tool_force"), b.get("tool_force"))}


# --- the page -----------------------------------------------------------------------------


def ratio(a: float, b: float) -> str:
    return f"{b / a:.2f}" if a else "-"


def table(entry: dict[str, Any]) -> str:
    b, a = entry["before"], entry["after"]
    sb, sa = per_correction(b), per_correction(a)
    rows = ["| per Newton correction | before | after | after / before |",
            "|---|---|---|---|"]
    names = {"assembly": "assembly (s)", "contact": "contact (s)",
             "factorization": "factorization, MUMPS (s)",
             "solve": "solve, MUMPS (s; GMRES on older factors included)",
             "rest": "rest (s)", "total": "**total (s)**",
             "outside": "outside MUMPS (s)"}
    for key, name in names.items():
        digits = 4 if sb["total"] < 0.1 else 3
        rows.append(f"| {name} | {sb[key]:.{digits}f} | {sa[key]:.{digits}f} | "
                    f"{ratio(sb[key], sa[key])} |")
    rows.append(f"| **share outside MUMPS** | {100 * sb['share_outside']:.1f} % | "
                f"{100 * sa['share_outside']:.1f} % | "
                f"{100 * (sa['share_outside'] - sb['share_outside']):+.1f} points |")
    rows.append(f"| run wall time (s; the runner's, set-up and writing included) | "
                f"{sb['run_wall']:.4f} | "
                f"{sa['run_wall']:.4f} | {ratio(sb['run_wall'], sa['run_wall'])} |")
    rows.append("| **run** | | | |")
    rows.append(f"| increments | {b['increments']} | {a['increments']} | "
                f"{ratio(b['increments'], a['increments'])} |")
    rows.append(f"| Newton corrections (rejected trials included) | {corrections(b)} | "
                f"{corrections(a)} | {ratio(corrections(b), corrections(a))} |")
    for key, name in (("factorizations", "factorizations"),
                      ("krylov_iterations", "Krylov (GMRES) iterations"),
                      ("evaluations", "evaluations"), ("cutbacks", "cutbacks")):
        vb, va = b["counts"].get(key), a["counts"].get(key)
        rows.append(f"| {name} | {'-' if vb is None else vb} | {'-' if va is None else va} | "
                    f"{ratio(vb, va) if vb is not None and va is not None else '-'} |")
    rows.append(f"| increments' total (s) | {b['time']['total']:.2f} | "
                f"{a['time']['total']:.2f} | {ratio(b['time']['total'], a['time']['total'])} |")
    rows.append(f"| run wall time - increments' total (s) | {sb['gap']:.2f} | {sa['gap']:.2f} "
                f"| |")
    rows.append(f"| process CPU time per correction (s; start-up, set-up, writing included) | "
                f"{sb['cpu']:.4f} | {sa['cpu']:.4f} | {ratio(sb['cpu'], sa['cpu'])} |")
    rows.append(f"| process waited: wall - CPU time (s) | {sb['waited']:.2f} | "
                f"{sa['waited']:.2f} | |")
    rows.append(f"| other processes' CPUs during the kept try | {b['other_cpus']:.2f} | "
                f"{a['other_cpus']:.2f} | |")
    for key, name in (("total", "increments' total (s)"), ("cpu", "process CPU time (s)"),
                      ("other_cpus", "other processes' CPUs")):
        rows.append(f"| tries in order: {name} | "
                    f"{', '.join(f'{t[key]:.2f}' for t in b['tries'])} | "
                    f"{', '.join(f'{t[key]:.2f}' for t in a['tries'])} | |")
    return "\n".join(rows)


def path_text(entry: dict[str, Any]) -> str:
    p = compare_paths(entry["before"], entry["after"])
    cols = ", ".join(p["columns"])
    extra = []
    if p["step"] is not None:
        extra.append("the steps equal bit for bit" if p["step"] == 0.0 else
                     f"the steps differ by at most {p['step']:.2g} relative")
    if p["tool_force"] is not None:
        extra.append("the tool forces equal bit for bit" if p["tool_force"] == 0.0 else
                     f"the tool forces differ by at most {p['tool_force']:.2g} of the largest")
    if p["same"]:
        return (f"Same path: yes, every increment's {cols} are equal ({'; '.join(extra)}).")
    d = p["first_difference"]
    return (f"Same path: **no**; the first difference is increment {d['increment']}'s "
            f"{d['column']} ({d['before']} before, {d['after']} after); compared: {cols}"
            + (f" ({'; '.join(extra)})" if extra else "") + ".")


def spread(tries: list[float]) -> float:
    return max(tries) / min(tries) - 1.0 if len(tries) > 1 and min(tries) > 0 else 0.0


def notes(numbers: dict[str, Any]) -> list[str]:
    """Findings, computed from the numbers."""
    lines = []
    for mesh, entry in numbers["meshes"].items():
        b, a = entry["before"], entry["after"]
        sb, sa = per_correction(b), per_correction(a)
        scatter = max(spread([t["total"] for t in b["tries"]]),
                      spread([t["total"] for t in a["tries"]]))
        tries = (f"the tries of one side differ by up to {100 * scatter:.0f} %"
                 if scatter else "one try per side, so no scatter is known")
        changes = sorted(PARTS, key=lambda k: abs(sa[k] - sb[k]), reverse=True)
        top = changes[0]
        lines.append(
            f"{mesh}: {sb['total']:.4g} -> {sa['total']:.4g} s per correction "
            f"(after / before {sa['total'] / sb['total']:.2f}; {tries}); outside MUMPS "
            f"{sb['outside']:.4g} -> {sa['outside']:.4g} s (after / before "
            f"{ratio(sb['outside'], sa['outside'])}), its share {100 * sb['share_outside']:.0f} "
            f"-> {100 * sa['share_outside']:.0f} %. The largest change per correction is "
            f"{top}'s, {sb[top]:.4g} -> {sa[top]:.4g} s; contact after / before "
            f"{ratio(sb['contact'], sa['contact'])}, rest {ratio(sb['rest'], sa['rest'])}, "
            f"assembly {ratio(sb['assembly'], sa['assembly'])}.")
        lead = max(("assembly", "contact", "rest"), key=lambda k: sa[k])
        lines.append(
            f"{mesh}, after: MUMPS (factorization {100 * sa['factorization'] / sa['total']:.0f} "
            f"%, solve {100 * sa['solve'] / sa['total']:.0f} %) against {lead} "
            f"{100 * sa[lead] / sa['total']:.0f} %, the largest part outside it; "
            f"{corrections(a) / max(a['increments'], 1):.1f} corrections and "
            f"{a['counts'].get('factorizations', 0) / max(a['increments'], 1):.1f} "
            f"factorizations per increment.")
        lines.append(
            f"{mesh}: the process's CPU time per correction, which other work taking turns on "
            f"the core does not lengthen, {sb['cpu']:.4g} -> {sa['cpu']:.4g} s (after / "
            f"before {ratio(sb['cpu'], sa['cpu'])}, against {ratio(sb['total'], sa['total'])} "
            f"for the wall time of the increments); the kept tries waited (wall - CPU time) "
            f"{sb['waited']:.3g} s before and {sa['waited']:.3g} s after, with other processes "
            f"on {b['other_cpus']:.2f} and {a['other_cpus']:.2f} cores.")
        fb, fa = b["counts"].get("factorizations", 0), a["counts"].get("factorizations", 0)
        if fb and fa:
            ob = b["time"]["factorization"] / fb
            oa = a["time"]["factorization"] / fa
            same = compare_paths(b, a)["same"]
            lines.append(
                f"{mesh}: one factorization {ob:.4g} s before, {oa:.4g} s after (after / before "
                f"{oa / ob:.2f}): " + (
                    "both factorize the same matrices (same path) with MUMPS, so its ratio "
                    "shows the machine's drift between the kept tries and the way to MUMPS."
                    if same else "the two paths factorize different matrices, so the ratio "
                    "also holds the change of the Jacobian (its pattern and values)."))
        gap = sb["gap"] - sa["gap"]
        lines.append(
            f"{mesh}: run wall time minus the increments' total (set-up, writing) "
            f"{sb['gap']:.3g} s before, {sa['gap']:.3g} s after "
            f"({gap:+.3g} s, {gap / max(corrections(b), 1):+.2g} s per correction, against "
            f"{sb['total']:.3g} s per correction in the table); run wall time per correction "
            f"after / before {ratio(sb['run_wall'], sa['run_wall'])}.")
    paper = numbers["meshes"].get("paper")
    if paper:
        s = per_correction(paper["after"])
        lines.append(
            f"Target (the paper's {PAPER_ITERATIONS:,} iterations, Nagata, in {TARGET_MIN:g} "
            f"minutes: {60.0 * TARGET_MIN / PAPER_ITERATIONS:.2f} s per iteration), after, "
            f"paper: {s['total']:.2f} s per correction, "
            f"{s['total'] * PAPER_ITERATIONS / 3600:.1f} h for {PAPER_ITERATIONS:,}; outside "
            f"MUMPS {s['outside']:.2f} s.")
    return lines


def in_repository(path: str) -> str:
    """A path as the page shows it: from the repository root when it lies in a checkout of
    it (the generated cases are git-ignored, so one is passed in from elsewhere)."""
    parts = Path(path).parts
    if "benchmarks" in parts:
        return str(Path(*parts[parts.index("benchmarks"):]))
    return Path(path).name


def report(numbers: dict[str, Any]) -> str:
    co = numbers["checkouts"]
    stamps = computed_at(code_version(), {side: co[side]["code"] for side in SIDES})
    checkouts = "\n".join(
        f"- {side}: `{co[side]['code']}` (the checkout's `git describe --always`, "
        f"committed {co[side]['date']}{code_commit(co[side])})" for side in SIDES)
    if numbers.get("between"):
        checkouts += ("\n\nThe commits of after since before that change the code (ddpy, "
                      "fortran, the build), oldest first:\n\n"
                      + "\n".join(f"- `{c.split(' ', 1)[0]}` {c.split(' ', 1)[1]}"
                                   for c in numbers["between"]))
    sections = []
    for mesh, entry in numbers["meshes"].items():
        a = entry["after"]
        repeats = numbers["repeats"][mesh]
        tries = (f"{repeats} tries per side, the faster kept" if repeats > 1 else
                 "One try per side" + (" (not two: the paper mesh's runs take minutes each)"
                                       if mesh == "paper" else ""))
        case = ("each checkout's `ddpy/cases/cylindrical_bending`"
                + (" (the same files in both)" if entry["case_same"] else
                   " (**the two checkouts' case files differ**)")
                if mesh == "coarse" else f"`{in_repository(entry['case']['after'])}`")
        sections.append(
            f"## {mesh}: {a['hexahedra']:,} hexahedra, {a['nodes']:,} nodes, first "
            f"{entry['increments_asked']} increments\n\n"
            f"Case: {case}. {tries}.\n\n{table(entry)}\n\n{path_text(entry)}\n")
    note_text = "\n".join(f"- {line}" for line in notes(numbers))
    return f"""# Benchmark: time per Newton correction of a forming run, before and after

{stamps}

`benchmarks/forming_iteration/run.py` (written by it, measured in one run on
{numbers['machine']}; {numbers['threads']} thread per run, the machine shared with other work:
the rows "other processes' CPUs" of each table say how many cores other processes used
during a try, from /proc/stat). The code compared:

{checkouts}

{numbers.get("compared", COMPARED)}

The cylindrical bending case (Nagata tools), `<checkout>/.venv/bin/python -m ddpy run CASE
--stop-after N --threads {numbers['threads']}` in a subprocess per try, before and after
alternating. The seconds are the run's own split of each increment (`increments/time_*` of
results.h5: assembly = the solid's element loop; contact = search, second derivatives, law
and Jacobian entries of the tools; factorization and solve = MUMPS, solve including GMRES
with older factors; rest = the rest of the increment's loop), summed over the increments and
divided by the Newton corrections of all trials, rejected ones included
(`increments/newton_iterations`). Share outside MUMPS = 1 - (factorization + solve) / total.

{chr(10).join(sections)}
Notes (computed from the tables):

{note_text}
"""


# --- running --------------------------------------------------------------------------------


def machine() -> str:
    model = ""
    try:
        with open("/proc/cpuinfo") as info:
            model = next((line.split(":", 1)[1].strip() for line in info
                          if line.startswith("model name")), "")
    except OSError:
        pass
    return f"{platform.machine()}{f' ({model})' if model else ''}, {os.cpu_count()} cores"


def run(args: argparse.Namespace) -> dict[str, Any]:
    checkouts = {"before": args.before.resolve(), "after": args.after.resolve()}
    pythons = {side: python_of(path) for side, path in checkouts.items()}
    if "paper" in args.meshes and not (args.paper_case / "control.dat").is_file():
        sys.exit(f"{args.paper_case}: no paper case (write it with "
                 "benchmarks/cylindrical_bending/make_case.py --mesh paper, or pass "
                 "--paper-case FOLDER)")
    numbers: dict[str, Any] = {
        "code": code_version(), "machine": machine(), "threads": args.threads,
        "checkouts": {side: {"path": str(path), "code": checkout_code(path),
                             "date": git(path, "log", "-1", "--format=%cs").stdout.strip()}
                      for side, path in checkouts.items()},
        "between": between(checkouts["before"], checkouts["after"]),
        "repeats": {}, "meshes": {}}
    for mesh in args.meshes:
        n = args.coarse_increments if mesh == "coarse" else args.paper_increments
        repeats = args.repeats if mesh == "coarse" else args.paper_repeats
        cases = {side: case_of(mesh, path, args.paper_case.resolve())
                 for side, path in checkouts.items()}
        tries: dict[str, list[dict[str, Any]]] = {side: [] for side in SIDES}
        for k in range(repeats):
            for side in (SIDES if k % 2 == 0 else SIDES[::-1]):
                r = measure(pythons[side], cases[side], n, args.threads)
                tries[side].append(r)
                s = per_correction(r)
                print(f"{mesh} {side} try {k + 1}: {s['total']:.4f} s per correction "
                      f"({corrections(r)} corrections, {r['increments']} increments, "
                      f"wall {r['wall']:.1f} s, other CPUs {r['other_cpus']:.2f})", flush=True)
        entry: dict[str, Any] = {
            "increments_asked": n, "case": {side: str(c) for side, c in cases.items()},
            "case_same": len({folder_digest(c) for c in cases.values()}) == 1}
        for side in SIDES:
            kept = min(tries[side], key=lambda r: r["time"]["total"])
            entry[side] = {**kept, "tries": [
                {"total": r["time"]["total"], "wall": r["wall"], "cpu": r["cpu"],
                 "other_cpus": r["other_cpus"]} for r in tries[side]]}
        numbers["repeats"][mesh] = repeats
        numbers["meshes"][mesh] = entry
        print(path_text(entry), flush=True)
    return numbers


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", type=Path, help="checkout of the code before (with .venv)")
    parser.add_argument("--after", type=Path, default=ROOT,
                        help="checkout of the code after (default: this one)")
    parser.add_argument("--paper-case", type=Path, default=PAPER_CASE,
                        help="the paper mesh's case folder (Nagata tools)")
    parser.add_argument("--meshes", nargs="+", default=["coarse", "paper"],
                        choices=["coarse", "paper"])
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=2, help="tries per side, coarse")
    parser.add_argument("--paper-repeats", type=int, default=2, help="tries per side, paper")
    parser.add_argument("--coarse-increments", type=int, default=20)
    parser.add_argument("--paper-increments", type=int, default=2)
    parser.add_argument("--json", type=Path, default=DOCS / "forming_iteration.json")
    parser.add_argument("--markdown", type=Path, default=DOCS / "forming_iteration.md")
    parser.add_argument("--compared", type=Path, metavar="FILE",
                        help="what before and after are, in Markdown (kept in the JSON)")
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the page from the JSON, measure nothing")
    args = parser.parse_args(argv)
    if args.report_only:
        numbers = json.loads(args.json.read_text())
        if args.compared is not None:
            numbers["compared"] = args.compared.read_text().strip()
            args.json.write_text(json.dumps(numbers, indent=1) + "\n")
        args.markdown.write_text(report(numbers))
        return 0
    if args.before is None:
        parser.error("--before CHECKOUT is needed (a checkout of the code to compare with, "
                     "its .venv built)")
    numbers = run(args)
    if args.compared is not None:
        numbers["compared"] = args.compared.read_text().strip()
    args.json.write_text(json.dumps(numbers, indent=1) + "\n")
    args.markdown.write_text(report(numbers))
    return 0


if __name__ == "__main__":
    sys.exit(main())
