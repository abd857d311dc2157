"""An elastic-plastic strip in pure bending against the moment-curvature of its Swift
material: a reference independent of the code (docs/theory/solid_shell.md).

A narrow strip (its sides free, so every fibre is in uniaxial stress) bent by rotating its
end section: the strain of a fibre at z from the middle surface is -kappa z (small strain:
at the largest curvature here the outer fibres strain by 3 %, where the logarithmic and
the engineering strain differ by 0.05 %), its stress the uniaxial Swift curve
sigma = K (eps0 + ep)^n beyond the first yield K eps0^n and E eps below it, and the moment
per unit width M(kappa) = int sigma(-kappa z) z dz over the thickness: a quadrature of a
scalar function, computed here."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from ddpy.model.control import NewtonSettings
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.static import StaticProblem

E, NU, K, EPS0, N = 210e3, 0.3, 645.3, 0.0102, 0.252
THICKNESS, HALF_LENGTH, HALF_WIDTH = 1.0, 1.0, 0.5
#: End rotation of the half strip and its increments: curvature up to 0.06 / mm.
ROTATION, INCREMENTS = 0.06, 12


def uniaxial_stress(strain: float) -> float:
    """Stress of the uniaxial Swift curve at a total strain (elastic below the first yield,
    then strain = stress / E + ep with stress = K (eps0 + ep)^n)."""
    first = K * EPS0**N
    if abs(strain) * E <= first:
        return E * strain
    def excess(s: float) -> float:
        return s / E + (s / K) ** (1.0 / N) - EPS0 - abs(strain)
    return float(np.sign(strain) * brentq(excess, first, K * (EPS0 + abs(strain))**N + 1.0,
                                          xtol=1e-12))


def analytic_moment(kappa: float, points: int = 4001) -> float:
    """Moment per unit width (N mm / mm) at curvature ``kappa`` (1/mm)."""
    z = np.linspace(-THICKNESS / 2, THICKNESS / 2, points)
    sigma = np.array([uniaxial_stress(-kappa * s) for s in z])
    return float(-np.trapezoid(sigma * z, z))


def strip_moments(element: str, layers: int) -> tuple[np.ndarray, np.ndarray]:
    """Curvatures and moments per unit width of the half strip (x in [0, 1] mm, 4 elements;
    its symmetry planes x = 0 and y = 0) whose end section x = 1 is turned rigidly about
    its middle line, in INCREMENTS static increments; the moment from the reactions of the
    end section."""
    material = Material(E, NU, Hill48(F=0.5, G=0.5, H=0.5, N=1.5), Swift(K, EPS0, N))
    mesh = HexMesh.box(HALF_LENGTH, HALF_WIDTH, THICKNESS, 4, 1, layers)
    problem = StaticProblem(Solid(mesh, material.props(), element=element))
    problem.fix(mesh.select(x=0.0), "x")
    problem.fix(mesh.select(y=0.0), "y")
    problem.fix(np.intersect1d(mesh.select(x=0.0), mesh.select(z=0.0)), "z")
    end = mesh.select(x=HALF_LENGTH)
    z = mesh.nodes[end, 2] - THICKNESS / 2
    problem.fix(end, "x", lambda factor: -np.sin(factor * ROTATION) * z)
    result = problem.solve(increments=INCREMENTS, newton=NewtonSettings(1e-8, 1e-8))
    kappa = np.array(result.factors) * ROTATION / HALF_LENGTH
    moment = np.array([-np.sum(r[end, 0] * z) / HALF_WIDTH for r in result.reactions])
    return kappa, moment


@pytest.mark.parametrize(("element", "layers", "low", "high"), [
    ("solid-shell", 2, -0.015, 0.015),
    ("solid-shell", 4, -0.010, 0.010),
    ("solid-shell", 8, -0.005, 0.005),
    # One layer: two Gauss points through the thickness overrate the plastic moment.
    ("solid-shell", 1, 0.12, 0.22),
    # The hexahedron: with one layer its mean dilatation holds the pressure constant
    # through the thickness, which takes a third of each fibre's uniaxial stress away;
    # with four its bilinear shears stiffen the bend (parasitic shear).
    ("hexahedron", 1, -0.37, -0.29),
    ("hexahedron", 4, 0.035, 0.055),
])
def test_pure_bending_follows_the_swift_moment_curvature(element: str, layers: int,
                                                          low: float, high: float) -> None:
    """Relative error of the moment at curvatures 0.01 to 0.06 / mm (outer fibre strain
    0.5 to 3 %, first yield at 0.14 %). Measured: solid-shell 2 layers +1.1 .. -0.04 %,
    4 layers -0.95 .. +0.27 %, 8 layers +0.29 .. +0.01 %, 1 layer +14 .. +21 %; hexahedron
    1 layer -31 .. -35 %, 4 layers +4.1 .. +4.8 % (docs/theory/solid_shell.md)."""
    kappa, moment = strip_moments(element, layers)
    reached = kappa >= 0.01 - 1e-12
    error = moment[reached] / np.array([analytic_moment(k) for k in kappa[reached]]) - 1.0
    assert reached.sum() == 11
    assert low <= error.min() and error.max() <= high, np.round(100 * error, 2)


def test_the_analytic_moment_has_its_limits() -> None:
    """The reference itself: elastic E t^3 / 12 kappa at small curvature, and toward the
    fully plastic moment K (eps0 + ep)^n t^2 / 4 of the outer fibres' hardening at large."""
    small = 1e-4
    assert analytic_moment(small) == pytest.approx(E * THICKNESS**3 / 12 * small, rel=1e-6)
    large = 1.0   # outer fibres at 50 %: the elastic core is 0.3 % of the thickness
    plastic = analytic_moment(large)
    assert K * EPS0**N * THICKNESS**2 / 4 < plastic < \
        uniaxial_stress(large * THICKNESS / 2) * THICKNESS**2 / 4
