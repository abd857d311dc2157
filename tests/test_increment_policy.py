"""The increment policy (ddpy.model.control.IncrementController), the forming problem's state
and its restore, and what a FormingResult keeps per increment."""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial

import numpy as np
import pytest

from ddpy.geometry.surfaces import NagataSurface
from ddpy.model.control import (
    FormingTuning,
    IncrementController,
    IncrementLimits,
    IncrementTuning,
    next_step,
)
from ddpy.model.forming import FormingProblem, FormingResult, FormingState
from ddpy.model.forming import RigidTool as _RigidTool
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid as _Solid

Solid = partial(_Solid, element="hexahedron")
RigidTool = partial(_RigidTool, contact="node")
#: Elastic in practice (yield stress 1e7 MPa): the increments stay the nominal ones.
ELASTIC = Material(210e3, 0.3, Hill48.von_mises(), Swift(1e7, 0.01, 0.0))


# -- the controller ---------------------------------------------------------------------

def controller(**limits: object) -> IncrementController:
    """A controller of increments of at most 0.1 of the phase, cut-back 0.5."""
    return IncrementController(IncrementLimits(**limits), 0.5, 0.1)  # type: ignore[arg-type]


def test_limits_ahead_shorten_the_trial_but_never_below_the_smallest() -> None:
    control = controller(min_fraction=0.01)
    assert (control.step, control.reason, control.smallest) == (0.1, "max", 0.1 * 0.01)
    control.shorten(1.5, "touch")  # a fraction of 1 or more leaves the trial alone
    assert (control.step, control.reason) == (0.1, "max")
    control.shorten(0.25, "touch")
    assert (control.step, control.reason) == (0.025, "touch")
    control.shorten(1e-6, "release")
    assert (control.step, control.reason) == (0.001, "release")
    # The smallest trial lands no yield point: it takes what comes.
    assert control.landing() is None
    assert controller().landing() == 0.1
    assert controller(yield_tolerance=0.0).landing() == IncrementTuning().yield_floor
    assert controller(yield_tolerance=None).landing() is None


def test_a_cut_halves_the_trial_and_stops_the_phase_when_it_cannot_go_on() -> None:
    control = controller(min_fraction=0.1)  # the smallest: 0.01, at most 4 cuts in a row
    assert control.max_cuts == 4
    assert control.cut(0.0) == "" and (control.step, control.reason) == (0.05, "cut")
    assert not control.touch and not control.release_ahead(True)  # a cut size stands
    assert control.cut(0.0) == "" and control.step == 0.025
    assert control.cut(0.0) == "" and control.step == 0.0125
    # One more cut would go below the smallest increment with most of the phase left.
    assert control.cut(0.0) == "smallest" and control.step == 0.0125
    # At the end of the phase (less than the smallest left) it may.
    assert control.cut(1.0 - 0.005) == "cuts"  # (the fifth in a row)
    control.accept(0.0, 0.0)  # a converged increment resets the row, and grows back
    assert control.cuts_in_row == 0 and (control.step, control.reason) == (0.025, "regrow")


@pytest.mark.parametrize("kind", ["strain", "rotation"])
def test_a_converged_trial_over_its_strain_or_rotation_limit_is_redone_to_it(kind: str
                                                                            ) -> None:
    control = controller(strain=0.02, rotation_deg=1.0)
    limit = 0.02 if kind == "strain" else math.radians(1.0)
    redo = control.strain_redo if kind == "strain" else control.rotation_redo
    assert not redo(1.05 * limit)  # within the slack
    assert control.step == 0.1
    assert redo(4.0 * limit)
    assert (control.step, control.reason) == (pytest.approx(0.025), kind)
    # The accepted trial's rates size the next one, to 90 % of the limit.
    control.accept(0.5 * 0.02 if kind == "strain" else 0.0,
                   0.5 * limit if kind == "rotation" else 0.0)
    assert (control.step, control.reason) == (pytest.approx(0.045), kind)
    assert (control.step, control.reason) == next_step(0.025, 0.1, kind, *(
        (0.5, 0.0) if kind == "strain" else (0.0, 0.5)))
    # A tuning with no slack redoes a trial just over its limit.
    strict = IncrementController(IncrementLimits(strain=0.02, rotation_deg=1.0), 0.5, 0.1,
                                 IncrementTuning(slack=1.0))
    assert (strict.strain_redo if kind == "strain" else strict.rotation_redo)(1.01 * limit)


def test_a_release_inside_a_trial_redoes_it_to_just_past_the_release_a_capped_number_of_times(
        ) -> None:
    control = controller(release=0.05, release_redos=2)
    assert control.checks_release
    assert not control.release_redo(0.96)  # within the last 5 %: accepted
    assert control.release_redo(0.5)
    assert (control.step, control.reason) == (pytest.approx(0.1 * 0.5 * 1.025), "release")
    assert control.release_redo(0.5) and control.redos == 2
    assert not control.checks_release  # the redos are used up: accepted with it inside
    control.accept(0.0, 0.0)
    assert control.checks_release and control.redos == 0
    assert not controller(release=None).checks_release
    assert not controller(release=None).release_ahead(True)
    assert not controller().release_ahead(False)  # no rate yet: nothing to look ahead by


def test_tuning_values_out_of_range_are_refused() -> None:
    for bad in ({"slack": 0.9}, {"grow_to": 0.0}, {"regrow": 1.0}, {"bisect_below": 1.0},
                {"careful_iterations": 0}, {"release_steps": 0}, {"max_augmentations": -1}):
        with pytest.raises(ValueError):
            IncrementTuning(**bad)  # type: ignore[arg-type]


# -- the problem's state ----------------------------------------------------------------

def pressed_block(history: bool = False) -> tuple[FormingProblem, FormingResult]:
    """A block on a plane pressed up by it 1 um in four increments."""
    mesh = HexMesh.box(1.0, 1.0, 0.5, 2, 2, 1, origin=(-0.5, -0.5, 0.0))
    plane = NagataSurface([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], [[0, 0, 1]] * 4,
                          [[0, 1, 2, 3]])
    problem = FormingProblem(Solid(mesh, ELASTIC), [RigidTool("plane", plane, mesh.select(z=0.0),
                                                            friction=0.1,
                                                            facing=(0, 0, -1))])
    problem.fix(mesh.select(z=0.5), "xyz")
    result = problem.run({"plane": (0, 0, 1e-3)}, max_increment=2.5e-4,
                         result=FormingResult(history=history))
    return problem, result


def test_a_result_keeps_the_last_increments_fields_and_all_of_them_only_when_asked() -> None:
    problem, result = pressed_block()
    assert len(result.factors) == 4 and len(result.tool_forces["plane"]) == 4
    assert result.displacements == [] and result.contact_states["plane"] == []
    assert result.last is not None
    np.testing.assert_array_equal(result.last.displacement, problem.u)
    assert result.last.displacement is not problem.u  # a copy: the next increment moves on
    assert (result.last.contact_states["plane"] != 0).all()
    kept = pressed_block(history=True)[1]
    assert len(kept.displacements) == len(kept.contact_states["plane"]) == 4
    np.testing.assert_array_equal(kept.displacements[-1], result.last.displacement)
    np.testing.assert_array_equal(kept.contact_states["plane"][-1],
                                  result.last.contact_states["plane"])
    assert not np.array_equal(kept.displacements[0], kept.displacements[-1])


def test_a_restored_state_continues_the_run_as_the_problem_it_came_from() -> None:
    problem, _ = pressed_block()
    state = problem.state()
    assert isinstance(state, FormingState)
    again = problem.run({"plane": (0, 0, 1e-3)}, max_increment=5e-4)
    other, _ = pressed_block()
    # Spoiled: restore must replace all it carries.
    other.u[:] = 1.0
    other.force[:] = 0.0
    other.position = {"plane": np.zeros(3)}
    other.solid_state = other.solid.initial_state()
    other.restore(state)
    assert other.state().positions["plane"][2] == pytest.approx(1e-3)
    same = other.run({"plane": (0, 0, 1e-3)}, max_increment=5e-4)
    np.testing.assert_array_equal(other.u, problem.u)
    np.testing.assert_array_equal(same.tool_forces["plane"][-1], again.tool_forces["plane"][-1])
    assert same.iterations == again.iterations
    # state() is a copy, and a state that does not fit is refused by name.
    state.u[:] = 5.0
    assert not np.array_equal(problem.u, state.u)
    with pytest.raises(ValueError, match=r"u \(3, 3\), expected \(18, 3\)"):
        other.restore(replace(state, u=np.zeros((3, 3))))
    with pytest.raises(ValueError, match="tools .'die'., expected .'plane'."):
        other.restore(replace(state, positions={"die": np.zeros(3)}))
    with pytest.raises(ValueError, match="backstress"):
        other.restore(replace(state, solid=replace(state.solid,
                                                   backstress=state.solid.stress.copy())))


def test_the_problem_takes_its_tuning() -> None:
    # A release in more steps is measured by the iterations of the increment it joins.
    def lifted(tuning: FormingTuning) -> int:
        problem, _ = pressed_block()
        problem.tuning = tuning
        return len(problem.run({}, max_increment=1.0, active=[]).residuals[0])

    few = lifted(FormingTuning())
    many = lifted(FormingTuning(increment=IncrementTuning(release_steps=16)))
    assert many > few >= IncrementTuning().release_steps + 1
