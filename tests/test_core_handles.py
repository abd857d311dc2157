"""The core's one handle table (fortran/solver/ddpy_handle_table.f90, docs/architecture.md):
a blank, a tool surface and a problem live behind handles Python owns (CoreHandle), released
when their owner goes; a released handle, a full table and a call that comes before the
ones it needs are refused with a message that says which."""

from __future__ import annotations

import gc

import numpy as np
import pytest

from ddpy import _core
from ddpy.core.constants import constant
from ddpy.core.handles import CoreHandle, CoreRefusal, check
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.newton import Layout
from ddpy.model.solid import Solid

ELASTIC = Material(210e3, 0.3, Hill48.von_mises(), Swift(1e7, 0.01, 0.0))


def one_element() -> Solid:
    return Solid(HexMesh.box(1.0, 1.0, 1.0, 1, 1, 1), ELASTIC, element="hexahedron")


def blank(solid: Solid) -> CoreHandle:
    """Another core copy of the blank of ``solid``, owned by the handle returned."""
    handle, status, _ = _core.blank_create(solid.mesh.nodes.ravel(),
                                           solid.mesh.elements.ravel(), 0, solid.props)
    check(status, "a blank")
    return CoreHandle(handle)


def test_a_released_blank_is_refused_by_the_problem_made_from_it() -> None:
    solid = one_element()
    layout = Layout(solid, [], np.zeros((8, 3), dtype=bool))
    copy = blank(solid)
    handle, status = _core.problem_create(copy.handle, layout.eqn, 0)
    check(status, "a problem of a live blank")
    CoreHandle(handle).close()
    copy.close()
    assert copy.closed
    with pytest.raises(CoreRefusal, match=r"problem: the core refused it: the handle holds "
                                          r"no such object \(released\?\)"):
        check(_core.problem_create(copy.handle, layout.eqn, 0)[1],
              "the problem")


def test_a_full_table_is_refused_and_its_handles_come_back_when_released() -> None:
    solid = one_element()
    blanks = []
    with pytest.raises(CoreRefusal, match="handle table is full"):
        for _ in range(constant("max_handles") + 1):
            blanks.append(blank(solid))
    assert len(blanks) > constant("max_handles") // 2
    blanks.clear()
    gc.collect()
    again = [blank(solid) for _ in range(constant("max_handles") // 2)]
    assert len({b.handle for b in again}) == len(again)


def test_a_trial_before_its_settings_and_state_is_refused() -> None:
    solid = one_element()
    layout = Layout(solid, [], np.zeros((8, 3), dtype=bool))
    problem = layout.core_problem(None)
    state = solid.initial_state()
    check(_core.problem_set_state(problem.handle, state.displacement.ravel(),
                                  state.axes.transpose(0, 1, 3, 2).ravel(),
                                  state.stress.ravel(), state.ep.ravel(),
                                  state.strain.ravel(), np.zeros(48)), "the state")
    zero = np.zeros(24)
    check(_core.problem_set_start(problem.handle, zero, zero, zero, zero, 0, np.zeros(0)),
          "the start")
    problem.set_limits(reach=0.0, element_size=1.0)
    # the Newton settings were never given
    *_, status = _core.problem_increment(problem.handle, 0, 0, 0)
    assert status == constant("refusal_order")
