"""Mixed isotropic-kinematic hardening (Armstrong-Frederick backstress, docs/theory/material.md):
the return mapping against the closed-form uniaxial response, its consistent tangent, the
elements and the core's Newton loop, objectivity, checkpoints, the deck and C_X = 0."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from ddpy.app.runner import run_case
from ddpy.io.case import DeckError
from ddpy.io.decks import read_case
from ddpy.io.results import ResultsReader
from ddpy.model.material import ArmstrongFrederick, Hill48, Material, Swift, Voce
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.static import StaticProblem
from tests.test_runner import compare, tiny_case

ROOT = Path(__file__).resolve().parents[1]
#: The bending benchmark's steel (G + H = 1: the hardening curve is the RD uniaxial one).
HILL = Hill48(F=0.254, G=0.397, H=0.603, N=1.689)
C_X, X_SAT = 60.0, 120.0
VOCE = Voce(300.0, 150.0, 12.0)
MIXED = Material(210e3, 0.3, HILL, VOCE, ArmstrongFrederick(C_X, X_SAT))


def uniaxial_step(material: Material, stress, back, ep, d11: float, lateral):
    """One increment of uniaxial stress along RD: the lateral strains solved by Newton with
    the consistent tangent so that s22 = s33 = 0. Returns the state, the lateral strains
    and the lateral residual norms of the iterations."""
    norms = []
    for _ in range(20):
        de = np.array([d11, lateral[0], lateral[1], 0.0, 0.0, 0.0])
        s, x, e, d, _ = material.update_mixed(stress, back, ep, de)
        norms.append(float(np.hypot(s[1], s[2])))
        if norms[-1] < 1e-9:
            return s, x, e, lateral, norms
        lateral = lateral - np.linalg.solve(d[1:3, 1:3], s[1:3])
    raise AssertionError(f"lateral Newton did not converge: {norms}")


def test_uniaxial_tension_then_compression_follows_the_closed_form() -> None:
    """Backstress x = X11 - X22 along RD: X_sat (1 - exp(-C ep)) in tension, then
    -X_sat + (x1 + X_sat) exp(-C (ep - ep1)) after the reversal; s11 = Y(ep) + x and
    x - Y(ep). Reverse yield at x1 - Y(ep1) (Bauschinger), saturation at -X_sat."""
    stress, back, ep, lateral = np.zeros(6), np.zeros(6), 0.0, np.zeros(2)
    step = 2e-5
    forward_checked = reverse_checked = 0
    for _ in range(3000):  # to about 0.06 plastic strain
        stress, back, ep, lateral, _ = uniaxial_step(MIXED, stress, back, ep, step, lateral)
        if ep > 0:
            x_ref = X_SAT * (1 - np.exp(-C_X * ep))
            assert back[0] - back[1] == pytest.approx(x_ref, rel=2e-3, abs=0.05)
            y = MIXED.yield_stress(ep)
            assert stress[0] == pytest.approx(y + x_ref, rel=1e-3)
            forward_checked += 1
    ep1, x1, y1 = ep, back[0] - back[1], float(MIXED.yield_stress(ep))
    assert x1 == pytest.approx(X_SAT * (1 - np.exp(-C_X * ep1)), rel=2e-3)
    first_reverse = None
    for _ in range(12000):
        stress, back, ep, lateral, _ = uniaxial_step(MIXED, stress, back, ep, -step, lateral)
        if ep > ep1:
            if first_reverse is None:
                first_reverse = stress[0]
                # Reverse yield: the first plastic step lands within one step's stress of it.
                assert first_reverse == pytest.approx(x1 - y1, abs=210e3 * step)
                assert abs(first_reverse) < y1 + x1 - 100.0  # the Bauschinger effect
            x_ref = -X_SAT + (x1 + X_SAT) * np.exp(-C_X * (ep - ep1))
            assert back[0] - back[1] == pytest.approx(x_ref, rel=2e-3, abs=0.3)
            assert stress[0] == pytest.approx(x_ref - MIXED.yield_stress(ep), rel=1e-3)
            reverse_checked += 1
    assert forward_checked > 2000 and reverse_checked > 5000
    assert back[0] - back[1] == pytest.approx(-X_SAT, rel=1e-3)  # saturated
    assert stress[0] == pytest.approx(-X_SAT - MIXED.yield_stress(ep), rel=1e-3)


def test_tangent_against_central_differences_and_the_quadratic_rate() -> None:
    """Random states whose backstress is not along the flow (a non-symmetric tangent), and
    the lateral Newton of a uniaxial step: each residual at most a constant times the square
    of the last."""
    rng = np.random.default_rng(3)
    for hardening in (VOCE, Swift(560.0, 0.02, 0.22)):
        material = Material(210e3, 0.3, HILL, hardening, ArmstrongFrederick(C_X, X_SAT))
        checked = 0
        for _ in range(40):
            s0, x0 = rng.normal(size=6) * 150, rng.normal(size=6) * 50
            x0[:3] -= x0[:3].mean()
            de = rng.normal(size=6) * 3e-3
            _, _, _, tangent, plastic = material.update_mixed(s0, x0, 0.03, de)
            if not plastic:
                continue
            h = 1e-8
            numeric = np.empty((6, 6))
            for j in range(6):
                e = np.zeros(6)
                e[j] = h
                numeric[:, j] = (material.update_mixed(s0, x0, 0.03, de + e)[0]
                                 - material.update_mixed(s0, x0, 0.03, de - e)[0]) / (2 * h)
            assert np.abs(numeric - tangent).max() <= 1e-7 * np.abs(tangent).max()
            checked += 1
        assert checked > 20
    # The first plastic step from a hardened state, backstress from an earlier loading.
    back = np.array([40.0, -20.0, -20.0, 30.0, 0.0, 0.0])
    _, _, _, _, norms = uniaxial_step(MIXED, back.copy(), back, 0.02, 4e-3, np.zeros(2))
    assert len(norms) >= 4
    for a, b in zip(norms[1:-1], norms[2:], strict=False):
        assert b <= 2e-3 * a * a + 1e-9, norms  # quadratic; 1e-3 measured


def one_block(element: str) -> tuple[Solid, np.ndarray]:
    mesh = HexMesh.box(4, 2, 1, 2, 1, 2)
    return Solid(mesh, MIXED, element=element), mesh.nodes


def stretch(x: np.ndarray, strain: float) -> np.ndarray:
    """Displacements of uniaxial stretch along x with the lateral contraction of plastic
    incompressibility."""
    lateral = (1 + strain) ** -0.5 - 1
    return x * np.array([strain, lateral, lateral])


@pytest.mark.parametrize("element", ["hexahedron", "solid-shell"])
def test_element_tangent_against_finite_differences(element: str) -> None:
    """After a plastic stretch, K against central differences of the internal forces in a
    second plastic increment (proportional: the material's tangent is symmetric there)."""
    solid, x = one_block(element)
    first = solid.assemble(stretch(x, 0.01))
    state = first.state
    assert np.abs(state.backstress).max() > 10.0
    u = stretch(x, 0.015)
    rows, cols, values = solid.tangent(u, state)
    k = np.zeros((u.size, u.size))
    np.add.at(k, (rows, cols), values)
    h = 1e-7
    rng = np.random.default_rng(5)
    for j in rng.choice(u.size, 10, replace=False):
        du = np.zeros(u.size)
        du[j] = h
        plus = solid.internal_force(u + du.reshape(-1, 3), state)[0].ravel()
        minus = solid.internal_force(u - du.reshape(-1, 3), state)[0].ravel()
        np.testing.assert_allclose(k[:, j], (plus - minus) / (2 * h),
                                   atol=2e-5 * np.abs(k).max())


@pytest.mark.parametrize("element", ["hexahedron", "solid-shell"])
def test_static_newton_converges_quadratically(element: str) -> None:
    """The core's Newton loop on a block stretched plastically, then compressed (the
    Bauschinger branch): the last correction of each increment squares the residual."""
    solid, x = one_block(element)
    problem = StaticProblem(solid)
    problem.fix(np.flatnonzero(x[:, 0] == 0), "x")
    problem.fix(np.flatnonzero(x[:, 1] == 0), "y")
    problem.fix(np.flatnonzero(x[:, 2] == 0), "z")
    end = np.flatnonzero(x[:, 0] == 4)
    problem.fix(end, "x", lambda t: 0.08 * min(t, 1 - t) * 2)
    result = problem.solve(increments=8)
    assert result.state is not None and np.abs(result.state.backstress).max() > 20.0
    # The last correction of every increment squares the residual (N; at most 1e-8: the
    # round-off floor of forces of 1e3 N); 1e-2 measured where not at the floor.
    assert len(result.residuals) == 8
    for r in result.residuals:
        assert r[-1] <= max(1e-8, 0.05 * r[-2] ** 2), result.residuals


def test_objective_under_a_large_rigid_rotation() -> None:
    """The second increment of a stretch, once plain and once turned 70 degrees about a
    skew axis with it: the same stress and backstress in material axes, the axes and the
    Cauchy stress turned."""
    for element in ("hexahedron", "solid-shell"):
        solid, x = one_block(element)
        state = solid.assemble(stretch(x, 0.01)).state
        axis = np.array([1.0, 2.0, 2.0]) / 3.0
        angle = np.radians(70)
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        rot = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
        u = stretch(x, 0.02)
        plain = solid.assemble(u, state).state
        turned = solid.assemble((x + u) @ rot.T - x, state).state
        assert np.abs(plain.backstress).max() > 20.0
        np.testing.assert_allclose(turned.backstress, plain.backstress, atol=1e-8)
        np.testing.assert_allclose(turned.stress, plain.stress, atol=1e-8)
        np.testing.assert_allclose(turned.axes, rot @ plain.axes, atol=1e-12)
        _, cauchy_plain, _ = solid.stresses(u, plain)
        _, cauchy_turned, _ = solid.stresses((x + u) @ rot.T - x, turned)

        def tensor(v):
            return np.array([[v[0], v[3], v[5]], [v[3], v[1], v[4]], [v[5], v[4], v[2]]])
        for a, b in zip(cauchy_plain.reshape(-1, 6), cauchy_turned.reshape(-1, 6),
                        strict=True):
            np.testing.assert_allclose(tensor(b), rot @ tensor(a) @ rot.T, atol=1e-8)


def kinematic_case(folder: Path, line: str) -> Path:
    """The tiny strip draw of tests/test_runner.py (bend and unbend over the die radius) with
    a material.dat line added after the hardening."""
    tiny_case(folder)
    material = folder / "material.dat"
    material.write_text(re.sub(r"(?m)^(hardening .*)$", rf"\1\n{line}", material.read_text()))
    return folder


def test_restart_carries_the_backstress(tmp_path: Path) -> None:
    case = kinematic_case(tmp_path / "case", "kinematic armstrong-frederick C 60 Xsat 100")
    loaded = read_case(case)
    assert loaded.material.material.mixed
    reference = run_case(loaded, tmp_path / "ref")
    assert reference.status == "completed", reference.message
    first = run_case(loaded, tmp_path / "out", max_increments=6, checkpoint_every=3)
    assert first.status == "stopped"
    last = run_case(loaded, tmp_path / "out", restart=True)
    assert last.status == "completed"
    compare(tmp_path / "ref", tmp_path / "out")
    # and the backstress mattered: the isotropic run's forces differ
    iso = run_case(read_case(tiny_case(tmp_path / "iso")), tmp_path / "iso_out")
    with ResultsReader(tmp_path / "ref" / "results.h5") as a, \
            ResultsReader(tmp_path / "iso_out" / "results.h5") as b:
        assert iso.status == "completed"
        assert not np.allclose(a.history()["tool_force"], b.history()["tool_force"],
                               rtol=1e-3)


@pytest.mark.parametrize("case, increments", [("cylindrical_bending", 12),
                                               ("reverse_deep_drawing", 10)])
def test_zero_rate_leaves_the_built_in_cases_unchanged(tmp_path: Path, case: str,
                                                       increments: int) -> None:
    """C 0 in the deck: the first increments of the built-in bending (12, plastic from the
    eighth) and deep drawing (10, plastic from the sixth) give the very forces and stresses
    of the deck without the line, and the API's update is the isotropic one to the bit."""
    source = ROOT / "ddpy" / "cases" / case
    plain = tmp_path / "plain"
    shutil.copytree(source, plain)
    zero = tmp_path / "zero"
    shutil.copytree(source, zero)
    material = zero / "material.dat"
    material.write_text(re.sub(r"(?m)^(hardening .*)$",
                               r"\1\nkinematic armstrong-frederick C 0 Xsat 150",
                               material.read_text()))
    for folder in (plain, zero):
        outcome = run_case(read_case(folder), tmp_path / f"{folder.name}_out",
                           max_increments=increments, threads=1)
        assert outcome.status == "stopped"
    with ResultsReader(tmp_path / "plain_out" / "results.h5") as a, \
            ResultsReader(tmp_path / "zero_out" / "results.h5") as b:
        ha, hb = a.history(), b.history()
        assert ha["tool_force"].shape[0] == increments
        assert np.any(ha["rmin"] < 1.0)  # the yield was reached: the return mapping ran
        np.testing.assert_array_equal(ha["tool_force"], hb["tool_force"])
        np.testing.assert_array_equal(a.field("stress"), b.field("stress"))
    isotropic = Material(210e3, 0.3, HILL, VOCE)
    zero_rate = Material(210e3, 0.3, HILL, VOCE, ArmstrongFrederick(0.0, 150.0))
    rng = np.random.default_rng(0)
    s, de = rng.normal(size=(200, 6)) * 200, rng.normal(size=(200, 6)) * 3e-3
    one = isotropic.update(s, np.full(200, 0.02), de)
    two = isotropic.update(s, np.full(200, 0.02), de)
    np.testing.assert_array_equal(one[0], two[0])
    s2, x2, ep2, d2, _ = zero_rate.update_mixed(s, np.zeros((200, 6)), np.full(200, 0.02), de)
    np.testing.assert_allclose(s2, one[0], rtol=1e-12, atol=1e-9)
    np.testing.assert_array_equal(x2, 0.0)


@pytest.mark.parametrize("line, expected", [
    ("kinematic armstrong-frederick C -5 Xsat 50", "kinematic hardening C_X must be non-negative"),
    ("kinematic armstrong-frederick C 50 Xsat nan", "finite number for the kinematic"),
    ("kinematic armstrong-frederick C inf Xsat 50", "finite number for the kinematic"),
    ("kinematic armstrong-frederick C 50 Xsat -1",
     "kinematic hardening X_sat must be non-negative"),
    ("kinematic armstrong-frederick C 50 Xsat 160", "must lie below the initial yield stress 160"),
    ("kinematic armstrong-frederick C 50", "kinematic armstrong-frederick C VALUE Xsat VALUE"),
    ("kinematic chaboche C 50 Xsat 50", "armstrong-frederick"),
])
def test_deck_errors_name_the_line(tmp_path: Path, line: str, expected: str) -> None:
    case = kinematic_case(tmp_path / "case", line)
    number = material_line(case, "kinematic")
    with pytest.raises(DeckError) as error:
        read_case(case)
    message = str(error.value)
    assert f"material.dat:{number}:" in message and expected in message, message


def test_a_kinematic_line_without_hardening_is_refused(tmp_path: Path) -> None:
    case = kinematic_case(tmp_path / "case", "kinematic armstrong-frederick C 50 Xsat 50")
    material = case / "material.dat"
    material.write_text(re.sub(r"(?m)^hardening .*\n", "", material.read_text()))
    number = material_line(case, "kinematic")
    with pytest.raises(DeckError) as error:
        read_case(case)
    assert (f"material.dat:{number}: a kinematic hardening needs the isotropic one"
            in str(error.value)), str(error.value)


def material_line(case: Path, key: str) -> int:
    lines = (case / "material.dat").read_text().splitlines()
    return next(i for i, text in enumerate(lines, 1) if text.startswith(key))
