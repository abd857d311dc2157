"""The forming problem's Jacobian against central differences of its residual (tests)."""

from __future__ import annotations

import numpy as np

from ddpy.model.forming import FormingProblem


def central_difference_errors(problem: FormingProblem, u: np.ndarray, force: np.ndarray,
                              positions: dict, step: float) -> tuple[float, float, np.ndarray]:
    """The largest error of the Jacobian against central differences of the residual over
    every unknown, in the equilibrium and the contact-law rows, each relative to the largest
    entry of its rows; and the pairs' states. The difference step is ``step`` times each
    unknown's scale (1e-3 mm for displacements, the largest contact force for forces); no
    pair may change state within it. A Gauss-point pair's multiplier is eliminated (the
    loop sets lambda = F(x); its dF/dx lies in the equilibrium rows): its law rows are
    checked along the multipliers only, their dC/dx being left out by design."""
    eq = problem.linearization(u, force, positions)
    jacobian = eq.matrix()
    eliminated = np.repeat(np.concatenate([np.full(t.slaves.size, t.contact == "gauss")
                                           for t in problem.tools]), 3)
    free = np.flatnonzero(~problem.fixed.ravel())
    scale_u, scale_f = 1e-3, np.abs(problem.force).max()
    errors = np.zeros_like(jacobian)
    for j in range(eq.residual.size):
        h = step * (scale_u if j < eq.n_free else scale_f)
        sides = []
        for sign in (1.0, -1.0):
            du, df = u.copy(), force.copy()
            if j < eq.n_free:
                du.ravel()[free[j]] += sign * h
            else:
                df.ravel()[j - eq.n_free] += sign * h
            side = problem.linearization(du, df, positions)
            assert np.array_equal(side.state, eq.state)  # no switch within the difference
            sides.append(side.residual)
        errors[:, j] = (sides[0] - sides[1]) / (2.0 * h) - jacobian[:, j]
        if j < eq.n_free:
            errors[eq.n_free:][eliminated, j] = 0.0
    worst = [np.abs(errors[rows]).max() / np.abs(jacobian[rows]).max()
             for rows in (slice(0, eq.n_free), slice(eq.n_free, None))]
    return worst[0], worst[1], eq.state
