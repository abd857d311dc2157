"""The levers report of the bending benchmark (benchmarks/cylindrical_bending/levers.py) on
synthetic runs: its two checks (Table 2's angles within 0.5 degree of the run without the
levers, the punch force's oscillation no worse) and the savings it states. No simulation."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "cylindrical_bending"
sys.path.insert(0, str(BENCH.parent))
from bench_common import load_module  # noqa: E402

levers = load_module(BENCH / "levers.py", "bending_levers")


def _run(theta: list[float], betas: tuple[float, float], oscillation: float, iterations: int,
         wall_s: float, force_shift: float = 0.0) -> dict[str, Any]:
    stroke = np.linspace(0.1, 28.5, 200)
    force = 70.0 * stroke / 28.5 + force_shift
    return {"code": "abc1234", "threads": 1, "status": "completed", "increments": 253,
            "full_size_increments": 247, "iterations": iterations,
            "springback_iterations": 60, "factorizations": 100, "krylov_iterations": 900,
            "wall_s": wall_s, "per_iteration_s": {"assembly": 0.2, "linear": 0.5},
            "max_force_N": float(force.max()), "oscillation_N": oscillation,
            "oscillation_after_20mm_N": 2 * oscillation, "theta_deg": theta,
            "beta1_deg": betas[0], "beta2_deg": betas[1],
            "curves": {"stroke": stroke.tolist(), "force": force.tolist()}}


ON = _run([17.5, 61.4, 106.9, 148.7], (14.52, 22.09), 0.032, 1382, 1136.0)


def test_the_checks_hold_for_the_same_answer_in_fewer_iterations() -> None:
    off = _run([17.6, 61.2, 107.3, 148.5], (14.50, 22.20), 0.040, 2764, 4544.0, 0.7)
    v = levers.verdicts(ON, off)
    assert v["angles_hold"] and v["oscillation_holds"]
    assert abs(v["largest_angle_diff"] - 0.4) < 1e-9
    text = levers.report(ON, {"off": {**off, "switched_off": levers.VARIANTS["off"]}},
                         "def5678")
    assert "within 0.5 degrees: **holds** (levers on minus off: theta_1 -0.10, theta_2 " \
        "+0.20, theta_3 -0.40, theta_4 +0.20, beta_1 +0.02, beta_2 -0.11; largest 0.40)" in text
    assert "no worse: **holds** (0.032 N with the levers, 0.04 N without; the force's " \
        "resolution, newton_force times the largest force: 0.007 N)" in text
    assert "1382 forming iterations against 2764 (-50%)" in text
    assert "18.9 min against 75.7 (-75%) on 1 thread(s)" in text
    assert "levers off 0.7 N (1.00% of the largest force)" in text
    assert "linear_solver direct, whole_step 0.0, rmin_touch every" in text


def test_an_angle_beyond_half_a_degree_or_a_worse_oscillation_fails_its_check() -> None:
    off = _run([17.5, 61.4, 107.5, 148.7], (14.52, 22.09), 0.024, 2764, 4544.0)
    v = levers.verdicts(ON, off)  # 0.032 N against 0.024 N + 0.007 N: worse
    assert not v["angles_hold"] and not v["oscillation_holds"]
    assert levers.verdicts(ON, {**off, "oscillation_N": 0.026})["oscillation_holds"]
    # a run converged to 1e-3 of the force resolves 0.07 N of 70 N, not 0.007 N
    assert levers.verdicts({**ON, "newton_force": 1e-3}, off)["oscillation_holds"]
    assert not levers.verdicts({**ON, "newton_force": 1e-4}, off)["oscillation_holds"]
    text = levers.report(ON, {"direct": {**off, "switched_off": levers.VARIANTS["direct"]}},
                         "def5678")
    assert "Against direct solves only: the angles of Table 2 within 0.5 degrees: **does " \
        "not hold**" in text
    assert "no worse: **does not hold**" in text
    assert "their wall times are on different threads" not in text
    text = levers.report(ON, {"direct": {**off, "threads": 2,
                                         "switched_off": levers.VARIANTS["direct"]}}, "x")
    assert "their wall times are on different threads (the table)" in text
