"""Bezier patches against an independent Bernstein-sum reference (docs/theory/surfaces.md).

Tolerances are relative to the size of the control net plus the rounding level of the power
basis: Horner on a monomial form over [0, 1]^2 rounds at about eps * sum_kl |A_kl| (``noise``),
which for a random degree (6, 6) net is some 1e5 times the net size. That conditioning is the
paper's reason to cap the degree at 6; the tests must not fail on it.
"""

from __future__ import annotations

from math import comb

import numpy as np
import pytest

from ddpy.geometry.surfaces import BezierSurface

DEGREES = [(n, m) for n in range(1, 7) for m in range(1, 7)]
POINTS_PER_PATCH = 40


def bernstein(n: int, i: int, t: np.ndarray) -> np.ndarray:
    """B_i^n(t) = C(n, i) t^i (1 - t)^(n - i); zero outside 0 <= i <= n."""
    if i < 0 or i > n:
        return np.zeros_like(t)
    return comb(n, i) * t**i * (1.0 - t) ** (n - i)


def bernstein_derivative(n: int, i: int, t: np.ndarray) -> np.ndarray:
    """d/dt B_i^n(t) = n (B_{i-1}^{n-1}(t) - B_i^{n-1}(t))."""
    return n * (bernstein(n - 1, i - 1, t) - bernstein(n - 1, i, t))


def reference(net: np.ndarray, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, ...]:
    """Point, S_u and S_v of the Bernstein sum sum_ij B_i^n(u) B_j^m(v) P_ij."""
    n, m = net.shape[0] - 1, net.shape[1] - 1
    bu = np.stack([bernstein(n, i, u) for i in range(n + 1)], axis=1)
    bv = np.stack([bernstein(m, j, v) for j in range(m + 1)], axis=1)
    du = np.stack([bernstein_derivative(n, i, u) for i in range(n + 1)], axis=1)
    dv = np.stack([bernstein_derivative(m, j, v) for j in range(m + 1)], axis=1)
    point = np.einsum("ki,kj,ijx->kx", bu, bv, net)
    s_u = np.einsum("ki,kj,ijx->kx", du, bv, net)
    s_v = np.einsum("ki,kj,ijx->kx", bu, dv, net)
    return point, s_u, s_v


@pytest.fixture(scope="module")
def random_surface():
    """One surface with a random patch of every degree pair (n, m) in 1..6 x 1..6."""
    rng = np.random.default_rng(20240611)
    nets = [rng.uniform(-1.0, 1.0, size=(n + 1, m + 1, 3)) for n, m in DEGREES]
    surface = BezierSurface(nets)
    ids = np.repeat(np.arange(len(nets)), POINTS_PER_PATCH)
    uv = rng.uniform(0.0, 1.0, size=(ids.size, 2))
    return surface, nets, ids, uv


EPS = np.finfo(float).eps


def noise(surface: BezierSurface, patch: int) -> float:
    """Rounding level of a power-basis evaluation of one patch on [0, 1]^2."""
    return EPS * np.abs(surface.power_coefficients(patch)).sum(axis=(0, 1)).max()


def per_patch(surface: BezierSurface, ids: np.ndarray, nets: list[np.ndarray]):
    """(patch, its query rows, its net size, its rounding level, its top degree) per patch."""
    for p, net in enumerate(nets):
        yield p, ids == p, np.abs(net).max(), noise(surface, p), max(net.shape[:2]) - 1


def test_degrees_recorded(random_surface):
    surface, nets, _, _ = random_surface
    assert surface.n_patches == 36
    assert [tuple(d) for d in surface.degrees] == DEGREES


def test_points_match_bernstein_sum_and_de_casteljau(random_surface):
    surface, nets, ids, uv = random_surface
    points, _, _ = surface.evaluate(ids, uv)
    casteljau = surface.evaluate_de_casteljau(ids, uv)
    assert points.shape == casteljau.shape == (ids.size, 3)
    for p, rows, scale, _, _ in per_patch(surface, ids, nets):
        ref, _, _ = reference(nets[p], uv[rows, 0], uv[rows, 1])
        np.testing.assert_allclose(casteljau[rows], ref, rtol=0, atol=1e-12 * scale)
        # The core's power basis about the patch centre keeps the rounding below 1e-12
        # relative even at degree 6 x 6 (about 4e-12 in the plain basis about 0).
        np.testing.assert_allclose(points[rows], ref, rtol=0, atol=1e-12 * scale)


def test_first_derivatives_match_bernstein_derivatives(random_surface):
    surface, nets, ids, uv = random_surface
    _, derivs, _ = surface.evaluate(ids, uv)
    assert derivs.shape == (ids.size, 2, 3)
    for p, rows, scale, rounding, degree in per_patch(surface, ids, nets):
        _, s_u, s_v = reference(nets[p], uv[rows, 0], uv[rows, 1])
        tol = 1e-11 * scale + degree * rounding
        np.testing.assert_allclose(derivs[rows, 0], s_u, rtol=0, atol=tol)
        np.testing.assert_allclose(derivs[rows, 1], s_v, rtol=0, atol=tol)


def test_second_derivatives_match_bernstein_derivatives(random_surface):
    surface, nets, ids, uv = random_surface
    second = surface.second_derivatives(ids, uv)
    assert second.shape == (ids.size, 3, 3)

    def basis(n, t, order):
        if order == 0:
            return np.stack([bernstein(n, i, t) for i in range(n + 1)], axis=1)
        if order == 1:
            return np.stack([bernstein_derivative(n, i, t) for i in range(n + 1)], axis=1)
        return np.stack([n * (n - 1) * (bernstein(n - 2, i - 2, t) - 2 * bernstein(n - 2, i - 1, t)
                                         + bernstein(n - 2, i, t)) for i in range(n + 1)], axis=1)

    for p, rows, scale, rounding, degree in per_patch(surface, ids, nets):
        net, u, v = nets[p], uv[rows, 0], uv[rows, 1]
        n, m = net.shape[0] - 1, net.shape[1] - 1
        tol = 1e-10 * scale + degree**2 * rounding
        for column, (a, b) in enumerate([(2, 0), (1, 1), (0, 2)]):
            exact = np.einsum("ki,kj,ijx->kx", basis(n, u, a), basis(m, v, b), net)
            np.testing.assert_allclose(second[rows, column], exact, rtol=0, atol=tol)


def test_first_derivatives_match_finite_differences(random_surface):
    surface, nets, ids, uv = random_surface
    h = 1e-6
    _, derivs, _ = surface.evaluate(ids, uv)
    for a in range(2):
        step = np.zeros(2)
        step[a] = h
        plus, _, _ = surface.evaluate(ids, uv + step)
        minus, _, _ = surface.evaluate(ids, uv - step)
        fd = (plus - minus) / (2 * h)
        for _, rows, scale, rounding, _ in per_patch(surface, ids, nets):
            # the rounding noise of the points is amplified by 1 / h in the difference quotient
            tol = 1e-7 * scale + rounding / h
            np.testing.assert_allclose(derivs[rows, a], fd[rows], rtol=0, atol=tol)


def test_second_derivatives_match_finite_differences(random_surface):
    surface, nets, ids, uv = random_surface
    h = 1e-6
    second = surface.second_derivatives(ids, uv)
    fd = {}
    for a in range(2):
        step = np.zeros(2)
        step[a] = h
        _, plus, _ = surface.evaluate(ids, uv + step)
        _, minus, _ = surface.evaluate(ids, uv - step)
        fd[a] = (plus - minus) / (2 * h)  # fd[a][:, b] = d/da dS/db
    for _, rows, scale, rounding, degree in per_patch(surface, ids, nets):
        tol = 1e-6 * scale + degree * rounding / h
        np.testing.assert_allclose(second[rows, 0], fd[0][rows, 0], rtol=0, atol=tol)  # S_uu
        np.testing.assert_allclose(second[rows, 1], fd[0][rows, 1], rtol=0, atol=tol)  # S_uv
        np.testing.assert_allclose(second[rows, 1], fd[1][rows, 0], rtol=0, atol=tol)  # S_vu
        np.testing.assert_allclose(second[rows, 2], fd[1][rows, 1], rtol=0, atol=tol)  # S_vv


def test_normals_are_unit_cross_product(random_surface):
    surface, _, ids, uv = random_surface
    _, derivs, normals = surface.evaluate(ids, uv)
    cross = np.cross(derivs[:, 0], derivs[:, 1])
    length = np.linalg.norm(cross, axis=1)
    regular = length > 1e-6  # stay away from (near-)singular points of the random nets
    assert regular.mean() > 0.95
    np.testing.assert_allclose(np.linalg.norm(normals[regular], axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(normals[regular], cross[regular] / length[regular, None],
                               rtol=0, atol=1e-10)


def test_cubic_power_coefficients():
    rng = np.random.default_rng(3)
    net = rng.normal(size=(4, 4, 3))
    m3 = np.array([[1, 0, 0, 0], [-3, 3, 0, 0], [3, -6, 3, 0], [-1, 3, -3, 1]], dtype=float)
    surface = BezierSurface([rng.normal(size=(2, 3, 3)), net])
    expected = np.einsum("ki,ijx,lj->klx", m3, net, m3)
    coef = surface.power_coefficients(1)
    assert coef.shape == (4, 4, 3)
    np.testing.assert_allclose(coef, expected, rtol=0, atol=1e-13)
    # and the power basis sum reproduces the evaluated points
    uv = rng.uniform(size=(20, 2))
    powers_u = uv[:, :1] ** np.arange(4)
    powers_v = uv[:, 1:] ** np.arange(4)
    points, _, _ = surface.evaluate(np.ones(20, dtype=int), uv)
    np.testing.assert_allclose(points, np.einsum("kp,kq,pqx->kx", powers_u, powers_v, coef),
                               rtol=0, atol=1e-12)


def test_power_coefficients_of_mixed_degree_patch():
    rng = np.random.default_rng(4)
    net = rng.normal(size=(3, 6, 3))  # degree (2, 5)
    surface = BezierSurface([net])

    def matrix(n):
        return np.array([[(-1) ** (k - i) * comb(n, k) * comb(k, i) if k >= i else 0
                          for i in range(n + 1)] for k in range(n + 1)], dtype=float)

    expected = np.einsum("ki,ijx,lj->klx", matrix(2), net, matrix(5))
    np.testing.assert_allclose(surface.power_coefficients(0), expected, rtol=0, atol=1e-12)


def test_bilinear_patch_is_bilinear_interpolation():
    rng = np.random.default_rng(5)
    net = rng.normal(size=(2, 2, 3))
    surface = BezierSurface(net[None])  # one (patches, n+1, m+1, 3) array
    uv = rng.uniform(-0.5, 1.5, size=(50, 2))  # outside the domain too: it is a polynomial
    u, v = uv[:, :1], uv[:, 1:]
    expected = ((1 - u) * (1 - v) * net[0, 0] + u * (1 - v) * net[1, 0]
                + (1 - u) * v * net[0, 1] + u * v * net[1, 1])
    points, derivs, _ = surface.evaluate(np.zeros(50, dtype=int), uv)
    np.testing.assert_allclose(points, expected, rtol=0, atol=1e-13)
    np.testing.assert_allclose(derivs[:, 0], (1 - v) * (net[1, 0] - net[0, 0])
                               + v * (net[1, 1] - net[0, 1]), rtol=0, atol=1e-13)
    second = surface.second_derivatives(np.zeros(50, dtype=int), uv)
    np.testing.assert_allclose(second[:, 0], 0.0, atol=1e-14)
    np.testing.assert_allclose(second[:, 2], 0.0, atol=1e-14)
    np.testing.assert_allclose(second[:, 1], np.broadcast_to(
        net[1, 1] - net[1, 0] - net[0, 1] + net[0, 0], (50, 3)), rtol=0, atol=1e-13)


def test_corners_interpolate_control_net():
    rng = np.random.default_rng(6)
    nets = [rng.normal(size=(n + 1, m + 1, 3)) for n, m in DEGREES]
    surface = BezierSurface(nets)
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    ids = np.repeat(np.arange(len(nets)), 4)
    params = np.tile(corners, (len(nets), 1))
    expected = np.concatenate([[net[0, 0], net[-1, 0], net[0, -1], net[-1, -1]] for net in nets])
    points, _, _ = surface.evaluate(ids, params)
    for p, net in enumerate(nets):
        tol = 1e-12 * np.abs(net).max() + noise(surface, p)
        np.testing.assert_allclose(points[ids == p], expected[ids == p], rtol=0, atol=tol)
    np.testing.assert_array_equal(surface.evaluate_de_casteljau(ids, params), expected)


def test_flat_net_has_constant_normal():
    rng = np.random.default_rng(7)
    # a planar control net (random points of the plane through o spanned by e1, e2)
    o = np.array([1.0, -2.0, 0.5])
    e1 = np.array([1.0, 2.0, 0.0]) / np.sqrt(5.0)
    e2 = np.array([-2.0, 1.0, 3.0]) / np.sqrt(14.0)
    grid = np.stack(np.meshgrid(np.linspace(0, 1, 5), np.linspace(0, 1, 4), indexing="ij"), -1)
    coords = grid + rng.uniform(-0.05, 0.05, size=grid.shape)
    net = o + coords[..., :1] * e1 + coords[..., 1:] * e2
    surface = BezierSurface([net])
    uv = rng.uniform(size=(100, 2))
    points, _, normals = surface.evaluate(np.zeros(100, dtype=int), uv)
    expected = np.cross(e1, e2) / np.linalg.norm(np.cross(e1, e2))
    np.testing.assert_allclose(normals, np.broadcast_to(expected, normals.shape), atol=1e-12)
    np.testing.assert_allclose((points - o) @ expected, 0.0, atol=1e-13)


def power_to_bernstein(n: int) -> np.ndarray:
    """Inverse of the Bernstein-to-power matrix: M_n^-1[i][k] = C(i, k) / C(n, k), i >= k."""
    return np.array([[comb(i, k) / comb(n, k) if i >= k else 0.0 for k in range(n + 1)]
                     for i in range(n + 1)])


def test_inverse_matrix_is_inverse():
    for n in range(1, 7):
        m = np.array([[(-1) ** (k - i) * comb(n, k) * comb(k, i) if k >= i else 0
                       for i in range(n + 1)] for k in range(n + 1)], dtype=float)
        np.testing.assert_allclose(power_to_bernstein(n) @ m, np.eye(n + 1), atol=1e-13)


def test_paraboloid_is_reproduced_exactly():
    # S(u, v) = (u, v, u^2 + v^2): power coefficients A[k, l] (vectors), then P = Minv A Minv^T
    power = np.zeros((3, 3, 3))
    power[1, 0, 0] = 1.0  # x = u
    power[0, 1, 1] = 1.0  # y = v
    power[2, 0, 2] = 1.0  # z = u^2
    power[0, 2, 2] = 1.0  # z += v^2
    inverse = power_to_bernstein(2)
    net = np.einsum("ik,klx,jl->ijx", inverse, power, inverse)
    np.testing.assert_allclose(net[1, 1], [0.5, 0.5, 0.0])  # the classical control point
    surface = BezierSurface([net])
    np.testing.assert_allclose(surface.power_coefficients(0), power, atol=1e-15)
    uv = np.random.default_rng(8).uniform(size=(200, 2))
    u, v = uv[:, 0], uv[:, 1]
    ids = np.zeros(200, dtype=int)
    points, derivs, normals = surface.evaluate(ids, uv)
    np.testing.assert_allclose(points, np.stack([u, v, u**2 + v**2], 1), rtol=0, atol=1e-15)
    np.testing.assert_allclose(derivs[:, 0], np.stack([1 + 0 * u, 0 * u, 2 * u], 1), atol=1e-15)
    np.testing.assert_allclose(derivs[:, 1], np.stack([0 * u, 1 + 0 * u, 2 * v], 1), atol=1e-15)
    exact_normal = np.stack([-2 * u, -2 * v, 1 + 0 * u], 1)
    exact_normal /= np.linalg.norm(exact_normal, axis=1)[:, None]
    np.testing.assert_allclose(normals, exact_normal, rtol=0, atol=1e-15)
    second = surface.second_derivatives(ids, uv)
    np.testing.assert_allclose(second, np.broadcast_to(
        [[0, 0, 2], [0, 0, 0], [0, 0, 2]], (200, 3, 3)), atol=1e-15)
