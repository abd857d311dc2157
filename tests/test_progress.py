"""The progress of ``ddpy run``: the whole run's share done and the time left."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from ddpy.app.cli_run import ProgressDisplay
from ddpy.app.convert import convert_inp
from ddpy.app.runner import Progress, run_case
from ddpy.io.decks import read_case

CAE_DECK = Path(__file__).parent / "data" / "cae_bending.inp"


def test_run_fraction_covers_every_phase_once(tmp_path: Path) -> None:
    """Three phases (two forming of 1 mm at <= 0.1 mm, one springback of 2 steps): the share
    rises over the whole run, reaches each phase's weight at its end and 1 at the last."""
    case = read_case(convert_inp(CAE_DECK, tmp_path / "case").folder)
    seen: list[Progress] = []
    outcome = run_case(case, tmp_path / "out", progress=seen.append, threads=1)
    assert outcome.status == "completed"
    fractions = [p.run_fraction for p in seen]
    assert all(b >= a for a, b in zip(fractions, fractions[1:], strict=False))
    assert fractions[-1] == pytest.approx(1.0)
    # Weights 10, 10 and 2 increments: each forming phase ends at 10/22, 20/22 of the run.
    ends = {p.phase_index: p.run_fraction for p in seen}
    assert ends[0] == pytest.approx(10 / 22) and ends[1] == pytest.approx(20 / 22)
    assert seen[0].run_fraction < 0.1


def _progress(fraction: float, phase: str = "forming") -> Progress:
    return Progress(phase, 0, 2, 1, "punch", 1.0, 10.0, 0.1, 3, "max_increment", fraction)


def test_progress_line_gives_the_run_share_and_the_time_left() -> None:
    now = [100.0]
    stream = io.StringIO()
    display = ProgressDisplay(stream, clock=lambda: now[0])
    display(_progress(0.10))                  # the first: no pace yet
    now[0] += 30.0
    display(_progress(0.25))                  # 15 % in 30 s: 75 % left in 150 s
    now[0] += 600.0
    display(_progress(0.40))                  # 30 % in 630 s: 60 % left in 1260 s
    lines = stream.getvalue().splitlines()
    assert lines[0].endswith("run 10.0 % done, ETA --")
    assert lines[1].endswith("run 25.0 % done, ETA 2 min 30 s")
    assert lines[2].endswith("run 40.0 % done, ETA 21 min 00 s")
