"""Contact search benchmark: projections per second, search time and scaling with the tool.

A wavy die surface z = f(x, y) is modelled four ways (bicubic Bezier patches, Nagata
quadrilaterals, Nagata triangles, bilinear facets) and searched by ``ContactSearch`` with
nodes spread like a blank a few mm above it (some penetrating). Measures, on 1 and 2
threads, projections and nodes per second for a ~5,000-patch tool and 30,000 nodes, the
set-up / query split, the Newton iterations, and the query cost for tools of 1e2 to 1e5
patches. Without flags, writes ``contact_search.md`` and two PNGs to ``docs/benchmarks``
(or ``--out DIR``); with ``--json``, prints only the numbers as JSON and writes nothing;
``--render FILE`` writes the report from numbers saved with ``--json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

import ddpy
from ddpy.core.parallel import threads
from ddpy.geometry.search import EDGE, INSIDE, NONE, ContactSearch
from ddpy.geometry.surfaces import BezierSurface, NagataSurface

REPO = Path(__file__).resolve().parents[2]
DEFAULT_OUT = REPO / "docs" / "benchmarks"
sys.path.insert(0, str(REPO / "benchmarks"))  # the benchmarks' shared module
from bench_common import code_version, computed_at  # noqa: E402

THREADS = (1, 2)
DESCRIPTIONS = ("Bezier bicubic", "Nagata quads", "Nagata triangles", "facets (quads)")
#: The die: side [mm] and target patch count of the main case.
SIDE, PATCHES = 200.0, 5000
#: Waves of the die surface: (amplitude, wavelength) [mm] of the two terms of f.
WAVE1, WAVE2 = (10.0, 100.0), (4.0, 60.0)
#: Gap of the blank to the die [mm] for the main patch size: smooth part + uniform noise.
GAP_MEAN, GAP_WAVE, GAP_NOISE = 1.25, 1.5, 0.25
SCALING_PATCHES = (100, 1_000, 10_000, 100_000)
#: Slope of log(query time per node) over log(patches) above which the cost is reported
#: as growing with the tool.
SLOPE_LIMIT = 0.15

Surface = BezierSurface | NagataSurface
Mesh = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]


# --------------------------------------------------------------------------- geometry


def height(x: NDArray[np.float64], y: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """The die z = f(x, y) and its derivatives f_x, f_y, f_xy."""
    (a1, l1), (a2, l2) = WAVE1, WAVE2
    k1, k2 = 2 * np.pi / l1, 2 * np.pi / l2
    s = k2 * (x + 0.5 * y)
    z = a1 * np.sin(k1 * x) * np.cos(k1 * y) + a2 * np.sin(s)
    fx = a1 * k1 * np.cos(k1 * x) * np.cos(k1 * y) + a2 * k2 * np.cos(s)
    fy = -a1 * k1 * np.sin(k1 * x) * np.sin(k1 * y) + 0.5 * a2 * k2 * np.cos(s)
    fxy = -a1 * k1**2 * np.cos(k1 * x) * np.sin(k1 * y) - 0.5 * a2 * k2**2 * np.sin(s)
    return z, fx, fy, fxy


def unit_normals(fx: NDArray[np.float64], fy: NDArray[np.float64]) -> NDArray[np.float64]:
    """Upward unit normals (-f_x, -f_y, 1) / |.| of the graph."""
    n = np.stack([-fx, -fy, np.ones_like(fx)], axis=-1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def grid_mesh(cells: int, side: float, triangles: bool) -> Mesh:
    """cells x cells grid on [0, side]^2 lifted to the die, exact normals; quads or triangles.

    Faces are counter-clockwise seen from above (the side the normals point to); a quad
    (a, b, c, d) splits into (a, b, c) and (a, c, d).
    """
    t = np.linspace(0.0, side, cells + 1)
    x, y = np.meshgrid(t, t, indexing="ij")
    z, fx, fy, _ = height(x, y)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    normals = unit_normals(fx, fy).reshape(-1, 3)
    ids = np.arange(x.size).reshape(cells + 1, cells + 1)
    a, b = ids[:-1, :-1].ravel(), ids[1:, :-1].ravel()
    c, d = ids[1:, 1:].ravel(), ids[:-1, 1:].ravel()
    if not triangles:
        return vertices, normals, np.column_stack([a, b, c, d])
    minus = -np.ones_like(a)
    faces = np.stack([np.column_stack([a, b, c, minus]), np.column_stack([a, c, d, minus])],
                     axis=1).reshape(-1, 4)
    return vertices, normals, faces


def hermite_nets(cells: int, side: float) -> NDArray[np.float64]:
    """Bicubic Bernstein nets (cells**2, 4, 4, 3) interpolating the die on a cells^2 grid.

    Each patch is the bicubic Hermite interpolant of f, f_x, f_y and f_xy at its corners,
    written in the Bernstein basis: x and y are linear in (u, v), and the corner, edge and
    inner control heights follow from the corner data (P_10 = f + h f_x / 3, P_11 = f +
    h (f_x + f_y) / 3 + h^2 f_xy / 9, ...). Neighbours share their edge data: the surface is
    C1 and its error is O(h^4).
    """
    h = side / cells
    i, j = (g.ravel() for g in np.meshgrid(np.arange(cells), np.arange(cells), indexing="ij"))
    x0, y0 = i * h, j * h
    nets = np.zeros((len(x0), 4, 4, 3))
    third = np.arange(4) / 3.0
    nets[..., 0] = x0[:, None, None] + h * third[None, :, None]
    nets[..., 1] = y0[:, None, None] + h * third[None, None, :]
    for a in (0, 1):
        for b in (0, 1):
            z, fx, fy, fxy = height(x0 + a * h, y0 + b * h)
            sa, sb, ia, jb = 1 - 2 * a, 1 - 2 * b, 3 * a, 3 * b  # inward steps, corner index
            nets[:, ia, jb, 2] = z
            nets[:, ia + sa, jb, 2] = z + sa * h * fx / 3
            nets[:, ia, jb + sb, 2] = z + sb * h * fy / 3
            nets[:, ia + sa, jb + sb, 2] = (z + sa * h * fx / 3 + sb * h * fy / 3
                                            + sa * sb * h * h * fxy / 9)
    return nets


def cells_for(description: str, patches: int) -> int:
    """Grid cells per side for about ``patches`` patches (triangles: two per cell)."""
    return round(np.sqrt(patches / 2 if description == "Nagata triangles" else patches))


def build_surface(description: str, cells: int, side: float) -> Surface:
    """The die on [0, side]^2 in one description on a cells x cells grid."""
    if description == "Bezier bicubic":
        return BezierSurface(hermite_nets(cells, side))
    vertices, normals, faces = grid_mesh(cells, side, description == "Nagata triangles")
    return NagataSurface(vertices, normals, faces, smooth=description != "facets (quads)")


def cell_edge(description: str) -> float:
    """Grid cell of the main case: patches of equal area in every description."""
    return SIDE / cells_for(description, PATCHES)


def blank_nodes(count: int, lo: float, hi: float, scale: float, rng: np.random.Generator
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``count`` nodes like a blank over [lo, hi]^2: (points, exact signed distance).

    A jittered a x b grid in mesh order (a * b = count, a <= b nearest sqrt(count)), each
    node offset along the exact normal by a gap (scale x [-0.5, 3] mm: a smooth field plus
    noise), so that its exact signed distance to the die is the gap (the gaps stay below
    the smallest radius of curvature of the die for scale 1). ``scale`` is the patch size
    relative to the main case: the gaps keep their ratio to the patch size.
    """
    a = max(d for d in range(1, int(np.sqrt(count)) + 1) if count % d == 0)
    b = count // a
    x, y = np.meshgrid(np.linspace(lo, hi, b), np.linspace(lo, hi, a), indexing="xy")
    spacing = (hi - lo) / max(b - 1, 1)
    x = np.clip(x.ravel() + rng.uniform(-0.3, 0.3, count) * spacing, lo, hi)
    y = np.clip(y.ravel() + rng.uniform(-0.3, 0.3, count) * spacing, lo, hi)
    z, fx, fy, _ = height(x, y)
    wave = np.sin(3 * np.pi * x / SIDE) * np.cos(2 * np.pi * y / SIDE)
    gap = scale * (GAP_MEAN + GAP_WAVE * wave + rng.uniform(-GAP_NOISE, GAP_NOISE, count))
    return np.column_stack([x, y, z]) + gap[:, None] * unit_normals(fx, fy), gap


def margin(scale: float) -> float:
    """Distance of the blank's edge from the tool's edge: the largest gap, plus 1 mm."""
    return (GAP_MEAN + GAP_WAVE + GAP_NOISE) * scale + 1.0


def min_radius_of_curvature(samples: int = 400) -> float:
    """Smallest principal radius of curvature of the die over the main tool (sampled)."""
    t = np.linspace(0.0, SIDE, samples)
    x, y = np.meshgrid(t, t, indexing="ij")
    eps = 1e-3
    _, fx, fy, fxy = height(x, y)
    fxx = (height(x + eps, y)[1] - height(x - eps, y)[1]) / (2 * eps)
    fyy = (height(x, y + eps)[2] - height(x, y - eps)[2]) / (2 * eps)
    w = 1.0 + fx**2 + fy**2
    # Shape operator of a graph: principal curvatures are the eigenvalues of I^-1 II.
    first = np.stack([np.stack([1 + fx**2, fx * fy], -1), np.stack([fx * fy, 1 + fy**2], -1)], -2)
    second = np.stack([np.stack([fxx, fxy], -1), np.stack([fxy, fyy], -1)], -2) / np.sqrt(w)[
        ..., None, None]
    kappa = np.linalg.eigvals(np.linalg.solve(first, second)).real
    return float(1.0 / np.abs(kappa).max())


# --------------------------------------------------------------------------- timing


Times = dict[Any, dict[str, Any]]


def timings(calls: dict[Any, Callable[[], object]], repeats: int, warm_up: bool = True) -> Times:
    """Best wall time and best CPU time of this process (all threads) of each call over
    ``repeats`` interleaved rounds, after a warm-up. On one thread the CPU time is the work
    done, whatever other processes take from the CPU meanwhile."""
    if warm_up:
        for call in calls.values():
            call()
    wall: dict[Any, list[float]] = {key: [] for key in calls}
    cpu: dict[Any, list[float]] = {key: [] for key in calls}
    for _ in range(repeats):
        for key, call in calls.items():
            start, start_cpu = time.perf_counter(), time.process_time()
            call()
            wall[key].append(time.perf_counter() - start)
            cpu[key].append(time.process_time() - start_cpu)
    return {key: {"wall": min(wall[key]), "cpu": min(cpu[key]), "walls": wall[key],
                  "cpus": cpu[key]} for key in calls}


def paired(times: Times, a: Any, b: Any, kind: str, combine: Callable[..., Any]) -> float:
    """Median over the rounds of ``combine(time of a, time of b)`` in the same round: calls
    timed next to each other see the same speed of the machine, which drifts."""
    return float(np.median([combine(x, y) for x, y in zip(times[a][kind], times[b][kind],
                                                          strict=True)]))


def with_threads(n: int, call: Callable[[], object]) -> Callable[[], object]:
    """``call`` run with ``n`` core threads."""

    def run() -> object:
        with threads(n):
            return call()

    return run


def cpu_busy() -> float:
    """Busy CPU seconds of the whole machine since boot, from /proc/stat."""
    try:
        fields = Path("/proc/stat").read_text().splitlines()[0].split()[1:]
    except OSError:
        return 0.0
    ticks = [float(f) / os.sysconf("SC_CLK_TCK") for f in fields[:8]]
    return sum(ticks) - ticks[3] - ticks[4]


def own_cpu() -> float:
    """CPU seconds used by this process (all threads)."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


class LoadMeter:
    """CPUs used by other processes between construction and ``value()``."""

    def __init__(self) -> None:
        self.start, self.busy, self.own = time.perf_counter(), cpu_busy(), own_cpu()

    def value(self) -> float:
        """Mean CPUs busy with other processes so far."""
        wall = max(time.perf_counter() - self.start, 1e-9)
        return max((cpu_busy() - self.busy) - (own_cpu() - self.own), 0.0) / wall


def wait_quiet(timeout: float, threshold: float = 0.2) -> float:
    """Wait up to ``timeout`` s until other processes use less than ``threshold`` CPUs."""
    deadline = time.perf_counter() + timeout
    while True:
        meter = LoadMeter()
        time.sleep(0.5)
        load = meter.value()
        if load < threshold or time.perf_counter() >= deadline:
            return load


def machine() -> dict[str, Any]:
    """nproc, CPU model, versions and the load average."""
    try:
        nproc = int(subprocess.run(["nproc"], capture_output=True, text=True,
                                   check=True).stdout)
    except (OSError, subprocess.CalledProcessError, ValueError):
        nproc = len(os.sched_getaffinity(0))
    model = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"nproc": nproc, "cpu_model": model, "numpy": np.__version__,
            "python": platform.python_version(), "ddpy": ddpy.__version__,
            "loadavg_start": os.getloadavg()[0]}


# --------------------------------------------------------------------------- measurements


def measure_main(description: str, nodes: int, repeats: int, check: int,
                 rng: np.random.Generator) -> dict[str, Any]:
    """One description, ~5,000 patches, ``nodes`` nodes: throughput on 1 and 2 threads,
    set-up and query times, global/local split, accuracy and misses against brute force."""
    meter = LoadMeter()
    start = time.perf_counter()
    surface = build_surface(description, cells_for(description, PATCHES), SIDE)
    build_s = time.perf_counter() - start
    points, gap = blank_nodes(nodes, margin(1.0), SIDE - margin(1.0), 1.0, rng)
    search = ContactSearch(surface)
    # Same candidates, Newton capped at one iteration / forced to twelve (tol = 0): the
    # difference gives the cost of one Newton iteration, hence the local-search share.
    capped = {m: ContactSearch(surface, max_iterations=m, tol=0.0 if m > 1 else 1e-12)
              for m in (1, 12)}
    calls: dict[Any, Callable[[], object]] = {("setup", 1): lambda: ContactSearch(surface)}
    for n in THREADS:
        calls["query", n] = with_threads(n, lambda: search.project(points))
    for m, capped_search in capped.items():
        calls[f"newton_{m}", 1] = with_threads(1, lambda c=capped_search: c.project(points))
    t = timings(calls, repeats)
    single = timings({"one": with_threads(1, lambda: search.project(points[:1]))}, 30)["one"]
    with threads(1):
        found = search.project(points)
        its = {m: int(c.project(points).iterations.sum()) for m, c in capped.items()}
    projections = int(found.candidates.sum())
    # From CPU times (1 thread): a difference of two runs must not carry the load of others.
    # Per round (the machine's speed drifts between rounds), then the median: the cost of an
    # iteration, and the local search (iterations + one final evaluation per projection) as
    # a share of the query of the same round.
    steps = int(found.iterations.sum()) + projections
    per_round = [(c12 - c1) / max(its[12] - its[1], 1) for c12, c1 in
                 zip(t["newton_12", 1]["cpus"], t["newton_1", 1]["cpus"], strict=True)]
    per_iteration = float(np.median(per_round))
    share = float(np.median([c * steps / q for c, q in
                             zip(per_round, t["query", 1]["cpus"], strict=True)]))

    sample = rng.choice(nodes, size=min(check, nodes), replace=False)
    brute = search.project(points[sample], brute_force=True)
    d_fast = np.linalg.norm(points[sample] - found.point[sample], axis=1)
    d_slow = np.linalg.norm(points[sample] - brute.point, axis=1)
    misses = int((d_fast > d_slow + 1e-9 * (1.0 + d_slow)).sum())

    error = np.abs(found.distance - gap)
    query_cpu = t["query", 1]["cpu"]
    local = share * query_cpu
    result: dict[str, Any] = {
        "patches": int(surface.n_patches), "nodes": nodes, "model_build_s": build_s,
        "setup_s": t["setup", 1]["wall"], "setup_cpu_s": t["setup", 1]["cpu"],
        "projections": projections, "candidates_per_node": projections / nodes,
        "mean_iterations": found.mean_iterations,
        "status": {"inside": int((found.status == INSIDE).sum()),
                   "edge": int((found.status == EDGE).sum()),
                   "none": int((found.status == NONE).sum())},
        "penetrating_nodes": int((gap < 0).sum()),
        "max_distance_error_um": float(error.max()) * 1e3,
        "mean_distance_error_um": float(error.mean()) * 1e3,
        "brute_force_sample": len(sample), "misses": misses,
        "split_1_thread_cpu": {"query_s": query_cpu, "local_s": local,
                               "global_s": query_cpu - local,
                               "ns_per_newton_iteration": per_iteration * 1e9},
    }
    for n in THREADS:
        q = t["query", n]["wall"]
        result[str(n)] = {"query_s": q, "query_cpu_s": t["query", n]["cpu"],
                          "projections_per_s": projections / q, "nodes_per_s": nodes / q,
                          "us_per_node": q / nodes * 1e6}
    # 1 and 2 threads run next to each other in every round: the median of their ratios.
    result["speedup"] = paired(t, ("query", 1), ("query", 2), "walls", lambda a, b: a / b)
    result["speedup_best_of"] = t["query", 1]["wall"] / t["query", 2]["wall"]
    result["cpus_obtained_2_threads"] = t["query", 2]["cpu"] / t["query", 2]["wall"]
    result["one_node_call_us"] = single["wall"] * 1e6
    result["search_s"] = {str(n): t["setup", 1]["wall"] + t["query", n]["wall"] for n in THREADS}
    result["other_processes_cpus"] = meter.value()
    return result


def measure_series(variant: str, description: str, nodes: int, repeats: int,
                   rng: np.random.Generator) -> dict[str, list[dict[str, Any]]]:
    """Set-up time and query time per node (1 thread) for tools of SCALING_PATCHES patches.

    ``grow``: patches of the main case's size on a die that grows with their number; the
    nodes lie either over a fixed window (the whole 100-patch tool, the same nodes for every
    tool: the algorithmic cost) or spread over the whole tool (fewer nodes per patch as the
    tool grows: adds the memory traffic). ``refine``: the 200 mm die in ever smaller
    patches, nodes over all of it, the gaps scaled with the patch size. All tools are built
    first and timed in interleaved rounds, so that a drift of the machine's speed during
    the series does not tilt the slope. Returns the rows of each node set.
    """
    meter = LoadMeter()
    tools: dict[int, dict[str, Any]] = {}
    for patches in SCALING_PATCHES:
        cells = cells_for(description, patches)
        edge = cell_edge(description) if variant == "grow" else SIDE / cells
        side = cells * edge
        start = time.perf_counter()
        surface = build_surface(description, cells, side)
        build_s = time.perf_counter() - start
        scale = edge / cell_edge(description)
        low = margin(scale)
        if variant == "grow":
            if not tools:
                window = blank_nodes(nodes, low, side - low, scale, rng)[0]
            node_sets = {"window": window,
                         "spread": blank_nodes(nodes, low, side - low, scale, rng)[0]}
        else:
            node_sets = {"refine": blank_nodes(nodes, low, side - low, scale, rng)[0]}
        tools[patches] = {"surface": surface, "side": side, "build_s": build_s,
                          "search": ContactSearch(surface),  # the warm-up of the set-up
                          "nodes": node_sets}
    calls: dict[Any, Callable[[], object]] = {}
    found: dict[Any, Any] = {}
    for patches, tool in tools.items():
        search = tool["search"]
        calls[patches, "setup"] = lambda s=tool["surface"]: ContactSearch(s)
        with threads(1):
            for name, points in tool["nodes"].items():
                found[patches, name] = search.project(points)  # the warm-up of the query
                calls[patches, name] = with_threads(1, lambda c=search, p=points: c.project(p))
        one = next(iter(tool["nodes"].values()))[:1]
        calls[patches, "one"] = with_threads(1, lambda c=search, p=one: c.project(p))
    t = timings(calls, repeats, warm_up=False)
    # One call of a single node is too short for one timing: best of 30 more, interleaved.
    ones = timings({key: call for key, call in calls.items() if key[1] == "one"}, 30)
    load = meter.value()
    rows: dict[str, list[dict[str, Any]]] = {}
    for patches, tool in tools.items():
        search = tool["search"]
        for name in tool["nodes"]:
            result = found[patches, name]
            rows.setdefault(name, []).append({
                "patches": int(tool["surface"].n_patches), "side_mm": tool["side"],
                "nodes": nodes, "model_build_s": tool["build_s"],
                "setup_s": t[patches, "setup"]["wall"], "setup_cpu_s": t[patches, "setup"]["cpu"],
                "query_s": t[patches, name]["wall"],
                "query_us_per_node": t[patches, name]["wall"] / nodes * 1e6,
                "query_cpu_us_per_node": t[patches, name]["cpu"] / nodes * 1e6,
                "mean_iterations": result.mean_iterations,
                "candidates_per_node": float(result.candidates.mean()),
                "none": int((result.status == NONE).sum()),
                "one_node_call_us": min(ones[patches, "one"]["wall"], t[patches, "one"]["wall"])
                * 1e6,
                "other_processes_cpus": load})
    return rows


def fit_slope(patches: list[int], values: list[float]) -> float:
    """Least-squares slope of log(values) over log(patches)."""
    return float(np.polyfit(np.log(patches), np.log(values), 1)[0])


def fit_scaling(rows: dict[str, dict[str, list[dict[str, Any]]]]) -> dict[str, Any]:
    """The rows of every node set and description with their fitted log-log slopes."""
    out: dict[str, Any] = {}
    for name, by_description in rows.items():
        out[name] = {}
        for description, series in by_description.items():
            n = [r["patches"] for r in series]
            out[name][description] = {"rows": series} | {
                f"{key}_slope": fit_slope(n, [r[value] for r in series]) for key, value in (
                    ("query", "query_us_per_node"), ("query_cpu", "query_cpu_us_per_node"),
                    ("setup", "setup_s"), ("build", "model_build_s"),
                    ("one_node", "one_node_call_us"))}
    return out


class Quiet:
    """Waits for other processes to go idle before a measurement, within a total budget."""

    def __init__(self, timeout: float, budget: float) -> None:
        self.timeout, self.budget, self.waited = timeout, budget, 0.0

    def measure(self, measure: Callable[[], dict[str, Any]], tries: int) -> dict[str, Any]:
        """``measure()``, repeated (up to ``tries`` times, each after waiting for quiet) while
        other processes disturb it; the least disturbed result is kept."""
        results: list[dict[str, Any]] = []
        for _ in range(tries):
            left = min(self.timeout, self.budget - self.waited)
            if results and left <= 0:
                break
            if left > 0:
                start = time.perf_counter()
                wait_quiet(left)
                self.waited += time.perf_counter() - start
            results.append(measure())
            if load_of(results[-1]) < 0.1:
                break
        return min(results, key=load_of)


def load_of(result: dict[str, Any]) -> float:
    """CPUs used by other processes during a measurement (or a series of them)."""
    if "other_processes_cpus" in result:
        return float(result["other_processes_cpus"])
    return max(float(r["other_processes_cpus"]) for rows in result.values() for r in rows)


def run(nodes: int, scaling_nodes: int, repeats: int, check: int, seed: int, refine: bool,
        quiet: Quiet) -> dict[str, Any]:
    """The whole benchmark; returns the numbers."""
    meter = LoadMeter()
    start = time.perf_counter()
    info = machine()
    rng = np.random.default_rng(seed)
    main = {d: quiet.measure(lambda d=d: measure_main(d, nodes, repeats, check, rng), 3)
            for d in DESCRIPTIONS}
    rows: dict[str, dict[str, list[dict[str, Any]]]] = {}
    for variant in ("grow", "refine") if refine else ("grow",):
        for description in DESCRIPTIONS:
            measured = quiet.measure(lambda v=variant, d=description: measure_series(
                v, d, scaling_nodes, repeats, rng), 1)
            for name, series in measured.items():
                rows.setdefault(name, {})[description] = series
    info["loadavg_end"] = os.getloadavg()[0]
    info["other_processes_cpus"] = meter.value()
    return {"machine": info, "code": code_version(), "nodes": nodes,
            "scaling_nodes": scaling_nodes,
            "repeats": repeats, "seed": seed, "brute_force_sample": check,
            "patch_edge_mm": {d: cell_edge(d) for d in DESCRIPTIONS},
            "min_radius_of_curvature_mm": min_radius_of_curvature(), "main": main,
            "scaling": fit_scaling(rows), "runtime_s": time.perf_counter() - start,
            "waited_s": quiet.waited, "wait_quiet_s": quiet.timeout,
            "wait_budget_s": quiet.budget}


# --------------------------------------------------------------------------- report


def fmt(value: float) -> str:
    """A rate with thousands separators."""
    return f"{value:,.0f}"


def throughput_table(numbers: dict[str, Any]) -> str:
    """Markdown: projections and nodes per second on 1 and 2 threads."""
    lines = ["| description | patches | projections per node | projections/s, 1 thread "
             "| projections/s, 2 threads | nodes/s, 1 thread | nodes/s, 2 threads "
             "| speed-up, paired / best | CPU time / wall time, 2 threads "
             "| other load [CPUs] |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, r in numbers["main"].items():
        lines.append(
            f"| {name} | {r['patches']} | {r['candidates_per_node']:.2f} "
            f"| {fmt(r['1']['projections_per_s'])} | {fmt(r['2']['projections_per_s'])} "
            f"| {fmt(r['1']['nodes_per_s'])} | {fmt(r['2']['nodes_per_s'])} "
            f"| {r['speedup']:.2f}x / {r['speedup_best_of']:.2f}x "
            f"| {r['cpus_obtained_2_threads']:.2f} "
            f"| {r['other_processes_cpus']:.2f} |")
    return "\n".join(lines)


def search_table(numbers: dict[str, Any]) -> str:
    """Markdown: the time to search the nodes, set-up and query, iterations, accuracy."""
    lines = ["| description | set-up [ms] | query, 1 thread [ms] | query, 2 threads [ms] "
             "| set-up + query, 1 / 2 threads [ms] | query, 1 thread, CPU time [ms] "
             "| mean Newton iterations | inside / edge / none | misses "
             "| max / mean error [um] |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, r in numbers["main"].items():
        s = r["status"]
        lines.append(
            f"| {name} | {r['setup_s'] * 1e3:.1f} | {r['1']['query_s'] * 1e3:.0f} "
            f"| {r['2']['query_s'] * 1e3:.0f} | {r['search_s']['1'] * 1e3:.0f} / "
            f"{r['search_s']['2'] * 1e3:.0f} | {r['1']['query_cpu_s'] * 1e3:.0f} "
            f"| {r['mean_iterations']:.2f} | {s['inside']} / {s['edge']} / {s['none']} "
            f"| {r['misses']} of {r['brute_force_sample']} "
            f"| {r['max_distance_error_um']:.2f} / {r['mean_distance_error_um']:.3f} |")
    return "\n".join(lines)


def split_table(numbers: dict[str, Any]) -> str:
    """Markdown: global and local search per node (1 thread, CPU time)."""
    lines = ["| description | query [us/node] | global search [us/node] "
             "| local search [us/node] | local share | one Newton iteration [ns] "
             "| model build [ms] |", "|---|---:|---:|---:|---:|---:|---:|"]
    for name, r in numbers["main"].items():
        sp, k = r["split_1_thread_cpu"], r["nodes"]
        lines.append(
            f"| {name} | {sp['query_s'] / k * 1e6:.2f} | {sp['global_s'] / k * 1e6:.2f} "
            f"| {sp['local_s'] / k * 1e6:.2f} | {100 * sp['local_s'] / sp['query_s']:.0f} % "
            f"| {sp['ns_per_newton_iteration']:.0f} | {r['model_build_s'] * 1e3:.0f} |")
    return "\n".join(lines)


def scaling_table(numbers: dict[str, Any], name: str) -> str:
    """Markdown: one node set of the scaling study, every description and tool size."""
    lines = ["| description | patches | tool side [mm] | set-up [ms] | query [us/node] "
             "| query, CPU time [us/node] | mean Newton iterations | projections per node "
             "| one-node call [us] | model build [ms] | other load [CPUs] |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for description, entry in numbers["scaling"][name].items():
        for r in entry["rows"]:
            lines.append(
                f"| {description} | {r['patches']} | {r['side_mm']:.0f} "
                f"| {r['setup_s'] * 1e3:.1f} | {r['query_us_per_node']:.2f} "
                f"| {r['query_cpu_us_per_node']:.2f} | {r['mean_iterations']:.2f} "
                f"| {r['candidates_per_node']:.2f} | {r['one_node_call_us']:.0f} "
                f"| {r['model_build_s'] * 1e3:.0f} "
                f"| {r['other_processes_cpus']:.2f} |")
    return "\n".join(lines)


def slope_table(numbers: dict[str, Any]) -> str:
    """Markdown: fitted log-log slopes of the query and set-up times."""
    names = list(numbers["scaling"])
    head = " | ".join(f"query, {n} (wall / CPU)" for n in names)
    lines = [f"| description | {head} | one-node call (grow) | set-up (grow) "
             "| model build (grow) |", "|---|" + "---:|" * (len(names) + 3)]
    for description in DESCRIPTIONS:
        cells = [f"{numbers['scaling'][n][description]['query_slope']:+.3f} / "
                 f"{numbers['scaling'][n][description]['query_cpu_slope']:+.3f}" for n in names]
        first = numbers["scaling"][names[0]][description]
        lines.append(f"| {description} | {' | '.join(cells)} | {first['one_node_slope']:+.2f} "
                     f"| {first['setup_slope']:+.2f} "
                     f"| {first['build_slope']:+.2f} |")
    return "\n".join(lines)


def findings(numbers: dict[str, Any]) -> list[str]:
    """Anomalies in plain words: poor 2-thread speed-up, slow descriptions, misses, growth."""
    main, text = numbers["main"], []
    for name, r in main.items():
        if r["speedup"] < 1.6:
            load = r["other_processes_cpus"]
            serial = 100 * r["one_node_call_us"] * 1e-6 / r["1"]["query_s"]
            cause = (f"other processes used {load:.2f} of the {numbers['machine']['nproc']} "
                     f"CPUs meanwhile and the query got {r['cpus_obtained_2_threads']:.2f} "
                     "CPUs of CPU time per second, so a thread shared its CPU; the work "
                     "itself parallelizes (independent nodes, dynamic schedule; the fixed "
                     f"cost of a call, {r['one_node_call_us']:.0f} us, is {serial:.2f} % of "
                     "the 1-thread query)" if load > 0.1 else
                     "no other load was measured and the query kept "
                     f"{r['cpus_obtained_2_threads']:.2f} CPUs busy, so no thread waited on a "
                     f"serial part (the fixed cost of a call, {r['one_node_call_us']:.0f} us, "
                     f"is {serial:.2f} % of the 1-thread query): the two threads slow each "
                     "other down in what the CPUs share (cache, memory bandwidth)")
            text.append(f"2-thread speed-up of {name}: {r['speedup']:.2f}x (below 1.6x); "
                        f"{cause}.")
    shares = {n: r["split_1_thread_cpu"] for n, r in main.items()}
    glob = [100 * s["global_s"] / s["query_s"] for s in shares.values()]
    text.append(f"The global search, not the Newton iterations, is most of a query: "
                f"{min(glob):.0f} to {max(glob):.0f} % of the 1-thread CPU time.")
    cost = {n: s["query_s"] / r["nodes"] for (n, s), r in zip(shares.items(), main.values(),
                                                              strict=True)}
    fastest = min(cost, key=cost.__getitem__)
    for name, c in cost.items():
        if c > 1.5 * cost[fastest]:
            sp, fast = shares[name], shares[fastest]
            k = main[name]["nodes"]
            text.append(
                f"{name} costs {c / cost[fastest]:.1f}x the CPU time per node of {fastest}: "
                f"global search {sp['global_s'] / k * 1e6:.1f} against "
                f"{fast['global_s'] / k * 1e6:.1f} us/node, local search "
                f"{sp['local_s'] / k * 1e6:.1f} against {fast['local_s'] / k * 1e6:.1f} us/node "
                f"({sp['ns_per_newton_iteration']:.0f} against "
                f"{fast['ns_per_newton_iteration']:.0f} ns per Newton iteration).")
    for name, r in main.items():
        if r["misses"] or r["status"]["none"]:
            text.append(f"{name}: {r['misses']} misses against brute force, "
                        f"{r['status']['none']} nodes without a patch.")
    for node_set, by_description in numbers["scaling"].items():
        for description, entry in by_description.items():
            rows = entry["rows"]
            if min(entry["query_slope"], entry["query_cpu_slope"]) > SLOPE_LIMIT:
                text.append(
                    f"Scaling, {node_set}: the query cost of {description} grows with slope "
                    f"{entry['query_slope']:.2f} (CPU time {entry['query_cpu_slope']:.2f}; "
                    f"{rows[0]['query_cpu_us_per_node']:.1f} to "
                    f"{rows[-1]['query_cpu_us_per_node']:.1f} us/node CPU from "
                    f"{rows[0]['patches']} to {rows[-1]['patches']} patches; projections per "
                    f"node {rows[0]['candidates_per_node']:.2f} to "
                    f"{rows[-1]['candidates_per_node']:.2f}).")
            if node_set == "window" and entry["one_node_slope"] > 0.3:
                text.append(
                    f"The fixed cost of one `project` call grows with the tool: "
                    f"{description}, one node, {rows[0]['one_node_call_us']:.0f} us at "
                    f"{rows[0]['patches']} patches, {rows[-1]['one_node_call_us']:.0f} us at "
                    f"{rows[-1]['patches']} (slope {entry['one_node_slope']:.2f}). Not the "
                    "1-based index arrays: `ContactSearch` makes them once (they were "
                    "temporaries as large as the spatial index, made on every call, before "
                    "docs/benchmarks/forming_iteration.md).")
            if any(r["none"] for r in rows):
                text.append(f"Scaling, {node_set}: {description} left nodes without a patch.")
    return text


def report(numbers: dict[str, Any], figures: tuple[Path, Path]) -> str:
    """The Markdown page."""
    m, main = numbers["machine"], numbers["main"]
    nodes = numbers["nodes"]
    pen = next(iter(main.values()))["penetrating_nodes"]
    edges = numbers["patch_edge_mm"]
    found_text = "\n".join(f"* {line}" for line in findings(numbers))
    refine = "refine" in numbers["scaling"]
    bez, nq, nt = (cells_for(d, PATCHES) for d in DESCRIPTIONS[:3])
    triangles = main["Nagata triangles"]["patches"]
    gaps = (GAP_MEAN - GAP_WAVE - GAP_NOISE, GAP_MEAN + GAP_WAVE + GAP_NOISE)
    quads = [SIDE / cells_for("Nagata quads", p) for p in SCALING_PATCHES]
    window = [e["rows"] for e in numbers["scaling"]["window"].values()]
    sides = (min(rows[0]["side_mm"] for rows in window),
             max(rows[-1]["side_mm"] for rows in window))
    per_patch = [numbers["scaling_nodes"] / p for p in (SCALING_PATCHES[0],
                                                        SCALING_PATCHES[-1])]
    args = (f" --wait-quiet {numbers['wait_quiet_s']:g} --wait-budget "
            f"{numbers['wait_budget_s']:g}" if numbers["wait_quiet_s"] else "")
    refine_text = (
        f"* **refine**: the {SIDE:g} mm die itself in ever smaller patches ({quads[0]:.2g} mm "
        f"down to {quads[-1]:.2g} mm),\n"
        "  the nodes over all of it, the gaps scaled with the patch size: the node distribution\n"
        "  relative to the patches is the same, as when a CAD surface is meshed finer.\n"
        if refine else "")
    refine_section = f"\n### refine\n\n{scaling_table(numbers, 'refine')}\n" if refine else ""
    return f"""# Contact search: throughput, search time and scaling

{computed_at(numbers.get("code", ""))}

Generated by `benchmarks/contact_search/run.py{args}` in {numbers['runtime_s']:.0f} s
({numbers['waited_s']:.0f} s of it waiting for other processes to go idle).
Machine: `nproc` = {m['nproc']}, CPU {m['cpu_model']}, numpy {m['numpy']}, Python
{m['python']}, ddpy {m['ddpy']}. The machine is shared: the CPUs used by other processes
during each measurement are in the "other load" columns (on average
{m['other_processes_cpus']:.2f} CPUs over the run; load average {m['loadavg_start']:.2f} at
the start, {m['loadavg_end']:.2f} at the end). Wall times on a loaded machine are too long;
the CPU time of a 1-thread run is not, so it is given next to them (it counts every thread
of the process, so the idle OpenMP thread still spinning after a 2-thread run can put it a
few % above the wall time).

## What is measured

* Tool: the die z = 10 sin(2 pi x / 100) cos(2 pi y / 100) + 4 sin(2 pi (x + y / 2) / 60)
  (mm) over 200 x 200 mm: two crossing waves, smallest radius of curvature
  {numbers['min_radius_of_curvature_mm']:.1f} mm, with inflexion lines. Four descriptions
  with about {PATCHES} patches of equal area:
  * Bezier bicubic: {bez} x {bez} patches, each the bicubic Hermite interpolant of f, f_x, f_y,
    f_xy at its corners written as a 4 x 4 Bernstein net (C1 across patches, error O(h^4)),
    patch edge {edges['Bezier bicubic']:.2f} mm;
  * Nagata quads: the {nq} x {nq} grid of vertices on the die with its exact normals;
  * Nagata triangles: a {nt} x {nt} grid (edge {edges['Nagata triangles']:.2f} mm), each cell
    split in two: {triangles:,} triangles;
  * facets (quads): the Nagata quad mesh with `smooth=False` (bilinear facets).
* Nodes: {nodes:,} nodes like a blank: a jittered grid in mesh order over the die (1 mm plus
  the largest gap from its edge), each node offset along the exact normal by a gap from
  {gaps[0]:g} to {gaps[1]:g} mm (a smooth field plus noise; {pen} nodes, {100 * pen / nodes:.1f} %,
  penetrate). The gap is below the radius of curvature, so it is the exact signed distance:
  the error below is |distance found - gap|, the model's shape error where the node
  projects.
* Set-up: `ContactSearch(surface)`: grid on every patch (the starts of the local search),
  bounds of every patch and their tree. Query: `project(points)` (no node normals). One
  projection is one local search (Newton) on one patch; the exact global search projects
  on the patches whose bound is below the nearest distance found (docs/theory/contact.md);
  projections per node is `candidates.mean()`. Best of {numbers['repeats']} after a
  warm-up, 1 and 2 core threads (`ddpy.core.parallel.threads`) interleaved. Misses: nodes of a
  random sample of {numbers['brute_force_sample']} whose closest point is farther than the
  one of `project(..., brute_force=True)` (every patch projected on).

## Projections and nodes per second

Rates from the best time of each. Speed-up, paired: the median over the rounds of the
1-thread over the 2-thread time of the same round (they run next to each other, so they see
the same speed of the machine, which drifts); best: the ratio of the best times. CPU time /
wall time: the CPUs the 2-thread query kept busy (2 = both, all the time).

{throughput_table(numbers)}

![throughput]({figures[0].name})

## Searching {nodes:,} nodes against the {PATCHES}-patch tool

{search_table(numbers)}

The set-up is done once per tool (or when its mesh changes), the query at every contact
check. Inside / edge / none: the closest point is inside a patch, held on a patch boundary
(facets: nodes above a convex edge), or not found.

### Where the time of a query goes (1 thread, CPU time)

The global search (the walk through the tree of patch bounds, the nearest grid point of
each patch projected on) hardly depends on the Newton iterations, so the query is also run
with Newton capped at one iteration and forced to up to twelve (`max_iterations=1`;
`max_iterations=12, tol=0`: many stop earlier, on a zero step) on nearly the same patches
(the search stops on the distance found, which a projection cut short overestimates a
little). Their difference in each round gives the cost of one iteration (an evaluation
with second derivatives and a 2 x 2 solve); the local search is that cost times
(iterations + one final evaluation) per projection, as a share of the query of the same
round (median over the rounds); the global search is the rest of the query (with the
Python and f2py call overhead). CPU times, because a difference of two wall
times on a loaded machine is mostly noise; still expect the split to scatter. Model build is
the construction of the surface object (`BezierSurface(nets)` / `NagataSurface(...)`), not
part of the set-up.

{split_table(numbers)}

## Scaling with the number of patches

The cost of one query (time of `project` per node, 1 thread, {numbers['scaling_nodes']:,}
nodes) for tools of about 10^2, 10^3, 10^4 and 10^5 patches, every description. The four
tools of a series are built first and timed in interleaved rounds (best of
{numbers['repeats']}): the speed of this virtual machine drifts over tens of seconds even
when no other process runs, and interleaving keeps that drift out of the slopes.

* **window** (grow): patches of the size of the main case on a die that grows with their
  number ({sides[0]:.0f} mm to {sides[1]:.0f} mm a side), the nodes always over the same
  {sides[0]:.0f} x {sides[0]:.0f} mm corner (the whole {SCALING_PATCHES[0]}-patch tool): node
  distribution and geometry seen by the nodes are fixed, only
  the tool grows. This is the algorithmic cost the issue asks about.
* **spread** (grow): the same tools, the nodes over the whole tool, from
  {per_patch[0]:g} nodes per patch down to {per_patch[1]:g}: adds the memory traffic of a
  large tool (cache misses).
{refine_text}* One-node call: the wall time of `project` with a single node (best of 30), i.e. the
  fixed cost of a call whatever the batch size. Projections per node: local searches per
  node, the patches whose bound is below the nearest distance found.

![scaling]({figures[1].name})

Fitted slopes of log(time) over log(patches) (0: independent of the tool size, 1: linear):

{slope_table(numbers)}

### window

{scaling_table(numbers, 'window')}

### spread

{scaling_table(numbers, 'spread')}
{refine_section}
## Findings

{found_text}
"""


def plot_main(numbers: dict[str, Any], path: Path) -> None:
    """(a) projections/s per description and thread count; (b) time to search the nodes."""
    from matplotlib.figure import Figure

    main = numbers["main"]
    names = list(main)
    x = np.arange(len(names))
    fig = Figure(figsize=(11, 4.4), layout="constrained")
    ax, bx = fig.subplots(1, 2)
    width = 0.38
    for offset, n, color in ((-width / 2, 1, "tab:blue"), (width / 2, 2, "tab:orange")):
        values = [main[name][str(n)]["projections_per_s"] / 1e6 for name in names]
        ax.bar(x + offset, values, width, color=color, label=f"{n} thread{'s' * (n > 1)}")
    for i, name in enumerate(names):
        ax.annotate(f"{main[name]['speedup']:.2f}x",
                    (x[i] + width / 2, main[name]["2"]["projections_per_s"] / 1e6),
                    ha="center", va="bottom", fontsize=9)
    ax.set_xticks(x, names, rotation=20, ha="right")
    ax.set_ylabel("projections per second [millions]")
    ax.set_title("(a) ~5,000-patch tool; label: 2-thread speed-up (paired)")
    ax.legend(loc="lower right")

    parts = (("setup", "set-up (1 thread)", "tab:gray"),
             ("global", "query: global search (CPU time)", "tab:blue"),
             ("local", "query: local search (CPU time)", "tab:green"))
    bottom = np.zeros(len(names))
    for key, label, color in parts:
        ms = np.array([1e3 * (main[n]["setup_s"] if key == "setup"
                              else main[n]["split_1_thread_cpu"][f"{key}_s"]) for n in names])
        bx.bar(x - width / 2, ms, width, bottom=bottom, color=color, label=label)
        bottom += ms
    bx.bar(x + width / 2, [1e3 * main[n]["search_s"]["2"] for n in names], width,
           color="tab:orange", label="set-up + query, 2 threads (wall)")
    bx.set_xticks(x, names, rotation=20, ha="right")
    bx.set_ylabel("time [ms]")
    bx.set_title(f"(b) searching {numbers['nodes']:,} nodes: 1 thread (left), 2 threads")
    bx.legend(fontsize=8, loc="upper right")
    bx.set_ylim(top=bx.get_ylim()[1] * 1.3)
    fig.savefig(path, dpi=100)


def plot_scaling(numbers: dict[str, Any], path: Path) -> None:
    """Query time per node against patches (log-log), one panel per node set; set-up."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import FuncFormatter

    plain = FuncFormatter(lambda value, _: f"{value:g}")
    node_sets = list(numbers["scaling"])
    fig = Figure(figsize=(11, 8.2), layout="constrained")
    axes = fig.subplots(2, 2).ravel()
    colors = dict(zip(DESCRIPTIONS, ("tab:red", "tab:blue", "tab:green", "tab:purple"),
                      strict=True))
    top = max(r["query_us_per_node"] for by in numbers["scaling"].values()
              for e in by.values() for r in e["rows"])
    bottom = min(r["query_cpu_us_per_node"] for by in numbers["scaling"].values()
                 for e in by.values() for r in e["rows"])
    titles = {"window": "nodes over a fixed window", "spread": "nodes over the whole tool",
              "refine": "fixed 200 mm die, finer patches"}
    for ax, node_set in zip(axes, node_sets, strict=False):
        for description, entry in numbers["scaling"][node_set].items():
            rows = entry["rows"]
            n = [r["patches"] for r in rows]
            ax.plot(n, [r["query_us_per_node"] for r in rows], "-o", color=colors[description],
                    label=f"{description}: {entry['query_slope']:+.2f} "
                          f"(CPU {entry['query_cpu_slope']:+.2f})")
            ax.plot(n, [r["query_cpu_us_per_node"] for r in rows], ":", marker=".",
                    color=colors[description])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylim(bottom / 1.3, top * 1.8)
        ax.yaxis.set_major_formatter(plain)
        ax.yaxis.set_minor_formatter(plain)
        ax.tick_params(axis="y", which="minor", labelsize=7)
        ax.set_xlabel("patches")
        ax.set_ylabel("query time per node [us], 1 thread")
        ax.set_title(f"{node_set}: {titles[node_set]}\n(solid: wall, dotted: CPU time; "
                     "legend: slope)", fontsize=10)
        ax.legend(fontsize=7.5, loc="upper left")
        ax.grid(True, which="both", alpha=0.3)
    bx = axes[len(node_sets)]
    for description in DESCRIPTIONS:
        for node_set, line in (("window", "-o"), ("refine", "--^")):
            if node_set not in numbers["scaling"]:
                continue
            entry = numbers["scaling"][node_set][description]
            rows = entry["rows"]
            bx.plot([r["patches"] for r in rows], [1e3 * r["setup_s"] for r in rows], line,
                    color=colors[description],
                    label=f"{description}, {'grow' if node_set == 'window' else node_set}: "
                          f"{entry['setup_slope']:.2f}")
    n = np.array(SCALING_PATCHES, dtype=float)
    last = numbers["scaling"]["window"][DESCRIPTIONS[0]]["rows"][-1]["setup_s"] * 1e3
    bx.plot(n, last * n / n[-1], color="black", linewidth=0.8, linestyle=":", label="slope 1")
    bx.set_xscale("log")
    bx.set_yscale("log")
    bx.set_xlabel("patches")
    bx.set_ylabel("set-up time [ms]")
    bx.yaxis.set_major_formatter(plain)
    bx.set_title("set-up: ContactSearch(surface) (legend: slope)", fontsize=10)
    bx.legend(fontsize=7, ncol=2)
    bx.grid(True, which="both", alpha=0.3)
    for ax in axes[len(node_sets) + 1:]:
        ax.set_visible(False)
    fig.savefig(path, dpi=100)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; print JSON (``--json``) or write the report and the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true",
                        help="print only the numbers as JSON and write nothing")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT,
                        help=f"folder for the report and the figures (default {DEFAULT_OUT})")
    parser.add_argument("--nodes", type=int, default=30_000, help="nodes of the main case")
    parser.add_argument("--scaling-nodes", type=int, default=10_000,
                        help="nodes of each scaling query")
    parser.add_argument("--repeats", type=int, default=3, help="timed runs (best is kept)")
    parser.add_argument("--check", type=int, default=100,
                        help="nodes checked against brute force per description")
    parser.add_argument("--no-refine", action="store_true",
                        help="skip the refined-die scaling (shorter run)")
    parser.add_argument("--seed", type=int, default=20140101, help="random seed")
    parser.add_argument("--wait-quiet", type=float, default=0.0, metavar="SECONDS",
                        help="before each measurement wait up to SECONDS for other processes "
                             "to go idle, and measure again (once) if they disturbed it")
    parser.add_argument("--wait-budget", type=float, default=120.0, metavar="SECONDS",
                        help="total time spent waiting with --wait-quiet (default 120)")
    parser.add_argument("--render", type=Path, default=None, metavar="JSON",
                        help="write the report and figures from numbers saved with --json "
                             "instead of measuring")
    args = parser.parse_args(argv)

    if args.render is not None:
        numbers = json.loads(args.render.read_text(encoding="utf-8"))
    else:
        numbers = run(args.nodes, args.scaling_nodes, args.repeats, args.check, args.seed,
                      not args.no_refine, Quiet(args.wait_quiet, args.wait_budget))
    if args.json:
        print(json.dumps(numbers))
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    figures = (args.out / "contact_search.png", args.out / "contact_search_scaling.png")
    plot_main(numbers, figures[0])
    plot_scaling(numbers, figures[1])
    path = args.out / "contact_search.md"
    path.write_text(report(numbers, figures), encoding="utf-8")
    print(throughput_table(numbers))
    print()
    print(search_table(numbers))
    print()
    print(slope_table(numbers))
    for line in findings(numbers):
        print("*", line)
    print(f"wrote {figures[0]}, {figures[1]} and {path} in {numbers['runtime_s']:.1f} s",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
