"""The Alart-Curnier contact law: exact derivatives (curvature included) and Coulomb's law."""

from __future__ import annotations

import numpy as np
import pytest

from ddpy.geometry.search import ContactSearch
from ddpy.geometry.surfaces import BezierSurface
from ddpy.model.contact import INACTIVE, SLIP, STICK, contact_law

RNG = np.random.default_rng(7)


def curved_tool() -> BezierSurface:
    """A doubly curved bicubic patch over [0, 10]^2, z = 2 sin-like bumps."""
    u = np.linspace(0, 10, 4)
    x, y = np.meshgrid(u, u, indexing="ij")
    z = np.array([[0.0, 1.5, -1.0, 0.5], [1.0, 2.5, 0.5, -0.5],
                  [-0.5, 1.0, 2.0, 1.0], [0.5, -1.0, 1.0, 0.0]])
    return BezierSurface([np.stack([x, y, z], axis=-1)])


TOOL = curved_tool()
SEARCH = ContactSearch(TOOL)


def law_at(x, x_n, force, mu, r):
    found = SEARCH.project(x)
    second = TOOL.second_derivatives(found.patch, found.params)
    return contact_law(force, found, second, x - x_n, mu, r), found


def nodes(k: int, gap: tuple[float, float]):
    """k points at normal distances in ``gap`` above interior points of the tool."""
    params = RNG.uniform(0.2, 0.8, size=(k, 2))
    points, _, normals = TOOL.evaluate(np.zeros(k, dtype=int), params)
    return points + RNG.uniform(*gap, size=(k, 1)) * normals, normals


@pytest.mark.parametrize("case", ["stick", "slip", "inactive"])
def test_derivatives_match_finite_differences(case: str) -> None:
    k = 40
    x, normals = nodes(k, (-0.05, 0.05) if case != "inactive" else (0.5, 1.0))
    x_n = x - RNG.normal(scale={"stick": 1e-4, "slip": 0.05, "inactive": 0.05}[case],
                         size=(k, 3))
    push = 100.0 + RNG.uniform(0, 50, size=(k, 1))
    force = push * normals + RNG.normal(scale=5.0, size=(k, 3))
    mu, r = 0.15, 1.0e3
    if case == "inactive":
        force = -force  # pulling: no contact force
    law, _ = law_at(x, x_n, force, mu, r)
    expected = {"stick": STICK, "slip": SLIP, "inactive": INACTIVE}[case]
    assert (law.state == expected).mean() > 0.7, law.state
    keep = law.state == expected
    h = 1e-6
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        plus, _ = law_at(x + step, x_n, force, mu, r)
        minus, _ = law_at(x - step, x_n, force, mu, r)
        fd = (plus.residual - minus.residual) / (2 * h)
        same = keep & (plus.state == law.state) & (minus.state == law.state)
        # Entries are up to r = 1e3; the curvature part is of order 10.
        np.testing.assert_allclose(law.d_x[same][:, :, j], fd[same], atol=1e-4)
        plus, _ = law_at(x, x_n, force + step, mu, r)
        minus, _ = law_at(x, x_n, force - step, mu, r)
        fd = (plus.residual - minus.residual) / (2 * h)
        np.testing.assert_allclose(law.d_lambda[same][:, :, j], fd[same], atol=1e-7)


def test_curvature_term_matters() -> None:
    # Dropping the curvature (dn/dx = 0) makes the derivative wrong on a curved tool.
    x, normals = nodes(20, (0.02, 0.05))
    force = 120.0 * normals
    law, found = law_at(x, x - 0.03, force, 0.15, 1.0e3)
    flat = contact_law(force, found, np.zeros((20, 3, 3)), 0.03 * np.ones((20, 3)), 0.15, 1e3)
    assert np.abs(law.d_x - flat.d_x).max() > 1.0


def test_solution_obeys_coulomb() -> None:
    # At C = 0: in stick the gap and slip vanish; in slip |t| = mu p against the slip.
    x, normals = nodes(1, (0.0, 0.0))
    mu, r = 0.2, 1.0e3
    found = SEARCH.project(x)
    n = found.normal[0]
    tangent = found.tangents[0, 0] / np.linalg.norm(found.tangents[0, 0])
    slip = 0.01 * tangent
    p = 50.0
    force = p * n - mu * p * tangent  # friction opposing a slip along +tangent
    law, _ = law_at(x, x - slip, force[None], mu, r)
    assert law.state[0] == SLIP
    np.testing.assert_allclose(law.residual[0], 0.0, atol=1e-9)
    # Sticking at zero slip with a force inside the cone.
    force = p * n + 0.5 * mu * p * tangent
    law, _ = law_at(x, x, force[None], mu, r)
    assert law.state[0] == STICK
    np.testing.assert_allclose(law.residual[0], 0.0, atol=1e-9)
    # Open gap, no force: inactive and satisfied.
    law, _ = law_at(x + 0.1 * n, x + 0.1 * n, np.zeros((1, 3)), mu, r)
    assert law.state[0] == INACTIVE
    np.testing.assert_allclose(law.residual[0], 0.0, atol=1e-12)


def test_bad_parameters() -> None:
    x, normals = nodes(2, (0.0, 0.1))
    found = SEARCH.project(x)
    second = TOOL.second_derivatives(found.patch, found.params)
    with pytest.raises(ValueError, match="friction must be >= 0"):
        contact_law(np.zeros((2, 3)), found, second, np.zeros((2, 3)), -0.1, 1e3)
    with pytest.raises(ValueError, match="augmentation must be > 0"):
        contact_law(np.zeros((2, 3)), found, second, np.zeros((2, 3)), 0.1, 0.0)
    with pytest.raises(ValueError, match="force must have shape"):
        contact_law(np.zeros((3, 3)), found, second, np.zeros((2, 3)), 0.1, 1e3)
