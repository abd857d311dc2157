"""The reverse deep drawing benchmark end to end at ddpy's defaults, both stages.

The built-in case (`ddpy run deep-drawing`: the benchmark's coarse blank with Nagata tools
at the defaults, the solid-shell and Gauss-point contact with its barrier, its ``nagata``
case) takes about 5 minutes on 1 thread, too long for the suite. The run checked here is
its smaller variant (benchmarks/reverse_deep_drawing/make_case.py ``write_variant_case``):
the same tool files and decks, the blank meshed with the same 4 mm quadrilaterals in one
layer of solid-shells instead of two (the element is made for one layer; 384 elements
against 768). It is run through both stages with the case runner and checked twice:

- against the physics, independently of any earlier run: the blank has no support along z
  but the tools (its symmetry planes react along x and y only), so the tools' z reactions
  balance at every increment; plastic flow keeps the volume; the stage 1 peak force lies
  between the force that draws the flange without friction or bending at the initial yield
  stress and the force that tears the cup wall in plane strain, and within 30 % of Siebel's
  classical estimate; the stage 2 peak force likewise, and within 20 % of Siebel's estimate
  taken step by step along the reverse redraw's path (the first cup's wall over punch 1's
  nose, its diameter shrinking on punch 1's end ring, over die 2's edge); the flange's free
  edge is in uniaxial hoop compression, so its equivalent plastic strain is its hoop strain
  ln(r / R0); the cup's depth after stage 1 is the punch travel; no node sinks into a tool
  deeper than the barrier's 0.5 % of the thickness (#47's limit is 1 %);
- against stored reference values (tests/data/reverse_deep_drawing_reference.json): the punch
  force curves of both stages, the cup heights and flange radius, the plastic strain along a
  radial section and its maximum. The reference is a run of this same variant
  (``python tests/test_reverse_deep_drawing.py`` rewrites it, stating the commit), accepted
  because it passes the physical checks above and because its forces agree with the
  benchmark's coarse two-layer blank (docs/benchmarks/reverse_deep_drawing.md) within 5 %
  (test_the_peak_forces_agree_with_the_two_layer_blank); the tolerances below say how far
  a change may move it before it must explain why and renew the reference.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from test_examples import assert_converged_within_tolerances

from ddpy.app.runner import BUILT_IN_CASES, run_case
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader
from ddpy.io.toolfile import read_tool
from ddpy.model.solid import DEFAULT_ELEMENT
from ddpy.model.tool import BARRIER_DEPTH
from ddpy.studies.drawing import element_centroids, hexahedron_volumes

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks" / "reverse_deep_drawing"
sys.path.insert(0, str(BENCH.parent))  # the benchmarks' shared module
from bench_common import load_module  # noqa: E402

CASE = BUILT_IN_CASES["deep-drawing"]
#: The variant run here: the built-in case's 4 mm quadrilaterals in one layer.
VARIANT_SIZE, VARIANT_LAYERS = 4.0, 1
REFERENCE = Path(__file__).resolve().parent / "data" / "reverse_deep_drawing_reference.json"
#: Where the force curves are compared: fractions of each stage's travel.
SAMPLES = np.linspace(0.05, 1.0, 39)
#: Tolerances against the reference: force 3 % of the stage's largest force, within a
#: window of 0.5 mm of travel (a node landing on a tool moves the curve by a fraction of an
#: increment); lengths 0.3 mm; plastic strain 0.03 along the section and 5 % at its maximum;
#: increments and iterations 30 %.
FORCE_TOL, WINDOW, LENGTH_TOL, STRAIN_TOL, COUNT_TOL = 0.03, 0.5, 0.3, 0.03, 0.3
#: Radii (initial, mm) where the plastic strain along the section y = 0 is compared.
SECTION = np.linspace(5.0, 80.0, 16)


def _make_case() -> Any:
    return load_module(BENCH / "make_case.py", "drawing_make_case")


def _stage_curves(r: ResultsReader, history: dict[str, np.ndarray]
                  ) -> list[tuple[np.ndarray, np.ndarray]]:
    """(travel, force) of the lead punch in each stage; force positive when drawing."""
    curves = []
    for stage, punch, sign in ((0, "punch1", 1.0), (1, "punch2", -1.0)):
        rows = history["phase"] == stage
        curves.append((history["travel"][rows], sign * r.tool_force(punch)[rows][:, 2]))
    return curves


def read_numbers(results: Path) -> dict[str, Any]:
    """What the checks compare, from a run's results file."""
    with ResultsReader(results) as r:
        history = r.history()
        frames = r.frames
        ends = [max((f for f in frames if f.phase == s), key=lambda f: f.increment)
                for s in (0, 1)]
        elements = np.asarray(r.elements)
        nodes0 = r.nodes
        numbers: dict[str, Any] = {"increments": [int(np.sum(history["phase"] == s))
                                                  for s in (0, 1)],
                                   "iterations": [int(history["iterations"][history["phase"] == s]
                                                      .sum()) for s in (0, 1)]}
        curves = _stage_curves(r, history)
        numbers["curves"] = [(t.tolist(), f.tolist()) for t, f in curves]
        numbers["peak_force_N"] = [float(f.max()) for _, f in curves]
        numbers["tool_force_z"] = history["tool_force"][:, :, 2].tolist()
        numbers["penetration_mm"] = np.asarray(history["penetration"]).max(axis=1).tolist()
        shapes = [r.field("coordinates", f.index) for f in ends]
        numbers["volume_mm3"] = [float(hexahedron_volumes(x, elements).sum())
                                 for x in (nodes0, *shapes)]
        rho0 = np.hypot(nodes0[:, 0], nodes0[:, 1])
        edge = rho0 > 85.0 - 1e-6
        numbers["flange_radius_mm"] = [float(np.hypot(x[edge, 0], x[edge, 1]).mean())
                                       for x in shapes]
        numbers["cup_height_mm"] = [float(np.ptp(x[:, 2])) for x in shapes]
        centroid0 = element_centroids(nodes0, elements)
        strain = [r.field("plastic_strain", f.index) for f in ends]
        numbers["max_plastic_strain"] = [float(e.max()) for e in strain]
        # The section: elements whose centroid lies within 4 degrees of y = 0.
        angle = np.degrees(np.arctan2(centroid0[:, 1], centroid0[:, 0]))
        rho_c = np.hypot(centroid0[:, 0], centroid0[:, 1])
        near = angle < 4.0
        order = np.argsort(rho_c[near])
        numbers["section_strain"] = np.interp(SECTION, rho_c[near][order],
                                              strain[1][near][order]).tolist()
        # The outer ring of elements (centroid within 2 mm of the edge) after stage 1.
        ring = rho_c > 83.0
        numbers["edge_strain"] = float(strain[0][ring].mean())
        numbers["edge_hoop_strain"] = float(np.log(
            np.hypot(shapes[0][edge, 0], shapes[0][edge, 1]).mean() / 85.0))
        numbers["bottom_z_mm"] = float(shapes[0][:, 2].min())
        numbers["holder1_force_N"] = float(-r.tool_force("holder1")[history["phase"] == 0][:, 2]
                                           .max())
        numbers["holder2_force_N"] = float(np.abs(r.tool_force("holder2")[history["phase"] == 1]
                                                  [:, 2]).max())
    return numbers


def write_variant(folder: Path) -> Path:
    """The smaller variant of the built-in case that the suite runs."""
    return _make_case().write_variant_case(folder, VARIANT_SIZE, layers=VARIANT_LAYERS)


@pytest.fixture(scope="module")
def variant(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_variant(tmp_path_factory.mktemp("variant"))


@pytest.fixture(scope="module")
def numbers(tmp_path_factory: pytest.TempPathFactory, variant: Path) -> dict[str, Any]:
    out = tmp_path_factory.mktemp("deep_drawing")
    outcome = run_case(read_case(variant), out)
    return {"status": outcome.status, "message": outcome.message,
            "results": outcome.results, **read_numbers(outcome.results)}


@pytest.fixture(scope="module")
def reference() -> dict[str, Any]:
    return json.loads(REFERENCE.read_text())


def test_built_in_case_is_the_benchmark_coarse_nagata_case(tmp_path: Path) -> None:
    # `ddpy run deep-drawing` runs ddpy/cases/reverse_deep_drawing: it must be what
    # make_case.py --default-case writes from the CAD model (decks and mesh to the byte, tool
    # files to 1e-9 mm, as gmsh's last digits may differ between machines).
    built = _make_case().write_default_case(tmp_path / "default")
    names = sorted(p.relative_to(built).as_posix() for p in built.rglob("*") if p.is_file())
    assert names == sorted(p.relative_to(CASE).as_posix() for p in CASE.rglob("*")
                           if p.is_file())
    meson = (ROOT / "meson.build").read_text()
    for name in names:
        assert f"'ddpy/cases/reverse_deep_drawing/{name}'" in meson, name
        if name.endswith(".tool"):
            a, b = read_tool(built / name), read_tool(CASE / name)
            assert (a.name, a.description) == (b.name, b.description), name
            assert np.array_equal(a.surface.faces, b.surface.faces), name
            for field in ("vertices", "corner_normals"):
                assert np.allclose(getattr(a.surface, field), getattr(b.surface, field),
                                   rtol=0.0, atol=1e-9), (name, field)
        elif name != "mesh.msh":
            assert (built / name).read_text() == (CASE / name).read_text(), name
        else:  # gmsh's mesh: the same elements, nodes to 1e-9 mm
            import meshio

            a, b = meshio.read(built / name), meshio.read(CASE / name)
            assert np.allclose(a.points, b.points, rtol=0.0, atol=1e-9)
            assert [c.data.tolist() for c in a.cells] == [c.data.tolist() for c in b.cells]


def test_a_variant_is_the_built_in_case_on_another_blank(tmp_path: Path) -> None:
    # make_case.py --variant writes the smaller deep drawings measured for the test suite
    # (docs/theory/contact.md, "The barrier"): the built-in case's tool files and decks
    # (ddpy's defaults: no element, contact or barrier line), only the blank (here one layer
    # of 6 mm elements) and max_increment changed.
    made = _make_case()
    variant = made.write_variant_case(tmp_path / "variant", 6.0, layers=1, max_increment=1.0)
    for tool in (CASE / "tools").iterdir():
        assert (variant / "tools" / tool.name).read_bytes() == tool.read_bytes(), tool.name
    for name in ("tools.dat", "material.dat", "bc.dat"):
        assert (CASE / name).read_text() == made.DEFAULT_HEADER + (variant / name).read_text()
    for name in ("tools.dat", "mesh.dat"):
        keys = {line.split()[0] for line in (CASE / name).read_text().splitlines()
                if line.strip() and not line.startswith("#")}
        assert not keys & {"barrier", "discretization", "element"}, name
    built, small = read_case(CASE), read_case(variant)
    assert all(t.discretization == "gauss" and t.barrier == BARRIER_DEPTH for t in built.tools)
    assert built.element == small.element == DEFAULT_ELEMENT
    assert [(p.name, p.tools, p.travel, p.lead) for p in small.phases] == \
        [(p.name, p.tools, p.travel, p.lead) for p in built.phases]
    assert [p.max_increment for p in small.phases] == [1.0, 1.0]
    assert np.unique(small.mesh.nodes[:, 2].round(9)).tolist() == [0.0, made.THICKNESS]
    assert small.mesh.n_elements < built.mesh.n_elements / 2  # 1 layer, coarser quads


def test_the_cli_knows_the_case_by_name() -> None:
    done = subprocess.run([sys.executable, "-m", "ddpy", "check", "deep-drawing"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "Reverse deep drawing" in done.stdout and "phase stage2" in done.stdout


def test_both_stages_complete(numbers: dict[str, Any]) -> None:
    assert numbers["status"] == "completed", numbers["message"]
    assert all(n > 10 for n in numbers["increments"])


def test_every_increment_converged_within_its_phase_tolerances(numbers: dict[str, Any],
                                                               variant: Path) -> None:
    with ResultsReader(numbers["results"]) as r:
        history = r.history()
    assert_converged_within_tolerances(history, read_case(variant).phases)


def test_the_tools_balance_along_z(numbers: dict[str, Any]) -> None:
    # Newton stops at an out-of-balance force of 1e-4 of the internal force's norm; over
    # the blank's ~850 nodes that allows sums of the order of 1e-4 * sqrt(n) of the force.
    forces = np.asarray(numbers["tool_force_z"])
    scale = np.abs(forces).max(axis=1)
    assert np.all(np.abs(forces.sum(axis=1)) <= 5e-3 * scale + 1.0)


def test_the_nodes_volume_is_kept_to_the_coarse_solid_shells_bound(numbers: dict[str, Any]
                                                                     ) -> None:
    # Plastic flow keeps the volume and elastic strains change it by (1 - 2 nu) / E * mean
    # stress ~ 6e-4. The volume measured here is the trilinear hexahedra's through the nodes,
    # which the solid-shell's assumed strains do not hold to: elements bent over radii of one
    # or two element sizes lose it (the stage-2 wall, wrapped half a turn over punch 1's
    # nose, most). It shrinks with the element size: on the benchmark's two-layer blanks at
    # the end of stage 2, -5.0 % with 4 mm elements and -1.0 % with 2 mm
    # (docs/benchmarks/reverse_deep_drawing*.md, "Physical checks"). Measured here -1.7 % and
    # -4.4 %; a lost element or a wrong stress update loses far more.
    v0, v1, v2 = numbers["volume_mm3"]
    assert v0 == pytest.approx(math.pi * 85.0**2 / 4 * 0.98, rel=2e-3)  # the faceted disc
    assert -0.03 < v1 / v0 - 1 < 6e-4 and -0.06 < v2 / v0 - 1 < 6e-4


def test_no_node_sinks_into_a_tool_below_the_limit(numbers: dict[str, Any]) -> None:
    # #47's limit: 1 % of the thickness at every converged increment; the barrier holds
    # every node at 0.5 % (BARRIER_DEPTH), so the deepest is that, to Newton's tolerance.
    deepest = float(np.max(numbers["penetration_mm"]))
    assert deepest <= 0.01 * 0.98
    assert deepest == pytest.approx(BARRIER_DEPTH * 0.98, rel=0.05)


def test_the_peak_forces_agree_with_the_two_layer_blank(numbers: dict[str, Any]) -> None:
    # The benchmark's coarse blank (the built-in case: the same 4 mm quadrilaterals in two
    # layers), its kept run in docs/benchmarks/reverse_deep_drawing_runs.json. One layer's
    # two Gauss points through the thickness overrate the fully plastic bending moment by
    # 15 % (docs/theory/solid_shell.md), but the drawing force is mostly the flange's
    # drawing and friction: measured -1.1 % and -2.9 %.
    kept = json.loads((ROOT / "docs" / "benchmarks" / "reverse_deep_drawing_runs.json")
                      .read_text())["nagata"]["numbers"]["stages"]
    for stage, name in enumerate(("stage1", "stage2")):
        assert numbers["peak_force_N"][stage] == pytest.approx(kept[name]["max_force_N"],
                                                               rel=0.05), name


def test_stage1_peak_force_against_drawing_theory(numbers: dict[str, Any]) -> None:
    material = read_case(CASE).material.material
    K, eps0, n = material.hardening.K, material.hardening.eps0, material.hardening.n
    t, r0 = 0.98, 85.0
    dims = _make_case().DIMENSIONS
    throat = dims.die_bore + dims.die_shoulder           # where the flange enters the die
    wall = dims.punch1_radius + 0.5 * t                    # the cup wall's mid-surface
    quarter = math.pi / 2
    peak = numbers["peak_force_N"][0]
    # Lower: the flange drawn at the initial yield stress, no friction, no bending.
    lower = K * eps0**n * math.log(r0 / throat) * throat * t * quarter
    # Upper: the wall torn in plane strain at the Swift material's tensile strength.
    uts = K * n**n * math.exp(-n)                          # engineering, uniaxial
    upper = 2 / math.sqrt(3) * uts * wall * t * quarter * 1.15   # 15 %: anisotropy
    assert lower < peak < upper, (lower, peak, upper)
    # Siebel: flange (mean flow stress over a mean strain of half the edge's), friction
    # wrap on the die shoulder, the holder's friction (its measured force) and bending.
    mean_flow = K * (eps0 + 0.5 * math.log(r0 / wall)) ** n
    mu = 0.15
    stress = (1.1 * mean_flow * math.log(r0 / wall) * math.exp(mu * math.pi / 2)
              + 2 * mu * numbers["holder1_force_N"] / (quarter * wall * t)
              + mean_flow * t / (2 * dims.die_shoulder))
    siebel = stress * wall * t * quarter
    assert peak == pytest.approx(siebel, rel=0.3), (peak, siebel)


def test_stage2_peak_force_against_reverse_redraw_theory(numbers: dict[str, Any]) -> None:
    material = read_case(CASE).material.material
    K, eps0, n = material.hardening.K, material.hardening.eps0, material.hardening.n
    flow = lambda strain: K * (eps0 + strain) ** n  # noqa: E731
    t, mu, quarter = 0.98, 0.15, math.pi / 2
    dims = _make_case().DIMENSIONS
    cup1, cup2 = 2 * dims.punch1_radius + t, 2 * dims.punch2_radius + t  # mid-wall diameters
    peak = numbers["peak_force_N"][1]
    # Upper: the new wall torn in plane strain at the tensile strength, as for stage 1.
    uts = K * n**n * math.exp(-n)
    upper = 2 / math.sqrt(3) * uts * 0.5 * cup2 * t * quarter * 1.15
    lower = K * eps0**n * math.log(cup1 / cup2) * 0.5 * cup2 * t * quarter
    assert lower < peak < upper, (lower, peak, upper)
    # Siebel, step by step along the sheet's path: the first cup's wall comes in free of
    # tension and turns half a turn over punch 1's nose (bent in and out, k t / 4r each,
    # the first under the friction of that turn); its diameter shrinks on punch 1's end
    # ring (the ideal work at the mean flow stress of the redraw, the first draw's strain
    # at the wall before it; both faces' friction under blank-holder 2's measured force);
    # then a quarter turn over die 2's edge carries all of it under friction, and bends.
    strain1 = math.log(170.0 / cup1)
    strain2 = strain1 + math.log(cup1 / cup2)
    k_mean, k_bend = 0.5 * (flow(strain1) + flow(strain2)), flow(strain2)
    half_nose = k_bend * t / (4 * dims.punch1_nose)
    incoming = half_nose * math.exp(mu * math.pi) + half_nose
    ideal = 1.1 * k_mean * math.log(cup1 / cup2)
    holder = 2 * mu * 4 * numbers["holder2_force_N"] / (math.pi * cup1 * t)
    stress = (math.exp(mu * quarter) * (incoming + ideal + holder)
              + k_bend * t / (2 * dims.punch1_edge))
    siebel = stress * 0.5 * cup2 * t * quarter
    # Siebel's elementary theory is good to 10 or 20 % (as the benchmark's report says).
    assert peak == pytest.approx(siebel, rel=0.2), (peak, siebel)


def test_the_flange_edge_is_in_hoop_compression(numbers: dict[str, Any]) -> None:
    # At the free edge the stress is uniaxial along the hoop: its equivalent plastic strain
    # is |ln(r / R0)| (Hill'48 with these coefficients moves it by at most ~3 %), averaged
    # over the ring of edge elements (their centroids lie inside the edge: 10 % more).
    hoop = abs(numbers["edge_hoop_strain"])
    assert hoop > 0.1
    assert numbers["edge_strain"] == pytest.approx(hoop, rel=0.15)


def test_the_cup_depth_after_stage_1_is_the_punch_travel(numbers: dict[str, Any]) -> None:
    # The bottom follows punch 1's end ring (0.98 above the blank's bottom) down; inside
    # punch 1's bore it is free and sags a little under the radial tension (0.12 mm here).
    travel = _make_case().DIMENSIONS.stage1
    assert -travel - 0.3 < numbers["bottom_z_mm"] < -travel + 0.05


def _windowed_close(travel: np.ndarray, force: np.ndarray, ref_travel: np.ndarray,
                    ref_force: np.ndarray, tol: float) -> list[float]:
    """Reference points the curve misses: no point of it within WINDOW of travel comes
    within ``tol`` of the reference force."""
    missed = []
    for s, f in zip(ref_travel, ref_force, strict=True):
        near = np.abs(travel - s) <= WINDOW
        fine = np.linspace(max(s - WINDOW, travel[0]), min(s + WINDOW, travel[-1]), 21)
        values = np.concatenate([force[near], np.interp(fine, travel, force)])
        if not np.any(np.abs(values - f) <= tol):
            missed.append(float(s))
    return missed


def test_force_curves_match_the_reference(numbers: dict[str, Any], reference: dict[str, Any]
                                          ) -> None:
    for stage in (0, 1):
        travel, force = (np.asarray(a) for a in numbers["curves"][stage])
        ref_travel, ref_force = (np.asarray(a) for a in reference["force_samples"][stage])
        tol = FORCE_TOL * float(np.max(ref_force))
        assert numbers["peak_force_N"][stage] == pytest.approx(
            reference["peak_force_N"][stage], rel=FORCE_TOL)
        assert _windowed_close(travel, force, ref_travel, ref_force, tol) == []


def test_shape_and_strain_match_the_reference(numbers: dict[str, Any],
                                              reference: dict[str, Any]) -> None:
    for key in ("cup_height_mm", "flange_radius_mm"):
        assert np.allclose(numbers[key], reference[key], rtol=0.0, atol=LENGTH_TOL), key
    assert np.allclose(numbers["section_strain"], reference["section_strain"], rtol=0.0,
                       atol=STRAIN_TOL)
    assert np.allclose(numbers["max_plastic_strain"], reference["max_plastic_strain"],
                       rtol=0.05)
    for key in ("increments", "iterations"):
        assert np.allclose(numbers[key], reference[key], rtol=COUNT_TOL), key


def write_reference(results: Path | None = None) -> None:
    """Run the case (or read ``results``, a completed run of it) and store its reference
    values; the physical checks above must pass on it before it is committed."""
    import tempfile

    if results is not None:
        result = read_numbers(results)
    else:
        with tempfile.TemporaryDirectory() as scratch:
            folder = write_variant(Path(scratch) / "variant")
            outcome = run_case(read_case(folder), Path(scratch) / "run")
            assert outcome.status == "completed", outcome.message
            result = read_numbers(outcome.results)
    samples = []
    for travel, force in result["curves"]:
        s = SAMPLES * travel[-1]
        samples.append((s.round(4).tolist(), np.interp(s, travel, force).round(2).tolist()))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, cwd=ROOT).stdout.strip()
    data = {"about": "tests/test_reverse_deep_drawing.py: `ddpy run deep-drawing`, "
                     f"written at commit {commit}",
            "force_samples": samples,
            **{k: result[k] for k in ("peak_force_N", "cup_height_mm", "flange_radius_mm",
                                      "section_strain", "max_plastic_strain", "increments",
                                      "iterations")}}
    REFERENCE.write_text(json.dumps(data, indent=1) + "\n")
    print(f"wrote {REFERENCE}")


if __name__ == "__main__":
    write_reference(Path(sys.argv[1]) if len(sys.argv) > 1 else None)


def test_the_report_counts_the_effort_up_to_each_mm_of_travel(numbers: dict[str, Any],
                                                               variant: Path) -> None:
    # The benchmark's report compares runs that stopped over the travel they all reached
    # (claim (d) on the paper's blank): its counts up to each whole mm of punch travel
    # must be those of the increments that ended there.
    report = load_module(BENCH / "run.py", "drawing_run")
    run = report.from_results(Path(numbers["results"]), variant).numbers
    with ResultsReader(numbers["results"]) as r:
        history = r.history()
    for p, name in enumerate(report.STAGES):
        stage, mask = run["stages"][name], history["phase"] == p
        travel, iterations = history["travel"][mask], history["iterations"][mask]
        by_mm = stage["by_mm"]
        assert len(by_mm["increments"]) == math.floor(stage["travel_mm"] + 1e-9)
        for mm, (count, its) in enumerate(zip(by_mm["increments"], by_mm["iterations"],
                                              strict=True), start=1):
            ended = travel <= mm + 1e-9
            assert count == ended.sum() and its == iterations[ended].sum(), (name, mm)
    # Stage 1 ends at a whole mm (40): its last count is the stage's.
    first = run["stages"]["stage1"]
    assert first["by_mm"]["increments"][-1] == first["increments"]
    assert first["by_mm"]["iterations"][-1] == first["iterations"]
