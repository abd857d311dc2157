"""The mixed-hardening springback report (benchmarks/kinematic_hardening/run.py) without its
runs: the fitted isotropic law follows the mixed model's monotonic curve within the report's
tolerance (the closed form, and uniaxial tension through both return mappings), the decks it
writes read back as the two laws, and its verdict flags a springback that differs."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from ddpy.io.decks import read_case
from ddpy.model.material import HardeningTable, Material
from tests.test_kinematic_hardening import uniaxial_step

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_common import load_module  # noqa: E402

kinematic = load_module(ROOT / "benchmarks" / "kinematic_hardening" / "run.py",
                        "kinematic_hardening_run")


def test_fitted_table_follows_the_mixed_monotonic_curve() -> None:
    """The table's Y(ep), from the core, against Voce + X_sat (1 - exp(-C_X ep)) written out
    here, on a grid finer than the table's and offset from its points, up to the report's
    range: within CURVE_TOLERANCE, as the report's curve_gap says."""
    table = kinematic.fitted_table()
    voce, back = kinematic.ISOTROPIC_PART, kinematic.BACKSTRESS
    ep = np.linspace(0.0, kinematic.CURVE_RANGE, 7919)
    expected = (voce.Y0 + voce.Q * (1 - np.exp(-voce.b * ep))
                + back.X_sat * (1 - np.exp(-back.C * ep)))
    fitted = Material(210e3, 0.3, kinematic.Hill48.von_mises(), table).yield_stress(ep)
    assert np.max(np.abs(fitted - expected)) <= kinematic.CURVE_TOLERANCE
    gap, _ = kinematic.curve_gap(table)
    assert gap <= kinematic.CURVE_TOLERANCE
    assert gap == pytest.approx(np.max(np.abs(fitted - expected)), rel=0.2)


def test_mixed_and_fitted_laws_give_the_same_uniaxial_tension() -> None:
    """Uniaxial tension along RD to over 4 % plastic strain through each law's return mapping,
    with the bending's Hill'48 (G + H = 1): the two stresses within CURVE_TOLERANCE at every
    step, though the mixed law's yield surface has moved by about X_sat."""
    hill = kinematic.Hill48(F=0.254, G=0.397, H=0.603, N=1.689)
    mixed = Material(210e3, 0.3, hill, kinematic.ISOTROPIC_PART, kinematic.BACKSTRESS)
    fitted = Material(210e3, 0.3, hill, kinematic.fitted_table())
    states = {law: (np.zeros(6), np.zeros(6), 0.0, np.zeros(2)) for law in ("mixed", "fitted")}
    worst = 0.0
    for _ in range(300):
        for law, material in (("mixed", mixed), ("fitted", fitted)):
            states[law] = uniaxial_step(material, *states[law][:3], 2e-4, states[law][3])[:4]
        worst = max(worst, abs(states["mixed"][0][0] - states["fitted"][0][0]))
    assert states["mixed"][2] > 0.04
    back = states["mixed"][1]
    assert back[0] - back[1] > 0.9 * kinematic.BACKSTRESS.X_sat  # x of the closed form
    assert worst <= kinematic.CURVE_TOLERANCE


def test_written_decks_hold_the_two_laws(tmp_path: Path) -> None:
    """write_case: the bending's decks with the mixed law read back with its Voce part and
    backstress, with the isotropic law as the fitted table and no backstress; the Hill'48
    coefficients kept."""
    source = kinematic.CASES["bending"]
    original = read_case(source, geometry=False).material.material
    mixed = read_case(kinematic.write_case(source, tmp_path / "mixed", "mixed"),
                      geometry=False).material.material
    iso = read_case(kinematic.write_case(source, tmp_path / "iso", "isotropic"),
                    geometry=False).material.material
    assert mixed.hardening == kinematic.ISOTROPIC_PART
    assert mixed.kinematic == kinematic.BACKSTRESS and mixed.mixed
    assert isinstance(iso.hardening, HardeningTable) and not iso.mixed
    assert iso.hardening == kinematic.fitted_table()
    assert mixed.yield_criterion == iso.yield_criterion == original.yield_criterion


@pytest.mark.parametrize(("mixed", "isotropic", "differs"), [
    (12.0, 10.0, True),     # 2 degrees, 20 %
    (8.0, 10.0, True),      # the same, the other way
    (10.1, 10.0, False),    # 0.1 degree: below both thresholds
    (10.4, 10.0, False),    # 0.4 degree but 4 %: a small relative change
    (0.3, 0.1, False),      # 200 % but 0.2 degree
    (-3.0, -2.5, True),     # negative springbacks (an angle that closes)
])
def test_verdict_flags_a_springback_that_differs(mixed: float, isotropic: float,
                                                 differs: bool) -> None:
    """The report's verdict: mixed and isotropic differ when both thresholds are passed."""
    flagged, text = kinematic.verdict(mixed, isotropic)
    assert flagged is differs
    assert text.startswith("differs" if differs else "same")
    assert f"{mixed - isotropic:+.2f} deg" in text


def test_the_report_weighs_each_runs_deepest_node_against_the_limit(tmp_path: Path) -> None:
    """The penetration section: the deepest node of each run over its blank's thickness
    against the 1 % limit; a kept run without the record says so."""
    run = {"status": "completed", "angles_deg": {"beta": [12.0, 25.0]}, "increments": 10,
           "iterations": 20, "per_iteration_s": {"total": 0.02, "assembly": 0.01},
           "threads": 1, "code": "abc1234", "thickness_mm": 1.0,
           "penetration_mm": {"punch": 0.005, "die": 0.004}}
    numbers = {"bending/mixed": run, "bending/isotropic": {
        **run, "penetration_mm": {"punch": 0.0105, "die": 0.002}},
               "strip_draw/mixed": {k: v for k, v in run.items() if k != "penetration_mm"}}
    text = kinematic.report(numbers, kinematic.fitted_table(), (0.0, 0.0),
                            tmp_path / "curves.png", "abc1234")
    assert "| bending | mixed | 0.005 | punch | 0.50 % | yes |" in text
    assert "| bending | isotropic | 0.0105 | punch | 1.05 % | **no** |" in text
    assert "| strip_draw | mixed | not recorded (a run kept at code abc1234) |" in text
