"""A rigid tool: its surface, the blank nodes that may touch it and its contact settings."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ddpy._validate import float_array, int_array
from ddpy.geometry.search import ContactSearch
from ddpy.geometry.surfaces import BezierSurface, NagataSurface

__all__ = ["RigidTool"]


@dataclass
class RigidTool:
    """A rigid tool: its surface, the blank nodes that may touch it (``slaves``), Coulomb
    friction, and optionally the outward normal of the blank face that meets it
    (``facing``: only patches facing the opposite way are contact candidates) and the
    augmentation parameter r of the contact law (default: ``default_augmentation``)."""

    name: str
    surface: BezierSurface | NagataSurface
    slaves: ArrayLike
    friction: float = 0.0
    facing: ArrayLike | None = None
    augmentation: float | None = None
    search: ContactSearch = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.name or not isinstance(self.name, str):
            raise ValueError("a tool needs a name")
        self.slaves = int_array(np.atleast_1d(self.slaves), f"slaves of tool {self.name}",
                                (None,))
        if self.slaves.size == 0:
            raise ValueError(f"tool {self.name} has no slave nodes: nothing can touch it")
        if np.unique(self.slaves).size != self.slaves.size:
            raise ValueError(f"tool {self.name}: slave nodes are repeated")
        if not (np.isfinite(self.friction) and self.friction >= 0.0):
            raise ValueError(f"tool {self.name}: friction must be >= 0, got {self.friction}")
        if self.augmentation is not None and not self.augmentation > 0.0:
            raise ValueError(f"tool {self.name}: augmentation must be > 0, got "
                             f"{self.augmentation}")
        if self.facing is not None:
            facing = float_array(self.facing, f"facing of tool {self.name}", (3,))
            if np.linalg.norm(facing) == 0.0:
                raise ValueError(f"tool {self.name}: facing must not be zero")
            self.facing = facing / np.linalg.norm(facing)
        self.search = ContactSearch(self.surface)
        if self.facing is not None and not (self.search.grid_normals @ self.facing < 0.0).any():
            raise ValueError(f"tool {self.name}: no patch faces its slave nodes (every normal "
                             f"points along facing {self.facing.tolist()}, away from the "
                             "blank): nothing can touch it; check the normals or facing")
