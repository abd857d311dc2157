"""Post-processing of results files: curves, tables and figures (``ddpy post``,
``ddpy compare``; docs/running.md).

The punch force against stroke uses each forming phase's lead tool (root attribute
``leads`` written by the runner): the stroke is the lead tool's displacement along its motion
in the phase, the force the component of its reaction against that motion.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy.io.results import LIMITS, ResultsReader

__all__ = ["Run", "compare_runs", "find_results", "forming_summary", "load_run", "post_run"]


@dataclass(frozen=True)
class Run:
    """The curves of one results file: per increment, the phase, the lead tool's stroke
    (mm, accumulated over forming phases) and force (N), the step, iterations, cutbacks, the
    limit, nodes in contact (per tool) and wall time; plus status and title."""

    path: Path
    label: str
    title: str
    status: str
    tools: tuple[str, ...]
    phases: tuple[str, ...]
    leads: tuple[str, ...]
    phase: NDArray[np.int32]
    stroke: NDArray[np.float64]
    force: NDArray[np.float64]
    step: NDArray[np.float64]
    iterations: NDArray[np.int32]
    cutbacks: NDArray[np.int32]
    limit: NDArray[np.int8]
    contact: NDArray[np.int32]
    time: NDArray[np.float64]

    @property
    def forming(self) -> NDArray[np.bool_]:
        """Rows of forming phases (a lead tool)."""
        return np.array([bool(self.leads[p]) for p in self.phase], dtype=bool)


def find_results(target: str | os.PathLike[str]) -> Path:
    """The results file of ``target``: a results file, an output folder holding
    results.h5, or a case folder whose default output (results/<name>) holds one."""
    from ddpy.app.runner import RESULTS, default_output

    path = Path(target)
    candidates = [path] if path.is_file() else [path / RESULTS,
                                                 default_output(path) / RESULTS]
    for c in candidates:
        if c.is_file():
            return c
    raise FileNotFoundError(f"{target}: no results found (looked for "
                            f"{', '.join(str(c) for c in candidates)})")


def load_run(target: str | os.PathLike[str], label: str | None = None) -> Run:
    """Read the curves of a results file (see find_results)."""
    path = find_results(target)
    with ResultsReader(path) as r:
        attrs = r._file.attrs
        leads = tuple(str(x) for x in attrs.get("leads", [""] * len(r.phases)))
        h = r.history()
        status = str(attrs.get("status", "unknown"))
    k = len(h["phase"])
    phase = h["phase"].astype(np.int32)
    stroke, force = np.zeros(k), np.zeros(k)
    offset = 0.0
    for p, lead in enumerate(leads):
        rows = np.flatnonzero(phase == p)
        if not lead or rows.size == 0:
            continue
        t = r.tools.index(lead)
        u, f = h["tool_displacement"][rows, t], h["tool_force"][rows, t]
        before = h["tool_displacement"][rows[0] - 1, t] if rows[0] > 0 else np.zeros(3)
        moved = u[-1] - before
        direction = moved / max(float(np.linalg.norm(moved)), 1e-300)
        stroke[rows] = offset + (u - before) @ direction
        force[rows] = -(f @ direction)
        offset = float(stroke[rows[-1]])
    return Run(path, label or _label(path), r.title, status, r.tools, r.phases, leads, phase,
               stroke, force, h["step"], h["iterations"].astype(np.int32),
               h["cutbacks"].astype(np.int32), h["limit"], h["nodes_in_contact"],
               h["time_total"])


def _label(path: Path) -> str:
    return path.parent.name if path.name == "results.h5" else path.stem


# ----------------------------------------------------------------------------- tables


def phase_table(run: Run) -> list[dict[str, object]]:
    """One row per phase: increments, iterations, cutbacks, final stroke, largest force,
    wall time."""
    rows = []
    for p, name in enumerate(run.phases):
        sel = run.phase == p
        if not sel.any():
            continue
        rows.append({"phase": name, "lead": run.leads[p] or "-",
                     "increments": int(sel.sum()), "iterations": int(run.iterations[sel].sum()),
                     "cutbacks": int(run.cutbacks[sel].sum()),
                     "stroke_mm": float(run.stroke[sel][-1]),
                     "max_force_N": float(run.force[sel].max()),
                     "time_s": float(run.time[sel].sum())})
    return rows


def write_csv(path: Path, rows: Sequence[dict[str, object]]) -> Path:
    with open(path, "w", newline="") as out:
        writer = csv.DictWriter(out, fieldnames=list(rows[0]) if rows else ["empty"])
        writer.writeheader()
        writer.writerows(rows)
    return path


def markdown(rows: Sequence[dict[str, object]]) -> str:
    """A markdown table of rows (dicts with the same keys)."""
    if not rows:
        return "(no increments)\n"
    keys = list(rows[0])

    def cell(value: object) -> str:
        return f"{value:.6g}" if isinstance(value, float) else str(value)

    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(cell(r[k]) for k in keys) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def increment_rows(run: Run) -> list[dict[str, object]]:
    rows = []
    for i in range(len(run.phase)):
        row: dict[str, object] = {
            "increment": i + 1, "phase": run.phases[run.phase[i]], "stroke_mm": run.stroke[i],
            "force_N": run.force[i], "step_mm": run.step[i],
            "iterations": int(run.iterations[i]), "cutbacks": int(run.cutbacks[i]),
            "limit": LIMITS.get(int(run.limit[i]), str(run.limit[i]))}
        for t, name in enumerate(run.tools):
            row[f"contact_{name}"] = int(run.contact[i, t])
        row["time_s"] = run.time[i]
        rows.append(row)
    return rows


# ----------------------------------------------------------------------------- figures


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _force_plot(runs: Sequence[Run], path: Path) -> Path:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for run in runs:
        sel = run.forming
        ax.plot(run.stroke[sel], run.force[sel], label=run.label)
    ax.set_xlabel("stroke of the lead tool (mm)")
    ax.set_ylabel("force on the lead tool (N)")
    ax.grid(True, alpha=0.3)
    if len(runs) > 1:
        ax.legend()
    else:
        ax.set_title(runs[0].title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _plastic_strain_map(results: Path, path: Path) -> Path:
    """The deformed blank of the last frame seen along its thinnest direction, boundary faces
    facing the viewer coloured by the equivalent plastic strain of their element."""
    from matplotlib.collections import PolyCollection

    from ddpy.model.mesh import HEX_FACES

    plt = _pyplot()
    with ResultsReader(results) as r:
        x = r.field("coordinates")
        ep = r.field("plastic_strain")
        elements = r.elements
        frame = r.frames[-1]
    view = int(np.argmin(np.ptp(x, axis=0)))
    axes = [a for a in range(3) if a != view]
    faces = elements[:, HEX_FACES]                                     # (m, 6, 4)
    normal = np.cross(x[faces[..., 2]] - x[faces[..., 0]], x[faces[..., 3]] - x[faces[..., 1]])
    facing = normal[..., view] > 0.0
    owner = np.nonzero(facing)[0]
    polygons = x[faces[facing]][..., axes]
    depth = x[faces[facing]][..., view].mean(axis=1)
    order = np.argsort(depth)                                          # far to near
    # The figure takes the blank's aspect ratio (within 1:3 and 3:1): an equal-aspect plot
    # of a quarter disc in a wide, fixed frame left a third of the image empty.
    span = np.ptp(x[:, axes], axis=0)
    ratio = float(np.clip(span[0] / max(span[1], 1e-12), 1.0 / 3.0, 3.0))
    height = 3.8 if ratio >= 1.0 else 5.2
    fig, ax = plt.subplots(figsize=(min(height * ratio + 1.6, 9.0), height))
    collection = PolyCollection(polygons[order], array=ep[owner][order], cmap="viridis",
                                edgecolors="k", linewidths=0.2)
    ax.add_collection(collection)
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel(f"{'xyz'[axes[0]]} (mm)")
    ax.set_ylabel(f"{'xyz'[axes[1]]} (mm)")
    ax.set_title(f"equivalent plastic strain, frame {frame.index} (increment "
                 f"{frame.increment})", fontsize=9)
    fig.colorbar(collection, ax=ax, shrink=0.8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def post_run(target: str | os.PathLike[str], output: str | os.PathLike[str] | None = None
             ) -> list[Path]:
    """Figures and tables of one run into ``output`` (default: the results' folder):
    force_stroke.png, increments.png (increment size and iterations), contact.png (nodes in
    contact per tool), plastic_strain.png, increments.csv, phases.csv and summary.md."""
    run = load_run(target)
    out = Path(output) if output else run.path.parent
    out.mkdir(parents=True, exist_ok=True)
    plt = _pyplot()
    paths = [_force_plot([run], out / "force_stroke.png")]
    number = np.arange(1, len(run.phase) + 1)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 5.2), sharex=True)
    a1.semilogy(number, np.maximum(run.step, 1e-12), ".", markersize=3)
    a1.set_ylabel("increment size (mm of lead travel)")
    a2.plot(number, run.iterations, ".", markersize=3)
    a2.set_ylabel("Newton iterations")
    a2.set_xlabel("increment")
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "increments.png", dpi=120)
    plt.close(fig)
    paths.append(out / "increments.png")
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for t, name in enumerate(run.tools):
        ax.plot(number, run.contact[:, t], label=name)
    ax.set_xlabel("increment")
    ax.set_ylabel("nodes in contact")
    ax.legend()
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "contact.png", dpi=120)
    plt.close(fig)
    paths.append(out / "contact.png")
    paths.append(_plastic_strain_map(run.path, out / "plastic_strain.png"))
    phases = phase_table(run)
    paths.append(write_csv(out / "increments.csv", increment_rows(run)))
    paths.append(write_csv(out / "phases.csv", phases))
    summary = (f"# {run.title}\n\nResults: `{run.path}`, status {run.status}, "
               f"{len(run.phase)} increments.\n\n" + markdown(phases)
               + forming_summary(run))
    (out / "summary.md").write_text(summary)
    paths.append(out / "summary.md")
    return paths


def forming_summary(run: Run) -> str:
    """The forming quantities of summary.md (docs/running.md): at the last frame the
    largest equivalent plastic strain, the thinnest node and the largest thinning, each
    with its label; and, when the run has a springback phase with a frame before it and
    one at its end, the largest displacement of a node over the springback. Empty for a
    run without frames past the initial state."""
    with ResultsReader(run.path) as r:
        frames = r.frames
        if len(frames) < 2:
            return ""
        last = r.frame(-1)
        node_ids, element_ids = r.node_ids, r.element_ids
        lines = [f"\n## Forming quantities (frame {frames[-1].index}, increment "
                 f"{frames[-1].increment})\n"]
        ep = last["plastic_strain"]
        e = int(np.argmax(ep))
        lines.append(f"- largest equivalent plastic strain: {ep[e]:.4g} (element "
                     f"{element_ids[e]}, mean of its Gauss points)")
        if "plastic_strain_nodal" in last:
            nodal = last["plastic_strain_nodal"]
            k = int(np.argmax(nodal))
            lines.append(f"- largest nodal equivalent plastic strain: {nodal[k]:.4g} (node "
                         f"{node_ids[k]})")
        if "thickness" in last:
            t, t0 = last["thickness"], r.field("thickness", 0)
            k = int(np.argmin(t))
            lines.append(f"- smallest thickness: {t[k]:.4g} mm (node {node_ids[k]}; "
                         f"{t0[k]:.4g} mm at the start)")
            thinning = last.get("thinning")
            if thinning is None:  # (files written before thinning was)
                thinning = np.divide(100.0 * (t0 - t), t0, out=np.zeros_like(t0),
                                     where=t0 > 0)
            k = int(np.argmax(thinning))
            lines.append(f"- largest thinning: {thinning[k]:.3g} % (node {node_ids[k]})")
        springback = [p for p, lead in enumerate(run.leads) if not lead]
        for p in springback:
            after = [f for f in frames if f.phase == p and f.increment > 0]
            before = [f for f in frames if f.phase < p]
            if not after or not before:
                continue
            moved = np.linalg.norm(r.field("displacement", after[-1].index)
                                   - r.field("displacement", before[-1].index), axis=1)
            k = int(np.argmax(moved))
            lines.append(f"- springback ({run.phases[p]}), largest displacement of a node: "
                         f"{moved[k]:.4g} mm (node {node_ids[k]}), from frame "
                         f"{before[-1].index} to frame {after[-1].index}")
    return "\n".join(lines) + "\n"


def compare_runs(targets: Sequence[str | os.PathLike[str]],
                 output: str | os.PathLike[str], labels: Sequence[str] | None = None
                 ) -> tuple[list[Path], str]:
    """Overlay the force-stroke curves of several runs (compare_force.png) and tabulate
    increments, iterations, cutbacks, largest force and wall time (compare.csv,
    compare.md). Returns the files and the markdown table."""
    if labels is not None and len(labels) != len(targets):
        raise ValueError(f"{len(labels)} labels for {len(targets)} runs")
    runs = [load_run(t, None if labels is None else labels[i]) for i, t in enumerate(targets)]
    out = Path(output)
    out.mkdir(parents=True, exist_ok=True)
    rows = [{"run": r.label, "status": r.status, "increments": len(r.phase),
             "iterations": int(r.iterations.sum()), "cutbacks": int(r.cutbacks.sum()),
             "final_stroke_mm": float(r.stroke[r.forming][-1]) if r.forming.any() else 0.0,
             "max_force_N": float(r.force.max()) if len(r.force) else 0.0,
             "time_s": float(r.time.sum())} for r in runs]
    table = markdown(rows)
    (out / "compare.md").write_text(table)
    paths = [_force_plot(runs, out / "compare_force.png"), write_csv(out / "compare.csv", rows),
             out / "compare.md"]
    return paths, table
