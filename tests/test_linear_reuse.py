"""Newton corrections solved with older factors: the core's GMRES (the one its Newton loop
runs) on a small system, and a forming run that reuses factorizations against one that
factorizes every iteration."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

from ddpy import _core
from ddpy.core.constants import constant
from ddpy.core.linalg import MumpsSolver, row_structure
from ddpy.model.contact import SLIP
from ddpy.model.control import FormingTuning, NewtonSettings
from ddpy.model.forming import FormingProblem
from ddpy.model.forming import RigidTool as _RigidTool
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid as _Solid
from tests.test_forming import ELASTIC, cylinder_crest

#: DD3IMP's discretization (the mean-dilatation hexahedron, node-to-surface contact),
#: selectable beside the defaults, which these cases were made with.
RigidTool = partial(_RigidTool, contact="node")
Solid = partial(_Solid, element="hexahedron")


def _dense_rows(n: int) -> tuple[np.ndarray, np.ndarray]:
    return tuple(index.astype(np.int32) for index in np.nonzero(np.ones((n, n))))


def test_gmres_on_older_factors_solves_and_reports_failure() -> None:
    # J: an unsymmetric 30 x 30 matrix in coordinates with repeated entries (summed); M: the
    # LU of a perturbed J, the "older factors". GMRES from x0 = M^-1 f on J M^-1 solves
    # J x = f to its tolerance in a few iterations; capped at 2 iterations it says it did
    # not converge; a zero right-hand side gives zero at once.
    rng = np.random.default_rng(3)
    n = 30
    dense = np.eye(n) * 4.0 + rng.normal(0.0, 0.3, (n, n))
    rows, cols = np.nonzero(np.ones((n, n)))
    values = dense[rows, cols]
    rows = np.concatenate([rows, rows[:40]]).astype(np.int32)  # duplicates: halves that sum
    cols = np.concatenate([cols, cols[:40]]).astype(np.int32)
    values = np.concatenate([values, values[:40] * 0.5])
    values[:40] *= 0.5
    weight = rng.uniform(0.5, 2.0, n)
    older = dense + rng.normal(0.0, 0.05, (n, n))
    f = rng.normal(size=n)
    with MumpsSolver("unsymmetric") as solver:
        solver.analyse(n, *_dense_rows(n))
        solver.factorize(older[_dense_rows(n)])
        x0 = solver.solve(f)  # the simplified correction
        structure = row_structure(n, rows, cols)
        x, k, converged, status = _core.krylov_solve(values, *structure, weight,
                                                     solver.handle, f, x0, 1e-12, n)
        assert status == 0 and converged == 1 and k < 15, (k, converged)
        np.testing.assert_allclose(x, np.linalg.solve(dense, f), rtol=1e-9)
        _, k, converged, status = _core.krylov_solve(values, *structure, weight,
                                                     solver.handle, f, x0, 1e-12, 2)
        assert status == 0 and converged == 0 and k == 2
        x, k, converged, status = _core.krylov_solve(values, *structure, weight,
                                                     solver.handle, np.zeros(n), np.zeros(n),
                                                     1e-8, 10)
        assert converged == 1 and k == 0 and not x.any()
        bad = structure.col.copy()
        bad[0] = n
        assert _core.krylov_solve(values, *structure._replace(col=bad), weight, solver.handle,
                                  f, x0, 1e-8, 10)[3] == 1
        # The lower triangle of a symmetric matrix stands for the whole of it.
        symmetric = dense + dense.T
        lower_rows, lower_cols = np.tril_indices(n)
        full = row_structure(n, *_dense_rows(n))
        lower = row_structure(n, lower_rows, lower_cols, symmetric=True)
        x_full = _core.krylov_solve(symmetric.ravel(), *full, weight, solver.handle, f, x0,
                                    1e-12, n)[0]
        x_lower = _core.krylov_solve(symmetric[lower_rows, lower_cols], *lower, weight,
                                     solver.handle, f, x0, 1e-12, n)[0]
        np.testing.assert_allclose(x_lower, x_full, rtol=1e-12)
        np.testing.assert_allclose(x_full, np.linalg.solve(symmetric, f), rtol=1e-9)


def _stiff_and_soft(n: int = 40) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """J = M + E with M diagonal, its first ten entries 1e4 times the rest (stiff
    directions, like a contact penalty's, and soft ones, like a thin sheet's bending), and
    a random E that couples them; W = 1. Returns J, M and a right-hand side that loads the
    stiff directions."""
    rng = np.random.default_rng(11)
    stiffness = np.where(np.arange(n) < 10, 1.0e4, 1.0)
    older = np.diag(stiffness)
    dense = older + 0.2 * rng.normal(size=(n, n)) * np.sqrt(np.outer(stiffness, stiffness))
    f = rng.normal(size=n) * stiffness
    return dense, older, f


@pytest.mark.parametrize("tol", [1e-1, 1e-2, 1e-3])
def test_gmres_stops_when_both_the_force_and_the_correction_are_met(tol: float) -> None:
    # The iterate GMRES returns meets both measures of the Newton loop: the force residual
    # ||J x - f|| <= tol ||f|| and the correction's error as the factors see it,
    # ||W M^-1 (J x - f)|| <= tol ||W x0|| (checked here with M and J themselves). On an
    # operator with stiff and soft directions either measure alone stops at an iterate
    # that misses the other: the test would fail if either check were dropped.
    dense, older, f = _stiff_and_soft()
    n = f.size
    rows, cols = _dense_rows(n)
    weight = np.ones(n)
    with MumpsSolver("unsymmetric") as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(older[rows, cols])
        x0 = solver.solve(f)
        x, k, converged, status = _core.krylov_solve(
            dense[rows, cols], *row_structure(n, rows, cols), weight, solver.handle, f, x0,
            tol, n)
    assert status == 0 and converged == 1 and 0 < k < n
    residual = dense @ x - f
    assert np.linalg.norm(residual) <= tol * np.linalg.norm(f) * (1 + 1e-9)
    assert (np.linalg.norm(np.linalg.solve(older, residual))
            <= tol * np.linalg.norm(x0) * (1 + 1e-9))
    # Each measure alone would have stopped earlier: the step before misses one of them.
    with MumpsSolver("unsymmetric") as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(older[rows, cols])
        earlier, *_ = _core.krylov_solve(
            dense[rows, cols], *row_structure(n, rows, cols), weight, solver.handle, f, x0,
            0.0, k - 1)
    residual = dense @ earlier - f
    assert (np.linalg.norm(residual) > tol * np.linalg.norm(f)
            or np.linalg.norm(np.linalg.solve(older, residual)) > tol * np.linalg.norm(x0))


def test_gmres_stops_where_the_krylov_space_stops_growing() -> None:
    # Older factors M of J = M (I + U V^T), U and V of rank 2, so that J M^-1 =
    # I + (M U)(V^T M^-1), the identity plus a rank-2 term. From x0 = M^-1 f the
    # residual f - J x0 = -(M U) V^T x0 lies in that term's range, so the Krylov space is
    # invariant from its second vector on (a breakdown). GMRES stops there with the solution,
    # exact to rounding, even asked for 0 (which rounding cannot meet: not converged) and
    # allowed all n iterations; a tolerance above rounding is met at the same iteration.
    rng = np.random.default_rng(5)
    n = 30
    older = np.eye(n) * 4.0 + rng.normal(0.0, 0.3, (n, n))
    u, v = rng.normal(size=(n, 2)), rng.normal(size=(n, 2))
    dense = older @ (np.eye(n) + u @ v.T)
    rows, cols = _dense_rows(n)
    weight = rng.uniform(0.5, 2.0, n)
    f = rng.normal(size=n)
    with MumpsSolver("unsymmetric") as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(older[rows, cols])
        x0 = solver.solve(f)
        for tol, done in ((0.0, 0), (1e-12, 1)):
            x, k, converged, status = _core.krylov_solve(
                dense[rows, cols], *row_structure(n, rows, cols), weight, solver.handle, f,
                x0, tol, n)
            assert status == 0 and k == 2 and converged == done, (tol, k, converged)
            np.testing.assert_allclose(x, np.linalg.solve(dense, f), rtol=1e-10)


def test_gmres_on_an_operator_singular_on_its_krylov_space_does_not_converge() -> None:
    # J with a zero first column and M = I: from x0 = M^-1 e_1 = e_1 the residual is e_1,
    # in the operator's null space; the Krylov space stops at its first vector and the
    # least-squares problem there is singular. GMRES stops at once and says it did not
    # converge (the residual of its rotations is 0 there: the singular pivot is what tells).
    n = 6
    rows, cols = _dense_rows(n)
    singular = np.eye(n)
    singular[:, 0] = 0.0
    e1 = np.eye(n)[0]
    with MumpsSolver("unsymmetric") as solver:
        solver.analyse(n, rows, cols)
        solver.factorize(np.eye(n)[rows, cols])
        _, k, converged, status = _core.krylov_solve(
            singular[rows, cols], *row_structure(n, rows, cols), np.ones(n), solver.handle,
            e1, e1, 1e-8, n)
    assert status == 0 and k == 1 and converged == 0


def block_on_crest(linear_solver: str, tuning: FormingTuning | None) -> FormingProblem:
    """An elastic block held at its top, its bottom face on a cylinder crest (Nagata, 8
    patches) with friction 0.15."""
    mesh = HexMesh.box(2.0, 1.0, 0.5, 8, 2, 2, origin=(-1.0, -0.5, 0.0))
    tool = RigidTool("cylinder", cylinder_crest("nagata", 8), mesh.select(z=0.0),
                     friction=0.15, facing=(0, 0, -1))
    problem = FormingProblem(Solid(mesh, ELASTIC), [tool], linear_solver=linear_solver,
                             tuning=tuning)
    problem.fix(mesh.select(z=0.5), "xyz")
    return problem


def slide(linear_solver: str, single_factors: int | None = None
          ) -> tuple[FormingProblem, object]:
    """A block pressed onto a cylinder crest, then slid over it with friction (nodes
    between stick and slip, the contact set changing); ``single_factors``: the tuning's
    (None: the default tuning, which tests/test_newton_branches.py patches)."""
    problem = block_on_crest(linear_solver, None if single_factors is None
                             else FormingTuning(single_factors=single_factors))
    result = problem.run({"cylinder": (0, 0, 0.02)}, max_increment=0.02)
    result = problem.run({"cylinder": (0.2, 0, 0)}, max_increment=0.05, result=result,
                         newton=NewtonSettings(1e-10, 1e-6))
    return problem, result


def test_reused_factors_give_the_direct_solution_with_fewer_factorizations() -> None:
    direct, result_direct = slide("direct")
    reuse, result_reuse = slide("reuse")
    assert (result_reuse.last.contact_states["cylinder"] == SLIP).sum() >= 3
    # Direct: one factorization per Newton iteration, those of rejected trials included.
    assert result_direct.cuts == 0
    assert result_direct.factorizations == result_direct.newton_iterations
    assert result_direct.krylov_iterations == 0
    # The same answer. Not to the Newton tolerance: a node that touches lands just past
    # the tool, within rounding of the tolerance, and the reused run took one first-touch
    # increment fewer; with friction the path shows (measured: 4e-7 of the largest
    # displacement, 2e-7 of the largest force).
    assert np.allclose(reuse.u, direct.u, rtol=0, atol=1e-5 * np.abs(direct.u).max())
    assert np.allclose(reuse.force, direct.force, rtol=0,
                       atol=1e-5 * np.abs(direct.force).max())
    assert result_reuse.factorizations < sum(result_reuse.iterations) / 2
    assert result_reuse.krylov_iterations > 0
    # Still Newton: no more iterations than the direct run. GMRES solves each correction
    # only as well as the residual needs (a tenth of it, or the tolerance in the last
    # iteration: krylov_last), so the last step is not quadratic by design; the quadratic
    # rate of the tangent itself is tested with the direct solver (tests/test_forming.py).
    assert sum(result_reuse.iterations) <= sum(result_direct.iterations) + 2


def test_single_precision_factors_solve_to_eps_single_times_the_condition() -> None:
    # A 40 x 40 unsymmetric matrix of condition number 1e4 (singular values from 1 to 1e-4):
    # double-precision factors solve it to rounding, single-precision ones to about
    # eps_single (6e-8) times the condition (a relative error within 1e-2, above 1e-6,
    # far above double's), and GMRES on the single factors to 1e-10 in a few steps.
    rng = np.random.default_rng(5)
    n = 40
    q1, _ = np.linalg.qr(rng.normal(size=(n, n)))
    q2, _ = np.linalg.qr(rng.normal(size=(n, n)))
    dense = q1 @ np.diag(np.geomspace(1.0, 1e-4, n)) @ q2
    exact = rng.normal(size=n)
    f = dense @ exact
    rows, cols = _dense_rows(n)
    errors = {}
    for precision in ("double", "single"):
        with MumpsSolver("unsymmetric", precision=precision) as solver:
            solver.analyse(n, rows, cols)
            solver.factorize(dense[rows, cols])
            x0 = solver.solve(f)
            errors[precision] = np.linalg.norm(x0 - exact) / np.linalg.norm(exact)
            if precision == "single":
                assert _core.solver_precision(solver.handle) == (
                    constant("precision_single"), 0)
                x, k, converged, status = _core.krylov_solve(
                    dense[rows, cols], *row_structure(n, rows, cols), np.ones(n),
                    solver.handle, f, x0, 1e-10, n)
                assert status == 0 and converged == 1 and k <= 8, k
                np.testing.assert_allclose(x, exact, rtol=0, atol=1e-8 * np.abs(exact).max())
    assert errors["double"] < 1e-10
    assert 1e-6 < errors["single"] < 1e-2, errors
    with pytest.raises(ValueError, match="precision"):
        MumpsSolver(precision="half")


def test_single_precision_factors_give_the_same_slide() -> None:
    # The slide with the Jacobian factorized in single precision: every correction is
    # GMRES's on those factors (to the Eisenstat-Walker tolerance), so the same increments
    # converge to the same answer within the Newton tolerance, in at most one more
    # iteration an increment. With the direct solver (no older factors) the tuning does
    # not apply: the same run to the bit.
    direct, _ = slide("direct")
    direct_single, result_direct_single = slide("direct", single_factors=1)
    assert np.array_equal(direct.u, direct_single.u) and result_direct_single.krylov_iterations == 0
    double, result_double = slide("reuse", single_factors=0)
    single, result_single = slide("reuse", single_factors=1)
    assert result_single.cuts == result_double.cuts == 0
    assert len(result_single.iterations) == len(result_double.iterations)
    assert result_single.krylov_iterations > 0
    assert np.allclose(single.u, double.u, rtol=0, atol=1e-5 * np.abs(double.u).max())
    assert np.allclose(single.force, double.force, rtol=0,
                       atol=1e-5 * np.abs(double.force).max())
    assert all(s <= d + 1 for s, d in zip(result_single.iterations, result_double.iterations,
                                          strict=True))


def test_a_phases_first_increment_keeps_a_tenth_of_the_tolerance_in_gmres() -> None:
    # krylov_last: a correction that may be the last leaves a linear residual of that many
    # force tolerances. A phase's first increment (the second press, one increment) keeps
    # 0.1 whatever the tuning says (its contact set is degenerate: docs/theory/
    # linear-solver.md, "Tolerance"), so at 0.1 and 10 it is the same to the bit; the
    # slide after it takes the tuning's tolerance (another path) to the same answer within
    # the Newton tolerance.
    def run(krylov_last: float) -> list[tuple[int, list[int], np.ndarray]]:
        problem = block_on_crest("reuse", FormingTuning(krylov_last=krylov_last))
        result, phases = None, []
        for move, size in (((0, 0, 0.01), 0.01), ((0, 0, 0.005), 0.01), ((0.2, 0, 0), 0.05)):
            result = problem.run({"cylinder": move}, max_increment=size, result=result)
            phases.append((result.krylov_iterations, list(result.iterations),
                           problem.u.copy()))
        return phases

    tenth, ten = run(0.1), run(10.0)
    assert len(tenth[1][1]) == len(tenth[0][1]) + 1  # the second press: one increment
    assert tenth[1][2].tobytes() == ten[1][2].tobytes()
    assert tenth[1][:2] == ten[1][:2]
    assert tenth[2][0] > tenth[1][0]  # GMRES ran in the slide
    assert tenth[2][:2] != ten[2][:2] or tenth[2][2].tobytes() != ten[2][2].tobytes()
    # Within the Newton tolerance (1e-3 of each of the slide's increments' motion, at most
    # that of the whole displacement; measured 2.3e-5 of it).
    assert np.allclose(ten[2][2], tenth[2][2], rtol=0, atol=1e-3 * np.abs(tenth[2][2]).max())
    with pytest.raises(ValueError, match="krylov_last"):
        FormingTuning(krylov_last=-1.0)


def test_linear_solver_choice_is_checked() -> None:
    mesh = HexMesh.box(1.0, 1.0, 0.5, 1, 1, 1)
    tool = RigidTool("cylinder", cylinder_crest("nagata", 4), mesh.select(z=0.0))
    with pytest.raises(ValueError, match="linear_solver"):
        FormingProblem(Solid(mesh, ELASTIC), [tool], linear_solver="iterative")
