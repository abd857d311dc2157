"""Checkpoint files: atomic replacement, generic dataclass states, clear refusals."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from ddpy.io.checkpoint import (
    CheckpointError,
    read_checkpoint,
    state_arrays,
    state_from_arrays,
    write_checkpoint,
)
from ddpy.model.material import Hill48, Material, Swift
from ddpy.model.mesh import HexMesh
from ddpy.model.solid import Solid, SolidState


@dataclass
class Grown:
    """A state with more fields than today's SolidState (one optional)."""

    stress: np.ndarray
    axes: np.ndarray
    reference: np.ndarray | None = None


def test_states_round_trip_field_by_field(tmp_path: Path) -> None:
    steel = Material(210e3, 0.3, Hill48.from_r_values(1.7, 1.2, 2.0), Swift(568.3, 0.006, 0.23))
    state = Solid(HexMesh.box(2.0, 1.0, 1.0, 2, 1, 1), steel).initial_state()
    state.stress = np.random.default_rng(1).normal(size=state.stress.shape)
    state.ep = np.ones_like(state.ep)
    grown = Grown(np.arange(6.0), np.eye(3))
    write_checkpoint(tmp_path / "c.npz", {"step": 3},
                     {**state_arrays(state), **state_arrays(grown, "grown/")})
    assert [p.name for p in tmp_path.iterdir()] == ["c.npz"]  # no temporary left
    meta, arrays = read_checkpoint(tmp_path / "c.npz")
    assert meta["step"] == 3
    back = state_from_arrays(SolidState, arrays)
    np.testing.assert_array_equal(back.stress, state.stress)
    np.testing.assert_array_equal(back.ep, state.ep)
    again = state_from_arrays(Grown, arrays, "grown/")
    np.testing.assert_array_equal(again.axes, np.eye(3))
    assert again.reference is None
    # A checkpoint of the old state lacks a required field of the new one, and the other way.
    with pytest.raises(CheckpointError, match="field 'axes' is missing"):
        state_from_arrays(Grown, {"grown/stress": np.zeros(6)}, "grown/")
    with pytest.raises(CheckpointError, match=r"has no fields \[.damage.\]"):
        state_from_arrays(SolidState, {**state_arrays(state), "state/damage": np.eye(3)})


def test_damaged_or_missing_checkpoints_are_refused(tmp_path: Path) -> None:
    with pytest.raises(CheckpointError, match="no checkpoint"):
        read_checkpoint(tmp_path / "none.npz")
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    with pytest.raises(CheckpointError, match="not a readable checkpoint"):
        read_checkpoint(tmp_path / "bad.npz")
