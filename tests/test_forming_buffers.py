"""The Jacobian values of a forming evaluation are assembled in place into the layout's two
buffers: each evaluation must give the values a fresh assembly gives, and an evaluation into
one buffer must leave the other (a line search's kept trial) as it was."""

from __future__ import annotations

import numpy as np

from ddpy.geometry.surfaces import NagataSurface
from ddpy.model.forming import FormingProblem, RigidTool
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid

STEEL = Material(210e3, 0.3, Hill48.von_mises(), Swift(500.0, 0.01, 0.2))


def pressed_block() -> tuple[FormingProblem, dict, np.ndarray]:
    """A block on a plane tool, clamped on top; its bottom pushed 1 um into the tool."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 3, 3, 2, origin=(-0.5, -0.5, 0.0))
    plane = NagataSurface([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], [[0, 0, 1]] * 4,
                          [[0, 1, 2, 3]])
    tool = RigidTool("plane", plane, mesh.select(z=0.0), friction=0.1, facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, STEEL), [tool])
    problem.fix(mesh.select(z=0.5), "xyz")
    positions = {"plane": np.array([0.0, 0.0, 1e-3])}
    return problem, positions, mesh.nodes.copy()


def evaluate(problem: FormingProblem, positions: dict, x_n: np.ndarray, u: np.ndarray,
             buffer: int) -> tuple:
    layout, _ = problem._prepare()
    on = np.ones(layout.node.size, dtype=bool)
    force = np.zeros((layout.node.size, 3))
    force[:, 2] = 1.0
    timings = dict.fromkeys(("contact", "assembly", "rest"), 0.0)
    out = problem._evaluate(layout, u, force, x_n, positions, on, timings, buffer=buffer)
    assert not isinstance(out, str)
    return out


def test_values_in_place_match_a_fresh_assembly_and_buffers_are_independent() -> None:
    problem, positions, x_n = pressed_block()
    layout, _ = problem._prepare()
    n = problem.solid.mesh.n_nodes
    u0 = np.zeros((n, 3))
    u1 = np.random.default_rng(0).normal(0.0, 1e-4, (n, 3)) * ~problem.fixed
    first = evaluate(problem, positions, x_n, u0, 0)
    kept = first[1].copy()
    assert first[1] is layout.values[0] or np.shares_memory(first[1], layout.values[0])
    second = evaluate(problem, positions, x_n, u1, 1)
    np.testing.assert_array_equal(layout.values[0], kept)  # the other buffer is untouched
    assert not np.array_equal(second[1], kept)
    k, m = layout.k_slots, layout.n_coupling
    for values, u in ((layout.values[0], u0), (layout.values[1], u1)):
        fresh = problem.solid.assemble(u, problem.state, layout.pattern).values
        np.testing.assert_array_equal(values[:k], fresh)
        np.testing.assert_array_equal(values[k:k + m], -1.0)
    # The same point again, into the other buffer: the same values, bit for bit.
    again = evaluate(problem, positions, x_n, u0, 1)
    np.testing.assert_array_equal(again[1], kept)
    np.testing.assert_array_equal(again[0], first[0])
