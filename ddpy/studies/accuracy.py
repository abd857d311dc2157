"""Accuracy of linear and Nagata interpolation of a circular arc (paper Fig. 3 and 4).

The arc is the trace of a cylinder described by a strip of quadrilateral patches, so the
numbers come from the same Nagata and facet code that describes the tools: the patch edge
on the cylinder's base is the Nagata curve of paper Eq. 4-5 (a straight chord for facets).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ddpy.geometry.surfaces import NagataSurface

__all__ = ["arc_errors", "arc_accuracy_study", "summary", "format_table", "plot_figures",
           "fit_order", "PAPER"]

#: The paper's figures: 30 degree arc (Fig. 3) and convergence orders (Fig. 4).
PAPER: dict[str, Any] = {
    "arc30": {"linear": {"radial_pct": 3.5, "normal_deg": 15.0},
              "nagata": {"radial_pct": 0.06, "normal_deg": 0.2}},
    "orders": {"linear": {"radial": 2.0, "normal": 1.0},
               "nagata": {"radial": 4.0, "normal": 3.0}},
}
METHODS = {"linear": False, "nagata": True}


def arc_errors(
    arc_deg: float, parts: int, smooth: bool, samples: int = 801, radius: float = 1.0
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Errors along an arc of ``arc_deg`` degrees split into ``parts`` equal segments.

    Returns the polar angle of each sample (degrees), the radial error in % of the radius
    (positive outside the circle) and the angle between the interpolated and the exact
    normal (degrees). Samples are taken at ``samples`` parameter values per segment.
    """
    if parts < 1 or samples < 2 or not 0.0 < arc_deg < 180.0 * parts:
        raise ValueError("need parts >= 1, samples >= 2 and 0 < arc_deg/parts < 180")
    angles = np.radians(np.linspace(0.0, arc_deg, parts + 1))
    rim = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
    vertices = np.vstack([radius * rim, radius * rim + [0.0, 0.0, 1.0]])
    normals = np.vstack([rim, rim])
    base = np.arange(parts)
    # Counter-clockwise seen from outside: along the arc, then up the cylinder.
    faces = np.column_stack([base, base + 1, base + parts + 2, base + parts + 1])
    surface = NagataSurface(vertices, normals, faces, smooth=smooth)
    s = np.linspace(0.0, 1.0, samples)
    ids = np.repeat(base, samples)
    params = np.column_stack([np.tile(s, parts), np.zeros(parts * samples)])
    points, _, unit_normals = surface.evaluate(ids, params)
    r = np.hypot(points[:, 0], points[:, 1])
    exact = points[:, :2] / r[:, None]
    cosine = np.clip(np.einsum("ij,ij->i", exact, unit_normals[:, :2]), -1.0, 1.0)
    polar = np.degrees(np.arctan2(points[:, 1], points[:, 0]))
    return polar, 100.0 * (r - radius) / radius, np.degrees(np.arccos(cosine))


def fit_order(h: NDArray[np.float64], error: NDArray[np.float64]) -> float:
    """Least-squares slope of log(error) against log(h)."""
    return float(np.polyfit(np.log(h), np.log(error), 1)[0])


def arc_accuracy_study(parts: range = range(2, 21)) -> dict[str, Any]:
    """The whole study: the 30 degree arc and the quarter circle in 2..20 parts."""
    result: dict[str, Any] = {"arc30": {}, "quarter": {"parts": list(parts),
                                                       "l_over_r": []}, "orders": {}}
    result["quarter"]["l_over_r"] = [np.pi / 2 / n for n in parts]
    for name, smooth in METHODS.items():
        polar, radial, normal = arc_errors(30.0, 1, smooth)
        result["arc30"][name] = {"angle_deg": polar, "radial_pct": radial, "normal_deg": normal}
        max_radial, max_normal = [], []
        for n in parts:
            _, radial_n, normal_n = arc_errors(90.0, n, smooth)
            max_radial.append(float(np.abs(radial_n).max()))
            max_normal.append(float(normal_n.max()))
        h = np.array(result["quarter"]["l_over_r"])
        result["quarter"][name] = {"radial_pct": max_radial, "normal_deg": max_normal}
        result["orders"][name] = {"radial": fit_order(h, np.array(max_radial)),
                                  "normal": fit_order(h, np.array(max_normal))}
    return result


def summary(result: dict[str, Any]) -> dict[str, Any]:
    """The headline numbers: max errors on the 30 degree arc and the fitted orders."""
    arc30 = {
        name: {"radial_pct": float(np.abs(r["radial_pct"]).max()),
               "normal_deg": float(np.max(r["normal_deg"]))}
        for name, r in result["arc30"].items()
    }
    return {"arc30": arc30, "orders": result["orders"]}


def format_table(result: dict[str, Any]) -> str:
    """Markdown table of the study next to the paper's values."""
    s = summary(result)
    lines = [
        "| quantity | linear (ddpy) | linear (paper) | Nagata (ddpy) | Nagata (paper) |",
        "|---|---|---|---|---|",
    ]
    rows = [
        ("30 deg arc: max radial error [% of r]", "arc30", "radial_pct", "{:.3f}"),
        ("30 deg arc: max normal error [deg]", "arc30", "normal_deg", "{:.3f}"),
        ("quarter circle: order of max radial error", "orders", "radial", "{:.2f}"),
        ("quarter circle: order of max normal error", "orders", "normal", "{:.2f}"),
    ]
    for label, group, key, fmt in rows:
        ours = [fmt.format(s[group][m][key]) for m in METHODS]
        paper = [f"{PAPER[group][m][key]:g}" for m in METHODS]
        lines.append(f"| {label} | {ours[0]} | {paper[0]} | {ours[1]} | {paper[1]} |")
    signs = {m: "inside" if result["arc30"][m]["radial_pct"][
        np.abs(result["arc30"][m]["radial_pct"]).argmax()] < 0 else "outside" for m in METHODS}
    lines.append("")
    lines.append(f"Largest radial error on the 30 degree arc: linear {signs['linear']} the "
                 f"circle, Nagata {signs['nagata']} (paper: inside, outside).")
    return "\n".join(lines)


def plot_figures(result: dict[str, Any], folder: Path) -> list[Path]:
    """Write Fig. 3 (error along the 30 degree arc) and Fig. 4 (convergence) as PNG."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    folder.mkdir(parents=True, exist_ok=True)
    colors = {"linear": "tab:red", "nagata": "tab:blue"}
    fig3 = Figure(figsize=(10, 4), layout="constrained")
    axes = fig3.subplots(1, 2)
    for ax, key, label in ((axes[0], "radial_pct", "radial error [% of r]"),
                           (axes[1], "normal_deg", "normal vector error [deg]")):
        twin = ax.twinx()
        for name, target in (("linear", ax), ("nagata", twin)):
            r = result["arc30"][name]
            target.plot(r["angle_deg"], r[key], color=colors[name], label=name)
            target.set_ylabel(f"{name}: {label}", color=colors[name])
        ax.set_xlabel("position on the arc [deg]")
    axes[0].set_title("(a) radial error, 30 deg arc")
    axes[1].set_title("(b) normal vector error, 30 deg arc")
    path3 = folder / "arc_accuracy_fig3.png"
    fig3.savefig(path3, dpi=120)

    fig4 = Figure(figsize=(10, 4), layout="constrained")
    axes = fig4.subplots(1, 2)
    h = np.array(result["quarter"]["l_over_r"])
    for ax, key, order_key, label in ((axes[0], "radial_pct", "radial", "max radial error [%]"),
                                      (axes[1], "normal_deg", "normal", "max normal error [deg]")):
        for name in METHODS:
            order = result["orders"][name][order_key]
            ax.loglog(h, result["quarter"][name][key], "o-", color=colors[name],
                      label=f"{name} (order {order:.2f})")
        ax.set_xlabel("normalized arc length l/r")
        ax.xaxis.set_minor_formatter(NullFormatter())  # minor labels overlap on 0.08..0.8
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    axes[0].set_title("(a) maximum radial error, quarter circle in 2..20 parts")
    axes[1].set_title("(b) maximum normal error")
    path4 = folder / "arc_accuracy_fig4.png"
    fig4.savefig(path4, dpi=120)
    return [path3, path4]
