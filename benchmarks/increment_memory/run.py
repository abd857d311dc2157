"""Benchmark: a forming run's peak memory against its number of increments.

The first forming phase of a case (default: the built-in cylindrical bending, ``ddpy run``'s
default, 732 nodes) is run by ``FormingProblem.run`` as the runner runs it (the case's
constraints, tools, motion, Newton settings and increment limits; one segment, no output),
stopped after each of ``--increments`` increments, each in a fresh process on one thread,
with ``tracemalloc`` (what Python and numpy allocate) started once the problem is built. It
prints the traced peak per stop and what is still held at its end, the run's result alive.
A run that keeps per increment only the small records (the factor, the tools' forces, the
residual norms) and the last increment's fields holds about the same memory whatever its
length; one that keeps a copy of the displacements and contact states per increment grows
by them at each.

    python benchmarks/increment_memory/run.py [--case FOLDER_OR_NAME] [--increments 20 245]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tracemalloc

from ddpy.model.forming import PhaseProgress


def measure(case: str, increments: int) -> tuple[float, float, int]:
    """The traced peak (MB) of the first ``increments`` increments of ``case``'s first
    forming phase, what is still held at their end with the run's result (MB), and the
    increments made."""
    from ddpy.app.runner import build_problem, case_folder
    from ddpy.core.parallel import set_threads
    from ddpy.io.case import Move
    from ddpy.io.decks import read_case

    set_threads(1)
    loaded = read_case(case_folder(case))
    phase = next(p for p in loaded.phases if not p.is_springback)
    problem = build_problem(loaded)
    nodes, components = loaded.boundary.constrained(phase.name)
    for c in range(3):
        if (components == c).any():
            problem.fix(nodes[components == c], c)
    motion = {m.tool: phase.displacement(m.tool) for m in phase.motions if isinstance(m, Move)}
    made = [0]

    def stop(progress: PhaseProgress) -> bool:
        made[0] = progress.increment
        return progress.increment >= increments

    tracemalloc.start()
    result = problem.run(motion, phase.max_increment, active=phase.tools,
                         newton=phase.newton, limits=phase.limits, on_increment=stop,
                         frames=False)
    kept, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    del result
    problem.close()
    return peak / 1e6, kept / 1e6, made[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="cylindrical-bending")
    parser.add_argument("--increments", type=int, nargs="+", default=[20, 245])
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        peak, kept, made = measure(args.case, args.increments[0])
        print(f"{made} {peak:.6f} {kept:.6f}")
        return
    print("| increments | traced peak (MB) | held at the end (MB) |\n|---:|---:|---:|")
    for n in args.increments:
        out = subprocess.run([sys.executable, __file__, "--child", "--case", args.case,
                              "--increments", str(n)], check=True, capture_output=True,
                             text=True, env={**os.environ, "OMP_NUM_THREADS": "1"}).stdout
        made, peak, kept = out.split()[-3:]
        print(f"| {made} | {float(peak):.2f} | {float(kept):.2f} |", flush=True)


if __name__ == "__main__":
    main()
