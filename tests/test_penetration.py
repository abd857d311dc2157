"""The deepest penetration of the blank into each tool: measured per increment, recorded in
the results, warned about once per tool past penetration_limit; and the augmented
Lagrangian of Gauss-point contact that keeps it within the limit (docs/theory/contact.md,
"Penetration")."""

from __future__ import annotations

import logging
from pathlib import Path

import h5py
import numpy as np
import pytest
from jacobian_check import central_difference_errors
from test_gauss_contact import PENALTY, block_on_dome
from test_runner import tiny_case
from test_surface_contact import ELASTIC

from ddpy.app.runner import RESULTS, run_case
from ddpy.geometry.surfaces import NagataSurface
from ddpy.io.decks import read_case
from ddpy.model.control import NewtonSettings
from ddpy.model.forming import FormingProblem, RigidTool
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid

PLANE = NagataSurface([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], [[0, 0, 1]] * 4,
                      [[0, 1, 2, 3]])


def pressed_block(newton: NewtonSettings, penalty: float, depth: float = 4e-3
                  ) -> tuple[FormingProblem, object]:
    """A 1 x 1 x 0.5 mm elastic block clamped at its top, its bottom pushed ``depth`` mm
    into a plane in four increments (Gauss-point contact, 2 x 2 points per face, without
    the barrier: the penalty law alone)."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2)
    tool = RigidTool("plane", PLANE, mesh.select(z=0.0), facing=(0, 0, -1), contact="gauss",
                     penalty=penalty, barrier=None)
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    result = problem.run({"plane": (0, 0, depth)}, max_increment=depth / 4, newton=newton)
    return problem, result


def test_the_recorded_penetration_is_the_depth_of_a_uniformly_pressed_block() -> None:
    """Plain penalty: the block and the penalty are springs in series, so every point sinks
    d = p / eps with p the uniform pressure, and d + the block's shortening = the push.
    The recorded penetration of each increment is that d (to rounding)."""
    problem, result = pressed_block(NewtonSettings(1e-12, 1e-9), PENALTY)
    depth = -problem.contact_state()[1]
    np.testing.assert_allclose(depth, depth.mean(), rtol=1e-9)
    assert result.penetration["plane"][-1] == pytest.approx(depth.mean(), rel=1e-9)
    area = 1.0  # the block's bottom
    pressure = -result.tool_forces["plane"][-1][2] / area
    assert result.penetration["plane"][-1] == pytest.approx(pressure / PENALTY, rel=1e-9)
    # it grows with the push, increment by increment
    assert np.all(np.diff(result.penetration["plane"]) > 0.0)


def test_the_augmented_law_meets_the_limit_where_the_plain_penalty_does_not() -> None:
    """A penalty as stiff as the block (eps = E / L): the plain law leaves half the push
    as penetration, 2 um of 4 (0.4 % of 0.5 mm); with penetration_limit 0.1 % the
    Uzawa updates bring every increment within 0.5 um, with the same tool force as the
    constraint met exactly (the block shortened by the whole push: E d / L) to 0.5 um /
    4 um. Uzawa's error falls by K / (K + eps) = 1/2 per update here; with a penalty far
    below the block's stiffness it would barely move (docs/theory/contact.md)."""
    stiff = ELASTIC.E / 0.5
    _, plain = pressed_block(NewtonSettings(1e-10, 1e-9), stiff)
    assert plain.penetration["plane"][-1] == pytest.approx(2e-3, rel=0.05)
    problem, augmented = pressed_block(NewtonSettings(1e-10, 1e-9, penetration=1e-3,
                                                      augment=True), stiff)
    assert max(augmented.penetration["plane"]) <= 0.5e-3 * (1 + 1e-9)
    assert augmented.augmentations > 0
    exact = ELASTIC.E * 4e-3 / 0.5  # MPa on 1 mm^2
    force = -augmented.tool_forces["plane"][-1][2]
    assert force == pytest.approx(exact, rel=0.5e-3 / 4e-3 + 0.02)
    # the tool's reaction is the sum of the contact forces
    np.testing.assert_allclose(augmented.tool_forces["plane"][-1], -problem.force.sum(axis=0),
                               rtol=1e-12)


def test_jacobian_with_pressure_multipliers_matches_central_differences() -> None:
    """The augmented law p = max(0, p_n - eps g) at points whose multipliers p_n are the
    pressures of the last increment (the slide after the press carries them), one column
    lifted off: its derivative is the plain law's (dp/dg = -eps where p > 0), and the
    kink sits at g = p_n / eps."""
    problem, mesh, tool = block_on_dome(0.3)
    problem.run({"dome": (1e-3, 0, 1e-3)}, max_increment=1e-3,
                newton=NewtonSettings(penetration=1e-3, augment=True))
    assert problem.pressure.max() > 0.0  # multipliers to start from
    u = problem.u.copy()
    u[tool.slaves[mesh.nodes[tool.slaves, 0] < -0.4], 2] += 0.2  # open
    moved = {"dome": problem.position["dome"] + (3e-5, 1e-5, 2e-5)}
    equilibrium, law, state = central_difference_errors(problem, u, problem.force, moved, 3e-5)
    assert 0 in set(state.tolist()) and len(set(state.tolist())) > 1, state
    assert equilibrium <= 1e-7 and law <= 1e-7, (equilibrium, law)


def test_a_run_records_the_penetration_and_warns_once_per_tool(tmp_path: Path,
                                                               caplog: pytest.LogCaptureFixture
                                                               ) -> None:
    """The strip drawing with the limit lowered to 1e-9 of the thickness (the plain
    penalty: nothing pushes the blank out): every tool that the blank enters is named in
    exactly one warning, with its depth in mm and in % of the thickness, and no other
    tool; the results hold the depth per increment and tool."""
    case = tiny_case(tmp_path / "case")
    control = case / "control.dat"
    control.write_text(control.read_text().replace("max_increment  0.2",
                                                   "max_increment  0.2\npenetration_limit 1e-9"))
    with caplog.at_level(logging.WARNING, logger="ddpy"):
        outcome = run_case(read_case(case), tmp_path / "out")
    assert outcome.status == "completed"
    with h5py.File(tmp_path / "out" / RESULTS) as f:
        depth = f["increments/penetration"][()]
        tools = [str(t) for t in f.attrs["tools"]]
    assert depth.shape == (outcome.increments, len(tools))
    warnings = [r.getMessage() for r in caplog.records if "inside tool" in r.getMessage()]
    entered = [t for t, d in zip(tools, depth.max(axis=0), strict=True) if d > 1e-9 * 1.0]
    assert entered, depth.max(axis=0)
    for tool in tools:
        named = [w for w in warnings if f"inside tool {tool} " in w]
        assert len(named) == (1 if tool in entered else 0), (tool, warnings)
    assert all(" mm (" in w and "% of its" in w for w in warnings)


def test_the_plain_penalty_carries_no_multiplier_through_a_release() -> None:
    """With the plain penalty (the default) no Gauss point keeps a pressure multiplier:
    not after an increment, and not after the release steps of a tool lifted off while
    another keeps its contact (where they were once carried by mistake, changing the
    answers of phases that lift a tool)."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 2)
    below = RigidTool("plane", PLANE, mesh.select(z=0.0), facing=(0, 0, -1),
                      contact="gauss", penalty=PENALTY)
    wall = NagataSurface([[0, -5, -5], [0, 5, -5], [0, 5, 5], [0, -5, 5]], [[1, 0, 0]] * 4,
                         [[0, 1, 2, 3]])
    side = RigidTool("side", wall, mesh.select(x=0.0), facing=(-1, 0, 0), contact="gauss",
                     penalty=PENALTY)
    problem = FormingProblem(Solid(mesh, ELASTIC), [below, side])
    problem.fix(mesh.select(z=0.5), "xyz")
    problem.run({"plane": (0, 0, 4e-3), "side": (1e-3, 0, 0)}, max_increment=1e-3)
    assert not problem.pressure.any()
    problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3, active=["plane"])
    assert np.abs(problem.force).max() > 0.0  # the plane still carries the block
    assert not problem.pressure.any()
