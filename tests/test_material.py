"""Hill'48 / Swift / Voce material: return mapping, consistent tangent, uniaxial tension.

References are independent of the core: Hill's closed forms for r-values and yield stress
ratios, the hardening laws written out here, the backward-Euler equations checked term by term,
central finite differences, and the von Mises radial return solved with SciPy.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from ddpy import _core
from ddpy.core.parallel import threads
from ddpy.model.material import (
    HardeningTable,
    Hill48,
    Material,
    ReturnMappingError,
    Swift,
    Voce,
)

E, NU = 210e3, 0.3
# Reverse deep drawing, DDQ steel (paper Table 4) and cylindrical bending, HSS (Table 1).
DDQ = Hill48(F=0.3137, G=0.3663, H=0.6337, L=1.5, M=1.5, N=1.1764)
HSS = Hill48(F=0.254, G=0.397, H=0.603, N=1.689)
SWIFT = Swift(K=568.3, eps0=0.0059, n=0.233)
VOCE = Voce(Y0=200.0, Q=250.0, b=8.0)
MATERIALS = {
    "ddq-swift": Material(E, NU, DDQ, SWIFT),
    "hss-voce": Material(E, NU, HSS, VOCE),
    "mises-swift": Material(E, NU, Hill48.von_mises(), Swift(K=645.3, eps0=0.0102, n=0.252)),
}


# --- independent references --------------------------------------------------------------

def hill_matrix(h: Hill48) -> np.ndarray:
    """P with s.P.s = 2 f (Voigt 11, 22, 33, 12, 23, 31)."""
    F, G, H, L, M, N = h.F, h.G, h.H, h.L, h.M, h.N
    p = np.zeros((6, 6))
    p[:3, :3] = [[G + H, -H, -G], [-H, F + H, -F], [-G, -F, F + G]]
    p[3, 3], p[4, 4], p[5, 5] = 2 * N, 2 * L, 2 * M
    return p


def hill_stress(h: Hill48, s: np.ndarray) -> np.ndarray:
    """sqrt(2 f) from stress differences (s.P.s would lose digits to a large pressure)."""
    return np.sqrt(h.F * (s[..., 1] - s[..., 2]) ** 2 + h.G * (s[..., 2] - s[..., 0]) ** 2
                   + h.H * (s[..., 0] - s[..., 1]) ** 2
                   + 2 * (h.L * s[..., 4] ** 2 + h.M * s[..., 5] ** 2 + h.N * s[..., 3] ** 2))


def flow_stress(material: Material, ep: np.ndarray) -> np.ndarray:
    law = material.hardening
    if isinstance(law, Swift):
        return law.K * (law.eps0 + ep) ** law.n
    return law.Y0 + law.Q * (1 - np.exp(-law.b * ep))


def compliance(material: Material) -> np.ndarray:
    e, nu = material.E, material.nu
    s = np.zeros((6, 6))
    s[:3, :3] = -nu / e
    s[range(3), range(3)] = 1 / e
    s[range(3, 6), range(3, 6)] = 2 * (1 + nu) / e
    return s


def hill_r_value(h: Hill48, angle: float) -> float:
    """Lankford coefficient at ``angle`` to RD (Hill 1948)."""
    s2, c2 = math.sin(angle) ** 2, math.cos(angle) ** 2
    return (h.H + (2 * h.N - h.F - h.G - 4 * h.H) * s2 * c2) / (h.F * s2 + h.G * c2)


def hill_ratio(h: Hill48, angle: float) -> float:
    """sigma_theta / sigma_0 = sqrt((G + H) / (F s^4 + G c^4 + H (c^2 - s^2)^2 + 2 N s^2 c^2)),
    from 2 f of the stress sigma (c^2, s^2, 0, s c, 0, 0)."""
    s, c = math.sin(angle), math.cos(angle)
    return math.sqrt((h.G + h.H) / (h.F * s**4 + h.G * c**4 + h.H * (c * c - s * s) ** 2
                                    + 2 * h.N * s * s * c * c))


def random_states(material: Material, k: int, rng: np.random.Generator,
                  level: tuple[float, float] = (0.3, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """Stresses with sigma_eq = level * Y(ep_old) plus a random pressure, ep_old in [0, 0.3]."""
    ep = rng.uniform(0, 0.3, k)
    s = rng.normal(size=(k, 6))
    s *= (rng.uniform(*level, k) * flow_stress(material, ep) / hill_stress(
        material.yield_criterion, s))[:, None]
    s[:, :3] += rng.normal(scale=200.0, size=(k, 1))
    return s, ep


def random_increments(material: Material, k: int, rng: np.random.Generator,
                      multiple: float) -> np.ndarray:
    """Random directions of norm ``multiple`` times the initial yield strain."""
    d = rng.normal(size=(k, 6))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return d * multiple * material.hardening.initial_yield_stress / material.E


def finite_difference_tangent(material: Material, s: np.ndarray, ep: np.ndarray,
                              de: np.ndarray) -> np.ndarray:
    """Central differences of the updated stress in the 6 increment components."""
    k = s.shape[0]
    h = 1e-6 * np.linalg.norm(de, axis=1)
    plus = np.repeat(de[:, None, :], 6, axis=1) + h[:, None, None] * np.eye(6)
    minus = np.repeat(de[:, None, :], 6, axis=1) - h[:, None, None] * np.eye(6)
    both = np.concatenate([plus.reshape(-1, 6), minus.reshape(-1, 6)])
    stress = material.update(np.tile(np.repeat(s, 6, axis=0), (2, 1)),
                             np.tile(np.repeat(ep, 6), 2), both)[0]
    sp, sm = stress[: 6 * k].reshape(k, 6, 6), stress[6 * k:].reshape(k, 6, 6)
    return ((sp - sm) / (2 * h[:, None, None])).transpose(0, 2, 1)  # [point, stress, strain]


# --- return mapping -------------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_consistent_tangent_matches_finite_differences(name: str) -> None:
    material = MATERIALS[name]
    rng = np.random.default_rng(7)
    s, ep = random_states(material, 40, rng)
    de = random_increments(material, 40, rng, rng.uniform(2, 20, 40)[:, None])
    stress, ep_new, tangent, plastic = material.update(s, ep, de)
    assert plastic.sum() > 20
    fd = finite_difference_tangent(material, s, ep, de)
    error = np.abs(fd - tangent).max(axis=(1, 2)) / np.abs(tangent).max(axis=(1, 2))
    assert error.max() < 1e-6, error.max()
    np.testing.assert_allclose(tangent, tangent.transpose(0, 2, 1), rtol=0, atol=1e-9 * E)
    # Plastic tangents are softer than the elastic one along the flow direction.
    n = np.einsum("ij,kj->ki", hill_matrix(material.yield_criterion), stress)
    c = material.elastic_tangent()
    assert np.all(np.einsum("ki,kij,kj->k", n, tangent, n)[plastic]
                  < np.einsum("ki,ij,kj->k", n, c, n)[plastic])


def test_elastic_steps_are_exact() -> None:
    material = MATERIALS["ddq-swift"]
    rng = np.random.default_rng(3)
    s, ep = random_states(material, 30, rng, level=(0.2, 0.5))
    de = random_increments(material, 30, rng, 0.2)
    stress, ep_new, tangent, plastic = material.update(s, ep, de)
    c = material.elastic_tangent()
    assert not plastic.any()
    np.testing.assert_array_equal(ep_new, ep)
    np.testing.assert_allclose(stress, s + de @ c.T, rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(tangent, np.broadcast_to(c, tangent.shape), rtol=1e-14)
    fd = finite_difference_tangent(material, s, ep, de)
    assert np.abs(fd - tangent).max() / np.abs(c).max() < 1e-6


@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_backward_euler_equations_hold(name: str) -> None:
    """On the yield surface, associative flow dEp = dlambda P s, plastic work = Y dep,
    isochoric flow, and the elastic law for the rest."""
    material = MATERIALS[name]
    rng = np.random.default_rng(11)
    s, ep = random_states(material, 300, rng)
    de = random_increments(material, 300, rng, rng.uniform(0.5, 30, 300)[:, None])
    stress, ep_new, _, plastic = material.update(s, ep, de)
    assert plastic.sum() > 150
    stress, s, ep, ep_new, de = stress[plastic], s[plastic], ep[plastic], ep_new[plastic], \
        de[plastic]
    y = flow_stress(material, ep_new)
    np.testing.assert_allclose(hill_stress(material.yield_criterion, stress), y, rtol=1e-10)
    dep = ep_new - ep
    assert np.all(dep > 0)
    plastic_strain = de - (stress - s) @ compliance(material).T
    np.testing.assert_allclose(np.einsum("ki,ki->k", stress, plastic_strain), y * dep,
                               rtol=1e-9)
    flow = (dep / y)[:, None] * stress @ hill_matrix(material.yield_criterion).T
    np.testing.assert_allclose(plastic_strain, flow, rtol=0,
                               atol=1e-9 * np.abs(plastic_strain).max())
    np.testing.assert_allclose(plastic_strain[:, :3].sum(axis=1), 0, atol=1e-12)


def test_von_mises_matches_radial_return() -> None:
    """Isotropic case against the textbook radial return solved by bracketing."""
    material = MATERIALS["mises-swift"]
    rng = np.random.default_rng(5)
    s, ep = random_states(material, 20, rng)
    de = random_increments(material, 20, rng, 25.0)
    stress, ep_new, _, plastic = material.update(s, ep, de)
    g = material.shear_modulus
    trial = s + de @ material.elastic_tangent().T
    for i in range(20):
        p = trial[i, :3].mean()
        dev = trial[i] - p * np.r_[1, 1, 1, 0, 0, 0]
        q_trial = math.sqrt(1.5 * (dev[:3] @ dev[:3] + 2 * dev[3:] @ dev[3:]))
        dep = brentq(lambda x, q=q_trial, e=ep[i]: q - 3 * g * x - flow_stress(material, e + x),
                     0, q_trial / (3 * g), xtol=1e-16, rtol=1e-15)
        expected = p * np.r_[1, 1, 1, 0, 0, 0] + dev * (1 - 3 * g * dep / q_trial)
        assert plastic[i]
        np.testing.assert_allclose(ep_new[i], ep[i] + dep, rtol=1e-12)
        np.testing.assert_allclose(stress[i], expected, rtol=0, atol=1e-9 * q_trial)


@pytest.mark.parametrize("name", sorted(MATERIALS))
def test_large_increments_converge(name: str) -> None:
    material = MATERIALS[name]
    rng = np.random.default_rng(13)
    k = 4000
    s, ep = random_states(material, k, rng, level=(0.0, 1.0))
    multiple = np.concatenate([rng.uniform(10, 50, k // 2), np.geomspace(50, 1e4, k // 2)])
    de = random_increments(material, k, rng, multiple[:, None])
    stress, ep_new, tangent, plastic, status = _core.material_update(
        material.props(), s.ravel(), ep, de.ravel())
    assert np.all(status == 0)
    assert np.all(plastic == 1)
    stress = stress.reshape(k, 6)
    np.testing.assert_allclose(hill_stress(material.yield_criterion, stress),
                               flow_stress(material, ep_new), rtol=1e-10)
    assert np.all(np.isfinite(tangent))


EDGE_MATERIALS = {
    "perfectly-plastic": Material(E, NU, DDQ, Swift(K=300.0, eps0=0.01, n=0.0)),
    "strong-voce": Material(E, NU, DDQ, Voce(Y0=50.0, Q=500.0, b=30.0)),  # H dlambda > 1
    "linear-swift": Material(E, NU, HSS, Swift(K=1000.0, eps0=0.2, n=1.0)),
    "near-singular-hill": Material(E, NU, Hill48(F=0.001, G=0.001, H=1.0, N=1.5), SWIFT),
    "auxetic": Material(E, -0.9, Hill48.von_mises(), VOCE),
}


@pytest.mark.parametrize("name", sorted(EDGE_MATERIALS))
def test_edge_materials(name: str) -> None:
    """Limits of the accepted parameters: the mapping still converges, the tangent is right."""
    material = EDGE_MATERIALS[name]
    rng = np.random.default_rng(19)
    s, ep = random_states(material, 1000, rng, level=(0.0, 1.0))
    de = random_increments(material, 1000, rng, np.geomspace(2, 1e3, 1000)[:, None])
    stress, ep_new, tangent, plastic = material.update(s, ep, de)
    assert plastic.mean() > 0.7
    np.testing.assert_allclose(hill_stress(material.yield_criterion, stress[plastic]),
                               flow_stress(material, ep_new[plastic]), rtol=1e-10)
    pick = np.flatnonzero(plastic)[::50]
    fd = finite_difference_tangent(material, s[pick], ep[pick], de[pick])
    error = np.abs(fd - tangent[pick]).max(axis=(1, 2)) / np.abs(tangent[pick]).max(axis=(1, 2))
    assert error.max() < 1e-6


def test_threads_give_identical_results() -> None:
    material = MATERIALS["ddq-swift"]
    rng = np.random.default_rng(17)
    s, ep = random_states(material, 5000, rng)
    de = random_increments(material, 5000, rng, 10.0)
    with threads(1):
        one = material.update(s, ep, de)
    with threads(2):
        two = material.update(s, ep, de)
    for a, b in zip(one, two, strict=True):
        np.testing.assert_array_equal(a, b)


def test_single_point_and_failure_status() -> None:
    material = MATERIALS["ddq-swift"]
    stress, ep, tangent, plastic = material.update(np.zeros(6), 0.0, [0.01, 0, 0, 0, 0, 0])
    assert stress.shape == (6,) and tangent.shape == (6, 6) and plastic and ep > 0
    props = material.props()
    bad_props = props.copy()
    bad_props[0] = -1.0
    nan_input = np.array([np.nan, 0, 0, 0, 0, 0.0])
    for p, de, code in ((bad_props, np.zeros(6), 2), (props, nan_input, 3)):
        out = _core.material_update(p, np.zeros(6), np.zeros(1), de)
        assert out[-1][0] == code
    with pytest.raises(ValueError, match="stress_old has a non-finite value"):
        material.update(nan_input, 0.0, np.zeros(6))


# --- uniaxial tension in the sheet plane ----------------------------------------------------

def voigt_rotations(angle: float) -> tuple[np.ndarray, np.ndarray]:
    """(Te, Ts): strain in the loading frame -> material frame (engineering shears), and
    stress in the material frame -> loading frame. Loading axis at ``angle`` to RD in 1-2."""
    c, s = math.cos(angle), math.sin(angle)
    r = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])  # columns: loading axes
    pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0)]

    def tensor(v: np.ndarray, shear: float) -> np.ndarray:
        t = np.zeros((3, 3))
        for m, (i, j) in enumerate(pairs):
            t[i, j] = t[j, i] = v[m] * (shear if m >= 3 else 1.0)
        return t

    te, ts = np.zeros((6, 6)), np.zeros((6, 6))
    for m in range(6):
        unit = np.eye(6)[m]
        strain = r @ tensor(unit, 0.5) @ r.T
        stress = r.T @ tensor(unit, 1.0) @ r
        te[:, m] = [strain[i, j] * (2.0 if n >= 3 else 1.0) for n, (i, j) in enumerate(pairs)]
        ts[:, m] = [stress[i, j] for i, j in pairs]
    return te, ts


def uniaxial_tension(material: Material, angle: float, total: float, steps: int) -> dict:
    """Uniaxial stress driver: the axial strain rises in equal steps, the five other stresses
    of the loading frame are held at zero by a Newton iteration on the other five strain
    increments with the consistent tangent."""
    te, ts = voigt_rotations(angle)
    stress, ep = np.zeros(6), 0.0
    strain = np.zeros(6)  # loading frame
    lateral = np.zeros(5)
    history = {"strain": [], "stress": [], "ep": [], "dplastic": []}
    s_loading_old = np.zeros(6)
    iterations = []
    for _ in range(steps):
        solves = 0
        while True:
            de = np.r_[total / steps, lateral]
            new, ep_new, tangent, _ = material.update(stress, ep, te @ de)
            s_loading = ts @ new
            residual = s_loading[1:]
            if np.abs(residual).max() <= 1e-11 * abs(s_loading[0]):
                break
            assert solves < 25, "uniaxial driver did not converge"
            jacobian = (ts @ tangent @ te)[1:, 1:]
            lateral = lateral - np.linalg.solve(jacobian, residual)
            solves += 1
        iterations.append(solves)
        history["dplastic"].append(de - compliance(material) @ (s_loading - s_loading_old))
        stress, ep, strain = new, ep_new, strain + de
        s_loading_old = s_loading
        history["strain"].append(strain.copy())
        history["stress"].append(s_loading)
        history["ep"].append(ep)
    out = {key: np.array(value) for key, value in history.items()}
    out["iterations"] = np.array(iterations)
    return out


ANGLES = {0: 0.0, 45: math.pi / 4, 90: math.pi / 2}
PAPER_R = {0: 1.73, 45: 1.23, 90: 2.02}


@pytest.fixture(scope="module")
def ddq_tension() -> dict[int, dict]:
    # 0.005 per step is about 6 times the yield strain: the mapping takes big steps.
    return {deg: uniaxial_tension(MATERIALS["ddq-swift"], angle, 0.30, 60)
            for deg, angle in ANGLES.items()}


@pytest.mark.parametrize("deg", sorted(ANGLES))
def test_uniaxial_r_values(ddq_tension: dict[int, dict], deg: int) -> None:
    run = ddq_tension[deg]
    plastic = run["ep"] > 0
    dp = run["dplastic"][plastic]
    r = dp[:, 1] / dp[:, 2]  # width / thickness plastic strain increments
    assert abs(r[-1] / PAPER_R[deg] - 1) < 0.01
    np.testing.assert_allclose(r, hill_r_value(DDQ, ANGLES[deg]), rtol=1e-8)
    np.testing.assert_allclose(r, DDQ.r_value(ANGLES[deg]), rtol=1e-8)
    # Newton on the lateral strains converges in a few iterations (quadratic).
    assert run["iterations"].max() <= 6


@pytest.mark.parametrize("deg", [45, 90])
def test_uniaxial_yield_stress_ratios(ddq_tension: dict[int, dict], deg: int) -> None:
    base, run = ddq_tension[0], ddq_tension[deg]
    for ep in (0.02, 0.1, 0.2):
        ratio = (np.interp(ep, run["ep"], run["stress"][:, 0])
                 / np.interp(ep, base["ep"], base["stress"][:, 0]))
        assert abs(ratio / hill_ratio(DDQ, ANGLES[deg]) - 1) < 0.01
    # Exactly, at every plastic step: sigma_theta = Y(ep) times the closed-form ratio.
    plastic = run["ep"] > 0
    np.testing.assert_allclose(
        run["stress"][plastic, 0] / flow_stress(MATERIALS["ddq-swift"], run["ep"][plastic]),
        hill_ratio(DDQ, ANGLES[deg]), rtol=1e-9)
    np.testing.assert_allclose(DDQ.yield_stress_ratio(ANGLES[deg]), hill_ratio(DDQ, ANGLES[deg]),
                               rtol=1e-14)


def test_uniaxial_swift_curve(ddq_tension: dict[int, dict]) -> None:
    run = ddq_tension[0]
    sigma = run["stress"][:, 0]
    plastic_strain = run["strain"][:, 0] - sigma / E
    yielded = run["ep"] > 0
    swift = 568.3 * (0.0059 + plastic_strain[yielded]) ** 0.233
    error = np.abs(sigma[yielded] / swift - 1)
    assert error.max() < 1e-3
    assert plastic_strain[-1] > 0.29
    np.testing.assert_allclose(plastic_strain[yielded], run["ep"][yielded], rtol=1e-9)
    np.testing.assert_allclose(sigma[yielded], swift, rtol=1e-9)  # exact for radial paths


def test_uniaxial_voce_curve() -> None:
    material = Material(E, NU, DDQ, VOCE)
    run = uniaxial_tension(material, 0.0, 0.2, 40)
    sigma = run["stress"][:, 0]
    plastic_strain = run["strain"][:, 0] - sigma / E
    yielded = run["ep"] > 0
    np.testing.assert_allclose(
        sigma[yielded], 200 + 250 * (1 - np.exp(-8 * plastic_strain[yielded])), rtol=1e-9)


# --- Hill'48 from r-values, and bad input ---------------------------------------------------

def test_r_values_back_out() -> None:
    assert (round(DDQ.r0, 2), round(DDQ.r45, 2), round(DDQ.r90, 2)) == (1.73, 1.23, 2.02)
    assert (round(HSS.r0, 3), round(HSS.r45, 3), round(HSS.r90, 3)) == (1.519, 2.094, 2.374)
    assert DDQ.r0 == pytest.approx(0.6337 / 0.3663)
    assert DDQ.r90 == pytest.approx(0.6337 / 0.3137)
    assert DDQ.r45 == pytest.approx(1.1764 / (0.3137 + 0.3663) - 0.5)
    for angle in ANGLES.values():
        assert DDQ.r_value(angle) == pytest.approx(hill_r_value(DDQ, angle), rel=1e-14)


def test_plane_strain_ratio_by_direct_minimisation() -> None:
    """The plane-strain state minimises the equivalent stress over the stress across the
    load at a fixed stress along it (zero strain across by normality): found by a scalar
    search on ``equivalent_stress`` instead of the closed form, at several angles, and the
    two textbook values (von Mises 2 / sqrt(3), normal anisotropy (1 + r) / sqrt(1 + 2 r))."""
    from scipy.optimize import minimize_scalar

    def searched(h: Hill48, angle: float) -> float:
        c, s = math.cos(angle), math.sin(angle)

        def equivalent(across: float) -> float:
            # 1 along (c, s), ``across`` along (-s, c); Voigt order 11 22 33 12 23 31.
            stress = [c * c + across * s * s, s * s + across * c * c, 0.0,
                      (1.0 - across) * s * c, 0.0, 0.0]
            return float(h.equivalent_stress(np.array(stress)))

        return 1.0 / minimize_scalar(equivalent, bounds=(-1.0, 2.0), method="bounded",
                                     options={"xatol": 1e-12}).fun

    for h in (DDQ, HSS):
        for angle in (0.0, 0.3, math.pi / 4, 1.2, math.pi / 2):
            assert h.plane_strain_ratio(angle) == pytest.approx(searched(h, angle), rel=1e-9)
    angles = np.linspace(0.0, math.pi / 2, 7)
    np.testing.assert_allclose(Hill48.von_mises().plane_strain_ratio(angles),
                               2 / math.sqrt(3), rtol=1e-14)
    r = 1.8
    normal = Hill48(F=1 / (1 + r), G=1 / (1 + r), H=r / (1 + r), N=(1 + 2 * r) / (1 + r))
    np.testing.assert_allclose(normal.plane_strain_ratio(angles), (1 + r) / math.sqrt(1 + 2 * r),
                               rtol=1e-14)


def test_from_r_values_round_trip() -> None:
    fitted = Hill48.from_r_values(1.73, 1.23, 2.02)
    np.testing.assert_allclose(fitted.coefficients, DDQ.coefficients, atol=2e-4)
    assert fitted.G + fitted.H == pytest.approx(1.0, rel=1e-15)
    assert (fitted.r0, fitted.r45, fitted.r90) == pytest.approx((1.73, 1.23, 2.02), rel=1e-14)
    for h in (DDQ, HSS, Hill48.von_mises()):
        back = Hill48.from_r_values(h.r0, h.r45, h.r90)
        scale = h.G + h.H  # from_r_values normalises to G + H = 1 with L = M = 1.5
        expected = np.array(h.coefficients) / scale
        expected[3:5] = 1.5
        np.testing.assert_allclose(back.coefficients, expected, rtol=1e-13)
    # The paper's closed form for F, G, H, N.
    r0, r45, r90 = 1.519, 2.094, 2.374
    expected = (r0 / (r90 * (1 + r0)), 1 / (1 + r0), r0 / (1 + r0), 1.5, 1.5,
                (r0 + r90) * (1 + 2 * r45) / (2 * r90 * (1 + r0)))
    assert Hill48.from_r_values(r0, r45, r90).coefficients == pytest.approx(expected, rel=1e-14)


def test_yield_stress_and_props() -> None:
    material = MATERIALS["ddq-swift"]
    ep = np.array([0.0, 0.1, 0.5])
    np.testing.assert_allclose(material.yield_stress(ep), flow_stress(material, ep), rtol=1e-14)
    y, slope = material.hardening_curve(ep)
    np.testing.assert_allclose(slope, 0.233 * 568.3 * (0.0059 + ep) ** -0.767, rtol=1e-13)
    assert SWIFT.initial_yield_stress == pytest.approx(171.9, abs=0.05)
    props = material.props()
    assert props.shape == (216,)
    np.testing.assert_array_equal(props[:12], [E, NU, 0.3137, 0.3663, 0.6337, 1.5, 1.5, 1.1764,
                                               1, 568.3, 0.0059, 0.233])
    assert not props[12:].any()
    assert MATERIALS["hss-voce"].props()[8:12].tolist() == [2, 200.0, 250.0, 8.0]


@pytest.mark.parametrize(("build", "message"), [
    (lambda: Material(0.0, NU, DDQ, SWIFT), "Young's modulus E must be positive"),
    (lambda: Material(-5.0, NU, DDQ, SWIFT), "Young's modulus E must be positive"),
    (lambda: Material(E, 0.5, DDQ, SWIFT), r"Poisson's ratio nu must lie in \(-1, 0.5\)"),
    (lambda: Material(E, -1.0, DDQ, SWIFT), r"Poisson's ratio nu must lie in \(-1, 0.5\)"),
    (lambda: Material(float("nan"), NU, DDQ, SWIFT), "E must be finite"),
    (lambda: Hill48(F=-0.5, G=0.2, H=0.2, N=1.5), "do not define a convex yield surface"),
    (lambda: Hill48(F=1.0, G=-0.4, H=-0.4, N=1.5), "do not define a convex yield surface"),
    (lambda: Hill48(F=0.3, G=0.4, H=0.6, N=0.0), "N must be positive"),
    (lambda: Hill48(F=0.3, G=0.4, H=0.6, L=-1.0, N=1.2), "L must be positive"),
    (lambda: Hill48.from_r_values(1.7, 0.0, 2.0), "r-values must be positive"),
    (lambda: Swift(K=-568.3, eps0=0.0059, n=0.233), "Swift K must be positive"),
    (lambda: Swift(K=568.3, eps0=0.0, n=0.233), "Swift eps0 must be positive"),
    (lambda: Swift(K=568.3, eps0=0.0059, n=1.5), r"Swift exponent n must lie in \[0, 1\]"),
    (lambda: Voce(Y0=0.0, Q=100.0, b=10.0), "Voce Y0 must be positive"),
    (lambda: Voce(Y0=200.0, Q=-100.0, b=10.0), "Voce Q must be non-negative"),
    (lambda: Voce(Y0=200.0, Q=100.0, b=-1.0), "Voce b must be non-negative"),
    (lambda: MATERIALS["ddq-swift"].update(np.zeros((2, 6)), [0.0, -0.1], np.zeros((2, 6))),
     "ep_old must be non-negative"),
    (lambda: MATERIALS["ddq-swift"].update(np.zeros((2, 6)), [0.0, 0.0], np.zeros((3, 6))),
     r"strain_increment must have shape \(2, 6\)"),
])
def test_bad_input_raises_value_error(build, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        build()


def test_bad_types_raise_type_error() -> None:
    with pytest.raises(TypeError, match="yield_criterion must be a Hill48"):
        Material(E, NU, "hill", SWIFT)
    with pytest.raises(TypeError, match="hardening must be Swift, Voce or HardeningTable"):
        Material(E, NU, DDQ, (568.3, 0.0059, 0.233))
    with pytest.raises(TypeError, match="Hill48 F must be a real number"):
        Hill48(F="a", G=0.4, H=0.6, N=1.2)


def test_core_check_agrees() -> None:
    """The core refuses what Python refuses, pointing at the property."""
    good = MATERIALS["ddq-swift"].props()
    assert _core.material_check(good) == 0
    assert _core.material_check(MATERIALS["hss-voce"].props()) == 0
    for index, value in ((0, 0.0), (1, 0.5), (2, -0.5), (7, 0.0), (8, 4.0), (9, -1.0),
                         (10, 0.0), (11, 2.0), (4, np.nan)):
        props = good.copy()
        props[index] = value
        if index == 2:
            props[3:5] = 0.2
        expected = {2: 3, 4: 5}.get(index, index + 1)
        assert _core.material_check(props) == expected, index
    assert _core.hill48_from_r_values(-1.0, 1.0, 1.0).tolist() == [0.0] * 6
    error = ReturnMappingError(np.array([4, 9]), np.array([1, 1], dtype=np.int32))
    assert "2 point(s), first at point 4" in str(error)


def test_hardening_table_interpolates_linearly() -> None:
    """Y(ep) and dY/dep of a table against values computed by hand: on the points, inside
    the segments (the slope of the segment, the right one at a point), beyond the last point
    (constant, slope 0); below 0 the first point."""
    table = HardeningTable((0.0, 0.1, 0.3, 0.5), (200.0, 250.0, 280.0, 290.0))
    material = Material(E, NU, Hill48.von_mises(), table)
    ep = np.array([0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.9, -0.1])
    y, slope = material.hardening_curve(ep)
    # 200 + 500 * 0.05; 250 + 150 * 0.1; 280 + 50 * 0.1
    np.testing.assert_allclose(y, [200, 225, 250, 265, 280, 285, 290, 290, 200], rtol=1e-14)
    np.testing.assert_allclose(slope, [500, 500, 150, 150, 50, 50, 0, 0, 500], rtol=1e-12)
    assert table.initial_yield_stress == 200.0
    props = material.props()
    assert props[8:12].tolist() == [3, 4, 0, 0]
    assert props[16:24].tolist() == [0.0, 200.0, 0.1, 250.0, 0.3, 280.0, 0.5, 290.0]
    assert not props[24:].any()
    # A one-point table: perfectly plastic.
    flat = Material(E, NU, Hill48.von_mises(), HardeningTable((0.0,), (150.0,)))
    np.testing.assert_allclose(flat.hardening_curve([0.0, 1.0]), [[150, 150], [0, 0]])


def test_hardening_table_return_mapping_lands_on_the_curve() -> None:
    """Uniaxial stress along x with a large plastic strain step: the return mapping's stress
    is the table's Y at its ep, and ep is what the table and the elastic strain give."""
    table = HardeningTable((0.0, 0.02, 0.1), (200.0, 300.0, 340.0))
    material = Material(E, NU, Hill48.von_mises(), table)
    stress, ep, _, plastic = material.update(np.zeros(6), 0.0, [0.05, -0.025, -0.025, 0, 0, 0])
    assert plastic
    assert ep > 0.02
    y = 300.0 + 500.0 * (ep - 0.02)
    seq = math.sqrt(0.5 * ((stress[0] - stress[1]) ** 2 + (stress[1] - stress[2]) ** 2
                           + (stress[2] - stress[0]) ** 2) + 3 * (stress[3:] ** 2).sum())
    assert seq == pytest.approx(y, rel=1e-10)


@pytest.mark.parametrize(("strains", "stresses", "message"), [
    ((0.1, 0.2), (200.0, 250.0), "first plastic strain must be 0"),
    ((0.0, 0.2, 0.2), (200.0, 250.0, 260.0), "must be above the one before"),
    ((0.0, 0.2), (200.0, 150.0), "softening is not supported"),
    ((0.0, 0.2), (-1.0, 150.0), "must be positive"),
    ((0.0,), (200.0, 250.0), "1 strains and 2 stresses"),
    (tuple(np.linspace(0, 1, 101)), tuple(np.linspace(100, 200, 101)), "1 to 100 points"),
])
def test_bad_hardening_table_is_refused(strains: tuple[float, ...], stresses: tuple[float, ...],
                                        message: str) -> None:
    with pytest.raises(ValueError, match=message):
        HardeningTable(strains, stresses)


def test_core_refuses_bad_tables() -> None:
    good = Material(E, NU, Hill48.von_mises(),
                    HardeningTable((0.0, 0.1, 0.3), (200.0, 250.0, 280.0))).props()
    assert _core.material_check(good) == 0
    for index, value, expected in ((9, 0.0, 10), (9, 101.0, 10), (9, 2.5, 10), (16, 0.01, 17),
                                   (18, 0.0, 19), (19, 190.0, 20), (17, 0.0, 18)):
        props = good.copy()
        props[index] = value
        assert _core.material_check(props) == expected, index
