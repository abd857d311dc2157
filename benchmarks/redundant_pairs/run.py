"""A node held by two tools at once: a strip between a flat die and a flat holder pressed
with a force, friction on both, pushed along the die by a frictionless stop whose nodes are
also the die's and the holder's (docs/theory/contact.md, "Redundant pairs"). Where such a
node sticks, two laws hold one direction of it and the Jacobian is singular in their
multipliers; the sweep over friction and holder force says in how many cases the first
increment converges, and the pull force against Coulomb's 2 mu F.

    python benchmarks/redundant_pairs/run.py     # 16 runs, about a minute on one thread

Writes docs/benchmarks/redundant_pairs.md. The rounding of the BLAS kernel decides how a
singular factorization fails; run it under OPENBLAS_CORETYPE=Haswell too to see another.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from ddpy.geometry.surfaces import NagataSurface
from ddpy.model.forming import FormingError, FormingProblem, RigidTool
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
from bench_common import DOCS, code_version, computed_at, table_row  # noqa: E402

FRICTIONS = (0.05, 0.1, 0.2, 0.3)
FORCES = (200.0, 500.0, 1000.0, 2000.0)
#: Mild steel, elastic under these loads (initial yield 199 MPa).
STEEL = Material(210e3, 0.3, Hill48.von_mises(), Swift(500.0, 0.01, 0.2))


def plane(corners: list[list[float]], normal: list[float]) -> NagataSurface:
    """One flat quadrilateral patch with the corners' normal."""
    return NagataSurface(corners, [normal] * 4, [[0, 1, 2, 3]])


def pushed_strip(mu: float, force: float) -> tuple[dict[str, float], float]:
    """The 10 x 1 x 1 mm strip pushed 1 mm (increments of at most 0.25 mm): its counts, and
    the stop's force over 2 mu F."""
    mesh = HexMesh.box(10.0, 1.0, 1.0, 10, 1, 1)
    die = plane([[-20, -5, 0], [40, -5, 0], [40, 5, 0], [-20, 5, 0]], [0, 0, 1])
    holder = plane([[-20, -5, 1], [-20, 5, 1], [40, 5, 1], [40, -5, 1]], [0, 0, -1])
    stop = plane([[0, -5, -5], [0, 5, -5], [0, 5, 5], [0, -5, 5]], [1, 0, 0])
    tools = [RigidTool("die", die, mesh.select(z=0.0), friction=mu, facing=(0, 0, -1),
                       contact="node"),
             RigidTool("holder", holder, mesh.select(z=1.0), friction=mu, facing=(0, 0, 1)),
             RigidTool("stop", stop, mesh.select(x=0.0), facing=(-1, 0, 0), contact="node")]
    problem = FormingProblem(Solid(mesh, STEEL), tools)
    problem.fix(np.arange(mesh.n_nodes), "y")
    result = problem.run({"stop": (1.0, 0, 0)}, max_increment=0.25, forces={"holder": force})
    pull = -result.tool_forces["stop"][-1][0]
    return {"increments": len(result.factors), "iterations": result.newton_iterations,
            "cuts": result.cuts}, pull / (2.0 * mu * force)


def main() -> None:
    rows, converged = [], 0
    for mu in FRICTIONS:
        for force in FORCES:
            try:
                counts, ratio = pushed_strip(mu, force)
            except FormingError as error:
                rows.append(table_row([mu, f"{force:g}", "no", "", "", "", "", str(error)[:90]]))
                continue
            converged += 1
            rows.append(table_row([mu, f"{force:g}", "yes", counts["increments"],
                                   counts["iterations"], counts["cuts"], f"{ratio:.6f}", ""]))
    kernel = os.environ.get("OPENBLAS_CORETYPE", "") or "OpenBLAS's choice for this CPU"
    text = [
        "# A node held by two tools at once (redundant pairs)",
        "",
        computed_at(code_version()),
        "",
        "Written by `benchmarks/redundant_pairs/run.py`. A 10 x 1 x 1 mm steel strip (10 "
        "elements) between a flat die (node-to-surface) and a flat holder (Gauss-point "
        "contact) pressed with F, friction mu on both, pushed 1 mm along the die by a "
        "frictionless stop (node-to-surface) in increments of at most 0.25 mm. The stop's "
        "slave nodes are the die's and the holder's too: where one sticks on the die, two "
        "laws hold its x motion (docs/theory/contact.md, \"Redundant pairs\"). Once the "
        f"strip slides, the stop carries 2 mu F. BLAS kernel: {kernel}.",
        "",
        f"**{converged} of {len(FRICTIONS) * len(FORCES)} runs converge.**",
        "",
        table_row(["mu", "F (N)", "converged", "increments", "Newton iterations", "cuts",
                   "pull / (2 mu F)", "error"]),
        table_row(["---"] * 8),
        *rows,
        "",
    ]
    out = DOCS / "redundant_pairs.md"
    out.write_text("\n".join(text))
    print(f"{converged} of {len(FRICTIONS) * len(FORCES)} converge; wrote {out}")


if __name__ == "__main__":
    main()
