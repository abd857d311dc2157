"""Nested-dissection pivot orders from the mesh (ddpy.core.ordering) and their use by MUMPS."""

from __future__ import annotations

import numpy as np
import pytest
from solid_helpers import props_vector

from ddpy.core.linalg import MumpsSolver
from ddpy.core.ordering import equation_order, nested_dissection, node_adjacency
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.static import StaticProblem


def test_adjacency_and_separators() -> None:
    """The adjacency counts the nodes sharing an element; the order is a permutation whose
    symbolic Cholesky factor (elimination-tree fill) is far smaller than the natural
    order's on a 30 x 10 sheet."""
    mesh = HexMesh.box(30.0, 10.0, 1.0, 30, 10, 1)
    graph = node_adjacency(mesh.elements, mesh.n_nodes)
    assert graph.n == mesh.n_nodes
    degree = np.diff(graph.indptr)
    assert degree.min() == 8 and degree.max() == 18  # corners, interior (itself too)
    order = nested_dissection(graph, mesh.nodes, leaf=8)
    assert np.array_equal(np.sort(order), np.arange(mesh.n_nodes))

    def fill(order: np.ndarray) -> int:
        """Entries of the Cholesky factor of the graph eliminated in `order` (symbolic)."""
        rank = np.empty_like(order)
        rank[order] = np.arange(order.size)
        later = [set(rank[graph.indices[graph.indptr[v]:graph.indptr[v + 1]]]) - {rank[v]}
                 for v in order]
        later = [{r for r in s if r > i} for i, s in enumerate(later)]
        total = 0
        for s in later:
            total += len(s)
            if s:
                parent = min(s)
                later[parent] |= s - {parent}
        return total

    assert fill(order) < 0.6 * fill(np.arange(mesh.n_nodes))


def test_equation_order_keeps_a_node_together() -> None:
    position = equation_order([2, 0, 1], [0, 0, 0, 1, 1, 2, 2, 2, 0])
    assert np.array_equal(np.sort(position), np.arange(9))
    # Node 2's equations first (5, 6, 7), then node 0's (0, 1, 2, 8), then node 1's.
    assert np.array_equal(np.argsort(position), [5, 6, 7, 0, 1, 2, 8, 3, 4])


def test_nested_order_in_mumps_gives_the_same_answer_with_less_fill() -> None:
    """A strip of 80 x 20 x 3 hexahedra: the same solution as with SCOTCH (what MUMPS uses
    when METIS is asked for and missing) and fewer factorization flops (measured: 0.73 of
    SCOTCH's here, 0.58 on the 20,172-element strip of the solid benchmark)."""
    mesh = HexMesh.box(60.0, 15.0, 1.0, 80, 20, 3)
    solid = Solid(mesh, props_vector())
    rows, cols, values = solid.tangent(np.zeros((mesh.n_nodes, 3)), symmetric=True)
    fixed = np.zeros(solid.n_dofs, dtype=bool)
    fixed[(3 * mesh.select(x=0.0)[:, None] + np.arange(3)).ravel()] = True
    eqn = np.full(solid.n_dofs, -1)
    eqn[~fixed] = np.arange((~fixed).sum())
    keep = ~fixed[rows] & ~fixed[cols]
    r, c, v = eqn[rows[keep]], eqn[cols[keep]], values[keep]
    n = int((~fixed).sum())
    rhs = np.random.default_rng(1).standard_normal(n)
    answers, flops = {}, {}
    for name in ("scotch", "nested"):
        with MumpsSolver("symmetric", name if name != "nested" else "amd") as solver:
            if name == "nested":
                solver.set_ordering(equation_order(solid.node_order(),
                                                   np.flatnonzero(~fixed) // 3))
            solver.analyse(n, r, c)
            solver.factorize(v)
            answers[name] = solver.solve(rhs)
            flops[name] = solver.statistics()["flops"]
    scale = np.abs(answers["scotch"]).max()
    assert np.abs(answers["nested"] - answers["scotch"]).max() <= 1e-8 * scale
    assert flops["nested"] < 0.8 * flops["scotch"]
    with MumpsSolver("symmetric") as solver, pytest.raises(ValueError, match="permutation"):
        solver.set_ordering([0, 0, 1])


def test_static_problem_with_nested_and_mumps_orderings_agree() -> None:
    mesh = HexMesh.box(10.0, 2.0, 1.0, 10, 2, 2)
    out = []
    for ordering in ("nested", "scotch"):
        problem = StaticProblem(Solid(mesh, props_vector()), ordering=ordering)
        problem.fix(mesh.select(x=0.0), "xyz")
        problem.load(mesh.select(x=10.0), [0.0, 0.0, -10.0])
        out.append(problem.solve().displacements[-1])
    assert np.abs(out[0] - out[1]).max() <= 1e-10 * np.abs(out[1]).max()


def test_contact_multipliers_first_lower_the_factorization_flops() -> None:
    """The forming Jacobian of the built-in bending case with node-to-surface contact (on
    the mean-dilatation hexahedron, DD3IMP's discretization), with pairs closed and open:
    the multipliers eliminated before the displacements give the same solution as with
    their nodes, with fewer flops (a closed stick pair's zero pivot is delayed by MUMPS):
    0.73 times on the 60 x 3 x 2 blank, 0.5 on the graded 33 x 2 x 3 blank before it."""
    from dataclasses import replace

    from ddpy.app.runner import DEFAULT_CASE, build_problem
    from ddpy.io.decks import read_case

    case = read_case(DEFAULT_CASE)
    problem = build_problem(replace(case, element="hexahedron", tools=[
        replace(t, discretization="node") for t in case.tools]))
    eq = problem.linearization(touching=1e-6 * problem.size)
    assert (eq.state == 1).sum() >= 5 and (eq.state == 0).sum() >= 100  # stick and open pairs
    n = eq.residual.size
    answers, flops = {}, {}
    for name, first in (("with node", None), ("first", np.arange(n) >= eq.n_free)):
        order = equation_order(problem.solid.node_order(), eq.nodes, first)
        if first is not None:
            assert order[first].max() < first.sum()  # the multipliers come first
        with MumpsSolver("unsymmetric", "amd") as solver:
            solver.set_ordering(order)
            solver.analyse(n, eq.rows, eq.cols)
            solver.factorize(eq.values)
            answers[name] = solver.solve(-eq.residual)
            flops[name] = solver.statistics()["flops"]
    scale = np.abs(answers["with node"]).max()
    assert np.abs(answers["first"] - answers["with node"]).max() <= 1e-8 * scale
    assert flops["first"] < 0.8 * flops["with node"]
