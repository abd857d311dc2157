"""The start of an increment (ddpy.model.start) against rigid motions, whose exact
continuation is known."""

import numpy as np
import pytest

from ddpy.model import HexMesh
from ddpy.model.start import blended_start, increment_starts, spin, start_weight

AXIS = np.array([1.0, 2.0, 2.0]) / 3.0  # a unit axis not along a mesh direction
CENTRE = np.array([0.3, -0.2, 4.0])  # off the block, as a die shoulder's centre is


def rotation(angle: float) -> np.ndarray:
    """Rotation matrix by ``angle`` about AXIS (Rodrigues)."""
    k = np.array([[0.0, -AXIS[2], AXIS[1]], [AXIS[2], 0.0, -AXIS[0]],
                  [-AXIS[1], AXIS[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


def turned(nodes: np.ndarray, angle: float) -> np.ndarray:
    """Displacements of ``nodes`` turned rigidly by ``angle`` about AXIS through CENTRE."""
    return CENTRE + (nodes - CENTRE) @ rotation(angle).T - nodes


def turned_start(mesh: HexMesh, u: np.ndarray, rate: np.ndarray, step: float,
                 last: float) -> np.ndarray:
    """The displacements an increment starts from with the turn carried on."""
    return u + increment_starts(mesh.nodes, mesh.elements, u, rate, step, last)[0]


@pytest.fixture(scope="module")
def block() -> HexMesh:
    return HexMesh.box(2.0, 1.0, 0.5, 4, 2, 2, origin=(-1.0, -0.5, 0.0))


def test_the_spin_of_a_rigid_rotation_is_its_angular_velocity(block: HexMesh) -> None:
    u = turned(block.nodes, 0.4)  # any placement: the gradient is taken where it stands
    x = block.nodes + u
    omega = 0.7 * AXIS
    rate = np.cross(omega, x - CENTRE)
    np.testing.assert_allclose(spin(block.nodes, block.elements, u, rate),
                               np.tile(omega, (block.n_nodes, 1)), atol=1e-12)


def test_a_stretch_and_a_translation_do_not_spin(block: HexMesh) -> None:
    u = turned(block.nodes, 0.4)
    x = block.nodes + u
    stretch = np.array([[0.3, 0.1, 0.0], [0.1, -0.2, 0.05], [0.0, 0.05, 0.1]])
    rate = x @ stretch.T + np.array([1.0, -2.0, 0.5])
    assert np.abs(spin(block.nodes, block.elements, u, rate)).max() < 1e-12
    # Without a spin the start is the rate's alone.
    np.testing.assert_allclose(turned_start(block, u, rate, 0.1, 0.05),
                               u + 0.1 * rate, rtol=0.0, atol=1e-14)


@pytest.mark.parametrize("ratio", [1.0, 0.5])
def test_a_rigid_rotation_is_continued_to_third_order(block: HexMesh, ratio: float) -> None:
    # The block turns at a constant rate (one radian per unit factor). After an increment
    # of last = ratio h, the start of the next (h) misses the exact turn by O(h^3): it
    # falls 8 times as h halves; the last rate alone misses it by O(h^2) (4 times).
    misses, linear = [], []
    for h in (0.04, 0.02, 0.01):
        last = ratio * h
        u_n = turned(block.nodes, 1.0)
        rate = (u_n - turned(block.nodes, 1.0 - last)) / last
        exact = turned(block.nodes, 1.0 + h)
        start = turned_start(block, u_n, rate, h, last)
        misses.append(np.abs(start - exact).max())
        linear.append(np.abs(u_n + h * rate - exact).max())
    assert misses[0] < 0.05 * linear[0], (misses, linear)
    for k in (1, 2):
        assert 7.0 < misses[k - 1] / misses[k] < 9.0, misses
        assert 3.5 < linear[k - 1] / linear[k] < 4.5, linear


def test_a_path_of_constant_acceleration_is_continued_exactly_by_the_rate_change(
        block: HexMesh) -> None:
    # u(t) = b t + c t^2 / 2 at every node: the mean
    # rate of an increment is the rate at its midpoint, so the change between the last two
    # midpoint rates is c exactly, whatever the three steps are, and the start that carries
    # it on lands on the path; the one that carries only the turn misses it.
    rng = np.random.default_rng(3)
    b = rng.normal(size=block.nodes.shape)
    c = block.nodes @ np.array([[0.3, 0.1, 0.0], [0.1, -0.2, 0.05], [0.0, 0.05, 0.1]])

    def path(t: float) -> np.ndarray:
        return b * t + 0.5 * c * t * t

    t, h, h1, h2 = 0.5, 0.03, 0.02, 0.05
    rate = (path(t) - path(t - h1)) / h1
    rate_before = (path(t - h1) - path(t - h1 - h2)) / h2
    turned, changed = increment_starts(block.nodes, block.elements, path(t), rate, h, h1,
                                       rate_before, h2)
    assert changed is not None
    exact = path(t + h) - path(t)
    np.testing.assert_allclose(changed, exact, rtol=0.0, atol=1e-13)
    assert np.abs(exact - turned).max() > 1e-4  # the turn alone misses the acceleration
    # The last increment's own starts, fitted to what it converged to: the change wins.
    assert start_weight(exact, turned, changed) == pytest.approx(1.0, abs=1e-12)
    assert increment_starts(block.nodes, block.elements, path(t), rate, h, h1)[1] is None


def test_the_start_weight_is_the_nearest_blend_shrunk_by_what_it_leaves() -> None:
    rng = np.random.default_rng(5)
    turned, changed = rng.normal(size=(7, 3)), rng.normal(size=(7, 3))
    between = changed - turned
    for weight in (0.0, 0.3, 1.0):
        actual = blended_start(turned, changed, weight)
        assert start_weight(actual, turned, changed) == pytest.approx(weight, abs=1e-12)
    # A part of the increment that neither start has (orthogonal to their difference)
    # leaves the nearest blend where it was, and shrinks the weight by the share of the
    # turn's miss it leaves unexplained: an equal part halves it.
    other = rng.normal(size=(7, 3))
    other -= np.vdot(other, between) / np.vdot(between, between) * between
    other *= 0.6 * np.linalg.norm(between) / np.linalg.norm(other)
    actual = blended_start(turned, changed, 0.6) + other
    assert start_weight(actual, turned, changed) == pytest.approx(0.3, abs=1e-12)
    # Beyond either start the blend stays at it: no extrapolation past the measured
    # change (twice the change: clipped at 1, which leaves a quarter of the miss), and no
    # turn taken back.
    assert start_weight(turned + 2.0 * between, turned, changed) == pytest.approx(0.75)
    assert start_weight(turned - 0.5 * between, turned, changed) == 0.0
    assert start_weight(changed, turned, None) == 0.0
    assert start_weight(changed, turned, turned.copy()) == 0.0
    assert start_weight(turned, turned, changed) == 0.0
    np.testing.assert_array_equal(blended_start(turned, None, 0.7), turned)
