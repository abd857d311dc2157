"""``ddpy post`` and ``ddpy compare``: figures and tables from results files."""

from __future__ import annotations

import csv
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_runner import tiny_case

from ddpy.app.post import load_run
from ddpy.app.runner import RESULTS, run_case
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """The tiny case run to the end, and a second run stopped early."""
    base = tmp_path_factory.mktemp("post")
    case = read_case(tiny_case(base / "case"))
    assert run_case(case, base / "full").status == "completed"
    assert run_case(case, base / "part", max_increments=12).status == "stopped"
    return base / "case", base / "full", base / "part"


def cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "ddpy", *args], capture_output=True,
                          text=True, cwd=cwd)


def test_force_against_stroke_follows_the_lead_tool(runs: tuple[Path, Path, Path]) -> None:
    _, full, _ = runs
    run = load_run(full)
    with ResultsReader(full / RESULTS) as r:
        punch_z = r.tool_displacement("punch")[:, 2]
        punch_f = r.tool_force("punch")[:, 2]
    forming = run.forming
    assert forming.sum() == len(run.phase) - 4  # the 4 springback steps have no lead
    # The punch moves down (-z): stroke = -u_z over both forming phases, force = +F_z.
    np.testing.assert_allclose(run.stroke[forming], -punch_z[forming], atol=1e-12)
    np.testing.assert_allclose(run.force[forming], punch_f[forming], atol=1e-9)
    assert run.stroke[forming][-1] == pytest.approx(2.55)
    assert run.force[forming].max() > 0.0


def test_post_writes_figures_and_tables(runs: tuple[Path, Path, Path], tmp_path: Path) -> None:
    _, full, _ = runs
    done = cli("post", str(full), "--output", str(tmp_path))
    assert done.returncode == 0, done.stderr
    for name in ("force_stroke.png", "increments.png", "contact.png", "plastic_strain.png"):
        data = (tmp_path / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000, name
    with open(tmp_path / "increments.csv") as f:
        rows = list(csv.DictReader(f))
    run = load_run(full)
    assert len(rows) == len(run.phase)
    assert float(rows[-5]["stroke_mm"]) == pytest.approx(2.55)
    assert {"contact_punch", "contact_die", "contact_holder", "limit"} <= set(rows[0])
    with open(tmp_path / "phases.csv") as f:
        phases = list(csv.DictReader(f))
    assert [p["phase"] for p in phases] == ["draw", "free_draw", "springback"]
    assert sum(int(p["increments"]) for p in phases) == len(rows)
    summary = (tmp_path / "summary.md").read_text()
    assert "| draw | punch |" in summary and "status completed" in summary


def test_iterations_table_counts_each_place_in_an_increment(runs: tuple[Path, Path, Path],
                                                            tmp_path: Path) -> None:
    """iterations.csv: per phase, the increments reaching iteration k are those with at least
    k Newton iterations (the increments table's own count), and the iteration rows' columns
    averaged over them; summary.md carries the table."""
    _, full, _ = runs
    assert cli("post", str(full), "--output", str(tmp_path)).returncode == 0
    with open(tmp_path / "iterations.csv") as f:
        rows = list(csv.DictReader(f))
    with ResultsReader(full / RESULTS) as r:
        phase, iterations = r.curve("phase").astype(int), r.curve("iterations").astype(int)
        it = r.iterations()
        names = r.phases
    for p, name in enumerate(names):
        mine = [row for row in rows if row["phase"] == name]
        assert [int(row["iteration"]) for row in mine] == list(range(
            iterations[phase == p].max() + 1))
        for row in mine:
            k = int(row["iteration"])
            assert int(row["increments"]) == int((iterations[phase == p] >= k).sum())
        start = mine[0]
        assert float(start["mean_step"]) == 0.0 and float(start["mean_yield_switched"]) == 0.0
    # the first correction of the draw, against the rows themselves
    draw = (phase[it["increment"] - 1] == 0) & (it["iteration"] == 2)
    first = next(row for row in rows if row["phase"] == names[0] and row["iteration"] == "1")
    assert float(first["mean_yield_switched"]) == pytest.approx(
        it["yield_switched"][draw].mean())
    assert float(first["median_residual"]) == pytest.approx(
        np.median(it["residual_force"][draw]))
    summary = (tmp_path / "summary.md").read_text()
    assert "## Newton iterations by their place in an increment" in summary


def test_post_finds_the_results_of_a_case_folder_and_says_when_there_are_none(
        runs: tuple[Path, Path, Path], tmp_path: Path) -> None:
    case, full, _ = runs
    missing = cli("post", str(case))
    assert missing.returncode == 1 and "no results found" in missing.stderr
    # A case folder: its default output results/<name> under the working directory.
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / case.name).symlink_to(full)
    done = cli("post", str(case), "--output", "figures", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "figures" / "force_stroke.png").is_file()


def test_compare_overlays_runs_and_tabulates_them(runs: tuple[Path, Path, Path],
                                                  tmp_path: Path) -> None:
    _, full, part = runs
    done = cli("compare", str(full), str(part / RESULTS), "--output", str(tmp_path),
               "--labels", "full,part")
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stdout.splitlines() if line.startswith("| full")
             or line.startswith("| part")]
    assert len(lines) == 2
    assert "| part | stopped | 12 |" in lines[1]
    assert (tmp_path / "compare_force.png").read_bytes()[:4] == b"\x89PNG"
    with open(tmp_path / "compare.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["run"] for r in rows] == ["full", "part"]
    assert int(rows[0]["increments"]) > int(rows[1]["increments"]) == 12
    bad = cli("compare", str(full), "--labels", "a,b", "--output", str(tmp_path))
    assert bad.returncode == 2 and "2 labels for 1 runs" in bad.stderr


def test_plastic_strain_map_fills_its_frame(tmp_path: Path) -> None:
    # The map takes the blank's proportions: the quarter disc of the deep drawing case in a
    # wide, fixed frame left a third of the image empty.
    import matplotlib.image

    run = cli("run", "deep-drawing", "--output", str(tmp_path / "run"), "--stop-after", "2")
    assert run.returncode == 0, run.stderr
    done = cli("post", str(tmp_path / "run"), "--output", str(tmp_path / "post"))
    assert done.returncode == 0, done.stderr
    image = matplotlib.image.imread(tmp_path / "post" / "plastic_strain.png")[..., :3]
    inked = (image < 0.95).any(axis=2).any(axis=0)
    used = np.flatnonzero(inked)
    assert (used[-1] - used[0]) / image.shape[1] > 0.8
    assert (~inked[used[0]:used[-1]]).sum() < 0.15 * image.shape[1]  # no wide empty band


def test_summary_gives_the_forming_quantities_and_the_springback(
        runs: tuple[Path, Path, Path], tmp_path: Path) -> None:
    """summary.md: the largest plastic strain, the smallest thickness and largest thinning
    of the last frame, and the largest nodal displacement over the springback (from the
    free draw's last frame to the springback's), each as the results file has it."""
    _, full, part = runs
    assert cli("post", str(full), "--output", str(tmp_path)).returncode == 0
    summary = (tmp_path / "summary.md").read_text()
    with ResultsReader(full / RESULTS) as r:
        ep, t, t0 = r.field("plastic_strain"), r.field("thickness"), r.field("thickness", 0)
        frames = r.frames
        before = [f for f in frames if f.phase == 1][-1]
        moved = np.linalg.norm(r.field("displacement") - r.field("displacement", before.index),
                               axis=1)
    def number(label: str) -> float:
        return float(re.search(label + r": ([-0-9.e+]+)", summary).group(1))

    assert number("largest equivalent plastic strain") == pytest.approx(ep.max(), rel=1e-3)
    assert number("smallest thickness") == pytest.approx(t.min(), rel=1e-3)
    assert number("largest thinning") == pytest.approx(100 * ((t0 - t) / t0).max(), rel=1e-2)
    assert number(r"springback \(springback\), largest displacement of a node") == \
        pytest.approx(moved.max(), rel=1e-3)
    assert moved.max() > 0.0
    # the blank's volume change, at the end and at most, and the deepest penetration per
    # tool, as the results' columns have them
    with ResultsReader(full / RESULTS) as r:
        change, depth = r.curve("volume_change"), r.curve("penetration").max(axis=0)
        tools = [str(t) for t in r.attribute("tools")]
    assert number("the blank's volume") == pytest.approx(100 * change[-1], rel=1e-2)
    k = int(np.argmax(np.abs(change)))
    assert f"{100 * change[k]:+.3g} % at most (increment {k + 1})" in summary
    for name, d in zip(tools, depth, strict=True):
        assert f"{name} {d:.3g} mm" in summary, (name, d)
    assert depth.max() > 0.0 and np.abs(change).max() > 0.0
    # A run stopped before its springback has no springback line.
    assert cli("post", str(part), "--output", str(tmp_path / "part")).returncode == 0
    text = (tmp_path / "part" / "summary.md").read_text()
    assert "largest thinning" in text and "springback (" not in text
