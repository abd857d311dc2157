"""The tree search's memory (ddpy.geometry.search.SearchMemory): points that moved a little
since their last full search are projected on their remembered patch alone, with the same
answers, bit for bit, as a search without memory."""

from __future__ import annotations

import numpy as np
import pytest
from test_search import MODELS, near_points
from test_surface_contact import ELASTIC, dome

from ddpy.geometry.search import NONE, ContactSearch, SearchMemory
from ddpy.model.control import FormingTuning
from ddpy.model.forming import FormingProblem, RigidTool
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid

RNG = np.random.default_rng(7)
FIELDS = ("patch", "params", "point", "normal", "tangents", "distance", "status")


def same(a, b) -> None:
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def walk(search: ContactSearch, x: np.ndarray, steps: list[float], **options
         ) -> tuple[SearchMemory, np.ndarray]:
    """Move x by random steps of the given sizes, each projected with and without the
    memory (the same answers asserted); the memory and, per step, the share of points
    that took their answer from it."""
    memory = SearchMemory(len(x))
    shares = []
    for size in steps:
        x = x + size * RNG.normal(size=x.shape)
        recalled = search.project(x, memory=memory, **options)
        same(recalled, search.project(x, **options))
        shares.append(memory.recalled.mean())
    return memory, np.array(shares)


@pytest.mark.parametrize("name, surface, shape, box", MODELS, ids=[m[0] for m in MODELS])
def test_the_memory_gives_the_answers_of_a_full_search(name, surface, shape, box) -> None:
    # Points within 2 mm of the surface moved as a Newton loop moves them (1e-4 to 1e-2
    # mm) and by jumps of half a millimetre, within a reach of 2 mm and without one.
    x = near_points(shape, box, 1500)
    search = ContactSearch(surface)
    steps = [0.0, 1e-3, 1e-2, 1e-3, 0.5, 1e-3, 1e-4]
    _, shares = walk(search, x, steps, reach=2.0)
    assert shares[0] == 0.0  # the first call searches every point
    assert shares[4] < shares[5]  # a jump leaves fewer points near their last search
    walk(search, x, steps)


@pytest.mark.parametrize("name", ["Cylinder-quad-nagata", "Torus-quad-nagata",
                                  "Cylinder-bezier"])
def test_points_in_contact_take_their_answers_from_the_memory(name) -> None:
    # On the tools' quadrilateral patches a point on the surface lies in its own patch's
    # boxes and, unless it is near an edge, outside its neighbours': a Newton step of 1e-3
    # mm then leaves nearly all of them with the answer they had.
    surface, shape, box = next(m[1:] for m in MODELS if m[0] == name)
    x = near_points(shape, box, 20000)
    x = x[np.abs(shape.signed_distance(x)) < 0.05]
    search = ContactSearch(surface)
    _, shares = walk(search, x, [0.0, 1e-3], reach=2.0)
    assert shares[1] > 0.8, shares


def test_far_points_and_a_moving_tool() -> None:
    # A point beyond the reach stays found nowhere without a search; the memory is in the
    # tool's frame, so a tool that moves as the points do changes nothing.
    # The points on a grid of 2^-10 mm and the shift of a few 2^-3 mm, so that the points
    # moved back into the tool's frame are the same numbers (x + shift - shift = x) and
    # the distances compare bit for bit; a generator of its own, so that the sample does
    # not depend on which tests ran before.
    name, surface, shape, box = MODELS[0]
    x = np.round(np.random.default_rng(11).uniform(-2 * box, 2 * box, size=(3000, 3))
                 * 1024.0) / 1024.0
    search = ContactSearch(surface)
    memory = SearchMemory(len(x))
    first = search.project(x, reach=1.0, memory=memory)
    assert (first.status == NONE).mean() > 0.5
    shift = np.array([0.375, -0.25, 0.125])
    assert np.array_equal(x + shift - shift, x)
    moved = search.project(x + shift, tool_displacement=shift, reach=1.0, memory=memory)
    same(moved, search.project(x + shift, tool_displacement=shift, reach=1.0))
    np.testing.assert_array_equal(moved.distance, first.distance)
    # Found nowhere without a search, but where a box lay within the reach.
    assert memory.recalled[first.status == NONE].mean() > 0.9


def test_the_orientation_filter_and_held_points() -> None:
    # Normals that turn between calls (a filtered patch may count again), and points held
    # on a patch, which take no search and leave their memory as it was.
    name, surface, shape, box = next(m for m in MODELS if "bezier" in m[0])
    x = RNG.uniform(-box, box, size=(3000, 3))
    normals = RNG.normal(size=x.shape)
    search = ContactSearch(surface)
    memory = SearchMemory(len(x))
    held = np.full(len(x), -1)
    for turn in (0.0, 0.05, 0.5, 0.05):
        normals = normals + turn * RNG.normal(size=x.shape)
        x = x + 1e-3 * RNG.normal(size=x.shape)
        same(search.project(x, node_normals=normals, memory=memory, held=held),
             search.project(x, node_normals=normals, held=held))
        held[::7] = 0
    with pytest.raises(ValueError, match="memory must be of 3000 points"):
        search.project(x, memory=SearchMemory(10))


@pytest.mark.parametrize("contact", ["node", "surface", "gauss"])
def test_a_forming_run_is_the_same_with_and_without_the_memory(contact) -> None:
    # The block pressed onto the dome and slid over it (tests/test_surface_contact.py) with
    # each contact discretization: the memory of the search over an increment's
    # evaluations changes no bit of the run.
    def run(memory: int):
        surface = dome()
        lift = float(surface.evaluate([0], [[0.5, 0.5]])[0][0, 2])
        mesh = HexMesh.box(2.0, 1.0, 0.5, 8, 2, 2, origin=(-1.0, -0.5, lift))
        options = {"penalty": 5e4} if contact == "gauss" else {}
        tool = RigidTool("dome", surface, mesh.select(z=lift), friction=0.15,
                         facing=(0, 0, -1), contact=contact, **options)
        problem = FormingProblem(Solid(mesh, ELASTIC), [tool],
                                 tuning=FormingTuning(search_memory=memory))
        problem.fix(mesh.select(z=lift + 0.5), "xyz")
        result = problem.run({"dome": (0, 0, 0.02)}, max_increment=0.01)
        return problem.run({"dome": (0.2, 0, 0.02)}, max_increment=0.05, result=result)

    with_memory, without = run(1), run(0)
    assert with_memory.residuals == without.residuals
    np.testing.assert_array_equal(with_memory.tool_forces["dome"],
                                  without.tool_forces["dome"])
    np.testing.assert_array_equal(with_memory.last.displacement, without.last.displacement)
