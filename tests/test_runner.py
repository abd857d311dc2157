"""The case runner: phases to the results file, checkpoints and restart, ``ddpy run``."""

from __future__ import annotations

import dataclasses
import json
import logging
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from ddpy.app.runner import (
    CHECKPOINT,
    DEFAULT_CASE,
    RESULTS,
    Progress,
    RunError,
    read_status,
    run_case,
)
from ddpy.io.checkpoint import CheckpointError, read_checkpoint, write_checkpoint
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader
from ddpy.model.control import NewtonSettings

ROOT = Path(__file__).resolve().parents[1]


def tiny_case(folder: Path, draw: float = 2.05, max_increment: float = 0.2) -> Path:
    """examples/strip_draw with short strokes and 2 x 1 x 2 elements (the example has 10
    along the strip): three phases, a gap-held holder switched off in the second,
    output_at, springback in 4 steps. The draw is no multiple of the largest increment, so
    that its last increment lands on the phase end. (The run in full is
    tests/test_examples.py's.)"""
    shutil.copytree(ROOT / "examples" / "strip_draw", folder)
    (folder / "mesh.dat").write_text("normal z\nbox 50 4 1  2 1 2\n")
    bc = folder / "bc.dat"
    bc.write_text(re.sub(r"ids [\d ]+", "ids 1 4 7 10 13 16 ", bc.read_text()))
    control = folder / "control.dat"
    text = control.read_text()
    text = text.replace("move   punch  0 0 -10", f"move   punch  0 0 -{draw}\n  output_at 0.5 1")
    text = text.replace("move           punch  0 0 -5", "move           punch  0 0 -0.5")
    text = text.replace("max_increment  0.2", f"max_increment  {max_increment}")
    control.write_text(text)
    return folder


def dd3imp(case: Path) -> Path:
    """The case with DD3IMP's discretization: the mean-dilatation hexahedron (unless its
    mesh deck names an element) and node-to-surface contact on every tool."""
    mesh = case / "mesh.dat"
    if "element" not in mesh.read_text():
        mesh.write_text(mesh.read_text() + "element hexahedron\n")
    tools = case / "tools.dat"
    tools.write_text(re.sub(r"(?m)^end$", "  discretization node\nend", tools.read_text()))
    return case


def compare(a: Path, b: Path) -> None:
    """Two results files hold the same run: every column but the timings, every frame."""
    with ResultsReader(a / RESULTS) as ra, ResultsReader(b / RESULTS) as rb:
        ha, hb = ra.history(), rb.history()
        assert ha.keys() == hb.keys()
        for name in ha:
            if not name.startswith("time_"):
                np.testing.assert_allclose(hb[name], ha[name], rtol=1e-10, atol=1e-12,
                                           err_msg=name)
        assert ra.frames == rb.frames
        for name in ("displacement", "stress", "plastic_strain", "contact_force"):
            np.testing.assert_allclose(rb.field(name), ra.field(name), rtol=1e-10,
                                       atol=1e-12, err_msg=name)
        np.testing.assert_array_equal(ra.iterations()["iteration"],
                                      rb.iterations()["iteration"])


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The tiny case run without interruption."""
    base = tmp_path_factory.mktemp("reference")
    case = tiny_case(base / "case")
    outcome = run_case(read_case(case), base / "out")
    assert outcome.status == "completed", outcome.message
    return case, base / "out"


def test_run_writes_every_phase_and_the_outputs(reference: tuple[Path, Path]) -> None:
    case, out = reference
    status = read_status(out)
    assert status["status"] == "completed"
    with ResultsReader(out / RESULTS) as r:
        # this process's peak: at least what Python with numpy and the core occupies
        assert r.peak_memory_mb is not None and r.peak_memory_mb > 20.0
        phase = r.curve("phase")
        assert set(phase) == {0, 1, 2} and np.all(np.diff(phase) >= 0)
        assert r.curve("increment").tolist() == list(range(1, r.n_increments + 1))
        travel, step = r.curve("travel"), r.curve("step")
        draw = phase == 0
        # Each phase ends at its travel; steps add up to it; max_increment holds.
        assert travel[draw][-1] == pytest.approx(2.05)
        assert step[draw].sum() == pytest.approx(2.05)
        assert step[phase == 1].sum() == pytest.approx(0.5)
        assert step.max() <= 0.2 + 1e-12
        # The punch moved down with its travel, pushed back by the blank.
        punch = r.tool_displacement("punch")
        np.testing.assert_allclose(-punch[draw][:, 2], travel[draw], atol=1e-12)
        assert r.tool_force("punch")[draw][-1, 2] > 0.0
        # The holder is off in free_draw and springback: no force, no contact.
        assert np.all(r.tool_force("holder")[phase > 0] == 0.0)
        assert r.curve("nodes_in_contact")[phase == 0, 1].max() > 0
        # Frames at output_at 0.5 and 1, every 10 increments, and every phase end.
        frames = r.frames
        at = {(f.phase, round(f.travel, 9)) for f in frames}
        assert {(0, 0.5), (0, 1.0), (0, 2.05), (1, 0.5)} <= at
        assert frames[-1].increment == r.n_increments and frames[-1].phase == 2
        limits = r.curve("limit")
        assert 6 in limits  # a phase end landed
        assert r.field("plastic_strain").max() > 0.0
        assert np.abs(r.field("contact_force", frame=-1)).max() == 0.0  # tools off
        assert r.iterations()["iteration"].size == r.curve("iterations").sum() + len(phase)
        # The residuals convergence was judged on, below each phase's tolerances in the
        # deck: the force residual over the force scale, the correction over the step.
        phases = read_case(case).phases
        newton = [phases[p].newton for p in phase]
        assert np.all(r.curve("residual_force") <= [n.force_tolerance for n in newton])
        assert np.all(r.curve("residual_displacement")
                      <= [n.displacement_tolerance for n in newton])
        # The work behind the converged iterations: the corrections of every trial (a
        # rejected one included) and the evaluations (line search included).
        forming, iterations = phase < 2, r.curve("iterations")
        newton, evaluations = r.curve("newton_iterations"), r.curve("evaluations")
        assert np.all(newton[forming] >= iterations[forming])
        assert np.all(evaluations[forming] >= newton[forming] + 1)
        assert newton.sum() >= iterations.sum() and evaluations.sum() > newton.sum()
        first = r.iterations()["iteration"] == 1  # before the first correction
        assert first.sum() == len(phase)
        assert np.all(np.isinf(r.iterations()["residual_displacement"][first]))


def test_every_output_file_is_readable_by_all(reference: tuple[Path, Path]) -> None:
    """results.xdmf was 0600 (the temporary file of its atomic rewrite kept mkstemp's
    mode): every file of the output folder is 0644, whatever the umask."""
    _, out = reference
    names = {p.name: p.stat().st_mode & 0o777 for p in out.iterdir() if p.is_file()}
    assert {RESULTS, "results.xdmf", CHECKPOINT, "status.json"} <= set(names)
    assert names == dict.fromkeys(names, 0o644)


def test_an_output_frame_leaves_the_path_of_increments_unchanged(tmp_path: Path) -> None:
    """An output_at travel the run reaches anyway (its first increment ends at 0.2 mm)
    splits the phase there; the next segment goes on with the phase's rate and step, so
    the increments, their iterations and the forces are those of the run without it (a
    segment that started afresh took other increments: no rate to start from)."""
    histories = []
    for label, output in (("frames", "  output_at 0.2\n"), ("none", "")):
        case = tiny_case(tmp_path / label)
        control = case / "control.dat"
        control.write_text(control.read_text().replace("  output_at 0.5 1\n", output))
        outcome = run_case(read_case(case), tmp_path / f"{label}_out")
        assert outcome.status == "completed", outcome.message
        with ResultsReader(tmp_path / f"{label}_out" / RESULTS) as r:
            histories.append(r.history())
            if label == "frames":
                assert (0, 0.2) in {(f.phase, round(f.travel, 9)) for f in r.frames}
    frames, none = histories
    for name in ("increment", "phase", "limit"):
        np.testing.assert_array_equal(frames[name], none[name], err_msg=name)
    # The iterations: the same in the phase of the frame. The continued segment's rate is
    # the phase's rescaled, equal to rounding; the next phase's start (the holder switched
    # off: 73 corrections and cuts) can turn that rounding into an iteration or two of one
    # increment (14 against 12, seen).
    framed = frames["phase"] == 0
    for name in ("iterations", "newton_iterations"):
        np.testing.assert_array_equal(frames[name][framed], none[name][framed], err_msg=name)
        assert abs(int(frames[name].sum()) - int(none[name].sum())) <= \
            0.05 * int(none[name].sum()), name
    for name in ("travel", "step", "tool_force"):
        np.testing.assert_allclose(frames[name], none[name], rtol=1e-6, atol=1e-9,
                                   err_msg=name)
    # A converged increment's residual is rounding below the tolerance (1e-3 of the force
    # scale): the same to 0.1 % of the tolerance.
    np.testing.assert_allclose(frames["residual_force"], none["residual_force"], rtol=0,
                               atol=1e-6)


def test_an_output_frame_closer_than_the_largest_increment_does_not_shorten_the_next(
        tmp_path: Path) -> None:
    """A frame at 0.05 mm (the largest increment is 0.2 mm) ends the first increment there;
    the next one is again as long as the largest increment allows (before, it kept the
    first segment's clipped step: 0.05 mm)."""
    case = tiny_case(tmp_path / "case")
    control = case / "control.dat"
    control.write_text(control.read_text().replace("  output_at 0.5 1\n",
                                                   "  output_at 0.05\n"))
    outcome = run_case(read_case(case), tmp_path / "out")
    assert outcome.status == "completed", outcome.message
    with ResultsReader(tmp_path / "out" / RESULTS) as r:
        travel, step = r.curve("travel"), r.curve("step")
    assert travel[0] == pytest.approx(0.05)
    assert step[1] == pytest.approx(0.2)


def test_restart_after_a_stop_ends_as_the_uninterrupted_run(
        reference: tuple[Path, Path], tmp_path: Path) -> None:
    case, ref = reference
    loaded = read_case(case)
    first = run_case(loaded, tmp_path, max_increments=7, checkpoint_every=3)
    assert first.status == "stopped" and first.increments == 7
    meta, _ = read_checkpoint(tmp_path / CHECKPOINT)
    assert meta["increments"] == 7 and meta["progress"] is not None
    second = run_case(loaded, tmp_path, restart=True, max_increments=8, checkpoint_every=4)
    assert second.status == "stopped"
    last = run_case(loaded, tmp_path, restart=True)
    assert last.status == "completed"
    compare(ref, tmp_path)


def test_a_checkpoint_of_another_version_is_refused_naming_the_file_and_version(
        reference: tuple[Path, Path], tmp_path: Path) -> None:
    """Version 1 checkpoints named the problem's attributes (u, _contact_state...), version
    2 holds its FormingState: a restart from an older one is refused, saying which file and
    which version; the same checkpoint as version 2 continues to the uninterrupted run, and
    the outcome gives the blank's fields of every frame."""
    case, ref = reference
    loaded = read_case(case)
    assert run_case(loaded, tmp_path, max_increments=7).status == "stopped"
    path = tmp_path / CHECKPOINT
    meta, arrays = read_checkpoint(path)
    assert meta["version"] == 2 and "forming/contact_state" in arrays
    assert (arrays["forming/contact_state"] != 0).any()  # (in contact at the stop)
    write_checkpoint(path, {**meta, "version": 1}, arrays)
    with pytest.raises(CheckpointError, match=rf"^{re.escape(str(path))}: checkpoint version "
                       r"1, this ddpy reads version 2 only"):
        run_case(loaded, tmp_path, restart=True)
    write_checkpoint(path, meta, arrays)
    last = run_case(loaded, tmp_path, restart=True)
    assert last.status == "completed"
    compare(ref, tmp_path)
    frames = last.field_frames()
    assert [f.increment for f in frames] == [f.increment for f in ResultsReader(
        tmp_path / RESULTS).frames]
    assert frames[-1].thinning is not None and frames[-1].to_meshio().points.shape[1] == 3


def test_restart_after_every_increment_ends_as_the_uninterrupted_run(
        reference: tuple[Path, Path], tmp_path: Path) -> None:
    # Every increment of the three phases is continued from a checkpoint: whatever the
    # solver carries from one increment to the next (contact forces and states, the last
    # rates, the increment size) must be in the checkpoint.
    case, ref = reference
    loaded = read_case(case)
    outcome = run_case(loaded, tmp_path, max_increments=1, checkpoint_every=1)
    done = 1
    while outcome.status == "stopped":
        done += 1
        outcome = run_case(loaded, tmp_path, restart=True, max_increments=done,
                           checkpoint_every=1)
        assert done < 500
    assert outcome.status == "completed"
    compare(ref, tmp_path)


def test_a_continued_run_records_the_fewest_threads_of_its_parts(
        reference: tuple[Path, Path], tmp_path: Path, monkeypatch) -> None:
    import ddpy.app.runner
    import ddpy.core.parallel

    case, _ = reference
    loaded = read_case(case)
    monkeypatch.setattr(ddpy.core.parallel, "max_threads", lambda: 1)
    monkeypatch.setattr(ddpy.app.runner, "peak_memory_mb", lambda: 5000.0)
    run_case(loaded, tmp_path, max_increments=3)
    monkeypatch.setattr(ddpy.core.parallel, "max_threads", lambda: 2)
    monkeypatch.setattr(ddpy.app.runner, "peak_memory_mb", lambda: 400.0)
    run_case(loaded, tmp_path, restart=True, max_increments=6)
    with ResultsReader(tmp_path / "results.h5") as r:
        assert r.threads == 1  # the first part shared the cores: not a run alone
        assert r.peak_memory_mb == 5000.0  # and the peak memory is the largest part's
    run_case(loaded, tmp_path, overwrite=True, max_increments=3)
    with ResultsReader(tmp_path / "results.h5") as r:
        assert r.threads == 2


def test_restart_refuses_a_changed_case_and_a_missing_checkpoint(
        reference: tuple[Path, Path], tmp_path: Path) -> None:
    case, ref = reference
    with pytest.raises(RunError, match="no checkpoint"):
        run_case(read_case(case), tmp_path / "empty", restart=True)
    with pytest.raises(RunError, match="exists"):
        run_case(read_case(case), ref)
    changed = shutil.copytree(case, tmp_path / "changed")
    (changed / "material.dat").write_text((changed / "material.dat").read_text() + "\n# x\n")
    shutil.copytree(ref, tmp_path / "out")
    with pytest.raises(CheckpointError, match="changed since the checkpoint"):
        run_case(read_case(changed), tmp_path / "out", restart=True)
    # The same decks read with another default element (as after a change of the code's
    # defaults): the checkpoint's state belongs to the other element.
    other = {"solid-shell": "hexahedron", "hexahedron": "solid-shell"}
    loaded = read_case(case)
    with pytest.raises(CheckpointError, match="a default changed"):
        run_case(dataclasses.replace(loaded, element=other[loaded.element]),
                 tmp_path / "out", restart=True)


def _start(case: Path, out: Path, *extra: str) -> subprocess.Popen[str]:
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    return subprocess.Popen([sys.executable, "-m", "ddpy", "run", str(case), "--output",
                             str(out), *extra], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)


def _wait_for_checkpoint(out: Path, process: subprocess.Popen[str], increments: int) -> None:
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline:
        assert process.poll() is None, "the run ended before it could be stopped"
        try:
            if read_checkpoint(out / CHECKPOINT)[0]["increments"] >= increments:
                return
        except CheckpointError:
            pass
        time.sleep(0.02)
    raise AssertionError("no checkpoint within 60 s")


@pytest.fixture(scope="module")
def slow_case(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The tiny case with small increments (long enough to be stopped), run once."""
    base = tmp_path_factory.mktemp("slow")
    case = tiny_case(base / "case", draw=1.5, max_increment=0.02)
    outcome = run_case(read_case(case), base / "out")
    assert outcome.status == "completed", outcome.message
    return case, base / "out"


def test_killed_run_restarts_to_the_same_results(slow_case: tuple[Path, Path],
                                                 tmp_path: Path) -> None:
    case, ref = slow_case
    process = _start(case, tmp_path, "--checkpoint-every", "5")
    _wait_for_checkpoint(tmp_path, process, 5)
    process.send_signal(signal.SIGKILL)
    process.wait(timeout=30)
    assert read_status(tmp_path)["status"] == "running"
    done = subprocess.run([sys.executable, "-m", "ddpy", "run", str(case), "--output",
                           str(tmp_path), "--restart"], capture_output=True, text=True,
                          env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert done.returncode == 0, done.stderr
    assert "completed" in done.stdout
    compare(ref, tmp_path)


def test_ctrl_c_stops_cleanly_and_keeps_the_results(slow_case: tuple[Path, Path],
                                                    tmp_path: Path) -> None:
    case, _ = slow_case
    process = _start(case, tmp_path)
    _wait_for_checkpoint(tmp_path, process, 10)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    assert "stopping after this increment" in stderr
    assert "interrupted" in stdout and "--restart" in stdout
    status = json.loads((tmp_path / "status.json").read_text())
    assert status["status"] == "interrupted" and status["increments"] >= 10
    with ResultsReader(tmp_path / RESULTS) as r:
        assert r.n_increments == status["increments"]
        assert r.frames[-1].increment == r.n_increments  # the fields where it stopped
    with h5py.File(tmp_path / RESULTS, "r") as f:
        assert f.attrs["status"] == "interrupted"
    # Not a terminal: one plain line per increment.
    assert stdout.count("\nincrement ") >= 10


def test_default_case_is_packaged(tmp_path: Path) -> None:
    # Its content is the benchmark's coarse Nagata case: tests/test_cylindrical_bending.py.
    files = sorted(p.relative_to(DEFAULT_CASE).as_posix() for p in DEFAULT_CASE.rglob("*")
                   if p.is_file())
    assert "mesh.msh" in files and "tools/punch.tool" in files
    meson = (ROOT / "meson.build").read_text()
    for name in files:
        assert f"'ddpy/cases/cylindrical_bending/{name}'" in meson, name
    # `ddpy run` without a case reads it and starts; here it stops at once, finding
    # results already in its default output folder.
    taken = tmp_path / "results" / "cylindrical_bending"
    taken.mkdir(parents=True)
    (taken / RESULTS).write_bytes(b"")
    done = subprocess.run([sys.executable, "-m", "ddpy", "run"], capture_output=True,
                          text=True, cwd=tmp_path)
    assert done.returncode == 1
    assert "running Unconstrained cylindrical bending" in done.stdout
    assert str(DEFAULT_CASE) in done.stdout
    assert "results/cylindrical_bending/results.h5 exists" in done.stderr


def test_verbose_run_reports_newton_iterations_and_cuts(tmp_path: Path) -> None:
    # -v: every Newton iteration's residual and step length on standard error; without it,
    # none of them. A cut increment is reported always, with its reason, so that a run that
    # cuts back hundreds of times is seen doing so (issue 19).
    case = tiny_case(tmp_path / "case")
    quiet = subprocess.run([sys.executable, "-m", "ddpy", "run", str(case), "--output",
                            str(tmp_path / "quiet"), "--stop-after", "2"],
                           capture_output=True, text=True)
    loud = subprocess.run([sys.executable, "-m", "ddpy", "run", str(case), "--output",
                           str(tmp_path / "loud"), "--stop-after", "2", "-v"],
                          capture_output=True, text=True)
    assert quiet.returncode == loud.returncode == 0, loud.stderr
    assert "iteration" not in quiet.stderr
    lines = [x for x in loud.stderr.splitlines() if "iteration 0: residual" in x]
    assert len(lines) >= 2
    assert "step length" in loud.stderr
    # One Newton iteration per increment at most: every increment is cut, each cut says so.
    control = case / "control.dat"
    control.write_text(control.read_text().replace("max_increment  0.2",
                                                   "max_increment  0.2\nmax_iterations 1"))
    cutting = subprocess.run([sys.executable, "-m", "ddpy", "run", str(case), "--output",
                              str(tmp_path / "cutting")], capture_output=True, text=True)
    assert cutting.returncode == 1
    # (The first increment's careful start may take 4 iterations: its cuts say so.)
    cuts = [x for x in cutting.stderr.splitlines() if " cut: no convergence in " in x]
    assert len(cuts) >= 3, cutting.stderr


def test_a_fine_blank_lying_on_the_die_converges_in_its_first_increment(tmp_path) -> None:
    # The built-in case with DD3IMP's discretization and its blank refined to 240 x 6 x 2
    # hexahedra (0.25 mm) starts with 868 bottom nodes on the die at zero gap; its first
    # increment (ended by the first touch of the next punch row) failed at every cut down
    # to the smallest increment. The
    # second start of a phase's first increment, with the touching pairs of the die (at
    # rest) left open, exact solves and full steps, converges at the first size, shortened
    # only by the landing of the first yielding point (docs/theory/contact.md).
    case = tmp_path / "case"
    shutil.copytree(DEFAULT_CASE, case)
    (case / "mesh.dat").write_text("normal z\nbox 60 15 1 240 6 2\n")
    dd3imp(case)
    seen = []
    outcome = run_case(read_case(case), tmp_path / "out", max_increments=1, threads=1,
                       progress=seen.append)
    assert outcome.status == "stopped"
    assert [p.limit for p in seen] == ["yield"]   # no cut
    assert seen[0].iterations < 25


def first_increment_of_a_solid_shell_blank(tmp_path: Path,
                                            max_iterations: int | None = None) -> Progress:
    """The built-in case's tools with DD3IMP's node-to-surface contact and a von Mises
    blank of 30 x 6 x 2 solid-shells, largest increment 0.1 mm (and ``max_iterations``):
    the progress of its first increment."""
    case = tmp_path / "case"
    shutil.copytree(DEFAULT_CASE, case)
    (case / "mesh.dat").write_text("normal z\nelement solid-shell\nbox 60 15 1 30 6 2\n")
    (case / "material.dat").write_text(
        "elastic E 210000 nu 0.3\nyield vonmises\n"
        "hardening swift K 645.3 eps0 0.0102 n 0.252\n")
    control = case / "control.dat"
    text = re.sub(r"(?m)^max_increment\s+\S+", "max_increment 0.1", control.read_text())
    if max_iterations is not None:
        text = re.sub(r"(?m)^max_iterations\s+\S+", f"max_iterations {max_iterations}",
                      text)
        assert f"max_iterations {max_iterations}" in text
    control.write_text(text)
    dd3imp(case)
    seen: list[Progress] = []
    outcome = run_case(read_case(case), tmp_path / "out", max_increments=1, threads=1,
                       progress=seen.append)
    assert outcome.status == "stopped" and len(seen) == 1
    return seen[0]


def test_a_first_increment_whose_default_start_fails_converges_on_the_careful_start(
        tmp_path, caplog) -> None:
    # The built-in case's tools, node-to-surface contact, with a von Mises blank of
    # 30 x 6 x 2 solid-shells: the
    # default start of the first increment cycles between contact states for 25
    # iterations at every cut, down to the smallest increment (found by
    # benchmarks/mesh_convergence). The careful start (the die's touching pairs open, exact
    # solves, full steps: docs/theory/contact.md) converges at the first size, and the
    # increment is not cut.
    caplog.set_level(logging.INFO, logger="ddpy.model.forming")
    first = first_increment_of_a_solid_shell_blank(tmp_path)
    assert first.limit != "cutback" and first.iterations <= 25
    logged = [r.getMessage() for r in caplog.records]
    assert any("starts again" in m for m in logged)      # the default start failed
    assert not any(" cut: " in m for m in logged)


def test_a_careful_start_may_take_more_iterations_than_the_deck_allows(tmp_path) -> None:
    # The blank above with max_iterations 12: its careful start needs about twice that
    # (it opens the die's pairs the blank does not need a few at a time), and it may take
    # IncrementTuning.careful_iterations times the deck's limit, once per phase
    # (docs/theory/contact.md). Held to the deck's 12 it is cut at every size.
    first = first_increment_of_a_solid_shell_blank(tmp_path, max_iterations=12)
    assert first.limit != "cutback" and 12 < first.iterations <= 48


def test_restart_at_a_phase_boundary_is_the_same_run_with_reused_factors(
        tmp_path: Path) -> None:
    # With older factors reused (GMRES on them), a run continued from a checkpoint has none
    # to reuse. Every phase sets its constraints, and with them a new solver, anew: so a
    # restart at a phase boundary is the same run as the uninterrupted one
    # (docs/theory/contact.md). The tiny case is below reuse_from: its deck tunes it to 0,
    # and the restarted run, which reads the same deck, reuses factors too (compare holds
    # the GMRES iterations of every increment against the whole run's).
    folder = dd3imp(tiny_case(tmp_path / "case"))
    control = folder / "control.dat"
    control.write_text("tune reuse_from 0\n" + control.read_text())
    # (With the solid-shell, the tiny case's springback step 3 does not converge in 25
    # iterations on reused factors: hexahedra here, the open finding in docs/theory/
    # solid_shell.md.)
    case = read_case(folder)
    assert case.control.tuning.reuse_from == 0
    assert run_case(case, tmp_path / "whole").status == "completed"
    with ResultsReader(tmp_path / "whole" / RESULTS) as r:
        phase = r.curve("phase")
        assert r.curve("krylov_iterations").sum() > 0  # the factors were reused
    for end in np.flatnonzero(np.diff(phase)) + 1:  # increments up to each phase's end
        first = run_case(case, tmp_path / f"part{end}", max_increments=int(end))
        assert first.status == "stopped"
        assert run_case(case, tmp_path / f"part{end}", restart=True).status == "completed"
        compare(tmp_path / "whole", tmp_path / f"part{end}")


def _snapshot(folder: Path) -> dict[str, tuple[bytes, int]]:
    """Every file of a folder: its bytes and modification time."""
    return {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(folder.iterdir())}


def test_a_second_run_on_a_running_folder_is_refused_and_the_first_ends_as_a_lone_run(
        slow_case: tuple[Path, Path], tmp_path: Path) -> None:
    # Issue 51: the second run deleted the first one's checkpoint and truncated its results
    # before it was refused; the first then ended with an unreadable results.h5.
    case, lone = slow_case
    first = _start(case, tmp_path)
    _wait_for_checkpoint(tmp_path, first, 1)  # running, with rows and a checkpoint written
    first.send_signal(signal.SIGSTOP)  # held still: the folder cannot change but by others
    try:
        before = _snapshot(tmp_path)
        for extra in ([], ["--overwrite"], ["--restart"]):
            second = subprocess.run([sys.executable, "-m", "ddpy", "run", str(case),
                                     "--output", str(tmp_path), *extra],
                                    capture_output=True, text=True,
                                    env={**os.environ, "OMP_NUM_THREADS": "1"})
            assert second.returncode == 1, (extra, second.stderr)
            assert second.stderr.splitlines() == [
                f"ddpy run: error: {tmp_path}: in use by another ddpy run (process "
                f"{first.pid}); nothing in it was changed: wait for that run to end, or "
                "choose another --output"], extra
            assert _snapshot(tmp_path) == before, extra
    finally:
        first.send_signal(signal.SIGCONT)
    stdout, stderr = first.communicate(timeout=120)
    assert first.returncode == 0 and "completed" in stdout, stderr
    compare(lone, tmp_path)
    assert not (tmp_path / ".ddpy.lock").exists()  # given back at the end


def test_the_results_file_records_each_phase_newton_tolerances(tmp_path: Path) -> None:
    # The tolerances set how closely two runs' answers can agree, so a results file says
    # what its answers were converged to: the deck's lines, and the defaults elsewhere.
    case = tiny_case(tmp_path / "case")
    control = case / "control.dat"
    text = control.read_text().replace(
        "  rmin_strain    0.01", "  rmin_strain    0.01\n  newton_force   5e-4")
    text = text.replace("  tools  punch die holder",
                        "  tools  punch die holder\n  newton_displacement  2e-3")
    control.write_text(text)
    phases = read_case(case).phases
    default = NewtonSettings()
    assert [p.newton.force_tolerance for p in phases] == \
        [default.force_tolerance, 5e-4, default.force_tolerance]
    outcome = run_case(read_case(case), tmp_path / "out", max_increments=1, threads=1)
    assert outcome.status == "stopped"
    with ResultsReader(tmp_path / "out" / RESULTS) as r:
        np.testing.assert_array_equal(r.attribute("newton_force"),
                                      [default.force_tolerance, 5e-4,
                                       default.force_tolerance])
        np.testing.assert_array_equal(r.attribute("newton_displacement"),
                                      [2e-3, default.displacement_tolerance,
                                       default.displacement_tolerance])
