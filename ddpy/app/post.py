"""Post-processing of results files: curves, tables and figures (``ddpy post``,
``ddpy compare``; docs/running.md).

The punch force against stroke uses each forming phase's lead tool (root attribute
``leads`` written by the runner): the stroke is the lead tool's displacement along its motion
in the phase, the force the component of its reaction against that motion. The model's
fraction of the part (full, half, quarter) comes from its symmetry planes (root attribute
``symmetry``); the full part's force is the model's times the number of copies.

The forming limit diagram compares each element's surface strains of the last frame with
the run's forming limit curve (docs/theory/forming_limits.md).
"""

from __future__ import annotations

import csv
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ddpy.io.results import LIMITS, Frame, ResultsReader
from ddpy.model.forming_limits import (
    FAILED,
    MARGINAL,
    MARGINAL_BAND,
    SAFE,
    FormingLimitCurve,
)
from ddpy.model.forming_quantities import SURFACES

__all__ = ["FormingLimitCheck", "IncrementPanels", "Run", "compare_runs", "find_results",
           "forming_limit_check", "forming_summary", "increment_panels", "load_run",
           "model_fraction", "post_run"]

#: The name of a model that is 1 / COPIES of the part.
FRACTION_NAMES = {1: "full", 2: "half", 4: "quarter", 8: "eighth"}


def model_fraction(symmetry: str | None) -> tuple[int | None, str]:
    """How many copies of the model make the full part, and the model's name, from the
    normal axis of each symmetry plane (``ResultsReader.symmetry``: "" a full model, "x" a
    half, "xy" a quarter). None copies when unknown: a file that does not record the
    planes, or two planes normal to one axis (a slice between them)."""
    if symmetry is None:
        return None, "model of unknown fraction (the results do not record its symmetry planes)"
    repeated = sorted({a for a in symmetry if symmetry.count(a) > 1})
    if repeated:
        return None, (f"slice between symmetry planes normal to {repeated[0]} (the full "
                      "part's force is unknown)")
    copies = 2 ** len(symmetry)
    planes = " and ".join(symmetry)
    if copies == 1:
        return 1, "full model"
    return copies, f"{FRACTION_NAMES[copies]} model (symmetry planes normal to {planes})"


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
    symmetry: str | None = None

    @property
    def fraction(self) -> tuple[int | None, str]:
        """Copies of the model in the full part and the model's name (model_fraction)."""
        return model_fraction(self.symmetry)

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
        leads = tuple(str(x) for x in r.attribute("leads", [""] * len(r.phases)))
        h = r.history()
        status = str(r.attribute("status", "unknown"))
        symmetry = r.symmetry
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
               h["time_total"], symmetry)


def _label(path: Path) -> str:
    return path.parent.name if path.name == "results.h5" else path.stem


# ----------------------------------------------------------------------------- tables


def phase_table(run: Run) -> list[dict[str, object]]:
    """One row per phase: increments, iterations, cutbacks, final stroke, largest force of
    the model and of the full part (empty when the model's fraction is unknown), wall
    time."""
    copies = run.fraction[0]
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
                     "max_force_full_part_N": ("" if copies is None
                                               else float(copies * run.force[sel].max())),
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


#: The iteration rows' columns of what switched (files written before them have none).
SWITCHES = ("points_switched", "pairs_switched", "yield_switched")


def iteration_rows(results: str | os.PathLike[str]) -> list[dict[str, object]]:
    """Per phase and per Newton iteration k of an increment (0: the start): the increments
    that reach it, the median relative residual there, the mean length of the step that
    led to it and the mean counts of what switched since the previous iterate (contact
    points, pairs, points between elastic and plastic), over the rows that recorded them.
    Where the iterations of a run go: a residual that falls slowly while the counts stay
    high is Newton finding the contact and plastic sets (docs/theory/speed.md)."""
    with ResultsReader(results) as r:
        it = r.iterations()
        phase = r.curve("phase").astype(int)
        phases = r.phases
    if it["increment"].size == 0:
        return []
    row_phase = phase[it["increment"] - 1]
    place = it["iteration"] - 1
    rows: list[dict[str, object]] = []
    for p in np.unique(row_phase):
        for k in range(int(place[row_phase == p].max()) + 1):
            sel = (row_phase == p) & (place == k)
            row: dict[str, object] = {
                "phase": phases[p] if p < len(phases) else str(p), "iteration": k,
                "increments": int(sel.sum()),
                "median_residual": float(np.median(it["residual_force"][sel]))}
            for name in ("step", *SWITCHES):
                values = it[name][sel] if name in it else np.zeros(0)
                values = values[values >= 0]  # -1: rows written before the column
                row[f"mean_{name}"] = float(values.mean()) if values.size else ""
            rows.append(row)
    return rows


# ----------------------------------------------------------------------------- figures


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _force_plot(runs: Sequence[Run], path: Path) -> Path:
    """The lead tool's force against its stroke. One run: the model's force and, for a
    symmetric model, the full part's (dashed); several runs: each run's full part's force
    (the model's where its fraction is unknown), so that models of different fractions
    compare."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    if len(runs) == 1:
        run = runs[0]
        sel = run.forming
        copies, name = run.fraction
        ax.plot(run.stroke[sel], run.force[sel], label=f"{name}, as computed")
        if copies is not None and copies > 1:
            ax.plot(run.stroke[sel], copies * run.force[sel], "--",
                    label=f"full part ({copies} x the {FRACTION_NAMES[copies]} model)")
        ax.set_ylabel("force on the lead tool (N)")
        ax.set_title(run.title, fontsize=9)
    else:
        for run in runs:
            sel = run.forming
            copies, name = run.fraction
            label = (f"{run.label}: full part ({copies} x)" if copies is not None
                     else f"{run.label}: {name}")
            ax.plot(run.stroke[sel], (copies or 1) * run.force[sel], label=label)
        ax.set_ylabel("force on the lead tool, full part (N)")
    ax.set_xlabel("stroke of the lead tool (mm)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


@dataclass(frozen=True)
class IncrementPanels:
    """What increments.png draws: each phase's span of increment numbers (name, first,
    last, whether it moves a lead tool), the increments that move a lead tool with their
    step (mm of lead travel: the log axis), the springback increments (no travel: drawn
    apart, on a strip of their own) and every increment's Newton iterations."""

    spans: tuple[tuple[str, int, int, bool], ...]
    forming_number: NDArray[np.int64]
    forming_step: NDArray[np.float64]
    springback_number: NDArray[np.int64]
    number: NDArray[np.int64]
    iterations: NDArray[np.int32]


def increment_panels(run: Run) -> IncrementPanels:
    """The data of increments.png (IncrementPanels)."""
    number = np.arange(1, len(run.phase) + 1)
    spans = []
    for p, name in enumerate(run.phases):
        rows = np.flatnonzero(run.phase == p)
        if rows.size:
            spans.append((name, int(number[rows[0]]), int(number[rows[-1]]),
                          bool(run.leads[p])))
    forming = run.forming
    return IncrementPanels(tuple(spans), number[forming], run.step[forming],
                           number[~forming], number, run.iterations)


def _increments_plot(run: Run, path: Path) -> Path:
    """increments.png: the step of each increment that moves a lead tool (log axis), the
    springback steps on a strip below it, and the Newton iterations; phases shaded and
    named inside the axes."""
    plt = _pyplot()
    from matplotlib.transforms import blended_transform_factory

    panels = increment_panels(run)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 5.2), sharex=True)
    if panels.forming_number.size:
        a1.semilogy(panels.forming_number, panels.forming_step, ".", markersize=3,
                    label="increment moving the lead tool")
        positive = panels.forming_step[panels.forming_step > 0]
        if positive.size:
            # Room above for the phase names and below for the springback strip.
            lo, hi = float(positive.min()), float(positive.max())
            decades = max(hi / lo, 10.0)
            a1.set_ylim(lo / decades**0.3, hi * decades**0.35)
    a1.set_ylabel("step (mm of lead travel)")
    a2.plot(panels.number, panels.iterations, ".", markersize=3)
    a2.set_ylabel("Newton iterations")
    a2.set_xlabel("increment")
    for k, (name, first, last, moves) in enumerate(panels.spans):
        for ax in (a1, a2):
            ax.axvspan(first - 0.5, last + 0.5, color="0.85" if k % 2 else "0.93", zorder=0)
        on_axes = blended_transform_factory(a1.transData, a1.transAxes)
        a1.text(0.5 * (first + last), 0.97, name + ("" if moves else "\n(no tool travel)"),
                transform=on_axes, ha="center", va="top", fontsize=8, clip_on=True)
    if panels.springback_number.size:
        # Springback steps move no tool: on their own strip at the foot of the axis, not
        # at a fake step on the log scale.
        on_foot = blended_transform_factory(a1.transData, a1.transAxes)
        a1.plot(panels.springback_number, np.full(panels.springback_number.size, 0.04), "s",
                color="C3", markersize=3, transform=on_foot, clip_on=False,
                label="springback step (no travel)")
        a1.legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 0.08))
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _blank_map(results: Path, path: Path, values: NDArray[np.float64], label: str,
               title: str, cmap: str = "viridis") -> Path:
    """The deformed blank of the last frame seen along its thinnest direction (from the
    side its normal points to: the top view of a flat sheet), boundary faces facing the
    viewer coloured by ``values`` (one per element, or one per node: a face takes the mean
    of its corners), the colourbar labelled ``label``."""
    from matplotlib.collections import PolyCollection

    from ddpy.model.mesh import HEX_FACES

    plt = _pyplot()
    with ResultsReader(results) as r:
        x = r.field("coordinates")
        elements = r.elements
    view = int(np.argmin(np.ptp(x, axis=0)))
    axes = [a for a in range(3) if a != view]
    faces = elements[:, HEX_FACES]                                     # (m, 6, 4)
    normal = np.cross(x[faces[..., 2]] - x[faces[..., 0]], x[faces[..., 3]] - x[faces[..., 1]])
    facing = normal[..., view] > 0.0
    owner = np.nonzero(facing)[0]
    face_values = (values[owner] if len(values) == len(elements)
                   else values[faces[facing]].mean(axis=1))
    polygons = x[faces[facing]][..., axes]
    depth = x[faces[facing]][..., view].mean(axis=1)
    order = np.argsort(depth)                                          # far to near
    # The figure takes the blank's aspect ratio (within 1:3 and 3:1): an equal-aspect plot
    # of a quarter disc in a wide, fixed frame left a third of the image empty.
    span = np.ptp(x[:, axes], axis=0)
    ratio = float(np.clip(span[0] / max(span[1], 1e-12), 1.0 / 3.0, 3.0))
    height = 3.8 if ratio >= 1.0 else 5.2
    fig, ax = plt.subplots(figsize=(min(height * ratio + 1.6, 9.0), height))
    collection = PolyCollection(polygons[order], array=face_values[order], cmap=cmap,
                                edgecolors="k", linewidths=0.2)
    ax.add_collection(collection)
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel(f"{'xyz'[axes[0]]} (mm)")
    ax.set_ylabel(f"{'xyz'[axes[1]]} (mm)")
    ax.set_title(title, fontsize=9)
    fig.colorbar(collection, ax=ax, shrink=0.8, label=label)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _frame_words(frame: Frame) -> str:
    return f"frame {frame.index} (increment {frame.increment})"


def _plastic_strain_map(results: Path, path: Path) -> Path:
    """plastic_strain.png: each element's equivalent plastic strain, last frame."""
    with ResultsReader(results) as r:
        ep, frame = r.field("plastic_strain"), r.frames[-1]
    return _blank_map(results, path, ep, "equivalent plastic strain (-, mean of the Gauss "
                      "points)", f"equivalent plastic strain, {_frame_words(frame)}")


def _thinning_map(results: Path, path: Path) -> Path | None:
    """thinning.png: each node's thinning in %, last frame; None for a blank without
    thickness (not meshed in layers)."""
    with ResultsReader(results) as r:
        fields, frame = r.frame(-1), r.frames[-1]
    if "thinning" not in fields:
        return None
    return _blank_map(results, path, fields["thinning"], "thinning 100 (t0 - t) / t0 (%)",
                      f"thinning, {_frame_words(frame)}", cmap="RdYlBu_r")


@dataclass(frozen=True)
class FormingLimitCheck:
    """Each element's strain point of the last frame against the forming limit curve: of
    the element's top, middle and bottom faces, the one closest to the curve (or furthest
    above it); its major and minor logarithmic strains, its margin below the curve (major
    strain; negative above it) and zone (SAFE, MARGINAL within ``band`` below the curve,
    FAILED on or above it)."""

    curve: FormingLimitCurve
    band: float
    frame: Frame
    element_ids: NDArray[np.int64]
    surface: NDArray[np.int64]
    major: NDArray[np.float64]
    minor: NDArray[np.float64]
    margin: NDArray[np.float64]
    zone: NDArray[np.int8]

    @property
    def worst(self) -> int:
        """The index of the element with the smallest margin."""
        return int(np.argmin(self.margin))


def forming_limit_check(results: str | os.PathLike[str], band: float = MARGINAL_BAND
                        ) -> FormingLimitCheck | str:
    """The forming limit check of a results file's last frame (FormingLimitCheck), or why
    there is none (a string)."""
    if not band >= 0:
        raise ValueError(f"the marginal band must be >= 0, got {band}")
    with ResultsReader(results) as r:
        curve = r.forming_limit()
        fields, frame, element_ids = r.frame(-1), r.frames[-1], r.element_ids
    if curve is None:
        return ("no forming limit curve in the results (a blank not meshed in layers, a "
                "hardening law without hardening, or results written before ddpy recorded "
                "it): give one with 'forming_limit table COUNT' in material.dat")
    names = [(f"major_strain_{s}", f"minor_strain_{s}") for s in SURFACES]
    if any(a not in fields or b not in fields for a, b in names):
        return "no surface strains in the results (a blank not meshed in layers)"
    major = np.stack([fields[a] for a, _ in names], axis=1)            # (m, 3)
    minor = np.stack([fields[b] for _, b in names], axis=1)
    margins = curve.margin(major, minor)
    surface = np.argmin(margins, axis=1)
    rows = np.arange(len(surface))
    major, minor = major[rows, surface], minor[rows, surface]
    return FormingLimitCheck(curve, band, frame, element_ids, surface, major, minor,
                             margins[rows, surface], curve.zone(major, minor, band))


_ZONES = ((SAFE, "safe", "tab:green"), (MARGINAL, "marginal", "orange"),
          (FAILED, "failed", "tab:red"))


def _fld_plot(check: FormingLimitCheck, path: Path) -> Path:
    """fld.png: every element's strain point coloured by its zone, the forming limit curve
    and the marginal band's lower edge."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 5.0))
    low = min(-0.3, float(check.minor.min()) * 1.1)
    high = max(0.3, float(check.minor.max()) * 1.1)
    e2 = np.linspace(low, high, 301)
    limit = check.curve.major_limit(e2)
    ax.plot(e2, limit, "k-", label="forming limit curve")
    ax.plot(e2, limit - check.band, "k--", linewidth=0.8,
            label=f"marginal band ({check.band:g} below)")
    for zone, name, colour in _ZONES:
        sel = check.zone == zone
        ax.scatter(check.minor[sel], check.major[sel], s=10, color=colour,
                   label=f"{name}: {int(sel.sum())} elements")
    ax.set_xlabel("minor strain (logarithmic, -)")
    ax.set_ylabel("major strain (logarithmic, -)")
    ax.set_ylim(bottom=min(0.0, float(check.major.min())),
                top=max(float(limit.max()), float(check.major.max())) * 1.1)
    ax.set_title(f"forming limit diagram, {_frame_words(check.frame)}\n"
                 f"{check.curve.describe()}", fontsize=8)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _fld_summary(check: FormingLimitCheck | str) -> str:
    """The forming limit section of summary.md."""
    lines = ["\n## Forming limit diagram\n"]
    if isinstance(check, str):
        return "\n".join(lines + [f"- {check}"]) + "\n"
    counts = ", ".join(f"{int((check.zone == z).sum())} {name}" for z, name, _ in _ZONES)
    k = check.worst
    zone = dict((z, name) for z, name, _ in _ZONES)[int(check.zone[k])]
    where = "below" if check.margin[k] > 0 else "above"
    lines += [f"- forming limit curve: {check.curve.describe()}",
              f"- marginal band: {check.band:g} in major strain below the curve",
              f"- elements ({_frame_words(check.frame)}, the most critical of each "
              f"element's top, middle and bottom faces): {counts}",
              f"- smallest margin to the forming limit curve: {check.margin[k]:.4g} "
              f"({abs(check.margin[k]):.4g} {where} the curve; element "
              f"{check.element_ids[k]}, {SURFACES[check.surface[k]]} face, major strain "
              f"{check.major[k]:.4g}, minor strain {check.minor[k]:.4g}): {zone}"]
    return "\n".join(lines) + "\n"


def post_run(target: str | os.PathLike[str], output: str | os.PathLike[str] | None = None,
             band: float = MARGINAL_BAND) -> list[Path]:
    """Figures and tables of one run into ``output`` (default: the results' folder):
    force_stroke.png, increments.png (increment size and iterations), contact.png (nodes in
    contact per tool), plastic_strain.png, thinning.png, fld.png (the forming limit
    diagram, marginal band ``band``), increments.csv, phases.csv, iterations.csv
    (iteration_rows) and summary.md."""
    run = load_run(target)
    check = forming_limit_check(run.path, band)
    out = Path(output) if output else run.path.parent
    out.mkdir(parents=True, exist_ok=True)
    plt = _pyplot()
    paths = [_force_plot([run], out / "force_stroke.png"),
             _increments_plot(run, out / "increments.png")]
    number = np.arange(1, len(run.phase) + 1)
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
    thinning = _thinning_map(run.path, out / "thinning.png")
    if thinning is not None:
        paths.append(thinning)
    if isinstance(check, FormingLimitCheck):
        paths.append(_fld_plot(check, out / "fld.png"))
    phases = phase_table(run)
    iterations = iteration_rows(run.path)
    paths.append(write_csv(out / "increments.csv", increment_rows(run)))
    paths.append(write_csv(out / "phases.csv", phases))
    paths.append(write_csv(out / "iterations.csv", iterations))
    copies, name = run.fraction
    summary = (f"# {run.title}\n\nResults: `{run.path}`, status {run.status}, "
               f"{len(run.phase)} increments; a {name}"
               + (f": the full part's force is {copies} x the model's" if copies and copies > 1
                  else "") + ".\n\n"
               + markdown(phases) + forming_summary(run) + _fld_summary(check)
               + "\n## Newton iterations by their place in an increment\n\n" + markdown(iterations))
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
        history = r.history()
        if "volume_change" in history and history["volume_change"].size:
            change = history["volume_change"]
            k = int(np.argmax(np.abs(change)))
            lines.append(f"- the blank's volume: {100 * change[-1]:+.3g} % at the end, "
                         f"{100 * change[k]:+.3g} % at most (increment {k + 1}); plastic flow "
                         "keeps it (docs/theory/solid_shell.md, \"Volume\")")
        if "penetration" in history and history["penetration"].size:
            depth = history["penetration"].max(axis=0)
            t0 = r.field("thickness", 0).max() if "thickness" in last else 0.0
            deepest = ", ".join(
                f"{name} {d:.3g} mm" + (f" ({100 * d / t0:.2g} % of the thickness)"
                                        if t0 > 0 else "")
                for name, d in zip(r.attribute("tools"), depth, strict=True))
            lines.append(f"- deepest in a tool over the run: {deepest}")
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
