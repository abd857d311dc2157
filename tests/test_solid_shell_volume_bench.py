"""The analysis of benchmarks/solid_shell_volume/run.py on single elements with known
answers: the fibres' tilt, and the split of an element's volume change into the compatible
trace and what the assumed strains add. No simulation."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from solid_helpers import props_vector

BENCH = Path(__file__).resolve().parents[1] / "benchmarks" / "solid_shell_volume"
sys.path.insert(0, str(BENCH.parent))
from bench_common import load_module  # noqa: E402

from ddpy.model.mesh import HexMesh  # noqa: E402
from ddpy.model.solid import Solid  # noqa: E402

volume = load_module(BENCH / "run.py", "solid_shell_volume")

#: A 4 x 3 x 0.5 mm element (nodes 0-3 the bottom face, 4-7 the top), as the blank's.
BOX = np.array([[0, 0, 0], [4, 0, 0], [4, 3, 0], [0, 3, 0],
                [0, 0, 0.5], [4, 0, 0.5], [4, 3, 0.5], [0, 3, 0.5]], dtype=float)


def test_fibre_tilt_is_the_shear_angle() -> None:
    """Top face moved along x by t tan(a): every fibre tilts by a to the bottom's normal."""
    for angle in (0.0, 12.0, 40.0):
        x = BOX.copy()
        x[4:, 0] += 0.5 * math.tan(math.radians(angle))
        assert volume.fibre_tilt(x, np.arange(8)[None, :])[0] == pytest.approx(angle, abs=1e-9)


def test_a_homogeneous_deformation_adds_nothing() -> None:
    """A homogeneous F (stretch and shear) on a rectangular element: the assumed strains
    equal the compatible ones everywhere, so they add no trace; ln(V1 / Vn) is ln det F and
    the compatible trace tr (F^T F - I) / 2 (Green-Lagrange, on the element's own axes)."""
    f = np.array([[1.05, 0.02, 0.01], [0.0, 0.97, 0.03], [0.01, 0.0, 1.02]])
    du = BOX @ f.T - BOX
    split = volume.element_split(BOX, BOX, du)
    assert split[0] == pytest.approx(math.log(np.linalg.det(f)), rel=1e-12)
    assert split[1] == pytest.approx(0.5 * np.trace(f.T @ f - np.eye(3)), rel=1e-12)
    assert np.abs(split[2:]).max() < 1e-14


def added_thickness_trace(x: np.ndarray, stretch: float) -> float:
    """The trace the corners' thickness strain adds on element ``x`` whose fibres at
    x = 4 stretch by ``stretch`` while those at x = 0 do not."""
    du = np.zeros((8, 3))
    du[[5, 6]] = stretch * (x[[5, 6]] - x[[1, 2]])
    return float(volume.element_split(x, x, du)[2])


def test_unequal_fibres_of_a_fanned_element_add_thickness_strain() -> None:
    """Fibres stretching unequally: on an element whose fibres fan out (a trapezoidal
    section, as over a radius) the thickness strain sampled at the corners parts from the
    compatible one at first order in the stretch (the fibres' directions differ), on the
    rectangular element only at second order (the stretch's square): halving the stretch
    halves the one and quarters the other."""
    fanned = BOX.copy()
    fanned[[5, 6], 0] += 0.3          # the fibres at x = 4 lean outward
    ratio = added_thickness_trace(fanned, 0.02) / added_thickness_trace(fanned, 0.01)
    assert ratio == pytest.approx(2.0, rel=0.05)
    ratio = added_thickness_trace(BOX, 0.02) / added_thickness_trace(BOX, 0.01)
    assert ratio == pytest.approx(4.0, rel=1e-9)
    assert abs(added_thickness_trace(fanned, 0.02)) > 10 * abs(added_thickness_trace(BOX, 0.02))


def test_the_split_adds_up_to_the_elements_own_strain() -> None:
    """Against the solid-shell itself: on a distorted, fanned element moved by a small
    random increment, the compatible trace plus what the assumed components add (the
    benchmark's first-order split) is the mean trace of the material strain the element
    gives its Gauss points (initial-volume weights, under which the enhanced strains have
    zero mean), to the increment's square."""
    rng = np.random.default_rng(3)
    x = BOX + rng.uniform(-0.1, 0.1, BOX.shape) * [1.0, 1.0, 0.1]
    x[[5, 6], 0] += 0.3
    mesh = HexMesh(x, np.arange(8)[None, :])
    solid = Solid(mesh, props_vector(), element="solid-shell")
    du = 1e-5 * rng.uniform(-1.0, 1.0, x.shape)
    strain = solid.internal_force(du)[1].strain[0]                  # (8 points, 6)
    w0 = np.array([np.linalg.det(x.T @ volume.shape_derivatives(volume.GAUSS * c))
                   for c in volume.CORNERS])
    element = float(w0 @ strain[:, :3].sum(axis=1) / w0.sum())
    split = volume.element_split(x, x, du)
    assert abs(element) > 1e-6
    assert split[1:].sum() == pytest.approx(element, rel=1e-4)
