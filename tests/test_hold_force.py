"""Force-controlled tools (a blank-holder force): the tool's displacement along its axis is one
more unknown of the core's Newton loop, its equation the balance of the prescribed force with
the contact forces on it (docs/theory/contact.md, "Force-controlled tools"). Checked against
independent references (Coulomb's 2 mu F, the through-thickness stress F / A), central
differences, the quadratic rate, a blank that cannot carry the force, a restart, and the
deck's refusals."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from test_runner import ROOT, compare

from ddpy.app.runner import RESULTS, run_case
from ddpy.geometry.surfaces import NagataSurface
from ddpy.io.decks import DeckError, read_case
from ddpy.io.results import ResultsReader
from ddpy.model.control import NewtonSettings
from ddpy.model.forming import FormingError, FormingProblem, RigidTool
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid
from ddpy.model.tool import BARRIER_DEPTH

#: Mild steel, elastic under the loads below (initial yield 199 MPa).
STEEL = Material(210e3, 0.3, Hill48.von_mises(), Swift(500.0, 0.01, 0.2))


def plane(z: float, up: bool, x: tuple[float, float] = (-20.0, 40.0)) -> NagataSurface:
    """A flat tool at height z, its normal +z (``up``: a die) or -z (a holder)."""
    corners = [[x[0], -5, z], [x[1], -5, z], [x[1], 5, z], [x[0], 5, z]]
    return NagataSurface(corners, [[0, 0, 1 if up else -1]] * 4,
                         [[0, 1, 2, 3]] if up else [[0, 3, 2, 1]])


def pressed_blank(force: float, contact: str, material: Material = STEEL
                  ) -> tuple[FormingProblem, object]:
    """A 2 x 2 x 1 mm quarter blank on a rigid support (its bottom held in z, two symmetry
    planes), a flat holder 0.2 mm above it pressed on it with ``force`` N: the holder is
    first brought onto the blank, then its position is solved for. One increment."""
    mesh = HexMesh.box(2.0, 2.0, 1.0, 2, 2, 1)
    holder = RigidTool("holder", plane(1.2, up=False), mesh.select(z=1.0), facing=(0, 0, 1),
                       contact=contact)
    problem = FormingProblem(Solid(mesh, material), [holder])
    problem.fix(mesh.select(z=0.0), "z")
    problem.fix(mesh.select(x=0.0), "x")
    problem.fix(mesh.select(y=0.0), "y")
    result = problem.run({}, max_increment=1.0, forces={"holder": force},
                         newton=NewtonSettings(1e-10, 1e-9))
    return problem, result


@pytest.mark.parametrize("contact", ["gauss", "node", "surface"])
def test_a_holder_pressed_on_a_flat_blank_carries_the_force_as_through_thickness_stress(
        contact: str) -> None:
    """Uniaxial compression of the blank: the holder's reaction is F (to the Newton
    tolerance) and every Gauss point's through-thickness (Cauchy) stress is -F / A, A the
    blank's area there (2 x 2 mm^2 grown by Poisson's lateral strain); the holder has moved
    down from 0.2 mm above the blank into it."""
    force = 400.0
    problem, result = pressed_blank(force, contact)
    np.testing.assert_allclose(result.tool_forces["holder"][-1], [0.0, 0.0, force],
                               atol=1e-8 * force)
    cauchy = problem.solid.stresses(problem.u, problem.solid_state)[1]
    x = problem.solid.mesh.nodes + problem.u
    area = np.ptp(x[:, 0]) * np.ptp(x[:, 1])
    assert area == pytest.approx(4.0 * (1.0 + 0.3 * 100.0 / 210e3) ** 2, rel=1e-6)
    np.testing.assert_allclose(cauchy[..., 2], -force / area, rtol=1e-9)
    assert result.tool_displacements["holder"][-1][2] < -0.2
    # the support carries it too
    assert problem.force.sum(axis=0)[2] == pytest.approx(-force, rel=1e-9)


def pulled_strip(mu: float, force: float, barrier: float | None = None
                 ) -> tuple[FormingProblem, object]:
    """A 10 x 1 x 1 mm strip between a flat die and a flat holder pressed with ``force`` N
    (with the barrier ``barrier``), friction ``mu`` on both, pushed 1 mm out along x by a
    frictionless pusher at its end."""
    mesh = HexMesh.box(10.0, 1.0, 1.0, 10, 1, 1)
    pusher = NagataSurface([[0, -5, -5], [0, 5, -5], [0, 5, 5], [0, -5, 5]], [[1, 0, 0]] * 4,
                           [[0, 1, 2, 3]])
    tools = [RigidTool("die", plane(0.0, up=True), mesh.select(z=0.0), friction=mu,
                       facing=(0, 0, -1), contact="node"),
             RigidTool("holder", plane(1.0, up=False), mesh.select(z=1.0), friction=mu,
                       facing=(0, 0, 1), barrier=barrier),
             RigidTool("pusher", pusher, mesh.select(x=0.0), facing=(-1, 0, 0),
                       contact="node")]
    problem = FormingProblem(Solid(mesh, STEEL), tools)
    problem.fix(np.arange(mesh.n_nodes), "y")
    result = problem.run({"pusher": (1.0, 0, 0)}, max_increment=0.25, forces={"holder": force})
    return problem, result


@pytest.mark.parametrize(("mu", "force"), [(0.1, 500.0), (0.2, 1000.0), (0.3, 2000.0)])
def test_the_pull_force_of_a_strip_between_die_and_holder_is_2_mu_f(mu: float,
                                                                    force: float) -> None:
    """A 10 x 1 x 1 mm strip between a flat die and a flat holder pressed with F, friction mu
    on both, pushed out along x by a frictionless pusher at its end: once it slides,
    Coulomb's law gives 2 mu F, within 0.5 %. The strip's end nodes on the die touch the
    pusher too: where such a node sticks, the die's tangential law and the pusher's normal
    law hold the same direction, and the Jacobian is singular in their multipliers (the
    perturbed Lagrangian of docs/theory/contact.md, "Redundant pairs")."""
    _, result = pulled_strip(mu, force)
    pull = -result.tool_forces["pusher"][-1][0]
    assert pull == pytest.approx(2.0 * mu * force, rel=5e-3)
    assert result.tool_forces["holder"][-1][2] == pytest.approx(force, rel=1e-6)


def _holder_on_a_dome_blank(contact: str, barrier: float | None
                            ) -> tuple[FormingProblem, np.ndarray, np.ndarray, dict]:
    """A 2 x 2 x 1 mm blank clamped at its bottom under a curved holder with friction (a
    Gauss-point holder with ``barrier``), displaced and loaded off equilibrium so that its
    pairs stick and slip."""
    corners = np.array([[-2, -2, 1.0], [6, -2, 1.0], [6, 6, 1.0], [-2, 6, 1.0]])
    normals = np.array([[0.1, 0.1, -1], [-0.1, 0.1, -1], [-0.1, -0.1, -1], [0.1, -0.1, -1]])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    mesh = HexMesh.box(2.0, 2.0, 1.0, 2, 2, 1)
    holder = RigidTool("holder", NagataSurface(corners, normals, [[0, 3, 2, 1]]),
                       mesh.select(z=1.0), friction=0.2, facing=(0, 0, 1), contact=contact,
                       penalty=2000.0 if contact == "gauss" else None, barrier=barrier)
    problem = FormingProblem(Solid(mesh, STEEL), [holder])
    problem.fix(mesh.select(z=0.0), "xyz")
    u = 1e-3 * np.random.default_rng(1).standard_normal((mesh.n_nodes, 3))
    u[problem.fixed] = 0.0
    u[mesh.select(z=1.0), 2] += 0.002
    force = np.tile([1.5, 0.0, -10.0], (holder.slaves.size, 1))
    return problem, u, force, {"holder": np.array([0.001, 0.0005, -0.36])}


@pytest.mark.parametrize(("contact", "barrier"), [("node", None), ("gauss", None),
                                                  ("gauss", BARRIER_DEPTH)])
def test_the_jacobian_of_the_tools_unknown_matches_central_differences(
        contact: str, barrier: float | None) -> None:
    """The column of the holder's displacement along its axis (-z) and the row of its force
    balance against central differences of the residual (every row but the law rows of a
    Gauss-point pair without a barrier, whose multiplier is eliminated: lambda = F(x), its
    dF/dx in the equilibrium rows; with a barrier its multiplier is the slave's own force,
    the holder's force F(x) + lambda, and its law rows count)."""
    problem, u, force, positions = _holder_on_a_dome_blank(contact, barrier)
    holds = {"holder": 30.0}
    eq = problem.linearization(u, force, positions, holds=holds)
    assert (eq.state > 0).sum() >= 4  # most pairs stick or slip
    jacobian = eq.matrix()
    axis = np.array([0.0, 0.0, -1.0])
    h = 1e-6
    sides = [problem.linearization(u, force, {"holder": positions["holder"] + s * h * axis},
                                   holds=holds).residual for s in (1.0, -1.0)]
    column = (sides[0] - sides[1]) / (2.0 * h)
    rows = np.ones(column.size, dtype=bool)
    if contact == "gauss" and barrier is None:
        rows[eq.n_free:-1] = False
    scale = np.abs(jacobian[:, -1]).max()
    assert scale > 0.0
    np.testing.assert_allclose(jacobian[rows, -1], column[rows], atol=1e-6 * scale)
    free = np.flatnonzero(~problem.fixed.ravel())
    row = np.zeros(column.size)
    row[-1] = column[-1]
    for j in range(column.size - 1):
        step = 1e-7 if j < eq.n_free else 1e-4
        residuals = []
        for sign in (1.0, -1.0):
            du, df = u.copy(), force.copy()
            if j < eq.n_free:
                du.ravel()[free[j]] += sign * step
            else:
                df.ravel()[j - eq.n_free] += sign * step
            residuals.append(problem.linearization(du, df, positions, holds=holds).residual[-1])
        row[j] = (residuals[0] - residuals[1]) / (2.0 * step)
    np.testing.assert_allclose(jacobian[-1], row, atol=1e-6 * np.abs(row).max())


def test_newton_keeps_its_quadratic_rate_with_the_tools_unknown() -> None:
    """The holder pressed on the blank from 0.2 mm above it, node-to-surface contact: the
    relative residuals fall with an order of convergence above 1.5 (2 in exact arithmetic)
    down to rounding; a Jacobian without the tool's column converges linearly at best."""
    _, result = pressed_blank(400.0, "node")
    relative = [it.residual for it in result.convergence[-1]]
    tail = [r for r in relative if r > 1e-12]  # (rounding: below 1e-12 here)
    assert len(tail) >= 3, relative
    orders = [np.log(c / b) / np.log(b / a) for a, b, c in zip(tail, tail[1:], tail[2:],
                                                                strict=False)]
    assert orders[-1] > 1.5, relative


def test_a_force_the_blank_cannot_carry_stops_the_phase_naming_the_tool() -> None:
    """A blank on a die of a very soft penalty (1 N/mm^3) and no barrier: 0.4 N sinks it
    0.1 mm, 400 N would sink it 100 mm, beyond the contact search's reach: the holder never
    flies off, the phase stops naming it and the increment, with the first phase's results
    kept."""
    mesh = HexMesh.box(2.0, 2.0, 1.0, 2, 2, 1, origin=(0.0, 0.0, -1e-3))
    tools = [RigidTool("die", plane(0.0, up=True), mesh.select(z=-1e-3), facing=(0, 0, -1),
                       penalty=1.0, barrier=None),
             RigidTool("holder", plane(1.2, up=False), mesh.select(z=1.0 - 1e-3),
                       facing=(0, 0, 1))]
    problem = FormingProblem(Solid(mesh, STEEL), tools)
    problem.fix(mesh.select(x=0.0), "x")
    problem.fix(mesh.select(y=0.0), "y")
    result = problem.run({}, max_increment=1.0, forces={"holder": 0.4})
    assert result.tool_forces["holder"][-1][2] == pytest.approx(0.4, rel=1e-6)
    with pytest.raises(FormingError, match=r"increment to phase factor 1: force-controlled "
                       r"tool 'holder' lost the blank pressing with 400 N: it moved farther "
                       r"than the contact search's reach") as caught:
        problem.run({}, max_increment=1.0, forces={"holder": 400.0}, result=result)
    assert len(caught.value.result.factors) == 1  # the first phase's increment stays
    assert problem.position["holder"][2] > -3.0  # where the last converged increment left it


def _strip_case(folder: Path, control_lines: str = "force  holder 200") -> Path:
    """examples/strip_draw with 2 mm of draw under a holder pressed with 200 N (the
    example holds it at a gap), an output at 1 mm, and the other phases shortened."""
    shutil.copytree(ROOT / "examples" / "strip_draw", folder)
    control = folder / "control.dat"
    text = control.read_text()
    text = text.replace("move   punch  0 0 -10", "move   punch  0 0 -2\n  output_at 1")
    text = text.replace("move           punch  0 0 -5", "move           punch  0 0 -0.5")
    control.write_text(text.replace("gap    holder die 1.1", control_lines))
    return folder


@pytest.fixture(scope="module")
def strip_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The strip drawn under the holder force, run without interruption."""
    base = tmp_path_factory.mktemp("strip")
    case = _strip_case(base / "case")
    outcome = run_case(read_case(case), base / "out")
    assert outcome.status == "completed", outcome.message
    return case, base / "out"


def test_the_results_record_the_holders_force_and_position_per_increment(
        strip_run: tuple[Path, Path]) -> None:
    """Every increment of the drawing phase records the holder's reaction along z, 200 N to
    the Newton tolerance, and its position, solved for (it moves as the strip thins and
    thickens under it); ddpy check's summary says so."""
    case, out = strip_run
    with ResultsReader(out / RESULTS) as reader:
        history = reader.history()
        holder = list(reader.tools).index("holder")
    draw = history["phase"] == 0
    # The holder's balance is one row of the residual: within the Newton tolerance (1e-3)
    # of the force scale, the norm of all pairs' forces (the punch's and the die's too),
    # which the sum of the tools' forces exceeds.
    tools = np.linalg.norm(history["tool_force"][draw], axis=2).sum(axis=1)
    error = np.abs(history["tool_force"][draw, holder, 2] - 200.0)
    assert np.all(error <= 1e-3 * tools), (error / tools).max()
    heights = history["tool_displacement"][draw, holder, 2]
    assert np.ptp(heights) > 0.0
    summary = read_case(case).summary()
    assert "holder pressed on the blank with 200 N along its axis" in summary


def test_a_restart_in_the_middle_of_the_force_controlled_phase_gives_the_same_run(
        strip_run: tuple[Path, Path], tmp_path: Path) -> None:
    """Stopped after 5 increments of the drawing phase and continued: the results equal the
    uninterrupted run's to 1e-10."""
    case, reference = strip_run
    loaded = read_case(case)
    first = run_case(loaded, tmp_path / "out", max_increments=5, checkpoint_every=2)
    assert first.status == "stopped"
    last = run_case(loaded, tmp_path / "out", restart=True)
    assert last.status == "completed", last.message
    compare(reference, tmp_path / "out")


@pytest.mark.parametrize("lines, expected", [
    ("force  holder 200\n  gap    holder die 1.1",
     r"control.dat:\d+: phase 'draw': tool 'holder' already has a motion at line \d+ "
     r"\(expected one 'move', 'gap' or 'force' per tool\)"),
    ("force  holder -200", r"control.dat:\d+: .*the force \(N, pressing the tool on the "
                           r"blank\) must be > 0, got -200"),
    ("force  holder 0", r"control.dat:\d+: .*the force \(N, pressing the tool on the "
                        r"blank\) must be > 0, got 0"),
    ("force  holder nan", r"control.dat:\d+: expected a finite number for the force"),
    ("force  holder inf", r"control.dat:\d+: expected a finite number for the force"),
    ("force  holder 200 slowly", r"control.dat:\d+: expected 'ramp' or nothing after the "
                                 "force"),
    ("force  holder 200\n  force  punch 100\n  lead punch",
     r"control.dat:\d+: phase 'draw': tool 'punch' already has a motion"),
    ("force  holder 200\n  lead   holder",
     r"control.dat:\d+: phase 'draw': lead tool 'holder' is held under a force"),
])
def test_bad_force_lines_are_refused_with_their_line(tmp_path: Path, lines: str,
                                                      expected: str) -> None:
    """A force with a motion or a gap, a negative or non-finite force, a word other than
    ramp, a force on the lead tool: each refused before any numerics, naming control.dat's
    line and what was expected."""
    case = _strip_case(tmp_path / "case", lines)
    with pytest.raises(DeckError, match=expected):
        read_case(case)


def test_a_force_on_a_tool_without_a_facing_direction_is_refused() -> None:
    """Every tool of a deck has a facing direction (tools.dat's contact); through the API a
    tool without one cannot be held under a force: there is no axis to press along."""
    mesh = HexMesh.box(2.0, 2.0, 1.0, 2, 2, 1)
    tool = RigidTool("holder", plane(1.2, up=False), mesh.select(z=1.0))
    problem = FormingProblem(Solid(mesh, STEEL), [tool])
    problem.fix(mesh.select(z=0.0), "xyz")
    with pytest.raises(ValueError, match="tool holder has no facing direction"):
        problem.run({}, max_increment=1.0, forces={"holder": 10.0})


def test_a_ramped_force_grows_with_the_lead_tools_travel(tmp_path: Path) -> None:
    """force holder 200 ramp: at each increment of the drawing phase (2 mm of punch travel,
    an output at 1 mm splitting it in two runs) the holder carries 200 N times the share of
    the travel done."""
    case = _strip_case(tmp_path / "case", "force  holder 200 ramp")
    outcome = run_case(read_case(case), tmp_path / "out", max_increments=24)
    assert outcome.status == "stopped", outcome.message
    with ResultsReader(tmp_path / "out" / RESULTS) as reader:
        history = reader.history()
        holder = list(reader.tools).index("holder")
    draw = history["phase"] == 0
    assert history["travel"][draw].max() > 1.0  # past the output at 1 mm
    np.testing.assert_allclose(history["tool_force"][draw, holder, 2],
                               200.0 * history["travel"][draw] / 2.0, rtol=1e-3)
