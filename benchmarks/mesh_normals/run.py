"""Vertex normals estimated from tool meshes, and the Nagata patches built on them.

The 3D counterpart of the arc study (docs/benchmarks/arc_accuracy.md, paper Fig. 3 and 4):
exact surfaces (a cylinder, a sphere cap, a torus band, a saddle) meshed at four sizes,
structured, perturbed and unstructured, in quadrilaterals and triangles
(``ddpy.studies.normal_accuracy``), and the plane-fillet-cylinder die of the tool-model
benchmark meshed from its CAD. For each mesh: the normal error of every estimator of
``ddpy.geometry.mesh_normals``, and the shape error of Nagata patches with the estimated
normals, with the exact normals, and of the flat facets; convergence orders fitted on the
three finest meshes. Also the largest angle between neighbouring faces of the smooth
surfaces (what the crease angle must stay above).

    python benchmarks/mesh_normals/run.py            # writes docs/benchmarks/mesh_normals.md
    python benchmarks/mesh_normals/run.py --json     # prints the numbers only
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ddpy.geometry.mesh_normals import (
    DEFAULT_CREASE_ANGLE,
    DEFAULT_ESTIMATOR,
    ESTIMATORS,
    estimate_normals,
)
from ddpy.studies.normal_accuracy import (
    MESH_KINDS,
    SURFACES,
    angle_between,
    fit_order,
    make_mesh,
    normal_errors,
    shape_errors,
)

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "benchmarks"
sys.path.insert(0, str(ROOT / "benchmarks"))  # the benchmarks' shared module
from bench_common import code_version, computed_at, table_row  # noqa: E402

#: Elements per 90 degrees of the smallest radius of curvature.
LEVELS = (4, 8, 16, 32)
#: Orders are fitted on the finest meshes.
FIT = 3
MODELS = {"nagata_estimated": "Nagata, estimated normals", "nagata_exact": "Nagata, exact normals",
          "facets": "facets"}


def study_surfaces() -> dict[str, Any]:
    """Normal and shape errors on the exact surfaces: {surface: {kind: {...}}}."""
    result: dict[str, Any] = {}
    for name, make in SURFACES.items():
        surface = make()
        result[name] = {"description": surface.description, "radius": surface.radius}
        for kind in MESH_KINDS:
            row: dict[str, Any] = {"h": [], "vertices": [], "dihedral_max": [],
                                   "normal_max": {e: [] for e in ESTIMATORS},
                                   "normal_rms": {e: [] for e in ESTIMATORS},
                                   "shape_max": {m: [] for m in MODELS}, "creases": []}
            for n in LEVELS:
                mesh = make_mesh(surface, kind, n)
                row["h"].append(mesh.mean_edge)
                row["vertices"].append(len(mesh.vertices))
                found = estimate_normals(mesh.vertices, mesh.faces, "max")
                row["dihedral_max"].append(float(np.nanmax(found.dihedral)))
                for estimator in ESTIMATORS:
                    error, corners, creases = normal_errors(mesh, estimator)
                    row["normal_max"][estimator].append(float(error.max()))
                    row["normal_rms"][estimator].append(float(np.sqrt((error ** 2).mean())))
                    if estimator == DEFAULT_ESTIMATOR:
                        row["creases"].append(creases)
                        estimated = corners
                for model in MODELS:
                    d = shape_errors(mesh, estimated if model == "nagata_estimated" else None,
                                     smooth=model != "facets")
                    row["shape_max"][model].append(float(np.abs(d).max()))
            result[name][kind] = row
    return result


def study_die() -> dict[str, Any]:
    """The plane-fillet-cylinder die meshed from its CAD (quadrilaterals, structured on its
    faces): estimated against CAD normals, and the shape errors against the CAD."""
    from ddpy.cad.examples import die_profile

    return study_cad(lambda: {"die": die_profile()}, {"die": (0.0, 0.0, 1.0)},
                     {"die": 4.0}, LEVELS, ESTIMATORS)["die"]


#: The forming benchmarks' tools (their CAD models, ddpy.cad.examples): the side the blank
#: lies on, and the smallest radius of each (mm), which sets its mesh.
BENCHMARK_TOOLS = {
    "bending punch": ("bending", "punch", (0.0, 0.0, -1.0), 23.5),
    "bending die": ("bending", "die", (0.0, 0.0, 1.0), 4.0),
    "drawing die 1": ("drawing", "die1", (0.0, 0.0, 1.0), 8.0),
    "drawing punch 1": ("drawing", "punch1", (0.0, 0.0, -1.0), 4.0),
    "drawing punch 2": ("drawing", "punch2", (0.0, 0.0, 1.0), 5.0),
}
#: Levels of the benchmark tools (the deep drawing tools at 32 per 90 degrees of their
#: smallest radius have hundreds of thousands of elements).
TOOL_LEVELS = (4, 8, 16)


def study_tools() -> dict[str, Any]:
    """The bending and deep drawing tools meshed from their CAD: the default estimator's
    normal errors and the shape errors, {tool: row}."""
    from ddpy.cad.examples import bending_tools, reverse_drawing_tools

    makers = {"bending": bending_tools, "drawing": reverse_drawing_tools}
    out: dict[str, Any] = {}
    for model, make in makers.items():
        tools = {name: spec for name, spec in BENCHMARK_TOOLS.items() if spec[0] == model}
        def faces(make=make, tools=tools) -> dict[str, list[int]]:
            made = make()
            return {name: made[spec[1]] for name, spec in tools.items()}

        rows = study_cad(faces,
            {name: spec[2] for name, spec in tools.items()},
            {name: spec[3] for name, spec in tools.items()}, TOOL_LEVELS,
            (DEFAULT_ESTIMATOR,))
        out.update(rows)
    return out


def study_cad(make, sides: dict[str, tuple[float, float, float]],
              radii: dict[str, float], levels: tuple[int, ...],
              estimators: tuple[str, ...]) -> dict[str, Any]:
    """Tools of one CAD model (``make`` builds it in the gmsh session and returns the faces
    of each tool) meshed at ``levels`` elements per 90 degrees of their smallest radius
    (structured quadrilaterals, edges of at most that length on the straight faces):
    ``estimators``' normals against the CAD's, and the shape errors against the CAD."""
    from ddpy.cad import ToolBuilder, gmsh_session
    from ddpy.cad.shape_error import shape_error
    from ddpy.geometry.surfaces import NagataSurface
    from ddpy.io.toolfile import ToolModel

    out: dict[str, Any] = {}
    with gmsh_session():
        import gmsh

        gmsh.model.add("tools")
        faces = make()
        for name, tool_faces in faces.items():
            row: dict[str, Any] = {"h": [], "vertices": [],
                                   "normal_max": {e: [] for e in estimators},
                                   "normal_rms": {e: [] for e in estimators},
                                   "shape_max": {m: [] for m in MODELS}, "creases": []}
            builder = ToolBuilder(tool_faces, name, blank_side=sides[name])
            for n in levels:
                mesh = builder.mesh(n, "quad", size=np.pi / 2 * radii[name] / n)
                c = np.where(mesh.elements < 0, mesh.elements[:, :1], mesh.elements)
                edge = np.linalg.norm(mesh.vertices[c] - mesh.vertices[np.roll(c, -1, axis=1)],
                                      axis=2)
                row["h"].append(float(edge.mean()))
                row["vertices"].append(len(mesh.vertices))
                exact = mesh.corner_normals
                valid = np.ones(c.shape, dtype=bool)
                valid[:, 3] = mesh.elements[:, 3] >= 0
                for estimator in estimators:
                    found = estimate_normals(mesh.vertices, mesh.elements, estimator)
                    error = angle_between(found.corner_normals, exact)[valid]
                    row["normal_max"][estimator].append(float(error.max()))
                    row["normal_rms"][estimator].append(float(np.sqrt((error ** 2).mean())))
                    if estimator == DEFAULT_ESTIMATOR:
                        estimated = found.corner_normals
                        row["creases"].append(int(found.crease.sum()))
                for model in MODELS:
                    normals = estimated if model == "nagata_estimated" else exact
                    surface = NagataSurface(mesh.vertices, normals, mesh.elements,
                                            smooth=model != "facets")
                    tool = ToolModel(name.replace(" ", "_"),
                                     "nagata" if model != "facets" else "facets",
                                     surface, mesh.element_face)
                    row["shape_max"][model].append(shape_error(tool, samples=5).max_distance)
            out[name] = row
        gmsh.model.remove()
    return out


def _orders(row: dict[str, Any], key: str) -> dict[str, float]:
    h = np.array(row["h"][-FIT:])
    return {k: fit_order(h, np.array(v[-FIT:])) for k, v in row[key].items()}


def summary(result: dict[str, Any]) -> dict[str, Any]:
    """Finest-level errors and orders per surface, mesh kind, estimator and model."""
    out: dict[str, Any] = {}
    for name, rows in result["surfaces"].items():
        out[name] = {}
        for kind in MESH_KINDS:
            row = rows[kind]
            out[name][kind] = {
                "normal_max_deg": {e: v[-1] for e, v in row["normal_max"].items()},
                "normal_max_order": _orders(row, "normal_max"),
                "normal_rms_deg": {e: v[-1] for e, v in row["normal_rms"].items()},
                "normal_rms_order": _orders(row, "normal_rms"),
                "shape_max_mm": {m: v[-1] for m, v in row["shape_max"].items()},
                "shape_max_order": _orders(row, "shape_max"),
            }
    die = result["die"]
    out["die"] = {"normal_max_deg": {e: v[-1] for e, v in die["normal_max"].items()},
                  "normal_max_order": _orders(die, "normal_max"),
                  "shape_max_mm": {m: v[-1] for m, v in die["shape_max"].items()},
                  "shape_max_order": _orders(die, "shape_max")}
    out["tools"] = {name: {"normal_max_deg": row["normal_max"][DEFAULT_ESTIMATOR][-1],
                           "normal_max_order": _orders(row, "normal_max")[DEFAULT_ESTIMATOR],
                           "shape_max_mm": {m: v[-1] for m, v in row["shape_max"].items()},
                           "shape_max_order": _orders(row, "shape_max")}
                    for name, row in result["tools"].items()}
    return out


def tools_table(tools: dict[str, Any]) -> str:
    """The benchmark tools at their finest level: normal and shape errors with orders."""
    lines = [table_row(["tool", "smallest radius [mm]", "vertices",
                        f"{DEFAULT_ESTIMATOR} max normal error [deg]", "RMS [deg]",
                        *[f"{label} max [mm]" for label in MODELS.values()]]),
             table_row(["---"] + ["---:"] * (4 + len(MODELS)))]
    for name, row in tools.items():
        normal = _orders(row, "normal_max")[DEFAULT_ESTIMATOR]
        rms = _orders(row, "normal_rms")[DEFAULT_ESTIMATOR]
        shape = _orders(row, "shape_max")
        lines.append(table_row(
            [name, f"{BENCHMARK_TOOLS[name][3]:g}", row["vertices"][-1],
             _cell(row["normal_max"][DEFAULT_ESTIMATOR][-1], normal),
             _cell(row["normal_rms"][DEFAULT_ESTIMATOR][-1], rms),
             *[_cell(row["shape_max"][m][-1], shape[m]) for m in MODELS]]))
    return "\n".join(lines)


# ------------------------------------------------------------------------------- report


def _cell(value: float, order: float) -> str:
    return f"{value:.3g} ({order:.2f})"


def normal_table(rows: dict[str, Any], key: str) -> str:
    lines = [table_row(["estimator", *MESH_KINDS]),
             table_row(["---"] + ["---:"] * len(MESH_KINDS))]
    for estimator in ESTIMATORS:
        cells = []
        for kind in MESH_KINDS:
            row = rows[kind]
            cells.append(_cell(row[key][estimator][-1], _orders(row, key)[estimator]))
        label = f"**{estimator}**" if estimator == DEFAULT_ESTIMATOR else estimator
        lines.append(table_row([label, *cells]))
    return "\n".join(lines)


def shape_table(rows: dict[str, Any]) -> str:
    lines = [table_row(["model", *MESH_KINDS]),
             table_row(["---"] + ["---:"] * len(MESH_KINDS))]
    for model, label in MODELS.items():
        cells = [_cell(rows[kind]["shape_max"][model][-1], _orders(rows[kind], "shape_max")[model])
                 for kind in MESH_KINDS]
        lines.append(table_row([label, *cells]))
    return "\n".join(lines)


def refinement_table(row: dict[str, Any]) -> str:
    lines = [table_row(["per 90 deg", "mean edge [mm]", "vertices",
                        *[f"{e} max [deg]" for e in ESTIMATORS],
                        *[f"{label} max [mm]" for label in MODELS.values()]]),
             table_row(["---:"] * (3 + len(ESTIMATORS) + len(MODELS)))]
    for i, n in enumerate(LEVELS):
        lines.append(table_row([n, f"{row['h'][i]:.4g}", row["vertices"][i],
                                *[f"{row['normal_max'][e][i]:.3g}" for e in ESTIMATORS],
                                *[f"{row['shape_max'][m][i]:.3g}" for m in MODELS]]))
    return "\n".join(lines)


def dihedral_table(surfaces: dict[str, Any], kinds: list[str]) -> str:
    lines = [table_row(["per 90 deg", *surfaces, *[f"{s} (perturbed tri)" for s in surfaces]]),
             table_row(["---:"] * (1 + 2 * len(surfaces)))]
    for i, n in enumerate(LEVELS):
        smooth = [f"{max(rows[k]['dihedral_max'][i] for k in kinds):.1f}"
                  for rows in surfaces.values()]
        slivers = [f"{rows['perturbed tri']['dihedral_max'][i]:.1f}"
                   for rows in surfaces.values()]
        lines.append(table_row([n, *smooth, *slivers]))
    return "\n".join(lines)


def plot(result: dict[str, Any], folder: Path) -> list[Path]:
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    colours = dict(zip(ESTIMATORS, ("tab:red", "tab:orange", "tab:green", "tab:purple",
                                    "tab:blue"), strict=True))
    paths = []
    fig = Figure(figsize=(13, 7), layout="constrained")
    axes = fig.subplots(2, 4)
    for col, (name, rows) in enumerate(result["surfaces"].items()):
        for r, kind in enumerate(("unstructured tri", "perturbed quad")):
            ax = axes[r, col]
            row = rows[kind]
            h = np.array(row["h"]) / rows["radius"]
            for estimator in ESTIMATORS:
                order = _orders(row, "normal_max")[estimator]
                ax.loglog(h, row["normal_max"][estimator], "o-", color=colours[estimator],
                          label=f"{estimator} ({order:.1f})")
            ax.set_title(f"{name}, {kind}", fontsize=10)
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_xlabel("mean edge / radius")
            ax.legend(fontsize=7)
        axes[0, col].set_ylabel("max normal error [deg]") if col == 0 else None
    axes[1, 0].set_ylabel("max normal error [deg]")
    fig.suptitle("Normal error of the estimators (order fitted on the three finest meshes)")
    path = folder / "mesh_normals_estimators.png"
    fig.savefig(path, dpi=100)
    paths.append(path)

    fig = Figure(figsize=(13, 7), layout="constrained")
    axes = fig.subplots(2, 4)
    styles = {"nagata_estimated": ("tab:blue", "o-"), "nagata_exact": ("k", "s--"),
              "facets": ("tab:red", "^-")}
    panels = [(name, "unstructured tri") for name in result["surfaces"]] + \
        [(name, "perturbed quad") for name in list(result["surfaces"])[:3]] + [("die", "")]
    for ax, (name, kind) in zip(axes.ravel(), panels, strict=True):
        if name == "die":
            row, radius, title = result["die"], 4.0, "die (CAD mesh, quad)"
        else:
            row = result["surfaces"][name][kind]
            radius, title = result["surfaces"][name]["radius"], f"{name}, {kind}"
        h = np.array(row["h"]) / radius
        for model, label in MODELS.items():
            colour, style = styles[model]
            order = _orders(row, "shape_max")[model]
            ax.loglog(h, row["shape_max"][model], style, color=colour,
                      label=f"{label} ({order:.1f})")
        ax.set_title(title, fontsize=10)
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("mean edge / radius")
        ax.legend(fontsize=7)
    axes[0, 0].set_ylabel("max distance [mm]")
    axes[1, 0].set_ylabel("max distance [mm]")
    fig.suptitle(f"Shape error: Nagata with {DEFAULT_ESTIMATOR} normals, with exact normals, "
                 "facets")
    path = folder / "mesh_normals_shape.png"
    fig.savefig(path, dpi=100)
    paths.append(path)
    return paths


def report(result: dict[str, Any], figures: list[Path], code: str, seconds: float) -> str:
    surfaces = result["surfaces"]
    die = result["die"]
    sections = []
    for name, rows in surfaces.items():
        sections.append(f"""### {name} ({rows['description']})

Max normal error [deg] at {LEVELS[-1]} elements per 90 degrees (order):

{normal_table(rows, 'normal_max')}

RMS normal error [deg] (order):

{normal_table(rows, 'normal_rms')}

Max distance to the surface [mm] (order):

{shape_table(rows)}
""")
    cases = len(surfaces) * len(MESH_KINDS)
    finest = {(s, k): {e: surfaces[s][k][key][e][-1] for e in ESTIMATORS}
              for s in surfaces for k in MESH_KINDS for key in ("normal_max",)}
    finest_rms = {(s, k): {e: surfaces[s][k]["normal_rms"][e][-1] for e in ESTIMATORS}
                  for s in surfaces for k in MESH_KINDS}
    best_max = {e: sum(min(v, key=v.get) == e for v in finest.values()) for e in ESTIMATORS}
    best_rms = {e: sum(min(v, key=v.get) == e for v in finest_rms.values()) for e in ESTIMATORS}
    worst = {e: max(v[e] for v in finest.values()) for e in ESTIMATORS}

    def orders(key: str, estimator: str, kinds=MESH_KINDS) -> list[float]:
        return [_orders(surfaces[s][k], key)[estimator] for s in surfaces for k in kinds]

    lines_choice = "\n".join(
        f"| {e} | {worst[e]:.3g} | {best_max[e]} of {cases} | {best_rms[e]} of {cases} | "
        f"{min(orders('normal_max', e)):.2f} to {max(orders('normal_max', e)):.2f} | "
        f"{min(orders('normal_rms', e)):.2f} to {max(orders('normal_rms', e)):.2f} |"
        for e in ESTIMATORS)
    choice_header = table_row(["estimator", "worst max error [deg]", "smallest max error",
                               "smallest RMS error", "orders of the max",
                               "orders of the RMS"]) + "\n|---|---:|---:|---:|---:|---:|"
    tri = [k for k in MESH_KINDS if k.endswith("tri")]
    quads = [k for k in MESH_KINDS if k.startswith(("perturbed quad", "unstructured quad"))]

    def shape_orders(model: str, kinds: list[str]) -> str:
        values = orders("shape_max", model, kinds)
        return f"{min(values):.2f} to {max(values):.2f}"

    ratio = [surfaces[s][k]["shape_max"]["nagata_estimated"][-1]
             / surfaces[s][k]["shape_max"]["nagata_exact"][-1] for s in surfaces for k in tri]
    smooth_kinds = [k for k in MESH_KINDS if k != "perturbed tri"]
    dihedral_smooth = max(max(rows[k]["dihedral_max"][0] for k in smooth_kinds)
                          for rows in surfaces.values())
    dihedral_slivers = max(max(rows["perturbed tri"]["dihedral_max"])
                           for rows in surfaces.values())
    creases = {k: sum(sum(rows[k]["creases"]) for rows in surfaces.values()) for k in MESH_KINDS}
    die_orders = _orders(die, "normal_max")
    tools = result["tools"]
    ratios = [row["shape_max"]["facets"][-1] / row["shape_max"]["nagata_estimated"][-1]
              for row in tools.values()]
    exact_ratios = [row["shape_max"]["facets"][-1] / row["shape_max"]["nagata_exact"][-1]
                    for row in tools.values()]
    fig1, fig2 = (p.name for p in figures)
    return f"""# Vertex normals of tool meshes

How good are the normals estimated from a tool mesh (`ddpy tools build MESH`,
[mesh-tools.md](../mesh-tools.md)), and the Nagata patches built on them? The arc study
([arc_accuracy.md](arc_accuracy.md), paper Fig. 3 and 4) carried exact normals; here they are
estimated from the vertices alone, in 3D.
Generated by `benchmarks/mesh_normals/run.py` in {seconds:.0f} s. {computed_at(code)}

## What is computed

* Surfaces (`ddpy.studies.normal_accuracy`), each meshed in its parameter rectangle (in mm
  of arc, so elements are near square on the surface) with vertices exactly on it:
  {'; '.join(f"{n}: {r['description']}" for n, r in surfaces.items())}.
* Meshes at h = (pi/2) r / n, n = {', '.join(str(n) for n in LEVELS)} elements per 90 degrees
  of the smallest radius of curvature r: structured grids (triangles: each cell cut along
  the same diagonal), the same with interior vertices moved at random by up to 30 % of the
  spacing, and gmsh's Frontal-Delaunay (recombined into quadrilaterals by Blossom, which
  leaves a few triangles). The boundary vertices count: their neighbourhood is one-sided,
  like that of a vertex on a crease.
* The die: the plane-fillet-cylinder die of [tool_models.md](tool_models.md) (land, convex
  fillet of radius 4 mm, concave cylinder of 23.5 mm, tangent to one another), meshed from its
  CAD by `ToolBuilder.mesh` (structured quadrilaterals) with n elements per 90 degrees
  and edges of at most (pi/2) 4 mm / n on the straight ones; exact normals from the CAD.
  The same for the tools of the forming benchmarks (`ddpy.cad.examples.bending_tools` and
  `reverse_drawing_tools`: {', '.join(tools)}), at n = {', '.join(str(n) for n in TOOL_LEVELS)}
  per 90 degrees of each tool's smallest radius, with the default estimator.
* **Normal error**: the angle between the estimated and the exact normal at every vertex
  (every sheet of a vertex, and every face corner on the die), max and RMS.
* **Shape error**: the largest distance from the patches to the exact surface, over 5 x 5
  samples per patch (triangles: their half), each projected on the surface by Gauss-Newton
  (on the die: `ddpy.cad.shape_error` against the CAD), for Nagata patches with the
  **{DEFAULT_ESTIMATOR}** estimated normals, Nagata patches with the exact normals, and the
  flat facets of the same mesh.
* Orders: least-squares slope of log(error) against log(mean edge) over the three finest
  meshes.

The estimators (`ddpy.geometry.mesh_normals`): **area** (face normals weighted by area),
**angle** (by the corner angle, Thurmer and Wuthrich 1998), **max** (corner cross products
over the squared edge lengths, Max 1999), **quadric** (weighted least-squares quadratic height
function through the vertex in its tangent plane, 1-ring), **cubic** (the same with the cubic
terms, 2-ring: an osculating jet of order 3, Cazals and Pouget 2003).

## The choice: {DEFAULT_ESTIMATOR}

Over the {cases} meshes of the finest level (4 surfaces, 6 kinds):

{choice_header}
{lines_choice}

The weighted means (area, angle, max) are first order in the max: at a boundary vertex (as at
a crease) the fan is one-sided, and a sum of face normals leans towards its faces; inside,
they are second order only where the fan is symmetric. Max's weights are exact on a sphere
only where the fan closes around the vertex; the angle weights suffer most from the thin
triangles of the perturbed meshes. The fits do not rest on the symmetry of the fan: the
quadric is second order (third on the cylinder and the sphere, whose height function in the
tangent plane has no cubic term), the cubic third order in the RMS everywhere. The cubic's
max error falls to second order where the corners of the meshed rectangle set it (three
points in the 1-ring, too few distinct rows for a cubic even in the 3-ring: the quadric is
fitted there). Hence the default: **{DEFAULT_ESTIMATOR}**, the smallest max error on
{best_max[DEFAULT_ESTIMATOR]} of the {cases} meshes and the smallest RMS error on
{best_rms[DEFAULT_ESTIMATOR]}, and the highest orders.

**Nagata patches on estimated normals.** On the triangle meshes, the Nagata patches with the
cubic's normals converge at orders {shape_orders("nagata_estimated", tri)} (with exact
normals {shape_orders("nagata_exact", tri)}, the facets {shape_orders("facets", tri)}), and
lie {min(ratio):.1f} to {max(ratio):.0f} times farther from the surface than with exact
normals at the finest level: the normal error moves the patch edges by about h times the
angle. On the distorted quadrilaterals (perturbed and unstructured) the Nagata patches
converge at orders {shape_orders("nagata_exact", quads)} even with the exact normals (on the
cylinder the largest distance is at the centre of the patches): a limit of the
quadrilateral patch on quadrilaterals that are not parallelograms, not of the normals (with
estimated normals {shape_orders("nagata_estimated", quads)}). Meshes of triangles or of
near-parallelogram quadrilaterals make the better Nagata tools.

**Tangent joints.** On the die, where a plane, a fillet of radius 4 mm and a cylinder of
23.5 mm meet tangentially, every estimator is first order (cubic
{die_orders[DEFAULT_ESTIMATOR]:.2f}, see the table below): the curvature jumps across the
joint and a height function fitted across it tilts by about h times the jump. At the joint
of the fillet with the cylinder, whose elements are long (the cylinder's turning angle sets
its division), the Nagata patches then err as much as the facets. Give the CAD (`--cad`)
where it exists; otherwise refine the mesh across the joints.

## Crease angle: {DEFAULT_CREASE_ANGLE:g} degrees

The largest angle between the normals of neighbouring faces of the smooth surfaces, over the
mesh kinds other than the perturbed triangles, and on the perturbed triangles:

{dihedral_table(surfaces, smooth_kinds)}

At 4 elements per 90 degrees, the density the tool models use, neighbouring faces of a smooth
surface meet at up to {dihedral_smooth:.1f} degrees (22.5 on a regular grid). The default
{DEFAULT_CREASE_ANGLE:g} degrees stays above that and below the 90 degrees of the edges where a
tool's working face ends. The random perturbation makes thin triangles whose normals are
poor (up to {dihedral_slivers:.1f} degrees between neighbours, at any level): there
{creases["perturbed tri"]} edges were taken for creases, on the other kinds
{sum(v for k, v in creases.items() if k != "perturbed tri")}. A mesh coarser than 4 elements
per 90 degrees, or a real crease flatter than {DEFAULT_CREASE_ANGLE:g} degrees, needs
`--crease-angle`.

## Results by surface

{chr(10).join(sections)}
### die (CAD mesh)

{refinement_table(die)}

Orders over the three finest meshes: normals
{', '.join(f"{e} {o:.2f}" for e, o in _orders(die, 'normal_max').items())};
shape {', '.join(f"{MODELS[m]} {o:.2f}" for m, o in _orders(die, 'shape_max').items())}.
The largest errors of the estimated normals are at the tangent joints (above).

### The bending and deep drawing tools (CAD meshes)

{tools_table(tools)}

At {TOOL_LEVELS[-1]} elements per 90 degrees of each tool's smallest radius (orders over
{', '.join(str(n) for n in TOOL_LEVELS)}, which include the coarsest meshes' large errors at
the faces' ends, so they overstate the rate). Their faces meet tangentially (flats,
shoulders, noses, walls): the largest normal errors,
{min(r["normal_max"][DEFAULT_ESTIMATOR][-1] for r in tools.values()):.2f} to
{max(r["normal_max"][DEFAULT_ESTIMATOR][-1] for r in tools.values()):.2f} degrees at the
finest level, are those of the joints, as on the die above, where the order is first. The
Nagata patches on the estimated normals lie {min(ratios):.1f} to {max(ratios):.1f} times
closer to the CAD than the facets of the same mesh (with the CAD's normals,
{min(exact_ratios):.0f} to {max(exact_ratios):.0f} times): where a tool's CAD exists, give it
(`--cad`).

## Figures

![normal error]({fig1})

![shape error]({fig2})
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print the summary and write nothing")
    parser.add_argument("--out", type=Path, default=DOCS,
                        help=f"folder for the report and figures (default {DOCS})")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    result = {"surfaces": study_surfaces(), "die": study_die(), "tools": study_tools()}
    seconds = time.perf_counter() - start
    if args.json:
        print(json.dumps(summary(result), indent=1))
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    figures = plot(result, args.out)
    path = args.out / "mesh_normals.md"
    path.write_text(report(result, figures, code_version(), seconds), encoding="utf-8")
    print(f"wrote {', '.join(str(p) for p in [*figures, path])} in {seconds:.0f} s",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
