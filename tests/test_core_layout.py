"""The Jacobian's layout the core computes (fortran/solver/ddpy_jacobian_layout.f90), as
``Layout`` reads it, and the core's evaluation that ``FormingProblem.linearization`` reads
(problem_evaluate)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from ddpy import _core
from ddpy.core.handles import CoreRefusal, check
from ddpy.geometry.surfaces import NagataSurface
from ddpy.model.forming import FormingProblem, RigidTool
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.newton import Layout
from ddpy.model.solid import Solid
from ddpy.model.static import StaticProblem

STEEL = Material(210e3, 0.3, Hill48.von_mises(), Swift(500.0, 0.01, 0.2))


def plane(z: float, facing: float) -> NagataSurface:
    """A flat square tool at height z whose normal opposes ``facing`` (+1: blank below)."""
    corners = np.array([[-2, -2, z], [6, -2, z], [6, 6, z], [-2, 6, z]], dtype=float)
    normals = np.tile([0.0, 0.0, -facing], (4, 1))
    return NagataSurface(corners, normals, [[0, 3, 2, 1]] if facing > 0 else [[0, 1, 2, 3]])


def two_tools(barrier: float | None = None) -> FormingProblem:
    """A 2 x 2 x 1 blank between a Gauss-point holder above (with a ``barrier``, or none)
    and a node-to-surface die below, on the symmetry plane x = 0 (held components of both
    tools' slaves)."""
    mesh = HexMesh.box(2.0, 2.0, 1.0, 2, 2, 1)
    holder = RigidTool("holder", plane(1.0, 1.0), mesh.select(z=1.0), facing=(0, 0, 1),
                       contact="gauss", penalty=2000.0, friction=0.1, barrier=barrier)
    die = RigidTool("die", plane(0.0, -1.0), mesh.select(z=0.0), facing=(0, 0, -1),
                    contact="node", friction=0.1)
    problem = FormingProblem(Solid(mesh, STEEL), [holder, die])
    problem.fix(mesh.select(x=0.0), "x")
    problem.fix(mesh.select(y=0.0), "y")
    return problem


@pytest.mark.parametrize("barrier", [None, 0.005])
def test_the_cores_layout_holds_each_block_where_the_evaluation_writes_it(
        barrier: float | None) -> None:
    """The solid's tangent first (its own coordinate structure), then one coupling entry per
    free component of each pair's node, the patch entries (a Gauss-point pair's in its
    node's equilibrium rows, none in a held row; with a barrier, its own law's at its node
    after them, in its law rows), each pair's 3 x 3 dC/dlambda, and the force-controlled
    holder's column, row and diagonal last."""
    problem = two_tools(barrier)
    layout = Layout(problem.solid, problem.tools, problem.fixed, holds=[0])
    nf, npair = layout.nf, layout.node.size
    assert layout.n == nf + 3 * npair + 1
    assert layout.rows.min() >= 0 and max(layout.rows.max(), layout.cols.max()) < layout.n
    solid = problem.solid.pattern(layout.eqn, symmetric=False)
    k = layout.k_slots
    assert k == solid.rows.size
    np.testing.assert_array_equal(layout.rows[:k], solid.rows)
    np.testing.assert_array_equal(layout.cols[:k], solid.cols)
    equ = layout.eqn.reshape(-1, 3)[layout.node]                 # (pairs, 3)
    law = nf + np.arange(3 * npair).reshape(npair, 3)
    coupled = equ >= 0
    assert (~coupled).any()  # held components on the symmetry planes
    ncoupling = int(coupled.sum())
    np.testing.assert_array_equal(layout.rows[k:k + ncoupling], equ[coupled])
    np.testing.assert_array_equal(layout.cols[k:k + ncoupling], law[coupled])
    # dC/dlambda closes the contact blocks, before the holder's entries
    gauss = slice(layout.first[0], layout.first[1])
    blocks = np.repeat(law, 3, axis=1).ravel(), np.tile(law, (1, 3)).ravel()
    hold_rows = layout.rows == layout.n - 1
    hold_cols = layout.cols == layout.n - 1
    first_hold = int(np.flatnonzero(hold_rows | hold_cols)[0])
    lam = slice(first_hold - 9 * npair, first_hold)
    np.testing.assert_array_equal(layout.rows[lam], blocks[0])
    np.testing.assert_array_equal(layout.cols[lam], blocks[1])
    # the patch entries: every Gauss-point pair's in equilibrium rows, none in a held row
    patch = slice(k + ncoupling, lam.start)
    rows, cols = layout.rows[patch], layout.cols[patch]
    assert np.all(cols < nf)
    in_law = rows >= nf
    die_held = law[layout.first[1]:][equ[layout.first[1]:] < 0]
    assert np.isin(die_held, rows).all()  # a node-to-surface pair keeps its held rows
    holder_law = np.isin(rows, law[gauss])
    if barrier is None:
        assert np.all(np.isin(rows[in_law], law[layout.first[1]:]))  # the die's pairs only
    else:  # each pair's own law: its 3 rows times its node's free dofs
        assert holder_law.sum() == 3 * (equ[gauss] >= 0).sum()
        for pair, eqs in zip(law[gauss], equ[gauss], strict=True):
            mine = np.isin(rows, pair)
            np.testing.assert_array_equal(np.sort(cols[mine]),
                                          np.sort(np.tile(eqs[eqs >= 0], 3)))
    # the holder: its column in its pairs' free equilibrium rows (and, with a barrier,
    # their law rows), its diagonal last
    assert layout.rows[-1] == layout.cols[-1] == layout.n - 1
    column = layout.rows[hold_cols & ~hold_rows]
    expected = [np.concatenate([e[e >= 0], [] if barrier is None else pair])
                for e, pair in zip(equ[gauss], law[gauss], strict=True)]
    np.testing.assert_array_equal(column, np.concatenate(expected))
    # its row: with a barrier the multipliers, then the Gauss-point pairs' F(x) entries,
    # in their equilibrium rows' columns
    row_entries = hold_rows & ~hold_cols
    lumped = ((rows < nf) & (rows >= 0) & ~holder_law).sum()
    assert row_entries.sum() == lumped + (0 if barrier is None else law[gauss].size)


def test_the_linearization_is_the_cores_evaluation_of_the_solid_and_the_pairs() -> None:
    """With the tools 0.5 mm off the blank and no pair forces the free equilibrium rows
    are fint - external and the solid's slots its tangent, bitwise as the solid assembles
    them; the coupling entries are 0 for the holder's eliminated multipliers and -1 for
    the die's."""
    problem = two_tools()
    rng = np.random.default_rng(5)
    n = problem.solid.mesh.n_nodes
    u = 1e-4 * rng.standard_normal((n, 3)) * ~problem.fixed
    away = {"holder": np.array([0.0, 0.0, 0.5]), "die": np.array([0.0, 0.0, -0.5])}
    eq = problem.linearization(u, np.zeros((problem.force.shape[0], 3)), away)
    assert not eq.state.any()  # every pair open
    layout = Layout(problem.solid, problem.tools, problem.fixed)
    pattern = problem.solid.pattern(layout.eqn, symmetric=False)
    assembly = problem.solid.assemble(u, problem.solid_state, pattern)
    k = layout.k_slots
    np.testing.assert_array_equal(eq.values[:k], assembly.values)
    np.testing.assert_array_equal(eq.residual[:eq.n_free],
                                  assembly.fint.ravel()[~problem.fixed.ravel()])
    equ = layout.eqn.reshape(-1, 3)[layout.node]
    gauss = np.repeat(np.arange(layout.node.size) < layout.first[1], 3).reshape(-1, 3)
    expected = np.where(gauss, 0.0, -1.0)[equ >= 0]
    np.testing.assert_array_equal(eq.values[k:k + expected.size], expected)


@pytest.mark.parametrize("symmetric", [False, True])
def test_the_solver_takes_the_distinct_entries_of_the_coordinates(symmetric: bool) -> None:
    """The entries the solver is analysed with (Layout.entries) are the coordinates' distinct
    positions by row, then column: SciPy's sum of duplicates has the same, and each
    position repeats on a blank (the elements around a node pair add to it)."""
    problem = two_tools()
    layout = (Layout(problem.solid, [], problem.fixed, symmetric=True) if symmetric
              else Layout(problem.solid, problem.tools, problem.fixed))
    rows, cols = layout.entries()
    summed = sp.csr_matrix((np.ones(layout.rows.size), (layout.rows, layout.cols)),
                           shape=(layout.n, layout.n))
    summed.sum_duplicates()
    np.testing.assert_array_equal(rows, np.repeat(np.arange(layout.n), np.diff(summed.indptr)))
    np.testing.assert_array_equal(cols, summed.indices)
    assert rows.size < layout.rows.size


def test_a_static_increment_factorizes_the_summed_entries() -> None:
    """A bar clamped at one end and stretched at the other, elastic: the core's Newton loop
    factorizes the summed entries and converges in at most three corrections, with an
    unsymmetric layout and a symmetric one (whose entries are its triangle's), to the same
    displacements; the end's reaction is E A u / L (nu = 0, small strain)."""
    mesh = HexMesh.box(4.0, 1.0, 1.0, 4, 1, 1)
    elastic = Material(210e3, 0.0, Hill48.von_mises(), Swift(1e9, 0.01, 0.2))
    answers = []
    for symmetry in ("unsymmetric", "symmetric"):
        problem = StaticProblem(Solid(mesh, elastic), symmetry=symmetry)
        problem.fix(mesh.select(x=0.0), "xyz")
        problem.fix(mesh.select(x=4.0), "x", 1e-4)
        result = problem.solve(increments=1)
        assert len(result.convergence[0]) <= 3
        reaction = result.reactions[-1][mesh.select(x=4.0), 0].sum()
        assert reaction == pytest.approx(210e3 * 1.0 * 1e-4 / 4.0, rel=1e-3)
        answers.append(result.displacements[-1])
    np.testing.assert_allclose(answers[0], answers[1], rtol=0, atol=1e-12)


def test_a_penalty_for_a_tool_the_problem_does_not_have_is_refused() -> None:
    problem = two_tools()
    layout = Layout(problem.solid, problem.tools, problem.fixed)
    handle = layout.core_problem(None).handle
    check(_core.problem_set_penalty(handle, 1, normal_penalty=1.0, tangential_penalty=1.0,
                                    barrier_depth=-1.0), "the die's penalty")
    with pytest.raises(CoreRefusal, match="index"):
        check(_core.problem_set_penalty(handle, 2, normal_penalty=1.0,
                                        tangential_penalty=1.0, barrier_depth=-1.0),
              "a penalty")


def test_a_barrier_cannot_come_or_go_once_the_layout_is_made() -> None:
    """Whether a tool has a barrier shapes the layout (its pairs' own laws): once the layout
    is made, a depth may change, its presence may not (the evaluation would write slots
    the layout does not have)."""
    problem = two_tools(0.005)
    layout = Layout(problem.solid, problem.tools, problem.fixed)
    handle = layout.core_problem(None).handle
    check(_core.problem_set_penalty(handle, 0, normal_penalty=1.0, tangential_penalty=1.0,
                                    barrier_depth=0.01), "a deeper barrier")
    with pytest.raises(CoreRefusal, match="value"):
        check(_core.problem_set_penalty(handle, 0, normal_penalty=1.0,
                                        tangential_penalty=1.0, barrier_depth=-1.0),
              "no barrier")
