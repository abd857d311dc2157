"""Measurements of the cylindrical bending benchmark (ddpy.studies.bending) on synthetic
geometry."""

from __future__ import annotations

import numpy as np
import pytest

from ddpy.studies.bending import contact_angle, force_oscillation, line_angle, smooth_curve

CENTRE = np.array([0.0, 0.0, 24.5])


def wrapped(angles_deg: np.ndarray, radius: float = 23.5, y: float = 0.0) -> np.ndarray:
    """Points on the punch's surface (axis along y through CENTRE) at angles from its
    lowest line, towards +x."""
    a = np.radians(angles_deg)
    return np.column_stack([radius * np.sin(a), np.full(a.size, y),
                            CENTRE[2] - radius * np.cos(a)])


def test_contact_angle_is_twice_the_farthest_contact_point() -> None:
    angles = np.linspace(0.0, 80.0, 17)                  # 5 degree steps
    flags = angles <= 52.0                                # in contact up to 50 degrees
    assert contact_angle(wrapped(angles), flags, CENTRE) == pytest.approx(100.0)
    assert contact_angle(wrapped(angles), flags, CENTRE, symmetric=False) == \
        pytest.approx(50.0)


def test_contact_angle_ignores_radius_position_along_axis_and_free_points() -> None:
    # Points off the surface (the blank's nodes are not exactly on it), along the axis, and
    # free points beyond the contact zone do not change the angle.
    angles = np.array([0.0, 20.0, 40.0, 75.0, 90.0])
    points = wrapped(angles, radius=24.0, y=7.0)
    points[1] = wrapped(np.array([20.0]), radius=23.6, y=-3.0)[0]
    flags = np.array([True, True, True, False, False])
    assert contact_angle(points, flags, CENTRE + [0, 5.0, 0]) == pytest.approx(80.0)
    assert contact_angle(points, np.zeros(5, bool), CENTRE) == 0.0


def test_contact_angle_follows_the_punch_and_other_axes() -> None:
    # The punch moved down by 10 mm; the same wrap measured about its new axis.
    points = wrapped(np.array([0.0, 30.0])) + [0, 0, -10.0]
    assert contact_angle(points, [True, True], CENTRE + [0, 0, -10.0]) == pytest.approx(60.0)
    # A punch with its axis along x, moving along -z: the wrap is in the yz-plane.
    a = np.radians(35.0)
    point = [[5.0, 10 * np.sin(a), -10 * np.cos(a)]]
    assert contact_angle(point, [True], [0, 0, 0], axis=(1, 0, 0)) == pytest.approx(70.0)
    with pytest.raises(ValueError, match="parallel"):
        contact_angle(point, [True], [0, 0, 0], axis=(0, 0, 1))
    with pytest.raises(ValueError, match="in_contact"):
        contact_angle(point, [True, False], [0, 0, 0])


@pytest.mark.parametrize("degrees", [0.0, 20.7, 35.0, 89.0])
def test_line_angle_of_a_straight_flange(degrees: float) -> None:
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 20.0, 30)
    a = np.radians(degrees)
    points = np.column_stack([30 + t * np.cos(a), rng.uniform(0, 15, t.size),
                              t * np.sin(a)])
    assert line_angle(points) == pytest.approx(degrees, abs=1e-9)
    assert line_angle(points[::-1] * [-1, 1, 1]) == pytest.approx(degrees, abs=1e-9)
    noisy = points + rng.normal(0.0, 0.01, points.shape) * [1, 0, 1]
    assert line_angle(noisy) == pytest.approx(degrees, abs=0.2)


def test_smooth_curve_keeps_polynomials_on_uneven_steps() -> None:
    rng = np.random.default_rng(1)
    s = np.sort(rng.uniform(0.0, 28.5, 300))
    f = 3.0 + 2.0 * s - 0.05 * s**2
    assert np.allclose(smooth_curve(s, f, window=1.0, order=2), f, atol=1e-8)
    assert force_oscillation(s, f) == pytest.approx(0.0, abs=1e-8)


def test_force_oscillation_measures_a_short_oscillation() -> None:
    # A trend plus an oscillation of amplitude 2 N and period 0.2 mm, much shorter than the
    # 1 mm window: the RMS deviation is about 2 / sqrt(2).
    s = np.linspace(0.0, 28.5, 2000)
    trend = 50.0 * np.sqrt(s + 1.0)
    wiggle = 2.0 * np.sin(2 * np.pi * s / 0.2)
    rms = force_oscillation(s, trend + wiggle, window=1.0, start=1.0)
    assert rms == pytest.approx(2.0 / np.sqrt(2.0), rel=0.05)
    # Twice the amplitude, twice the measure; the trend alone hardly counts.
    assert force_oscillation(s, trend + 2 * wiggle, start=1.0) == pytest.approx(2 * rms, rel=1e-6)
    assert force_oscillation(s, trend, start=1.0) < 1e-3


def test_force_oscillation_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="at least"):
        force_oscillation([0.0, 1.0], [1.0, 2.0])
    with pytest.raises(ValueError, match="window"):
        force_oscillation(np.arange(5.0), np.arange(5.0), window=0.0)
    with pytest.raises(ValueError, match="no point"):
        force_oscillation(np.arange(5.0), np.arange(5.0), start=10.0)
