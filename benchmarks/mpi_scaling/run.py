"""MPI processes and the parallel MUMPS (docs/mpi.md): the same answers, the time and memory
per factorization and per iteration on 1 and 2 processes, and MUMPS's own estimates for
large blanks. Writes docs/benchmarks/mpi_scaling.md and its numbers, mpi_scaling.json.

Needs both builds: .venv (sequential, ./setup.sh) and .venv-mpi (./setup.sh --mpi).

    python benchmarks/mpi_scaling/run.py                 # every part, then the report
    python benchmarks/mpi_scaling/run.py --part answers  # one part (answers, paper,
                                                         # estimates), kept in the JSON
    python benchmarks/mpi_scaling/run.py --report        # the report from the JSON

- answers: the built-in case (`ddpy run`) with the sequential build and with the MPI build
  on 1, 2 and 3 processes (3 oversubscribed on this 2-core machine), and the coarse
  cylindrical bending cases of the other tool models on 2 processes: increments,
  iterations, forces and final fields against the sequential run.
- paper: the first increments of the paper's bending blank (Nagata tools, make_case.py
  --mesh paper), sequential build and MPI build on 1 process with 1 and 2 threads and on 2
  processes with 1 thread each: time per factorization and per Newton iteration (the run's
  own timings), peak memory of every process.
- estimates: MUMPS's analysis (elemental input, the mesh's nested dissection order) of
  structured blanks of 20 thousand, 200 thousand and 2 million hexahedra (3 layers) on 1 to
  64 processes: estimated flops, factor entries and memory per process.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
import bench_common  # noqa: E402

ROOT = bench_common.ROOT
SEQ_PYTHON = ROOT / ".venv" / "bin" / "python"
MPI_PYTHON = ROOT / ".venv-mpi" / "bin" / "python"
WORK = HERE / "results"
JSON_FILE = bench_common.DOCS / "mpi_scaling.json"
REPORT = bench_common.DOCS / "mpi_scaling.md"
BENDING = ROOT / "benchmarks" / "cylindrical_bending"
PAPER_CASE = BENDING / "cases" / "paper" / "nagata"
COARSE_MODELS = ("bezier", "facets_coarse", "facets_fine")
#: Increments of the paper's blank timed (its first increment is the careful start: a
#: factorization at every iteration).
PAPER_INCREMENTS = 2
#: --kept-only: report the runs kept in WORK and run nothing more (a part cut short).
KEPT_ONLY = False
#: Structured blanks for the estimates: (label, nx, ny, layers); 3 layers as the paper's.
BLANKS = (("20k", 115, 58, 3), ("200k", 365, 183, 3), ("2M", 1155, 577, 3))
ESTIMATE_PROCESSES = (1, 2, 4, 8, 16, 32, 64)
#: Memory of one process that the estimates plan with: this machine's 24 GB over 2 cores.
MEMORY_PER_PROCESS_MB = 12_000


# ---- running ddpy on processes --------------------------------------------------------


def mpirun_args(n: int) -> list[str]:
    """mpirun on n processes of this machine, as docs/mpi.md says: as root, beyond the
    cores, not bound to one core each (the driver's threads need both)."""
    args = ["mpirun", "-n", str(n), "--oversubscribe", "--bind-to", "none"]
    if os.geteuid() == 0:
        args.append("--allow-run-as-root")
    return args + ["-x", "OMP_NUM_THREADS"]


def rank_main(argv: list[str]) -> int:
    """`ddpy` (its cli.main) with the peak memory of this process written at its end to
    <output>/memory-<rank>.json (the ranks > 0 serve in cli.main)."""
    from ddpy.app.cli import main
    from ddpy.core import mpi

    code = main(argv)
    rank = int(os.environ.get("OMPI_COMM_WORLD_RANK", "0"))
    output = Path(argv[argv.index("--output") + 1])
    output.mkdir(parents=True, exist_ok=True)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    (output / f"memory-{rank}.json").write_text(json.dumps({"rank": rank, "peak_mb": peak_mb}))
    del mpi
    return code


def ddpy_run(build: str, processes: int, threads: int, case: Path | None, output: Path,
             extra: list[str] = ()) -> dict[str, Any]:
    """One `ddpy run` (build "seq" or "mpi"; processes > 1 only for "mpi") into output;
    its wall time, each process's peak memory and the machine's load. Kept in
    <output>/run.json: a run done before is not run again (delete its folder for that)."""
    kept = output / "run.json"
    if kept.exists():
        return json.loads(kept.read_text())
    if KEPT_ONLY:
        raise FileNotFoundError(kept)
    if output.exists():
        shutil.rmtree(output)
    load_before = os.getloadavg()[0]
    python = SEQ_PYTHON if build == "seq" else MPI_PYTHON
    command = [str(python), str(Path(__file__).resolve()), "--rank-main", "run"]
    command += ([str(case)] if case else []) + ["--output", str(output),
                                                "--threads", str(threads), *extra]
    if build == "mpi":
        command = mpirun_args(processes) + command
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env,
                          stdin=subprocess.DEVNULL, cwd=WORK)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    memory = sorted((json.loads(p.read_text()) for p in output.glob("memory-*.json")),
                    key=lambda m: m["rank"])
    run = {"wall_s": wall, "peak_mb": [round(m["peak_mb"], 1) for m in memory],
           "load": [round(load_before, 1), round(os.getloadavg()[0], 1)]}
    kept.write_text(json.dumps(run))
    return run


def read_run(folder: Path) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """A run's increments and its last frame's fields."""
    import h5py

    with h5py.File(folder / "results.h5", "r") as f:
        k = f["increments"].attrs["count"]
        increments = {name: f["increments"][name][:k] for name in f["increments"]}
        last = f["fields"][f"{f['fields'].attrs['count'] - 1:06d}"]
        fields = {name: last[name][()] for name in
                  ("displacement", "stress", "plastic_strain", "thickness")}
    return increments, fields


def compare(reference: Path, other: Path) -> dict[str, Any]:
    """How a run differs from the reference run: increments, iterations, relative
    differences of steps, forces and the last frame's fields."""
    (a, fa), (b, fb) = read_run(reference), read_run(other)
    same = a["step"].size == b["step"].size

    def rel(x: np.ndarray, y: np.ndarray) -> float:
        scale = float(np.abs(x).max())
        return float(np.abs(x - y).max() / scale) if scale else float(np.abs(x - y).max())

    result: dict[str, Any] = {
        "increments": [int(a["step"].size), int(b["step"].size)],
        "iterations": [int(a["iterations"].sum()), int(b["iterations"].sum())],
        "factorizations": [int(a["factorizations"].sum()), int(b["factorizations"].sum())],
        "cutbacks": [int(a["cutbacks"].sum()), int(b["cutbacks"].sum())],
    }
    # The last frame (the end of the run) holds the same nodes whatever the path.
    result.update({name: rel(fa[name], fb[name]) for name in fa})
    if same:
        differ = np.flatnonzero(a["iterations"] != b["iterations"])
        result.update({
            "increments_with_other_iterations": [int(i) + 1 for i in differ],
            "step": rel(a["step"], b["step"]),
            "tool_force": rel(a["tool_force"], b["tool_force"]),
        })
    else:
        # Another path of increments: the forming phase's tool forces compared at the
        # reference's travels (linear interpolation of the other run's curve).
        ka, kb = a["phase"] == 0, b["phase"] == 0
        xa, xb = a["travel"][ka], b["travel"][kb]
        fa0, fb0 = a["tool_force"][ka], b["tool_force"][kb]
        at = np.stack([[np.interp(xa, xb, fb0[:, t, c]) for c in range(3)]
                       for t in range(fa0.shape[1])]).transpose(2, 0, 1)
        result["tool_force_on_travel"] = rel(fa0, at)
        # what a path's difference is measured against: the reference curve's largest
        # change over one increment (a facet's jump)
        result["tool_force_jump"] = float(np.abs(np.diff(fa0, axis=0)).max()
                                          / np.abs(fa0).max())
    return result


def timings(folder: Path) -> dict[str, float]:
    """Per factorization and per Newton iteration, from the run's own timings."""
    inc, _ = read_run(folder)
    lu = int(inc["factorizations"].sum())
    iterations = int(inc["iterations"].sum())
    return {"increments": int(inc["step"].size), "iterations": iterations,
            "factorizations": lu, "krylov_iterations": int(inc["krylov_iterations"].sum()),
            "s_per_factorization": float(inc["time_factorization"].sum()) / max(lu, 1),
            "s_per_iteration": float(inc["time_total"].sum()) / max(iterations, 1),
            "solve_s": float(inc["time_solve"].sum()),
            "assembly_s": float(inc["time_assembly"].sum()),
            "total_s": float(inc["time_total"].sum())}


# ---- the parts ------------------------------------------------------------------------


def make_cases(mesh: str) -> None:
    """The cylindrical bending cases of one blank (its make_case.py), on a fresh checkout."""
    subprocess.run([str(SEQ_PYTHON), str(BENDING / "make_case.py"), "--mesh", mesh],
                   check=True)


def part_answers() -> dict[str, Any]:
    """The built-in case on the sequential build and on 1, 2, 3 processes; the coarse
    cases of the other tool models on 2 processes."""
    out: dict[str, Any] = {"built_in": {}, "coarse": {}}
    reference = WORK / "answers" / "seq"
    out["built_in"]["seq"] = ddpy_run("seq", 1, 1, None, reference)
    for n in (2, 1, 3):
        folder = WORK / "answers" / f"mpi{n}"
        try:
            run = ddpy_run("mpi", n, 1, None, folder)
        except FileNotFoundError:
            continue
        out["built_in"][f"mpi{n}"] = {**run, **compare(reference, folder)}
        print(f"built-in, {n} process(es): {out['built_in'][f'mpi{n}']}", file=sys.stderr)
    for model in COARSE_MODELS:
        case = BENDING / "cases" / "coarse" / model
        if not (case / "control.dat").exists():
            make_cases("coarse")
        seq = WORK / "answers" / f"coarse-{model}-seq"
        par = WORK / "answers" / f"coarse-{model}-mpi2"
        try:
            ddpy_run("seq", 1, 1, case, seq)
            run = ddpy_run("mpi", 2, 1, case, par)
        except FileNotFoundError:
            continue
        out["coarse"][model] = {**run, **compare(seq, par)}
        print(f"coarse {model}, 2 processes: {out['coarse'][model]}", file=sys.stderr)
    return out


def part_paper() -> dict[str, Any]:
    """The paper's blank, its first increments, on each set-up."""
    if not (PAPER_CASE / "control.dat").exists():
        make_cases("paper")
    setups = (("mpi", 2, 1), ("mpi", 1, 1), ("mpi", 1, 2), ("seq", 1, 2))
    out: dict[str, Any] = {"increments": PAPER_INCREMENTS, "runs": {}}
    for build, n, threads in setups:
        label = f"{build} {n}p {threads}t"
        folder = WORK / "paper" / label.replace(" ", "-")
        try:
            run = ddpy_run(build, n, threads, PAPER_CASE, folder,
                           ["--stop-after", str(PAPER_INCREMENTS)])
        except FileNotFoundError:
            continue
        out["runs"][label] = {"build": build, "processes": n, "threads": threads, **run,
                              **timings(folder)}
        print(f"paper {label}: {out['runs'][label]}", file=sys.stderr)
    return out


def blank_structure(label: str, nx: int, ny: int, layers: int) -> Path:
    """The element unknowns and the nested dissection pivot order of a structured blank
    (3 unknowns per node), kept in WORK/estimates/<label>.npz."""
    path = WORK / "estimates" / f"{label}.npz"
    if path.exists():
        return path
    from ddpy.core.ordering import equation_order, nested_dissection, node_adjacency
    from ddpy.model.mesh import HexMesh

    path.parent.mkdir(parents=True, exist_ok=True)
    mesh = HexMesh.box(nx * 1.0, ny * 1.0, 1.0, nx, ny, layers)
    elements = np.asarray(mesh.elements, dtype=np.int64)
    start = time.perf_counter()
    nodes = nested_dissection(node_adjacency(elements, len(mesh.nodes)), mesh.nodes)
    position = equation_order(nodes, np.repeat(np.arange(len(mesh.nodes)), 3))
    seconds = time.perf_counter() - start
    unknowns = (3 * elements[:, :, None] + np.arange(3)).reshape(len(elements), 24)
    np.savez(path, unknowns=unknowns.astype(np.int32), position=position.astype(np.int32),
             hexahedra=len(elements), n=3 * len(mesh.nodes), ordering_s=seconds)
    return path


def analyse_main(structure: Path, output: Path, assembled: bool = False) -> int:
    """Under mpirun: rank 0 analyses the structure (elemental input, or the elements'
    coordinates when ``assembled``; its pivot order) and writes MUMPS's estimates; ranks > 0
    serve."""
    from ddpy.core import mpi

    if mpi.start() > 0:
        mpi.serve()
        return 0
    from ddpy.core.linalg import MumpsSolver

    data = np.load(structure)
    solver = MumpsSolver()
    solver.set_ordering(data["position"])
    start = time.perf_counter()
    unknowns = data["unknowns"]
    if assembled:
        solver.analyse(int(data["n"]), np.repeat(unknowns, 24, axis=1).ravel(),
                       np.tile(unknowns, (1, 24)).ravel())
    else:
        solver.analyse_elements(int(data["n"]), unknowns)
    stats = solver.statistics()
    stats["analysis_s"] = time.perf_counter() - start
    stats["peak_mb_rank0"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    output.write_text(json.dumps(stats))
    return 0


def part_estimates() -> dict[str, Any]:
    """MUMPS's estimates for each blank and number of processes."""
    out: dict[str, Any] = {}
    for label, nx, ny, layers in BLANKS:
        structure = blank_structure(label, nx, ny, layers)
        data = np.load(structure)
        entry: dict[str, Any] = {"hexahedra": int(data["hexahedra"]), "unknowns": int(data["n"]),
                                 "ordering_s": float(data["ordering_s"]), "processes": {}}
        for n in ESTIMATE_PROCESSES:
            result = WORK / "estimates" / f"{label}-{n}.json"
            command = mpirun_args(n) + [str(MPI_PYTHON), str(Path(__file__).resolve()),
                                        "--analyse", str(structure), str(result)]
            if KEPT_ONLY and not result.exists():
                continue
            if not result.exists():  # kept: delete WORK/estimates to analyse again
                done = subprocess.run(command, capture_output=True, text=True,
                                      env=dict(os.environ, OMP_NUM_THREADS="1"),
                                      stdin=subprocess.DEVNULL)
                if done.returncode != 0:
                    raise RuntimeError(f"analysis of {label} on {n} failed:\n{done.stderr}")
            entry["processes"][str(n)] = json.loads(result.read_text())
            print(f"estimates {label} on {n}: {entry['processes'][str(n)]}", file=sys.stderr)
        if label == BLANKS[0][0]:  # the elemental input's estimates against the assembled's
            result = WORK / "estimates" / f"{label}-1-assembled.json"
            if not result.exists() and not KEPT_ONLY:
                subprocess.run([str(MPI_PYTHON), str(Path(__file__).resolve()), "--analyse",
                                str(structure), str(result), "assembled"], check=True,
                               stdin=subprocess.DEVNULL)
            if result.exists():
                entry["assembled_1"] = json.loads(result.read_text())
        out[label] = entry
    return out


# ---- the report -----------------------------------------------------------------------


def _g(x: float, digits: int = 3) -> str:
    return f"{x:.{digits}g}"


def _e(x: float) -> str:
    return f"{x:.1e}"


def _load(run: dict[str, Any]) -> str:
    """The machine's 1-minute load average before and after a run."""
    return "{} / {}".format(*run["load"]) if "load" in run else "?"


def report(data: dict[str, Any]) -> str:
    row = bench_common.table_row
    lines = ["# MPI processes and the parallel MUMPS", "",
             bench_common.computed_at(data.get("code", "")) + " Written by "
             "`benchmarks/mpi_scaling/run.py` (every number below is computed by it) on "
             f"this machine: {data.get('cores', '?')} cores, shared with other work: the "
             "load column gives the machine's 1-minute load average before and after each "
             "run (2 is both cores busy), so the times are as noisy as that says; how to run "
             "with MPI: [docs/mpi.md](../mpi.md).", ""]
    answers = data.get("answers")
    if answers:
        lines += ["## The same answers", "",
                  "Each run against the sequential build's run of the same case (`ddpy run`, "
                  "1 thread per process). Relative differences: the largest difference over "
                  "all increments (steps, tool forces) or over the last frame (fields), over "
                  "the largest value; where the runs took different increments, the tool "
                  "forces of the forming phase at the sequential run's travels (\"on "
                  "travel\") and no steps. With single-precision factors (the default) each "
                  "Newton correction is GMRES's to its tolerance, not an exact solve, so the "
                  "builds agree to the convergence tolerance, not to rounding, and an "
                  "increment can take another path (docs/mpi.md).", "",
                  row(["case", "processes", "increments (seq / MPI)",
                       "Newton iterations (seq / MPI)", "increments with other iterations",
                       "step", "tool force", "displacement", "stress", "plastic strain",
                       "wall s", "load"]),
                  row(["---"] * 12)]

        def add(case: str, n: str, r: dict[str, Any]) -> None:
            other = r.get("increments_with_other_iterations", [])
            lines.append(row([case, n, "{} / {}".format(*r["increments"]),
                              "{} / {}".format(*r["iterations"]),
                              (", ".join(map(str, other)) or "none")
                              if "increments_with_other_iterations" in r else "-",
                              _e(r["step"]) if "step" in r else "-",
                              _e(r["tool_force"]) if "tool_force" in r else
                              _e(r["tool_force_on_travel"]) + " (on travel; the largest "
                              "change over one increment: " + _e(r["tool_force_jump"]) + ")"
                              if "tool_force_on_travel" in r else "-",
                              _e(r.get("displacement", float("nan"))),
                              _e(r.get("stress", float("nan"))),
                              _e(r.get("plastic_strain", float("nan"))),
                              _g(r["wall_s"]), _load(r)]))

        for key, r in answers["built_in"].items():
            if key != "seq":
                add("built-in (coarse, Nagata)", key[3:], r)
        for model, r in answers["coarse"].items():
            add(f"coarse, {model}", "2", r)
        lines += ["", f"The sequential build's built-in run took "
                  f"{_g(answers['built_in']['seq']['wall_s'])} s.", ""]
    paper = data.get("paper")
    if paper:
        lines += ["## Time and memory on the paper's bending blank", "",
                  f"The first {paper['increments']} increments of the paper's blank (Nagata "
                  "tools; the first increment factorizes at every iteration). Times are the "
                  "run's own (results.h5: factorization time over factorizations, the "
                  "increments' time over their Newton iterations); peak memory is each "
                  "process's largest resident size (rank 0 first).", "",
                  row(["build", "processes x threads", "factorizations", "s per factorization",
                       "Newton iterations", "s per iteration", "solves s", "peak MB per process",
                       "wall s", "load"]),
                  row(["---"] * 10)]
        for r in paper["runs"].values():
            lines.append(row([r["build"], f"{r['processes']} x {r['threads']}",
                              r["factorizations"], _g(r["s_per_factorization"]),
                              r["iterations"], _g(r["s_per_iteration"]), _g(r["solve_s"]),
                              " + ".join(f"{m:.0f}" for m in r["peak_mb"]),
                              _g(r["wall_s"]), _load(r)]))
        lines.append("")
    estimates = data.get("estimates")
    if estimates:
        lines += ["## MUMPS's estimates for large blanks", "",
                  "Structured blanks of 3 layers (HexMesh.box), 3 unknowns per node, the "
                  "mesh's nested dissection order, LU; MUMPS's analysis only (elemental "
                  "input): RINFOG(1) flops of the elimination, INFOG(3) factor entries, "
                  "INFOG(16) / INFOG(17) memory of the factorization in core on the largest "
                  "process / all processes (with the 40 % workspace ddpy asks for). The "
                  "contact multipliers are left out (a few per cent of the unknowns).", "",
                  row(["blank", "hexahedra", "unknowns", "processes", "flops",
                       "factor entries", "MB, largest process", "MB, all processes",
                       "analysis s"]),
                  row(["---"] * 9)]
        for label, e in estimates.items():
            for n, s in e["processes"].items():
                lines.append(row([label, e["hexahedra"], e["unknowns"], n,
                                  _e(s["estimated_flops"]), _e(s["estimated_factor_entries"]),
                                  s["estimated_memory_mb_max"],
                                  s["estimated_memory_mb_total"], _g(s["analysis_s"])]))
        first = next(iter(estimates.values()))
        if "assembled_1" in first:
            e, a = first["processes"]["1"], first["assembled_1"]
            lines += ["", "The elemental input against the coordinates a run gives: on the "
                      f"{next(iter(estimates))} blank, 1 process, the same structure given as "
                      "coordinates and the same order estimate "
                      f"{_e(a['estimated_flops'])} flops, {_e(a['estimated_factor_entries'])} "
                      f"factor entries and {a['estimated_memory_mb_max']} MB, against "
                      f"{_e(e['estimated_flops'])}, {_e(e['estimated_factor_entries'])} and "
                      f"{e['estimated_memory_mb_max']} MB above."]
        lines += ["", *plan(data), ""]
    return "\n".join(lines)


def plan(data: dict[str, Any]) -> list[str]:
    """What the estimates mean: processes and memory each blank needs, and a time per
    factorization from the flop rate measured on the paper's blank."""
    row = bench_common.table_row
    estimates = data["estimates"]
    rate = None
    paper = data.get("paper", {}).get("runs", {})
    twelve = estimates.get("20k", {}).get("processes", {}).get("1")
    one = paper.get("mpi 1p 1t")
    if one and twelve:
        rate = twelve["estimated_flops"] / one["s_per_factorization"]
    two = paper.get("mpi 2p 1t")
    # rank 0's own share beyond MUMPS's: the driver (mesh, state, assembly, contact, output)
    # of the paper's 20,010-hexahedron blank, as rank 0's peak over rank 1's on 2 processes
    driver_mb = (two["peak_mb"][0] - two["peak_mb"][1]) if two and len(two["peak_mb"]) > 1 \
        else None
    lines = ["### An estimate of what each blank needs", "",
             f"Stated as an estimate: with {MEMORY_PER_PROCESS_MB // 1000} GB per process "
             "(this machine's 24 GB over its 2 cores), the fewest processes of those analysed "
             "whose largest MUMPS share fits" + (
                 f"; the time per factorization at the flop rate of one process measured "
                 f"here ({_e(rate)} flop/s: the 20k blank's estimated flops over the paper "
                 "blank's measured time per factorization, 1 process, 1 thread; the two blanks "
                 "are about the same size), divided by the processes as if MUMPS scaled "
                 "perfectly, which it does not" if rate else "") + ".", "",
             row(["blank", "processes", "machines of 24 GB (2 processes each)",
                  "MB, largest MUMPS share", "MB, all MUMPS shares",
                  "MB, rank 0 (its share and the driver)",
                  "s per factorization (ideal)"]), row(["---"] * 7)]
    for label, e in estimates.items():
        driver_here = driver_mb * e["hexahedra"] / 20010 if driver_mb is not None else 0.0
        fits = [(int(n), s) for n, s in e["processes"].items()
                if s["estimated_memory_mb_max"] <= MEMORY_PER_PROCESS_MB]
        if not fits:
            most = max(map(int, e["processes"]))
            lines.append(row([label, f"more than {most}", "", "", "", "", ""]))
            continue
        n, s = min(fits, key=lambda f: f[0])
        rank0 = (f"{s['estimated_memory_mb_max'] + driver_here:.0f}" if driver_mb is not None
                 else "?")
        lines.append(row([label, n, (n + 1) // 2, s["estimated_memory_mb_max"],
                          s["estimated_memory_mb_total"], rank0,
                          _g(s["estimated_flops"] / rate / n) if rate else "?"]))
    lines += ["", "Rank 0 holds the driver besides its MUMPS share: the mesh, the state, the "
              "assembled coordinates, the contact search and the results. Its column adds "
              "the paper blank's measured driver memory (rank 0's peak over rank 1's on 2 "
              "processes"
              + (f", {driver_mb:.0f} MB for 20,010 hexahedra" if driver_mb is not None else "")
              + ") scaled with the hexahedra: an estimate. Beyond about 200 thousand "
              "hexahedra rank 0 outgrows a machine of this size while the MUMPS shares "
              "still fit: the centralized driver, not the factorization, sets the limit there, "
              "and a run needs a large-memory machine for rank 0 (or the assembly and input "
              "distributed, docs/mpi.md). The time column assumes perfect scaling: MUMPS's "
              "factorization of a sheet's tree scales well below that on many processes, and "
              "the centralized matrix is sent from rank 0 at every factorization."]
    return lines


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--rank-main"]:
        return rank_main(argv[1:])
    if argv[:1] == ["--analyse"]:
        return analyse_main(Path(argv[1]), Path(argv[2]), argv[3:4] == ["assembled"])
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--part", choices=("answers", "paper", "estimates"), action="append")
    parser.add_argument("--report", action="store_true", help="only write the report")
    parser.add_argument("--kept-only", action="store_true",
                        help="take the runs kept in benchmarks/mpi_scaling/results, run no more")
    args = parser.parse_args(argv)
    global KEPT_ONLY
    KEPT_ONLY = args.kept_only
    data = json.loads(JSON_FILE.read_text()) if JSON_FILE.exists() else {}
    if not args.report:
        for exe in (SEQ_PYTHON, MPI_PYTHON):
            if not exe.exists():
                parser.error(f"{exe} is missing: ./setup.sh and ./setup.sh --mpi build both")
        WORK.mkdir(parents=True, exist_ok=True)
        parts = args.part or ["answers", "paper", "estimates"]
        for part in parts:
            result = {"answers": part_answers, "paper": part_paper,
                      "estimates": part_estimates}[part]()
            # read again: another part may have been written meanwhile
            data = json.loads(JSON_FILE.read_text()) if JSON_FILE.exists() else {}
            data[part] = result
            data["code"] = bench_common.code_version()
            data["cores"] = bench_common.cores()
            JSON_FILE.write_text(json.dumps(data, indent=1) + "\n")
    REPORT.write_text(report(data) + "\n")
    print(REPORT)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
