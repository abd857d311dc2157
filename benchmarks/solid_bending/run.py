"""Benchmark: a DDQ steel strip of 20,172 hexahedra in 3 layers bent into the plastic range.

The strip, 120 x 30 x 1 mm (the blank of the paper's bending benchmark), is clamped at x = 0
and its end x = 120 is pushed down by a prescribed 30 mm in increments (the root yields at
about 8 mm). Every Newton iteration is timed: assembly with the return mapping (Fortran,
OpenMP), MUMPS factorization and solve. Each thread count runs in its own process with
OMP_NUM_THREADS and OPENBLAS_NUM_THREADS set, one after the other.

    python benchmarks/solid_bending/run.py [--threads 1 2] [--increments 12]

writes docs/benchmarks/solid_bending.md, solid_bending.json and solid_bending.png.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmarks' shared module
from bench_common import code_version, computed_at  # noqa: E402

LENGTH, WIDTH, THICK = 120.0, 30.0, 1.0
NX, NY, NZ = 164, 41, 3
DEFLECTION = 30.0
# DDQ steel of the paper's Table 4 (MPa).
PROPS = [210e3, 0.3, 0.3137, 0.3663, 0.6337, 1.5, 1.5, 1.1764, 1, 568.3, 0.0059, 0.233,
         0, 0, 0, 0]


def cpu_busy() -> float:
    """CPU seconds all processes have used since boot (/proc/stat)."""
    with open("/proc/stat") as stat:
        fields = [int(v) for v in stat.readline().split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields) - idle) / os.sysconf("SC_CLK_TCK")


def own_cpu() -> float:
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def other_load(seconds: float) -> float:
    """CPUs used by other processes over the next ``seconds`` (this process idle)."""
    busy, own, start = cpu_busy(), own_cpu(), time.perf_counter()
    time.sleep(seconds)
    return max(cpu_busy() - busy - (own_cpu() - own), 0.0) / (time.perf_counter() - start)


def wait_quiet(timeout: float, threshold: float = 0.2) -> float:
    """Wait up to ``timeout`` s until other processes use less than ``threshold`` CPUs."""
    deadline = time.perf_counter() + timeout
    load = other_load(0.5)
    while load >= threshold and time.perf_counter() < deadline:
        load = other_load(2.0)
    return load


def worker(increments: int) -> dict:
    """One run in this process (threads come from the environment)."""
    from ddpy.core.linalg import MumpsSolver
    from ddpy.core.parallel import max_threads
    from ddpy.model.control import NewtonSettings
    from ddpy.model.mesh import HexMesh
    from ddpy.model.solid import Solid
    from ddpy.model.static import StaticProblem

    start = time.perf_counter()
    mesh = HexMesh.box(LENGTH, WIDTH, THICK, NX, NY, NZ)
    solid = Solid(mesh, np.array(PROPS), rolling_direction_deg=0.0)
    problem = StaticProblem(solid)
    problem.fix(mesh.select(x=0.0), "xyz")
    end = mesh.select(x=LENGTH)
    problem.fix(end, "z", -DEFLECTION)
    setup = time.perf_counter() - start
    start = time.perf_counter()
    layout = problem._prepare()  # pattern and MUMPS analysis, once for the whole run
    analysis = time.perf_counter() - start
    solver: MumpsSolver = problem._solver  # type: ignore[assignment]
    busy, own = cpu_busy(), own_cpu()
    start = time.perf_counter()
    result = problem.solve(increments=increments, newton=NewtonSettings(1e-6, 1e-6))
    total = time.perf_counter() - start
    others = max(cpu_busy() - busy - (own_cpu() - own), 0.0) / total
    stats = solver.statistics()
    reaction = float(result.reactions[-1][end, 2].sum())
    return {
        "threads": max_threads(),
        "openblas_threads": os.environ.get("OPENBLAS_NUM_THREADS"),
        "code": code_version(),
        "elements": mesh.n_elements, "nodes": mesh.n_nodes,
        "gauss_points": int(result.ep[-1].size),
        "free_dofs": int((~problem.fixed).sum()), "nnz": int(layout.k_slots),
        "setup_s": setup, "analysis_s": analysis, "solve_total_s": total,
        "increments": len(result.factors), "cuts": result.cuts,
        "iterations": result.iterations,
        "timings": result.timings, "evaluations": result.evaluations,
        "corrections": result.newton_iterations, "factorizations": result.factorizations,
        "ep_max": float(result.ep[-1].max()),
        "plastic_fraction": float((result.ep[-1] > 0).mean()),
        "end_force_N": reaction,
        "mumps": stats, "other_cpus": others,
    }


def summary(run: dict) -> dict:
    """Mean seconds of one assembly, factorization and solve, and of a Newton correction with
    everything it took (line-search evaluations included)."""
    t = run["timings"]
    out = {"assembly": t["assembly"] / run["evaluations"],
           "factorization": t["factorization"] / run["factorizations"],
           "solve": t["solve"] / run["corrections"]}
    out["per_iteration"] = sum(t.values()) / run["corrections"]
    out["ratio"] = out["assembly"] / out["factorization"]
    # Evaluations beyond one per correction and one per increment: line-search trials.
    out["line_searches"] = run["evaluations"] - run["corrections"] - run["increments"] - run["cuts"]
    return out


ORDERINGS = {0: "AMD", 1: "nested dissection of the mesh (ddpy.core.ordering)", 2: "AMF",
             3: "SCOTCH", 4: "PORD", 5: "METIS", 6: "QAMD"}
HEADER = ("| threads | assembly | factorization | solve | per iteration (all) "
          "| assembly / factorization | iterations | line-search evaluations | run (s) "
          "| other CPUs |\n|---|---|---|---|---|---|---|---|---|---|")


def write_report(runs: list[dict], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = []
    for run in runs:
        s = summary(run)
        rows.append(
            f"| {run['threads']} | {s['assembly']:.3f} | {s['factorization']:.3f} | "
            f"{s['solve']:.3f} | {s['per_iteration']:.2f} | {100 * s['ratio']:.1f} % "
            f"| {sum(run['iterations'])} | {s['line_searches']} | "
            f"{run['solve_total_s']:.0f} | {run['other_cpus']:.2f} |")
    first = runs[0]
    s1 = summary(first)
    speedup = ""
    if len(runs) > 1:
        s2 = summary(runs[1])
        speedup = (f"From 1 to {runs[1]['threads']} threads the assembly runs "
                   f"{s1['assembly'] / s2['assembly']:.2f} times faster and the factorization "
                   f"{s1['factorization'] / s2['factorization']:.2f} times. ")
    ratios = ", ".join(f"{100 * summary(r)['ratio']:.1f} % on {r['threads']} thread"
                       f"{'s' if r['threads'] > 1 else ''}" for r in runs)
    verdict = "meets" if all(summary(r)["ratio"] < 0.2 for r in runs) else "misses"
    mumps = first["mumps"]
    iterations = ", ".join(str(i) for i in first["iterations"])
    gauss = (f"at {first['gauss_points']:,} Gauss points" if "gauss_points" in first else
             "at every Gauss point")
    code = computed_at(first.get("code", ""), {f"{r['threads']} thread(s)": r.get("code", "")
                                               for r in runs} if len(runs) > 1 else None)
    text = f"""# Benchmark: plastic bending of a {first['elements']:,}-hexahedron sheet

{code}

`benchmarks/solid_bending/run.py` (written by it; numbers from one run on
{platform.machine()} with {os.cpu_count()} cores, shared with other work, so single timings
scatter by tens of percent: means over the run are given).

**Model.** A DDQ steel strip (paper Table 4: E = 210 GPa, nu = 0.3, Hill'48 F = 0.3137,
G = 0.3663, H = 0.6337, L = M = 1.5, N = 1.1764, Swift K = 568.3 MPa, eps0 = 0.0059,
n = 0.233) of 120 x 30 x 1 mm, {NX} x {NY} x {NZ} = {first['elements']:,} hexahedra
({NZ} layers), {first['nodes']:,} nodes, {first['free_dofs']:,} free dofs; clamped at x = 0,
the end x = 120 pushed down by {DEFLECTION:.0f} mm (prescribed u_z) in
{first['increments']} increments. At the end {100 * first['plastic_fraction']:.0f} % of the
Gauss points have yielded, the largest equivalent plastic strain is
{first['ep_max']:.4f}, the end force is {abs(first['end_force_N']):.1f} N. Tolerances
1e-6 on force and correction; symmetric storage ({first['nnz']:,} coordinate entries, lower
triangle), MUMPS LDL^T with ordering {ORDERINGS.get(mumps['ordering'], mumps['ordering'])}
(INFOG(7) = {mumps['ordering']}), {mumps['flops']:.3g}
flops and {mumps['factor_entries']:,} entries per factorization. Pattern and MUMPS analysis
once per run: {first['analysis_s']:.2f} s.

**Time per Newton iteration** (mean seconds of one assembly, factorization and solve, as
the core's Newton loop measures them; assembly = internal forces, consistent tangent and
return mapping {gauss}, written straight into the MUMPS coordinate values; per iteration =
everything over the Newton corrections, the evaluations of the energy line search when a
whole step overshoots included; "other CPUs": how many of the {os.cpu_count()} cores other
processes used on average during the run, from /proc/stat):

{HEADER}
{chr(10).join(rows)}

Assembly / factorization (means): {ratios}: the run {verdict} the target of less than
20 %.
{speedup}(The factorization is MUMPS's: its multithreading comes from OpenBLAS inside the
dense frontal matrices only.) Iterations per increment: {iterations}
(cuts: {first['cuts']}).

![time per iteration](solid_bending.png)
"""
    out.mkdir(parents=True, exist_ok=True)
    (out / "solid_bending.md").write_text(text)
    (out / "solid_bending.json").write_text(json.dumps(runs, indent=1))
    fig, ax = plt.subplots(figsize=(6, 3.2))
    labels = [f"{r['threads']} thread{'s' if r['threads'] > 1 else ''}" for r in runs]
    left = np.zeros(len(runs))
    for key, colour in (("assembly", "C0"), ("factorization", "C1"), ("solve", "C2")):
        values = np.array([summary(r)[key] for r in runs])
        ax.barh(labels, values, left=left, color=colour, label=key)
        left += values
    ax.set_xlabel("seconds per assembly, factorization and solve (mean)")
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title(f"{first['elements']:,} hexahedra, {first['free_dofs']:,} dofs", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "solid_bending.png", dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--increments", type=int, default=12)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "benchmarks")
    parser.add_argument("--wait-quiet", type=float, default=0.0, metavar="SECONDS",
                        help="before each run wait up to SECONDS for other processes to "
                        "use less than 0.2 CPUs")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(args.increments)))
        return
    runs = []
    for n in args.threads:
        if args.wait_quiet > 0:
            wait_quiet(args.wait_quiet)
        env = dict(os.environ, OMP_NUM_THREADS=str(n), OPENBLAS_NUM_THREADS=str(n))
        out = subprocess.run([sys.executable, __file__, "--worker", "--increments",
                              str(args.increments)], env=env, capture_output=True, text=True,
                             check=True)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
        s = summary(runs[-1])
        print(f"{n} thread(s): assembly {s['assembly']:.3f} s, factorization "
              f"{s['factorization']:.3f} s, solve {s['solve']:.3f} s, ratio "
              f"{100 * s['ratio']:.1f} %, iterations {runs[-1]['iterations']}", flush=True)
    write_report(runs, args.out)


if __name__ == "__main__":
    main()
