"""Benchmark: where and why the solid-shell blank loses volume (docs/theory/solid_shell.md,
"Volume").

Plastic flow keeps the volume; the solid-shell keeps it for its material strain (assumed
plus enhanced), not for the volume of its nodes. This measures the difference:

- over the blanks of the reverse deep drawing (its kept runs, docs/benchmarks/
  reverse_deep_drawing*_runs.json): the blank's volume change at the end against the
  element size, solid-shell and hexahedron;
- on the built-in coarse deep drawing (`ddpy run deep-drawing`, fields every 5
  increments), solid-shell against the mean-dilatation hexahedron with the same contact:
  the blank's volume over the run, and per element its volume change against the tilt of
  its fibres (node a + 4 minus node a) to its bottom face's normal, the mark of an element
  bent over a tool radius; the element that lost most, over the run;
- which assumed strain parts from the volume: per element over a span of frames, the trace
  of each assumed covariant strain's change from the compatible one at the Gauss points,
  tr E = E_ab G^ab with G^ab the contravariant metric of x_n, summed with the initial-volume
  weights (a first-order analysis, Green-Lagrange strains).

    python benchmarks/solid_shell_volume/run.py            # both runs (~3 min), the report
    python benchmarks/solid_shell_volume/run.py --report   # the report from the kept numbers
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the benchmarks' shared module
import bench_common  # noqa: E402

from ddpy.app.runner import BUILT_IN_CASES  # noqa: E402
from ddpy.io.results import ResultsReader  # noqa: E402
from ddpy.studies.drawing import hexahedron_volumes  # noqa: E402

WORK = HERE / "results"
JSON_FILE = bench_common.DOCS / "solid_shell_volume.json"
REPORT = bench_common.DOCS / "solid_shell_volume.md"
ELEMENTS = ("solid-shell", "hexahedron")
#: Fields every this many increments.
OUTPUT_EVERY = 5
#: Spans of frames of the solid-shell run for the split by assumed strain (stage 1: where
#: the flange first wraps die 1's shoulder, and near its end).
SPANS = ((25, 26), (40, 41))
#: Elements whose fibres tilt by more than this (degrees) count as bent over a radius.
TILTED = 10.0
#: The reverse deep drawing's blanks, their kept runs and element sizes (make_case.py).
BLANKS = (("coarse", ""), ("medium", "_medium"), ("paper", "_paper"))
#: The radii the blank wraps in the reverse deep drawing (make_case.Dimensions, mm).
RADII = {"die 1's shoulder": 8.0, "punch 1's nose": 7.0, "punch 1's inner edge": 5.0,
         "punch 2's nose": 5.0}

CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
GAUSS = 1.0 / math.sqrt(3.0)


def make_case(element: str) -> Path:
    """The built-in deep drawing with fields every OUTPUT_EVERY increments, on ``element``."""
    case = WORK / "cases" / element
    if case.exists():
        shutil.rmtree(case)
    shutil.copytree(BUILT_IN_CASES["deep-drawing"], case)
    control = case / "control.dat"
    control.write_text(re.sub(r"(?m)^output_every\s+\d+", f"output_every   {OUTPUT_EVERY}",
                              control.read_text()))
    if element == "hexahedron":
        mesh = case / "mesh.dat"
        mesh.write_text(mesh.read_text() + "element hexahedron\n")
    return case


def run_both() -> dict[str, str]:
    """Both runs side by side, one thread each; their code."""
    code = bench_common.code_version()
    jobs = []
    for element in ELEMENTS:
        output = WORK / element
        command = [sys.executable, "-m", "ddpy.app.cli", "run", str(make_case(element)),
                   "--output", str(output), "--overwrite", "--threads", "1"]
        log = (WORK / f"{element}.log").open("w")
        jobs.append((element, subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT,
                                               env=dict(os.environ, OMP_NUM_THREADS="1"))))
    for element, job in jobs:
        if job.wait() != 0:
            raise RuntimeError(f"the {element} run failed: see {WORK / (element + '.log')}")
    return {element: code for element in ELEMENTS}


def shape_derivatives(xi: NDArray[np.float64]) -> NDArray[np.float64]:
    """dN_a/dxi_j (8, 3) of the trilinear hexahedron at natural point xi."""
    out = np.empty((8, 3))
    for j in range(3):
        k, m = [i for i in range(3) if i != j]
        out[:, j] = CORNERS[:, j] * (1 + CORNERS[:, k] * xi[k]) * (1 + CORNERS[:, m] * xi[m]) / 8
    return out


def fibre_tilt(x: NDArray[np.float64], elements: NDArray[np.int32]) -> NDArray[np.float64]:
    """Per element, the mean angle (degrees) of its four fibres to its bottom face's normal."""
    xe = x[elements]
    bottom, top = xe[:, :4], xe[:, 4:]
    normal = np.cross(bottom[:, 2] - bottom[:, 0], bottom[:, 3] - bottom[:, 1])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    fibre = top - bottom
    cosine = np.abs(np.einsum("eij,ej->ei", fibre, normal)) / np.linalg.norm(fibre, axis=2)
    return np.degrees(np.arccos(np.clip(cosine, 0.0, 1.0))).mean(axis=1)


def analyse_run(path: Path) -> dict[str, Any]:
    """Per frame: the blank's volume change, the correlation over the elements of their
    volume change with their fibres' tilt, the elements tilted past TILTED; the element
    that lost most at the end, with its history."""
    with ResultsReader(path) as r:
        x0, elements, frames = r.nodes, r.elements, r.frames
        v0 = hexahedron_volumes(x0, elements)
        rows, positions = [], []
        for frame in frames:
            x = x0 + r.field("displacement", frame.index)
            positions.append(x)
            change = hexahedron_volumes(x, elements) / v0 - 1.0
            tilt = fibre_tilt(x, elements)
            spread = change.std() > 0 and tilt.std() > 0
            rows.append({"frame": frame.index, "increment": frame.increment,
                         "phase": frame.phase, "travel_mm": float(frame.travel),
                         "volume_change": float(
                             hexahedron_volumes(x, elements).sum() / v0.sum() - 1.0),
                         "correlation": float(np.corrcoef(tilt, change)[0, 1])
                         if spread else None,
                         "tilted": int((tilt > TILTED).sum()),
                         "largest_tilt_deg": float(tilt.max())})
        phases = [str(p) for p in r.attribute("phases")]
        ids = r.element_ids
    final = hexahedron_volumes(positions[-1], elements) / v0 - 1.0
    worst = int(np.argmin(final))
    history = []
    for row, x in zip(rows, positions, strict=True):
        xe = x[elements[worst]]
        history.append({"increment": row["increment"],
                        "volume_change": float(hexahedron_volumes(x, elements[worst:worst + 1])[0]
                                               / v0[worst] - 1.0),
                        "fibres_mm": [float(np.linalg.norm(xe[a + 4] - xe[a]))
                                      for a in range(4)],
                        "tilt_deg": float(fibre_tilt(x, elements[worst:worst + 1])[0])})
    centre = x0[elements[worst]].mean(axis=0)
    return {"frames": rows, "phases": phases,
            "worst": {"element": int(ids[worst]), "radius_mm": float(np.hypot(*centre[:2])),
                      "history": history}}


def split_by_assumed_strain(path: Path, spans: tuple[tuple[int, int], ...]
                            ) -> list[dict[str, Any]]:
    """Over each span of frames, summed over the blank with the initial-volume weights:
    ln(V1 / Vn) of each element, the trace of its compatible strain increment, and the
    traces the assumed thickness strain (from the mid-surface corners) and transverse
    shears (from the mid-edges) add to it (tr E = E_ab G^ab)."""
    with ResultsReader(path) as r:
        x0, elements = r.nodes, r.elements
        out = []
        for first, last in spans:
            xa = x0 + r.field("displacement", first)
            xb = x0 + r.field("displacement", last)
            travel = (float(r.frames[first].travel), float(r.frames[last].travel))
            sums = np.zeros(5)
            for e in range(len(elements)):
                sums += element_split(x0[elements[e]], xa[elements[e]],
                                      xb[elements[e]] - xa[elements[e]])
            out.append({"frames": [first, last], "travel_mm": travel,
                        "volume": float(sums[0]), "compatible": float(sums[1]),
                        "thickness": float(sums[2]), "shear_13": float(sums[3]),
                        "shear_23": float(sums[4])})
    return out


def element_split(x0: NDArray[np.float64], xn: NDArray[np.float64],
                  du: NDArray[np.float64]) -> NDArray[np.float64]:
    """One element: ln(V1 / Vn), and the W0-weighted means of the compatible strain's
    trace and of the traces the assumed 33, 13 and 23 components add."""
    def covariant(xi: list[float]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        dn = shape_derivatives(np.asarray(xi, dtype=float))
        g, d = xn.T @ dn, du.T @ dn
        return 0.5 * (g.T @ d + d.T @ g + d.T @ d), g

    corners = [covariant([a, b, 0.0])[0][2, 2] for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    vn = v1 = weights = 0.0
    sums = np.zeros(4)
    for p in range(8):
        xi = GAUSS * CORNERS[p]
        strain, g = covariant(list(xi))
        dn = shape_derivatives(xi)
        w0 = float(np.linalg.det(x0.T @ dn))
        vn += float(np.linalg.det(g))
        v1 += float(np.linalg.det(g + du.T @ dn))
        metric = np.linalg.inv(g.T @ g)
        interpolate = 0.25 * (1 + CORNERS[:4, 0] * xi[0]) * (1 + CORNERS[:4, 1] * xi[1])
        e33 = float(interpolate @ corners)
        z = float(xi[2])
        e13 = 0.5 * ((1 - xi[1]) * covariant([0, -1, z])[0][0, 2]
                     + (1 + xi[1]) * covariant([0, 1, z])[0][0, 2])
        e23 = 0.5 * ((1 - xi[0]) * covariant([-1, 0, z])[0][1, 2]
                     + (1 + xi[0]) * covariant([1, 0, z])[0][1, 2])
        sums += w0 * np.array([np.sum(strain * metric),
                               (e33 - strain[2, 2]) * metric[2, 2],
                               2.0 * (e13 - strain[0, 2]) * metric[0, 2],
                               2.0 * (e23 - strain[1, 2]) * metric[1, 2]])
        weights += w0
    return np.concatenate([[math.log(v1 / vn)], sums / weights])


def blanks() -> list[dict[str, Any]]:
    """The reverse deep drawing's kept runs: per blank the end's volume change of the
    solid-shell (Nagata, Bezier) and of DD3IMP's hexahedron."""
    make_case = bench_common.load_module(
        bench_common.ROOT / "benchmarks" / "reverse_deep_drawing" / "make_case.py",
        "reverse_deep_drawing_make_case")
    out = []
    for mesh, suffix in BLANKS:
        kept = json.loads((bench_common.DOCS / f"reverse_deep_drawing{suffix}_runs.json")
                          .read_text())
        row: dict[str, Any] = {"blank": mesh, "size_mm": float(make_case.ELEMENT_SIZE[mesh])}
        for model in ("nagata", "bezier", "dd3imp"):
            numbers = kept[model]["numbers"]
            end = numbers["stages"]["stage2"]["end"]
            row[model] = {"volume_change": end["volume_change"],
                          "element_volume_change_max": end["element_volume_change_max"],
                          "hexahedra": numbers["hexahedra"], "code": numbers["code"],
                          "discretization": numbers["discretization"]}
        out.append(row)
    return out


def report(data: dict[str, Any]) -> str:
    row = bench_common.table_row
    runs = data["runs"]
    run_code = {f"built-in case on the {e}": c for e, c in data["run_code"].items()}
    run_code.update({f"deep drawing {b['blank']} {m}": b[m]["code"]
                     for b in data["blanks"] for m in ("nagata", "bezier", "dd3imp")})
    lines = ["# Where the solid-shell blank loses volume", "",
             "Written by `benchmarks/solid_shell_volume/run.py`; every number below is computed "
             "by it (its kept numbers: `solid_shell_volume.json`). "
             + bench_common.computed_at(data["code"], run_code),
             "", "Plastic flow keeps the volume; the solid-shell keeps it for its material "
             "strain, not for the volume of its nodes (docs/theory/solid_shell.md, "
             "\"Volume\"). Volumes are the exact ones of the trilinear hexahedra.", "",
             "## Over the blanks of the reverse deep drawing", "",
             "The end of stage 2, from the benchmark's kept runs (docs/benchmarks/"
             "reverse_deep_drawing*.md); the radii the blank wraps: "
             + ", ".join(f"{name} {r:g} mm" for name, r in RADII.items()) + ".", "",
             row(["blank", "element size (mm)", "hexahedra", "solid-shell, Nagata",
                  "its largest element", "solid-shell, Bezier",
                  "hexahedron, node-to-surface (DD3IMP's)", "order against the coarser blank",
                  "size over the smallest radius"]), row(["---"] * 9)]
    smallest = min(RADII.values())
    previous = None
    for b in data["blanks"]:
        order = ""
        if previous is not None:
            order = f"{math.log(previous['nagata']['volume_change'] / b['nagata']['volume_change']) / math.log(previous['size_mm'] / b['size_mm']):.2f}"  # noqa: E501
        lines.append(row([b["blank"], f"{b['size_mm']:.3g}", b["nagata"]["hexahedra"],
                          f"{100 * b['nagata']['volume_change']:+.3g} %",
                          f"{100 * b['nagata']['element_volume_change_max']:+.3g} %",
                          f"{100 * b['bezier']['volume_change']:+.3g} %",
                          f"{100 * b['dd3imp']['volume_change']:+.3g} %", order,
                          f"{b['size_mm'] / smallest:.2f}"]))
        previous = b
    lines += ["", "## The built-in coarse case, solid-shell against hexahedron", "",
              f"`ddpy run deep-drawing` with fields every {OUTPUT_EVERY} increments, on each "
              "element with the same Gauss-point contact, one thread each side by side. Per "
              "frame: the blank's volume change, and over the elements the correlation of "
              "their own volume change with the mean tilt of their fibres to their bottom "
              f"face's normal; the elements tilted past {TILTED:g} degrees.", "",
              row(["increment", "phase", "travel (mm)", "solid-shell: volume",
                   "correlation", "tilted", "hexahedron: travel (mm)", "volume", "correlation",
                   "tilted"]),
              row(["---"] * 10)]
    shell, hexa = runs["solid-shell"], runs["hexahedron"]
    for f in shell["frames"][1::4]:
        # the hexahedron's frame of the same phase nearest in travel (the runs' increments
        # differ)
        same = [g for g in hexa["frames"] if g["phase"] == f["phase"]]
        h = min(same, key=lambda g: abs(g["travel_mm"] - f["travel_mm"])) if same else None

        def corr(x: dict[str, Any] | None) -> str:
            return "-" if x is None or x["correlation"] is None else f"{x['correlation']:+.2f}"

        lines.append(row([f["increment"], shell["phases"][f["phase"]], f"{f['travel_mm']:.2f}",
                          f"{100 * f['volume_change']:+.3g} %", corr(f), f["tilted"],
                          "-" if h is None else f"{h['travel_mm']:.2f}",
                          "-" if h is None else f"{100 * h['volume_change']:+.3g} %", corr(h),
                          "-" if h is None else h["tilted"]]))
    late = [f["correlation"] for f in shell["frames"]
            if f["correlation"] is not None and f["tilted"] > 0]
    late_h = [f["correlation"] for f in hexa["frames"]
              if f["correlation"] is not None and f["tilted"] > 0]
    worst = shell["worst"]
    history = worst["history"]
    first = next(h for h in history if h["volume_change"] < -0.01)
    lines += ["", "Over the frames with elements tilted past "
              f"{TILTED:g} degrees, the correlation lies between {min(late):+.2f} and "
              f"{max(late):+.2f} on the solid-shell, between {min(late_h):+.2f} and "
              f"{max(late_h):+.2f} on the hexahedron (whose mean dilatation keeps each "
              "element's volume).", "",
              f"The solid-shell's element that lost most by the end: element {worst['element']} "
              f"(initial radius {worst['radius_mm']:.4g} mm), past -1 % from increment "
              f"{first['increment']}:", "",
              row(["increment", "volume", "fibre lengths (mm)", "mean fibre tilt (degrees)"]),
              row(["---"] * 4)]
    start = history.index(first)
    for h in history[max(start - 1, 0):start + 12]:
        lines.append(row([h["increment"], f"{100 * h['volume_change']:+.3g} %",
                          " / ".join(f"{v:.3f}" for v in h["fibres_mm"]),
                          f"{h['tilt_deg']:.1f}"]))
    lines += ["", "## Which assumed strain parts from the volume", "",
              "Solid-shell run, per element over a span of frames, summed over the blank "
              "with the initial-volume weights (a first-order analysis on Green-Lagrange "
              "strains of the span): ln(V1 / Vn), the trace of the compatible strain "
              "increment at the Gauss points, and the trace each assumed component adds "
              "(tr E = E_ab G^ab, G^ab the contravariant metric of x_n: the shears enter "
              "through G^13 and G^23, nonzero where the fibres tilt). Sums of per-element "
              "values in %.", "",
              row(["frames", "travel (mm)", "ln(V1 / Vn)", "compatible trace",
                   "thickness strain from the corners", "shear 13 from mid-edges",
                   "shear 23 from mid-edges", "thickness's share of the three"]),
              row(["---"] * 8)]
    for s in data["split"]:
        added = s["thickness"] + s["shear_13"] + s["shear_23"]
        lines.append(row([f"{s['frames'][0]}-{s['frames'][1]}",
                          f"{s['travel_mm'][0]:.2f}-{s['travel_mm'][1]:.2f}",
                          f"{100 * s['volume']:.3g}", f"{100 * s['compatible']:.3g}",
                          f"{100 * s['thickness']:+.3g}", f"{100 * s['shear_13']:+.3g}",
                          f"{100 * s['shear_23']:+.3g}",
                          f"{100 * s['thickness'] / added:.0f} %"]))
    lines += ["", "The material holds the trace of the assumed strains (the compatible one "
              "plus what the assumed components add) at its elastic part, so the nodes' "
              "volume loses what those components add. (The compatible trace is of "
              "Green-Lagrange strains, above the logarithmic ln(V1 / Vn) in compression.)", ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--report", action="store_true",
                        help="write the report from the kept numbers, running nothing")
    args = parser.parse_args()
    if args.report:
        data = json.loads(JSON_FILE.read_text())
    else:
        WORK.mkdir(parents=True, exist_ok=True)
        run_code = run_both()
        results = {e: WORK / e / "results.h5" for e in ELEMENTS}
        data = {"run_code": run_code,
                "runs": {e: analyse_run(p) for e, p in results.items()},
                "split": split_by_assumed_strain(results["solid-shell"], SPANS)}
    data["code"] = bench_common.code_version()
    data["blanks"] = blanks()
    JSON_FILE.write_text(json.dumps(data, indent=1) + "\n")
    REPORT.write_text(report(data))
    print(REPORT)


if __name__ == "__main__":
    main()
