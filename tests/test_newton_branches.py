"""Branches of the core's Newton loop of one increment trial (forming_increment,
fortran/solver/ddpy_forming_newton.f90), each forced by a small case and asserted through
FormingProblem.run: the line search's fallback on the residual norm and its last resort,
elements that fail at the extrapolated start, at the converged state and at trial steps, a
residual that is not finite, a Jacobian MUMPS cannot factorize, GMRES on older factors that
does not converge, and what run() makes of each failure (its log, its cuts, FormingError).

Several tests use one property of the loop's history: an increment of the phase's largest
size that starts at the converged state u_n (the first of a phase, or a resumed one whose
last rate is zero) reports, at its iteration 1, the correction over the motion as 1 (to
rounding). The correction is the step length times the Newton direction, the motion
|u - u_n| at the iterate, and the first iterate is u_n plus that step: the ratio is 1 only
if the iterate is the one the step length says. (A cut increment reports its size over
the largest: the motion is scaled up to a whole increment's, docs/theory/contact.md.)"""

from __future__ import annotations

import logging
import re
from dataclasses import replace
from functools import partial

import numpy as np
import pytest

import ddpy.model.forming as forming
from ddpy.geometry.surfaces import NagataSurface
from ddpy.model.control import (
    FormingTuning,
    IncrementLimits,
    IncrementTuning,
    NewtonSettings,
)
from ddpy.model.forming import (
    FormingError,
    FormingProblem,
    PhaseProgress,
    default_augmentation,
)
from ddpy.model.forming import RigidTool as _RigidTool
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid as _Solid
from tests.test_forming import ELASTIC, block_on_plane, plane_tool
from tests.test_linear_reuse import slide

#: No increment limit acts: a phase whose tools stay at rest is one increment.
UNLIMITED = IncrementLimits(strain=0.99, rotation_deg=90.0, yield_tolerance=None,
                            first_touch=False, release=None)
#: One cut allowed (the smallest increment is the nominal one): a failing run stops after
#: the trials at the full and the half increment (the first increment of a phase is tried
#: again with the resting tools' touching pairs open, and its retries start so).
ONE_CUT = IncrementLimits(min_fraction=1.0)
TIGHT = NewtonSettings(1e-10, 1e-8)

#: DD3IMP's discretization (the mean-dilatation hexahedron, node-to-surface contact),
#: selectable beside the defaults, which these cases were made with.
RigidTool = partial(_RigidTool, contact="node")
Solid = partial(_Solid, element="hexahedron")


def far_tool(slaves: np.ndarray) -> RigidTool:
    """A plane 50 mm below the blank: a tool nothing touches (a run needs one)."""
    far = NagataSurface([[-5, -5, -50], [5, -5, -50], [5, 5, -50], [-5, 5, -50]],
                        [[0, 0, 1]] * 4, [[0, 1, 2, 3]])
    return RigidTool("far", far, slaves, facing=(0, 0, -1))


def step_lengths(caplog: pytest.LogCaptureFixture) -> list[float]:
    """The step lengths of the Newton iterations logged at DEBUG, in order."""
    return [float(m.group(1)) for record in caplog.records
            if (m := re.search(r"iteration \d+: .*, step length (\S+)$", record.getMessage()))]


def messages(caplog: pytest.LogCaptureFixture, level: int = logging.INFO) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.levelno == level]


# -- the line search: fallback on the residual norm, and the last step tried -------------

def on_die(mesh: HexMesh, clamped: np.ndarray, load: np.ndarray,
           contact: bool = True) -> FormingProblem:
    """A blank lying on a flat die at rest (zero gap, no force), partly clamped, under a
    constant external load that lifts part of it off the die. The augmentation is a
    thousandth of the default, far below the blank's stiffness. The die's touching pairs
    start closed (the predictor of an increment's first iteration), so the first Newton
    step holds the blank down by pulling on those pairs; at any trial along it the law
    opens them, and the simplified correction, solved with the closed rows, must undo the
    whole pull, a long way in mm over the small r: the natural monotonicity test fails at
    every step length. Without ``contact`` the die lies 1 mm below (the reference: the converged
    blank is off the die)."""
    solid = Solid(mesh, ELASTIC)
    die = RigidTool("die", plane_tool(), mesh.select(z=0.0), facing=(0, 0, -1),
                    augmentation=1e-3 * default_augmentation(solid))
    problem = FormingProblem(solid, [die], linear_solver="direct")
    if not contact:
        problem.position["die"] = np.array([0.0, 0.0, -1.0])
    problem.fix(clamped, "xyz")
    problem.external[:] = load
    return problem


def lifted_strip(contact: bool = True) -> FormingProblem:
    """A 1 x 1 x 0.5 mm strip clamped at its end x = -0.5, its other end pulled up by 10 N:
    the pull on the pairs is about the load, and the residual norm at the full step (the
    pull, now the open law's residual) is below the norm at the start (the load)."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 1, 1, origin=(-0.5, -0.5, 0.0))
    tip = mesh.select(x=0.5, z=0.5)
    load = np.zeros((mesh.n_nodes, 3))
    load[tip, 2] = 10.0 / tip.size
    return on_die(mesh, mesh.select(x=-0.5), load, contact)


def tilted_column(contact: bool = True) -> FormingProblem:
    """A 1 x 1 x 8 mm column standing on the die, the half x <= 0 of its base clamped,
    pushed sideways at its top by 10 N: the base's edge x = 0.5 lifts. The pull that holds
    it down in the first step is a lever's, 16 times the load in norm: as the open law's
    residual it makes the residual norm at every trial larger than at the start."""
    mesh = HexMesh.box(1.0, 1.0, 8.0, 2, 1, 8, origin=(-0.5, -0.5, 0.0))
    base, top = mesh.select(z=0.0), mesh.select(z=8.0)
    load = np.zeros((mesh.n_nodes, 3))
    load[top, 0] = -10.0 / top.size
    return on_die(mesh, base[mesh.nodes[base, 0] <= 0.0], load, contact)


def test_a_fallback_step_keeps_its_evaluation_while_shorter_steps_are_tried(caplog) -> None:
    # The full first step lowers the residual norm but fails the monotonicity test: it
    # becomes the fallback, and the four shorter trials (which fail the test too) are
    # evaluated elsewhere, so that the fallback's own iterate is the one taken. Were it
    # overwritten by the shorter trials, the loop would go on from the last of them (1/16
    # of the step) while counting the full step: the correction of iteration 1 would be 16
    # times the motion.
    caplog.set_level(logging.DEBUG, logger="ddpy.model.forming")
    problem = lifted_strip()
    result = problem.run({"die": (0, 0, 0)}, max_increment=1.0, limits=UNLIMITED,
                         newton=TIGHT)
    assert result.cuts == 0 and len(result.factors) == 1
    assert result.fallbacks == 1
    assert step_lengths(caplog)[0] == 1.0
    residuals = result.residuals[0]
    assert residuals[1] < residuals[0]
    assert result.convergence[0][1].correction == pytest.approx(1.0, rel=1e-9)
    assert result.convergence[0][-1].residual <= 1e-10
    # The strip ends off the die (its free bottom nodes lifted, no contact force): the
    # same answer as without the die.
    assert_ends_off_the_die(problem, lifted_strip(contact=False), 4)


def assert_ends_off_the_die(problem: FormingProblem, without_die: FormingProblem,
                            lifted_nodes: int) -> None:
    """The run ended with ``lifted_nodes`` free slaves lifted off the die and no contact
    force: the answer of the same problem run without the die."""
    slaves = problem.tools[0].slaves
    lifted = slaves[~problem.fixed[slaves, 2]]
    assert lifted.size == lifted_nodes and (problem.u[lifted, 2] > 0.0).all()
    assert not problem.force.any()
    without_die.run({"die": (0, 0, 0)}, max_increment=1.0, limits=UNLIMITED, newton=TIGHT)
    np.testing.assert_allclose(problem.u, without_die.u, rtol=0,
                               atol=1e-7 * np.abs(without_die.u).max())


def test_a_step_that_no_trial_improves_is_the_last_one_tried(caplog) -> None:
    # Every trial of the first step fails the monotonicity test and raises the residual
    # norm: no fallback, and the step taken is the last one tried, 1/16 of the Newton step
    # (the loop halves once more after it, then takes that back). Its length is the one
    # the correction counts: iteration 1's correction over the motion is 1, not 1/2.
    caplog.set_level(logging.DEBUG, logger="ddpy.model.forming")
    problem = tilted_column()
    result = problem.run({"die": (0, 0, 0)}, max_increment=1.0, limits=UNLIMITED,
                         newton=TIGHT)
    assert result.cuts == 0 and len(result.factors) == 1
    assert result.fallbacks == 0
    assert step_lengths(caplog)[0] == 1.0 / 16.0
    residuals = result.residuals[0]
    assert residuals[1] > residuals[0]
    assert result.convergence[0][1].correction == pytest.approx(1.0, rel=1e-9)
    assert_ends_off_the_die(problem, tilted_column(contact=False), 2)


def test_a_stalled_increment_says_how_many_pairs_changed_state(caplog, monkeypatch) -> None:
    # One iteration allowed: the strip's first step (the fallback above) opens the pairs
    # the predictor closed, and the trial reports them when it gives up. The second start
    # leaves the resting die's touching pairs open: its step changes no state. (Held to
    # the deck's one iteration: with its usual 4 times the limit it converges.) The half
    # increment's first correction is its whole motion, half a whole increment's: the
    # measure the correction is judged on (docs/theory/contact.md).
    caplog.set_level(logging.INFO, logger="ddpy.model.forming")
    problem = lifted_strip()
    problem.tuning = replace(problem.tuning, increment=IncrementTuning(careful_iterations=1))

    def stalled(correction: str) -> str:
        return (r"no convergence in 1 iterations: residual \S+ of the force scale "
                rf"\(tolerance 1e-10\), correction {re.escape(correction)} of the motion "
                r"\(tolerance 1e-08\)")

    whole, half = stalled("1.00e+00"), stalled("5.00e-01")
    with pytest.raises(FormingError, match=rf"failed after 1 cuts: {half} \(hint: lower "
                       r"max_increment or raise max_iterations \(control.dat\)\)$") as failed:
        problem.run({"die": (0, 0, 0)}, max_increment=1.0, limits=ONE_CUT,
                    newton=NewtonSettings(1e-10, 1e-8, max_iterations=1))
    assert failed.value.result.cuts == 2 and not failed.value.result.factors
    first = messages(caplog)[0]
    changed = re.fullmatch(rf"increment to phase factor 1 \(step 1\) starts again with the "
                           rf"resting tools' touching pairs open: {whole}; (\d+) contact "
                           rf"pair\(s\) still changed state in the last iteration", first)
    assert changed and int(changed.group(1)) > 0, first


# -- failing elements ---------------------------------------------------------------------

def test_an_element_failing_at_the_extrapolated_start_starts_from_the_converged_state(
) -> None:
    # A resumed increment starts at u_n + its size x the last rate. A rate that lifts a
    # node of the middle layer 1 mm (through the clamped top) inverts elements there: the
    # loop starts at u_n instead, and runs exactly as from a zero rate (whose start is u_n),
    # with one evaluation more (the failed start), not as a failed trial.
    def squeeze(rate: np.ndarray) -> tuple[FormingProblem, forming.FormingResult]:
        problem, _ = block_on_plane(0.2)
        progress = PhaseProgress({"plane": np.zeros(3)}, {}, 0.0, 1.0, "max", rate)
        result = problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3, resume=progress)
        return problem, result

    _, mesh = block_on_plane(0.2)
    rate = np.zeros((mesh.n_nodes, 3))
    zero_problem, zero = squeeze(rate)
    rate[mesh.select(z=0.25)[0], 2] = 1.0
    bad_problem, bad = squeeze(rate)
    assert zero.cuts == bad.cuts == 0 and len(bad.factors) == 1
    assert bad.evaluations == zero.evaluations + 1
    assert bad.newton_iterations == zero.newton_iterations
    assert bad.residuals == zero.residuals
    np.testing.assert_array_equal(bad_problem.u, zero_problem.u)
    np.testing.assert_array_equal(bad_problem.force, zero_problem.force)


def test_an_element_failing_at_the_converged_state_fails_the_trial(caplog) -> None:
    # The converged state given to the run has a bottom corner node lifted through the
    # element above it (the only element it belongs to): every trial fails at its start,
    # before a Newton correction, naming that element.
    caplog.set_level(logging.INFO, logger="ddpy.model.forming")
    problem, mesh = block_on_plane(0.0)
    corner = mesh.select(x=0.5, y=0.5, z=0.0)[0]
    (element,) = np.flatnonzero((mesh.elements == corner).any(axis=1))
    problem.u[corner, 2] = 0.6
    why = f"element {element} is inverted (det F <= 0 or det J0 <= 0 at a Gauss point)"
    with pytest.raises(FormingError) as failed:
        problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3, limits=ONE_CUT)
    hint = "(hint: an element turns inside out: lower max_increment, or refine the blank " \
        "where it bends)"
    assert str(failed.value) == f"increment to 0.0005 mm of the 0.001 mm stroke failed " \
        f"after 1 cuts: {why} {hint}"
    result = failed.value.result
    assert result.cuts == 2 and not result.factors
    # Once the default start of a phase's first increment failed, its retries take the
    # careful start only: three trials, not four.
    assert result.evaluations == 3 and result.newton_iterations == 0
    assert result.factorizations == 0
    assert messages(caplog) == [
        f"increment to 0.001 mm of the 0.001 mm stroke (step 0.001 mm) starts again with "
        f"the resting tools' touching pairs open: {why}",
        f"increment to 0.001 mm of the 0.001 mm stroke (step 0.001 mm) cut: {why} {hint}",
        f"increment to 0.0005 mm of the 0.001 mm stroke (step 0.0005 mm) cut: {why} {hint}"]


def compressed_cube(load: float) -> tuple[FormingProblem, np.ndarray]:
    """A 1 mm cube on a fixed base, pushed down at its top by a constant force of
    ``load`` x E x 1 mm^2: the first Newton step, on the stiffness at rest, shortens it by
    ``load`` mm."""
    mesh = HexMesh.box(1.0, 1.0, 1.0, 1, 1, 1)
    bottom, top = mesh.select(z=0.0), mesh.select(z=1.0)
    problem = FormingProblem(Solid(mesh, ELASTIC), [far_tool(bottom)],
                             linear_solver="direct")
    problem.fix(bottom, "xyz")
    problem.external[top, 2] = -load * ELASTIC.E / top.size
    return problem, top


def test_a_trial_step_that_inverts_the_element_is_halved(caplog) -> None:
    # Pushed by 2 E, the cube's first Newton step shortens it by 2 mm: the full step and
    # the half one invert it (det F < 0, = 0), the quarter leaves it 0.5 mm high and is
    # taken. Hencky's law stiffens in compression, so the run converges where the nominal
    # stress -E ln(stretch) / stretch is 2 E (nu = 0: uniaxial).
    caplog.set_level(logging.DEBUG, logger="ddpy.model.forming")
    problem, top = compressed_cube(2.0)
    result = problem.run({"far": (0, 0, 0)}, max_increment=1.0, limits=UNLIMITED,
                         newton=NewtonSettings(1e-10, 1e-10))
    assert result.cuts == 0 and len(result.factors) == 1
    assert step_lengths(caplog)[0] == 0.25
    assert all(step == 1.0 for step in step_lengths(caplog)[1:])
    # One evaluation at the start, one per trial: two more for the inverted ones.
    assert result.evaluations == 1 + result.newton_iterations + 2
    stretch = 1.0 + problem.u[top, 2]
    np.testing.assert_allclose(-np.log(stretch) / stretch, 2.0, rtol=1e-9)


def test_a_newton_step_inverting_the_element_at_every_trial_fails_the_trial() -> None:
    # Pushed by 64 E, even 1/16 of the first step (4 mm) inverts the cube: the trial fails
    # after one correction and its five trials, naming the element. Three trials: the
    # default and the careful start at the full increment, the careful one at the half.
    problem, _ = compressed_cube(64.0)
    with pytest.raises(FormingError, match=r"^increment to phase factor 0.5 failed after 1 "
                       r"cuts: element 0 is inverted \(det F <= 0") as failed:
        problem.run({"far": (0, 0, 0)}, max_increment=1.0, limits=ONE_CUT)
    result = failed.value.result
    assert result.newton_iterations == 3 and result.evaluations == 3 * 6
    assert result.fallbacks == 0 and not result.factors


# -- a residual that is not finite, a Jacobian that cannot be factorized ----------------

def test_a_residual_that_is_not_finite_fails_the_trial(caplog) -> None:
    # NaN in the external load of one node: the residual norm at the start is not finite,
    # and every trial fails there, before any correction, halved 10 times down to the
    # smallest increment (a thousandth of the nominal one): two starts at the first size,
    # the careful one alone at each cut.
    caplog.set_level(logging.INFO, logger="ddpy.model.forming")
    problem, mesh = block_on_plane(0.0)
    problem.external[mesh.select(z=0.25)[0], 2] = np.nan
    with pytest.raises(FormingError, match=r"^increment to 1.953e-06 mm of the 0.001 mm "
                       r"stroke failed: a cut would make it smaller than the smallest "
                       r"increment \(0.001 of the largest\): the residual is not finite "
                       r"\(hint: a load or a material value is not a number\)$") as failed:
        problem.run({"plane": (0, 0, 1e-3)}, max_increment=1e-3,
                    limits=IncrementLimits(min_fraction=1e-3), newton=NewtonSettings(cutback=0.5))
    result = failed.value.result
    assert result.cuts == 10 and result.evaluations == 2 + 9
    assert result.newton_iterations == 0 and not result.factors
    cuts = [m for m in messages(caplog) if " cut: " in m]
    assert len(cuts) == 10 and all(m.endswith(" cut: the residual is not finite (hint: a "
                                              "load or a material value is not a number)")
                                   for m in cuts)


def test_a_jacobian_mumps_cannot_factorize_fails_the_trial() -> None:
    # A node that belongs to no element (decks refuse one; the Python API takes it) has
    # free dofs with no stiffness: the Jacobian is singular, every factorization fails and
    # each trial reports MUMPS's code in its first correction (three trials, as above).
    box = HexMesh.box(1.0, 1.0, 1.0, 1, 1, 1)
    mesh = HexMesh(np.vstack([box.nodes, [[3.0, 0.0, 0.0]]]), box.elements)
    problem = FormingProblem(Solid(mesh, ELASTIC), [far_tool(mesh.select(z=0.0))],
                             linear_solver="direct")
    problem.fix(mesh.select(x=0.0), "xyz")
    problem.external[mesh.select(x=1.0), 0] = 1.0
    with pytest.raises(FormingError, match=r"failed after 1 cuts: MUMPS factorization or "
                       r"solve failed with code -(6|10): the matrix is (structurally|"
                       r"numerically) singular \(hint: a part of the model is free to "
                       r"move") as failed:
        problem.run({"far": (0, 0, 0)}, max_increment=1.0, limits=ONE_CUT)
    result = failed.value.result
    assert result.newton_iterations == result.evaluations == 3
    assert result.factorizations == 0 and not result.factors


# -- GMRES on older factors that does not converge ----------------------------------------

def test_gmres_that_does_not_converge_gives_way_to_a_factorization(monkeypatch) -> None:
    # GMRES capped at one iteration and asked for an exact solution never converges: after
    # the first factorization every correction tries it once, then factorizes, and solves
    # with the new factors, so the run is the direct one, step for step.
    # (Double-precision factors: the single ones' guard is the next test's.)
    direct, result_direct = slide("direct")
    default = FormingTuning()
    monkeypatch.setattr(forming, "FormingTuning", lambda: replace(
        default, krylov_max=1, krylov_loose=0.0, krylov_tight=0.0, single_factors=0))
    reuse, result = slide("reuse")
    assert result.newton_iterations == result_direct.newton_iterations
    assert result.factorizations == result.newton_iterations
    assert result.krylov_iterations == result.newton_iterations - 1
    assert result.evaluations == result_direct.evaluations
    np.testing.assert_allclose(np.concatenate(result.residuals),
                               np.concatenate(result_direct.residuals), rtol=1e-9)
    np.testing.assert_allclose(reuse.u, direct.u, rtol=0, atol=1e-12 * np.abs(direct.u).max())


def test_single_factors_too_coarse_give_way_to_double_ones(caplog, monkeypatch) -> None:
    # The same GMRES, capped at one iteration to an exact solution, on single-precision
    # factors: right after their first factorization it misses its tolerance, as it would
    # on a Jacobian of condition number near 1/eps_single. The trial is done again on
    # double factors and the run goes on with them: step for step the double run of the
    # test above, the failed trial's work counted besides.
    default = FormingTuning()
    monkeypatch.setattr(forming, "FormingTuning", lambda: replace(
        default, krylov_max=1, krylov_loose=0.0, krylov_tight=0.0, single_factors=0))
    double, result_double = slide("reuse")
    monkeypatch.setattr(forming, "FormingTuning", lambda: replace(
        default, krylov_max=1, krylov_loose=0.0, krylov_tight=0.0, single_factors=1))
    with caplog.at_level(logging.WARNING, logger="ddpy.model.forming"):
        single, result = slide("reuse")
    assert sum("double precision from here on" in r.getMessage() for r in caplog.records) == 1
    assert result.cuts == 0 and result.iterations == result_double.iterations
    assert result.factorizations == result_double.factorizations + 1
    np.testing.assert_array_equal(single.u, double.u)
