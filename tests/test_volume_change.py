"""The blank's volume change: the exact volume of a moved mesh, recorded per increment in the
results and warned about once past VOLUME_LIMIT (plastic flow keeps the volume, so a larger
change is the elements' error; docs/theory/solid_shell.md, "Volume")."""

from __future__ import annotations

import logging
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
from test_runner import tiny_case

import ddpy.app.runner as runner
from ddpy.app.runner import RESULTS, run_case
from ddpy.io.decks import read_case
from ddpy.model.mesh import HexMesh

#: The six faces of a hexahedron (Gmsh order), each counter-clockwise seen from outside.
FACES = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]


def volume_by_faces(x: np.ndarray, elements: np.ndarray) -> float:
    """The volume as (1/3) of the flux of x through the boundary (divergence theorem),
    each bilinear face integrated by 2 x 2 Gauss points: x . (x_s x x_t) is of degree 2 in
    each face coordinate, so the rule is exact. Independent of the element's Jacobian."""
    g = np.array([-1.0, 1.0]) / np.sqrt(3.0)
    total = 0.0
    for element in elements:
        for face in FACES:
            c = x[element[face]]
            for s in g:
                for t in g:
                    n = np.array([(1 - s) * (1 - t), (1 + s) * (1 - t), (1 + s) * (1 + t),
                                  (1 - s) * (1 + t)]) / 4
                    ds = np.array([-(1 - t), 1 - t, 1 + t, -(1 + t)]) / 4
                    dt = np.array([-(1 - s), -(1 + s), 1 + s, 1 - s]) / 4
                    total += (n @ c) @ np.cross(ds @ c, dt @ c) / 3.0
    return total


def f_displacement(results: Path, increment: int) -> np.ndarray:
    """The blank's displacement at ``increment``, from the frame written there (the test's
    case writes one at every increment)."""
    with h5py.File(results) as f:
        for k in range(int(f["fields"].attrs["count"])):
            if int(f[f"fields/{k:06d}"].attrs["increment"]) == increment:
                return f[f"fields/{k:06d}/displacement"][()]
    raise AssertionError(f"no frame at increment {increment}")


def test_the_volume_of_a_moved_mesh_is_exact() -> None:
    """A 3 x 2 x 2 box moved by a random field of 10 % of its elements' size (warped faces)
    has the volume of the flux formula to rounding; a linear map scales it by its
    determinant."""
    mesh = HexMesh.box(3.0, 2.0, 1.0, 3, 2, 2)
    rng = np.random.default_rng(7)
    u = 0.1 * rng.uniform(-0.5, 0.5, mesh.nodes.shape)
    assert mesh.volume(u) == pytest.approx(volume_by_faces(mesh.nodes + u, mesh.elements),
                                           rel=1e-13)
    each = mesh.element_volumes(u)
    assert each.shape == (12,) and each.sum() == pytest.approx(mesh.volume(u), rel=1e-15)
    assert each[5] == pytest.approx(volume_by_faces(mesh.nodes + u, mesh.elements[5:6]),
                                    rel=1e-13)
    assert abs(mesh.volume(u) - 6.0) > 1e-3
    a = np.array([[1.1, 0.2, 0.0], [0.0, 0.9, 0.3], [0.1, 0.0, 1.2]])
    assert mesh.volume(mesh.nodes @ a.T - mesh.nodes) == pytest.approx(
        6.0 * np.linalg.det(a), rel=1e-13)
    with pytest.raises(ValueError, match="displacement"):
        mesh.volume(u[:-1])


def test_a_run_records_the_volume_change_and_warns_once(tmp_path: Path,
                                                        caplog: pytest.LogCaptureFixture
                                                        ) -> None:
    """The strip drawing on 2 x 1 x 2 elements (25 mm long over a punch of radius 5 mm):
    each increment's volume change is V / V0 - 1 of the displacement its frames hold
    (frames land on increments); the blank loses more than VOLUME_LIMIT where its two
    elements wrap the punch, and exactly one warning names the change and the increment
    where it first went past."""
    case = tiny_case(tmp_path / "case")
    control = case / "control.dat"
    control.write_text(re.sub(r"(?m)^output_every\s+\d+", "output_every 1", control.read_text()))
    with caplog.at_level(logging.WARNING, logger="ddpy"):
        outcome = run_case(read_case(case), tmp_path / "out")
    assert outcome.status == "completed"
    with h5py.File(tmp_path / "out" / RESULTS) as f:
        change = f["increments/volume_change"][()]
        nodes, elements = f["mesh/nodes"][()], f["mesh/elements"][()]
        labels = f["mesh/element_ids"][()]
        frames = [(int(f[f"fields/{k:06d}"].attrs["increment"]),
                   f[f"fields/{k:06d}/displacement"][()],
                   f[f"fields/{k:06d}/volume_change"][()])
                  for k in range(int(f["fields"].attrs["count"]))]
    assert change.shape == (outcome.increments,)
    mesh = HexMesh(nodes, elements)
    checked = 0
    for increment, u, each in frames:
        # the frame's cell field: each element's own change
        assert each == pytest.approx(mesh.element_volumes(u) / mesh.element_volumes() - 1.0,
                                     abs=1e-14)
        if increment > 0:
            assert change[increment - 1] == pytest.approx(
                mesh.volume(u) / mesh.volume() - 1.0, abs=1e-14)
            checked += 1
    assert checked >= 3
    past = np.flatnonzero(np.abs(change) > runner.VOLUME_LIMIT)
    assert past.size, np.abs(change).max()
    warnings = [r.getMessage() for r in caplog.records if "volume changed" in r.getMessage()]
    assert len(warnings) == 1, warnings
    assert f"by {100 * change[past[0]]:+.3g} %" in warnings[0], (warnings, change[past[0]])
    assert f"increment {past[0] + 1})" in warnings[0], (warnings, past[0])
    # the element that changed most by then, by its label, and where it started
    u = f_displacement(tmp_path / "out" / RESULTS, past[0] + 1)
    own = mesh.element_volumes(u) / mesh.element_volumes() - 1.0
    worst = int(np.argmax(np.abs(own)))
    centre = nodes[elements[worst]].mean(axis=0)
    assert (f"element {labels[worst]} ({100 * own[worst]:+.3g} %, initially centred at "
            f"{centre[0]:.4g}, {centre[1]:.4g}, {centre[2]:.4g} mm)") in warnings[0], warnings
