"""The Numisheet'93 square cup: benchmarks/square_cup/make_case.py and the built-in case
`ddpy run square-cup`.

- make_case writes, for both materials, every blank and every tool model, decks that
  `ddpy check` accepts, with the benchmark's quarter of the blank-holder force;
- the built-in case is what make_case --default-case writes from the CAD model (as the other
  built-in cases are checked);
- a short run of the built-in case: at every converged increment the force-controlled
  blank-holder carries the deck's force, to the Newton tolerance.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ddpy.app.cli import main
from ddpy.app.runner import BUILT_IN_CASES, RESULTS, run_case
from ddpy.io.case import HoldForce
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader
from ddpy.io.toolfile import read_tool

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks" / "square_cup"
sys.path.insert(0, str(BENCH.parent))  # the benchmarks' shared module
from bench_common import load_module  # noqa: E402

CASE = BUILT_IN_CASES["square-cup"]


@pytest.fixture(scope="module")
def make_case() -> Any:
    return load_module(BENCH / "make_case.py", "square_cup_make_case")


@pytest.fixture(scope="module")
def default_case(make_case: Any, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """make_case.py --default-case, written into a fresh folder."""
    folder = tmp_path_factory.mktemp("square_cup") / "default"
    assert make_case.main(["--default-case", str(folder)]) == 0
    return folder


def _holder_force(case: Path) -> float:
    """The force of the deck's force-controlled blank-holder (N)."""
    (phase,) = read_case(case).phases
    motion = phase.motion("holder")
    assert isinstance(motion, HoldForce)
    return float(motion.force)


def test_make_case_writes_decks_that_ddpy_check_accepts(make_case: Any, default_case: Path,
                                                         tmp_path: Path) -> None:
    """Every material, blank and tool model: the decks read, the blank is the quarter of the
    150 mm square of the material's thickness, the holder is pressed with a quarter of
    19.6 kN, and `ddpy check` (with the tools placed against the blank) accepts a coarse
    case of each material. The Bezier files are built; the
    mesh models take the built-in case's Nagata files under their names (a Nagata file
    serves as facets too): the facets' own files take a minute to build and do not change
    the decks."""
    tools = tmp_path / "tools"
    make_case.build_tools(tools, models=("bezier",))
    for tool in make_case.TOOLS:
        for model in make_case.MODELS[1:]:
            file = make_case.TOOL_FILES[model][0]
            (tools / f"{tool}.{file}.tool").write_bytes(
                (default_case / "tools" / f"{tool}.nagata.tool").read_bytes())
    # Every case is written; one model per material and blank is read (a case reads in
    # about half a second; the models differ only in tools.dat), every model once or more.
    for i, material in enumerate(make_case.MATERIALS):
        sheet = make_case.SHEETS[material]
        for j, mesh in enumerate(make_case.MESHES):
            for k, model in enumerate(make_case.MODELS):
                folder = make_case.write_case(tmp_path / "cases" / material / mesh / model,
                                              material, model, mesh)
                if k != (i + j) % len(make_case.MODELS):
                    continue
                case = read_case(folder)
                assert np.ptp(case.mesh.nodes, axis=0) == pytest.approx(
                    [75.0, 75.0, sheet.thickness])
                assert _holder_force(folder) == pytest.approx(19.6e3 / 4)
                assert case.phases[0].output_at == pytest.approx([15.0, 40.0])
                if mesh == "coarse":
                    assert main(["check", str(folder)]) == 0, folder


def test_built_in_case_is_make_case_default_output(default_case: Path) -> None:
    """`ddpy run square-cup` runs ddpy/cases/square_cup: it must be what make_case.py
    --default-case writes from the CAD model (decks to the byte, tool files to 1e-9 mm, as
    gmsh's last digits may differ between machines), every file listed in meson.build."""
    names = sorted(p.relative_to(default_case).as_posix() for p in default_case.rglob("*")
                   if p.is_file())
    assert names == sorted(p.relative_to(CASE).as_posix() for p in CASE.rglob("*")
                           if p.is_file())
    meson = (ROOT / "meson.build").read_text()
    for name in names:
        assert f"'ddpy/cases/square_cup/{name}'" in meson, name
        if name.endswith(".tool"):
            a, b = read_tool(default_case / name), read_tool(CASE / name)
            assert (a.name, a.description) == (b.name, b.description), name
            assert np.array_equal(a.surface.faces, b.surface.faces), name
            for field in ("vertices", "corner_normals"):
                assert np.allclose(getattr(a.surface, field), getattr(b.surface, field),
                                   rtol=0.0, atol=1e-9), (name, field)
        else:
            assert (default_case / name).read_text() == (CASE / name).read_text(), name


def test_the_cli_knows_the_case_by_name() -> None:
    done = subprocess.run([sys.executable, "-m", "ddpy", "check", "square-cup"],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "Square cup (Numisheet'93)" in done.stdout
    assert "holder pressed on the blank with 4900 N along its axis" in done.stdout


def test_a_short_run_holds_the_deck_holder_force(tmp_path: Path) -> None:
    """The first increments of `ddpy run square-cup`: the punch moves down, and at every
    converged increment the blank-holder's reaction along z is the deck's force to the
    Newton tolerance (the force's equation is one row of the residual whose norm the loop
    brings below newton_force times the internal force's norm: 1e-3 of the force here)
    while its position is solved for (it moves)."""
    case = read_case(CASE)
    outcome = run_case(case, tmp_path / "out", max_increments=4, threads=1)
    assert outcome.status == "stopped", outcome.message
    with ResultsReader(tmp_path / "out" / RESULTS) as reader:
        history = reader.history()
        tools = list(reader.tools)
    assert len(history["travel"]) == 4
    assert np.all(np.diff(history["travel"]) > 0.0)
    holder = tools.index("holder")
    np.testing.assert_allclose(history["tool_force"][:, holder, 2], _holder_force(CASE),
                               rtol=1e-3)
    assert np.all(history["tool_displacement"][:, holder, 2] != 0.0)
